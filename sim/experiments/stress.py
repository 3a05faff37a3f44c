"""Stress tests: how REFORM and GCFF degrade as tracking gets worse and crowds change.

F1 at T = 2/3 and T = 1 (the protocol of :mod:`reform.metrics`) of REFORM with each of the
paper's three pair classifiers and of GCFF, as functions of:

* tracking errors applied to simulated parties (:class:`reform.perturb.Perturbation`):
  ``position-noise`` (metres per axis), ``orientation-noise`` (degrees), ``dropout`` (share of
  people missing from each frame);
* the scene (the ``mingle`` scenario's options): ``density`` (guests per m², through the room's
  side), ``groups`` (number of guests at the default density, hence the number of groups),
  ``group-size`` (largest group allowed);
* the ``sensor``: the ground truth of everyone in the room against the robot's head sensor
  (`sim.sensor.Sensor`): field of view and range only, with occlusion by MuJoCo rays, and with
  occlusion plus Kinect-like tracking errors;
* the ``event-rate``: scripted changes per minute on top of the party's own (`mingle`'s
  ``event_rate``, `scenarios.changes`): latecomers walking up to groups, members drifting away,
  groups walking over to merge;
* the ``crowd``: people in a ``concourse`` (`scenarios.concourse`: walkers crossing, a queue,
  groups standing aside), from a hundred up to a concourse of thousands.

Protocol. The detectors are trained once: REFORM's three classifiers on a synthetic training set
of ``mingle`` and ``word-improv`` episodes, GCFF tuned (stride and mdl, by grid search with the
protocol's F1 at T = 2/3) on a subsample of the same frames. Training and test episodes draw
their seeds from different spawn keys of the master seed (``SeedSequence(seed, spawn_key=(role,
...))``), so no test episode is a training episode. Each point of a curve is scored on
``seeds`` test episodes of the SALSA-like party (``mingle``, 18 guests, 0.4 per m², unless the
axis changes it), frame rate ``rate_hz``; the ground truth of a perturbed or observed frame is
the truth restricted to the people it holds. Perturbations at every level of an axis use the
same random numbers (common random numbers), so a curve's steps come from the level, not from
the draw.

Detectors of your own (``plugins``: any object with ``predict``, see `reform.detectors`) run
beside these on the same frames, fitted on the same training frames when they have ``fit``;
``reform-sim stress --detector NAME|package.module:factory`` adds them from the command line.

Confidence intervals: two-stage bootstrap (episodes, then frames within each;
:mod:`reform.bootstrap`), percentile intervals, the same resamples for every detector at a point.

Everything runs in parallel, as independent units of work (`sim.executor`): over the machine's
cores (joblib processes) or as Ray tasks on a cluster; the results do not depend on the backend
or the number of workers. ``GRIDS["small"]`` runs in seconds (tests, the demo);
``GRIDS["default"]`` is the documented run.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from reform.bootstrap import ScoreIntervals, bootstrap_weights, frame_intervals
from reform.classifiers import BAGGED_TREES, LOGISTIC_REGRESSION, WEIGHTED_KNN, make_classifier
from reform.detector import Reform
from reform.detectors import fit_detector, run_detector
from reform.frame import Frame
from reform.gcff import Gcff
from reform.json_values import json_float, json_record
from reform.metrics import T_ONE, T_TWO_THIRDS, evaluate
from reform.perturb import Perturbation
from reform.seeding import Role, derive_int, derive_rng
from reform.temporal import DEFAULT_TOLERANCE_S, evaluate_events, frame_interval
from sim.episode import simulate_episode
from sim.executor import Executor, cpu_count
from sim.experiments.stress_grid import (
    AXES,
    BASE_PEOPLE,
    GRIDS,
    SENSOR_NAMES,
    StressGrid,
    check_axis,
    resolve_grid,
)
from sim.sensor import Sensor

__all__ = [
    "AXES",
    "DETECTORS",
    "DETECTOR_LABELS",
    "GRIDS",
    "SENSORS",
    "THRESHOLDS",
    "StressAxis",
    "StressGrid",
    "StressPoint",
    "StressResults",
    "resolve_grid",
    "run_stress",
    "train_detectors",
    "training_frames",
]

GCFF = "gcff-tuned"  # the catalogue's name: GCFF searched on the training frames
DETECTORS = (WEIGHTED_KNN, BAGGED_TREES, LOGISTIC_REGRESSION, GCFF)
DETECTOR_LABELS: Mapping[str, str] = MappingProxyType(
    {
        WEIGHTED_KNN: "REFORM weighted KNN",
        BAGGED_TREES: "REFORM bagged trees",
        LOGISTIC_REGRESSION: "REFORM logistic regression",
        GCFF: "GCFF",
    }
)
THRESHOLDS = ("2/3", "1")  # matching thresholds scored (exact: T_TWO_THIRDS, T_ONE)
_THRESHOLD_VALUES = {"2/3": T_TWO_THIRDS, "1": T_ONE}

TEST_SCENARIO = "mingle"  # the party every point is scored on
CROWD_SCENARIO = "concourse"  # the crowd axis's scene
TRAINING_SCENARIOS = ("mingle", "word-improv")
BASE_DENSITY_PER_M2 = 0.4  # guests per m² of the test party (mingle's default, SALSA-like)

# Kinect-like tracking errors of the "tracker" sensor level (skeleton tracking of the robot's
# head sensor): metres per axis, radians, share of people missed per frame.
TRACKER_POSITION_NOISE_M = 0.05
TRACKER_YAW_NOISE_RAD = math.radians(10.0)
TRACKER_DROPOUT = 0.05

# The sensor levels (`SENSOR_NAMES`): None is the ground truth of everyone in the room.
SENSORS: Mapping[str, Sensor | None] = MappingProxyType(
    dict(
        zip(
            SENSOR_NAMES,
            (
                None,
                Sensor(occlusion=False),
                Sensor(),
                Sensor(
                    position_noise=TRACKER_POSITION_NOISE_M,
                    yaw_noise=TRACKER_YAW_NOISE_RAD,
                    dropout=TRACKER_DROPOUT,
                ),
            ),
            strict=True,
        )
    )
)
_SENSOR_TEXT = {
    "truth": "ground truth, everyone in the room",
    "fov": "robot's head sensor: field of view and range only",
    "occlusion": "robot's head sensor: field of view, range, occlusion",
    "tracker": (
        f"robot's head sensor with occlusion and tracking errors ({TRACKER_POSITION_NOISE_M} m, "
        f"{math.degrees(TRACKER_YAW_NOISE_RAD):g} deg, {TRACKER_DROPOUT:.0%} dropout)"
    ),
}

# A party mingle's planner cannot lay out (no free floor) is drawn again with another seed, at
# most this many times.
MAX_REDRAWS = 5
ROBOT_VIEW_COST = 4.0  # a robot-view episode costs about this many ground-truth ones (rays)


# ------------------------------------------------------------------------------------------------
# Episodes


@dataclass(frozen=True)
class _EpisodeSpec:
    scenario: str
    seed: int
    options: tuple[tuple[str, Any], ...]
    duration: float
    rate: float
    sensor: str = "truth"


def _simulate(spec: _EpisodeSpec) -> tuple[Frame, ...]:
    return _simulate_scene(spec)[0]


def _simulate_scene(spec: _EpisodeSpec) -> tuple[tuple[Frame, ...], float]:
    """The episode's frames and its crowd density: humans in the room per m² (time mean)."""
    sensor = SENSORS[spec.sensor]
    episode = simulate_episode(
        spec.scenario,
        seed=spec.seed,
        duration=spec.duration,
        rate=spec.rate,
        options=dict(spec.options),
        view="truth" if sensor is None else "robot",
        sensor=sensor,
    )
    width, depth = episode.dataset.metadata["room_m"]
    humans = np.mean([np.count_nonzero(~f.is_robot) for f in episode.truth])
    return episode.dataset.frames, float(humans) / (float(width) * float(depth))


def _room_side(people: int, density: float) -> float:
    """Side of the square room holding ``people`` at ``density`` per m² (rounded up to a µm)."""
    return math.ceil(math.sqrt(people / density) * 1e6) / 1e6


def _scene_spec(grid: StressGrid, axis: str | None, level: Any, seed: int) -> _EpisodeSpec:
    """The test episode of level ``level`` of scene axis ``axis`` (None: the base party)."""
    options: dict[str, Any] = {"duration": grid.duration_s}
    sensor = "truth"
    scenario = TEST_SCENARIO
    if axis == "density":
        options["room_side"] = _room_side(BASE_PEOPLE, float(level))
    elif axis == "groups":
        options["people"] = int(level)
    elif axis == "group-size":
        options["max_group_size"] = int(level)
    elif axis == "sensor":
        options["robot"] = True
        sensor = str(level)
    elif axis == "event-rate":
        options["event_rate"] = float(level)
    elif axis == "crowd":
        scenario = CROWD_SCENARIO
        options["people"] = int(level)
    return _EpisodeSpec(
        scenario, seed, tuple(sorted(options.items())), grid.duration_s, grid.rate_hz, sensor
    )


def training_frames(
    *,
    seed: int,
    episodes: int = 4,
    duration: float = 600.0,
    rate: float = 0.5,
    scenarios: Sequence[str] = TRAINING_SCENARIOS,
    jobs: int | None = None,
    executor: Executor | None = None,
) -> tuple[Frame, ...]:
    """The synthetic training set: ``episodes`` episodes of each training scenario.

    Episode ``i`` of scenario ``s`` (in ``scenarios`` order) has seed
    ``derive_int(seed, Role.STRESS_TRAIN, s, i)`` (`reform.seeding`); test episodes of
    :func:`run_stress` use another role.

    Args:
        seed: master seed.
        episodes: episodes per scenario.
        duration: seconds per episode.
        rate: frames per second.
        scenarios: registered scenario names, at their default options.
        jobs: local worker processes (None: every core).
        executor: where the episodes run (`sim.executor.Executor`) instead of ``jobs`` local
            processes; the frames do not depend on it.

    Returns:
        The annotated frames, scenario by scenario, episode by episode.
    """
    specs = _training_specs(seed, episodes, duration, rate, scenarios)
    return _simulate_all(specs, executor=_executor(jobs, executor))


def _executor(jobs: int | None, executor: Executor | None) -> Executor:
    """``executor``, or local processes (``jobs`` of them); not both."""
    if executor is None:
        return Executor("local", jobs=jobs)
    if jobs is not None:
        raise ValueError(f"jobs is for local processes; give it or executor, got both ({jobs})")
    return executor


def _simulate_all(
    specs: Sequence[_EpisodeSpec], *, executor: Executor, cpu: list[float] | None = None
) -> tuple[Frame, ...]:
    """The frames of every episode of ``specs``, episode after episode."""
    episodes = _parallel(_simulate, specs, executor=executor, cpu=cpu)
    return tuple(f for frames in episodes for f in frames)


def _training_specs(
    seed: int, episodes: int, duration: float, rate: float, scenarios: Sequence[str]
) -> list[_EpisodeSpec]:
    return [
        _EpisodeSpec(name, derive_int(seed, Role.STRESS_TRAIN, s, i), (), duration, rate)
        for s, name in enumerate(scenarios)
        for i in range(episodes)
    ]


# ------------------------------------------------------------------------------------------------
# Detectors


def _fit(name: str, frames: Sequence[Frame], grid: StressGrid) -> Any:
    if name == GCFF:
        step = max(1, math.ceil(len(frames) / grid.gcff_tuning_frames))
        return Gcff(
            tune=True,
            stride_grid=grid.gcff_stride_grid_m,
            mdl_grid=grid.gcff_mdl_grid_m2,
        ).fit(list(frames[::step]))
    return Reform(make_classifier(name)).fit(frames)


def train_detectors(
    frames: Sequence[Frame],
    *,
    grid: StressGrid | None = None,
    jobs: int | None = None,
    names: Sequence[str] = DETECTORS,
    executor: Executor | None = None,
) -> dict[str, Any]:
    """REFORM with each classifier fitted on ``frames``, and GCFF tuned on a subsample of them.

    Args:
        frames: annotated training frames.
        grid: the GCFF tuning grid and subsample size (default ``GRIDS["default"]``).
        jobs: local worker processes (None: every core).
        names: which of :data:`DETECTORS` to fit.
        executor: where the fits run (`sim.executor.Executor`) instead of ``jobs`` local
            processes; the fitted detectors do not depend on it.

    Returns:
        Detector name -> fitted detector, in ``names`` order.
    """
    grid = GRIDS["default"] if grid is None else grid
    unknown = [n for n in names if n not in DETECTORS]
    if unknown:
        raise ValueError(f"names must be among {DETECTORS}, got {unknown}")
    return _fit_all(frames, grid, names, executor=_executor(jobs, executor))


def _fit_all(
    frames: Sequence[Frame],
    grid: StressGrid,
    names: Sequence[str],
    *,
    executor: Executor,
    cpu: list[float] | None = None,
) -> dict[str, Any]:
    """Detector name -> ``_fit(name, frames, grid)``, the fits run by ``executor`` (the
    frames sent once)."""
    fitted = _parallel(_fit, list(names), shared=(frames, grid), executor=executor, cpu=cpu)
    return dict(zip(names, fitted, strict=True))


# ------------------------------------------------------------------------------------------------
# Scoring one condition


@dataclass(frozen=True)
class _Scored:
    """Per-frame scores of every detector on one condition of one episode."""

    sequence: tuple[str, ...]
    precision: Mapping[tuple[str, str], np.ndarray]  # (detector, threshold) -> (n_frames,)
    recall: Mapping[tuple[str, str], np.ndarray]
    pairs: int
    pairs_correct: Mapping[str, int]
    people: int
    fformations: int
    fformation_members: int
    density: float  # humans in the room per m²
    notes: tuple[str, ...] = ()
    events: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)  # detector -> counts

    @staticmethod
    def noted(scored: _Scored, notes: Sequence[str]) -> _Scored:
        return dataclasses.replace(scored, notes=tuple(notes))


def _event_counts(frames: Sequence[Frame], predictions: Sequence[Any]) -> dict[str, Any]:
    """What the temporal scores of a point pool over its episodes (`reform.evaluate_events`,
    matched within 1 s or the frame interval where longer); empty where the episode cannot be
    scored in time (fewer than two annotated frames)."""
    try:
        tolerance = max(DEFAULT_TOLERANCE_S, frame_interval(frames))
        scored = evaluate_events(frames, predictions, tolerance_s=tolerance)
    except ValueError:
        return {}
    return {
        "true": len(scored.true_events),
        "detected": len(scored.detected_events),
        "matched": len(scored.matches),
        "false": scored.false_events,
        "minutes": scored.minutes,
        "switches": scored.identity_switches,
        "latency": scored.latency_s.tolist(),
        "tolerance_s": tolerance,
    }


def _score(
    frames: Sequence[Frame],
    detectors: Mapping[str, Any],
    density: float,
    temporal: bool = False,
    deadline_s: float | None = None,
) -> _Scored:
    precision, recall, correct = {}, {}, {}
    events: dict[str, Mapping[str, Any]] = {}
    sequence: tuple[str, ...] = ()
    pairs = 0
    for name, detector in detectors.items():
        predictions = run_detector(name, detector, frames, deadline_s=deadline_s)
        evaluation = evaluate(frames, predictions)
        if temporal:
            events[name] = _event_counts(frames, predictions)
        for key in THRESHOLDS:
            scores = evaluation.at(_THRESHOLD_VALUES[key])
            precision[name, key] = np.asarray(scores.frame_precision)
            recall[name, key] = np.asarray(scores.frame_recall)
        correct[name] = int(evaluation.pairs_correct.sum())
        pairs = int(evaluation.pairs.sum())
        sequence = evaluation.sequence
    annotated = [f for f in frames if f.groups is not None]
    groups = [g for f in annotated for g in f.fformations()]
    return _Scored(
        sequence=sequence,
        precision=precision,
        recall=recall,
        pairs=pairs,
        pairs_correct=correct,
        people=sum(f.n_people for f in annotated),
        fformations=len(groups),
        fformation_members=sum(len(g) for g in groups),
        density=density,
        events=events,
    )


def _perturbation(axis: str, level: float) -> Perturbation:
    if axis == "position-noise":
        return Perturbation(position_noise=level)
    if axis == "orientation-noise":
        return Perturbation(yaw_noise=math.radians(level))
    if axis == "dropout":
        return Perturbation(dropout=level)
    raise ValueError(f"axis {axis!r} is not a perturbation")


def _perturb_task(
    grid: StressGrid,
    axis: str,
    axis_index: int,
    episode: int,
    base: tuple[Sequence[Frame], float],
    seed: int,
    detectors: Mapping[str, Any],
    temporal: bool = False,
    deadline_s: float | None = None,
) -> list[tuple[str, int, int, _Scored | str]]:
    frames, density = base
    out: list[tuple[str, int, int, _Scored | str]] = []
    for k, level in enumerate(grid.levels(axis)):
        perturbation = _perturbation(axis, level)
        # The same draws at every level.
        rng = derive_rng(seed, Role.STRESS_PERTURB, axis_index, episode)
        perturbed = perturbation.apply_all(frames, rng)
        scored = _score(perturbed, detectors, density, temporal, deadline_s)
        out.append((axis, k, episode, scored))
    return out


def _scene_task(
    grid: StressGrid,
    axis: str,
    k: int,
    seed: int,
    detectors: Mapping[str, Any],
    temporal: bool = False,
    deadline_s: float | None = None,
) -> list[tuple[str, int, int, _Scored | str]]:
    """Every test episode of level ``k`` of a scene axis (one task: the detectors are unpacked
    and compiled once per task)."""
    level = grid.levels(axis)[k]
    out: list[tuple[str, int, int, _Scored | str]] = []
    for episode in range(grid.seeds):
        notes = []
        for attempt in range(MAX_REDRAWS + 1):
            keys = (episode,) if attempt == 0 else (episode, attempt)
            spec = _scene_spec(grid, axis, level, derive_int(seed, Role.STRESS_TEST, *keys))
            try:
                frames, density = _simulate_scene(spec)
            except ValueError as exc:  # the planner cannot lay out this party: draw another
                notes.append(f"seed {spec.seed}: {exc}")
                continue
            scored = _score(frames, detectors, density, temporal, deadline_s)
            out.append((axis, k, episode, _Scored.noted(scored, notes)))
            break
        else:
            out.append((axis, k, episode, "; ".join(notes)))
    return out


def _cost(grid: StressGrid, task: tuple[Callable[..., Any], tuple[Any, ...]]) -> float:
    """A rough relative cost of a task (people x frames), to start the longest first."""
    function, args = task
    if function is _perturb_task:
        return len(grid.levels(args[1])) * BASE_PEOPLE
    axis, k = args[1], args[2]
    level = grid.levels(axis)[k]
    if axis in ("groups", "crowd"):
        people = float(level)
    elif axis == "sensor":
        people = BASE_PEOPLE * (1.0 if level == "truth" else ROBOT_VIEW_COST)
    else:
        people = float(BASE_PEOPLE)
    return people * grid.seeds


# ------------------------------------------------------------------------------------------------
# Results


@dataclass(frozen=True)
class StressPoint:
    """One point of every detector's curves.

    Attributes:
        value: the level as a number (the sensor's index in :data:`SENSORS` order).
        label: the level as text.
        episodes: test episodes scored.
        frames: annotated frames scored.
        people_per_frame: mean people (robot included) per frame.
        people_per_m2: crowd density: humans in the room per m², mean over episodes.
        fformations_per_frame: mean true F-formations per frame.
        fformation_size: mean size of the true F-formations (NaN when there are none).
        scores: detector -> threshold (``"2/3"``, ``"1"``) -> precision, recall, F1 with intervals.
        pairwise_accuracy: detector -> share of pairs labelled correctly.
        notes: seeds the scenario could not be made with (each drawn again with another seed;
            an episode is missing only when every redraw failed).
        temporal: with ``temporal=True``, detector -> its group events scored in time, pooled
            over the episodes (`reform.evaluate_events`): ``true_events``, ``detected_events``,
            ``recall``, ``precision``, ``latency_median_s``, ``latency_p95_s``,
            ``false_events_per_minute``, ``identity_switches``, ``tolerance_s``.
    """

    value: float
    label: str
    episodes: int
    frames: int
    people_per_frame: float
    people_per_m2: float
    fformations_per_frame: float
    fformation_size: float
    scores: Mapping[str, Mapping[str, ScoreIntervals]]
    pairwise_accuracy: Mapping[str, float]
    notes: tuple[str, ...] = ()
    temporal: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        out = json_record(self)
        if not self.temporal:
            out.pop("temporal", None)
        return out


@dataclass(frozen=True)
class StressAxis:
    """One stress axis: its points, in level order."""

    name: str
    title: str
    x_label: str
    description: str
    points: tuple[StressPoint, ...]

    @property
    def x(self) -> np.ndarray:
        return np.array([p.value for p in self.points], dtype=np.float64)

    def curve(self, detector: str, threshold: str = "2/3", *, score: str = "f1") -> np.ndarray:
        """(3, k) value, low, high of ``score`` along the axis (NaN where no frame was scored)."""
        out = np.full((3, len(self.points)), np.nan)
        for k, point in enumerate(self.points):
            if detector in point.scores:
                interval = getattr(point.scores[detector][threshold], score)
                out[:, k] = (interval.value, interval.low, interval.high)
        return out

    def to_json(self) -> dict[str, Any]:
        return json_record(self)


@dataclass(frozen=True)
class StressResults:
    """Everything a stress run measured.

    Attributes:
        grid: the levels and sizes.
        grid_name: ``"default"``, ``"small"`` or ``"custom"``.
        seed: master seed.
        jobs: worker processes used.
        axes: one :class:`StressAxis` per axis run.
        training: what the detectors were trained on, and GCFF's tuned setting.
        timings: wall-clock seconds per stage and in total.
        environment: the machine: ``cores`` and ``load_average_start`` (1, 5, 15 minutes).
        detectors: every detector run, name -> label: :data:`DETECTOR_LABELS`, then the
            plugins (labelled by their names).
    """

    grid: StressGrid
    grid_name: str
    seed: int
    jobs: int
    axes: tuple[StressAxis, ...]
    training: Mapping[str, Any]
    timings: Mapping[str, float] = field(default_factory=dict)
    environment: Mapping[str, Any] = field(default_factory=dict)
    detectors: Mapping[str, str] = field(default_factory=lambda: dict(DETECTOR_LABELS))

    def axis(self, name: str) -> StressAxis:
        for axis in self.axes:
            if axis.name == name:
                return axis
        raise KeyError(f"axis {name!r} was not run (axes {[a.name for a in self.axes]})")

    def to_json(self, *, command: str | None = None) -> dict[str, Any]:
        return {
            "kind": "reform-sim/stress",
            "schema_version": 1,
            "command": command,
            "grid_name": self.grid_name,
            "grid": self.grid.to_json(),
            "seed": self.seed,
            "jobs": self.jobs,
            "detectors": dict(self.detectors),
            "sensors": dict(_SENSOR_TEXT),
            "training": _jsonable(self.training),
            "timings_s": {k: round(v, 2) for k, v in self.timings.items()},
            "environment": _jsonable(self.environment),
            "axes": [a.to_json() for a in self.axes],
        }


def _jsonable(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return json_float(float(value))
    return value


def _point(
    axis: str,
    k: int,
    level: Any,
    scored: list[_Scored],
    notes_: list[str],
    *,
    seed: int,
    axis_index: int,
    resamples: int,
) -> StressPoint:
    value = float(list(SENSORS).index(level)) if axis == "sensor" else float(level)
    label = str(level) if axis == "sensor" else f"{level:g}"
    if not scored:
        nan = math.nan
        return StressPoint(value, label, 0, 0, nan, nan, nan, nan, {}, {}, tuple(notes_))
    sequence = [s for part in scored for s in part.sequence]
    frames = len(sequence)
    weights = bootstrap_weights(
        sequence, rng=derive_rng(seed, Role.STRESS_BOOTSTRAP, axis_index, k), resamples=resamples
    )
    detectors = list(dict.fromkeys(d for d, _ in scored[0].precision))  # in the run's order
    n_sequences = len(set(sequence))
    scores = {
        d: {
            t: frame_intervals(
                np.concatenate([part.precision[d, t] for part in scored]),
                np.concatenate([part.recall[d, t] for part in scored]),
                weights=weights,
                sequences=n_sequences,
            )
            for t in THRESHOLDS
        }
        for d in detectors
    }
    pairs = sum(part.pairs for part in scored)
    accuracy = {
        d: (sum(part.pairs_correct[d] for part in scored) / pairs if pairs else math.nan)
        for d in detectors
    }
    ff = sum(part.fformations for part in scored)
    temporal = {d: _pooled([part.events.get(d, {}) for part in scored]) for d in detectors}
    return StressPoint(
        value=value,
        label=label,
        episodes=len(scored),
        frames=frames,
        people_per_frame=sum(part.people for part in scored) / frames,
        people_per_m2=float(np.mean([part.density for part in scored])),
        fformations_per_frame=ff / frames,
        fformation_size=sum(part.fformation_members for part in scored) / ff if ff else math.nan,
        scores=scores,
        pairwise_accuracy=accuracy,
        notes=tuple(notes_),
        temporal={d: v for d, v in temporal.items() if v},
    )


def _pooled(counts: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """One detector's event counts of a point's episodes pooled: recall and precision over all
    events, latency percentiles over all matches, false events per minute over all minutes."""
    counts = [c for c in counts if c]
    if not counts:
        return {}
    true = sum(c["true"] for c in counts)
    detected = sum(c["detected"] for c in counts)
    matched = sum(c["matched"] for c in counts)
    minutes = sum(c["minutes"] for c in counts)
    latency = np.array([x for c in counts for x in c["latency"]], dtype=np.float64)
    return {
        "true_events": true,
        "detected_events": detected,
        "recall": matched / true if true else None,
        "precision": matched / detected if detected else None,
        "latency_median_s": float(np.median(latency)) if latency.size else None,
        "latency_p95_s": float(np.percentile(latency, 95)) if latency.size else None,
        "false_events_per_minute": sum(c["false"] for c in counts) / minutes if minutes else None,
        "identity_switches": sum(c["switches"] for c in counts),
        "tolerance_s": max(c["tolerance_s"] for c in counts),
    }


# ------------------------------------------------------------------------------------------------
# Parallel map


def _cpu_count() -> int:
    return cpu_count()


def _load_average() -> list[float] | None:
    try:
        return [round(v, 2) for v in os.getloadavg()]
    except OSError:  # pragma: no cover - not every platform has one
        return None


def _timed(function: Callable[..., Any], item: Any, *shared: Any) -> tuple[Any, float]:
    """``function(item, *shared)`` and the CPU seconds it took."""
    start = time.process_time()
    result = function(item, *shared)
    return result, time.process_time() - start


def _parallel(
    function: Callable[..., Any],
    items: Sequence[Any],
    *,
    executor: Executor,
    shared: Sequence[Any] = (),
    progress: Callable[[int, int], None] | None = None,
    cpu: list[float] | None = None,
) -> list[Any]:
    """``function(item, *shared)`` over ``items``, in order, run by ``executor``.

    The CPU seconds of every call are appended to ``cpu`` when it is given.
    """

    def done(k: int, total: int, _result: Any) -> None:
        if progress is not None:
            progress(k, total)

    timed = executor.map(
        functools.partial(_timed, function), items, shared=tuple(shared), on_done=done
    )
    if cpu is not None:
        cpu.extend(seconds for _, seconds in timed)
    return [result for result, _ in timed]


# ------------------------------------------------------------------------------------------------
# The run


def run_stress(
    grid: StressGrid | str = "default",
    *,
    seed: int = 0,
    jobs: int | None = None,
    axes: Sequence[str] | None = None,
    detectors: Mapping[str, Any] | None = None,
    plugins: Mapping[str, Any] | None = None,
    progress: Callable[[str], None] | None = None,
    executor: Executor | None = None,
    temporal: bool = False,
    detector_timeout: float | None = None,
) -> StressResults:
    """Runs the stress tests.

    Every stage splits into independent units (an episode, a detector's fit, a scoring task)
    that ``executor`` runs: local processes (``jobs`` of them) by default, or Ray tasks
    (`sim.executor.Executor`); the results are the same bit for bit whichever runs them.

    Args:
        grid: a :class:`StressGrid` or the name of one of :data:`GRIDS`.
        seed: master seed of training episodes, test episodes, perturbations and bootstrap.
        jobs: local worker processes (None: every core). Results do not depend on it.
        axes: axes to run (names of :data:`AXES`), default all.
        detectors: fitted detectors by name (:data:`DETECTORS` keys) instead of training them
            on the synthetic training set; e.g. REFORM trained on SALSA.
        plugins: detectors of your own by name, run beside the built-in ones: any object with
            ``predict(frames)`` (`reform.detectors.Detector`), e.g. from
            `reform.detectors.make_detector`. One with ``fit`` is fitted on a copy of the
            synthetic training set's frames (the caller's object is left as it was). Their
            output is checked (`reform.detectors.run_detector`): a plugin that raises or
            returns something that is not a partition fails the run with one line naming it
            and the frame.
        progress: called with one line of text as stages start and tasks finish.
        executor: where the units run, instead of ``jobs`` local processes.
        temporal: also score every detector's group events in time at every point
            (`StressPoint.temporal`).
        detector_timeout: seconds each detector may take to predict a frame
            (`reform.detectors.run_detector`'s ``deadline_s``; None: its default, scaled by the
            people in the frame).

    Returns:
        The curves with their confidence intervals, the training summary and the timings.
    """
    grid_name, grid = resolve_grid(grid)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an int >= 0, got {seed!r}")
    if jobs is not None and (isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1):
        raise ValueError(f"jobs must be None or an int >= 1, got {jobs!r}")
    names = tuple(AXES) if axes is None else tuple(check_axis(a) for a in axes)
    executor = _executor(jobs, executor)
    workers = executor.workers
    say = progress if progress is not None else (lambda _line: None)
    timings: dict[str, float] = {}
    start = time.perf_counter()
    environment: dict[str, Any] = {
        "cores": _cpu_count(),
        "backend": executor.backend,
        "load_average_start": _load_average(),
    }
    cpu: list[float] = []

    plugins = dict(plugins or {})
    clash = [name for name in plugins if name in DETECTORS]
    if clash:
        raise ValueError(
            f"plugins must be named apart from the built-in detectors {DETECTORS}, got {clash}"
        )
    if detectors is not None:
        missing = [d for d in DETECTORS if d not in detectors]
        if missing:
            raise ValueError(f"detectors must hold {DETECTORS}, missing {missing}")
    learners = [name for name, plugin in plugins.items() if getattr(plugin, "fit", None)]

    test_seeds = [derive_int(seed, Role.STRESS_TEST, i) for i in range(grid.seeds)]
    training: dict[str, Any] = {}
    train: tuple[Frame, ...] = ()
    if detectors is None or learners:
        say(
            f"training set: {grid.train_episodes} episode(s) each of "
            f"{', '.join(TRAINING_SCENARIOS)} ({grid.train_duration_s:g} s at "
            f"{grid.train_rate_hz:g} Hz)"
        )
        t0 = time.perf_counter()
        specs = _training_specs(
            seed, grid.train_episodes, grid.train_duration_s, grid.train_rate_hz, TRAINING_SCENARIOS
        )
        train = _simulate_all(specs, executor=executor, cpu=cpu)
        train_seeds = {
            name: [spec.seed for spec in specs if spec.scenario == name]
            for name in TRAINING_SCENARIOS
        }
        overlap = set(test_seeds) & {x for seeds in train_seeds.values() for x in seeds}
        if overlap:  # pragma: no cover - 63-bit seeds from distinct spawn keys
            raise RuntimeError(f"test and training seeds overlap: {sorted(overlap)}")
        timings["training set"] = time.perf_counter() - t0
    if detectors is None:
        say(f"training REFORM (3 classifiers) and tuning GCFF on {len(train)} frames")
        t0 = time.perf_counter()
        detectors = _fit_all(train, grid, DETECTORS, executor=executor, cpu=cpu)
        timings["training"] = time.perf_counter() - t0
        gcff = detectors[GCFF]
        training = {
            "source": "synthetic",
            "scenarios": list(TRAINING_SCENARIOS),
            "episode_seeds": train_seeds,
            "frames": len(train),
            "pairs": detectors[WEIGHTED_KNN].training_summary_["pairs"],
            "together_pairs": detectors[WEIGHTED_KNN].training_summary_["together_pairs"],
            "gcff_stride_m": gcff.stride_,
            "gcff_mdl_m2": gcff.mdl_,
            "gcff_tuning_frames": gcff.grid_search_.n_frames,
            "gcff_tuning_f1": gcff.grid_search_.best_f1,
        }
    else:
        training = {"source": "given"}
    if learners:
        say(f"fitting {', '.join(learners)} on {len(train)} frames")
        t0 = time.perf_counter()
        plugins = {name: fit_detector(name, plugin, train) for name, plugin in plugins.items()}
        timings["fitting plugins"] = time.perf_counter() - t0
    if plugins:
        training["plugins"] = {
            name: (
                f"fitted on the {len(train)} synthetic training frames"
                if name in learners
                else "no fit: run as given"
            )
            for name in plugins
        }
    labels = {name: DETECTOR_LABELS.get(name, name) for name in [*detectors, *plugins]}
    detectors = {**detectors, **plugins}
    training["test_seeds"] = test_seeds

    perturb_axes = [a for a in names if AXES[a].kind == "perturb"]
    scene_axes = [a for a in names if AXES[a].kind == "scene"]
    base: list[tuple[tuple[Frame, ...], float]] = []
    t0 = time.perf_counter()
    if perturb_axes:
        say(f"simulating {grid.seeds} test episode(s) of {TEST_SCENARIO}")
        specs = [_scene_spec(grid, None, None, s) for s in test_seeds]
        base = _parallel(_simulate_scene, specs, executor=executor, cpu=cpu)
    timings["test episodes"] = time.perf_counter() - t0

    axis_index = {name: list(AXES).index(name) for name in names}
    tasks: list[tuple[Callable[..., Any], tuple[Any, ...]]] = []
    for name in perturb_axes:
        for e, episode in enumerate(base):
            tasks.append((_perturb_task, (grid, name, axis_index[name], e, episode, seed)))
    for name in scene_axes:
        for k in range(len(grid.levels(name))):
            tasks.append((_scene_task, (grid, name, k, seed)))
    # Longest first, so that no long task starts last; the results do not depend on the order.
    tasks.sort(key=lambda task: -_cost(grid, task))
    say(f"scoring {len(tasks)} task(s) on {min(workers, max(len(tasks), 1))} worker(s)")
    t0 = time.perf_counter()

    def report(done: int, total: int) -> None:
        say(f"  {done}/{total} tasks done ({time.perf_counter() - start:.0f} s)")

    # The detectors are shared by every task: sent once to each worker (Ray: once in all).
    results = _parallel(
        _call,
        tasks,
        shared=(detectors, bool(temporal), detector_timeout),
        executor=executor,
        progress=report,
        cpu=cpu,
    )
    timings["scoring"] = time.perf_counter() - t0

    cells: dict[tuple[str, int], list[tuple[int, _Scored | str]]] = {}
    for batch in results:
        for axis, k, episode, scored in batch:
            cells.setdefault((axis, k), []).append((episode, scored))
    out_axes = []
    for name in names:
        points = []
        for k, level in enumerate(grid.levels(name)):
            entries = sorted(cells.get((name, k), []), key=lambda item: item[0])
            scored = [s for _, s in entries if isinstance(s, _Scored)]
            notes_ = [s for _, s in entries if isinstance(s, str)]
            notes_ += [n for s in scored for n in s.notes]
            points.append(
                _point(
                    name,
                    k,
                    level,
                    scored,
                    notes_,
                    seed=seed,
                    axis_index=axis_index[name],
                    resamples=grid.resamples,
                )
            )
        info = AXES[name]
        out_axes.append(
            StressAxis(info.name, info.title, info.x_label, info.description, tuple(points))
        )
    timings["total"] = time.perf_counter() - start
    environment["cpu_s"] = round(sum(cpu), 2)
    environment["load_average_end"] = _load_average()
    return StressResults(
        grid=grid,
        grid_name=grid_name,
        seed=int(seed),
        jobs=workers,
        axes=tuple(out_axes),
        training=training,
        timings=timings,
        environment=environment,
        detectors=labels,
    )


def _call(
    task: tuple[Callable[..., Any], tuple[Any, ...]],
    detectors: Mapping[str, Any],
    temporal: bool = False,
    deadline_s: float | None = None,
) -> Any:
    function, args = task
    return function(*args, detectors, temporal, deadline_s)


def sensor_description(name: str) -> str:
    """One line on sensor level ``name``."""
    return _SENSOR_TEXT[name]
