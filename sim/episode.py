"""One episode: a scenario enacted in the MuJoCo world, written down as Frames.

`simulate_episode` is the one function that turns a scenario (a registered name with a seed
and options, or a made `scenarios.Scenario`) into frames:

1. the scenario's `Stage` becomes a `SceneSpec` (`scene_spec`; the spec validates sizes,
   overlaps and room capacity);
2. the `World` samples the scenario's `Timeline` for intents (every ``1 / decision_rate`` s)
   and moves everyone at ``1 / dt`` Hz;
3. poses are read every ``1 / rate`` seconds and the world settles the ground truth by the
   scenario layer's rule (``World(truth=scenario.ground_truth())``, `scenarios.GroundTruth`: a
   group starts when its members have arrived at their places facing the centre, and ends when
   the first leaves), in this one place for every path (blocks, frames, the robot's view);
4. with ``view="robot"`` the robot's head sensor (`sim.sensor.Sensor`) observes each frame
   (field of view, range, occlusion by MuJoCo rays, dropouts, noise) and the observed frame
   keeps the ground truth restricted to the people it holds.

`episode_blocks` is the fast ground-truth path (`reform.FrameBlock` blocks, MuJoCo kinematics
batched per block) and `stream_episode` yields frames one at a time; `simulate_episode`
collects them into a `reform.Dataset` with the scenario's events beside it, and `write_episode`
writes them to a Parquet file as they come, in bounded memory, however long the episode.

Sizes: every entry point sizes its request first (`estimate_episode`, `sim.sizing`) and refuses,
before anything is simulated, what this machine can never hold or finish (more memory than it
has with its swap, a run beyond `sim.sizing.MAX_RUN_SECONDS`); commands check the estimate
against the memory available and the free disk as well.

Seeds: the scenario is drawn from ``seed``; the world's idle sway and the sensor's noise come
from two children of ``numpy.random.SeedSequence(seed)``. The same scenario, seed and options
give identical frames. The frame at ``t`` is the state after ``t`` seconds; the first is at
``1 / rate`` and the last at the largest multiple of ``1 / rate`` not beyond ``duration``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import os
from collections import Counter
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import mujoco
import numpy as np
import pyarrow.compute as pc
import pyarrow.parquet as pq

import scenarios
from reform.atomic import atomic_path
from reform.datasets import write_parquet
from reform.frame import Dataset, Frame
from reform.frame_block import FrameBlock
from reform.seeding import SENSOR, WORLD, derive_seed
from scenarios import Scenario, ScenarioEvent, Stage
from scenarios.script import Intent
from sim import sizing
from sim.scene import FurnitureSpec, PersonSpec, RobotSpec, SceneSpec
from sim.sensor import Sensor
from sim.world import (
    DEFAULT_BLOCK_ROWS,
    DEFAULT_DECISION_RATE_HZ,
    DEFAULT_DT_S,
    World,
)

__all__ = [
    "DEFAULT_RATE_HZ",
    "SCHEDULE_BYTES",
    "STREAM_CHUNK_BYTES",
    "VIEWS",
    "Episode",
    "ScenarioScript",
    "WrittenEpisode",
    "episode_blocks",
    "estimate_episode",
    "prepare",
    "scene_spec",
    "simulate_episode",
    "stream_episode",
    "write_episode",
]

DEFAULT_RATE_HZ = 2.0  # Hz, frames per second written (SALSA-like annotation rate)
VIEWS = ("truth", "robot")
STREAM_CHUNK_BYTES = 64 * 2**20  # bytes of frames write_episode holds before it writes them
SCHEDULE_BYTES = 64 * 2**20  # bytes: the world's step schedule of one block of frames at most
# (stream_episode and write_episode take fewer frames per block when a frame spans many steps)
_FRAME_SLACK = 1e-9  # periods: a duration this close to a whole number of frames counts as it
_MAX_STEPS_PER_FRAME = 2.0**62  # steps: more are sized as this many (an int64 still holds it)
# What makes an episode smaller, as sizing's messages name it.
_SHRINK = "a shorter {duration}, a lower {rate} or a larger {dt}"

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
            body_radius=p.radius,
        )
        for p in stage.people
    ]
    robot = None
    if stage.robot is not None:
        robot = RobotSpec(id=stage.robot.id, position=stage.robot.position, yaw=stage.robot.yaw)
    furniture = [
        FurnitureSpec(kind=f.kind, position=f.position, size=f.size, yaw=f.yaw)
        for f in stage.furniture
    ]
    return SceneSpec(people=people, robot=robot, room=stage.room, name=name, furniture=furniture)


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

    @property
    def agents(self) -> int:
        """People and robot of the scene."""
        stage = self.scenario.stage
        return len(stage.people) + (stage.robot is not None)

    @property
    def steps_per_frame(self) -> int:
        """Control steps of ``dt`` between two frames (the world checks it is whole)."""
        steps = 1.0 / (self.rate * self.dt)  # inf for a dt near the smallest float
        return max(1, round(min(steps, _MAX_STEPS_PER_FRAME)))

    @property
    def block_rows(self) -> int:
        """Frames per block of the world's rollout: `DEFAULT_BLOCK_ROWS`, fewer when their step
        schedule would take more than `SCHEDULE_BYTES`."""
        per_row = self.steps_per_frame * sizing.SCHEDULE_BYTES_PER_STEP
        return max(1, min(DEFAULT_BLOCK_ROWS, SCHEDULE_BYTES // per_row))

    def describe(self) -> str:
        """``mingle for 600 s at 2 Hz (dt 0.01 s)``, for messages."""
        return (
            f"{self.scenario.name} for {self.count / self.rate:g} s at {self.rate:g} Hz "
            f"(dt {self.dt:g} s)"
        )


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
    if isinstance(dt, bool) or not isinstance(dt, (int, float)):
        raise ValueError(f"dt must be a number of seconds, got {dt!r}")
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be a positive number of seconds, got {dt}")
    world_seed, sensor_seed = derive_seed(made.seed, WORLD), derive_seed(made.seed, SENSOR)
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


def _estimate(
    plan: _Plan,
    *,
    view: str,
    streamed: bool,
    recording: bool,
    block_rows: int | None = None,
    recording_model: bool = False,
) -> sizing.Estimate:
    """The plan's `sizing.Estimate`: every frame held unless ``streamed`` (then a chunk of
    `STREAM_CHUNK_BYTES`); the robot's view schedules one frame's steps at a time."""
    chunk = max(1, STREAM_CHUNK_BYTES // sizing.frame_bytes(plan.agents, view=view))
    if view == "robot":
        rows = 1
    else:
        rows = plan.block_rows if block_rows is None else block_rows
    return sizing.episode_estimate(
        agents=plan.agents,
        frames=plan.count,
        steps_per_frame=plan.steps_per_frame,
        schedule_rows=rows,
        view=view,
        held_frames=chunk if streamed else plan.count,
        recording=recording,
        recording_model=recording_model,
    )


def _guard(plan: _Plan, estimate: sizing.Estimate) -> None:
    """Refuses, before anything is simulated, what this machine can never hold or finish."""
    sizing.check_possible(estimate, what=plan.describe(), shrink=_SHRINK)


def estimate_episode(
    scenario: str | Scenario,
    *,
    seed: int | None = None,
    duration: float | None = None,
    rate: float = DEFAULT_RATE_HZ,
    view: View = "truth",
    dt: float = DEFAULT_DT_S,
    decision_rate: float = DEFAULT_DECISION_RATE_HZ,
    options: Mapping[str, Any] | None = None,
    streamed: bool = False,
    recording: bool = False,
    recording_model: bool = False,
) -> sizing.Estimate:
    """What an episode will take (memory, disk, time), from its arguments alone.

    Arguments as for `simulate_episode`; ``streamed``: written by `write_episode` (a chunk of
    frames held at a time) rather than returned whole; ``recording``: also recorded for Rerun
    (``recording_model``: the people's bodies drawn from the scene's model).
    Nothing is simulated; the scenario is made (pass a made one to make it once).

    Raises:
        ValueError: the arguments `simulate_episode` refuses (no refusal for size: see
            `sim.sizing.check`).
    """
    if view not in VIEWS:
        raise ValueError(f"view must be one of {VIEWS}, got {view!r}")
    plan = _plan(
        scenario,
        seed=seed,
        duration=duration,
        rate=rate,
        dt=dt,
        decision_rate=decision_rate,
        options=options,
        sequence=None,
    )
    return _estimate(
        plan, view=view, streamed=streamed, recording=recording, recording_model=recording_model
    )


def _world(plan: _Plan) -> World:
    return World(
        scene_spec(plan.scenario.stage, name=plan.scenario.name),
        seed=plan.world_seed,
        script=ScenarioScript(plan.scenario),
        dt=plan.dt,
        decision_rate=plan.decision_rate,
        sequence=plan.sequence,
        truth=plan.scenario.ground_truth(),
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
) -> Iterator[FrameBlock]:
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
    if isinstance(block_rows, bool) or not isinstance(block_rows, (int, np.integer)):
        raise ValueError(f"block_rows must be a positive int, got {block_rows!r}")
    _guard(
        plan, _estimate(plan, view="truth", streamed=True, recording=False, block_rows=block_rows)
    )
    world = _world(plan)
    return _blocks(plan, world, block_rows=block_rows, threads=threads)


def _blocks(plan: _Plan, world: World, *, block_rows: int, threads: int) -> Iterator[FrameBlock]:
    return world.rollout(
        plan.count / plan.rate, rate=plan.rate, block_rows=block_rows, threads=threads
    )


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
        streamed=True,
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
    streamed: bool,
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
                f'view="robot" needs a robot, and {scenarios.without_robot(plan.scenario.name)}'
            )
        sensor = Sensor() if sensor is None else sensor
    _guard(plan, _estimate(plan, view=view, streamed=streamed, recording=False))
    return plan, _world(plan), sensor


def _stream(
    plan: _Plan, world: World, view: str, sensor: Sensor | None
) -> Iterator[tuple[Frame, Frame]]:
    if view == "truth":
        for block in _blocks(plan, world, block_rows=plan.block_rows, threads=1):
            for frame in block.frames():
                yield frame, frame
        return
    assert sensor is not None
    rng = np.random.default_rng(plan.sensor_seed)
    for frame in world.run(plan.count / plan.rate, rate=plan.rate):
        yield frame, sensor.observe(world, rng)


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
        streamed=False,
    )
    truth: list[Frame] = []
    seen: list[Frame] = []
    for world_frame, observed in _stream(plan, world, view, sensor):
        truth.append(world_frame)
        seen.append(observed)
    dataset = Dataset(
        frames=tuple(seen),
        name=plan.scenario.name,
        source=_source(plan),
        metadata=_metadata(plan, view, sensor),
    )
    return Episode(
        dataset=dataset,
        truth=tuple(truth),
        events=_events(plan),
        scenario=plan.scenario,
        model=world.model,
    )


def _source(plan: _Plan) -> str:
    return f"reform-sim simulate --scenario {plan.scenario.name} --seed {plan.scenario.seed}"


def _events(plan: _Plan) -> tuple[ScenarioEvent, ...]:
    """The scenario's events within the episode."""
    end = plan.count / plan.rate
    return tuple(e for e in plan.scenario.events if e.time <= end + 1e-9)


@dataclass(frozen=True, eq=False)
class WrittenEpisode:
    """An episode that `write_episode` wrote.

    Attributes:
        path: the Parquet file.
        frames: frames written.
        group_sizes: F-formation size (2 or more) -> how many times one was in a frame, over the
            frames written (the groups restricted to the people in each frame).
        events: the scenario's events within the episode, by time.
        scenario: the scenario enacted.
        metadata: the file's metadata (the episode's parameters), as `simulate_episode`'s
            dataset has it.
    """

    path: Path
    frames: int
    group_sizes: Mapping[int, int]
    events: tuple[ScenarioEvent, ...]
    scenario: Scenario
    metadata: Mapping[str, Any]


def write_episode(
    scenario: str | Scenario,
    path: str | os.PathLike[str],
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
    progress: Callable[[int], object] | None = None,
) -> WrittenEpisode:
    """Runs one episode and writes its frames to a Parquet file as they come.

    The file reads back (`reform.datasets.read_parquet`) as the dataset `simulate_episode`
    returns for the same arguments, but at most `STREAM_CHUNK_BYTES` of frames are held at a
    time: each chunk is written as one row group, so an episode of any length runs in bounded
    memory (as the world's rollout does, `sim.world.World.rollout`). The file appears whole or
    not at all (`reform.atomic.atomic_path`).

    Args:
        scenario, seed, duration, rate, view, sensor, dt, decision_rate, options, sequence: as
            for `simulate_episode`.
        path: the ``.parquet`` file to write (its folder is created).
        progress: called with the number of frames made, after each frame (a progress bar's
            ``update``).

    Returns:
        The `WrittenEpisode`: path, frame count, F-formation sizes, events.

    Raises:
        ValueError: what `simulate_episode` refuses, before anything is simulated.
    """

    path = Path(path)
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
        streamed=True,
    )
    metadata = _metadata(plan, view, sensor)
    chunk_frames = max(1, STREAM_CHUNK_BYTES // sizing.frame_bytes(plan.agents, view=view))
    sizes: Counter[int] = Counter()
    written = 0
    with contextlib.ExitStack() as stack:
        target = stack.enter_context(atomic_path(path))
        scratch = target.with_name(target.name + ".chunk.parquet")
        stack.callback(scratch.unlink, missing_ok=True)
        writer = None
        chunk: list[Frame] = []
        frames = (observed for _, observed in _stream(plan, world, view, sensor))
        for frame in frames:
            chunk.append(frame)
            sizes.update(len(g) for g in frame.groups or () if len(g) >= 2)
            if progress is not None:
                progress(1)
            if len(chunk) < chunk_frames and written + len(chunk) < plan.count:
                continue
            # The chunk as the whole-file writer writes it, its frames numbered from `written`.
            write_parquet(
                Dataset(
                    frames=tuple(chunk),
                    name=plan.scenario.name,
                    source=_source(plan),
                    metadata=metadata,
                ),
                scratch,
            )
            table = pq.read_table(scratch)
            index = table.schema.get_field_index("frame")
            table = table.set_column(
                index, table.schema.field(index), pc.add(table.column(index), written)
            )
            if writer is None:
                writer = stack.enter_context(
                    pq.ParquetWriter(
                        target, table.schema, compression="zstd", write_page_checksum=True
                    )
                )
            writer.write_table(table)
            written += len(chunk)
            chunk = []
    return WrittenEpisode(
        path=path,
        frames=written,
        group_sizes=dict(sorted(sizes.items())),
        events=_events(plan),
        scenario=plan.scenario,
        metadata=metadata,
    )
