"""The one-command demo (``reform-sim demo``): the whole toolkit on an embedded default, in minutes.

Stages, each announced on stderr:

1. **Scenarios.** Every registered scenario (``scenarios.names()``) is simulated briefly in
   MuJoCo (ground truth).
2. **Synthetic training set.** ``mingle`` and ``word-improv`` episodes generated as
   hive-partitioned Parquet (:func:`sim.generate.generate_dataset`) under ``OUT/synthetic``,
   with the recipe :mod:`sim.experiments.sim2real` recommends (``RECOMMENDED``: its
   scenarios and annotation models) at the demo's smaller budget, sources balanced by pairs.
3. **Training.** REFORM with the paper's three classifiers on the synthetic set (their
   ready-made hyper-parameters); the recommended classifier, with the recommended REFORM
   options, is saved as ``OUT/model.skops``. With SALSA at hand, the same classifier trained on
   SALSA's training split is added for reference.
4. **Evaluation.** REFORM and GCFF (the paper's setting) on held-back synthetic episodes (seeds
   never trained on) and, when the datasets are found, on the SALSA test split and every
   annotated Babble frame.
5. **Stress tests** on the small grid (:func:`sim.experiments.stress.run_stress`) with the demo's
   models.
6. **The paper's HRI experiment re-enacted** (:func:`sim.experiments.hri.hri_experiment`).
7. **Recordings and report.** One Rerun ``.rrd`` per scenario (people, groups, REFORM's and
   GCFF's detections, events), one per evaluation, the stress curves and the HRI scenes; a
   Markdown report with tables and PNG plots (``OUT/report.md``) and every number in
   ``OUT/results.json``.

The run returns a :class:`DemoResult` holding everything measured; its report
(:func:`sim.experiments.demo_report.write_report`) writes ``report.md`` and ``results.json``
from it. The same seed gives the same numbers; a second run in the same folder reuses the
generated episodes. ``quick=True`` shrinks every budget (for tests).
"""

from __future__ import annotations

import contextlib
import os
import platform
import shlex
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

import scenarios
from reform.classifiers import BAGGED_TREES, make_classifier
from reform.datasets import fetch, is_fetched, load_babble, load_salsa
from reform.detector import Reform
from reform.detectors import make_detector, run_detector
from reform.frame import Dataset, Frame
from reform.metrics import T_ONE, T_TWO_THIRDS, Evaluation, evaluate
from reform.persistence import save_model
from reform.splits import DEFAULT_TRAIN_FRACTION, time_split
from sim.episode import simulate_episode
from sim.executor import Executor
from sim.experiments.demo_files import DEFAULT_OUT, FIGURES, MODEL, RECORDINGS, SYNTHETIC
from sim.experiments.figures import Bar, score_bars, top_view
from sim.experiments.gcff import PAPER_MDL_M2, PAPER_STRIDE_M
from sim.experiments.hri import (
    HriExperiment,
    baseline_detectors,
    hri_experiment,
    record_scenes,
    reform_detectors,
    salsa_training,
)
from sim.experiments.hri_report import to_markdown as hri_markdown
from sim.experiments.report_files import write_markdown
from sim.experiments.sim2real import RECOMMENDED, recipe
from sim.experiments.stress import GCFF as STRESS_GCFF
from sim.experiments.stress import GRIDS, StressResults, run_stress
from sim.experiments.stress_report import record as record_stress
from sim.experiments.stress_report import write_report as write_stress
from sim.experiments.synthetic import (
    SyntheticSource,
    balance_pairs,
    count_pairs,
    even_subset,
    generate_sources,
)
from sim.progress import elapsed_line
from sim.recording import record_episode, record_evaluation
from sim.ticking import ticking

__all__ = [
    "DEFAULT_OUT",
    "DemoBudget",
    "DemoResult",
    "FULL",
    "QUICK",
    "run_demo",
]

HELD_BACK_SEED_OFFSET = 1_000_003  # held-back episodes: master seed + this (never trained on)
CLASSIFIERS = ("bagged-trees", "weighted-knn", "logistic-regression")
SAVED_CLASSIFIER = RECOMMENDED.classifier  # the sim-to-real experiment's; saved as model.skops
GCFF_LABEL = "GCFF (paper: 70 cm, 30000 cm²)"
MAJORITY_LABEL = "Majority"
CLASSIFIER_TEXT = {
    "bagged-trees": "Bagged Trees",
    "weighted-knn": "Weighted KNN",
    "logistic-regression": "Logistic Regression",
}


def recommended_sources(
    *, episodes: int, duration: float, rate: float | None = None
) -> tuple[SyntheticSource, ...]:
    """The recommended recipe's sources (`sim.experiments.sim2real.RECOMMENDED`) at a budget:
    ``episodes`` episodes of ``duration`` seconds each (at ``rate`` Hz, else the recipe's)."""
    return tuple(
        replace(s, episodes=episodes, duration=duration, rate=s.rate if rate is None else rate)
        for s in recipe(RECOMMENDED.recipe).sources
    )


@dataclass(frozen=True)
class DemoBudget:
    """How much the demo simulates and scores.

    Attributes:
        name: ``"full"`` or ``"quick"``.
        scenario_s: seconds of each registered scenario simulated for its recording.
        train: the synthetic training set's sources.
        held_back: the held-back synthetic sources (another master seed).
        stress_grid: a name of :data:`sim.experiments.stress.GRIDS` or a ``StressGrid``.
        stress_axes: stress axes run (None: all).
        hri_seeds: episodes per HRI scene.
        hri_views: views of the HRI experiment.
        resamples: bootstrap resamples (stress, HRI).
        real_frames: annotated real frames scored at most per dataset (None: all), evenly
            spaced in time.
        salsa_train_frames: SALSA training frames the SALSA-trained model learns from at most
            (None: the whole training split), evenly spaced in time.
    """

    name: str
    scenario_s: float
    train: tuple[SyntheticSource, ...]
    held_back: tuple[SyntheticSource, ...]
    stress_grid: Any
    stress_axes: tuple[str, ...] | None
    hri_seeds: int
    hri_views: tuple[str, ...]
    resamples: int
    real_frames: int | None = None
    salsa_train_frames: int | None = None


FULL = DemoBudget(
    name="full",
    scenario_s=60.0,
    train=recommended_sources(episodes=4, duration=300.0),
    held_back=(
        SyntheticSource("mingle", episodes=2, duration=300.0),
        SyntheticSource("word-improv", episodes=2),
    ),
    stress_grid="small",
    stress_axes=None,
    hri_seeds=2,
    hri_views=("truth", "robot"),
    resamples=200,
)

QUICK = DemoBudget(
    name="quick",
    scenario_s=15.0,
    train=recommended_sources(episodes=1, duration=90.0, rate=0.5),
    held_back=(
        SyntheticSource("mingle", episodes=1, duration=60.0, rate=0.5),
        SyntheticSource("word-improv", episodes=1, duration=120.0, rate=0.5),
    ),
    stress_grid="quick",
    stress_axes=("position-noise",),
    hri_seeds=1,
    hri_views=("truth",),
    resamples=50,
    real_frames=60,
    salsa_train_frames=120,
)


@dataclass(frozen=True)
class DemoResult:
    """What the demo did, measured and wrote: everything its report
    (:mod:`sim.experiments.demo_report`) puts in ``report.md`` and ``results.json``.

    Attributes:
        out_dir: the output folder.
        model: the saved REFORM model (skops).
        recordings: every ``.rrd`` written.
        figures: every PNG written.
        scores: ``(detector, dataset) -> Evaluation.to_json`` of every detector scored.
        timings: seconds per stage and in total.
        datasets: the real datasets found (``"salsa"``, ``"babble"``).
        budget: the budget run.
        seed: the master seed.
        command: the command line that reproduces the run.
        scenarios: per registered scenario, what its recording and figure show (people,
            seconds, groups per frame, REFORM's and GCFF's F1, the files).
        training: per synthetic source, the frames and pairs kept after balancing.
        tests: frames per test set.
        detectors: the detectors scored, in order.
        evaluations: ``(detector, test set) ->`` the scores the report tabulates.
        stress: the stress tests' results.
        stress_plots: per stress axis, its plot (relative to ``out_dir``).
        hri: the HRI re-enactment's results.
        machine: cores and platform of the machine that ran it.
    """

    out_dir: Path
    model: Path
    recordings: tuple[Path, ...]
    figures: tuple[Path, ...]
    scores: Mapping[tuple[str, str], Mapping[str, Any]]
    timings: Mapping[str, float]
    datasets: tuple[str, ...]
    budget: DemoBudget
    seed: int
    command: str
    scenarios: tuple[Mapping[str, Any], ...]
    training: Mapping[str, Mapping[str, int]]
    tests: Mapping[str, int]
    detectors: tuple[str, ...]
    evaluations: Mapping[tuple[str, str], Mapping[str, float]]
    stress: StressResults
    stress_plots: Mapping[str, str]
    hri: HriExperiment
    machine: Mapping[str, Any]


class _Stages:
    """Announces stages on a callback and times them; with ``show``, on a terminal, a line
    under a stage with its time so far (`_working`), redrawn while the stage works."""

    def __init__(self, total: int, say: Callable[[str], None], *, show: bool = False) -> None:
        self.total = total
        self.say = say
        self.show = show
        self.index = 0
        self.started = time.perf_counter()
        self.timings: dict[str, float] = {}
        self._name: str | None = None
        self._t0 = 0.0
        self._working = contextlib.ExitStack()

    def begin(self, name: str, text: str, *, working: bool = True) -> None:
        """Starts stage ``name``, said as ``text``; ``working``: its time-so-far line (False
        for a stage whose own lines are printed past tqdm, as generation's estimates are)."""
        self.end()
        self.index += 1
        self._name, self._t0 = name, time.perf_counter()
        elapsed = time.perf_counter() - self.started
        self.say(f"[{self.index}/{self.total}] {text}  (at {elapsed:.0f} s)")
        if working:
            desc = f"[{self.index}/{self.total}] {name}"
            self._working.enter_context(_working(desc, show=self.show))

    def end(self) -> None:
        self._working.close()
        if self._name is not None:
            self.timings[self._name] = time.perf_counter() - self._t0
            self._name = None


def _bar(iterable: Any, *, desc: str, total: int | None = None, show: bool = True) -> Any:
    """``iterable`` counted by a bar on stderr that keeps ticking while an item takes long
    (`sim.ticking`): a stage is never silent."""
    bar = tqdm(
        iterable,
        desc=desc,
        total=total,
        file=sys.stderr,
        disable=not show,
        dynamic_ncols=True,
        leave=False,
    )
    with bar, ticking(bar):
        yield from bar


@contextlib.contextmanager
def _working(desc: str, *, show: bool = True) -> Iterator[None]:
    """On a terminal, a line ``desc: 00:04 so far`` redrawn while a step with no bar of its own
    works (`sim.ticking`: the stress test's episodes and plots, the model trained on SALSA, 4 to
    15 s each on two busy cores), cleared when it ends. A log gets nothing."""
    line = elapsed_line(desc, disable=not (show and sys.stderr.isatty()))
    with line, ticking(line):
        yield


def _say(line: str) -> None:
    """A stage's line on stderr: on a terminal above the bars being drawn (`tqdm.write`)."""
    if sys.stderr.isatty():
        tqdm.write(line, file=sys.stderr)
    else:
        print(line, file=sys.stderr, flush=True)


def _find_datasets(datasets: str | os.PathLike[str] | None) -> dict[str, Dataset]:
    """SALSA and Babble under ``datasets`` (``salsa/``, ``babble/``), those present; with
    ``datasets`` None, the ones fetched with ``reform-sim datasets fetch``."""
    found: dict[str, Dataset] = {}
    if datasets is None:
        for name, load in (("salsa", load_salsa), ("babble", load_babble)):
            if is_fetched(name):
                found[name] = load(fetch(name))
        return found
    root = Path(datasets)
    if not root.is_dir():
        raise FileNotFoundError(f"datasets: {root} is not a folder (expected salsa/ and babble/)")
    if (root / "salsa").is_dir():
        found["salsa"] = load_salsa(root / "salsa")
    if (root / "babble").is_dir():
        found["babble"] = load_babble(root / "babble")
    return found


def _even(frames: Sequence[Frame], most: int | None) -> tuple[Frame, ...]:
    return tuple(frames) if most is None else even_subset(frames, most)


def _snapshot_index(frames: Sequence[Frame]) -> int:
    """The frame to draw: the one with the most F-formations, latest among equals."""
    return max(range(len(frames)), key=lambda k: (len(frames[k].fformations()), k))


def _scores_row(evaluation: Evaluation) -> dict[str, float]:
    two, one = evaluation.at(T_TWO_THIRDS), evaluation.at(T_ONE)
    return {
        "precision": two.precision,
        "recall": two.recall,
        "f1": two.f1,
        "f1_t1": one.f1,
        "pairwise_accuracy": evaluation.pairwise_accuracy,
    }


def run_demo(
    *,
    out_dir: str | os.PathLike[str] = DEFAULT_OUT,
    datasets: str | os.PathLike[str] | None = None,
    seed: int = 0,
    jobs: int | None = None,
    quick: bool = False,
    progress: Callable[[str], None] | None = None,
    progress_bars: bool = True,
    recordings: bool = True,
) -> DemoResult:
    """Runs the demo and writes its episodes, model, recordings and figures into ``out_dir``.

    The report (``report.md``, ``results.json``) is written from the result by
    :func:`sim.experiments.demo_report.write_report`.

    Args:
        out_dir: the output folder (created; generated episodes in it are reused).
        datasets: folder holding ``salsa/`` and/or ``babble/``; None or missing ones are
            skipped.
        seed: master seed of everything drawn.
        jobs: worker processes (None: every core).
        quick: tiny budgets (:data:`QUICK`) instead of :data:`FULL`.
        progress: ``callable(str)`` told each stage (default: print to stderr).
        progress_bars: tqdm bars on stderr.
        recordings: write the Rerun recordings (False: none, and no ``recordings/`` folder;
            every score is the same).

    Returns:
        The :class:`DemoResult`.
    """
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed must be an int >= 0, got {seed!r}")
    if jobs is not None and (isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1):
        raise ValueError(f"jobs must be None or an int >= 1, got {jobs!r}")
    budget = QUICK if quick else FULL
    say = progress or _say
    out = Path(out_dir)
    real = _find_datasets(datasets)
    out.mkdir(parents=True, exist_ok=True)
    if recordings:
        (out / RECORDINGS).mkdir(exist_ok=True)
    (out / FIGURES).mkdir(exist_ok=True)
    stages = _Stages(7, say, show=progress_bars)
    try:
        recorded: list[Path] = []
        figures: list[Path] = []
        say(
            f"reform-sim demo ({budget.name} budget, seed {seed}) -> {out}; real data: "
            + (", ".join(sorted(real)) if real else "none found")
        )

        # 1. Every registered scenario, briefly.
        names = scenarios.names()
        stages.begin("scenarios", f"simulating every registered scenario ({len(names)}) briefly")
        episodes = {}
        for k, name in enumerate(_bar(names, desc="scenarios", show=progress_bars)):
            made = scenarios.make(name, seed=seed + k)
            duration = min(made.duration, budget.scenario_s)
            episodes[name] = simulate_episode(made, duration=duration)

        # 2. The synthetic training set.
        stages.begin(
            "synthetic", "generating the synthetic training set (Parquet shards)", working=False
        )
        train_frames = generate_sources(
            budget.train,
            root=out / SYNTHETIC / "train",
            seed=seed,
            n_jobs=jobs,
            progress=progress_bars,
        )
        salsa_train: tuple[Frame, ...] = ()
        salsa_test: tuple[Frame, ...] = ()
        if "salsa" in real:
            salsa_train, salsa_test = time_split(real["salsa"].annotated(), DEFAULT_TRAIN_FRACTION)
        kept = balance_pairs(train_frames)
        synthetic = tuple(f for frames in kept.values() for f in frames)
        training_summary = {
            name: {"frames": len(frames), "pairs": count_pairs(frames)}
            for name, frames in kept.items()
        }

        # 3. Training.
        stages.begin("training", f"training REFORM on {len(synthetic)} synthetic frames")
        models: dict[str, Any] = {}
        for name in _bar(CLASSIFIERS, desc="classifiers", show=progress_bars):
            options = dict(RECOMMENDED.options) if name == SAVED_CLASSIFIER else {}
            models[name] = Reform(_classifier(name, jobs), **options).fit(synthetic)
        model_path = save_model(models[SAVED_CLASSIFIER], out / MODEL)
        salsa_model = None
        if salsa_train:
            salsa_model = Reform(_classifier(SAVED_CLASSIFIER, jobs)).fit(
                _even(salsa_train, budget.salsa_train_frames)
            )

        # 4. Evaluation.
        stages.begin(
            "evaluation",
            "scoring REFORM and GCFF on held-back episodes and real data",
            working=False,
        )
        held = generate_sources(
            budget.held_back,
            root=out / SYNTHETIC / "held-back",
            seed=seed + HELD_BACK_SEED_OFFSET,
            n_jobs=jobs,
            progress=progress_bars,
        )
        tests: dict[str, tuple[Frame, ...]] = {
            "held-back synthetic": tuple(f for frames in held.values() for f in frames)
        }
        if salsa_test:
            tests["SALSA test split"] = _even(salsa_test, budget.real_frames)
        if "babble" in real:
            tests["Babble"] = _even(real["babble"].annotated(), budget.real_frames)
        gcff = make_detector("gcff", stride=PAPER_STRIDE_M, mdl=PAPER_MDL_M2)
        detectors: dict[str, Any] = {
            f"REFORM {CLASSIFIER_TEXT[n]} (synthetic)": models[n] for n in CLASSIFIERS
        }
        if salsa_model is not None:
            detectors[f"REFORM {CLASSIFIER_TEXT[SAVED_CLASSIFIER]} (SALSA train)"] = salsa_model
        detectors[GCFF_LABEL] = gcff
        detectors[MAJORITY_LABEL] = make_detector("majority")
        scores: dict[tuple[str, str], dict[str, Any]] = {}
        evaluations: dict[tuple[str, str], Evaluation] = {}
        predictions: dict[tuple[str, str], list[Any]] = {}
        work = [(d, t) for t in tests for d in detectors]
        for detector, dataset in _bar(work, desc="scoring", show=progress_bars):
            frames = tests[dataset]
            predicted = run_detector(detector, detectors[detector], frames)
            evaluation = evaluate(frames, predicted)
            predictions[(detector, dataset)] = predicted
            evaluations[(detector, dataset)] = evaluation
            scores[(detector, dataset)] = evaluation.to_json(detector=detector, dataset=dataset)

        # 5. Stress tests.
        stages.begin("stress", "stress tests on the small grid (noise, dropouts, crowds, sensor)")

        stress = run_stress(
            _stress_grid(budget.stress_grid),
            seed=seed,
            jobs=jobs,
            axes=budget.stress_axes,
            detectors={**{n: models[n] for n in CLASSIFIERS}, STRESS_GCFF: gcff},
            progress=lambda line: say(f"  stress: {line.strip()}"),  # tasks done, as they finish
        )
        command = _command(out, datasets, seed, quick=quick, recordings=recordings)
        stress_files = write_stress(stress, out / "stress", command=command)
        figures += [p for k, p in stress_files.items() if k.startswith("plot:")]
        if recordings:
            recorded.append(record_stress(stress, out / RECORDINGS / "stress.rrd"))

        # 6. The HRI re-enactment.
        stages.begin("hri", "re-enacting the paper's HRI experiment (three scenes with the robot)")

        hri_detectors = reform_detectors(
            {SAVED_CLASSIFIER: models[SAVED_CLASSIFIER]}, training="synthetic"
        )
        if salsa_model is not None:
            hri_detectors += reform_detectors({SAVED_CLASSIFIER: salsa_model}, training="salsa")
        hri_detectors += baseline_detectors(reference=False)
        # What the HRI page says about the SALSA-trained model (the synthetic one is described in
        # the demo's report: its training set is not sim.experiments.stress's).
        hri_training: dict[str, Any] = {}
        if salsa_model is not None:
            hri_training["salsa"] = salsa_training(salsa_model, DEFAULT_TRAIN_FRACTION)
        hri = hri_experiment(
            seed=seed,
            seeds=budget.hri_seeds,
            views=budget.hri_views,
            resamples=budget.resamples,
            detectors=hri_detectors,
            training=hri_training,
            # the episodes, as by default
            executor=Executor("local", jobs=1, progress=progress_bars),
        )
        write_markdown(out / "hri.md", hri_markdown(hri, command=command))
        if recordings:
            recorded += record_scenes(hri_detectors, out / RECORDINGS / "hri", seed=seed)

        # 7. Recordings, figures, report.
        stages.begin(
            "report",
            "writing recordings (.rrd), figures (PNG) and the report"
            if recordings
            else "writing figures (PNG) and the report",
        )

        reform_main = models[SAVED_CLASSIFIER]
        main_label = f"REFORM {CLASSIFIER_TEXT[SAVED_CLASSIFIER]} (synthetic)"
        scenario_rows = []
        for name in _bar(names, desc="scenes", show=progress_bars):
            episode = episodes[name]
            frames = episode.truth
            reform_parts = run_detector(main_label, reform_main, frames)
            gcff_parts = run_detector(GCFF_LABEL, gcff, frames)
            parts = {"reform": reform_parts, "gcff": gcff_parts}
            annotated = any(f.annotated for f in frames)
            scored = {d: evaluate(frames, p) for d, p in parts.items()} if annotated else {}
            path = out / RECORDINGS / f"scenario-{name}.rrd"
            if recordings:
                record_episode(
                    path,
                    frames,
                    detections=parts,
                    evaluations=scored,
                    events=episode.events,
                    model=episode.model,
                    seed=episode.scenario.seed,
                    name=f"scenario {name}",
                )
                recorded.append(path)
            k = _snapshot_index(frames)
            snapshot = frames[k]
            figures.append(
                top_view(
                    snapshot,
                    {
                        "ground truth": snapshot.partition(),
                        "REFORM": reform_parts[k],
                        "GCFF": gcff_parts[k],
                    },
                    out / FIGURES / f"scenario-{name}.png",
                    title=f"{name}, t = {snapshot.time:g} s",
                )
            )
            scenario_rows.append(
                {
                    "scenario": name,
                    "description": episode.scenario.description,
                    "people": max(f.n_people for f in frames),
                    "seconds": len(frames) / episode.dataset.metadata["rate_hz"],
                    "frames": len(frames),
                    "fformations_per_frame": float(np.mean([len(f.fformations()) for f in frames])),
                    "reform_f1": _f1(scored.get("reform")),
                    "gcff_f1": _f1(scored.get("gcff")),
                    "recording": str(path.relative_to(out)) if recordings else None,
                    "figure": f"{FIGURES}/scenario-{name}.png",
                }
            )
        if recordings:  # each test set's REFORM and GCFF, scored frame by frame
            for dataset, frames in tests.items():
                slug = dataset.lower().replace(" ", "-")
                path = out / RECORDINGS / f"evaluation-{slug}.rrd"
                record_evaluation(
                    path,
                    frames,
                    {
                        "reform": predictions[(main_label, dataset)],
                        "gcff": predictions[(GCFF_LABEL, dataset)],
                    },
                    {
                        "reform": evaluations[(main_label, dataset)],
                        "gcff": evaluations[(GCFF_LABEL, dataset)],
                    },
                    name=f"evaluation {dataset}",
                    dataset=slug,
                    seed=seed,
                    classifier=reform_main.classifier_,
                )
                recorded.append(path)
        bars = {
            dataset: [
                Bar(detector, 100 * evaluations[(detector, dataset)].at(T_TWO_THIRDS).f1)
                for detector in detectors
                if detector != MAJORITY_LABEL
            ]
            for dataset in tests
        }
        figures.append(
            score_bars(
                bars,
                out / FIGURES / "scores.png",
                ylabel="F1 at T = 2/3 (%)",
                title="REFORM trained on synthetic crowds, and GCFF",
            )
        )
    finally:
        stages.end()
    timings = dict(stages.timings)
    timings["total"] = time.perf_counter() - stages.started
    return DemoResult(
        out_dir=out,
        model=model_path,
        recordings=tuple(recorded),
        figures=tuple(figures),
        scores=scores,
        timings=timings,
        datasets=tuple(sorted(real)),
        budget=budget,
        seed=seed,
        command=command,
        scenarios=tuple(scenario_rows),
        training=training_summary,
        tests={d: len(f) for d, f in tests.items()},
        detectors=tuple(detectors),
        evaluations={k: _scores_row(v) for k, v in evaluations.items()},
        stress=stress,
        stress_plots={
            k.split(":", 1)[1]: str(p.relative_to(out))
            for k, p in stress_files.items()
            if k.startswith("plot:")
        },
        hri=hri,
        machine={"cores": os.cpu_count(), "platform": platform.platform()},
    )


def _stress_grid(name: str) -> Any:
    """``"quick"``: the small grid cut to two levels, one short episode; else a grid's name."""
    if name != "quick":
        return name
    return replace(
        GRIDS["small"], position_noise_m=(0.0, 0.5), seeds=1, duration_s=20.0, resamples=50
    )


def _classifier(name: str, jobs: int | None) -> Any:
    """A ready-made classifier; bagged trees grow their trees on ``jobs`` processes (the same
    trees whatever the number: scikit-learn draws every tree's seed before splitting the
    work)."""
    estimator = make_classifier(name)
    if name == BAGGED_TREES:
        estimator.set_params(n_jobs=jobs if jobs is not None else -1)
    return estimator


def _f1(evaluation: Evaluation | None) -> float | None:
    if evaluation is None or evaluation.n_frames == 0:
        return None
    return float(evaluation.at(T_TWO_THIRDS).f1)


def _command(
    out: Path,
    datasets: str | os.PathLike[str] | None,
    seed: int,
    *,
    quick: bool = False,
    recordings: bool = True,
) -> str:
    words = ["reform-sim", "demo"]
    if datasets is not None:
        words += ["--data", str(datasets)]
    words += ["--out", str(out)]
    if seed:
        words += ["--seed", str(seed)]
    if quick:
        words.append("--quick")
    if not recordings:
        words.append("--no-recordings")
    return shlex.join(words)
