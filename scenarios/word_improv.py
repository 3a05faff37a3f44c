"""``word-improv``: the Word Improv Game of the Babble dataset.

A moderator and 2-7 players stand in a circle in a 5 m x 5 m area. A turn lasts about
``turn_duration`` seconds (drawn within +-40 %): the moderator reads a word and picks a player,
the two speak in turn, and everyone's head turns to whoever speaks. After each turn the players
shuffle, each walking to another player's place at random, and the circle re-forms (a little
tighter when it has lost someone). A player who fails (with probability ``fail_probability``
per turn, seeded) leaves the circle and the area; the rest shuffle. The game ends with one
player left.

Ground truth (see `scenarios.truth`): the standing circle is an F-formation from the frame in
which everyone stands at their place facing the centre; shuffling frames hold none, as in
Babble's annotations. The robot may stay out (``none``), watch from a corner (``watch``) or be
the moderator (``moderate``).

Defaults follow this project's measurements of Babble (``docs/results/characterisation.md``):
the o-space radius law ``0.674 + 0.086 * (n - 2)`` metres is the least-squares line through
Babble's mean Tightness by group size 2-7 (0.703, 0.715, 0.860, 0.926, 1.025, 1.107 m), and
the small place and facing noise matches its near-regular circles (Symmetry 20-37 degrees,
torsos facing the group's centre within 5 degrees in the median).
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np

from scenarios.casting import cast
from scenarios.conversation import converse, standing
from scenarios.formation import CIRCLE_OPTIONS, CircleNoise, CircleShape, RadiusLaw
from scenarios.registry import PlaceNoise, Range, register, shared_help
from scenarios.scenario import Scenario
from scenarios.script import Intent
from scenarios.stage import RobotPlace, Stage
from scenarios.timeline import TimelineBuilder

__all__ = ["BABBLE_RADIUS", "word_improv"]

AREA_M = (5.0, 5.0)  # metres, Babble's play area (the room)
BABBLE_RADIUS = RadiusLaw(base=0.674, per_member=0.086)  # metres, fit to Babble (module doc)
TURN_SPREAD = 0.4  # a turn lasts turn_duration x U(1 - spread, 1 + spread)
SHUFFLE_SPEED_M_S = (0.8, 1.2)  # m/s, walking speed while shuffling
SHUFFLE_DELAY_S = (0.0, 1.0)  # seconds, when each player sets off after the turn
SETTLE_S = 2.5  # seconds allowed beyond the longest walk for the circle to re-form
CENTRE_JITTER_M = 0.15  # metres, the re-formed circle's centre moves by up to this
ANGLE_JITTER = 0.2  # share of the even gap a member's angle may deviate by
EXIT_GAP_M = 0.4  # metres from the wall where a failing player leaves the area
AROUND_M = 0.6  # metres outside the circle where shuffling players walk round it
AROUND_STEP_RAD = math.pi / 4  # radians, largest turn between two waypoints round the circle
ROUTE_PACE = 0.7  # waypoints are timed for walkers this much slower than their speed
ROBOT_ID = 0
ROBOT_CORNER_M = 0.6  # metres from the walls, where a watching robot stands
END_TAIL_S = 2.0  # seconds recorded after the game ends (the last two still stand together)
MAX_TURNS = 10_000  # turns after which the game stops even without a winner


@register("word-improv", tags=("game",), robot={"robot": "watch"})
@shared_help(circle=CIRCLE_OPTIONS)
def word_improv(
    *,
    seed: int,
    players: Annotated[int, Range(2, 7)] = 6,
    turn_duration: Annotated[float, Range(5.0, 300.0, unit="s")] = 30.0,
    fail_probability: Annotated[float, Range(0.01, 1.0)] = 0.12,
    robot: Literal["none", "watch", "moderate"] = "none",
    radius_base: Annotated[float, Range(0.3, 2.0, unit="m")] = BABBLE_RADIUS.base,
    radius_per_member: Annotated[float, Range(0.0, 0.5, unit="m")] = BABBLE_RADIUS.per_member,
    radius_spread: Annotated[float, Range(0.0, 0.5)] = 0.03,
    position_noise: PlaceNoise = 0.03,
    orientation_noise: Annotated[float, Range(0.0, 0.8, unit="rad")] = 0.08,
    head_noise: Annotated[float, Range(0.0, 0.8, unit="rad")] = 0.0,
    mean_utterance: Annotated[float, Range(0.5, 60.0, unit="s")] = 5.0,
) -> Scenario:
    """The Babble Word Improv Game: a circle that shuffles and loses a player at a time.

    Args:
        seed: seeds every draw.
        players: players at the start, besides the moderator; Babble: 6 and a moderator.
        turn_duration: mean length of a turn, seconds.
        fail_probability: chance that the turn's player fails and leaves, per turn.
        robot: none, watch (from a corner) or moderate (the robot is the moderator).
        {circle}
        mean_utterance: mean length of one speaker's turn to speak, seconds.
    """
    name = "word-improv"
    shape = CircleShape(
        RadiusLaw(radius_base, radius_per_member),
        radius_spread,
        CircleNoise(position_noise, orientation_noise),
    )
    largest = shape.law(players + 1) * (1.0 + 3.0 * radius_spread) + CENTRE_JITTER_M + 0.35
    if largest > 0.5 * min(AREA_M):
        raise ValueError(
            f"{name}: a circle of {players + 1} with radius_base {radius_base:g} m and "
            f"radius_per_member {radius_per_member:g} m does not fit the "
            f"{AREA_M[0]:g} m x {AREA_M[1]:g} m area"
        )
    rng = np.random.default_rng(seed)
    moderated_by_robot = robot == "moderate"
    first_person = 1
    moderator = ROBOT_ID if moderated_by_robot else first_person
    player_ids = [first_person + k + (0 if moderated_by_robot else 1) for k in range(players)]
    people = player_ids if moderated_by_robot else [moderator, *player_ids]
    agents = [*people] + ([ROBOT_ID] if robot != "none" else [])
    builder = TimelineBuilder(agents)

    def formation(members: list[int], angles_of: dict[int, float]) -> tuple:
        n = len(members)
        centre = rng.uniform(-CENTRE_JITTER_M, CENTRE_JITTER_M, size=2)
        radius = shape.radius(n, rng, least=0.5)
        places, facings = shape.noise.places(centre, radius, [angles_of[m] for m in members], rng)
        return centre, places, facings

    def slots(members_in_order: list[int], moderator_angle: float) -> dict[int, float]:
        """Even angles around the circle, the moderator's first."""
        n = len(members_in_order)
        gap = 2.0 * math.pi / n
        jitter = rng.uniform(-ANGLE_JITTER, ANGLE_JITTER, size=n) * gap
        jitter[0] = 0.0
        return {
            m: moderator_angle + gap * k + float(jitter[k]) for k, m in enumerate(members_in_order)
        }

    moderator_angle = float(rng.uniform(-math.pi, math.pi))
    remaining = list(player_ids)
    order = [moderator, *[remaining[k] for k in rng.permutation(len(remaining))]]
    angles_of = slots(order, moderator_angle)
    members = [moderator, *remaining]
    centre, places, facings = formation(members, angles_of)
    place_of = {m: places[k] for k, m in enumerate(members)}
    facing_of = {m: float(facings[k]) for k, m in enumerate(members)}
    robot_place = None
    if robot == "watch":
        hx, hy = 0.5 * AREA_M[0] - ROBOT_CORNER_M, 0.5 * AREA_M[1] - ROBOT_CORNER_M
        corner = np.array([-hx, -hy])
        robot_place = RobotPlace(
            id=ROBOT_ID,
            position=(float(corner[0]), float(corner[1])),
            yaw=float(math.atan2(-corner[1], -corner[0])),
        )
    elif moderated_by_robot:
        robot_place = RobotPlace(
            id=ROBOT_ID,
            position=(float(place_of[ROBOT_ID][0]), float(place_of[ROBOT_ID][1])),
            yaw=facing_of[ROBOT_ID],
        )
    starts = np.array([place_of[p] for p in people])
    roles = cast(
        rng,
        people,
        starts,
        [facing_of[p] for p in people],
        parts=["moderator" if p == moderator else "player" for p in people],
    )
    handle = builder.group(members, places, facings, centre, start=0.0)
    builder.event(0.0, "game", f"moderator {moderator}, players {remaining}")
    t = 0.0
    turn = 0
    while len(remaining) >= 1 and turn < MAX_TURNS:
        turn += 1
        picked = remaining[int(rng.integers(len(remaining)))]
        length = turn_duration * rng.uniform(1.0 - TURN_SPREAD, 1.0 + TURN_SPREAD)
        final = len(remaining) == 1
        builder.event(
            t,
            "turn",
            f"turn {turn}: the moderator reads a word, player {picked} improvises"
            + (" (the winner)" if final else ""),
        )
        spots = np.array([place_of[m] for m in members])
        turn_facings = np.array([facing_of[m] for m in members])
        converse(
            builder,
            members,
            spots,
            turn_facings,
            start=t,
            end=t + length,
            rng=rng,
            mean_utterance=mean_utterance,
            speakers=[moderator, picked],
            head_noise=head_noise,
        )
        if robot == "watch":
            assert robot_place is not None
            builder.set(
                t,
                ROBOT_ID,
                standing(np.array(robot_place.position), robot_place.yaw, gaze_agent=picked),
            )
        t += length
        if final:
            builder.event(t, "end", f"player {picked} wins")
            t += END_TAIL_S
            break
        builder.end_group(handle, t)
        if rng.random() < fail_probability:
            remaining.remove(picked)
            out = _exit_point(place_of[picked])
            speed = float(rng.uniform(*SHUFFLE_SPEED_M_S))
            builder.set(t, picked, Intent(goal=out, speed=speed))
            gone = t + float(np.hypot(*(np.array(out) - place_of[picked]))) / speed + SETTLE_S
            builder.set(gone, picked, Intent(present=False))
            builder.event(t, "elimination", f"player {picked} fails and leaves the circle")
        builder.event(t, "shuffle", f"players {remaining} shuffle")
        # Players in the circle's order (from the moderator on), then each to another's place.
        circle = sorted(remaining, key=lambda m: (angles_of[m] - moderator_angle) % math.tau)
        moved = _derangement(len(circle), rng)
        order = [moderator, *[circle[k] for k in moved]]
        angles_of = slots(order, moderator_angle)
        members = [moderator, *remaining]
        centre, places, facings = formation(members, angles_of)
        walk = 0.0
        for k, m in enumerate(members):
            delay = 0.0 if m == moderator else float(rng.uniform(*SHUFFLE_DELAY_S))
            speed = float(rng.uniform(*SHUFFLE_SPEED_M_S))
            step_in = standing(places[k], facings[k], speed=speed, gaze_point=tuple(centre))
            if m == moderator:
                builder.set(t + delay, m, step_in)
                distance = float(np.hypot(*(places[k] - place_of[m])))
                walk = max(walk, delay + distance / speed)
                continue
            # Players step out of the circle, walk around it to just outside their new place
            # and step in between their neighbours (not across or along a standing circle).
            here = place_of[m]
            clock = t + delay
            gaze = (float(centre[0]), float(centre[1]))
            pace = ROUTE_PACE * speed  # waypoints are timed for a slowed walker: none skipped
            for spot in _around(here, places[k], centre, ring=radius_of(places) + AROUND_M):
                builder.set(clock, m, Intent(goal=spot, speed=speed, gaze_point=gaze))
                clock += float(np.hypot(*(np.array(spot) - here))) / pace
                here = np.array(spot)
            builder.set(clock, m, step_in)
            clock += float(np.hypot(*(places[k] - here))) / speed
            walk = max(walk, clock - t)
        handle = builder.group(members, places, facings, centre, start=t)
        place_of = {m: places[k] for k, m in enumerate(members)}
        facing_of = {m: float(facings[k]) for k, m in enumerate(members)}
        t += walk + SETTLE_S
    return Scenario(
        name=name,
        seed=seed,
        stage=Stage(room=AREA_M, people=roles, robot=robot_place),
        timeline=builder.build(),
        duration=t,
        description="the Babble Word Improv Game: a shuffling circle that loses a player a turn",
    )


def radius_of(places: np.ndarray) -> float:
    """Mean distance of ``places`` to their mean, metres."""
    return float(np.hypot(*(places - places.mean(axis=0)).T).mean())


def _around(
    start: np.ndarray, place: np.ndarray, centre: np.ndarray, *, ring: float
) -> list[tuple[float, float]]:
    """Waypoints from ``start`` out to a ring of radius ``ring`` round ``centre``, along it the
    shorter way (steps of at most `AROUND_STEP_RAD`), to just outside ``place``."""
    a0 = math.atan2(start[1] - centre[1], start[0] - centre[0])
    a1 = math.atan2(place[1] - centre[1], place[0] - centre[0])
    turn = math.remainder(a1 - a0, math.tau)
    steps = max(1, math.ceil(abs(turn) / AROUND_STEP_RAD))
    return [
        _inside_area(centre + ring * np.array([math.cos(a), math.sin(a)]))
        for a in a0 + turn * np.arange(steps + 1) / steps
    ]


def _inside_area(point: np.ndarray) -> tuple[float, float]:
    """``point`` moved inside the area, a body and a margin from the walls."""
    hx, hy = 0.5 * AREA_M[0] - EXIT_GAP_M, 0.5 * AREA_M[1] - EXIT_GAP_M
    return (float(np.clip(point[0], -hx, hx)), float(np.clip(point[1], -hy, hy)))


def _exit_point(place: np.ndarray) -> tuple[float, float]:
    """The nearest point just inside the area's wall, outward from ``place``."""
    hx, hy = 0.5 * AREA_M[0] - EXIT_GAP_M, 0.5 * AREA_M[1] - EXIT_GAP_M
    x, y = float(place[0]), float(place[1])
    if hx - abs(x) < hy - abs(y):
        return (math.copysign(hx, x), float(np.clip(y, -hy, hy)))
    return (float(np.clip(x, -hx, hx)), math.copysign(hy, y))


def _derangement(n: int, rng: np.random.Generator) -> np.ndarray:
    """A random permutation of ``range(n)`` moving every index (``n`` >= 2), by rejection."""
    while True:
        order = rng.permutation(n)
        if n < 2 or not np.any(order == np.arange(n)):
            return order
