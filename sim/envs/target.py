"""Which group the robot is meant to join, where it stands, and whether it exists now.

The target is one of the scenario's planned F-formations (`scenarios.PlannedGroup`):

1. a planned group the script puts the robot in (``hri-conversation``), the earliest; else
2. a planned group of people that the robot can join, chosen at random (with the env's
   generator) among those planned to start within `TARGET_HORIZON_S` of the start and to last
   at least `TARGET_MIN_LIFE_S`: *joinable* means that a place on its circle, at most 0.7 of
   ``ring_tolerance`` outside it and inside the walls, keeps the task's clearance plus 0.1 m
   from every member's planned place and from the places of the other groups planned
   meanwhile (`joinable_place`);
3. none (``hri-passing``): the task cannot succeed.

The target's circle is the plan's o-space centre with the mean distance of the **people's**
planned places from it as radius; once they stand there, it follows where they actually stand
(people arrive within the ground-truth rule's 0.25 m of their places): the planned centre
moved by the people's mean offset from their places, the radius their mean distance from it.
The group is *formed* when its people have arrived at their places, by the scenario's
ground-truth rule (`scenarios.GroundTruth`) applied to the people alone (so a group the robot
belongs to is formed before the robot gets there). When the planned group ends, the target
passes to its successor: the next planned group to start (at or after the end) that shares at
least two people with it (the circle re-formed after a shuffle, two groups merged, someone
joined). With no successor the target is *gone*.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from scenarios import GroundTruth, PlannedGroup
from sim.envs.reward import JoinTask, OSpace, joining_place

__all__ = [
    "TARGET_HORIZON_S",
    "TARGET_MIN_LIFE_S",
    "Target",
    "choose_target",
    "circle_of",
    "joinable_place",
]

TARGET_HORIZON_S = 10.0  # seconds: a target chosen at random starts within this
TARGET_MIN_LIFE_S = 20.0  # seconds: ... and is planned to last at least this long
JOIN_MARGIN_M = 0.1  # metres beyond the task's clearance a joinable place keeps from people
JOIN_OFFSET_SHARE = 0.7  # share of the ring tolerance a joinable place may lie outside the circle
_TIME_SLACK_S = 1e-6  # seconds


def _people(group: PlannedGroup, robot_id: int) -> np.ndarray:
    return np.array([m != robot_id for m in group.members], dtype=bool)


def circle_of(group: PlannedGroup, robot_id: int) -> OSpace:
    """The o-space circle of a planned group: its centre, its people's mean radius."""
    return OSpace.around(group.centre, group.places[_people(group, robot_id)])


def joinable_place(
    group: PlannedGroup,
    robot_id: int,
    task: JoinTask,
    bounds: tuple[float, float, float, float] | None = None,
    others: np.ndarray | None = None,
) -> np.ndarray | None:
    """A place for the robot in the group's circle, from the plan, or None.

    For a group the script puts the robot in, its planned place. Otherwise a place on the
    circle (at most `JOIN_OFFSET_SHARE` of ``ring_tolerance`` outside it, inside ``bounds``
    (x_min, x_max, y_min, y_max), the walls, when given) that keeps the task's clearance and
    `JOIN_MARGIN_M` more from every member's planned place and from ``others`` (k, 2), people
    planned to stand nearby: a place with room to spare, not one on the edge of the rules.
    """
    people = _people(group, robot_id)
    if people.sum() < 2:
        return None
    if not people.all():
        return np.array(group.places[~people][0], dtype=np.float64)
    circle = circle_of(group, robot_id)
    places = group.places
    if others is not None and len(others):
        near = np.hypot(*(others - circle.centre).T) <= circle.radius + 2.0 * task.clearance
        places = np.vstack([places, others[near]])
    angles = np.sort(np.arctan2(places[:, 1] - circle.centre[1], places[:, 0] - circle.centre[0]))
    gaps = np.diff(np.append(angles, angles[0] + 2.0 * math.pi))
    k = int(np.argmax(gaps))
    mid = angles[k] + 0.5 * gaps[k]
    outward = circle.centre + np.array([math.cos(mid), math.sin(mid)])
    clearance = task.clearance + JOIN_MARGIN_M
    place = joining_place(
        circle,
        places,
        outward,
        clearance=clearance,
        max_offset=JOIN_OFFSET_SHARE * task.ring_tolerance,
        bounds=bounds,
    )
    if bounds is not None:
        x0, x1, y0, y1 = bounds
        if not (x0 <= place[0] <= x1 and y0 <= place[1] <= y1):
            return None
    if np.min(np.hypot(*(places - place).T)) < clearance:
        return None
    return place


def choose_target(
    plan: Sequence[PlannedGroup],
    robot_id: int,
    task: JoinTask,
    rng: np.random.Generator,
    *,
    bounds: tuple[float, float, float, float] | None = None,
) -> PlannedGroup | None:
    """The planned group the robot is meant to join (see the module doc), or None.

    ``bounds`` (x_min, x_max, y_min, y_max): where the robot's centre may stand (the walls).
    """
    with_robot = [g for g in plan if robot_id in g.members and _people(g, robot_id).sum() >= 2]
    if with_robot:
        return min(with_robot, key=lambda g: g.start)
    candidates = []
    for g in plan:
        if g.start > TARGET_HORIZON_S or g.end - max(g.start, 0.0) < TARGET_MIN_LIFE_S:
            continue
        # Other people planned to stand around then must leave the gap free too.
        others = [
            h.places[[m != robot_id and m not in g.members for m in h.members]]
            for h in plan
            if h is not g and h.start < g.end and h.end > g.start and h.start <= TARGET_HORIZON_S
        ]
        crowd = np.vstack(others) if others else None
        if joinable_place(g, robot_id, task, bounds, crowd) is not None:
            candidates.append(g)
    if not candidates:
        return None
    return candidates[int(rng.integers(len(candidates)))]


class Target:
    """Follows the target group through the episode.

    Args:
        plan: every planned group of the scenario.
        first: the target chosen at the start.
        ids: (n,) agent ids, the order of the pose arrays given to `update`.
        robot_id: the robot's id.
    """

    def __init__(
        self,
        plan: Sequence[PlannedGroup],
        first: PlannedGroup,
        ids: Sequence[int],
        robot_id: int,
    ) -> None:
        self._plan = tuple(sorted(plan, key=lambda g: g.start))
        self._ids = [int(i) for i in ids]
        self._robot = int(robot_id)
        self._gone = False
        self._follow(first)

    def _follow(self, group: PlannedGroup) -> None:
        people = _people(group, self._robot)
        self.group = group
        self.members = tuple(m for m, p in zip(group.members, people, strict=True) if p)
        self.circle = circle_of(group, self._robot)
        alone = PlannedGroup(
            members=self.members,
            places=group.places[people],
            facings=group.facings[people],
            centre=group.centre,
            start=group.start,
            end=group.end,
        )
        self._truth = GroundTruth([alone], self._ids)
        self._formed = False
        self._rows = np.array([self._ids.index(m) for m in self.members], dtype=np.int64)
        self._places = group.places[people]

    @property
    def gone(self) -> bool:
        """The target group ended with no successor."""
        return self._gone

    def _successor(self) -> PlannedGroup | None:
        mine = set(self.members)
        later = [
            g
            for g in self._plan
            if g is not self.group
            and g.start >= self.group.end - _TIME_SLACK_S
            and len(mine & {m for m in g.members if m != self._robot}) >= 2
        ]
        return min(later, key=lambda g: g.start) if later else None

    def update(
        self, time: float, present: np.ndarray, position: np.ndarray, yaw: np.ndarray
    ) -> bool:
        """Whether the target group is formed at ``time`` (poses of every agent, (n,) ...)."""
        if self._gone:
            return False
        if time >= self.group.end - _TIME_SLACK_S:
            successor = self._successor()
            if successor is None:
                self._gone = True
                return False
            self._follow(successor)
        if not self._formed:  # once formed, a lone planned group lasts until its end
            groups = self._truth.update(np.array([time]), present[None], position[None], yaw[None])[
                0
            ]
            self._formed = bool(groups)
        if self._formed:
            # The circle where the people actually stand: the planned centre moved with them.
            actual = position[self._rows]
            centre = self.group.centre + (actual - self._places).mean(axis=0)
            self.circle = OSpace.around(centre, actual)
        return self._formed
