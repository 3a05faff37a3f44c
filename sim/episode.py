"""One episode: a scenario enacted in the MuJoCo world, written down as Frames.

`simulate_episode` is the one function that turns a scenario (a registered name with a seed
and options, or a made `scenarios.Scenario`) into frames:

1. the scenario's `Stage` becomes a `SceneSpec` (`scene_spec`; the spec validates sizes,
   overlaps and room capacity);
2. the `World` samples the scenario's `Timeline` for intents (every ``1 / decision_rate`` s)
   and moves everyone at ``1 / dt`` Hz;
3. poses are read every ``1 / rate`` seconds and the ground truth is settled by the scenario
   layer's rule (`scenarios.GroundTruth`: a group starts when its members have arrived at their
   places facing the centre, and ends when the first leaves);
4. with ``view="robot"`` the robot's head sensor (`sim.sensor.Sensor`) observes each frame
   (field of view, range, occlusion by MuJoCo rays, dropouts, noise) and the observed frame
   keeps the ground truth restricted to the people it holds.

`episode_blocks` is the fast ground-truth path (blocks of `Poses`, MuJoCo kinematics batched per
block) and `stream_episode` yields frames one at a time; `simulate_episode` collects them into a
`reform.Dataset` with the scenario's events beside it.

Seeds: the scenario is drawn from ``seed``; the world's idle sway and the sensor's noise come
from two children of ``numpy.random.SeedSequence(seed)``. The same scenario, seed and options
give identical frames. The frame at ``t`` is the state after ``t`` seconds; the first is at
``1 / rate`` and the last at the largest multiple of ``1 / rate`` not beyond ``duration``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Literal

import mujoco
import numpy as np

import scenarios
from reform.frame import Dataset, Frame
from scenarios import Scenario, ScenarioEvent, Stage
from scenarios.script import Intent
from sim.scene import PersonSpec, RobotSpec, SceneSpec
from sim.sensor import Sensor
from sim.world import (
    DEFAULT_BLOCK_ROWS,
    DEFAULT_DECISION_RATE_HZ,
    DEFAULT_DT_S,
    Poses,
    World,
    restrict_groups,
)

__all__ = [
    "DEFAULT_RATE_HZ",
    "VIEWS",
    "Episode",
    "ScenarioScript",
    "episode_blocks",
    "prepare",
    "scene_spec",
    "simulate_episode",
    "stream_episode",
]

DEFAULT_RATE_HZ = 2.0  # Hz, frames per second written (SALSA-like annotation rate)
VIEWS = ("truth", "robot")
_FRAME_SLACK = 1e-9  # periods: a duration this close to a whole number of frames counts as it

View = Literal["truth", "robot"]


def scene_spec(stage: Stage, *, name: str = "scene") -> SceneSpec:
    """The MuJoCo scene description of a scenario's stage (validated by `SceneSpec`)."""
    people = [
        PersonSpec(
            id=p.id,
            position=p.position,
            yaw=p.yaw,
            height=p.height,
            width=p.width,
            present=p.present,
        )
        for p in stage.people
    ]
    robot = None
    if stage.robot is not None:
        robot = RobotSpec(id=stage.robot.id, position=stage.robot.position, yaw=stage.robot.yaw)
    return SceneSpec(people=people, robot=robot, room=stage.room, name=name)


def prepare(
    scenario: str | Scenario,
    *,
    seed: int | None = None,
    options: Mapping[str, Any] | None = None,
) -> Scenario:
    """The made scenario: ``make(scenario, seed=seed, **options)`` for a name, else itself.

    Raises:
        ValueError: a name without a seed, a made scenario with options or another seed, or
            anything `scenarios.make` refuses.
    """
    if isinstance(scenario, Scenario):
        if options:
            raise ValueError(
                "options apply to a scenario name; a made Scenario already has its options, "
                f"got {sorted(options)}"
            )
        if seed is not None and seed != scenario.seed:
            raise ValueError(
                f"seed {seed!r} differs from the made scenario's seed {scenario.seed}; make it "
                "again with that seed"
            )
        return scenario
    if not isinstance(scenario, str):
        raise ValueError(
            f"scenario must be a registered name or a Scenario, got {type(scenario).__name__}"
        )
    if seed is None:
        raise ValueError(f"seed is required to make scenario {scenario!r}")
    return scenarios.make(scenario, seed=seed, **dict(options or {}))


def _frame_count(duration: float, rate: float) -> int:
    for name, value in (("duration", duration), ("rate", rate)):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{name} must be a number, got {value!r}")
    if not (math.isfinite(rate) and rate > 0.0):
        raise ValueError(f"rate must be a positive number of frames per second, got {rate}")
    if not (math.isfinite(duration) and duration > 0.0):
        raise ValueError(f"duration must be a positive number of seconds, got {duration}")
    count = math.floor(duration * rate + _FRAME_SLACK)
    if count < 1:
        raise ValueError(
            f"duration {duration:g} s holds no frame at {rate:g} Hz: it must be >= {1 / rate:g} s"
        )
    return count


class ScenarioScript:
    """A scenario's intents as the world's `scenarios.script.Script`; it declares no groups, as
    the ground truth is settled from the poses (`scenarios.truth`)."""

    def __init__(self, scenario: Scenario) -> None:
        self._timeline = scenario.timeline

    def intents(self, t: float) -> Mapping[int, Intent]:
        return self._timeline.intents(t)

    def groups(self, t: float) -> None:
        return None


@dataclass(frozen=True)
class _Plan:
    scenario: Scenario
    count: int
    rate: float
    dt: float
    decision_rate: float
    sequence: str
    world_seed: np.random.SeedSequence
    sensor_seed: np.random.SeedSequence


def _plan(
    scenario: str | Scenario,
    *,
    seed: int | None,
    duration: float | None,
    rate: float,
    dt: float,
    decision_rate: float,
    options: Mapping[str, Any] | None,
    sequence: str | None,
) -> _Plan:
    made = prepare(scenario, seed=seed, options=options)
    count = _frame_count(made.duration if duration is None else duration, rate)
    world_seed, sensor_seed = np.random.SeedSequence(made.seed).spawn(2)
    return _Plan(
        scenario=made,
        count=count,
        rate=float(rate),
        dt=float(dt),
        decision_rate=float(decision_rate),
        sequence=f"{made.name}-{made.seed}" if sequence is None else str(sequence),
        world_seed=world_seed,
        sensor_seed=sensor_seed,
    )


def _world(plan: _Plan) -> World:
    return World(
        scene_spec(plan.scenario.stage, name=plan.scenario.name),
        seed=plan.world_seed,
        script=ScenarioScript(plan.scenario),
        dt=plan.dt,
        decision_rate=plan.decision_rate,
        sequence=plan.sequence,
    )


def episode_blocks(
    scenario: str | Scenario,
    *,
    seed: int | None = None,
    duration: float | None = None,
    rate: float = DEFAULT_RATE_HZ,
    dt: float = DEFAULT_DT_S,
    decision_rate: float = DEFAULT_DECISION_RATE_HZ,
    options: Mapping[str, Any] | None = None,
    sequence: str | None = None,
    block_rows: int = DEFAULT_BLOCK_ROWS,
    threads: int = 1,
) -> Iterator[Poses]:
    """Ground-truth poses of an episode in blocks, with the settled groups (the fast path).

    Arguments as for `simulate_episode`; ``block_rows`` frames per block, MuJoCo kinematics
    on ``threads`` threads. Everything is validated before the first block is computed.
    """
    plan = _plan(
        scenario,
        seed=seed,
        duration=duration,
        rate=rate,
        dt=dt,
        decision_rate=decision_rate,
        options=options,
        sequence=sequence,
    )
    world = _world(plan)
    return _blocks(plan, world, block_rows=block_rows, threads=threads)


def _blocks(plan: _Plan, world: World, *, block_rows: int, threads: int) -> Iterator[Poses]:
    truth = plan.scenario.ground_truth(world.ids.tolist())
    for block in world.rollout(
        plan.count / plan.rate, rate=plan.rate, block_rows=block_rows, threads=threads
    ):
        groups = truth.update(block.time, block.present, block.position, block.yaw)
        yield dataclasses.replace(block, groups=groups)


def stream_episode(
    scenario: str | Scenario,
    *,
    seed: int | None = None,
    duration: float | None = None,
    rate: float = DEFAULT_RATE_HZ,
    view: View = "truth",
    sensor: Sensor | None = None,
    dt: float = DEFAULT_DT_S,
    decision_rate: float = DEFAULT_DECISION_RATE_HZ,
    options: Mapping[str, Any] | None = None,
    sequence: str | None = None,
) -> Iterator[tuple[Frame, Frame]]:
    """The episode's frames one at a time, as ``(ground truth, view)`` pairs.

    With ``view="truth"`` both are the same frame. Arguments as for `simulate_episode`;
    everything is validated before the first frame is computed.
    """
    plan, world, sensor = _setup(
        scenario,
        seed=seed,
        duration=duration,
        rate=rate,
        view=view,
        sensor=sensor,
        dt=dt,
        decision_rate=decision_rate,
        options=options,
        sequence=sequence,
    )
    return _stream(plan, world, view, sensor)


def _setup(
    scenario: str | Scenario,
    *,
    seed: int | None,
    duration: float | None,
    rate: float,
    view: str,
    sensor: Sensor | None,
    dt: float,
    decision_rate: float,
    options: Mapping[str, Any] | None,
    sequence: str | None,
) -> tuple[_Plan, World, Sensor | None]:
    if view not in VIEWS:
        raise ValueError(f"view must be one of {VIEWS}, got {view!r}")
    if sensor is not None and not isinstance(sensor, Sensor):
        raise ValueError(f"sensor must be a sim.sensor.Sensor, got {type(sensor).__name__}")
    if view == "truth" and sensor is not None:
        raise ValueError('sensor applies to view="robot" only')
    plan = _plan(
        scenario,
        seed=seed,
        duration=duration,
        rate=rate,
        dt=dt,
        decision_rate=decision_rate,
        options=options,
        sequence=sequence,
    )
    if view == "robot":
        if plan.scenario.stage.robot is None:
            raise ValueError(
                f'view="robot" needs a robot, and this {plan.scenario.name} has none '
                "(see its robot option)"
            )
        sensor = Sensor() if sensor is None else sensor
    return plan, _world(plan), sensor


def _stream(
    plan: _Plan, world: World, view: str, sensor: Sensor | None
) -> Iterator[tuple[Frame, Frame]]:
    if view == "truth":
        for block in _blocks(plan, world, block_rows=DEFAULT_BLOCK_ROWS, threads=1):
            for frame in block.frames():
                yield frame, frame
        return
    assert sensor is not None
    rng = np.random.default_rng(plan.sensor_seed)
    truth = plan.scenario.ground_truth(world.ids.tolist())
    n = world.ids.size
    for frame in world.run(plan.count / plan.rate, rate=plan.rate):
        rows = np.array([world.agent_index(int(i)) for i in frame.ids], dtype=np.int64)
        present = np.zeros((1, n), dtype=bool)
        present[0, rows] = True
        position = np.zeros((1, n, 2))
        position[0, rows] = frame.position
        yaw = np.zeros((1, n))
        yaw[0, rows] = frame.yaw
        (groups,) = truth.update(np.array([frame.time]), present, position, yaw)
        world_frame = frame.replace(groups=restrict_groups(groups, set(frame.ids.tolist())))
        observed = sensor.observe(world, rng)
        seen = set(observed.ids.tolist())
        observed = observed.replace(groups=restrict_groups(world_frame.groups, seen))
        yield world_frame, observed


@dataclass(frozen=True, eq=False)
class Episode:
    """A simulated episode.

    Attributes:
        dataset: the frames of the requested view, with the episode's parameters as metadata.
        truth: the ground-truth frames (the dataset's own frames with ``view="truth"``).
        events: the scenario's events within the episode, by time.
        scenario: the scenario enacted.
        model: the compiled MuJoCo model of the scene (for drawing it).
    """

    dataset: Dataset
    truth: tuple[Frame, ...]
    events: tuple[ScenarioEvent, ...]
    scenario: Scenario
    model: mujoco.MjModel


def _metadata(plan: _Plan, view: str, sensor: Sensor | None) -> dict[str, Any]:
    made = plan.scenario
    meta: dict[str, Any] = {
        "generator": "sim.episode.simulate_episode",
        "scenario": made.name,
        "seed": made.seed,
        "options": dict(made.options),
        "duration_s": plan.count / plan.rate,
        "rate_hz": plan.rate,
        "view": view,
        "dt_s": plan.dt,
        "decision_rate_hz": plan.decision_rate,
        "room_m": list(made.stage.room),
    }
    if sensor is not None:
        meta["sensor"] = dataclasses.asdict(sensor)
    return meta


def simulate_episode(
    scenario: str | Scenario,
    *,
    seed: int | None = None,
    duration: float | None = None,
    rate: float = DEFAULT_RATE_HZ,
    view: View = "truth",
    sensor: Sensor | None = None,
    dt: float = DEFAULT_DT_S,
    decision_rate: float = DEFAULT_DECISION_RATE_HZ,
    options: Mapping[str, Any] | None = None,
    sequence: str | None = None,
) -> Episode:
    """Runs one episode of a scenario and returns its frames and events.

    Args:
        scenario: a registered name (made with ``seed`` and ``options``) or a made `Scenario`.
        seed: the episode's seed (required with a name; a made scenario's own by default).
        duration: seconds to simulate; default the scenario's natural length.
        rate: frames per second written.
        view: ``"truth"`` (every agent's true pose) or ``"robot"`` (what the robot's head
            sensor sees; needs a robot).
        sensor: the robot's sensor model (``view="robot"``); default `Sensor()` (Kinect-like).
        dt: control step, seconds (up to 0.1; coarser is faster, motion a little rougher).
        decision_rate: how often the script is sampled, Hz (``1 / decision_rate`` a whole
            number of ``dt``).
        options: scenario options (with a name).
        sequence: the frames' sequence name; default ``"<scenario>-<seed>"``.

    Returns:
        The `Episode`: dataset, ground-truth frames, events, scenario and MuJoCo model.

    Raises:
        ValueError: unknown scenario or option, impossible options, a non-positive duration or
            rate, an unknown view, a robot view without a robot: before anything is simulated.
    """
    plan, world, sensor = _setup(
        scenario,
        seed=seed,
        duration=duration,
        rate=rate,
        view=view,
        sensor=sensor,
        dt=dt,
        decision_rate=decision_rate,
        options=options,
        sequence=sequence,
    )
    truth: list[Frame] = []
    seen: list[Frame] = []
    for world_frame, observed in _stream(plan, world, view, sensor):
        truth.append(world_frame)
        seen.append(observed)
    made = plan.scenario
    end = plan.count / plan.rate
    dataset = Dataset(
        frames=tuple(seen),
        name=made.name,
        source=f"reform-sim simulate --scenario {made.name} --seed {made.seed}",
        metadata=_metadata(plan, view, sensor),
    )
    return Episode(
        dataset=dataset,
        truth=tuple(truth),
        events=tuple(e for e in made.events if e.time <= end + 1e-9),
        scenario=made,
        model=world.model,
    )
