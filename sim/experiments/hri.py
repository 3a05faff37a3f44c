"""The REFORM paper's HRI proof of concept, re-enacted in simulation.

The paper recorded three scripted scenes with the Directions Robot (a Kinect and a wide-angle
camera on the robot, skeleton tracking), annotated 100 frames picked at random from the 3,091
recorded, and reported P / R / F1 at T = 2/3 of REFORM trained on SALSA only (all three
classifiers: 75.7 / 100 / 86.2) and of GCFF (51.5 / 63.6 / 56.9). Here the three scenes are the
registered scenarios ``hri-conversation`` (two people and the robot: an F-formation of three),
``hri-robot-excluded`` (two people talk in front of the robot: an F-formation of two) and
``hri-passing`` (people walk past: no F-formation), simulated with several seeds each and scored
from three views of the same episodes:

* ``truth``: the ground truth of everyone in the room (robot included);
* ``robot``: the robot's head sensor (`sim.sensor.Sensor`: Kinect field of view 57 degrees,
  0.5-4.5 m, occlusion by MuJoCo rays) with Kinect-like tracking errors (the ``tracker`` level
  of :mod:`sim.experiments.stress`);
* ``robot-wide``: the same with a 180-degree field of view, standing in for the wide-angle
  camera the paper's robot also carried.

The robot is in every frame at its true pose (it knows where it is); the ground truth of an
observed frame is the truth restricted to the people observed.

Detectors: REFORM with each of the paper's classifiers trained on the SALSA training split
(``reform.time_split``, the first 60 % of each session by time; default hyper-parameters of
``reform.classifiers``), as the paper trained on SALSA only, when SALSA is given; REFORM with the
same classifiers trained on the synthetic training set of
:func:`sim.experiments.stress.training_frames` (``mingle`` and ``word-improv``, seeds disjoint from
the HRI episodes'); GCFF at the paper's setting (stride 0.7 m, mdl 30,000 cm² = 3 m²) and at the
reference code's default (0.7 m, 1 m²); and the majority baseline (no groups).

Degenerate frames (the protocol of :mod:`reform.metrics`): a frame with no true F-formation has
recall 1 whatever is detected, and precision 1 if nothing is detected, else 0. Every frame of
``hri-passing`` is such a frame, and so are the frames of the other two scenes before the group
has formed and after it dissolves. Recall on them is 1 by convention, so a detector's recall
pooled over the three scenes is lifted by them, and its precision is the share of those frames it
leaves empty; the majority baseline scores perfectly on ``hri-passing``. The paper's recall of
100 is what a detector that never misses a true group gets under these conventions.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

import reform.classifiers
import scenarios
from reform.bootstrap import ScoreIntervals, bootstrap_weights, score_intervals
from reform.classifiers import BAGGED_TREES, WEIGHTED_KNN
from reform.detectors import make_detector, run_detector
from reform.frame import Frame
from reform.gcff import MDL_M2, STRIDE_M
from reform.json_values import json_record
from reform.metrics import Evaluation, evaluate
from reform.seeding import Role, derive_int, derive_rng
from reform.splits import DEFAULT_TRAIN_FRACTION, time_split
from sim.episode import DEFAULT_RATE_HZ, simulate_episode
from sim.executor import Executor
from sim.experiments.gcff import PAPER_MDL_M2, PAPER_STRIDE_M
from sim.experiments.hri_views import DEFAULT_SEEDS, VIEW_NAMES
from sim.experiments.stress import (
    DETECTOR_LABELS,
    THRESHOLDS,
    TRACKER_DROPOUT,
    TRACKER_POSITION_NOISE_M,
    TRACKER_YAW_NOISE_RAD,
    StressGrid,
    resolve_grid,
    train_detectors,
    training_frames,
)
from sim.recording import FieldOfView, record_episode
from sim.sensor import Sensor

__all__ = [
    "HRI_SCENARIOS",
    "PAPER_HRI",
    "VIEWS",
    "HriDetector",
    "HriExperiment",
    "HriRow",
    "baseline_detectors",
    "hri_detectors",
    "hri_episodes",
    "hri_experiment",
    "record_scenes",
    "reform_detectors",
]

HRI_SCENARIOS = scenarios.PAPER_HRI_SCENES  # the paper's three scenes: a fixed set, not a tag
ALL = "all"  # the three scenes pooled, as the paper's 100 frames were
WIDE_FOV_DEG = 180.0  # degrees, the robot-wide view's field of view
VIEWS: Mapping[str, Sensor | None] = MappingProxyType(
    dict(
        zip(
            VIEW_NAMES,
            (
                None,
                Sensor(
                    position_noise=TRACKER_POSITION_NOISE_M,
                    yaw_noise=TRACKER_YAW_NOISE_RAD,
                    dropout=TRACKER_DROPOUT,
                ),
                Sensor(
                    fov_deg=WIDE_FOV_DEG,
                    position_noise=TRACKER_POSITION_NOISE_M,
                    yaw_noise=TRACKER_YAW_NOISE_RAD,
                    dropout=TRACKER_DROPOUT,
                ),
            ),
            strict=True,
        )
    )
)
VIEW_TEXT = {
    "truth": "ground truth of everyone in the room",
    "robot": (
        "the robot's head sensor (57 deg, 0.5-4.5 m, occlusion) with tracking errors "
        f"({TRACKER_POSITION_NOISE_M} m, {math.degrees(TRACKER_YAW_NOISE_RAD):g} deg, "
        f"{TRACKER_DROPOUT:.0%} dropout)"
    ),
    "robot-wide": f"as robot, with a {WIDE_FOV_DEG:g} deg field of view",
}
# The paper's HRI proof of concept, T = 2/3, P / R / F1 in % (definitions.md).
PAPER_HRI: Mapping[str, tuple[float, float, float]] = MappingProxyType(
    {"REFORM (each of the three classifiers)": (75.7, 100.0, 86.2), "GCFF": (51.5, 63.6, 56.9)}
)
CLASSIFIERS = tuple(
    reform.classifiers.CLASSIFIERS
)  # the paper's three, as reform.classifiers names them
# Training data of REFORM: key suffix -> (label suffix, "trained on" column).
_TRAINING = {
    "salsa": ("SALSA-trained", "SALSA train"),
    "synthetic": ("synthetic-trained", "synthetic"),
}


@dataclass(frozen=True)
class HriDetector:
    """A fitted detector with its key, display name and training data (``"-"`` for none)."""

    key: str
    label: str
    training: str
    detector: Any


def reform_detectors(fitted: Mapping[str, Any], *, training: str) -> list[HriDetector]:
    """REFORM with each fitted classifier of ``fitted`` (classifier name -> fitted
    ``reform.Reform``), trained on ``training`` (``"salsa"`` or ``"synthetic"``), in order."""
    if training not in _TRAINING:
        raise ValueError(f"training must be one of {tuple(_TRAINING)}, got {training!r}")
    label, trained_on = _TRAINING[training]
    return [
        HriDetector(f"{name}@{training}", f"{DETECTOR_LABELS[name]}, {label}", trained_on, model)
        for name, model in fitted.items()
    ]


def salsa_training(model: Any, train_fraction: float) -> dict[str, Any]:
    """What the HRI page says of a model trained on SALSA's training split: its frames, the
    share of each session they are (``train_fraction``) and its training pairs."""
    summary = model.training_summary_
    return {
        "frames": summary["frames"],
        "train_fraction": train_fraction,
        "pairs": summary["pairs"],
    }


def baseline_detectors(*, reference: bool = True) -> list[HriDetector]:
    """The untrained detectors, from the detector registry (`reform.detectors.make_detector`):
    GCFF at the paper's setting (`sim.experiments.gcff.PAPER_STRIDE_M`, ``PAPER_MDL_M2``), at
    the reference code's default (`reform.gcff.STRIDE_M`, ``MDL_M2``; with ``reference``) and
    the majority baseline."""
    out = [
        HriDetector(
            "gcff@paper",
            "GCFF, paper setting (70 cm, 30000 cm²)",
            "-",
            make_detector("gcff", stride=PAPER_STRIDE_M, mdl=PAPER_MDL_M2),
        )
    ]
    if reference:
        out.append(
            HriDetector(
                "gcff@reference",
                "GCFF, reference default (70 cm, 10000 cm²)",
                "-",
                make_detector("gcff", stride=STRIDE_M, mdl=MDL_M2),
            )
        )
    out.append(HriDetector("majority", "Majority (no groups)", "-", make_detector("majority")))
    return out


def hri_episodes(
    *,
    seed: int,
    seeds: int = DEFAULT_SEEDS,
    rate: float = DEFAULT_RATE_HZ,
    views: Sequence[str] = tuple(VIEWS),
    executor: Executor | None = None,
) -> dict[tuple[str, str], list[tuple[Frame, ...]]]:
    """The HRI episodes, each seen from every view.

    Episode ``i`` of scenario ``s`` has seed ``derive_int(seed, Role.HRI_EPISODE, s, i)``
    (`reform.seeding`); the views of one episode are the same simulation (the world does not
    depend on the sensor). Each episode is a unit of work run by ``executor`` (default: in
    this process); the frames do not depend on it.

    Returns:
        ``(scenario, view) -> one tuple of frames per episode``.
    """
    unknown = [v for v in views if v not in VIEWS]
    if unknown:
        raise ValueError(f"views must be among {tuple(VIEWS)}, got {unknown}")
    views = tuple(views)
    units = [
        (scenario, derive_int(seed, Role.HRI_EPISODE, s, i), rate, views)
        for s, scenario in enumerate(HRI_SCENARIOS)
        for i in range(seeds)
    ]
    executor = Executor("local", jobs=1) if executor is None else executor
    out: dict[tuple[str, str], list[tuple[Frame, ...]]] = {}
    seen_all = executor.map(_hri_episode, units, desc="HRI episodes", unit="episode")
    for (scenario, *_), seen in zip(units, seen_all, strict=True):
        for view, frames in seen:
            out.setdefault((scenario, view), []).append(frames)
    return out


def _hri_episode(
    unit: tuple[str, int, float, tuple[str, ...]],
) -> list[tuple[str, tuple[Frame, ...]]]:
    """One HRI episode, ``(scenario, seed, rate, views)``, seen from each view: the robot's
    views in ``views`` order, then the truth."""
    scenario, episode, rate, views = unit
    out: list[tuple[str, tuple[Frame, ...]]] = []
    truth: tuple[Frame, ...] | None = None
    for view in views:
        sensor = VIEWS[view]
        if sensor is None:
            continue
        run = simulate_episode(scenario, seed=episode, rate=rate, view="robot", sensor=sensor)
        out.append((view, run.dataset.frames))
        truth = run.truth
    if "truth" in views:
        if truth is None:
            truth = simulate_episode(scenario, seed=episode, rate=rate).dataset.frames
        out.append(("truth", truth))
    return out


def hri_detectors(
    *,
    salsa: Sequence[Frame] | None,
    seed: int,
    train_fraction: float = DEFAULT_TRAIN_FRACTION,
    grid: StressGrid | str = "default",
    jobs: int | None = None,
    progress: Callable[[str], None] | None = None,
    executor: Executor | None = None,
) -> tuple[list[HriDetector], dict[str, Any]]:
    """The detectors of the experiment, fitted, and what they were trained on.

    Args:
        salsa: SALSA's frames, to train REFORM on its training split; None: no SALSA rows.
        seed: master seed of the synthetic training set.
        train_fraction: share of each SALSA session's annotated frames, by time, for training.
        grid: the size of the synthetic training set (``train_*`` fields of a
            :class:`sim.experiments.stress.StressGrid`, or a name of
            :data:`sim.experiments.stress.GRIDS`).
        jobs: local worker processes (None: every core).
        progress: called with one line of text per stage.
        executor: where the episodes and fits run (`sim.executor.Executor`), instead of
            ``jobs`` local processes.

    Returns:
        The detectors (SALSA-trained REFORM, synthetic-trained REFORM, GCFF twice, majority)
        and a summary of the training data.
    """
    say = progress or (lambda _line: None)
    if executor is None:
        executor = Executor("local", jobs=jobs)
    elif jobs is not None:
        raise ValueError(f"jobs is for local processes; give it or executor, got both ({jobs})")
    detectors: list[HriDetector] = []
    info: dict[str, Any] = {}
    if salsa is not None:
        annotated = [f for f in salsa if f.groups is not None]
        train, _ = time_split(annotated, train_fraction)
        say(f"training REFORM on the SALSA training split ({len(train)} frames)")
        fitted = train_detectors(train, names=CLASSIFIERS, executor=executor)
        detectors += reform_detectors(fitted, training="salsa")
        info["salsa"] = salsa_training(fitted[WEIGHTED_KNN], train_fraction)
    _, grid = resolve_grid(grid)
    say(
        f"simulating the synthetic training set ({grid.train_episodes} episodes each of mingle "
        "and word-improv)"
    )
    synthetic = training_frames(
        seed=seed,
        episodes=grid.train_episodes,
        duration=grid.train_duration_s,
        rate=grid.train_rate_hz,
        executor=executor,
    )
    say(f"training REFORM on the synthetic training set ({len(synthetic)} frames)")
    fitted = train_detectors(synthetic, names=CLASSIFIERS, executor=executor)
    detectors += reform_detectors(fitted, training="synthetic")
    info["synthetic"] = {
        "frames": len(synthetic),
        "episodes_per_scenario": grid.train_episodes,
        "duration_s": grid.train_duration_s,
        "rate_hz": grid.train_rate_hz,
        "pairs": fitted[WEIGHTED_KNN].training_summary_["pairs"],
        "seed": seed,
    }
    detectors += baseline_detectors()
    return detectors, info


@dataclass(frozen=True)
class HriRow:
    """One detector on one view of one scenario (or of all three pooled).

    Attributes:
        detector: key, e.g. ``"bagged-trees@salsa"``.
        label: display name.
        training: ``"SALSA train"``, ``"synthetic"`` or ``"-"``.
        view: one of :data:`VIEWS`.
        scenario: one of :data:`HRI_SCENARIOS` or ``"all"``.
        scores: threshold (``"2/3"``, ``"1"``) -> P, R, F1 of the frame means with 95 % intervals.
        micro: threshold -> (P, R, F1) from TP, FP, FN summed over frames.
        pairwise_accuracy: share of pairs labelled correctly.
    """

    detector: str
    label: str
    training: str
    view: str
    scenario: str
    scores: Mapping[str, ScoreIntervals]
    micro: Mapping[str, tuple[float, float, float]]
    pairwise_accuracy: float

    def to_json(self) -> dict[str, Any]:
        # the micro scores are written as they are, not through json_float
        return json_record(self, micro={t: list(v) for t, v in self.micro.items()})


@dataclass(frozen=True)
class HriExperiment:
    """The experiment's results.

    Attributes:
        rows: every (detector, view, scenario) scored.
        views: views scored.
        seeds: episodes per scenario.
        seed: master seed.
        rate_hz: frames per second scored.
        data: per (view, scenario): frames, episodes, people per frame, share of frames with a
            true F-formation.
        training: what the REFORM models were trained on.
        timings: wall-clock seconds per stage.
    """

    rows: tuple[HriRow, ...]
    views: tuple[str, ...]
    seeds: int
    seed: int
    rate_hz: float
    data: Mapping[str, Mapping[str, Mapping[str, float]]]
    training: Mapping[str, Any]
    timings: Mapping[str, float] = field(default_factory=dict)

    def row(self, detector: str, view: str, scenario: str = ALL) -> HriRow:
        for row in self.rows:
            if (row.detector, row.view, row.scenario) == (detector, view, scenario):
                return row
        raise KeyError(f"no row for detector {detector!r}, view {view!r}, scenario {scenario!r}")

    @property
    def detectors(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(row.detector for row in self.rows))

    def to_json(self, *, command: str | None = None) -> dict[str, Any]:
        return {
            "kind": "reform-sim/hri-experiment",
            "schema_version": 1,
            "command": command,
            "seed": self.seed,
            "seeds": self.seeds,
            "rate_hz": self.rate_hz,
            "scenarios": list(HRI_SCENARIOS),
            "views": {v: VIEW_TEXT[v] for v in self.views},
            "paper": {k: list(v) for k, v in PAPER_HRI.items()},
            "data": {v: {s: dict(d) for s, d in by.items()} for v, by in self.data.items()},
            "training": self.training,
            "timings_s": {k: round(v, 2) for k, v in self.timings.items()},
            "rows": [row.to_json() for row in self.rows],
        }


def _micro(evaluation: Evaluation, threshold: str) -> tuple[float, float, float]:
    micro = evaluation.at(threshold).micro
    return (micro.precision, micro.recall, micro.f1)


def _rows(
    detector: HriDetector,
    view: str,
    frames_by: Mapping[str, Sequence[Frame]],
    *,
    seed: int,
    resamples: int,
) -> list[HriRow]:
    """The detector's rows on one view: each scene (``frames_by[scene]``) and all pooled.

    Raises:
        reform.detectors.DetectorError: one line naming the detector (its label), the view and
            the frame, when the detector raises or returns no partition of a frame.
    """
    name = f"{detector.label} ({view} view)"
    predictions = {s: run_detector(name, detector.detector, frames_by[s]) for s in HRI_SCENARIOS}
    out = []
    for k, scenario in enumerate((*HRI_SCENARIOS, ALL)):
        if scenario == ALL:
            frames = frames_by[ALL]
            predicted = [p for s in HRI_SCENARIOS for p in predictions[s]]
        else:
            frames, predicted = frames_by[scenario], predictions[scenario]
        evaluation = evaluate(frames, predicted)
        rng = derive_rng(seed, Role.HRI_BOOTSTRAP, k)
        weights = bootstrap_weights(evaluation.sequence, rng=rng, resamples=resamples)
        out.append(
            HriRow(
                detector=detector.key,
                label=detector.label,
                training=detector.training,
                view=view,
                scenario=scenario,
                scores={t: score_intervals(evaluation, t, weights=weights) for t in THRESHOLDS},
                micro={t: _micro(evaluation, t) for t in THRESHOLDS},
                pairwise_accuracy=evaluation.pairwise_accuracy,
            )
        )
    return out


def _data_summary(frames: Sequence[Frame], episodes: int) -> dict[str, float]:
    return {
        "episodes": episodes,
        "frames": len(frames),
        "people_per_frame": float(np.mean([f.n_people for f in frames])) if frames else math.nan,
        "frames_with_fformation": float(np.mean([bool(f.fformations()) for f in frames]))
        if frames
        else math.nan,
    }


def hri_experiment(
    *,
    salsa: Sequence[Frame] | None = None,
    seed: int = 0,
    seeds: int = DEFAULT_SEEDS,
    rate: float = DEFAULT_RATE_HZ,
    views: Sequence[str] = tuple(VIEWS),
    resamples: int = 1000,
    jobs: int | None = None,
    detectors: Sequence[HriDetector] | None = None,
    training: Mapping[str, Any] | None = None,
    progress: Callable[[str], None] | None = None,
    executor: Executor | None = None,
) -> HriExperiment:
    """Runs the HRI experiment.

    Args:
        salsa: SALSA's frames (``reform.datasets.load_salsa``) to train REFORM on its training
            split, as the paper did; None leaves the SALSA-trained rows out.
        seed: master seed (HRI episodes, synthetic training set, bootstrap).
        seeds: episodes per scenario.
        rate: frames per second.
        views: views to score (names of :data:`VIEWS`).
        resamples: bootstrap resamples.
        jobs: worker processes for training (None: every core).
        detectors: fitted detectors (from :func:`hri_detectors`) instead of training them.
        training: what ``detectors`` were trained on (the second value of
            :func:`hri_detectors`), for the report.
        progress: called with one line of text per stage.
        executor: where the training and the episodes run (`sim.executor.Executor`), instead
            of ``jobs`` local processes (the episodes: in this process without it).

    Returns:
        The rows, the data summary, the training summary and the timings.
    """
    if isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1:
        raise ValueError(f"seeds must be an int >= 1, got {seeds!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed must be an int >= 0, got {seed!r}")
    views = tuple(views)
    say = progress or (lambda _line: None)
    timings: dict[str, float] = {}
    start = time.perf_counter()
    if detectors is None:
        detectors, training = hri_detectors(
            salsa=salsa, seed=seed, jobs=jobs, progress=say, executor=executor
        )
        timings["training"] = time.perf_counter() - start
    training = dict(training or {})
    t0 = time.perf_counter()
    say(f"simulating {seeds} episode(s) of each HRI scenario, views {', '.join(views)}")
    episodes = hri_episodes(seed=seed, seeds=seeds, rate=rate, views=views, executor=executor)
    timings["simulation"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    rows: list[HriRow] = []
    data: dict[str, dict[str, dict[str, float]]] = {}
    for view in views:
        runs = {s: episodes[s, view] for s in HRI_SCENARIOS}
        frames_by = {s: [f for e in runs[s] for f in e] for s in HRI_SCENARIOS}
        frames_by[ALL] = [f for s in HRI_SCENARIOS for f in frames_by[s]]
        data[view] = {s: _data_summary(frames_by[s], len(runs[s])) for s in HRI_SCENARIOS}
        data[view][ALL] = _data_summary(frames_by[ALL], sum(map(len, runs.values())))
        say(f"scoring {len(detectors)} detectors on the {view} view")
        for detector in detectors:
            rows += _rows(detector, view, frames_by, seed=seed, resamples=resamples)
    timings["scoring"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - start
    return HriExperiment(
        rows=tuple(rows),
        views=views,
        seeds=seeds,
        seed=seed,
        rate_hz=float(rate),
        data=data,
        training=training,
        timings=timings,
    )


def record_scenes(
    detectors: Sequence[HriDetector],
    out_dir: str | Path,
    *,
    seed: int = 0,
    rate: float = DEFAULT_RATE_HZ,
    view: str = "robot",
) -> list[Path]:
    """One Rerun recording per HRI scene: its first episode, seen from ``view``, with detections.

    The detections are those of REFORM with bagged trees (SALSA-trained when present, else
    synthetic-trained) and GCFF at the paper's setting.

    Returns:
        The paths written, ``out_dir/<scenario>.rrd``.
    """
    if view not in VIEWS:
        raise ValueError(f"view must be one of {tuple(VIEWS)}, got {view!r}")
    by_key = {d.key: d for d in detectors}
    chosen = {}
    for key, name in (
        (f"{BAGGED_TREES}@salsa", "reform"),
        (f"{BAGGED_TREES}@synthetic", "reform"),
        ("gcff@paper", "gcff"),
    ):
        if key in by_key and name not in chosen:
            chosen[name] = by_key[key]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for s, scenario in enumerate(HRI_SCENARIOS):
        episode_seed_ = derive_int(seed, Role.HRI_EPISODE, s, 0)
        sensor = VIEWS[view]
        run = simulate_episode(
            scenario,
            seed=episode_seed_,
            rate=rate,
            view="truth" if sensor is None else "robot",
            sensor=sensor,
        )
        seen = run.dataset.frames
        path = out / f"{scenario}.rrd"
        record_episode(
            path,
            run.truth,
            observed=None if sensor is None else seen,
            detections={
                name: run_detector(d.label, d.detector, seen) for name, d in chosen.items()
            },
            events=run.events,
            model=run.model,
            seed=episode_seed_,
            name=f"{scenario} ({view} view)",
            field_of_view=FieldOfView.of(sensor),
        )
        paths.append(path)
    return paths
