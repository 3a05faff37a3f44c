"""Which group the robot is meant to join, where it stands, and whether it exists now.

The target is one of the scenario's planned F-formations (`scenarios.PlannedGroup`):

1. a planned group the script puts the robot in (``hri-conversation``), the earliest; else
2. a planned group of people that the robot can join, chosen at random (with the env's
   generator) among those planned to start within `TARGET_HORIZON_S` of the start and to last
   at least `TARGET_MIN_LIFE_S`: *joinable* means that a place on its circle, at most
   ``ring_tolerance`` outside it, keeps the task's clearance from every member's planned place;
3. none (``hri-passing``): the task cannot succeed.

The target's circle is the plan's o-space centre with the mean distance of the **people's**
planned places from it as radius. The group is *formed* when its people have arrived at their
places, by the scenario's ground-truth rule (`scenarios.GroundTruth`) applied to the people
alone (so a group the robot belongs to is formed before the robot gets there). When the planned
group ends, the target passes to its successor: the next planned group to start (at or after
the end) that shares at least two people with it (the circle re-formed after a shuffle, two
groups merged, someone joined). With no successor the target is *gone*.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from scenarios import GroundTruth, PlannedGroup
from sim.envs.reward import JoinTask, OSpace, joining_place

__all__ = ["TARGET_HORIZON_S", "TARGET_MIN_LIFE_S", "Target", "choose_target", "is_joinable"]

TARGET_HORIZON_S = 10.0  # seconds: a target chosen at random starts within this
TARGET_MIN_LIFE_S = 20.0  # seconds: ... and is planned to last at least this long
_TIME_SLACK_S = 1e-6  # seconds


def _people(group: PlannedGroup, robot_id: int) -> np.ndarray:
    return np.array([m != robot_id for m in group.members], dtype=bool)


def circle_of(group: PlannedGroup, robot_id: int) -> OSpace:
    """The o-space circle of a planned group: its centre, its people's mean radius."""
    return OSpace.around(group.centre, group.places[_people(group, robot_id)])


def is_joinable(group: PlannedGroup, robot_id: int, task: JoinTask) -> bool:
    """Whether a place on the group's circle (at most ``ring_tolerance`` outside) keeps the
    task's clearance from every person's planned place."""
    people = _people(group, robot_id)
    if people.sum() < 2:
        return False
    circle = circle_of(group, robot_id)
    places = group.places[people]
    angles = np.arctan2(places[:, 1] - circle.centre[1], places[:, 0] - circle.centre[0])
    widest = np.sort(angles)
    gaps = np.diff(np.append(widest, widest[0] + 2.0 * math.pi))
    k = int(np.argmax(gaps))
    outward = circle.centre + np.array(
        [math.cos(widest[k] + 0.5 * gaps[k]), math.sin(widest[k] + 0.5 * gaps[k])]
    )
    place = joining_place(
        circle, places, outward, clearance=task.clearance, max_offset=task.ring_tolerance
    )
    return bool(np.min(np.hypot(*(places - place).T)) >= task.clearance)


def choose_target(
    plan: Sequence[PlannedGroup], robot_id: int, task: JoinTask, rng: np.random.Generator
) -> PlannedGroup | None:
    """The planned group the robot is meant to join (see the module doc), or None."""
    with_robot = [g for g in plan if robot_id in g.members and _people(g, robot_id).sum() >= 2]
    if with_robot:
        return min(with_robot, key=lambda g: g.start)
    candidates = [
        g
        for g in plan
        if g.start <= TARGET_HORIZON_S
        and g.end - max(g.start, 0.0) >= TARGET_MIN_LIFE_S
        and is_joinable(g, robot_id, task)
    ]
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
        groups = self._truth.update(np.array([time]), present[None], position[None], yaw[None])[0]
        return bool(groups)
