"""``concourse``: a station hall of hundreds to thousands, with flows, a queue and groups aside.

300 people by default (50-3,000) in a square hall (auto-sized at 0.4 people per m^2 where groups
stand, unless a side is given) laid out as a cross of floor for flows and four corners:

* **entrances** (2-4) in the middle of the walls, at the ends of the cross's arms (west and
  east; then north; then south). **Walkers** cross the hall between two entrances through its
  middle, keeping to the right of each arm, leave, and come back through some entrance a while
  later, again and again.
* **A queue** stands in the south-east corner: a line snaking in rows from a counter at the
  south wall. Every so often its head is served and walks out through the nearest entrance
  (by the south arm); everyone steps forward one place; someone comes in through an entrance
  and walks, by the hall's middle, to its end.
* **Conversational groups** stand aside in the other corners (all four without a queue): each
  corner is cut into square patches of at most `PATCH_PEOPLE` guests, each a party planned by
  `scenarios.mingle`'s planner (groups forming, growing, shrinking, merging and splitting,
  people alone, scripted changes), its groups kept inside its patch.

Walkers and queuers are never in a conversational group: a queue is not an F-formation, so the
ground truth holds only the corners' planned groups (`scenarios.truth`), as for every scenario.

A crowd that cannot fit its hall (more than `MAX_GROUP_DENSITY_PER_M2` guests per m^2 of the
floor the corners' parties plan on, a queue longer than its corner holds, or more than
`MAX_WALKER_DENSITY_PER_M2` walkers per m^2 of the cross) is refused, naming the size asked,
the size that fits and the option to change.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np

from scenarios.casting import cast
from scenarios.changes import EventRate
from scenarios.conversation import standing
from scenarios.mingle import (
    DENSITY_PER_M2,
    SETTLE_S,
    LargestGroup,
    MeanSeconds,
    MingleParams,
    NoFloorError,
    Party,
    UtteranceSeconds,
    write_party,
)
from scenarios.mingle import WALL_GAP_M as PARTY_WALL_GAP_M
from scenarios.registry import Range, SceneSeconds, check_ranges, register
from scenarios.scenario import Scenario
from scenarios.script import Intent
from scenarios.stage import PLANNING_RADIUS_M, Furniture, Stage
from scenarios.timeline import TimelineBuilder

__all__ = ["ConcourseParams", "build_concourse", "concourse"]

MAX_HALL_M = 100.0  # metres, largest hall side (the simulator's largest room)
MIN_HALL_M = 20.0  # metres, smallest hall side picked
CROSS_SHARE = 0.2  # the cross of floor for flows is this share of the hall's side wide
PATCH_PEOPLE = 120  # most guests planned as one party (a corner holds k x k such patches)
LANE_SHARE = 0.4  # share of an arm's width a lane spans, from the arm's middle to its right
# Guests per m^2 of the floor a patch's party plans on (inside its margins): the party's planner
# lays out 0.5 for every seed tried, 0.6 for most, 0.7 for none; beyond, no room to mingle.
MAX_GROUP_DENSITY_PER_M2 = 0.5
MAX_WALKER_DENSITY_PER_M2 = 0.3  # walkers per m^2 of the cross: beyond, no room to cross
WALL_GAP_M = PARTY_WALL_GAP_M + PLANNING_RADIUS_M  # metres from a wall to the nearest place
# (a patch's party keeps as far from its edges: the floor it plans on is this much smaller)
WALK_SPEED_M_S = (1.1, 1.5)  # m/s, walkers cross at these speeds
QUEUE_SPEED_M_S = 0.8  # m/s, queuers step forward at this speed
SLOT_M = 0.75  # metres between two places of the queue in a row
ROW_GAP_M = 1.1  # metres between two rows of the snaking queue
COUNTER_SIZE_M = (2.0, 0.5, 1.1)  # metres: length, depth, height of the queue's counter
COUNTER_FRONT_M = 1.0  # metres from the south wall to the head of the queue
QUEUE_STANDING = 2 / 3  # share of the queuers in the line at the start (the rest come later)
MIN_SERVICE_S = 1.0  # seconds, shortest time between two people served
MIN_WAIT_S = 1.0  # seconds, shortest wait of a walker between two crossings
# Spawn keys of the parts drawn from the seed (each part its own generator).
CORNERS, QUEUE, WALKERS, CASTING = range(4)
# Entrances, in the order the option ``entrances`` opens them: (x, y) directions from the middle.
DOORS = ((-1.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.0, -1.0))
SOUTH = DOORS[3]  # the queue's corner is the south-east one
# Corners, in the order groups take them; the last holds the queue when there is one.
CORNER_SIGNS = ((-1.0, 1.0), (1.0, 1.0), (-1.0, -1.0), (1.0, -1.0))


@dataclass(frozen=True)
class ConcourseParams:
    """Every number that shapes a concourse: the options of ``concourse``, declared once here.

    Attributes:
        people: everyone in the scene: standing in groups (or alone beside them), queuing,
            and walking through.
        duration: length of the scene, seconds.
        hall_side: side of the square hall, metres; 0: the smallest (at least 20 m, at most
            100 m) with 0.4 guests per m^2 where groups stand and room for the queue and the
            walkers.
        entrances: doors in the middle of the walls: west and east, then north, then south.
        group_share: share of the people standing in the corners, in conversational groups or
            alone beside them.
        queue_share: share of the people queuing at the counter (two thirds in the line at the
            start, the rest coming in later); 0: no queue, groups in all four corners.
        service_time: mean time between two people served at the counter, seconds.
        mean_wait: mean time a walker stays out between two crossings, seconds.
        max_group_size: largest conversational group.
        mean_stay: mean time a member stays in a group, seconds.
        mean_alone: mean time someone standing alone stays so before acting, seconds.
        mean_utterance: mean length of one speaker's turn, seconds.
        event_rate: scripted changes per minute in each corner (someone walks up to join a
            group, drifts away from one, two groups merge; ``scenarios.changes``).
    """

    people: Annotated[int, Range(50, 3000)] = 300
    duration: SceneSeconds = 300.0
    hall_side: Annotated[float, Range(0.0, MAX_HALL_M, unit="m")] = 0.0
    entrances: Annotated[int, Range(2, 4)] = 4
    group_share: Annotated[float, Range(0.0, 1.0)] = 0.6
    queue_share: Annotated[float, Range(0.0, 0.5)] = 0.1
    service_time: Annotated[float, Range(MIN_SERVICE_S, 600.0, unit="s")] = 10.0
    mean_wait: Annotated[float, Range(MIN_WAIT_S, 600.0, unit="s")] = 30.0
    max_group_size: LargestGroup = MingleParams.max_group_size
    mean_stay: MeanSeconds = MingleParams.mean_stay
    mean_alone: MeanSeconds = MingleParams.mean_alone
    mean_utterance: UtteranceSeconds = MingleParams.mean_utterance
    event_rate: EventRate = MingleParams.event_rate

    def counts(self) -> tuple[int, int, int]:
        """(standing in the corners, queuing, walking) people."""
        guests = round(self.group_share * self.people)
        queuers = min(round(self.queue_share * self.people), self.people - guests)
        return guests, queuers, self.people - guests - queuers

    def corners(self) -> int:
        """Corners where groups stand: three beside a queue, else four."""
        return 3 if self.counts()[1] else 4

    def check(self, name: str) -> None:
        """`ValueError` naming the option for impossible values: each out of its range
        (`scenarios.registry.check_ranges`) or shares beyond the whole; `NoFloorError` for a
        crowd that cannot fit its hall."""
        check_ranges(name, self)
        if self.group_share + self.queue_share > 1.0 + 1e-9:
            raise ValueError(
                f"{name}: options group_share and queue_share must add up to at most 1, got "
                f"{self.group_share:g} + {self.queue_share:g}"
            )
        guests, queuers, _ = self.counts()
        if 0 < guests < 2 * self.corners():
            raise ValueError(
                f"{name}: option group_share must put 0 or at least {2 * self.corners()} people "
                f"in the corners (2 a corner), got {guests}"
            )
        if 0 < queuers < 2:
            raise ValueError(
                f"{name}: option queue_share must put 0 or at least 2 people in the queue, "
                f"got {queuers}"
            )
        side = self.side()
        most = _most_people(self, side)
        if self.people > most:
            need = _least_side(self)
            given = f"a {side:g} m x {side:g} m hall"
            if self.hall_side == 0.0:
                given = f"the largest hall ({MAX_HALL_M:g} m x {MAX_HALL_M:g} m)"
            if need is None or self.hall_side == 0.0:
                fix = f"people {most} or fewer"
            else:
                fix = f"a hall_side of at least {need:g} m"
            raise NoFloorError(
                f"{name}: {self.people} people do not fit {given} at a sane density "
                f"(at most {MAX_GROUP_DENSITY_PER_M2:g} guests per m^2 of the corners' floor, "
                f"{MAX_WALKER_DENSITY_PER_M2:g} walkers per m^2 of the cross, a queue its "
                f"corner holds), i.e. {most} people; give {fix}"
            )

    def side(self) -> float:
        """The hall's side, metres."""
        if self.hall_side > 0.0:
            return self.hall_side
        return _least_side(self, density=DENSITY_PER_M2) or MAX_HALL_M


@dataclass(frozen=True)
class _Layout:
    """Where things are in a hall of ``side`` metres (centred on the origin)."""

    side: float

    @property
    def corner(self) -> float:
        """Side of each corner square, metres."""
        return 0.5 * (1.0 - CROSS_SHARE) * self.side

    @property
    def cross(self) -> float:
        """Width of the cross's arms, metres."""
        return CROSS_SHARE * self.side

    def corner_centre(self, k: int) -> np.ndarray:
        """(2,) the middle of corner ``k`` (`CORNER_SIGNS`), metres."""
        off = 0.5 * (self.side - self.corner)
        return off * np.array(CORNER_SIGNS[k])

    def door(self, k: int, rng: np.random.Generator) -> np.ndarray:
        """(2,) a spot just inside entrance ``k``, drawn across its width, metres."""
        across = float(rng.uniform(-LANE_SHARE, LANE_SHARE)) * self.cross
        return self.edge * np.array(DOORS[k]) + across * _right(DOORS[k])

    @property
    def edge(self) -> float:
        """How far from the middle a spot just inside an entrance is, metres."""
        return 0.5 * self.side - WALL_GAP_M

    def route(self, a: int, b: int, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
        """(2,) spots a walker passes from entrance ``a`` to entrance ``b``, metres: in at
        ``a``, where the two lanes meet, out at ``b`` (walkers keep to the right of the arms:
        people walking in and out of one entrance, or along one arm both ways, pass each
        other)."""
        start, middle = self.entry(a, rng)
        inward = -np.array(DOORS[a])
        return (start, *self.onward(inward, float(middle @ _right(inward)), b, rng))

    def entry(self, a: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """(2,) spots someone coming in through entrance ``a`` passes, metres: just inside it,
        on a lane right of the arm's middle, and the end of that lane at the hall's middle."""
        inward = -np.array(DOORS[a])
        middle = float(rng.uniform(0.05, LANE_SHARE)) * self.cross * _right(inward)
        return -self.edge * inward + middle, middle

    def onward(
        self, heading: np.ndarray, near: float, b: int, rng: np.random.Generator
    ) -> tuple[np.ndarray, ...]:
        """(2,) spots on from a lane ``near`` metres right of an arm's middle, walking along
        ``heading`` toward the hall's middle, out through entrance ``b``: where the lanes meet
        (unless straight on), then out, metres."""
        outward = np.array(DOORS[b])
        far = float(rng.uniform(0.05, LANE_SHARE)) * self.cross
        finish = self.edge * outward + far * _right(outward)
        if abs(float(heading @ outward)) > 0.5:  # straight on: one lane
            return (finish,)
        return (near * _right(heading) + far * _right(outward), finish)

    def queue_slots(self) -> tuple[np.ndarray, np.ndarray]:
        """Places of the queue, head first: (k, 2) metres, snaking in rows from the counter,
        and (k,) the way each faces (the place before it; the head faces the counter)."""
        x0 = 0.5 * self.side - self.corner + WALL_GAP_M
        x1 = 0.5 * self.side - WALL_GAP_M
        y0 = -0.5 * self.side + COUNTER_FRONT_M
        y1 = -0.5 * self.side + self.corner - WALL_GAP_M
        per_row = int((x1 - x0) / SLOT_M) + 1
        rows = int((y1 - y0) / ROW_GAP_M) + 1
        places = []
        for r in range(rows):
            xs = x0 + SLOT_M * np.arange(per_row)
            places += [(x, y0 + r * ROW_GAP_M) for x in (xs if r % 2 == 0 else xs[::-1])]
        places = np.array(places)
        d = np.diff(places, axis=0, prepend=places[:1] + [0.0, 1.0])
        facings = np.arctan2(-d[:, 1], -d[:, 0])
        return places, facings

    def counter(self) -> Furniture:
        """The queue's counter at the south wall, in front of the head of the queue."""
        head = self.queue_slots()[0][0]
        y = -0.5 * self.side + 0.5 * COUNTER_SIZE_M[1]
        return Furniture("bar", (float(head[0]), y), COUNTER_SIZE_M)


def _right(heading: tuple[float, float] | np.ndarray) -> np.ndarray:
    """(2,) the unit vector to the right of ``heading`` (a unit vector)."""
    return np.array([heading[1], -heading[0]], dtype=np.float64)


def _patches(guests: int, corners: int) -> int:
    """Patches along a corner's side (k: k x k patches a corner) for ``guests`` in ``corners``."""
    return max(1, math.ceil(math.sqrt(guests / corners / PATCH_PEOPLE)))


def _fits(
    params: ConcourseParams,
    people: int,
    side: float,
    *,
    density: float = MAX_GROUP_DENSITY_PER_M2,
) -> bool:
    """Whether ``people`` in ``params``'s shares fit a hall of ``side`` metres: the guests at most
    ``density`` per m^2 of the floor their patches' parties plan on, the queue within the slots
    its corner holds, the walkers at most `MAX_WALKER_DENSITY_PER_M2` per m^2 of the cross."""
    params = dataclasses.replace(params, people=people)
    layout = _Layout(side)
    guests, queuers, walkers = params.counts()
    if guests:
        corners = params.corners()
        k = _patches(guests, corners)
        floor = corners * max(layout.corner - 2.0 * k * WALL_GAP_M, 0.0) ** 2
        if guests > density * floor:
            return False
    if queuers and queuers > len(layout.queue_slots()[0]) / QUEUE_STANDING:
        return False
    cross = side**2 - 4.0 * layout.corner**2
    return walkers <= MAX_WALKER_DENSITY_PER_M2 * cross


def _most_people(params: ConcourseParams, side: float) -> int:
    """The most people in ``params``'s shares that a hall of ``side`` metres holds (`_fits`)."""
    low, high = 0, 1
    while _fits(params, high, side):
        low, high = high, 2 * high
    while high - low > 1:  # _fits(low), not _fits(high)
        middle = (low + high) // 2
        low, high = (middle, high) if _fits(params, middle, side) else (low, middle)
    return low


def _least_side(
    params: ConcourseParams, *, density: float = MAX_GROUP_DENSITY_PER_M2
) -> float | None:
    """The smallest whole hall side (metres, from `MIN_HALL_M`) that holds ``params``'s people
    (`_fits`, guests at ``density``); None: no hall does."""
    for side in range(int(MIN_HALL_M), int(MAX_HALL_M) + 1):
        if _fits(params, params.people, float(side), density=density):
            return float(side)
    return None


def _rng(seed: int, part: int, k: int = 0) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(part, k)))


def _corner_parties(
    params: ConcourseParams, layout: _Layout, guests: int, seed: int
) -> list[tuple[Party, np.random.Generator]]:
    """The parties standing aside, planned (ids from 1) and moved to where they stand: each
    corner cut into k x k square patches of at most `PATCH_PEOPLE` guests, a party each (the
    planner's work grows faster than its guests)."""
    corners = params.corners()
    k = _patches(guests, corners)
    side = layout.corner / k
    patches = [
        layout.corner_centre(c) + side * (np.array([i, j]) - 0.5 * (k - 1))
        for c in range(corners)
        for i in range(k)
        for j in range(k)
    ]
    n = len(patches)
    sizes = [guests // n + (p < guests % n) for p in range(n)]
    parties = []
    first = 1
    for p, (size, centre) in enumerate(zip(sizes, patches, strict=True)):
        rng = _rng(seed, CORNERS, p)
        zone = MingleParams(
            people=size,
            duration=params.duration,
            room_side=side,
            max_group_size=params.max_group_size,
            mean_stay=params.mean_stay,
            mean_alone=params.mean_alone,
            mean_utterance=params.mean_utterance,
            event_rate=params.event_rate,
        )
        party = Party(zone, rng, side, first_id=first)
        party.run()
        party.translate(centre)
        parties.append((party, rng))
        first += size
    return parties


def _walk(
    builder: TimelineBuilder, m: int, t: float, path: tuple[np.ndarray, ...], speed: float
) -> float:
    """``m``, on their way from ``path[0]`` to ``path[1]`` from ``t`` (the caller's intent),
    walks on through the rest of ``path`` at ``speed``, each spot in turn. Returns when they
    should reach the last, seconds."""
    for k in range(1, len(path) - 1):
        t += float(np.hypot(*(path[k] - path[k - 1]))) / speed
        after = path[k + 1]
        builder.set(t, m, Intent(goal=(float(after[0]), float(after[1])), speed=speed))
    return t + float(np.hypot(*(path[-1] - path[-2]))) / speed


def _way_out(
    layout: _Layout, head: np.ndarray, door: int, rng: np.random.Generator
) -> tuple[np.ndarray, ...]:
    """(2,) spots someone served at the head of the queue passes on the way out through
    ``door``, metres: west to the south arm of the cross, then as a walker would, along its lane
    (straight out through the south entrance, or north and out through another)."""
    if DOORS[door] == SOUTH:
        return (head, layout.door(door, rng))
    north = -np.array(SOUTH)
    near = float(rng.uniform(0.05, LANE_SHARE)) * layout.cross
    arm = near * _right(north) + np.array([0.0, head[1]])
    return (head, arm, *layout.onward(north, near, door, rng))


def _queue(
    builder: TimelineBuilder,
    ids: list[int],
    layout: _Layout,
    params: ConcourseParams,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray, list[bool]]:
    """The queue: who stands where at the start, served one by one, stepping forward, newcomers
    walking in to its end. Returns the queuers' start positions (k, 2), yaws (k,) and whether
    each is in the hall at the start."""
    places, facings = layout.queue_slots()
    standing_n = min(len(places), max(2, round(QUEUE_STANDING * len(ids))))
    line = ids[:standing_n]
    outside = [(0.0, m) for m in ids[standing_n:]]  # (free from, id), earliest first
    doors = params.entrances
    exit_door = min(
        range(doors), key=lambda d: float(np.hypot(*(places[0] - layout.edge * np.array(DOORS[d]))))
    )
    starts = np.array([layout.door(exit_door, rng) for _ in ids])
    starts[:standing_n] = places[:standing_n]
    yaws = np.zeros(len(ids))
    yaws[:standing_n] = facings[:standing_n]
    for k, m in enumerate(line):
        builder.set(0.0, m, standing(places[k], facings[k]))
    for _, m in outside:
        builder.set(0.0, m, Intent(present=False))
    walking_in: dict[int, float] = {}  # newcomer -> when they reach the hall's middle

    def take_places(until: float) -> None:
        """Newcomers reaching the middle by ``until`` walk on to their place in the line."""
        for m, at in sorted(walking_in.items(), key=lambda item: item[1]):
            if at <= until:
                k = line.index(m)
                builder.set(at, m, standing(places[k], facings[k]))
                del walking_in[m]

    t = max(float(rng.exponential(params.service_time)), MIN_SERVICE_S)
    while t < params.duration:
        take_places(t)
        if line:  # the head is served and leaves; the others step forward
            served = line.pop(0)
            walking_in.pop(served, None)
            speed = float(rng.uniform(*WALK_SPEED_M_S))
            path = _way_out(layout, places[0], exit_door, rng)
            goal = (float(path[1][0]), float(path[1][1]))
            builder.set(t, served, Intent(goal=goal, speed=speed))
            gone = _walk(builder, served, t, path, speed) + SETTLE_S
            builder.set(gone, served, Intent(present=False))
            builder.event(t, "served", f"person {served} is served at the counter and leaves")
            for k, m in enumerate(line):
                if m not in walking_in:
                    builder.set(t, m, standing(places[k], facings[k], speed=QUEUE_SPEED_M_S))
            outside.append((gone, served))
            outside.sort()
        if outside and outside[0][0] <= t:  # someone comes in, by the hall's middle
            _, m = outside.pop(0)
            door, middle = layout.entry(int(rng.integers(doors)), rng)
            line.append(m)
            speed = float(rng.uniform(*WALK_SPEED_M_S))
            builder.set(
                t,
                m,
                Intent(
                    present=True,
                    appear_at=(float(door[0]), float(door[1])),
                    goal=(float(middle[0]), float(middle[1])),
                    speed=speed,
                ),
            )
            walking_in[m] = t + float(np.hypot(*(middle - door))) / speed
            builder.event(t, "queue", f"person {m} comes in and joins the end of the queue")
        t += max(float(rng.exponential(params.service_time)), MIN_SERVICE_S)
    take_places(math.inf)
    present = [k < standing_n for k in range(len(ids))]
    return starts, yaws, present


def _walkers(
    builder: TimelineBuilder,
    ids: list[int],
    layout: _Layout,
    params: ConcourseParams,
    rng: np.random.Generator,
) -> np.ndarray:
    """Walkers cross the hall between two entrances through its middle, again and again.
    Returns their (k, 2) start spots (outside, at a door)."""
    doors = params.entrances
    starts = np.array([layout.door(int(rng.integers(doors)), rng) for _ in ids])
    for m in ids:
        builder.set(0.0, m, Intent(present=False))
        # The first crossing starts any time in one cycle (a crossing and a wait), so that
        # walkers come in as steadily from the start as later.
        t = float(rng.uniform(0.0, params.mean_wait + layout.side / np.mean(WALK_SPEED_M_S)))
        while t < params.duration:
            a = int(rng.integers(doors))
            b = (a + 1 + int(rng.integers(doors - 1))) % doors
            spots = layout.route(a, b, rng)
            speed = float(rng.uniform(*WALK_SPEED_M_S))
            start = spots[0]
            builder.set(
                t,
                m,
                Intent(
                    present=True,
                    appear_at=(float(start[0]), float(start[1])),
                    goal=(float(spots[1][0]), float(spots[1][1])),
                    speed=speed,
                ),
            )
            builder.event(t, "cross", f"person {m} crosses the hall")
            t = _walk(builder, m, t, spots, speed) + SETTLE_S
            builder.set(t, m, Intent(present=False))
            t += max(float(rng.exponential(params.mean_wait)), MIN_WAIT_S)
    return starts


def build_concourse(params: ConcourseParams, *, seed: int, name: str) -> Scenario:
    """The concourse of ``params`` drawn with ``seed``."""
    params.check(name)
    layout = _Layout(params.side())
    guests, queuers, walkers = params.counts()
    queue_ids = list(range(guests + 1, guests + queuers + 1))
    walker_ids = list(range(guests + queuers + 1, params.people + 1))
    builder = TimelineBuilder(range(1, params.people + 1))
    try:
        parties = _corner_parties(params, layout, guests, seed) if guests else []
    except NoFloorError:
        if params.hall_side == 0.0 and layout.side >= MAX_HALL_M:  # the largest, picked
            fix = "fewer people, a smaller group_share or a larger max_group_size"
        elif params.hall_side == 0.0:
            fix = f"a hall_side larger than the {layout.side:g} m picked"
        else:
            fix = "a larger hall_side"
        raise NoFloorError(
            f"{name}: no floor found for the drawn groups (seed {seed}): {guests} people in "
            f"groups of at most {params.max_group_size} do not fit {params.corners()} corners "
            f"of {layout.corner:g} m ({layout.side:g} m hall); give {fix}"
        ) from None
    for party, rng in parties:
        write_party(builder, party, rng)
    rng = _rng(seed, CASTING)
    roles = []
    for party, _ in parties:
        starts = np.array([party.start_position[m] for m in party.ids])
        yaws = [party.start_yaw[m] for m in party.ids]
        roles += cast(rng, party.ids, starts, yaws, parts="guest")
    if queue_ids:
        starts, yaws, present = _queue(builder, queue_ids, layout, params, _rng(seed, QUEUE))
        roles += cast(rng, queue_ids, starts, yaws, parts="queuer", present=present)
    if walker_ids:
        starts = _walkers(builder, walker_ids, layout, params, _rng(seed, WALKERS))
        roles += cast(
            rng, walker_ids, starts, [0.0] * len(walker_ids), parts="walker", present=False
        )
    return Scenario(
        name=name,
        seed=seed,
        stage=Stage(
            room=(layout.side, layout.side),
            people=tuple(roles),
            furniture=(layout.counter(),) if queue_ids else (),
        ),
        timeline=builder.build(),
        duration=params.duration,
        description="a station concourse: walkers crossing, a queue, groups standing aside",
    )


@register("concourse", options=ConcourseParams, tags=("crowd",))
def concourse(*, seed: int, **options: Any) -> Scenario:
    """A station concourse: hundreds walking through, queuing and talking in groups aside.

    Its options are the fields of `ConcourseParams`.
    """
    return build_concourse(ConcourseParams(**options), seed=seed, name="concourse")
