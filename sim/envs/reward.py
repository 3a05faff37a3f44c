"""The "join the conversation" task: the robot takes a place in a group's circle.

The robot is told which group to join (its *target*: the people of one of the scenario's planned
F-formations). The group's **o-space** is the disc its members face into; they stand on a
circle around it, the **o-space circle**, of centre ``c`` (the scenario's planned centre) and
radius ``r`` (the mean distance of the people's planned places from ``c``). The robot has
joined when, at once and for `JoinTask.hold` seconds without a break:

* it stands **on the circle**: its base is within ``ring_tolerance`` of radius ``r`` from ``c``,
  ``|‖p − c‖ − r| ≤ ring_tolerance``;
* it **faces the centre**: its base yaw is within ``facing_tolerance`` of the bearing of ``c``;
* it is **in nobody's personal space**: its body disc (radius 0.28 m) does not enter the disc of
  radius ``personal_space`` around any person's centre, i.e. every person's centre is at least
  ``personal_space + robot radius`` away (0.35 + 0.28 = 0.63 m, about the spacing the scripted
  people keep with each other); standing on the circle clear of every member means standing in
  a gap between two of them;
* the group is **formed**: its people have arrived at their places (the scenario's ground-truth
  rule, `scenarios.truth`, applied to the people of the group).

Inside the inner edge of the ring, ``‖p − c‖ < r − ring_tolerance``, the robot is **in the
o-space** (it walked into the middle of the conversation).

Reward terms, per control step (their sum is the reward; `reward_terms` returns them by name):

* ``progress``: ``progress_weight × (d_{t−1} − d_t)`` with ``d = |‖p − c‖ − r|`` the distance
  to the circle (a potential difference, metres); 0 while the group is not formed;
* ``facing``: ``facing_weight × cos(facing error)`` while on the circle, else 0;
* ``intrusion``: ``−intrusion_penalty`` per person whose personal space the robot is in;
* ``o_space``: ``−o_space_penalty`` while in the o-space;
* ``time``: ``−time_penalty`` every step;
* ``success``: ``+success_reward`` on the step the robot has held its place for ``hold`` s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
import numpy.typing as npt

from reform.frame import wrap_angle

__all__ = [
    "FACING_TOLERANCE_RAD",
    "HOLD_S",
    "PERSONAL_SPACE_M",
    "REWARD_TERMS",
    "RING_TOLERANCE_M",
    "ROBOT_BODY_RADIUS_M",
    "STRIDE_M",
    "Assessment",
    "JoinTask",
    "OSpace",
    "assess",
    "estimate_o_space",
    "joining_place",
    "reward_terms",
]

PERSONAL_SPACE_M = 0.35  # metres, around a person's centre; the robot's body must stay out
RING_TOLERANCE_M = 0.30  # metres, |distance to the centre - radius| that counts as on the circle
FACING_TOLERANCE_RAD = math.radians(30.0)  # radians, base yaw off the bearing of the centre
HOLD_S = 1.0  # seconds the robot must hold its place to have joined
ROBOT_BODY_RADIUS_M = 0.28  # metres, the robot's base disc (sim.scene.ROBOT_RADIUS_M)
STRIDE_M = 0.7  # metres, how far in front of a person their o-space vote lies (GCFF's stride)
_CENTRE_PRIOR = 0.05  # weight of the stride-point mean when intersecting facing lines
_PLACE_STEPS = 13  # radii tried per gap when placing the robot

# Reward weights (per control step unless stated).
PROGRESS_WEIGHT = 1.0  # reward per metre of approach to the circle
FACING_WEIGHT = 0.05  # reward per step on the circle, times the cosine of the facing error
INTRUSION_PENALTY = 0.2  # per step and per person whose personal space the robot is in
O_SPACE_PENALTY = 0.2  # per step in the o-space
TIME_PENALTY = 0.01  # per step
SUCCESS_REWARD = 10.0  # once, when the robot has joined

REWARD_TERMS = ("progress", "facing", "intrusion", "o_space", "time", "success")


@dataclass(frozen=True)
class JoinTask:
    """Parameters of the joining task (defaults: the module constants).

    Attributes:
        personal_space: radius around a person's centre the robot's body must not enter, m.
        ring_tolerance: how far off the o-space circle still counts as on it, metres.
        facing_tolerance: how far the base yaw may be off the bearing of the centre, radians.
        hold: seconds the robot must hold its place to have joined.
        robot_radius: the robot's body radius, metres.
        progress_weight: reward per metre of approach to the circle.
        facing_weight: reward per step on the circle (times the cosine of the facing error).
        intrusion_penalty: penalty per step and person whose personal space the robot is in.
        o_space_penalty: penalty per step in the o-space.
        time_penalty: penalty per step.
        success_reward: reward on joining.
    """

    personal_space: float = PERSONAL_SPACE_M
    ring_tolerance: float = RING_TOLERANCE_M
    facing_tolerance: float = FACING_TOLERANCE_RAD
    hold: float = HOLD_S
    robot_radius: float = ROBOT_BODY_RADIUS_M
    progress_weight: float = PROGRESS_WEIGHT
    facing_weight: float = FACING_WEIGHT
    intrusion_penalty: float = INTRUSION_PENALTY
    o_space_penalty: float = O_SPACE_PENALTY
    time_penalty: float = TIME_PENALTY
    success_reward: float = SUCCESS_REWARD

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"JoinTask.{f.name} must be a number, got {value!r}") from None
            if not (math.isfinite(number) and number >= 0.0):
                raise ValueError(f"JoinTask.{f.name} must be finite and >= 0, got {value!r}")
            object.__setattr__(self, f.name, number)
        if self.facing_tolerance > math.pi:
            raise ValueError(
                f"JoinTask.facing_tolerance must be within [0, pi] radians, got "
                f"{self.facing_tolerance}"
            )

    @property
    def clearance(self) -> float:
        """Closest the robot's centre may come to a person's centre, metres."""
        return self.personal_space + self.robot_radius


@dataclass(frozen=True)
class OSpace:
    """An o-space circle.

    Attributes:
        centre: (2,) metres.
        radius: metres, the members' distance from the centre.
    """

    centre: np.ndarray
    radius: float

    def __post_init__(self) -> None:
        centre = np.array(self.centre, dtype=np.float64)
        if centre.shape != (2,) or not np.all(np.isfinite(centre)):
            raise ValueError(f"OSpace.centre must be a finite (x, y), got {self.centre!r}")
        centre.flags.writeable = False
        object.__setattr__(self, "centre", centre)
        radius = float(self.radius)
        if not (math.isfinite(radius) and radius >= 0.0):
            raise ValueError(f"OSpace.radius must be finite and >= 0 metres, got {self.radius!r}")
        object.__setattr__(self, "radius", radius)

    @classmethod
    def around(cls, centre: npt.ArrayLike, places: npt.ArrayLike) -> OSpace:
        """The circle of ``centre`` through (on average) ``places`` (k, 2), metres."""
        centre = np.asarray(centre, dtype=np.float64)
        places = np.asarray(places, dtype=np.float64).reshape(-1, 2)
        radius = float(np.mean(np.hypot(*(places - centre).T))) if len(places) else 0.0
        return cls(centre=centre, radius=radius)


def estimate_o_space(
    position: npt.ArrayLike, yaw: npt.ArrayLike, *, stride: float = STRIDE_M
) -> OSpace:
    """The o-space of people standing at ``position`` (k, 2) and facing ``yaw`` (k,).

    Positions are trusted more than facings (people turn to whoever speaks, even outside the
    group):

    * three or more people: the circle through them (least squares), unless it lies behind
      most of them (people on a line), then the point nearest every facing line;
    * two people: a point on the perpendicular bisector of the pair: where their facing lines
      cross it when both cross it in front of them at points within half their distance of
      each other (the mean, no farther out than the pair's distance), else their midpoint;
    * one person: ``stride`` in front of them.

    The radius is the members' mean distance from the centre.
    """
    position = np.asarray(position, dtype=np.float64).reshape(-1, 2)
    yaw = np.asarray(yaw, dtype=np.float64).reshape(-1)
    k = position.shape[0]
    if yaw.shape[0] != k or k < 1:
        raise ValueError(
            f"position (k, 2) and yaw (k,) must describe k >= 1 people, got {position.shape} "
            f"and {yaw.shape}"
        )
    heading = np.stack([np.cos(yaw), np.sin(yaw)], axis=1)
    if k == 1:
        return OSpace(centre=position[0] + stride * heading[0], radius=stride)
    if k == 2:
        return OSpace.around(_pair_centre(position, heading), position)
    centre = _circle_fit(position)
    if centre is not None:
        toward = centre - position
        facing = np.einsum("ij,ij->i", toward, heading)
        if np.mean(facing > 0.0) >= 0.5:
            return OSpace.around(centre, position)
    return OSpace.around(_lines_centre(position, heading, stride), position)


def _pair_centre(position: np.ndarray, heading: np.ndarray) -> np.ndarray:
    middle = position.mean(axis=0)
    along = position[1] - position[0]
    half = 0.5 * float(np.hypot(*along))
    if half == 0.0:
        return middle
    normal = np.array([-along[1], along[0]]) / (2.0 * half)
    offsets = []
    for p, u in zip(position, heading, strict=True):
        # p + s u = middle + h normal  ->  [u, -normal] (s, h) = middle - p
        matrix = np.column_stack([u, -normal])
        if abs(np.linalg.det(matrix)) < 1e-6:
            return middle
        s, h = np.linalg.solve(matrix, middle - p)
        if s <= 0.0:
            return middle
        offsets.append(float(h))
    # The two crossings must agree (within half the pair's distance): two people facing each
    # other, with noise, cross it anywhere, and their centre is the middle.
    if abs(offsets[0] - offsets[1]) > half:
        return middle
    h = 0.5 * (offsets[0] + offsets[1])
    return middle + math.copysign(min(abs(h), 2.0 * half), h) * normal


def _circle_fit(position: np.ndarray) -> np.ndarray | None:
    """Centre of the least-squares circle through the points (None when they are collinear)."""
    a = np.column_stack([2.0 * position, np.ones(len(position))])
    b = np.einsum("ij,ij->i", position, position)
    solution, _, rank, singular = np.linalg.lstsq(a, b, rcond=None)
    if rank < 3 or singular[-1] < 1e-6 * singular[0]:
        return None
    return solution[:2]


def _lines_centre(position: np.ndarray, heading: np.ndarray, stride: float) -> np.ndarray:
    """The point nearest every facing line, pulled toward the mean stride point."""
    prior = (position + stride * heading).mean(axis=0)
    normal = np.eye(2)[None] - heading[:, :, None] * heading[:, None, :]
    weight = _CENTRE_PRIOR * len(position)
    a = normal.sum(axis=0) + weight * np.eye(2)
    b = np.einsum("kij,kj->i", normal, position) + weight * prior
    return np.linalg.solve(a, b)


def joining_place(
    o_space: OSpace,
    members: npt.ArrayLike,
    robot_position: npt.ArrayLike,
    *,
    clearance: float,
    max_offset: float,
    bounds: tuple[float, float, float, float] | None = None,
) -> np.ndarray:
    """Where the robot should stand to join: in a gap of the circle, clear of the members.

    The gaps are the angular intervals between the members around the centre. For each, the
    place is on its bisector, at the circle's radius or moved outward (by at most
    ``max_offset``) until every member's centre is ``clearance`` away. Among the gaps where that
    works, the one nearest the robot (around the circle) is taken; when none works, the one
    leaving the most room.

    Args:
        o_space: the circle.
        members: (k, 2) members' positions, metres.
        robot_position: (2,) metres.
        clearance: closest the robot's centre may come to a member's, metres.
        max_offset: how far beyond the radius the place may move, metres.
        bounds: (x_min, x_max, y_min, y_max) where the robot's centre may stand (the walls),
            metres; None for no walls.

    Returns:
        (2,) the place, metres.
    """
    members = np.asarray(members, dtype=np.float64).reshape(-1, 2)
    centre = o_space.centre
    robot = np.asarray(robot_position, dtype=np.float64)
    robot_angle = math.atan2(robot[1] - centre[1], robot[0] - centre[0])
    if len(members) == 0:
        return centre + o_space.radius * np.array([math.cos(robot_angle), math.sin(robot_angle)])
    angles = np.sort(np.arctan2(members[:, 1] - centre[1], members[:, 0] - centre[0]))
    widths = np.diff(np.append(angles, angles[0] + 2.0 * math.pi))
    mids = angles + 0.5 * widths
    directions = np.stack([np.cos(mids), np.sin(mids)], axis=1)  # (g, 2)
    radii = o_space.radius + np.linspace(0.0, max_offset, _PLACE_STEPS)  # (s,)
    spots = centre + radii[None, :, None] * directions[:, None, :]  # (g, s, 2)
    gaps = np.hypot(*np.moveaxis(spots[:, :, None, :] - members[None, None], -1, 0))
    room = gaps.min(axis=2)  # (g, s): distance to the nearest member
    if bounds is not None:
        x0, x1, y0, y1 = bounds
        outside = (
            (spots[..., 0] < x0)
            | (spots[..., 0] > x1)
            | (spots[..., 1] < y0)
            | (spots[..., 1] > y1)
        )
        room = np.where(outside, -np.inf, room)
    ok = room >= clearance
    feasible = ok.any(axis=1)
    if feasible.any():
        first = np.argmax(ok, axis=1)  # the innermost radius that works, per gap
        off = np.abs(wrap_angle(mids - robot_angle))
        g = int(np.flatnonzero(feasible)[np.argmin(off[feasible])])
        return spots[g, first[g]]
    g, k = np.unravel_index(int(np.argmax(room)), room.shape)
    return spots[g, k]


@dataclass(frozen=True)
class Assessment:
    """Where the robot stands with respect to the task, at one control step.

    Attributes:
        formed: the target group exists (its people have arrived).
        distance_to_circle: ``|‖p − c‖ − r|``, metres (NaN when not formed).
        facing_error: ``|wrap(bearing of c − yaw)|``, radians (NaN when not formed).
        on_circle: within the ring tolerance of the circle.
        facing: within the facing tolerance.
        in_o_space: inside the inner edge of the ring.
        intruded: ids of the people whose personal space the robot is in.
        placed: on the circle, facing the centre, in nobody's personal space, group formed.
    """

    formed: bool
    distance_to_circle: float
    facing_error: float
    on_circle: bool
    facing: bool
    in_o_space: bool
    intruded: tuple[int, ...]
    placed: bool


def assess(
    task: JoinTask,
    *,
    robot_position: npt.ArrayLike,
    robot_yaw: float,
    people_ids: npt.ArrayLike,
    people_position: npt.ArrayLike,
    o_space: OSpace | None,
) -> Assessment:
    """The robot's standing in the task now (ground truth).

    Args:
        task: the parameters.
        robot_position: (2,) metres.
        robot_yaw: radians.
        people_ids: (k,) ids of the people present.
        people_position: (k, 2) their positions, metres.
        o_space: the target group's circle, or None while the group is not formed.
    """
    robot = np.asarray(robot_position, dtype=np.float64)
    people = np.asarray(people_position, dtype=np.float64).reshape(-1, 2)
    ids = np.asarray(people_ids).reshape(-1)
    gaps = np.hypot(people[:, 0] - robot[0], people[:, 1] - robot[1])
    intruded = tuple(int(i) for i in ids[gaps < task.clearance])
    if o_space is None:
        nan = float("nan")
        return Assessment(False, nan, nan, False, False, False, intruded, False)
    delta = o_space.centre - robot
    distance = math.hypot(delta[0], delta[1])
    signed = distance - o_space.radius
    facing_error = abs(float(wrap_angle(math.atan2(delta[1], delta[0]) - robot_yaw)))
    on_circle = abs(signed) <= task.ring_tolerance
    facing = facing_error <= task.facing_tolerance
    return Assessment(
        formed=True,
        distance_to_circle=abs(signed),
        facing_error=facing_error,
        on_circle=on_circle,
        facing=facing,
        in_o_space=signed < -task.ring_tolerance,
        intruded=intruded,
        placed=on_circle and facing and not intruded,
    )


def reward_terms(
    task: JoinTask, previous: Assessment | None, current: Assessment, *, joined: bool
) -> dict[str, float]:
    """The reward terms of one control step, by name (`REWARD_TERMS`); their sum is the reward.

    Args:
        task: the parameters.
        previous: the assessment one step earlier (None on the first step).
        current: the assessment now.
        joined: the robot has held its place for ``task.hold`` seconds as of this step.
    """
    progress = 0.0
    if previous is not None and previous.formed and current.formed:
        progress = task.progress_weight * (previous.distance_to_circle - current.distance_to_circle)
    facing = task.facing_weight * math.cos(current.facing_error) if current.on_circle else 0.0
    return {
        "progress": float(progress),
        "facing": float(facing),
        "intrusion": -task.intrusion_penalty * len(current.intruded),
        "o_space": -task.o_space_penalty if current.in_o_space else 0.0,
        "time": -task.time_penalty,
        "success": task.success_reward if joined else 0.0,
    }
