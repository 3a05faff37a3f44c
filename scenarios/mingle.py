"""``mingle``: a SALSA-like party of people forming and leaving conversational groups.

18 people by default (2-100) in a square room (SALSA-like density, 0.4 people per m^2, unless a
side is given). Groups of 2 to ``max_group_size`` form, grow when someone joins, shrink when
someone leaves, merge and split; people stand alone for a while, then join a group or pair up
with someone; optional passers-by cross the room, and the robot may watch from a wall.
Members stand on an o-space circle whose radius grows with the group's size, with noise on
places, facings and gaze; listeners look at whoever speaks.

The radius law ``0.444 + 0.067 * (n - 2)`` metres is a least-squares fit to this project's
SALSA mean Tightness by group size 2-8 (0.417, 0.530, 0.574, 0.682, 0.727, 0.755, 0.869 m,
both sessions; ``docs/results/characterisation.md``) of the mean radius the scenario draws:
the law times ``1 + 0.10 Z`` (Z standard normal), never below the radius at which neighbours
stand `scenarios.stage.SPACING_M` apart (0.726 m for 7, 0.823 m for 8); the fit's residuals
are -0.035 to +0.036 m. SALSA holds 25 groups of 8, so
``max_group_size`` defaults to 8. The spread of radii and the place, facing and gaze noise
follow SALSA's wider spread of Tightness (sd 0.08-0.18 m) and in-group Effort Angles (median
1.62 rad).

Four options widen what a party looks like (`docs/guide/crowds.md`), each off by default:
``spacing`` lets people stand shoulder to shoulder (smaller body discs), ``unevenness`` spreads
members unevenly round elliptical o-spaces (SALSA's Symmetry by size), ``arrangements`` makes a
share of the groups stand side by side or as presenter and audience, and ``furniture`` puts
tables, bar counters and posters in the room with groups standing at them.

Everything is drawn when the scenario is made: an event-driven planner (`Party`) walks
through the party's timeline (joins, leaves, merges, splits, pairings, passers-by), reserving
floor space for every group so that groups never overlap, then the conversations and glances
are written for every group and every person standing alone.
"""

from __future__ import annotations

import dataclasses
import heapq
import math
from dataclasses import dataclass, field
from typing import Annotated, Any

import numpy as np

from scenarios.casting import cast
from scenarios.changes import (
    CHANGE_OPTIONS,
    JOIN,
    LEAVE,
    MERGE,
    ApproachSpeed,
    EventKinds,
    EventRate,
    draw_kind,
    next_change,
)
from scenarios.conversation import converse, standing
from scenarios.formation import (
    CIRCLE_OPTIONS,
    CircleNoise,
    CircleShape,
    RadiusLaw,
    ellipse_offsets,
    facing_centre,
    min_radius,
    separate,
)
from scenarios.registry import (
    PlaceNoise,
    Range,
    SceneSeconds,
    check_ranges,
    register,
    shared_help,
)
from scenarios.scenario import Scenario
from scenarios.script import Intent
from scenarios.stage import (
    CLEARANCE_M,
    PLANNING_RADIUS_M,
    SPACING_M,
    Furniture,
    RobotPlace,
    Stage,
)
from scenarios.timeline import PlannedGroup, TimelineBuilder

__all__ = [
    "SALSA_RADIUS",
    "LargestGroup",
    "MeanSeconds",
    "UtteranceSeconds",
    "MingleParams",
    "NoFloorError",
    "Party",
    "build_mingle",
    "build_mingle_in_room",
    "mingle",
    "write_party",
]

SALSA_RADIUS = RadiusLaw(base=0.444, per_member=0.067)  # metres, fit to SALSA (module doc)
DENSITY_PER_M2 = 0.4  # people per m^2 of a room picked for them (SALSA: ~18 in ~45 m^2)
MAX_DENSITY_PER_M2 = 1.0  # people per m^2: beyond this groups cannot find room
MIN_ROOM_M = 4.0  # metres, smallest room side picked
# Share of groups of each size 2..8 at the start: SALSA's groups per frame by size.
SALSA_GROUP_SHARE = (1.36, 1.49, 0.83, 0.47, 0.33, 0.21, 0.02)
GROUP_MARGIN_M = 0.15  # metres kept free around a group's outer ring
ALONE_CLAIM_M = 0.5  # metres, floor reserved around someone standing alone
WALL_GAP_M = 0.35  # metres, places keep this far from the walls (plus a body)
WALL_MARGIN_M = 0.05  # metres, no place (noise included) comes closer to a wall (plus a body)
SETTLE_S = 2.5  # seconds allowed beyond distance / speed to stop and turn
MAKE_ROOM_S = 1.0  # seconds before a newcomer arrives that the members make room
WALK_SPEED_M_S = (0.9, 1.3)  # m/s, party walking speeds
GLANCE_MEAN_S = 5.0  # seconds, mean time between glances of someone alone
JOIN_SHARE = 0.7  # chance that someone alone who decides to act joins a group
PAIR_SHARE = 0.25  # ... or pairs up with someone else alone (else wanders)
LEAVE_TO_GROUP_SHARE = 0.5  # chance that a leaver walks straight to another group
MEAN_SPLIT_S = 400.0  # seconds, mean time before a group of >= 4 splits
MEAN_MERGE_S = 600.0  # seconds, mean time before a group merges with a neighbour
MERGE_REACH_M = 3.5  # metres, groups further apart than this do not merge
JOIN_REACH_M = 5.0  # metres, people prefer groups nearer than this
JOIN_SIZE_PENALTY = 0.3  # a group of n is joined 1 / (1 + penalty n) as often
PASS_GAP_S = (10.0, 60.0)  # seconds, a passer-by waits this long between crossings
PLACE_TRIES = 60  # random draws when looking for free floor
START_MISSES = 500  # groups in a row that find no floor before the largest size shrinks
ROOM_RETRIES = 10  # times an auto-sized room grows when the drawn party does not fit
ROOM_GROWTH = 1.1  # factor of each growth
ROBOT_ID = 0
ROBOT_WALL_GAP_M = 0.6  # metres from the west wall to the watching robot
ROBOT_CLAIM_M = 0.6  # metres of floor kept free around the robot
ANGLE_JITTER = 0.4  # share of the even gap a member's angle may deviate by
MAX_ASPECT = 4.0  # longest over shortest o-space axis of a group at unevenness 1
GAP_CONCENTRATION = 0.4  # Dirichlet concentration of uneven gaps (below 1: a few wide gaps)
ROW_STRETCH = 1.8  # a side-by-side row stands on an arc this much wider than a circle's radius
ROW_MAX = 4  # largest side-by-side row; larger groups form circles or presenter and audience
AUDIENCE_ARC = math.radians(150.0)  # radians, widest arc an audience stands on
SHOULDER_GAP_M = 0.05  # metres between neighbours of a row or an audience beyond the spacing
CIRCLE, ROW, AUDIENCE = "circle", "side-by-side", "presenter-audience"
CORNER = "corner"  # a half circle in a room's corner, facing into it
CORNER_ARC = math.pi  # radians, the arc a group in a corner stands on
TABLE_SIZE_M = (0.8, 0.8, 0.75)  # metres: diameter, diameter, height of a round table
BAR_SIZE_M = (2.0, 0.5, 1.1)  # metres: length, depth, height of a bar counter at a wall
POSTER_SIZE_M = (1.0, 0.05, 1.8)  # metres: width, depth, height of a poster board at a wall
FURNITURE_GAP_M = 0.08  # metres between a body's disc and the furniture it stands at
FURNITURE_WALL_END_M = 0.4  # metres, a bar or a poster keeps this far from the room's corners
# Scripted changes (`scenarios.changes`).
FIRST_CHANGE_S = 5.0  # seconds into the party before the first scripted change
CHANGE_GAP_S = 3.0  # seconds a scripted change waits beyond the end of the one before
SETTLED_S = 10.0  # seconds a group stands as it is before a scripted change takes it on
CHANGE_SLACK_S = 10.0  # seconds beyond a walker's planned arrival the group is left alone
APPROACH_M = 1.2  # metres from their place a latecomer's last straight walk up starts
CHANGED_MAX = 6  # people: a scripted join or merge makes a group of at most this many
APPROACH_SPEED_M_S = 1.0  # m/s, default speed of a latecomer walking up


# Option types of a party, declared alike by every scenario that plans one (`scenarios.concourse`).
LargestGroup = Annotated[int, Range(2, 12)]
"""The largest group a party allows, people: 2 to 12."""
MeanSeconds = Annotated[float, Range(1.0, unit="s")]
"""A mean time of a party's comings and goings (a stay in a group, a time alone), seconds: >= 1."""
UtteranceSeconds = Annotated[float, Range(0.5, 60.0, unit="s")]
"""The mean length of one speaker's turn, seconds: 0.5 to 60."""


class NoFloorError(ValueError):
    """The scene's people do not fit its floor (a party's room, a concourse's hall)."""


@shared_help(circle=CIRCLE_OPTIONS, changes=CHANGE_OPTIONS)
@dataclass(frozen=True)
class MingleParams:
    """Every number that shapes a party: the options of ``mingle``, declared once here.

    Attributes:
        people: guests.
        duration: length of the party, seconds.
        room_side: side of the square room, metres; 0: 0.4 people per m^2, at least 4 m, grown
            by 10% steps while the drawn party does not fit.
        max_group_size: largest group; SALSA holds groups of 8.
        robot: whether the robot stands by the west wall, watching.
        passers_by: extra people crossing the room now and then.
        {circle}
        mean_stay: mean time a member stays in a group, seconds.
        mean_alone: mean time someone stays alone before acting, seconds.
        alone_share: share of the guests alone at the start.
        mean_utterance: mean length of one speaker's turn, seconds.
        spacing: closest two people's places may be, metres; below the default 0.63 (bodies
            as discs that enclose the arms) people get body discs of radius
            ``(spacing - 0.03) / 2`` and can stand shoulder to shoulder (SALSA's
            nearest-neighbour distance q10 is 0.44 m).
        unevenness: how unevenly a group's members spread round its o-space circle: each
            angular gap is ``1 - unevenness`` of the even gap plus ``unevenness`` of a gap
            drawn from a Dirichlet of concentration 0.4 (a few wide gaps; never closer than
            ``spacing``), so groups open on one side and bunch on another; and each group
            of three or more is an ellipse of axes ratio drawn uniform in
            [1, 1 + 3 unevenness]; 0: evenly spread round a circle, as before.
        arrangements: share of the groups formed that are not circles: half of them (groups
            of up to 4) stand side by side on a wide arc facing one point (at a bar), the
            others as presenter and audience (one faces the rest, who face them, as at a
            poster); a group that outgrows its arrangement becomes a circle.
        furniture: pieces of furniture, in turn a round table, a bar counter at a wall, a
            poster at a wall and a room's corner, each with a group standing at it from the
            start (a ring round the table, a row along the bar facing it, a presenter at the
            poster and an audience facing them, a half circle in the corner facing it);
            people leave and (at a table) join these groups, which never merge, split or
            move. The furniture is in the MuJoCo scene; people walking do not collide with
            it.
        {changes}
    """

    people: Annotated[int, Range(2, 100)] = 18
    duration: SceneSeconds = 600.0
    room_side: Annotated[float, Range(0.0, 100.0, unit="m")] = 0.0
    max_group_size: LargestGroup = 8
    robot: bool = False
    passers_by: Annotated[int, Range(0, 20)] = 0
    radius_base: Annotated[float, Range(0.3, 2.0, unit="m")] = SALSA_RADIUS.base
    radius_per_member: Annotated[float, Range(0.0, 0.5)] = SALSA_RADIUS.per_member
    radius_spread: Annotated[float, Range(0.0, 0.5)] = 0.10
    position_noise: PlaceNoise = 0.05
    orientation_noise: Annotated[float, Range(0.0, 1.0)] = 0.7
    head_noise: Annotated[float, Range(0.0, 1.0, unit="rad")] = 0.2
    mean_stay: MeanSeconds = 300.0
    mean_alone: MeanSeconds = 10.0
    alone_share: Annotated[float, Range(0.0, 1.0)] = 0.08
    mean_utterance: UtteranceSeconds = 4.0
    spacing: Annotated[float, Range(0.43, 1.0, unit="m")] = SPACING_M
    unevenness: Annotated[float, Range(0.0, 1.0)] = 0.0
    arrangements: Annotated[float, Range(0.0, 1.0)] = 0.0
    furniture: Annotated[int, Range(0, 6)] = 0
    event_rate: EventRate = 0.0
    event_kinds: EventKinds = "mixed"
    approach_speed: ApproachSpeed = APPROACH_SPEED_M_S

    def check(self, name: str) -> None:
        """`ValueError` naming the option for impossible values: each out of its range
        (`scenarios.registry.check_ranges`), or a party that cannot fit its room."""
        check_ranges(name, self)
        if self.room_side > 0.0:
            if self.room_side < MIN_ROOM_M:
                raise ValueError(
                    f"{name}: option room_side must be 0 (picked from the number of people) or "
                    f">= {MIN_ROOM_M:g} m, got {self.room_side:g}"
                )
            density = (self.people + self.passers_by) / self.room_side**2
            if density > MAX_DENSITY_PER_M2:
                most = int(MAX_DENSITY_PER_M2 * self.room_side**2)
                raise ValueError(
                    f"{name}: {self.people + self.passers_by} people do not fit a "
                    f"{self.room_side:g} m x {self.room_side:g} m room with room to mingle "
                    f"(at most {MAX_DENSITY_PER_M2:g} per m^2, i.e. {most} people); "
                    "give a larger room_side or 0"
                )

    def side(self) -> float:
        """The room's side, metres."""
        if self.room_side > 0.0:
            return self.room_side
        return max(MIN_ROOM_M, math.sqrt((self.people + self.passers_by) / DENSITY_PER_M2))


@dataclass
class _Group:
    members: list[int]
    centre: np.ndarray
    radius: float
    angles: dict[int, float]
    record: int = -1  # index of its current record
    version: int = 0
    aspect: float = 1.0  # long over short axis of its o-space (1: a circle)
    axis: float = 0.0  # direction of the long axis, radians
    kind: str = CIRCLE  # CIRCLE, ROW (side by side) or AUDIENCE (presenter and audience)
    stretch: float = 1.0  # places stand on a circle of radius * stretch (a row's is wider)
    presenter: int = -1  # the presenter of an AUDIENCE
    mid: float | None = None  # fixed direction of a row's middle or the presenter (furniture)
    hold: float = 0.0  # smallest radius, metres (a ring round a table)
    anchor: int = -1  # the furniture it stands at (it never merges, splits or moves)
    spot: np.ndarray | None = None  # centre of the floor it takes, if not its centre (a bar)

    def place_of(self, m: int) -> np.ndarray:
        """(2,) where member ``m`` stands on the o-space circle (before noise), metres."""
        angle = self.angles[m]
        radius = self.radius * self.stretch
        if self.aspect == 1.0:
            return self.centre + radius * np.array([math.cos(angle), math.sin(angle)])
        return self.centre + radius * ellipse_offsets([angle], self.aspect, self.axis)[0]


@dataclass
class _Record:
    """A group's shape from one moment on, as planned: ``group`` (open-ended) and its ``end``,
    which comes earlier as members are sent away (at or before the start: it never forms), the
    speeds of the members walking up to it and, for a scripted change, the records it
    continues (``group.newcomers`` names who is new)."""

    group: PlannedGroup
    end: float = math.inf
    speeds: dict[int, float] = field(default_factory=dict)
    continues: tuple[int, ...] = ()  # the records a scripted change continues (indices)


@dataclass
class _Alone:
    person: int
    spot: np.ndarray
    facing: float
    start: float
    end: float = math.inf


class Party:
    """Plans the party: who is where, in which group, from when to when (`run`); a patch of a
    larger scene too (``first_id``, `translate`; `scenarios.concourse`)."""

    def __init__(
        self,
        params: MingleParams,
        rng: np.random.Generator,
        side: float,
        *,
        keep_clear: tuple[np.ndarray, ...] = (),
        first_id: int = 1,
    ) -> None:
        self.p = params
        self.keep_clear = keep_clear  # spots no group or person may take (the robot's)
        self.rng = rng
        self.half = 0.5 * side
        self.shape = CircleShape(
            RadiusLaw(params.radius_base, params.radius_per_member, params.spacing),
            params.radius_spread,
            CircleNoise(params.position_noise, params.orientation_noise, params.spacing),
        )
        self.ids = list(range(first_id, first_id + params.people))
        self.records: list[_Record] = []
        self.alone: list[_Alone] = []
        self.walks: list[tuple[float, int, Intent]] = []
        self.events: list[tuple[float, str, str]] = []
        self.groups: dict[int, _Group] = {}
        self.group_of: dict[int, int] = {}
        self.alone_at: dict[int, _Alone] = {}
        self.busy_until: dict[int, float] = {}
        self.position: dict[int, np.ndarray] = {}
        self.version: dict[int, int] = dict.fromkeys(self.ids, 0)
        self.queue: list[tuple[float, int, str, tuple]] = []
        self.count = 0
        self.next_gid = 0
        self.furniture: list[Furniture] = []
        self.changing: dict[int, float] = {}  # group -> when its scripted change is over

    # -- floor space ------------------------------------------------------------------------

    def reach(self, radius: float) -> float:
        """Radius of the floor a group whose members stand within ``radius`` occupies."""
        return radius + PLANNING_RADIUS_M + GROUP_MARGIN_M

    def extent(self, g: _Group, radius: float | None = None) -> float:
        """How far from its floor centre (`floor_centre`) group ``g``'s members stand, with
        o-space ``radius`` (default its own): its long semi-axis; a row's half length."""
        radius = g.radius if radius is None else radius
        if g.kind == ROW:
            return max(radius, 0.5 * (ROW_MAX - 1) * (self.p.spacing + SHOULDER_GAP_M))
        return radius * math.sqrt(g.aspect)

    def floor_centre(self, g: _Group) -> np.ndarray:
        """The middle of the floor ``g`` takes: its centre, or a row's middle."""
        return g.centre if g.spot is None else g.spot

    def draw_shape(self, n: int, radius: float) -> _Group:
        """The kind and o-space shape of a new group of ``n`` and o-space ``radius`` (drawn
        only when the options ``arrangements`` and ``unevenness`` ask), as a template."""
        shape = _Group([], np.zeros(2), radius, {})
        if self.p.arrangements > 0.0 and self.rng.random() < self.p.arrangements:
            shape.kind = ROW if n <= ROW_MAX and self.rng.random() < 0.5 else AUDIENCE
            if shape.kind == ROW:
                shape.mid = float(self.rng.uniform(-math.pi, math.pi))
        if self.p.unevenness > 0.0 and n > 2 and shape.kind == CIRCLE:
            shape.aspect = 1.0 + self.p.unevenness * (MAX_ASPECT - 1.0) * float(self.rng.random())
            shape.axis = float(self.rng.uniform(-math.pi, math.pi))
        return shape

    def claim(self, shape: _Group) -> float:
        """The floor radius a new group of template ``shape`` claims."""
        return self.reach(self.extent(shape))

    def fits(
        self,
        centre: np.ndarray,
        claim: float,
        *,
        ignore_groups: tuple[int, ...] = (),
        ignore_people: tuple[int, ...] = (),
    ) -> bool:
        """Whether floor of radius ``claim`` round ``centre`` is inside the walls and clear of
        every group, everyone alone and every kept spot (those ignored aside)."""
        bound, obstacles = self.obstacles(claim, ignore_groups, ignore_people)
        return _clear(float(centre[0]), float(centre[1]), bound, obstacles)

    def obstacles(
        self, claim: float, ignore_groups: tuple[int, ...], ignore_people: tuple[int, ...]
    ) -> tuple[float, list[tuple[float, float, float]]]:
        """What floor of radius ``claim`` must keep clear of: the farthest its centre may be
        from the room's middle along either axis, metres, and ``(x, y, distance)`` of every
        group's floor centre, spot of someone alone and kept spot (those ignored aside),
        metres, with the distance ``claim`` must keep from it."""
        limit = self.half - WALL_GAP_M - PLANNING_RADIUS_M
        inner = claim - PLANNING_RADIUS_M - GROUP_MARGIN_M
        obstacles = []
        for gid, g in self.groups.items():
            if gid in ignore_groups:
                continue
            c = self.floor_centre(g)
            obstacles.append((float(c[0]), float(c[1]), claim + self.reach(self.extent(g))))
        for pid, a in self.alone_at.items():
            if pid in ignore_people:
                continue
            obstacles.append((float(a.spot[0]), float(a.spot[1]), claim + ALONE_CLAIM_M))
        for spot in self.keep_clear:
            obstacles.append((float(spot[0]), float(spot[1]), claim + ROBOT_CLAIM_M))
        return limit - max(inner, 0.0), obstacles

    def free_spot(
        self,
        claim: float,
        *,
        near: np.ndarray | None = None,
        within: float = 0.0,
        ignore_groups: tuple[int, ...] = (),
        ignore_people: tuple[int, ...] = (),
    ) -> np.ndarray | None:
        """(2,) a centre of free floor of radius ``claim`` (`fits`), metres: drawn uniform in
        the room, or ``near`` a point (0.5 m to ``within`` from it, in a uniform direction);
        None after `PLACE_TRIES` draws that do not fit."""
        limit = self.half - WALL_GAP_M - PLANNING_RADIUS_M
        bound, obstacles = self.obstacles(claim, ignore_groups, ignore_people)
        uniform = self.rng.uniform
        if near is None:
            for _ in range(PLACE_TRIES):
                spot = uniform(-limit, limit, size=2)
                if _clear(float(spot[0]), float(spot[1]), bound, obstacles):
                    return spot
            return None
        # ``near + reach * (cos, sin)``, one coordinate at a time (the same sums and products)
        nx, ny = float(near[0]), float(near[1])
        for _ in range(PLACE_TRIES):
            angle = uniform(-math.pi, math.pi)
            reach = uniform(0.5, within)
            x, y = nx + reach * math.cos(angle), ny + reach * math.sin(angle)
            if _clear(x, y, bound, obstacles):
                return np.array([x, y])
        return None

    # -- groups -----------------------------------------------------------------------------

    def draw_radius(self, n: int) -> float:
        return max(self.shape.radius(n, self.rng, least=0.6), min_radius(n, spacing=self.p.spacing))

    def layout(self, g: _Group, angles: dict[int, float]) -> dict[int, float]:
        """The members' angles round ``g``'s centre for its kind (a circle, `spread`; a row
        or presenter and audience, `arc`); a kind the group no longer suits (a row grown past
        `ROW_MAX`, an audience of fewer than two or whose presenter left) becomes a circle."""
        n = len(g.members)
        g.radius = max(g.radius, g.hold)
        if (
            g.kind == ROW
            and n > ROW_MAX
            or g.kind == AUDIENCE
            and (n < 3 or g.presenter not in g.members and g.presenter >= 0)
        ):
            if g.kind == ROW and g.spot is not None and g.anchor < 0:
                g.centre, g.spot, g.mid = g.spot, None, None  # the circle forms where it stood
            g.kind, g.stretch = CIRCLE, 1.0
        if g.kind == CIRCLE:
            return self.spread(g.members, angles, g.radius)
        return self.arc(g, angles)

    def arc(self, g: _Group, angles: dict[int, float]) -> dict[int, float]:
        """A row: the members side by side on an arc of radius `ROW_STRETCH` times the group's
        radius, facing its centre (a bar, a shared view). Presenter and audience: the
        presenter on the circle, the audience side by side on the far side (an arc of at most
        `AUDIENCE_ARC`), in the members' order round the centre. In a corner: a half circle
        toward the room, facing the corner."""
        members = sorted(g.members, key=lambda m: angles[m] % (2.0 * math.pi))
        step_m = self.p.spacing + SHOULDER_GAP_M
        if g.kind == CORNER:  # a half circle facing the corner, the walls at its back
            step = CORNER_ARC / (len(members) - 1)
            g.radius = max(g.radius, step_m / (2.0 * math.sin(0.5 * step)))
            start = g.mid - 0.5 * CORNER_ARC
            return {m: start + k * step for k, m in enumerate(members)}
        if g.kind == ROW:
            g.stretch = ROW_STRETCH
            radius = g.radius * g.stretch
            step = 2.0 * math.asin(min(1.0, step_m / (2.0 * radius)))
            mid = g.mid
            if mid is None:
                mid = _mean_direction(np.array([angles[m] for m in members]))
            turns = [angles[m] % (2.0 * math.pi) for m in members]
            widths = np.diff(turns, append=turns[0] + 2.0 * math.pi)
            first = (int(np.argmax(widths)) + 1) % len(members)
            row = members[first:] + members[:first]
            start = mid - 0.5 * step * (len(row) - 1)
            return {m: start + k * step for k, m in enumerate(row)}
        if g.presenter not in g.members:
            g.presenter = members[int(self.rng.integers(len(members)))]
        audience = [m for m in members if m != g.presenter]
        facing = angles[g.presenter] if g.mid is None else g.mid
        step = 2.0 * math.asin(min(1.0, step_m / (2.0 * g.radius)))
        step = min(step, AUDIENCE_ARC / max(len(audience) - 1, 1))
        start = facing + math.pi - 0.5 * step * (len(audience) - 1)
        # the audience keeps its order round the centre, starting past the presenter
        k0 = members.index(g.presenter)
        order = members[k0 + 1 :] + members[:k0]
        out = {g.presenter: facing}
        out.update({m: start + k * step for k, m in enumerate(order)})
        return out

    def spread(
        self, members: list[int], angles: dict[int, float], radius: float
    ) -> dict[int, float]:
        """Even angles in the members' order around the circle, rotated to move them least,
        each moved at random by up to `ANGLE_JITTER` of the gap, or less where neighbours
        would come closer than the option ``spacing`` (with ``unevenness``: `uneven`)."""
        order = sorted(members, key=lambda m: angles[m] % (2.0 * math.pi))
        n = len(order)
        if self.p.unevenness > 0.0 and n > 2:
            return self.uneven(order, angles, radius)
        gap = 2.0 * math.pi / n
        offsets = np.array([angles[m] - k * gap for k, m in enumerate(order)])
        base = _mean_direction(offsets)
        chord = 2.0 * radius * math.sin(min(gap, math.pi) / 2.0)
        room = max(0.0, 1.0 - self.p.spacing / chord) if n > 2 else ANGLE_JITTER
        share = min(ANGLE_JITTER, room)
        jitter = self.rng.uniform(-share, share, size=n) * gap
        return {m: base + k * gap + float(jitter[k]) for k, m in enumerate(order)}

    def uneven(self, order: list[int], angles: dict[int, float], radius: float) -> dict[int, float]:
        """Angles of the members (``order``: by angle) with uneven gaps: each gap is
        ``1 - unevenness`` of the even one plus ``unevenness`` of a gap drawn from a
        Dirichlet of concentration `GAP_CONCENTRATION`, then squeezed so that no gap brings
        neighbours closer than ``spacing``; the widest drawn gap goes where the members'
        widest gap was, and the whole is rotated to move them least."""
        n = len(order)
        u = self.p.unevenness
        drawn = (1.0 - u) / n + u * self.rng.dirichlet(np.full(n, GAP_CONCENTRATION))
        closest = 2.0 * math.asin(min(1.0, self.p.spacing / (2.0 * radius)))
        closest = min(closest, 2.0 * math.pi / n)
        gaps = closest + (2.0 * math.pi - n * closest) * drawn
        gaps = np.roll(gaps, n - 1 - int(np.argmax(gaps)))  # the widest gap closes the ring
        turns = [angles[m] % (2.0 * math.pi) for m in order]
        widths = np.diff(turns, append=turns[0] + 2.0 * math.pi)
        first = (int(np.argmax(widths)) + 1) % n  # the member after the widest gap
        order = order[first:] + order[:first]
        at = np.concatenate([[0.0], np.cumsum(gaps[:-1])])
        offsets = np.array([angles[m] for m in order]) - at
        base = _mean_direction(offsets)
        return {m: base + float(at[k]) for k, m in enumerate(order)}

    def record(
        self,
        gid: int,
        t: float,
        speeds: dict[int, float] | None = None,
        *,
        newcomers: tuple[int, ...] | None = None,
        continues: tuple[int, ...] = (),
    ) -> None:
        """A new planned record of group ``gid``'s current shape from ``t`` (``newcomers``,
        ``continues``: a scripted change, see `_Record`)."""
        g = self.groups[gid]
        members = list(g.angles)
        angles = np.array([g.angles[m] for m in members])
        places, facings = self.shape.noise.places(
            g.centre, g.radius * g.stretch, angles, self.rng, aspect=g.aspect, axis=g.axis
        )
        if g.kind == AUDIENCE:  # the audience faces the presenter, who faces the audience
            noise = facings - facing_centre(places, g.centre)
            k = members.index(g.presenter)
            targets = np.repeat(places[k : k + 1], len(members), axis=0)
            targets[k] = np.delete(places, k, axis=0).mean(axis=0)
            d = targets - places
            facings = np.angle(np.exp(1j * (np.arctan2(d[:, 1], d[:, 0]) + noise)))
        edge = self.half - PLANNING_RADIUS_M - WALL_MARGIN_M
        places = _within(places, edge)
        if g.anchor >= 0:  # at a wall: the clip may bring two closer than the spacing
            for _ in range(10):
                places = _within(separate(places, spacing=self.p.spacing), edge)
        planned = PlannedGroup(tuple(members), places, facings, g.centre, t, newcomers=newcomers)
        self.records.append(_Record(planned, speeds=speeds or {}, continues=continues))
        g.record = len(self.records) - 1
        g.version += 1
        if g.kind == ROW:
            self.events.append((t, "arrange", f"group {sorted(members)} stands side by side"))
        elif g.kind == AUDIENCE:
            audience = sorted(m for m in members if m != g.presenter)
            self.events.append((t, "arrange", f"person {g.presenter} presents to {audience}"))
        for k, m in enumerate(members):
            self.position[m] = places[k]

    def close_all(self, gid: int, t: float, *, but: int | None = None) -> None:
        """Every open record holding a member of ``gid`` (``but`` one) ends at ``t``."""
        members = set(self.groups[gid].members) - {but}
        for rec in self.records:
            if rec.end > t and not members.isdisjoint(rec.group.members):
                rec.end = t

    def new_group(
        self,
        members: list[int],
        centre: np.ndarray,
        radius: float,
        t: float,
        *,
        shape: _Group | None = None,
    ) -> int:
        """A group of ``members`` round ``centre`` (a row: ``centre`` is its middle, and it
        faces a point `ROW_STRETCH` times ``radius`` beyond); ``shape``: the template of its
        kind, o-space shape, direction, radius floor and furniture (`draw_shape`, `furnish`),
        else a circle."""
        gid = self.next_gid
        self.next_gid += 1
        g = _Group(list(members), centre.copy(), radius, {})
        if shape is not None:
            g.kind, g.mid, g.hold, g.anchor = shape.kind, shape.mid, shape.hold, shape.anchor
            g.aspect, g.axis = shape.aspect, shape.axis
            if g.kind == ROW and g.anchor < 0 and g.mid is not None:
                g.spot = centre.copy()
                g.centre = centre - radius * ROW_STRETCH * np.array(
                    [math.cos(g.mid), math.sin(g.mid)]
                )
        angles = {}
        for m in members:
            d = self.position[m] - g.centre
            angles[m] = math.atan2(d[1], d[0]) if np.hypot(*d) > 1e-6 else self.rng.uniform(-3, 3)
        g.angles = self.layout(g, angles)
        self.groups[gid] = g
        for m in members:
            self.group_of[m] = gid
            self.end_alone(m, t)
        return gid

    def gather(self, gid: int, t: float) -> None:
        """The members of new group ``gid`` walk to their places from ``t``; it is recorded
        and its split and merge scheduled."""
        g = self.groups[gid]
        speeds = {m: self.walk(m, g.place_of(m), t)[0] for m in g.members}
        self.record(gid, t, speeds=speeds)
        self.schedule_group(gid, t)

    def schedule_group(self, gid: int, t: float) -> None:
        g = self.groups[gid]
        if len(g.members) >= 4:
            self.push(t + self.rng.exponential(MEAN_SPLIT_S), "split", (gid, g.version))
        self.push(t + self.rng.exponential(MEAN_MERGE_S), "merge", (gid, g.version))

    def schedule_member(self, m: int, t: float) -> None:
        self.version[m] += 1
        self.push(t + self.rng.exponential(self.p.mean_stay), "leave", (m, self.version[m]))

    # -- people alone -----------------------------------------------------------------------

    def start_alone(self, m: int, spot: np.ndarray, t: float) -> None:
        facing = float(self.rng.uniform(-math.pi, math.pi))
        entry = _Alone(m, spot.copy(), facing, t)
        self.alone.append(entry)
        self.alone_at[m] = entry
        self.position[m] = spot.copy()
        self.version[m] += 1
        self.push(t + self.rng.exponential(self.p.mean_alone), "decide", (m, self.version[m]))

    def end_alone(self, m: int, t: float) -> None:
        entry = self.alone_at.pop(m, None)
        if entry is not None:
            entry.end = min(entry.end, t)

    def walk(self, m: int, goal: np.ndarray, t: float) -> tuple[float, float]:
        """``m`` walks to ``goal`` from ``t``: (speed, arrival time)."""
        speed = float(self.rng.uniform(*WALK_SPEED_M_S))
        arrive = t + float(np.hypot(*(goal - self.position[m]))) / speed + SETTLE_S
        self.busy_until[m] = arrive
        return speed, arrive

    # -- the timeline -----------------------------------------------------------------------

    def push(self, t: float, kind: str, payload: tuple) -> None:
        if t < self.p.duration:
            self.count += 1
            heapq.heappush(self.queue, (t, self.count, kind, payload))

    def start(self) -> None:
        """The party at t = 0: groups drawn with SALSA's size shares, the rest alone."""
        rng = self.rng
        sizes = np.arange(2, 2 + len(SALSA_GROUP_SHARE))
        share = np.array(SALSA_GROUP_SHARE)
        share = np.where(sizes <= self.p.max_group_size, share, 0.0)
        share = share / share.sum()
        unplaced = [self.ids[k] for k in rng.permutation(len(self.ids))]
        n_alone = int(round(self.p.alone_share * len(unplaced)))
        alone = unplaced[:n_alone]
        unplaced = unplaced[n_alone:]
        largest = self.p.max_group_size  # shrinks when groups keep finding no floor
        misses = 0
        for k in range(self.p.furniture):
            unplaced = self.furnish(k, unplaced)
        while len(unplaced) >= 2:
            n = int(min(rng.choice(sizes, p=share), len(unplaced)))
            if len(unplaced) - n == 1:  # leave nobody as the odd one out, where sizes allow
                if n < largest:
                    n += 1
                elif n > 2:
                    n -= 1
            radius = self.draw_radius(n)
            shape = self.draw_shape(n, radius)
            centre = self.free_spot(self.claim(shape))
            if centre is None:
                if n > 2:
                    misses += 1
                    if misses >= START_MISSES:
                        # No floor for groups this large: draw only smaller ones from now on.
                        largest, misses = n - 1, 0
                        share = np.where(sizes <= largest, share, 0.0)
                        share = share / share.sum()
                    continue
                break
            misses = 0
            members, unplaced = unplaced[:n], unplaced[n:]
            for k, m in enumerate(members):
                angle = 2.0 * math.pi * k / n
                self.position[m] = centre + radius * np.array([math.cos(angle), math.sin(angle)])
            gid = self.new_group(members, centre, radius, 0.0, shape=shape)
            self.record(gid, 0.0)
            self.schedule_group(gid, 0.0)
            for m in members:
                self.schedule_member(m, 0.0)
        alone += unplaced
        self.start_yaw = {}
        for rec in self.records:
            for k, m in enumerate(rec.group.members):
                self.start_yaw[m] = float(rec.group.facings[k])
        for m in alone:
            spot = self.free_spot(ALONE_CLAIM_M)
            if spot is None:
                raise NoFloorError(
                    f"mingle: no free floor for {len(self.ids)} people in a "
                    f"{2 * self.half:g} m room; give a larger room_side"
                )
            self.position[m] = spot
            self.start_alone(m, spot, 0.0)
            self.start_yaw[m] = self.alone_at[m].facing
        self.start_position = dict(self.position)
        if self.p.event_rate > 0.0:
            first = next_change(rng, self.p.event_rate, ready=FIRST_CHANGE_S, last=0.0)
            self.push(first, "change", ())

    def furnish(self, k: int, unplaced: list[int]) -> list[int]:
        """Furniture ``k`` (a table, a bar, a poster, a corner, in turn) and the group that
        stands at it from the start, taken from ``unplaced``: a ring round a table, a row along
        a bar facing it, an audience facing a presenter at a poster, a half circle facing a
        corner. Returns who is left."""
        kind = ("table", "bar", "poster", "corner")[k % 4]
        rng = self.rng
        body = 0.5 * self.p.spacing
        if kind == "table":
            n = int(rng.integers(3, 7))
        elif kind == "corner":
            n = int(rng.integers(3, 6))
        elif kind == "bar":
            n = int(rng.integers(2, ROW_MAX + 1))
        else:
            n = int(rng.integers(3, 7))
        n = min(n, len(unplaced))
        if n < 2:
            return unplaced
        radius = self.draw_radius(n)
        anchored = _Group([], np.zeros(2), radius, {}, anchor=k)
        if kind == "corner":  # the walls are the furniture: no object
            step = CORNER_ARC / (n - 1)
            chord = (self.p.spacing + SHOULDER_GAP_M) / (2.0 * math.sin(0.5 * step))
            radius = anchored.hold = max(radius, chord)
            for _ in range(PLACE_TRIES):
                signs = np.array([1.0, 1.0]) - 2.0 * rng.integers(2, size=2)
                off = math.sqrt(0.5) * radius + PLANNING_RADIUS_M + WALL_MARGIN_M + FURNITURE_GAP_M
                centre = signs * (self.half - off)
                if self.clear(centre, self.reach(radius)):
                    break
            else:
                raise NoFloorError(f"mingle: no free corner in a {2 * self.half:g} m room")
            anchored.kind = CORNER
            anchored.mid = math.atan2(-signs[1], -signs[0])  # the members stand toward the room
            item: Furniture | None = None
        elif kind == "table":
            size = TABLE_SIZE_M
            anchored.hold = 0.5 * size[0] + body + FURNITURE_GAP_M
            radius = max(radius, anchored.hold)
            centre = self.free_spot(self.reach(radius))
            if centre is None:
                raise NoFloorError(
                    f"mingle: no free floor for a table in a {2 * self.half:g} m room"
                )
            item = Furniture(kind, (float(centre[0]), float(centre[1])), size)
        else:
            size = BAR_SIZE_M if kind == "bar" else POSTER_SIZE_M
            front = size[1] + FURNITURE_GAP_M + body  # from the wall to where people stand
            for _ in range(PLACE_TRIES):
                wall = int(rng.integers(4))
                inward = wall * 0.5 * math.pi + math.pi  # the wall's normal into the room
                normal = np.array([math.cos(inward), math.sin(inward)])
                along = np.array([-normal[1], normal[0]])
                reach = self.half - 0.5 * size[0] - FURNITURE_WALL_END_M
                offset = float(rng.uniform(-reach, reach)) * along
                spot = (self.half - 0.5 * size[1]) * -normal + offset
                if kind == "bar":  # the row's arc centre lies beyond the counter: they face it
                    stand = radius * ROW_STRETCH
                    centre = offset - normal * (self.half - front + stand)
                    floor = centre + normal * stand
                else:  # the presenter between the poster and the centre, the audience beyond
                    centre = offset - normal * (self.half - front - radius)
                    floor = centre
                if self.clear(floor, self.reach(radius)):
                    break
            else:
                raise NoFloorError(
                    f"mingle: no free wall for a {kind} in a {2 * self.half:g} m room"
                )
            anchored.kind = ROW if kind == "bar" else AUDIENCE
            anchored.mid = inward if kind == "bar" else inward + math.pi
            item = Furniture(
                kind, (float(spot[0]), float(spot[1])), size, yaw=float(inward + 0.5 * math.pi)
            )
        if item is not None:
            self.furniture.append(item)
        members, rest = unplaced[:n], unplaced[n:]
        for j, m in enumerate(members):
            angle = 2.0 * math.pi * j / n
            self.position[m] = centre + radius * np.array([math.cos(angle), math.sin(angle)])
        gid = self.new_group(members, centre, radius, 0.0, shape=anchored)
        if kind == "bar":
            self.groups[gid].spot = floor
        self.events.append((0.0, "furnish", f"group {sorted(members)} stands at the {kind}"))
        self.record(gid, 0.0)
        self.schedule_group(gid, 0.0)
        for m in members:
            self.schedule_member(m, 0.0)
        return rest

    def clear(self, centre: np.ndarray, claim: float) -> bool:
        """Whether floor of radius ``claim`` round ``centre`` is clear of every group and kept
        spot (walls aside: furniture stands at them)."""
        for g in self.groups.values():
            c = self.floor_centre(g)
            if np.hypot(*(centre - c)) < claim + self.reach(self.extent(g)):
                return False
        return all(np.hypot(*(centre - k)) >= claim + ROBOT_CLAIM_M for k in self.keep_clear)

    def run(self) -> None:
        self.start()
        while self.queue:
            t, _, kind, payload = heapq.heappop(self.queue)
            getattr(self, "on_" + kind)(t, *payload)

    def translate(self, offset: np.ndarray) -> None:
        """Moves the planned party by ``offset`` (2,) metres: every walk, group record, spot of
        someone alone and start position (a party planned in its own square, then put where
        it stands in a larger hall)."""
        dx, dy = float(offset[0]), float(offset[1])

        def moved(point: tuple[float, float] | None) -> tuple[float, float] | None:
            return None if point is None else (point[0] + dx, point[1] + dy)

        self.walks = [
            (
                t,
                m,
                dataclasses.replace(
                    intent,
                    goal=moved(intent.goal),
                    face_point=moved(intent.face_point),
                    gaze_point=moved(intent.gaze_point),
                    appear_at=moved(intent.appear_at),
                ),
            )
            for t, m, intent in self.walks
        ]
        for rec in self.records:
            g = rec.group
            rec.group = PlannedGroup(
                g.members,
                g.places + offset,
                g.facings,
                g.centre + offset,
                g.start,
                g.end,
                newcomers=g.newcomers,
            )
        for entry in self.alone:
            entry.spot = entry.spot + offset
        self.start_position = {m: p + offset for m, p in self.start_position.items()}

    def on_leave(self, t: float, m: int, version: int) -> None:
        if version != self.version[m] or m not in self.group_of:
            return
        if self.busy_until.get(m, 0.0) > t:
            self.push(self.busy_until[m] + 1.0, "leave", (m, version))
            return
        gid = self.group_of.pop(m)
        g = self.groups[gid]
        self.close_all(gid, t)
        g.members.remove(m)
        del g.angles[m]
        self.events.append((t, "leave", f"person {m} leaves group {sorted([*g.members, m])}"))
        self.shrink(gid, t)
        target = None
        if self.rng.random() < LEAVE_TO_GROUP_SHARE:
            target = self.pick_group(m, t, exclude=gid)
        if target is not None and self.join(m, target, t):
            return
        spot = self.free_spot(ALONE_CLAIM_M, near=self.position[m], within=3.0)
        if spot is None:
            spot = self.position[m]
        speed, arrive = self.walk(m, spot, t)
        self.walks.append((t, m, Intent(goal=(float(spot[0]), float(spot[1])), speed=speed)))
        self.position[m] = spot
        self.start_alone(m, spot, arrive)

    def shrink(self, gid: int, t: float) -> None:
        """After someone left: the rest re-form (or the last one stands alone)."""
        g = self.groups[gid]
        if len(g.members) >= 2:
            g.radius = self.draw_radius(len(g.members))
            g.angles = self.layout(g, g.angles)
            self.record(gid, t)
            self.schedule_group(gid, t)
            return
        (last,) = g.members
        del self.groups[gid]
        self.group_of.pop(last, None)
        self.version[last] += 1
        self.start_alone(last, self.position[last], t)

    def pick_group(self, m: int, t: float, *, exclude: int = -1) -> int | None:
        hx, hy = self.position[m].tolist()
        options, weights = [], []
        for gid, g in self.groups.items():
            if gid == exclude or len(g.members) >= self.p.max_group_size:
                continue
            if self.changing.get(gid, -math.inf) > t:  # a scripted change under way
                continue
            cx, cy = g.centre.tolist()
            d = float(np.hypot(cx - hx, cy - hy))
            options.append(gid)
            weights.append(math.exp(-d / JOIN_REACH_M) / (1.0 + JOIN_SIZE_PENALTY * len(g.members)))
        if not options:
            return None
        w = np.array(weights) / sum(weights)
        return options[int(self.rng.choice(len(options), p=w))]

    def join(self, m: int, gid: int, t: float) -> bool:
        """``m`` walks up to group ``gid``; the members make room just before ``m`` arrives
        (the group, as it was, ends then) and the larger group forms once all stand."""
        g = self.groups[gid]
        n = len(g.members) + 1
        radius = self.draw_radius(n)
        centre = g.centre
        claim = self.reach(self.extent(g, radius))
        if not self.fits(self.floor_centre(g), claim, ignore_groups=(gid,), ignore_people=(m,)):
            return False
        self.end_alone(m, t)
        d = self.position[m] - centre
        angles = dict(g.angles)
        angles[m] = math.atan2(d[1], d[0])
        g.members.append(m)
        g.radius = radius
        g.angles = self.layout(g, angles)
        self.group_of[m] = gid
        speed, arrive = self.walk(m, g.place_of(m), t)
        shift = max(t, arrive - SETTLE_S - MAKE_ROOM_S)
        self.close_all(gid, shift, but=m)
        self.record(gid, shift, speeds={m: speed})
        planned = self.records[g.record].group
        k = planned.members.index(m)
        self.walks.append((t, m, standing(planned.places[k], planned.facings[k], speed=speed)))
        self.schedule_group(gid, t)
        self.schedule_member(m, t)
        self.events.append((t, "join", f"person {m} joins group {sorted(g.members)}"))
        return True

    def on_decide(self, t: float, m: int, version: int) -> None:
        if version != self.version[m] or m not in self.alone_at:
            return
        draw = self.rng.random()
        if draw < JOIN_SHARE:
            target = self.pick_group(m, t)
            if target is not None and self.join(m, target, t):
                return
        elif draw < JOIN_SHARE + PAIR_SHARE:
            others = [o for o in self.alone_at if o != m and self.busy_until.get(o, 0.0) <= t]
            if others:
                o = others[int(self.rng.integers(len(others)))]
                if self.pair(m, o, t):
                    return
        spot = self.free_spot(ALONE_CLAIM_M, near=self.position[m], within=4.0, ignore_people=(m,))
        if spot is None:
            self.version[m] += 1
            self.push(t + self.rng.exponential(self.p.mean_alone), "decide", (m, self.version[m]))
            return
        self.end_alone(m, t)
        speed, arrive = self.walk(m, spot, t)
        self.walks.append((t, m, Intent(goal=(float(spot[0]), float(spot[1])), speed=speed)))
        self.position[m] = spot
        self.start_alone(m, spot, arrive)

    def pair(self, a: int, b: int, t: float) -> bool:
        radius = self.draw_radius(2)
        centre = 0.5 * (self.position[a] + self.position[b])
        shape = self.draw_shape(2, radius)
        claim = self.claim(shape)
        if not self.fits(centre, claim, ignore_people=(a, b)):
            spot = self.free_spot(claim, near=centre, within=2.0, ignore_people=(a, b))
            if spot is None:
                return False
            centre = spot
        self.gather(self.new_group([a, b], centre, radius, t, shape=shape), t)
        for m in (a, b):
            self.schedule_member(m, t)
        self.events.append((t, "pair", f"people {a} and {b} start talking"))
        return True

    def on_split(self, t: float, gid: int, version: int) -> None:
        g = self.groups.get(gid)
        if g is None or g.version != version or len(g.members) < 4 or g.anchor >= 0:
            return
        if any(self.busy_until.get(m, 0.0) > t for m in g.members):
            self.schedule_group(gid, t)
            return
        order = sorted(g.members, key=lambda m: g.angles[m] % (2.0 * math.pi))
        n = len(order)
        k = int(self.rng.integers(2, n - 1))
        first = int(self.rng.integers(n))
        moving = [order[(first + j) % n] for j in range(k)]
        staying = [m for m in order if m not in moving]
        radius = self.draw_radius(len(moving))
        shape = self.draw_shape(len(moving), radius)
        claim = self.claim(shape)
        stay_radius = self.draw_radius(len(staying))
        stay_claim = self.reach(self.extent(g, stay_radius))
        here = self.floor_centre(g)
        # The moving part settles beside the group, on the side it stood.
        side = np.mean([self.position[m] for m in moving], axis=0) - here
        side = side / max(float(np.hypot(*side)), 1e-9)
        centre = None
        for extra in (0.2, 0.6, 1.2):
            guess = here + side * (stay_claim + claim + extra)
            if self.fits(
                guess, claim, ignore_groups=(gid,), ignore_people=tuple(g.members)
            ) and self.fits_pair(guess, claim, here, stay_claim):
                centre = guess
                break
        if centre is None:
            return
        self.close_all(gid, t)
        self.events.append((t, "split", f"group {sorted(g.members)} splits off {sorted(moving)}"))
        g.members = staying
        g.radius = stay_radius
        g.angles = self.layout(g, {m: g.angles[m] for m in staying})
        for m in moving:
            self.group_of.pop(m)
        new = self.new_group(moving, centre, radius, t, shape=shape)
        self.record(gid, t)
        self.schedule_group(gid, t)
        self.gather(new, t)

    def fits_pair(self, a: np.ndarray, ra: float, b: np.ndarray, rb: float) -> bool:
        return float(np.hypot(*(a - b))) >= ra + rb

    def on_merge(self, t: float, gid: int, version: int) -> None:
        g = self.groups.get(gid)
        if g is None or g.version != version or g.anchor >= 0:
            return
        best, best_d = None, MERGE_REACH_M
        for hid, h in self.groups.items():
            if hid == gid or len(g.members) + len(h.members) > self.p.max_group_size:
                continue
            if h.anchor >= 0:
                continue
            d = float(np.hypot(*(h.centre - g.centre))) - g.radius - h.radius
            if d < best_d:
                best, best_d = hid, d
        if best is None:
            self.schedule_group(gid, t)
            return
        h = self.groups[best]
        members = g.members + h.members
        if any(self.busy_until.get(m, 0.0) > t for m in members):
            self.schedule_group(gid, t)
            return
        radius = self.draw_radius(len(members))
        ng, nh = len(g.members), len(h.members)
        centre = (ng * self.floor_centre(g) + nh * self.floor_centre(h)) / (ng + nh)
        shape = self.draw_shape(len(members), radius)
        claim = self.claim(shape)
        if not self.fits(centre, claim, ignore_groups=(gid, best), ignore_people=tuple(members)):
            self.schedule_group(gid, t)
            return
        self.close_all(gid, t)
        self.close_all(best, t)
        detail = f"groups {sorted(g.members)} and {sorted(h.members)} merge"
        self.events.append((t, "merge", detail))
        del self.groups[gid]
        del self.groups[best]
        for m in members:
            self.group_of.pop(m, None)
        self.gather(self.new_group(members, centre, radius, t, shape=shape), t)

    # -- scripted changes (`scenarios.changes`) ----------------------------------------------

    def idle(self, gid: int, t: float) -> bool:
        """Whether group ``gid`` may take part in a scripted change at ``t``: not at furniture,
        nobody in it walking, and standing as it is for `SETTLED_S` (or from the start)."""
        g = self.groups[gid]
        since = self.records[g.record].group.start
        return (
            g.anchor < 0
            and (since == 0.0 or t >= since + SETTLED_S)
            and all(self.busy_until.get(m, 0.0) <= t for m in g.members)
        )

    def on_change(self, t: float) -> None:
        """A scripted change at ``t`` (a latecomer joins, a member drifts away, a group walks
        over to merge), then the next one scheduled."""
        p = self.p
        idle = [gid for gid in self.groups if self.idle(gid, t)]
        alone = [m for m in self.alone_at if self.busy_until.get(m, 0.0) <= t]
        most = min(p.max_group_size, CHANGED_MAX)
        joinable = [gid for gid in idle if len(self.groups[gid].members) < most]
        leavable = [gid for gid in idle if len(self.groups[gid].members) >= 3]
        pairs = self.merge_pairs(idle)
        possible = {JOIN: bool(alone and joinable), LEAVE: bool(leavable), MERGE: bool(pairs)}
        kind = draw_kind(self.rng, p.event_kinds, possible)
        done = t
        if kind == JOIN:
            m = alone[int(self.rng.integers(len(alone)))]
            done = self.latecomer(m, joinable[int(self.rng.integers(len(joinable)))], t)
        elif kind == LEAVE:
            done = self.drift(leavable[int(self.rng.integers(len(leavable)))], t)
        elif kind == MERGE:
            big, small = pairs[int(self.rng.integers(len(pairs)))]
            done = self.walk_over(big, small, t)
        ready = max(t, done) + CHANGE_GAP_S
        self.push(next_change(self.rng, p.event_rate, ready=ready, last=t), "change", ())

    def merge_pairs(self, idle: list[int]) -> list[tuple[int, int]]:
        """(larger, smaller) groups among ``idle`` near enough to merge (`MERGE_REACH_M`)
        whose members together make a group the party allows, of `CHANGED_MAX` at most."""
        out = []
        for a in idle:
            for b in idle:
                g, h = self.groups[a], self.groups[b]
                if (len(g.members), -a) <= (len(h.members), -b):
                    continue  # each pair once: the larger first (ties: the older)
                if len(g.members) + len(h.members) > min(self.p.max_group_size, CHANGED_MAX):
                    continue
                if float(np.hypot(*(h.centre - g.centre))) - g.radius - h.radius < MERGE_REACH_M:
                    out.append((a, b))
        return out

    def latecomer(self, m: int, gid: int, t: float) -> float:
        """``m``, alone, walks up to group ``gid`` at the approach speed: to `APPROACH_M` out
        from their place, then straight to it; the members make room just before ``m``
        arrives, the group as it was recorded until then. Returns when ``m`` should have
        arrived (``t`` when there is no room)."""
        g = self.groups[gid]
        radius = self.draw_radius(len(g.members) + 1)
        claim = self.reach(self.extent(g, radius))
        if not self.fits(self.floor_centre(g), claim, ignore_groups=(gid,), ignore_people=(m,)):
            return t
        speed = self.p.approach_speed
        before = g.record
        self.end_alone(m, t)
        d = self.position[m] - g.centre
        angles = dict(g.angles)
        angles[m] = math.atan2(d[1], d[0])
        g.members.append(m)
        g.radius = radius
        g.angles = self.layout(g, angles)
        self.group_of[m] = gid
        place = g.place_of(m)
        outward = place - g.centre
        near = place + APPROACH_M * outward / max(float(np.hypot(*outward)), 1e-9)
        edge = self.half - WALL_GAP_M - PLANNING_RADIUS_M
        near = np.clip(near, -edge, edge)
        on = t + float(np.hypot(*(near - self.position[m]))) / speed
        arrive = on + float(np.hypot(*(place - near))) / speed + SETTLE_S
        shift = max(on, arrive - SETTLE_S - MAKE_ROOM_S)
        self.close_all(gid, shift, but=m)
        self.record(gid, shift, speeds={m: speed}, newcomers=(m,), continues=(before,))
        planned = self.records[g.record].group
        k = planned.members.index(m)
        self.walks.append((t, m, Intent(goal=(float(near[0]), float(near[1])), speed=speed)))
        self.walks.append((on, m, standing(planned.places[k], planned.facings[k], speed=speed)))
        for x in g.members:  # nobody leaves, splits off or merges until the latecomer stands
            self.busy_until[x] = max(self.busy_until.get(x, 0.0), arrive + CHANGE_SLACK_S)
        self.changing[gid] = arrive + CHANGE_SLACK_S  # ... nor joins
        self.schedule_group(gid, t)
        self.schedule_member(m, t)
        detail = f"person {m} walks up to join group {sorted(g.members)} (scripted)"
        self.events.append((t, JOIN, detail))
        return arrive

    def drift(self, gid: int, t: float) -> float:
        """A member of group ``gid`` (three or more) drifts away to stand alone nearby; the
        others stay where they stood, still a group. Returns ``t``."""
        g = self.groups[gid]
        m = g.members[int(self.rng.integers(len(g.members)))]
        before = g.record
        self.close_all(gid, t)
        planned = self.records[before].group
        keep = [k for k, x in enumerate(planned.members) if x != m]
        rest = PlannedGroup(
            tuple(planned.members[k] for k in keep),
            planned.places[keep],
            planned.facings[keep],
            planned.centre,
            t,
            newcomers=(),
        )
        self.records.append(_Record(rest))  # the group as it was ends as ``m`` sets off
        g.record = len(self.records) - 1
        g.version += 1
        g.members.remove(m)
        del g.angles[m]
        self.group_of.pop(m)
        self.events.append(
            (t, LEAVE, f"person {m} drifts away from group {sorted([*g.members, m])}")
        )
        self.schedule_group(gid, t)
        spot = self.free_spot(ALONE_CLAIM_M, near=self.position[m], within=3.0)
        if spot is None:
            spot = self.position[m]
        speed, arrive = self.walk(m, spot, t)
        self.walks.append((t, m, Intent(goal=(float(spot[0]), float(spot[1])), speed=speed)))
        self.position[m] = spot
        self.start_alone(m, spot, arrive)
        return t

    def walk_over(self, gid: int, other: int, t: float) -> float:
        """Group ``other`` walks over to group ``gid`` at the approach speed and they merge
        round ``gid``'s centre, ``gid`` making room just before they arrive; both groups are
        recorded as they were until then. Returns when the last should have arrived (``t``
        when there is no room)."""
        g, h = self.groups[gid], self.groups[other]
        members = g.members + h.members
        radius = self.draw_radius(len(members))
        claim = self.reach(self.extent(g, radius))
        here = self.floor_centre(g)
        if not self.fits(here, claim, ignore_groups=(gid, other), ignore_people=tuple(members)):
            return t
        speed = self.p.approach_speed
        before = (g.record, h.record)
        angles = dict(g.angles)
        for m in h.members:
            d = self.position[m] - g.centre
            angles[m] = math.atan2(d[1], d[0])
        self.close_all(other, t)
        walkers = list(h.members)
        g.members = members
        g.radius = radius
        g.angles = self.layout(g, angles)
        arrive = (
            t
            + SETTLE_S
            + max(float(np.hypot(*(g.place_of(m) - self.position[m]))) / speed for m in walkers)
        )
        shift = max(t, arrive - SETTLE_S - MAKE_ROOM_S)
        g.members = [m for m in members if m not in walkers]
        self.close_all(gid, shift)
        g.members = members
        del self.groups[other]
        speeds = dict.fromkeys(walkers, speed)
        self.record(gid, shift, speeds=speeds, newcomers=tuple(walkers), continues=before)
        planned = self.records[g.record].group
        for m in walkers:
            self.group_of[m] = gid
            k = planned.members.index(m)
            self.walks.append((t, m, standing(planned.places[k], planned.facings[k], speed=speed)))
        for x in g.members:  # nobody leaves, splits off or merges until the walkers stand
            self.busy_until[x] = max(self.busy_until.get(x, 0.0), arrive + CHANGE_SLACK_S)
        self.changing[gid] = arrive + CHANGE_SLACK_S  # ... nor joins
        self.schedule_group(gid, t)
        detail = f"group {sorted(walkers)} walks over to merge with group {sorted(g.members)}"
        self.events.append((t, MERGE, detail + " (scripted)"))
        return arrive


def _mean_direction(angles: np.ndarray) -> float:
    """The direction of the mean of unit vectors at ``angles`` (radians): ``np.angle`` of
    ``np.exp(1j * angles).mean()``, the mean taken as ``mean`` takes it (the sum over the
    count), without its overhead."""
    unit = np.exp(1j * angles)
    return float(np.angle(unit.sum() / unit.size))


def _within(points: np.ndarray, edge: float) -> np.ndarray:
    """``points`` clipped to [-edge, edge] on each axis: ``np.clip``'s values, without its
    overhead."""
    return np.minimum(np.maximum(points, -edge), edge)


def _clear(x: float, y: float, bound: float, obstacles: list[tuple[float, float, float]]) -> bool:
    """Whether (x, y) (metres) lies within ``bound`` of the room's middle along both axes and
    at least its distance from each of ``obstacles`` (`Party.obstacles`)."""
    if max(abs(x), abs(y)) > bound:
        return False
    hypot = math.hypot
    for ox, oy, distance in obstacles:
        if hypot(x - ox, y - oy) < distance:
            return False
    return True


def _glances(
    builder: TimelineBuilder,
    entry: _Alone,
    end: float,
    rng: np.random.Generator,
    targets: list[int],
) -> None:
    """Someone alone stands at their spot and looks around: a point or a person now and then."""
    t = entry.start
    targets = [o for o in targets if o != entry.person]
    stop = min(entry.end, end)
    if not t < stop:
        return
    # One standing intent, made (and checked) once, given each glance's gaze; the point looked
    # at summed coordinate by coordinate (the same sums and products as on the arrays).
    stand = standing(entry.spot, entry.facing)
    sx, sy = entry.spot.tolist()
    while t < stop:
        if targets and rng.random() < 0.5:
            intent = stand.looking_at(agent=targets[int(rng.integers(len(targets)))])
        else:
            angle = entry.facing + rng.uniform(-1.0, 1.0)
            intent = stand.looking_at(
                point=(sx + 2.0 * math.cos(angle), sy + 2.0 * math.sin(angle))
            )
        builder.set(t, entry.person, intent)
        t += max(rng.exponential(GLANCE_MEAN_S), 1.0)


def _passers(
    builder: TimelineBuilder,
    ids: list[int],
    half: float,
    duration: float,
    rng: np.random.Generator,
) -> list[tuple[float, str, str]]:
    """Passers-by cross the room from one wall to another, again and again."""
    events = []
    edge = half - WALL_GAP_M - PLANNING_RADIUS_M
    for pid in ids:
        builder.set(0.0, pid, Intent(present=False))
        t = float(rng.uniform(*PASS_GAP_S))
        while t < duration:
            side = int(rng.integers(4))
            along = rng.uniform(-edge, edge, size=2)
            start = _on_wall(side, along[0], edge)
            finish = _on_wall((side + 2) % 4, along[1], edge)
            speed = float(rng.uniform(*WALK_SPEED_M_S))
            builder.set(
                t,
                pid,
                Intent(
                    present=True,
                    appear_at=(float(start[0]), float(start[1])),
                    goal=(float(finish[0]), float(finish[1])),
                    speed=speed,
                ),
            )
            events.append((t, "pass", f"passer-by {pid} crosses the room"))
            t += float(np.hypot(*(finish - start))) / speed + SETTLE_S
            builder.set(t, pid, Intent(present=False))
            t += float(rng.uniform(*PASS_GAP_S))
    return events


def _on_wall(side: int, along: float, edge: float) -> np.ndarray:
    return [
        np.array([edge, along]),
        np.array([along, edge]),
        np.array([-edge, along]),
        np.array([along, -edge]),
    ][side]


def write_party(builder: TimelineBuilder, party: Party, rng: np.random.Generator) -> None:
    """Writes a planned party (`Party.run`) into ``builder``: its walks, every group record
    with its conversation, the glances of everyone standing alone and its events."""
    params = party.p
    for t, m, intent in party.walks:
        builder.set(t, m, intent)
    handles: dict[int, int] = {}  # record -> planned group in the builder
    for r, rec in enumerate(party.records):
        planned = rec.group
        if rec.end <= planned.start:
            continue
        handles[r] = builder.group(
            planned.members,
            planned.places,
            planned.facings,
            planned.centre,
            start=planned.start,
            end=rec.end,
            newcomers=planned.newcomers,
            continues=[handles[c] for c in rec.continues if c in handles],
        )
        converse(
            builder,
            planned.members,
            planned.places,
            planned.facings,
            start=planned.start,
            end=min(rec.end, params.duration),
            rng=rng,
            mean_utterance=params.mean_utterance,
            head_noise=params.head_noise,
            speed=rec.speeds,
        )
    for entry in party.alone:
        if entry.end > entry.start:
            _glances(builder, entry, params.duration, rng, party.ids)
    for t, kind, detail in party.events:
        builder.event(t, kind, detail)


def build_mingle(params: MingleParams, *, seed: int, name: str) -> Scenario:
    """The party of ``params`` drawn with ``seed``."""
    params.check(name)
    rng = np.random.default_rng(seed)
    side = params.side()
    robot = None
    if params.robot:
        robot = RobotPlace(id=ROBOT_ID, position=(-0.5 * side + ROBOT_WALL_GAP_M, 0.0), yaw=0.0)
    keep_clear = () if robot is None else (np.array(robot.position),)
    party = Party(params, rng, side, keep_clear=keep_clear)
    party.run()
    people = party.ids
    passers = list(range(params.people + 1, params.people + params.passers_by + 1))
    agents = [*people, *passers] + ([ROBOT_ID] if params.robot else [])
    builder = TimelineBuilder(agents)
    write_party(builder, party, rng)
    for t, kind, detail in _passers(builder, passers, 0.5 * side, params.duration, rng):
        builder.event(t, kind, detail)
    if robot is not None:
        t = 0.0
        while t < params.duration:
            builder.set(
                t,
                ROBOT_ID,
                standing(
                    np.array(robot.position),
                    0.0,
                    gaze_agent=people[int(rng.integers(len(people)))],
                ),
            )
            t += max(rng.exponential(GLANCE_MEAN_S), 1.0)
    starts = np.array([party.start_position[m] for m in people])
    yaws = [party.start_yaw[m] for m in people]
    roles = cast(rng, people, starts, yaws, parts="guest")
    if passers:
        edge = 0.5 * side - WALL_GAP_M - PLANNING_RADIUS_M
        spots = np.array([[edge, -edge + 0.7 * k] for k in range(len(passers))])
        roles += cast(rng, passers, spots, [0.0] * len(passers), parts="passer-by", present=False)
    if params.spacing < SPACING_M:  # bodies that let people stand shoulder to shoulder
        body = 0.5 * (params.spacing - CLEARANCE_M)
        roles = tuple(dataclasses.replace(role, radius=body) for role in roles)
    return Scenario(
        name=name,
        seed=seed,
        stage=Stage(
            room=(side, side),
            people=tuple(roles),
            robot=robot,
            furniture=tuple(party.furniture),
        ),
        timeline=builder.build(),
        duration=params.duration,
        description="a SALSA-like party: groups forming, merging, splitting; people alone",
    )


@register("mingle", options=MingleParams, tags=("party",), robot={"robot": True})
def mingle(*, seed: int, **options: Any) -> Scenario:
    """A SALSA-like party: groups of 2-8 forming, merging, splitting; people alone.

    Its options are the fields of `MingleParams`.
    """
    params = MingleParams(**options)
    if params.room_side > 0.0:  # the user's room: a party that does not fit is an error
        return build_mingle(params, seed=seed, name="mingle")
    return build_mingle_in_room(params, seed=seed, name="mingle")


def build_mingle_in_room(params: MingleParams, *, seed: int, name: str) -> Scenario:
    """`build_mingle`, growing the room by `ROOM_GROWTH` (at most `ROOM_RETRIES` times) while
    the drawn party does not fit; the room actually used is the scenario's stage."""
    params.check(name)  # before the room is picked: a negative room_side is not "pick one"
    params = dataclasses.replace(params, room_side=params.side())
    for _ in range(ROOM_RETRIES):
        try:
            return build_mingle(params, seed=seed, name=name)
        except NoFloorError:
            params = dataclasses.replace(params, room_side=params.room_side * ROOM_GROWTH)
    raise NoFloorError(
        f"{name}: no room found for the drawn party (seed {seed}): {params.people} people still "
        f"do not fit a {params.room_side:g} m room"
    )
