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
from scenarios.conversation import MEAN_UTTERANCE_S, converse, standing
from scenarios.formation import CircleNoise, facing_centre
from scenarios.registry import PlaceNoise, Range, SceneSeconds, register, shared_help
from scenarios.scenario import Scenario
from scenarios.script import Intent
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
        self.builder = TimelineBuilder([*people, ROBOT_ID])

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
@shared_help(talk=_TALK_OPTIONS)
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
) -> Scenario:
    """Two people walk up to the Directions Robot and converse with it (an F-formation of 3).

    Args:
        seed: seeds every draw.
        radius: o-space radius of the group of three, metres.
        talk_duration: seconds of conversation once both have arrived.
        approach: where the two come from (the robot faces east, "front").
        {talk}
    """
    scene = _Scene("hri-conversation", seed)
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
    end = scene.talk(
        guests,
        robot_joins=True,
        talk_duration=talk_duration,
        leave=leave,
        mean_utterance=mean_utterance,
    )
    return scene.made(end, "two people and the robot converse: one F-formation of three")


@register("hri-robot-excluded", tags=("hri",), robot={})
@shared_help(talk=_TALK_OPTIONS)
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
) -> Scenario:
    """Two people stand in front of the robot and talk to each other; the robot is left out.

    Args:
        seed: seeds every draw.
        distance: from the robot to the pair's o-space centre, metres.
        radius: half the distance between the two, metres.
        talk_duration: seconds of conversation once both stand at their places.
        walk_in: whether they walk in first (else they stand there from the start).
        {talk}
    """
    scene = _Scene("hri-robot-excluded", seed)
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
