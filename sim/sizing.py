"""What a run will cost, from its arguments alone, and whether this machine can hold it.

A long command (``reform-sim simulate``, ``reform-sim generate``) sizes its request before any
work starts: `episode_estimate` and `dataset_estimate` turn the run's shape (agents, frames,
control steps per frame, view, recording, episodes, workers) into an `Estimate` of its peak
memory, the bytes it writes and its wall-clock time, and `check` compares them with this
machine (`available_memory`, `free_disk`) and raises `RequestTooLarge`, one line naming the
estimate, the limit and how to change it.

The costs below were measured once, on a 2-CPU Linux x86_64 machine with 24 GB of memory, by
``python -m sim.sizing`` (:func:`measure`): fresh processes run the scenario ``mingle``
(4 and 40 people, then 18 with the robot in its view) for 600 s and 3,000 s at 2 Hz, with
``dt`` 0.01 s and 0.002 s, their peak resident memory read from the kernel (``wait4``) and the
costs per frame, per agent and per step fitted to the differences. Rerun it to re-measure on
another machine. They are estimates: within a factor of two of what a run takes, which is all a
refusal needs, as what is refused is larger by orders of magnitude.

This module imports only the standard library, so a command can size its request before it
loads MuJoCo.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NoReturn

from reform.machine import available_memory, format_size, total_memory

__all__ = [
    "MAX_RUN_SECONDS",
    "Estimate",
    "busy",
    "RequestTooLarge",
    "available_memory",
    "check",
    "check_episodes",
    "check_possible",
    "dataset_estimate",
    "episode_estimate",
    "flag_name",
    "format_duration",
    "format_size",
    "frame_bytes",
    "free_disk",
    "gcff_tuning_estimate",
    "stress_estimate",
    "describe",
    "measure",
    "parse_size",
    "pool_start",
    "python_name",
    "recording_disk",
    "total_memory",
]

# Measured costs (python -m sim.sizing; see the module docstring).
BASE_MEMORY_BYTES = 245_000_000  # bytes: a simulate process before its frames (Python, numpy,
# MuJoCo, the compiled motion kernel, the scene)
FRAME_BYTES = 3_600  # bytes of memory per Frame held, beside its agents (the object, its arrays'
# headers, its groups; with its share of the Parquet columns written at the end)
AGENT_FRAME_BYTES = 400  # bytes of memory per agent of a Frame held (poses, id, kind, its row
# of the Parquet columns written at the end)
FAST_AGENT_FRAME_BYTES = 600  # bytes of memory per agent-frame of an episode that generate
# writes from pose arrays (blocks, concatenated arrays, columns, the Arrow table)
RECORDING_AGENT_FRAME_BYTES = 1_100  # bytes of memory per agent-frame while a finished episode
# is recorded for Rerun (its columns and the logged chunks)
DISK_AGENT_FRAME_BYTES = 58  # bytes of Parquet (zstd) per agent of a frame written
DISK_EPISODE_BYTES = 9_800  # bytes of Parquet per file beside its rows (footer, metadata)
# A .rrd as `simulate --save` and `generate --save-recordings` write it (measured by writing
# them: mingle with 4, 18 and 40 people, 20 s and 80 s at 2 Hz, truth and robot views; fitted by
# hand to the sizes, which the fit meets within 15 %). A short recording is mostly its fixed
# part: the figure of long ones alone (73 bytes an agent-frame) underestimated them about 4x.
RECORDING_DISK_BYTES = 110_000  # bytes of .rrd per recording beside its frames (blueprint,
# layout, static scene, the recording's properties)
RECORDING_DISK_AGENT_BYTES = 530  # bytes of .rrd per agent beside its frames (its entities)
RECORDING_DISK_MODEL_AGENT_BYTES = 38_000  # bytes of .rrd per agent whose body is drawn from
# the scene's model (static meshes: what `generate --save-recordings` records)
RECORDING_DISK_FRAME_BYTES = 280  # bytes of .rrd per frame beside its agents (times, scores)
RECORDING_DISK_AGENT_FRAME_BYTES = 89  # bytes of .rrd per agent-frame recorded
RECORDING_DISK_OBSERVED_AGENT_FRAME_BYTES = 15  # bytes of .rrd per agent-frame the robot
# observes (the observed stream beside the truth)
CARD_EPISODE_BYTES = 4_800  # bytes of memory per episode a generated dataset's card lists
CARD_DISK_EPISODE_BYTES = 600  # bytes per episode of the card written (JSON and Markdown)
SECONDS_PER_AGENT_STEP = 3.5e-7  # seconds per agent per control step (motion, kinematics)
SECONDS_PER_AGENT_FRAME = 6.5e-6  # seconds per agent per output frame (Frame, truth, Parquet)
SECONDS_PER_OBSERVED_AGENT_FRAME = 1.8e-5  # seconds per agent per frame the robot observes
# (field of view, occlusion rays, noise), beside the above
SECONDS_PER_RECORDED_AGENT_FRAME = 1.0e-6  # seconds per agent-frame recorded for Rerun
SECONDS_PER_EPISODE = 0.076  # seconds per generated episode beside its frames (scenario,
# scene, World, shard)
WORKER_START_SECONDS = 3.0  # seconds for a pool of worker processes to start: each imports
# NumPy, MuJoCo and the package before its first unit (`reform-sim generate --jobs 2` took 2 to
# 5 s to its first episode on two shared cores, against 0.2 s of episodes estimated)
BUSY_SAID = 1.25  # a machine this many times slower than idle is said to be busy in an estimate
SCHEDULE_BYTES_PER_STEP = 8  # bytes: the world's step schedule, one int64 per control step of a
# block of output rows (sim.world.World.rollout, World.step)

# Studies (measured on the same machine, loaded by other work, so on the slow side):
# `reform-sim stress --grid small --jobs 1` scored 12,348 agent-frames in 7.4 s of wall clock
# (REFORM three ways, GCFF and the majority baseline, with bootstrap intervals), and GCFF
# segmented SALSA's first 300 annotated frames (18 people) in 0.62 s.
SECONDS_PER_SCORED_AGENT_FRAME = 6.0e-4  # seconds per agent of a test frame the stress test
# scores (every detector, the bootstrap)
STRESS_RESULT_BYTES = 2_500  # bytes of stress.json per scored test episode (its per-frame counts)
STRESS_REPORT_BYTES = 1_000_000  # bytes of the stress report beside its episodes (plots, text)
SECONDS_PER_GCFF_FRAME = 2.1e-3  # seconds GCFF takes to segment one frame of 18 people
GCFF_SETTING_BYTES = 1_000  # bytes of memory per (stride, mdl) setting a grid search holds (the
# pair, its scores)
DEFAULT_DT_S = 0.01  # seconds: the simulator's control step, for studies that do not set it

# Limits.
MAX_RUN_SECONDS = 7 * 24 * 3600.0  # seconds: a run estimated to take longer here is refused as
# a mistake (a generated dataset grows across runs: a larger --episodes extends it)
VIEWS = ("truth", "robot")

# ASCII digits only: ``\d`` would take other scripts' digits ('٣') for 3.
_SIZE = re.compile(r"\s*([0-9]+(?:\.[0-9]*)?|\.[0-9]+)\s*([kmgtpe]?)(i?b?)\s*", re.IGNORECASE)
MAX_SIZE = 8 * 1024**6  # bytes (8E, 8 EiB): the largest size parse_size gives


# --------------------------------------------------------------------------------------------
# Sizes in words


def parse_size(text: str) -> int:
    """Bytes from a size such as ``"8G"``, ``"512M"``, ``"1.5GiB"`` or ``"1000000"``.

    The suffixes K, M, G, T, P, E are powers of 1024 (``"8G"`` is 8 GiB), with or without a
    trailing ``B`` or ``iB``; a bare number is bytes.

    Raises:
        ValueError: anything else (digits of other scripts too), a size of 0, or one past
            `MAX_SIZE`.
    """
    text = str(text)
    shown = repr(text) if len(text) <= 40 else f"{text[:20]!r}… ({len(text):,} characters)"
    match = _SIZE.fullmatch(text)
    if match is None or (match.group(3) and not match.group(2) and match.group(3).lower() != "b"):
        raise ValueError(f"expected a size such as 8G, 512M or 1.5GiB, got {shown}")
    power = " KMGTPE".index(match.group(2).upper() or " ")
    size = float(match.group(1)) * 1024**power  # inf past a float's range
    if not size <= MAX_SIZE:
        raise ValueError(f"expected a size of at most 8E (8 EiB), got {shown}")
    if size < 1:
        raise ValueError(f"expected a size of at least 1 byte, got {shown}")
    return int(size)


def format_duration(seconds: float) -> str:
    """``41 s``, ``12 min``, ``3.2 h``, ``41 days``, ``2.1e+06 years``."""
    seconds = float(seconds)
    for unit, length in (("years", 365.25 * 86400), ("days", 86400.0), ("h", 3600.0)):
        if seconds >= 2 * length:
            return f"{seconds / length:.3g} {unit}"
    if seconds >= 120.0:
        return f"{seconds / 60.0:.0f} min"
    return f"{seconds:.2g} s" if seconds < 10 else f"{seconds:.0f} s"


# --------------------------------------------------------------------------------------------
# This machine


def free_disk(path: str | os.PathLike[str]) -> int:
    """Free bytes, for this user, on the file system ``path`` is (or would be) written on: that
    of its nearest existing folder."""
    folder = Path(os.path.abspath(path))
    while not folder.is_dir() and folder != folder.parent:
        folder = folder.parent
    return shutil.disk_usage(folder).free


# --------------------------------------------------------------------------------------------
# Estimates


@dataclass(frozen=True)
class Estimate:
    """What a run is expected to take.

    Attributes:
        memory: bytes of memory at the run's peak (the process, or all its workers); a float,
            as absurd requests overflow any integer type numpy or the disk knows.
        memory_cause: what most of that memory holds, for messages.
        disk: bytes the run writes.
        seconds: wall-clock seconds on this machine.
        frames: output frames (over every episode).
        agents: people and robot of (the first) episode.
    """

    memory: float
    memory_cause: str
    disk: float
    seconds: float
    frames: int
    agents: int


def frame_bytes(agents: int, *, view: str = "truth") -> int:
    """Bytes of memory one output frame of ``agents`` takes while held (two Frames, the truth and
    the observed one, in the robot's view)."""
    return (2 if view == "robot" else 1) * (FRAME_BYTES + agents * AGENT_FRAME_BYTES)


def _check_shape(agents: int, frames: int, steps_per_frame: int, view: str) -> None:
    for name, value in (
        ("agents", agents),
        ("frames", frames),
        ("steps_per_frame", steps_per_frame),
    ):
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise ValueError(f"{name} must be an int >= 0, got {value!r}")
    if view not in VIEWS:
        raise ValueError(f"view must be one of {VIEWS}, got {view!r}")


def _episode_seconds(
    agents: int, frames: int, steps_per_frame: int, view: str, recording: bool
) -> float:
    per_frame = SECONDS_PER_AGENT_FRAME
    if view == "robot":
        per_frame += SECONDS_PER_OBSERVED_AGENT_FRAME
    if recording:
        per_frame += SECONDS_PER_RECORDED_AGENT_FRAME
    steps = float(frames) * steps_per_frame
    return steps * agents * SECONDS_PER_AGENT_STEP + float(frames) * agents * per_frame


def _frames_text(frames: int, agents: int) -> str:
    return f"{count(frames)} frame{'s' * (frames != 1)} of {agents} agent{'s' * (agents != 1)}"


def count(number: int) -> str:
    """``1,200``; ``2e+30`` for numbers too long to read digit by digit."""
    return f"{number:,}" if number < 10**15 else f"{float(number):.3g}"


def episode_estimate(
    *,
    agents: int,
    frames: int,
    steps_per_frame: int,
    schedule_rows: int,
    view: str = "truth",
    held_frames: int,
    recording: bool = False,
    recording_model: bool = False,
) -> Estimate:
    """The cost of one simulated episode written as Parquet.

    Args:
        agents: people and robot in the scene.
        frames: output frames.
        steps_per_frame: control steps of ``dt`` between two output frames.
        schedule_rows: output rows whose steps the world schedules at once (a block of
            ``World.rollout``; 1 for ``World.run``).
        view: ``"truth"`` or ``"robot"`` (a second, observed Frame per frame, and occlusion rays).
        held_frames: frames held in memory at once: all of them when the episode is returned
            whole (or recorded), a chunk when it streams to disk.
        recording: the finished episode is also recorded for Rerun (memory, time, a ``.rrd``).
        recording_model: the recording draws the people's bodies from the scene's model.

    Returns:
        The `Estimate`: peak memory, bytes written (Parquet, and the ``.rrd`` when recording),
        seconds.
    """
    _check_shape(agents, frames, steps_per_frame, view)
    held = min(held_frames, frames)
    agent_frames = float(frames) * agents  # floats: absurd requests overflow integers
    rows = max(1, min(schedule_rows, frames))
    recorded = agent_frames * RECORDING_AGENT_FRAME_BYTES if recording else 0.0
    parts = {
        f"{_frames_text(held, agents)} held in memory": float(held) * frame_bytes(agents, view=view)
        + recorded,
        f"the world's schedule of {count(steps_per_frame)} control steps per frame": float(rows)
        * steps_per_frame
        * SCHEDULE_BYTES_PER_STEP,
    }
    disk = agent_frames * DISK_AGENT_FRAME_BYTES + DISK_EPISODE_BYTES
    if recording:
        disk += recording_disk(agents, frames, view=view, model=recording_model)
    return Estimate(
        memory=BASE_MEMORY_BYTES + sum(parts.values()),
        memory_cause=max(parts, key=parts.__getitem__),
        disk=disk,
        seconds=SECONDS_PER_EPISODE
        + _episode_seconds(agents, frames, steps_per_frame, view, recording),
        frames=frames,
        agents=agents,
    )


def recording_disk(agents: int, frames: int, *, view: str = "truth", model: bool = False) -> float:
    """Bytes of the ``.rrd`` of an episode of ``agents`` agents and ``frames`` frames, its robot's
    observed frames too when ``view`` is ``"robot"``, the people's bodies drawn from the scene's
    model when ``model``."""
    agent_frames = float(frames) * agents
    per_agent = RECORDING_DISK_AGENT_BYTES + (RECORDING_DISK_MODEL_AGENT_BYTES if model else 0)
    per_agent_frame = RECORDING_DISK_AGENT_FRAME_BYTES + (
        RECORDING_DISK_OBSERVED_AGENT_FRAME_BYTES if view == "robot" else 0
    )
    return (
        RECORDING_DISK_BYTES
        + agents * per_agent
        + float(frames) * RECORDING_DISK_FRAME_BYTES
        + agent_frames * per_agent_frame
    )


def dataset_estimate(
    episode: Estimate, *, episodes: int, workers: int = 1, arrays: bool = False
) -> Estimate:
    """The cost of a generated dataset of ``episodes`` episodes like ``episode``, each held
    whole by one of ``workers`` processes while it is written, and the card listing them all.

    Args:
        episode: one episode's `Estimate`, every frame held (`episode_estimate`).
        episodes: episodes to write.
        workers: processes writing episodes at once.
        arrays: the episodes are written from pose arrays (the ground-truth view without
            recordings: ``FAST_AGENT_FRAME_BYTES`` per agent-frame) rather than from Frames.
    """
    for name, value in (("episodes", episodes), ("workers", workers)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} must be an int >= 1, got {value!r}")
    workers = min(workers, episodes)
    per_worker = episode.memory
    if arrays:  # pose arrays rather than Frames
        per_worker += float(episode.frames) * (
            episode.agents * FAST_AGENT_FRAME_BYTES - frame_bytes(episode.agents)
        )
    card = float(episodes) * CARD_EPISODE_BYTES
    if card > workers * (per_worker - BASE_MEMORY_BYTES):
        cause = f"the dataset card's entries for {count(episodes)} episodes"
    else:
        cause = f"{workers} worker{'s' * (workers != 1)}, each with {episode.memory_cause}"
    return Estimate(
        memory=workers * per_worker + card,
        memory_cause=cause,
        disk=float(episodes) * (episode.disk + CARD_DISK_EPISODE_BYTES),
        seconds=float(episodes) * episode.seconds / workers + pool_start(workers),
        frames=episodes * episode.frames,
        agents=episode.agents,
    )


def pool_start(workers: int) -> float:
    """Seconds before ``workers`` worker processes take their first unit
    (`WORKER_START_SECONDS`; none for one, which works in the calling process)."""
    return WORKER_START_SECONDS if workers > 1 else 0.0


def stress_estimate(
    *,
    seeds: int,
    frames: int,
    rate_hz: float,
    base_people: int,
    perturb_levels: int,
    scene_agents: Sequence[tuple[int, bool]],
    train_frames: int,
    workers: int,
) -> Estimate:
    """The cost of a stress test (`reform-sim stress`).

    Args:
        seeds: test episodes per point.
        frames: frames of each test episode.
        rate_hz: their frame rate (the simulator steps `DEFAULT_DT_S` between control steps).
        base_people: people of the party the perturbation axes perturb.
        perturb_levels: levels of the perturbation axes run, summed over them (each scores
            every base episode once per level).
        scene_agents: for each level of the scene axes run, its agents and whether the robot's
            sensor observes them (each simulates and scores ``seeds`` new episodes).
        train_frames: frames of the training set simulated and fitted on.
        workers: processes scoring at once.
    """
    for name, value in (("seeds", seeds), ("frames", frames), ("workers", workers)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} must be an int >= 1, got {value!r}")
    workers = max(1, workers)

    def simulated(agents: int, robot: bool) -> float:
        return episode_estimate(
            agents=agents,
            frames=frames,
            steps_per_frame=max(1, round(1.0 / (rate_hz * DEFAULT_DT_S))),
            schedule_rows=1,
            view="robot" if robot else "truth",
            held_frames=frames,
        ).seconds

    base = seeds if perturb_levels else 0
    agent_frames = float(perturb_levels) * seeds * frames * base_people
    simulate = base * simulated(base_people, False) + float(train_frames) * base_people * (
        SECONDS_PER_AGENT_FRAME
    )
    largest = base_people
    for agents, robot in scene_agents:
        agent_frames += float(seeds) * frames * agents
        simulate += seeds * simulated(agents, robot)
        largest = max(largest, agents)
    scored = (perturb_levels + len(scene_agents)) * float(seeds)
    held = float(base) * frames * frame_bytes(base_people)
    parts = {
        f"{count(base)} test episodes of {base_people} people held to perturb": held,
        f"the scores of {count(int(scored))} test episodes": scored * frames * 200.0,
        f"{workers} worker{'s' * (workers != 1)}, each with an episode of {largest} agents": (
            workers * (BASE_MEMORY_BYTES + float(frames) * frame_bytes(largest, view="robot"))
        ),
    }
    return Estimate(
        memory=BASE_MEMORY_BYTES + sum(parts.values()),
        memory_cause=max(parts, key=parts.__getitem__),
        disk=STRESS_REPORT_BYTES + scored * STRESS_RESULT_BYTES,
        seconds=(simulate + agent_frames * SECONDS_PER_SCORED_AGENT_FRAME) / workers
        + pool_start(workers),
        frames=int(scored) * frames,
        agents=largest,
    )


def gcff_tuning_estimate(*, settings: int, tuning_frames: int, scored_frames: int) -> Estimate:
    """The cost of tuning GCFF by grid search and scoring detectors with it
    (`reform-sim experiment gcff`).

    Args:
        settings: (stride, mdl) settings tried.
        tuning_frames: frames each setting segments.
        scored_frames: frames segmented after tuning (every detector, every test set).
    """
    frames = float(settings) * tuning_frames + scored_frames
    return Estimate(
        memory=BASE_MEMORY_BYTES + float(settings) * GCFF_SETTING_BYTES,
        memory_cause=f"the scores of {count(settings)} GCFF settings",
        disk=STRESS_REPORT_BYTES,
        seconds=frames * SECONDS_PER_GCFF_FRAME,
        frames=int(frames),
        agents=18,
    )


def busy() -> tuple[float, float, int]:
    """How much longer work takes now than on this machine idle: the square root of the load
    average of the last minute over the CPUs this process may use, at least 1; with the load
    and the CPUs. The root damps an average that lags the machine by up to a minute (measured:
    `reform-sim generate` under loads of 4.6 to 8 on two CPUs took 0.7x to 3.1x its idle
    estimate; the root keeps each within 3x, the plain ratio did not)."""
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    cpus = max(1, cpus or 1)
    try:
        load = os.getloadavg()[0]
    except OSError:  # no load average on this platform
        return 1.0, 0.0, cpus
    return max(1.0, (load / cpus) ** 0.5), load, cpus


def describe(estimate: Estimate, what: str) -> str:
    """One line stating an estimate before a long run starts: ``the stress test: about 12 min
    on this machine, 1.3 GiB of memory, 2.1 MiB written (estimates)``. The time is the
    estimate's on this machine as busy as it is now (`busy`: other work shares its CPUs)."""
    factor, load, cpus = busy()
    shared = f" (busy: load {load:.1f} on {cpus} CPUs)" if factor > BUSY_SAID else ""
    return (
        f"{what}: about {format_duration(estimate.seconds * factor)} on this machine{shared}, "
        f"{format_size(estimate.memory)} of memory, {format_size(estimate.disk)} written "
        "(estimates, sim.sizing)"
    )


# --------------------------------------------------------------------------------------------
# Refusals


class _Spelled(dict):
    """Format fields spelled by a function: ``"{max_memory}"`` -> ``"--max-memory"``."""

    def __init__(self, spell: Callable[[str], str]) -> None:
        super().__init__()
        self._spell = spell

    def __missing__(self, key: str) -> str:
        return self._spell(key)


def python_name(name: str) -> str:
    """How a library call spells a parameter in a message: its name, ``max_memory``."""
    return name


def flag_name(name: str, flags: Mapping[str, str] | None = None) -> str:
    """How a command spells a parameter: ``flags[name]``, else ``--max-memory`` for
    ``max_memory``."""
    if flags and name in flags:
        return flags[name]
    return "--" + name.replace("_", "-")


class RequestTooLarge(ValueError):
    """A request that cannot fit this machine, refused before any work.

    The message names the estimate, the limit and what changes it; the parameters it names
    are spelled as a library call spells them (``duration``) or, through :meth:`message`, as a
    command does (``--duration``).

    Attributes:
        resource: ``"memory"``, ``"disk"`` or ``"time"``.
        needed: the estimate: bytes, or seconds for time.
        limit: the limit it exceeds, same unit.
    """

    def __init__(self, resource: str, needed: float, limit: float, template: str) -> None:
        self.resource = resource
        self.needed = needed
        self.limit = limit
        self._template = template
        super().__init__(self.message())

    def message(self, spell: Callable[[str], str] = python_name) -> str:
        """The message, each parameter's name spelled by ``spell``."""
        return self._template.format_map(_Spelled(spell))


def _ask_for_less(shrink: str) -> str:
    return f"ask for less ({shrink})"


def _either(fixes: Sequence[str]) -> str:
    return fixes[0] if len(fixes) == 1 else ", ".join(fixes[:-1]) + ", or " + fixes[-1]


def _refuse_memory(
    estimate: Estimate, what: str, limit: float, limit_text: str, fixes: Sequence[str]
) -> NoReturn:
    raise RequestTooLarge(
        "memory",
        estimate.memory,
        limit,
        f"{what} needs about {format_size(estimate.memory)} of memory "
        f"({estimate.memory_cause}), more than {limit_text}; {_either(fixes)}",
    )


def _check_time(estimate: Estimate, what: str, shrink: str, max_seconds: float) -> None:
    if estimate.seconds > max_seconds:
        raise RequestTooLarge(
            "time",
            estimate.seconds,
            max_seconds,
            f"{what} would take about {format_duration(estimate.seconds)} on this machine "
            f"({_frames_text(estimate.frames, estimate.agents)}), more than the "
            f"{format_duration(max_seconds)} a run may take (sim.sizing.MAX_RUN_SECONDS); "
            + _ask_for_less(shrink),
        )


def check_episodes(episodes: int, *, what: str, flag: str) -> None:
    """Refuses, before any work, a study whose ``episodes`` simulated episodes would take longer
    than `MAX_RUN_SECONDS` even at `SECONDS_PER_EPISODE` each (the least an episode costs beside
    its frames): the guard of the studies that count episodes rather than frames.

    Raises:
        RequestTooLarge: naming the estimate, the limit and ``flag``.
    """
    seconds = episodes * SECONDS_PER_EPISODE
    if seconds > MAX_RUN_SECONDS:
        raise RequestTooLarge(
            "time",
            seconds,
            MAX_RUN_SECONDS,
            f"{what} would take at least {format_duration(seconds)} on this machine "
            f"({count(episodes)} episodes at {SECONDS_PER_EPISODE:g} s each at the least), more "
            f"than the {format_duration(MAX_RUN_SECONDS)} a run may take "
            f"(sim.sizing.MAX_RUN_SECONDS); ask for fewer ({flag})",
        )


def check(
    estimate: Estimate,
    *,
    what: str = "the run",
    shrink: str,
    memory_limit: float | None = None,
    limit_option: str = "max_memory",
    alternative: str = "",
    out: str | os.PathLike[str] | None = None,
    out_option: str = "out",
    disk_needed: float | None = None,
    max_seconds: float = MAX_RUN_SECONDS,
) -> None:
    """Raises `RequestTooLarge` when ``estimate`` cannot fit: memory, then disk, then time.

    Args:
        estimate: the run's `Estimate`.
        what: the run, as the message names it.
        shrink: what makes the run smaller, a template naming parameters in braces
            (``"a shorter {duration} or a lower {rate}"``).
        memory_limit: bytes of memory the run may take; None for what this machine has
            available now (`available_memory`).
        limit_option: the parameter that sets ``memory_limit``, named in the message.
        alternative: another way to fit the memory (streaming, fewer workers), a template
            naming parameters in braces (``"without {save} the frames stream to {out}"``).
        out: where the run writes; None skips the disk check.
        out_option: the parameter naming ``out``.
        disk_needed: bytes still to write, when less than ``estimate.disk`` (a resumed run).
        max_seconds: the longest run allowed, seconds.

    Raises:
        RequestTooLarge: naming the estimate, the limit and what to change.
    """
    limit = available_memory() if memory_limit is None else memory_limit
    if estimate.memory > limit:
        if memory_limit is None:
            limit_text = f"the {format_size(limit)} of memory this machine has available"
        else:
            limit_text = f"the limit {{{limit_option}}} {format_size(limit)}"
        fixes = [_ask_for_less(shrink), *([alternative] if alternative else [])]
        fixes.append(f"change the limit with {{{limit_option}}} SIZE (e.g. 64G)")
        _refuse_memory(estimate, what, limit, limit_text, fixes)
    if out is not None:
        needed = estimate.disk if disk_needed is None else disk_needed
        free = free_disk(out)
        if needed > free:
            raise RequestTooLarge(
                "disk",
                needed,
                free,
                f"{what} writes about {format_size(needed)} "
                f"({_frames_text(estimate.frames, estimate.agents)}), more than the "
                f"{format_size(free)} free where {{{out_option}}} {os.fspath(out)} is; "
                f"{_ask_for_less(shrink)} or write elsewhere",
            )
    _check_time(estimate, what, shrink, max_seconds)


def check_possible(estimate: Estimate, *, what: str, shrink: str) -> None:
    """Raises `RequestTooLarge` for what this machine can never do: take more memory than it
    has with its swap (`total_memory`), or run longer than `MAX_RUN_SECONDS`. The guard of
    library calls, which take no limit; commands `check` against the memory available instead.
    """
    limit = total_memory()
    if estimate.memory > limit:
        limit_text = f"the {format_size(limit)} of memory and swap this machine has"
        _refuse_memory(estimate, what, limit, limit_text, [_ask_for_less(shrink)])
    _check_time(estimate, what, shrink, MAX_RUN_SECONDS)


# --------------------------------------------------------------------------------------------
# Measuring the costs


_PROBE = """
import json, sys, time
from pathlib import Path
job = json.loads(sys.argv[1])
out = Path(job["out"])
if job["kind"] == "generate":
    from sim.generate import generate_dataset
    started = time.perf_counter()
    generate_dataset("mingle", episodes=job["episodes"], seed=1, out_dir=out, n_jobs=1,
                     options=job["options"], duration=job["duration"], progress=False)
    seconds = time.perf_counter() - started
    shards = sum(p.stat().st_size for p in out.rglob("*.parquet"))
    card = (out / "dataset.json").stat().st_size + (out / "README.md").stat().st_size
    import tracemalloc
    from sim.generate import ShardSummary, read_card
    tracemalloc.start()
    held = read_card(out)
    summaries = [ShardSummary.from_json(entry) for entry in held["shards"]]
    text = json.dumps(held, indent=2)
    card_memory = tracemalloc.get_traced_memory()[1]
    print(json.dumps({"seconds": seconds, "disk": shards, "card": card,
                      "card_memory": card_memory}))
else:
    from reform.datasets import write_parquet
    from sim.episode import simulate_episode
    started = time.perf_counter()
    episode = simulate_episode("mingle", seed=1, duration=job["duration"], dt=job["dt"],
                               view=job["view"], options=job["options"])
    write_parquet(episode.dataset, out)
    seconds = time.perf_counter() - started
    result = {"seconds": seconds, "disk": out.stat().st_size, "frames": len(episode.truth),
              "agents": len(episode.scenario.stage.people)
              + (episode.scenario.stage.robot is not None)}
    if job.get("record"):
        from sim.recording import record_episode
        rrd = out.with_suffix(".rrd")
        started = time.perf_counter()
        record_episode(rrd, episode.truth, events=episode.events, seed=1, name="probe")
        result["record_seconds"] = time.perf_counter() - started
        result["rrd"] = rrd.stat().st_size
    print(json.dumps(result))
"""


def _probe(job: Mapping[str, object]) -> dict[str, float]:  # pragma: no cover - by hand
    """Runs one probe in a fresh process: its printed figures and its peak resident bytes."""

    child = subprocess.Popen(
        [sys.executable, "-c", _PROBE, json.dumps(job)], stdout=subprocess.PIPE, text=True
    )
    printed = child.stdout.read()
    _, status, usage = os.wait4(child.pid, 0)  # reaped here, for its resource usage
    child.returncode = os.waitstatus_to_exitcode(status)
    child.stdout.close()
    if child.returncode:
        raise RuntimeError(f"probe {job} failed with exit status {child.returncode}")
    result = json.loads(printed)
    result["rss"] = usage.ru_maxrss * 1024  # Linux reports kilobytes
    return result


def measure() -> dict[str, float]:  # pragma: no cover - run by hand, see the module docstring
    """Measures the costs above on this machine and prints them as this module writes them.

    Runs small episodes of ``mingle`` in fresh processes and fits the differences of their peak
    resident memory, wall-clock time and file sizes. Takes a few minutes.
    """

    with tempfile.TemporaryDirectory() as scratch:
        runs: dict[str, dict[str, float]] = {}

        def run(name: str, **job: object) -> dict[str, float]:
            job.setdefault("kind", "held")
            job.setdefault("dt", 0.01)
            job.setdefault("view", "truth")
            job["out"] = str(Path(scratch) / f"{name}.parquet")
            runs[name] = _probe(job)
            print(f"{name}: {runs[name]}", flush=True)
            return runs[name]

        short, long = 600.0, 3000.0
        few, many = {"people": 4}, {"people": 40}
        a = run("few-short", duration=short, options=few)
        b = run("few-long", duration=long, options=few)
        c = run("many-short", duration=short, options=many)
        d = run("many-long", duration=long, options=many)
        e = run("many-short-fine", duration=short, options=many, dt=0.002)
        robot = {"people": 18, "robot": True}
        f = run("robot-short", duration=short, options=robot, view="robot", record=True)
        g = run("robot-long", duration=long, options=robot, view="robot", record=True)
        k = run("robot-long-unrecorded", duration=long, options=robot, view="robot")
        h = run("generate-short", kind="generate", episodes=1, duration=short, options=many)
        i = run("generate-long", kind="generate", episodes=1, duration=long, options=many)
        j = run("generate-tiny", kind="generate", episodes=16, duration=0.5, options=few)

    frames = b["frames"] - a["frames"]
    n_few, n_many, n_robot = a["agents"], c["agents"], f["agents"]
    slope_few = (b["rss"] - a["rss"]) / frames
    slope_many = (d["rss"] - c["rss"]) / frames
    agent_frame = (slope_many - slope_few) / (n_many - n_few)
    per_frame = slope_few - n_few * agent_frame
    steps = c["frames"] * (0.5 / 0.01)
    agent_step = (e["seconds"] - c["seconds"]) / (4 * steps * n_many)
    frame_seconds = (d["seconds"] - c["seconds"]) / (frames * n_many) - 50 * agent_step
    robot_frames = g["frames"] - f["frames"]
    observed = (g["seconds"] - f["seconds"]) / (robot_frames * n_robot) - 50 * agent_step
    figures = {
        "BASE_MEMORY_BYTES": a["rss"] - a["frames"] * slope_few,
        "FRAME_BYTES": per_frame,
        "AGENT_FRAME_BYTES": agent_frame,
        "FAST_AGENT_FRAME_BYTES": (i["rss"] - h["rss"]) / (frames * n_many),
        "RECORDING_AGENT_FRAME_BYTES": (g["rss"] - k["rss"]) / (g["frames"] * n_robot),
        "DISK_AGENT_FRAME_BYTES": c["disk"] / (c["frames"] * n_many),
        "DISK_EPISODE_BYTES": j["disk"] / 16,
        "RECORDING_DISK_AGENT_FRAME_BYTES": (g["rrd"] - f["rrd"]) / (robot_frames * n_robot),
        "CARD_EPISODE_BYTES": j["card_memory"] / 16,
        "CARD_DISK_EPISODE_BYTES": j["card"] / 16,
        "SECONDS_PER_AGENT_STEP": agent_step,
        "SECONDS_PER_AGENT_FRAME": frame_seconds,
        "SECONDS_PER_OBSERVED_AGENT_FRAME": observed - frame_seconds,
        "SECONDS_PER_RECORDED_AGENT_FRAME": (g["record_seconds"] - f["record_seconds"])
        / (robot_frames * n_robot),
        "SECONDS_PER_EPISODE": j["seconds"] / 16,
    }
    for name, value in figures.items():
        print(f"{name} = {value:.3g}")
    return figures


if __name__ == "__main__":  # pragma: no cover
    measure()
