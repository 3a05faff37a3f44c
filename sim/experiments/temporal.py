"""Groups in time: every detector's events, latency and flicker on the default party and on the
real datasets, and what the temporal filters buy (``reform-sim experiment temporal``).

The protocol is the benchmark's (`sim.experiments.benchmark`, ``--temporal``), over one more
dataset: the **default party**, ``episodes`` episodes of ``mingle`` at its default options
(seeds from the master seed, `reform.seeding.Role.TEMPORAL_PARTY`; and the same episodes with
scripted changes, ``event_rate`` 4 a minute), ``duration`` seconds each at
``rate`` frames per second, written to a Parquet file in a temporary folder and read back like
any dataset. Every catalogued detector that runs with its defaults, or learns on training frames
(fitted on the first 60 % of each recording, scored on the rest, as the benchmark does), is
scored per frame (P/R/F1 with block-bootstrap intervals) and in time (`reform.evaluate_events`:
event recall and precision, latency, false events per minute, identity switches, intervals over
sequences).

**The filters' goal** (issue: groups in time), on the party: each filter against the detector it
wraps, on the same frames, a filter passing when its false events per minute are at most half
the detector's, its median latency at most one second later, and its frame F1 at T = 2/3 not
lower. The filters run at their catalogue defaults, fixed before this experiment was run; no
setting is chosen on the frames scored here.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from reform import Dataset, write_parquet
from reform.detectors import builtin_names, detector_info
from reform.seeding import Role, derive_int
from sim.episode import simulate_episode
from sim.executor import Executor
from sim.experiments.benchmark import Benchmark, DatasetSpec, detector_spec, run_benchmark

__all__ = [
    "FILTERS",
    "FilterGoal",
    "TemporalResult",
    "filter_goals",
    "party_frames",
    "run_temporal",
]

PARTY = "party (simulated)"  # the simulated dataset's label
SCRIPTED = "party with scripted changes (simulated)"
SCENARIO = "mingle"
# The parties simulated: the default one (the filters' goal), and the same with scripted
# changes (latecomers, people drifting away, groups merging), whose joins and leaves the
# default party's own comings and goings rarely make.
PARTIES: Mapping[str, Mapping[str, Any]] = {PARTY: {}, SCRIPTED: {"event_rate": 4.0}}
EPISODES = 4
DURATION_S = 240.0
RATE_HZ = 5.0
# Each filter against the detector it wraps at its catalogue default.
FILTERS: Mapping[str, str] = {"smoothed": "gcff", "hysteresis": "reform-trained"}
MAX_FLICKER_RATIO = 0.5  # the filter's false events per minute over the detector's, at most
MAX_ADDED_LATENCY_S = 1.0  # seconds of median latency a filter may add


def party_frames(
    *,
    seed: int,
    episodes: int,
    duration: float,
    rate: float,
    options: Mapping[str, Any] | None = None,
    name: str = PARTY,
) -> Dataset:
    """A party: ``episodes`` episodes of ``mingle`` with ``options`` (default: its defaults),
    one sequence each; the same seeds whatever the options."""
    frames = []
    for i in range(episodes):
        episode = simulate_episode(
            SCENARIO,
            seed=derive_int(seed, Role.TEMPORAL_PARTY, i),
            duration=duration,
            rate=rate,
            options=dict(options or {}),
            sequence=f"party-{i}",
        )
        frames.extend(episode.dataset.frames)
    return Dataset(frames=tuple(frames), name=name, source=f"{SCENARIO}, seed {seed}")


@dataclass(frozen=True)
class FilterGoal:
    """One filter against the detector it wraps, on the party."""

    filter: str
    detector: str
    flicker: tuple[float, float]  # false events per minute: detector, filter
    latency: tuple[float | None, float | None]  # median latency, seconds: detector, filter
    f1: tuple[float, float]  # frame F1 at T = 2/3: detector, filter
    met: bool

    def to_json(self) -> dict[str, Any]:
        return {
            "filter": self.filter,
            "detector": self.detector,
            "false_events_per_minute": list(self.flicker),
            "latency_median_s": list(self.latency),
            "f1_2/3": list(self.f1),
            "met": self.met,
        }


def _cell(benchmark: Benchmark, dataset: str, spec: str) -> Any:
    for cell in benchmark.cells:
        if cell.dataset == dataset and cell.detector == detector_spec(spec).label:
            return cell
    return None


def filter_goals(benchmark: Benchmark) -> list[FilterGoal]:
    """Each filter of `FILTERS` scored on the party against the detector it wraps."""
    goals = []
    for name, inner in FILTERS.items():
        base, filtered = _cell(benchmark, PARTY, inner), _cell(benchmark, PARTY, name)
        cells = (base, filtered)
        if any(
            c is None or c.scores is None or not c.temporal or "skipped" in c.temporal
            for c in cells
        ):
            continue
        flicker = (
            base.temporal["false_events_per_minute"],
            filtered.temporal["false_events_per_minute"],
        )
        latency = (
            base.temporal["latency_s"]["median"],
            filtered.temporal["latency_s"]["median"],
        )
        f1 = (base.scores.at["2/3"][2], filtered.scores.at["2/3"][2])
        later = (
            None if None in latency else latency[1] - latency[0]  # type: ignore[operator]
        )
        met = (
            flicker[1] <= MAX_FLICKER_RATIO * flicker[0]
            and later is not None
            and later <= MAX_ADDED_LATENCY_S + 1e-9
            and f1[1] >= f1[0]
        )
        goals.append(FilterGoal(name, inner, flicker, latency, f1, bool(met)))
    return goals


@dataclass(frozen=True)
class TemporalResult:
    """The benchmark over the party and the real datasets, and the filters' goals."""

    benchmark: Benchmark
    goals: tuple[FilterGoal, ...]
    party: Mapping[str, Any]
    seconds: float


def run_temporal(
    real: Sequence[DatasetSpec],
    *,
    seed: int = 0,
    episodes: int = EPISODES,
    duration: float = DURATION_S,
    rate: float = RATE_HZ,
    detectors: Sequence[str] | None = None,
    jobs: int = 1,
    executor: Executor | None = None,
    progress: Callable[[str], None] | None = None,
) -> TemporalResult:
    """Scores every detector per frame and in time on the party and on ``real``.

    Args:
        real: the real datasets (`sim.experiments.benchmark.DatasetSpec`), perhaps none.
        seed: master seed of the party's episodes.
        episodes, duration, rate: the party's size: episodes, seconds each, frames per second.
        detectors: catalogue names (default: every built-in that runs with its defaults or
            learns on training frames).
        jobs: local worker processes, or ``executor``.
        progress: called with a line as each stage and cell finishes.
    """
    say = progress or (lambda _line: None)
    start = time.perf_counter()
    names = list(detectors) if detectors else list(builtin_names(needs=("", "training")))
    for name in names:
        detector_info(name)  # an unknown name: one line, before any work
    specs = [detector_spec(name) for name in names]
    parties = {
        label: party_frames(
            seed=seed,
            episodes=episodes,
            duration=duration,
            rate=rate,
            options=options,
            name=label,
        )
        for label, options in PARTIES.items()
    }
    say(f"simulated the parties: {episodes} episodes each of {duration:g} s at {rate:g} Hz")
    with tempfile.TemporaryDirectory(prefix="reform-sim-temporal-") as folder:
        datasets = [
            DatasetSpec(
                name=label, path=str(write_parquet(party, Path(folder) / f"party-{k}.parquet"))
            )
            for k, (label, party) in enumerate(parties.items())
        ]
        datasets += list(real)
        total = len(datasets) * len(specs)

        def done(count: int, _total: int, cell: Any) -> None:
            say(f"{count}/{total} {cell.dataset} × {cell.detector}")

        benchmark = run_benchmark(
            datasets, specs, jobs=jobs, executor=executor, progress=done, temporal=True
        )
    people = [f.n_people for f in parties[PARTY].frames]
    return TemporalResult(
        benchmark=benchmark,
        goals=tuple(filter_goals(benchmark)),
        party={
            "scenario": SCENARIO,
            "seed": seed,
            "episodes": episodes,
            "duration_s": duration,
            "rate_hz": rate,
            "frames": len(parties[PARTY].frames),
            "scripted_options": dict(PARTIES[SCRIPTED]),
            "people_per_frame": sum(people) / len(people) if people else 0.0,
        },
        seconds=time.perf_counter() - start,
    )
