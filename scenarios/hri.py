"""The REFORM paper's proof-of-concept scenes with the Directions Robot.

* ``hri-conversation``: two people walk up to the robot and talk with it: one F-formation of
  three, the robot included, from the moment both have arrived until they leave.
* ``hri-robot-excluded``: two people stand in front of the robot and talk to each other: an
  F-formation of two; the robot watches and is left out.
* ``hri-passing``: people walk past each other and the robot, again and again: no F-formation.

The robot stands near the west wall facing east (+x); its sensor looks into the room. Timing,
positions, paths and gaze vary with the seed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Annotated, Any, Literal

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
from scenarios.conversation import MEAN_UTTERANCE_S, converse, standing
from scenarios.formation import CircleNoise, facing_centre, min_radius
from scenarios.registry import PlaceNoise, Range, SceneSeconds, register, shared_help
from scenarios.scenario import Scenario
from scenarios.script import WALK_SPEED_M_S, Intent
from scenarios.stage import RobotPlace, Role, Stage
from scenarios.timeline import TimelineBuilder

__all__ = ["hri_conversation", "hri_passing", "hri_robot_excluded"]

ROOM_M = (6.0, 5.0)  # metres, the HRI room
PASSING_ROOM_M = (8.0, 6.0)  # metres, room of hri-passing
ROBOT_ID = 0
_GUESTS = (1, 2)  # the two people of hri-conversation and hri-robot-excluded
ROBOT_WALL_GAP_M = 1.0  # metres from the west wall to the robot
WALK_SPEED_RANGE_M_S = (1.0, 1.3)  # m/s, people's walking speeds
SETTLE_S = 2.5  # seconds allowed beyond distance / speed to stop and turn
EXIT_GAP_M = 0.45  # metres from a wall where people leave the room
START_DELAY_S = (0.0, 1.0)  # seconds, when each person sets off
TRIANGLE_JITTER_RAD = 0.15  # radians, spread of the people's places around the even triangle
# Scripted changes (`scenarios.changes`).
VISITORS = 4  # people who may come in as latecomers or as a pair that merges (ids after guests)
MAX_GROUP = 5  # people in the group at most, the robot included
FIRST_CHANGE_S = 3.0  # seconds after the guests have arrived before the first change
MAKE_ROOM_S = 1.0  # seconds before a latecomer arrives that the members make room
APPROACH_SPEED_M_S = 1.0  # m/s, default speed of a latecomer walking up
CHANGE_GAP_S = 3.0  # seconds a change waits beyond the end of the one before
END_GAP_S = 3.0  # seconds a change is over before the conversation ends
DRIFT_M = 1.2  # metres someone drifting away first steps back from the group
APPROACH_M = 1.2  # metres from their place a latecomer's last straight walk up starts
OPEN_ARC_RAD = math.pi / 3.0  # radians either side of east in which newcomers come in
ROOM_MARGIN_M = 0.9  # metres from the walls the spot where a pair meets keeps
PAIR_DISTANCE_M = (2.0, 2.6)  # metres from the group's centre to where a pair meets
PAIR_RADIUS_M = 0.42  # metres, half the distance between the two of a pair
PAIR_TALK_S = (4.0, 8.0)  # seconds a pair talks before walking over to merge
# Options the HRI scenes share: the standard deviation of a facing, radians, and the mean
# length of one speaker's turn, seconds.
_FacingNoise = Annotated[float, Range(0.0, 0.5, unit="rad")]
_UtteranceSeconds = Annotated[float, Range(0.5, 30.0, unit="s")]


def _robot(room: tuple[float, float]) -> RobotPlace:
    return RobotPlace(id=ROBOT_ID, position=(-0.5 * room[0] + ROBOT_WALL_GAP_M, 0.0), yaw=0.0)


def _walk_time(a: np.ndarray, b: np.ndarray, speed: float) -> float:
    return float(np.hypot(*(np.asarray(b) - np.asarray(a)))) / speed + SETTLE_S


def _approach(
    rng: np.random.Generator,
    side: str,
    robot: RobotPlace,
    places: np.ndarray,
    facings: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two people walk in side by side from ``side`` to ``places``: their (2, 2) start
    positions, metres, and the (2, 2) places and (2,) facings reordered so that their paths do
    not cross."""
    hx, hy = 0.5 * ROOM_M[0] - 0.5, 0.5 * ROOM_M[1] - 0.5
    if side == "random":
        side = ("front", "left", "right")[int(rng.integers(3))]
    if side == "front":
        x = rng.uniform(hx - 0.6, hx)
        y = rng.uniform(-0.6, 0.6)
        starts = np.array([[x, y + 0.4], [x, y - 0.4]])
    else:
        sign = 1.0 if side == "left" else -1.0
        x = robot.position[0] + rng.uniform(1.2, 2.4)
        starts = np.array([[x - 0.4, sign * hy], [x + 0.4, sign * hy]])
    straight = np.hypot(*(starts[0] - places[0])) + np.hypot(*(starts[1] - places[1]))
    swapped = np.hypot(*(starts[0] - places[1])) + np.hypot(*(starts[1] - places[0]))
    if swapped < straight:
        return starts, places[::-1].copy(), facings[::-1].copy()
    return starts, places, facings


def _take_places(
    builder: TimelineBuilder,
    people: list[int],
    starts: np.ndarray,
    places: np.ndarray,
    facings: np.ndarray,
    rng: np.random.Generator,
    *,
    walk_in: bool = True,
) -> float:
    """``people`` stand at ``starts``, then walk to ``places`` (each setting off within
    `START_DELAY_S` when they walk in) and face ``facings``; returns when the last has arrived,
    seconds (0 when they do not walk in)."""
    arrive = 0.0
    for k, person in enumerate(people):
        delay = float(rng.uniform(*START_DELAY_S)) if walk_in else 0.0
        speed = float(rng.uniform(*WALK_SPEED_RANGE_M_S))
        builder.set(0.0, person, Intent())
        builder.set(delay, person, standing(places[k], facings[k], speed=speed))
        if walk_in:
            arrive = max(arrive, delay + _walk_time(starts[k], places[k], speed))
    return arrive


@dataclass(frozen=True)
class _Guests:
    """The two guests of a scene at their places: (2, 2) places, metres, and (2,) facings,
    radians, on the o-space circle round ``centre``, and when the last has arrived, seconds."""

    places: np.ndarray
    facings: np.ndarray
    centre: np.ndarray
    arrive: float


@dataclass
class _Scene:
    """An HRI scene being drawn: its name, seed and generator, its room with the robot at the
    west wall; the people's roles and the timeline's builder once they are cast (`cast`)."""

    name: str
    seed: int
    room: tuple[float, float] = ROOM_M
    visitors: int = 0  # people absent at the start who may come in (scripted changes)
    rng: np.random.Generator = field(init=False)
    robot: RobotPlace = field(init=False)
    roles: tuple[Role, ...] = field(init=False)
    builder: TimelineBuilder = field(init=False)

    def __post_init__(self) -> None:
        self.rng = np.random.default_rng(self.seed)
        self.robot = _robot(self.room)

    @property
    def robot_xy(self) -> np.ndarray:
        """(2,) where the robot stands, metres."""
        return np.array(self.robot.position)

    def cast(self, people: list[int], starts: np.ndarray, yaws: np.ndarray, part: str) -> None:
        """``people``, playing ``part``, start at ``starts`` facing ``yaws``; the scene's
        builder holds them and the robot."""
        self.roles = cast(self.rng, people, starts, yaws, parts=part)
        if self.visitors:  # absent until they come in, by the east wall
            ids = self.visitor_ids
            spots = np.array([self.door(k) for k in range(len(ids))])
            yaws = np.full(len(ids), math.pi)
            self.roles += cast(self.rng, ids, spots, yaws, parts="visitor", present=False)
        self.builder = TimelineBuilder([*people, *self.visitor_ids, ROBOT_ID])

    @property
    def visitor_ids(self) -> list[int]:
        """Ids of the visitors, after the guests'."""
        return list(range(_GUESTS[-1] + 1, _GUESTS[-1] + 1 + self.visitors))

    def door(self, k: int) -> np.ndarray:
        """(2,) where visitor ``k`` comes in, by the east wall, metres."""
        hx, hy = 0.5 * self.room[0] - EXIT_GAP_M, 0.5 * self.room[1] - 1.0
        return np.array([hx, -hy + 2.0 * hy * (k + 0.5) / max(self.visitors, 1)])

    def robot_stands(self, t: float, **gaze: Any) -> None:
        """From ``t`` the robot stands at its place, looking where ``gaze`` says (`standing`)."""
        self.builder.set(t, ROBOT_ID, standing(self.robot_xy, self.robot.yaw, **gaze))

    def guests(
        self,
        centre: np.ndarray,
        radius: float,
        angles: np.ndarray,
        *,
        approach: str | None,
        position_noise: float,
        orientation_noise: float,
    ) -> _Guests:
        """The two guests take their places at ``angles`` on the o-space circle around
        ``centre``, walking in from ``approach`` (`_approach`; None: they stand there from the
        start)."""
        noise = CircleNoise(position_noise, orientation_noise)
        places, facings = noise.places(centre, radius, angles, self.rng)
        if approach is None:
            starts, start_yaws = places.copy(), facings.copy()
        else:
            starts, places, facings = _approach(self.rng, approach, self.robot, places, facings)
            start_yaws = facing_centre(starts, centre)
        people = list(_GUESTS)
        self.cast(people, starts, start_yaws, "guest")
        walk_in = approach is not None
        arrive = _take_places(
            self.builder, people, starts, places, facings, self.rng, walk_in=walk_in
        )
        return _Guests(places, facings, centre, arrive)

    def talk(
        self,
        guests: _Guests,
        *,
        robot_joins: bool,
        talk_duration: float,
        leave: bool,
        mean_utterance: float,
    ) -> float:
        """The guests converse from when the last has arrived for ``talk_duration`` seconds:
        with the robot (``robot_joins``: a group of three; the robot looks at the first guest),
        or in front of it (a group of two; the robot looks at the group's centre, then at each
        speaker); then, with ``leave``, they walk out. The group is planned from the start (the
        rule starts it once all have arrived) until they set off. Returns the scene's end,
        seconds."""
        people = list(_GUESTS)
        members, places, facings = people, guests.places, guests.facings
        if robot_joins:
            members = [ROBOT_ID, *people]
            places = np.vstack([self.robot_xy, guests.places])
            facings = np.concatenate([[self.robot.yaw], guests.facings])
            self.builder.event(0.0, "approach", f"people {people} walk up to the robot")
        talk_end = guests.arrive + talk_duration
        end = talk_end if leave else math.inf
        self.builder.group(members, places, facings, guests.centre, start=0.0, end=end)
        turns = converse(
            self.builder,
            members,
            places,
            facings,
            start=guests.arrive,
            end=talk_end,
            rng=self.rng,
            mean_utterance=mean_utterance,
        )
        if robot_joins:
            self.robot_stands(0.0, gaze_agent=people[0])
        else:
            self.robot_stands(0.0, gaze_point=tuple(guests.centre))
            for t, speaker in turns:
                self.robot_stands(t, gaze_agent=speaker)
        return self.leave(people, guests.places, talk_end) if leave else talk_end

    def talk_with_changes(
        self,
        guests: _Guests,
        *,
        robot_joins: bool,
        radius: float,
        noise: CircleNoise,
        talk_duration: float,
        leave: bool,
        mean_utterance: float,
        event_rate: float,
        event_kinds: str,
        approach_speed: float,
    ) -> float:
        """`talk`, with scripted changes of the group while it talks (`scenarios.changes`):
        visitors come in from the east wall and join as latecomers, members drift away and
        leave the room (coming back later as latecomers), and pairs of visitors meet in the
        room and walk over to merge with the group. The group grows up to `MAX_GROUP` people
        on a circle of ``radius`` (wider when its members would stand closer than
        `scenarios.stage.SPACING_M`); with the robot in it, the robot keeps its place on the
        circle. Returns the scene's end, seconds."""
        people = list(_GUESTS)
        group = _Circle.first(self, guests, robot_joins=robot_joins, radius=radius)
        if robot_joins:
            self.builder.event(0.0, "approach", f"people {people} walk up to the robot")
            self.robot_stands(0.0, gaze_agent=people[0])
        else:
            self.robot_stands(0.0, gaze_point=tuple(guests.centre))
        talk_end = guests.arrive + talk_duration
        away = {v: 0.0 for v in self.visitor_ids}  # who is out of the room, and from when
        rng = self.rng
        talk = {"mean_utterance": mean_utterance}
        last, ready = guests.arrive, guests.arrive + FIRST_CHANGE_S
        while True:
            t = next_change(rng, event_rate, ready=ready, last=last)
            if t >= talk_end:
                break
            last = t
            free = sorted(v for v, at in away.items() if at <= t)
            n = len(group.members)
            possible = {
                JOIN: bool(free) and n < MAX_GROUP,
                LEAVE: n >= 3,
                MERGE: len(free) >= 2 and n + 2 <= MAX_GROUP,
            }
            kind = draw_kind(rng, event_kinds, possible)
            if kind == JOIN:
                person = free[int(rng.integers(len(free)))]
                walkers = {person: (group.open_bearing(), approach_speed)}
                grown = group.grown(self, walkers, radius=radius, noise=noise)
                place = grown.place(person)
                start = self.door_facing(place)
                near = grown.outside(place)
                on = t + float(np.hypot(*(near - start))) / approach_speed
                arrive = on + _walk_time(near, place, approach_speed)
                if arrive + END_GAP_S > talk_end:
                    break
                self.builder.set(
                    t,
                    person,
                    Intent(
                        present=True,
                        appear_at=(float(start[0]), float(start[1])),
                        goal=(float(near[0]), float(near[1])),
                        speed=approach_speed,
                    ),
                )
                self.builder.set(
                    on, person, standing(place, grown.facing(person), speed=approach_speed)
                )
                self.builder.event(
                    t,
                    JOIN,
                    f"person {person} walks up to join group {sorted(group.members)} at "
                    f"{approach_speed:g} m/s",
                )
                del away[person]
                shift = max(on, arrive - SETTLE_S - MAKE_ROOM_S)
                group = self._change(group, grown, t, shift, [person], **talk)
                ready = arrive + CHANGE_GAP_S
            elif kind == LEAVE:
                if t + END_GAP_S > talk_end:
                    break
                movable = [m for m in group.members if m != ROBOT_ID]
                person = movable[int(rng.integers(len(movable)))]
                out = self._drift(group, person, t)
                away[person] = out + CHANGE_GAP_S
                self.builder.event(
                    t, LEAVE, f"person {person} drifts away from group {sorted(group.members)}"
                )
                group = self._change(group, group.without(person), t, t, [], **talk)
                ready = t + CHANGE_GAP_S
            elif kind == MERGE:
                pair = sorted(int(v) for v in rng.choice(free, size=2, replace=False))
                bearing = group.open_bearing()
                met = self._pair(group, pair, t, bearing, noise=noise)
                walkers = {
                    m: (math.atan2(*(met.place(m) - group.centre)[::-1]), approach_speed)
                    for m in pair
                }
                grown = group.grown(self, walkers, radius=radius, noise=noise)
                go = met.arrive + float(rng.uniform(*PAIR_TALK_S))
                arrive = go + max(
                    _walk_time(met.place(m), grown.place(m), approach_speed) for m in pair
                )
                if arrive + END_GAP_S > talk_end:
                    break
                for m in pair:
                    del away[m]
                    door = self.door_facing(met.place(m))
                    self.builder.set(
                        t,
                        m,
                        Intent(
                            present=True,
                            appear_at=(float(door[0]), float(door[1])),
                            goal=tuple(met.place(m)),
                        ),
                    )
                self.builder.event(t, "pair", f"people {pair} come in and talk")
                met.talk(self, met.arrive, go, **talk)
                for m in pair:
                    self.builder.set(
                        go, m, standing(grown.place(m), grown.facing(m), speed=approach_speed)
                    )
                self.builder.event(
                    go,
                    MERGE,
                    f"group {pair} walks over to merge with group {sorted(group.members)} at "
                    f"{approach_speed:g} m/s",
                )
                shift = max(go + CHANGE_GAP_S, arrive - SETTLE_S - MAKE_ROOM_S)
                group = self._change(group, grown, go, shift, pair, also=met, **talk)
                ready = arrive + CHANGE_GAP_S
            else:
                ready = t
        group.talk(self, group.talk_from, talk_end, **talk)
        if not leave:
            return talk_end
        self.builder.end_group(group.handle, talk_end)
        leaving = [m for m in group.members if m != ROBOT_ID]
        return self.leave(leaving, np.array([group.place(m) for m in leaving]), talk_end)

    def _change(
        self,
        group: _Circle,
        after: _Circle,
        t: float,
        shift: float,
        newcomers: list[int],
        *,
        also: _Circle | None = None,
        mean_utterance: float,
    ) -> _Circle:
        """``group`` becomes ``after`` (planned from ``t``, its ``newcomers`` to arrive; with
        newcomers, continuing ``group`` and ``also``): ``group`` talks until ``shift``, when
        its members walk to their new places; ``after`` talks from then."""
        group.talk(self, group.talk_from, shift, mean_utterance=mean_utterance)
        self.builder.end_group(group.handle, shift)
        if also is not None:
            self.builder.end_group(also.handle, t)
        # Someone left: the group as it was ends as they set off, not when the rest does.
        continues = [group.handle] if newcomers else []
        if also is not None:
            continues.append(also.handle)
        after.handle = self.builder.group(
            after.members,
            after.places,
            after.facings,
            after.centre,
            start=t,
            newcomers=newcomers,
            continues=continues,
        )
        after.talk_from = shift
        return after

    def door_facing(self, place: np.ndarray) -> np.ndarray:
        """(2,) where someone walking to ``place`` comes in: by the east wall, level with it
        (within 1.5 m of the room's middle), metres."""
        hx = 0.5 * self.room[0] - EXIT_GAP_M
        return np.array([hx, float(np.clip(place[1], -1.5, 1.5))])

    def _drift(self, group: _Circle, person: int, t: float) -> float:
        """``person`` steps back from ``group`` by `DRIFT_M`, then walks out by the east wall;
        returns when they are gone, seconds."""
        here = group.place(person)
        outward = here - group.centre
        outward = outward / max(float(np.hypot(*outward)), 1e-9)
        hx, hy = 0.5 * self.room[0] - EXIT_GAP_M, 0.5 * self.room[1] - EXIT_GAP_M
        back = np.clip(here + DRIFT_M * outward, [-hx, -hy], [hx, hy])
        exit_at = np.array([hx, float(np.clip(back[1] + self.rng.uniform(-0.8, 0.8), -1.5, 1.5))])
        speed = float(self.rng.uniform(*WALK_SPEED_RANGE_M_S))
        self.builder.set(t, person, Intent(goal=(float(back[0]), float(back[1])), speed=speed))
        on = t + _walk_time(here, back, speed) - SETTLE_S
        self.builder.set(
            on, person, Intent(goal=(float(exit_at[0]), float(exit_at[1])), speed=speed)
        )
        out = on + _walk_time(back, exit_at, speed)
        self.builder.set(out, person, Intent(present=False))
        return out

    def _pair(
        self,
        group: _Circle,
        pair: list[int],
        t: float,
        bearing: float,
        *,
        noise: CircleNoise,
    ) -> _Circle:
        """``pair`` come in at ``t`` (`door_facing`) and meet as a group of two in the room,
        `PAIR_DISTANCE_M` from ``group``'s centre toward ``bearing`` (radians); planned from
        ``t``."""
        rng = self.rng
        reach = float(rng.uniform(*PAIR_DISTANCE_M))
        limit = 0.5 * np.array(self.room) - ROOM_MARGIN_M - PAIR_RADIUS_M
        spot = group.centre + reach * np.array([math.cos(bearing), math.sin(bearing)])
        spot = np.clip(spot, -limit, limit)
        # North and south of the spot: each walks in level with their place, and on to theirs
        # in the group without crossing the other's path.
        angles = np.array([0.5 * math.pi, -0.5 * math.pi])
        places, facings = noise.places(spot, PAIR_RADIUS_M, angles, rng)
        arrive = t + max(
            _walk_time(self.door_facing(places[k]), places[k], WALK_SPEED_M_S) for k in range(2)
        )
        met = _Circle(list(pair), places, facings, spot, PAIR_RADIUS_M, arrive=arrive)
        met.handle = self.builder.group(pair, places, facings, spot, start=t)
        return met

    def leave(self, people: list[int], places: np.ndarray, t: float) -> float:
        """At ``t`` the robot stops following and ``people`` walk from ``places`` to the east
        wall and out; returns the episode's end, a second after the last is gone."""
        self.builder.event(t, "leave", f"people {people} walk away")
        self.robot_stands(t)
        gone = t
        hx = 0.5 * self.room[0] - EXIT_GAP_M
        for k, person in enumerate(people):
            side = float(np.clip(places[k, 1] + self.rng.uniform(-0.8, 0.8), -1.5, 1.5))
            exit_at = np.array([hx, side])
            speed = float(self.rng.uniform(*WALK_SPEED_RANGE_M_S))
            goal = (float(exit_at[0]), float(exit_at[1]))
            self.builder.set(t, person, Intent(goal=goal, speed=speed))
            out = t + _walk_time(places[k], exit_at, speed)
            self.builder.set(out, person, Intent(present=False))
            gone = max(gone, out)
        return gone + 1.0

    def made(self, duration: float, description: str) -> Scenario:
        """The scene, made: its people and the robot in its room."""
        return Scenario(
            name=self.name,
            seed=self.seed,
            stage=Stage(room=self.room, people=self.roles, robot=self.robot),
            timeline=self.builder.build(),
            duration=duration,
            description=description,
        )


@dataclass
class _Circle:
    """A group of an HRI scene as planned from one moment: its members round ``centre``, at
    (k, 2) ``places``, metres, facing (k,) ``facings``, radians; the planned group's
    ``handle``; when its conversation starts (``talk_from``) and, for a pair on its way in,
    when it has arrived (``arrive``); who walks up to it at what speed (``speeds``, m/s);
    whether the robot is one of it (it keeps its place) or watches it (``watched``)."""

    members: list[int]
    places: np.ndarray
    facings: np.ndarray
    centre: np.ndarray
    radius: float
    handle: int = -1
    talk_from: float = 0.0
    arrive: float = 0.0
    speeds: dict[int, float] = field(default_factory=dict)
    watched: bool = False

    @classmethod
    def first(cls, scene: _Scene, guests: _Guests, *, robot_joins: bool, radius: float) -> _Circle:
        """The guests' group (with the robot, ``robot_joins``), planned from the start."""
        members, places, facings = list(_GUESTS), guests.places, guests.facings
        if robot_joins:
            members = [ROBOT_ID, *members]
            places = np.vstack([scene.robot_xy, guests.places])
            facings = np.concatenate([[scene.robot.yaw], guests.facings])
        group = cls(members, places, facings, guests.centre, radius, watched=not robot_joins)
        group.handle = scene.builder.group(members, places, facings, guests.centre, start=0.0)
        group.talk_from = guests.arrive
        return group

    def place(self, m: int) -> np.ndarray:
        return self.places[self.members.index(m)]

    def outside(self, place: np.ndarray) -> np.ndarray:
        """(2,) `APPROACH_M` out from ``place``, away from the centre, metres: where a
        latecomer's last straight walk up to ``place`` starts."""
        outward = place - self.centre
        return place + APPROACH_M * outward / max(float(np.hypot(*outward)), 1e-9)

    def facing(self, m: int) -> float:
        return float(self.facings[self.members.index(m)])

    def without(self, person: int) -> _Circle:
        """The group once ``person`` has left: the others where they stood."""
        keep = [k for k, m in enumerate(self.members) if m != person]
        return _Circle(
            [self.members[k] for k in keep],
            self.places[keep],
            self.facings[keep],
            self.centre,
            self.radius,
            watched=self.watched,
        )

    def open_bearing(self) -> float:
        """The direction from the centre toward the door (east, within `OPEN_ARC_RAD`),
        farthest in angle from every member: where newcomers come in, radians."""
        taken = np.array([math.atan2(*(p - self.centre)[::-1]) for p in self.places])
        candidates = np.linspace(-OPEN_ARC_RAD, OPEN_ARC_RAD, 25)
        apart = np.abs(np.angle(np.exp(1j * (candidates[:, None] - taken[None, :]))))
        return float(candidates[int(np.argmax(apart.min(axis=1)))])

    def grown(
        self,
        scene: _Scene,
        walkers: dict[int, tuple[float, float]],
        *,
        radius: float,
        noise: CircleNoise,
    ) -> _Circle:
        """The group with ``walkers`` (id -> the angle round the centre they come in at,
        radians; speed, m/s) in it: everyone spread evenly round the circle in their order
        round it, the robot at its place; the circle widened to `min_radius` of its size
        (with the robot, its centre moves away from the robot to keep it on the circle). The
        robot keeps its place; in a group without it, the first newcomer takes the angle they
        come in at."""
        angles = {
            m: math.atan2(*(p - self.centre)[::-1])
            for m, p in zip(self.members, self.places, strict=True)
        }
        angles.update({w: angle for w, (angle, _) in walkers.items()})
        n = len(angles)
        wide = max(radius, min_radius(n))
        fixed = ROBOT_ID in self.members
        centre = self.centre
        if fixed:
            yaw = scene.robot.yaw
            centre = scene.robot_xy + wide * np.array([math.cos(yaw), math.sin(yaw)])
            angles[ROBOT_ID] = math.pi + yaw
        # The robot keeps its place, else the first newcomer takes theirs where they come in.
        anchor = ROBOT_ID if fixed else next(iter(walkers))
        order = sorted(angles, key=lambda m: (angles[m] - angles[anchor]) % (2.0 * math.pi))
        gap = 2.0 * math.pi / n
        even = np.array([angles[anchor] + k * gap for k in range(n)])
        places, facings = noise.places(centre, wide, even, scene.rng)
        if fixed:
            places[0], facings[0] = scene.robot_xy, scene.robot.yaw
        return _Circle(
            order,
            places,
            facings,
            centre,
            wide,
            speeds={w: speed for w, (_, speed) in walkers.items()},
            watched=self.watched,
        )

    def talk(self, scene: _Scene, start: float, end: float, *, mean_utterance: float) -> None:
        """The members converse from ``start`` to ``end``; the robot watching looks at the
        group's centre, then at each speaker."""
        if end <= start:
            return
        turns = converse(
            scene.builder,
            self.members,
            self.places,
            self.facings,
            start=start,
            end=end,
            rng=scene.rng,
            mean_utterance=mean_utterance,
            speed=self.speeds or None,
        )
        if self.watched:
            scene.robot_stands(start, gaze_point=(float(self.centre[0]), float(self.centre[1])))
            for t, speaker in turns:
                scene.robot_stands(t, gaze_agent=speaker)


_TALK_OPTIONS = {
    "leave": "whether they walk out at the end (the group ends when they set off).",
    "position_noise": "standard deviation of each person's place, metres.",
    "orientation_noise": "standard deviation of each person's facing, radians.",
    "mean_utterance": "mean length of one speaker's turn, seconds.",
}
"""The help of the options the two conversation scenes share."""


# The REFORM paper's proof-of-concept: exactly these three scenes, in this order. A curated set,
# not a tag: a new scenario tagged "hri" joins the HRI tag's listings, never this experiment.
PAPER_HRI_SCENES = ("hri-conversation", "hri-robot-excluded", "hri-passing")


@register("hri-conversation", tags=("hri",), robot={})
@shared_help(talk=_TALK_OPTIONS, changes=CHANGE_OPTIONS)
def hri_conversation(
    *,
    seed: int,
    radius: Annotated[float, Range(0.3, 1.5, unit="m")] = 0.6,
    talk_duration: SceneSeconds = 40.0,
    approach: Literal["front", "left", "right", "random"] = "random",
    leave: bool = True,
    position_noise: PlaceNoise = 0.03,
    orientation_noise: _FacingNoise = 0.1,
    mean_utterance: _UtteranceSeconds = MEAN_UTTERANCE_S,
    event_rate: EventRate = 0.0,
    event_kinds: EventKinds = "mixed",
    approach_speed: ApproachSpeed = APPROACH_SPEED_M_S,
) -> Scenario:
    """Two people walk up to the Directions Robot and converse with it (an F-formation of 3).

    Args:
        seed: seeds every draw.
        radius: o-space radius of the group of three, metres.
        talk_duration: seconds of conversation once both have arrived.
        approach: where the two come from (the robot faces east, "front").
        {talk}
        {changes}
    """
    scene = _Scene("hri-conversation", seed, visitors=VISITORS if event_rate > 0.0 else 0)
    yaw = scene.robot.yaw
    centre = scene.robot_xy + radius * np.array([math.cos(yaw), math.sin(yaw)])
    gap = 2.0 * math.pi / 3.0 + scene.rng.uniform(-TRIANGLE_JITTER_RAD, TRIANGLE_JITTER_RAD, size=2)
    angles = np.array([math.pi - gap[0], math.pi + gap[1]])  # left of the robot, then right
    guests = scene.guests(
        centre,
        radius,
        angles,
        approach=approach,
        position_noise=position_noise,
        orientation_noise=orientation_noise,
    )
    if event_rate > 0.0:
        end = scene.talk_with_changes(
            guests,
            robot_joins=True,
            radius=radius,
            noise=CircleNoise(position_noise, orientation_noise),
            talk_duration=talk_duration,
            leave=leave,
            mean_utterance=mean_utterance,
            event_rate=event_rate,
            event_kinds=event_kinds,
            approach_speed=approach_speed,
        )
        return scene.made(end, "two people and the robot converse; people join, leave, merge")
    end = scene.talk(
        guests,
        robot_joins=True,
        talk_duration=talk_duration,
        leave=leave,
        mean_utterance=mean_utterance,
    )
    return scene.made(end, "two people and the robot converse: one F-formation of three")


@register("hri-robot-excluded", tags=("hri",), robot={})
@shared_help(talk=_TALK_OPTIONS, changes=CHANGE_OPTIONS)
def hri_robot_excluded(
    *,
    seed: int,
    distance: Annotated[float, Range(1.0, 4.0, unit="m")] = 1.8,
    radius: Annotated[float, Range(0.3, 1.0, unit="m")] = 0.42,
    talk_duration: SceneSeconds = 40.0,
    walk_in: bool = True,
    leave: bool = True,
    position_noise: PlaceNoise = 0.03,
    orientation_noise: _FacingNoise = 0.1,
    mean_utterance: _UtteranceSeconds = MEAN_UTTERANCE_S,
    event_rate: EventRate = 0.0,
    event_kinds: EventKinds = "mixed",
    approach_speed: ApproachSpeed = APPROACH_SPEED_M_S,
) -> Scenario:
    """Two people stand in front of the robot and talk to each other; the robot is left out.

    Args:
        seed: seeds every draw.
        distance: from the robot to the pair's o-space centre, metres.
        radius: half the distance between the two, metres.
        talk_duration: seconds of conversation once both stand at their places.
        walk_in: whether they walk in first (else they stand there from the start).
        {talk}
        {changes}
    """
    scene = _Scene("hri-robot-excluded", seed, visitors=VISITORS if event_rate > 0.0 else 0)
    bearing = scene.rng.uniform(-0.3, 0.3)
    centre = scene.robot_xy + distance * np.array([math.cos(bearing), math.sin(bearing)])
    axis = bearing + math.pi / 2.0 + scene.rng.uniform(-0.5, 0.5)
    guests = scene.guests(
        centre,
        radius,
        np.array([axis, axis + math.pi]),
        approach="random" if walk_in else None,
        position_noise=position_noise,
        orientation_noise=orientation_noise,
    )
    if event_rate > 0.0:
        end = scene.talk_with_changes(
            guests,
            robot_joins=False,
            radius=radius,
            noise=CircleNoise(position_noise, orientation_noise),
            talk_duration=talk_duration,
            leave=leave,
            mean_utterance=mean_utterance,
            event_rate=event_rate,
            event_kinds=event_kinds,
            approach_speed=approach_speed,
        )
        return scene.made(end, "two people converse in front of the robot; others join, leave")
    end = scene.talk(
        guests,
        robot_joins=False,
        talk_duration=talk_duration,
        leave=leave,
        mean_utterance=mean_utterance,
    )
    return scene.made(end, "two people converse in front of the robot: one F-formation of two")


@register("hri-passing", tags=("hri",), robot={})
def hri_passing(
    *,
    seed: int,
    people: Annotated[int, Range(1, 6)] = 2,
    passes: Annotated[int, Range(1, 50)] = 4,
    look_at_robot: Annotated[float, Range(0.0, 1.0)] = 0.3,
) -> Scenario:
    """People walk past each other and the robot, again and again: no F-formation.

    Args:
        seed: seeds every draw.
        people: how many walk.
        passes: how many times each crosses the robot's view.
        look_at_robot: probability that a walker looks at the robot on a pass.
    """
    scene = _Scene("hri-passing", seed, room=PASSING_ROOM_M)
    rng = scene.rng
    ids = list(range(1, people + 1))
    hy = 0.5 * scene.room[1] - 0.5
    lanes_x = (scene.robot.position[0] + 1.0, 0.5 * scene.room[0] - 0.6)
    # Start spread along both side walls, alternating, so that walkers meet head on.
    sides = np.array([1.0 if k % 2 == 0 else -1.0 for k in range(people)])
    starts = np.stack([np.linspace(lanes_x[0] + 0.3, lanes_x[1] - 0.3, people), sides * hy], axis=1)
    scene.cast(ids, starts, -sides * math.pi / 2.0, "walker")
    builder = scene.builder
    scene.robot_stands(0.0)
    finish = 0.0
    for k, person in enumerate(ids):
        here = starts[k]
        side = sides[k]
        t = float(rng.uniform(0.0, 2.0))
        for n in range(passes):
            side = -side
            goal = np.array([rng.uniform(*lanes_x), side * hy])
            speed = float(rng.uniform(*WALK_SPEED_RANGE_M_S))
            draw = rng.random()
            if draw < look_at_robot:
                gaze = {"gaze_agent": ROBOT_ID}
            elif draw < look_at_robot + 0.2 and people > 1:
                other = ids[(k + 1 + int(rng.integers(people - 1))) % people]
                gaze = {"gaze_agent": other}
            else:
                gaze = {}
            builder.set(
                t,
                person,
                Intent(goal=(float(goal[0]), float(goal[1])), speed=speed, **gaze),
            )
            builder.event(t, "pass", f"person {person} crosses (pass {n + 1} of {passes})")
            t += _walk_time(here, goal, speed)
            builder.set(t, person, Intent(face_yaw=float(-side * math.pi / 2.0)))
            here = goal
            t += float(rng.uniform(0.5, 3.0))
        finish = max(finish, t)
    return scene.made(finish, "people walk past each other and the robot: no F-formation")
