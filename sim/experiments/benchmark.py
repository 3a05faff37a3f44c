"""The field's benchmark: every detector on every dataset, scored as the field reports it.

One cell per (detector, dataset): the detector predicts every annotated frame the dataset holds
(a dataset named in ``test_split`` only its test part of :func:`reform.time_split`, the frames
``reform-sim train --frames train`` leaves out), and the frames are scored with the field's
protocol (:func:`reform.evaluate`: precision and recall means over frames, F1 of the means, at
T = 2/3 and T = 1), for the dataset and for each of its sequences. The mean over datasets is the
plain mean of the per-dataset figures, over the datasets a detector was scored on.

Detectors are named as the catalogue names them (`reform.catalogue`: a registered name, an
installed plugin's name, ``package.module:factory``), made with their declared defaults, and
given what they need (`reform.detectors.prepare_detector`):

* a detector that runs on a dataset's own settings (``gcff-own``: each sequence's shipped
  ``settings_gc.mat``, the GCFF paper's protocol) is specialised to the dataset; a dataset that
  ships none is skipped, and says so;
* a detector that learns its settings (``gcff-tuned``) is fitted on the training part of the
  dataset's :func:`reform.time_split` and scored on its test part only, never on what it saw;

and REFORM models given as files (``reform-sim train``'s ``.skops``).

Cells are independent units of work (`sim.executor`): they run in this process (``jobs=1``),
on local worker processes (joblib's loky), or as Ray tasks (``backend="ray"``); the results are
the same, and in the same order, whichever runs them. This module imports no Rerun and no
MuJoCo; the report (Markdown, JSON, plot, ``.rrd``) is :mod:`sim.experiments.benchmark_report`.
"""

from __future__ import annotations

import math
import os
import sys
import time
import zlib
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from reform.bootstrap import bootstrap_weights, score_intervals
from reform.datasets import (
    detect_format,
    is_fetched,
    load_dataset,
    local_datasets_dir,
    one_per_recording,
    registry,
    resolve,
)
from reform.detectors import (
    DetectorError,
    check_frame_memory,
    detector_info,
    detector_names,
    make_detector,
    prepare_detector,
    register_detector,
    run_detector,
)
from reform.frame import Dataset, Frame, Group
from reform.json_values import json_float
from reform.metrics import evaluate
from reform.seeding import Role, derive_rng
from reform.splits import DEFAULT_TRAIN_FRACTION, time_split
from sim.executor import BACKENDS, Executor

__all__ = [
    "BACKENDS",
    "GCFF_ONE",
    "GCFF_OWN",
    "PUBLISHED",
    "THRESHOLDS",
    "Benchmark",
    "Cell",
    "DatasetSpec",
    "DetectorSpec",
    "dataset_spec",
    "detector_spec",
    "found_datasets",
    "one_recording_each",
    "run_benchmark",
    "scored_part",
]

THRESHOLDS = ("2/3", "1")
BOOTSTRAP_RESAMPLES = 1000  # resamples of each cell's interval
BLOCKS_PER_SEQUENCE = 10  # contiguous stretches of a recording, the clusters resampled
BOOTSTRAP_SEED = 0  # the benchmark's intervals: the same on every run
GCFF_ONE = "gcff"
GCFF_OWN = "gcff-own"
GCFF_TUNED = "gcff-tuned"
REFORM_PREFIX = "reform:"  # a DetectorSpec.spec naming a model file
DANTE_PREFIX = "dante:"  # a DetectorSpec.spec naming a DANTE model file (.safetensors)
_MODEL_PREFIXES = (REFORM_PREFIX, DANTE_PREFIX)

# Published figures, (P, R, F1) in % at T = 2/3, keyed by (dataset, what was run); each with
# its source. The REFORM paper (Hedayati et al. 2020, definitions.md "The paper's numbers"):
# SALSA's test split, trained on ~60 % of SALSA; Babble, trained on SALSA only.
PUBLISHED: dict[tuple[str, str], tuple[float, float, float, str]] = {
    ("salsa", "gcff"): (63.8, 64.2, 64.2, "REFORM paper, GCFF at stride 0.7, MDL 30000"),
    ("salsa", "weighted-knn"): (78.1, 82.7, 80.3, "REFORM paper"),
    ("salsa", "bagged-trees"): (78.3, 84.3, 81.2, "REFORM paper"),
    ("salsa", "logistic-regression"): (71.3, 78.6, 74.8, "REFORM paper"),
    ("babble", "gcff"): (65.0, 75.0, 69.6, "REFORM paper, GCFF at stride 0.7, MDL 30000"),
    ("babble", "weighted-knn"): (74.3, 87.5, 80.4, "REFORM paper"),
    ("babble", "bagged-trees"): (75.6, 90.0, 82.1, "REFORM paper"),
    ("babble", "logistic-regression"): (65.6, 80.0, 72.1, "REFORM paper"),
}
# The original GCFF code with each sequence's own settings, run under GNU Octave (F1 in % at
# T = 2/3 and T = 1; the READMEs of the GCFF packagings in the shared datasets folder).
ORIGINAL_GCFF_OWN: dict[tuple[str, str], tuple[float, float, float, float, str]] = {
    ("coffeebreak", "Seq1"): (74.9, 79.3, 77.0, 45.1, "original GCFF code, coffeebreak README"),
    ("coffeebreak", "Seq2"): (91.3, 97.9, 94.4, 73.1, "original GCFF code, coffeebreak README"),
    ("synth", "synth"): (96.7, 98.0, 97.3, 90.9, "original GCFF code, synth README"),
}


@dataclass(frozen=True)
class DatasetSpec:
    """A dataset to score on: how to load it, and which of its frames count.

    Attributes:
        name: the name in the tables (the registry's name, else the folder's).
        path: the local file or folder.
        format: the format, or None to detect it.
        units: the file's length unit, or None for the format's default.
        metres_per_pixel: the scale of ``units="px"``.
        time_unit: the unit of the files' time stamps (GCFF and DANTE), or None to read it from
            them (`reform.datasets.load_dataset`).
        split: ``"all"`` (every annotated frame) or ``"test"`` (the test part of
            :func:`reform.time_split`, for a dataset that detectors were trained on).
        train_fraction: the split's training share.
    """

    name: str
    path: str
    format: str | None = None
    units: str | None = None
    metres_per_pixel: float | None = None
    time_unit: str | None = None
    split: str = "all"
    train_fraction: float = DEFAULT_TRAIN_FRACTION

    def __post_init__(self) -> None:
        if self.split not in ("all", "test"):
            raise ValueError(f"split must be 'all' or 'test', got {self.split!r}")

    @property
    def label(self) -> str:
        return f"{self.name} (test split)" if self.split == "test" else self.name

    def load(self) -> Dataset:
        return load_dataset(
            self.path,
            format=self.format,
            units=self.units,
            metres_per_pixel=self.metres_per_pixel,
            time_unit=self.time_unit,
        )

    def frames(self, dataset: Dataset) -> tuple[Frame, ...]:
        """The annotated frames scored: all of them, or the train or test part of the time
        split."""
        if self.split in ("train", "test"):
            train, test = time_split(dataset.frames, self.train_fraction)
            part = train if self.split == "train" else test
            return tuple(f for f in part if f.groups is not None)
        return dataset.annotated()


@dataclass(frozen=True)
class DetectorSpec:
    """A detector to run: a row of the table.

    Attributes:
        label: the row's name.
        spec: :data:`GCFF_ONE`, :data:`GCFF_OWN`, ``"reform:<model file>"``, or anything
            :func:`reform.detectors.make_detector` builds (a registered or installed name, or
            ``package.module:factory``).
        kind: what was run, for the published figures: ``"gcff"``, a REFORM classifier's name
            (``"bagged-trees"``), or the spec.
        search: a folder searched for a ``package.module:factory`` plugin's module after the
            installed packages, in whichever process builds it (:func:`detector_spec` gives the
            folder the run started in, as ``python -m`` would search it), or None.
        registered: the `reform.detectors.DetectorInfo` of a name registered in this process
            (`reform.register_detector`), registered again in a worker that has not seen it,
            or None.
        deadline_s: seconds the detector may take to import, to be made, and to predict each
            frame (`reform.detectors.run_detector`), or None for the registry's defaults.
    """

    label: str
    spec: str
    kind: str = ""
    search: str | None = field(default=None, compare=False)
    registered: Any = field(default=None, compare=False)
    deadline_s: float | None = field(default=None, compare=False)

    @property
    def key(self) -> str:
        """A short name without spaces or slashes: the detector's entity in the recordings."""
        if self.spec.startswith(_MODEL_PREFIXES):
            prefix, _, path = self.spec.partition(":")
            text = f"{prefix}-{Path(path).stem}"
        else:
            text = self.spec
        return (
            "".join(c if c.isalnum() or c in "-_" else "-" for c in text).strip("-") or "detector"
        )

    @property
    def learns(self) -> bool:
        """Whether the detector learns its settings from training frames (``gcff-tuned``)."""
        if self.spec.startswith(_MODEL_PREFIXES) or ":" in self.spec:
            return False
        if self.spec not in detector_names() and self.registered is not None:
            return self.registered.needs == "training"
        return detector_info(self.spec).needs == "training"

    def _made(self) -> Any:
        """The detector as `reform.detectors.make_detector` makes it (neither specialised to a
        dataset nor fitted), found as :attr:`search` and :attr:`registered` say."""
        if self.search is not None and self.search not in sys.path:
            sys.path.append(self.search)  # a worker started before the run knows nothing of it
        if self.registered is not None and self.spec not in detector_names():
            info = self.registered  # registered in the process that started the run
            register_detector(
                info.name,
                info.factory,
                help=info.help,
                options=info.options,
                citation=info.citation,
                needs=info.needs,
            )
        return make_detector(self.spec, deadline_s=self.deadline_s)

    def sizer(self) -> Any:
        """A detector of this kind that says what a frame costs it
        (`reform.detectors.frame_memory`) without reading a model file: REFORM's cost does not
        depend on its model; None for a DANTE model (not known) and for a detector that cannot
        be made (its cell says why)."""
        if self.spec.startswith(REFORM_PREFIX):
            from reform.detector import Reform

            return Reform()
        if self.spec.startswith(DANTE_PREFIX):
            return None
        try:
            return self._made()
        except DetectorError:  # one that cannot be made says so where its cell builds it
            return None

    def build(self, dataset: Dataset, training: Sequence[Frame] = ()) -> tuple[Any, str | None]:
        """``(detector, None)``, or ``(None, reason)`` when it does not apply to ``dataset``:
        made with its declared defaults, specialised to ``dataset`` when it runs on a dataset's
        own settings, fitted on ``training`` when it :attr:`learns`."""
        if self.spec.startswith(REFORM_PREFIX):
            from reform.persistence import load_model  # here: a run without models needs no skops

            return load_model(self.spec[len(REFORM_PREFIX) :]), None
        if self.spec.startswith(DANTE_PREFIX):
            return make_detector("dante", model=self.spec[len(DANTE_PREFIX) :]), None

        detector = self._made()
        if ":" in self.spec:
            return detector, None
        try:
            ready = prepare_detector(
                self.spec, detector, dataset=dataset, training=training or None
            )
        except DetectorError as exc:
            if self.learns:
                raise
            return None, str(exc).removeprefix(f"{self.spec}: ")
        return ready, None


def detector_spec(spec: str) -> DetectorSpec:
    """The row for a ``--detector`` value (a catalogue name such as ``gcff``, ``gcff-own``,
    ``majority``, or a plugin)."""
    if ":" in spec:
        return DetectorSpec(label=spec, spec=spec, kind=spec, search=os.getcwd())
    info = detector_info(spec) if spec in detector_names() else None
    registered = info if info is not None and info.source == "registered" else None
    return DetectorSpec(label=_label(spec), spec=spec, kind=spec, registered=registered)


def _label(spec: str) -> str:
    """A row's name: GCFF's variants say which settings they run with."""
    if spec == GCFF_ONE:
        defaults = {o.name: o.default for o in detector_info(spec).options}
        return f"GCFF, one setting ({defaults['stride']:g} m, {defaults['mdl'] * 1e4:,.0f} cm²)"
    if spec == GCFF_OWN:
        return "GCFF, each dataset's own settings"
    if spec == GCFF_TUNED:
        return "GCFF, tuned on each dataset's training part"
    if spec in detector_names() and detector_info(spec).needs == "training":
        return f"{spec}, trained on each dataset's training part"
    return spec


def model_spec(path: str | os.PathLike[str]) -> DetectorSpec:
    """The row for a model file: REFORM's (``.skops``, labelled with its classifier and file
    name) or DANTE's (``.safetensors``, `reform-sim train --detector dante`)."""
    if str(path).lower().endswith(".safetensors"):
        make_detector("dante", model=path)  # a file that is not a DANTE model: one line, now
        return DetectorSpec(
            label=f"DANTE ({Path(path).stem})", spec=f"{DANTE_PREFIX}{path}", kind="dante"
        )
    from reform.persistence import model_info  # here: a run without models needs no skops

    info = model_info(path)
    kind = _classifier_kind(str(info.get("classifier_repr", "")))
    name = Path(path).stem
    label = f"REFORM {kind}" if kind == name else f"REFORM {kind or 'model'} ({name})"
    return DetectorSpec(label=label, spec=f"{REFORM_PREFIX}{path}", kind=kind)


_CLASSIFIER_KINDS = {
    "KNeighborsClassifier": "weighted-knn",
    "BaggingClassifier": "bagged-trees",
    "LogisticRegression": "logistic-regression",
}


def _classifier_kind(representation: str) -> str:
    for marker, kind in _CLASSIFIER_KINDS.items():
        if marker in representation:
            return kind
    return ""


def found_datasets() -> list[str]:
    """Every dataset name on this machine: the fetched public ones, then the local folders
    (`reform.datasets.local_datasets_dir`) whose format is recognised."""
    names = [entry.name for entry in registry() if is_fetched(entry.name)]
    local = local_datasets_dir()
    if local is not None and local.is_dir():
        for child in sorted(local.iterdir()):
            if child.is_dir() and child.name not in names:
                try:
                    detect_format(child)
                except ValueError:
                    continue
                names.append(child.name)
    return names


def one_recording_each(
    names: Sequence[str], *, named: Collection[str] = ()
) -> tuple[list[str], list[str]]:
    """``names`` with each recording once, so that a mean over datasets counts it once: a second
    packaging of a recording that is among ``names`` too (`reform.datasets.one_per_recording`)
    is left out, unless it is one of ``named`` (chosen by the user).

    Returns:
        The names kept, in order, and one line for each name left out, saying why.
    """
    _, repeats = one_per_recording(names)
    left_out = {n: r for n, r in repeats.items() if n not in named}
    lines = [
        f"{n} left out: the same recording as {r}, which is scored (give --data {n} to score it)"
        for n, r in left_out.items()
    ]
    return [n for n in names if n not in left_out], lines


def dataset_spec(
    data: str,
    *,
    test_split: Sequence[str] = ("salsa",),
    train_fraction: float = DEFAULT_TRAIN_FRACTION,
    format: str | None = None,  # noqa: A002
    units: str | None = None,
    metres_per_pixel: float | None = None,
    time_unit: str | None = None,
) -> DatasetSpec:
    """The dataset a ``--data`` value names: a path, or a fetched or local dataset's name."""
    path = resolve(data)
    name = Path(data).name if Path(data).exists() else data
    return DatasetSpec(
        name=name,
        path=str(path),
        format=format,
        units=units,
        metres_per_pixel=metres_per_pixel,
        time_unit=time_unit,
        split="test" if name in test_split else "all",
        train_fraction=train_fraction,
    )


@dataclass(frozen=True)
class Scores:
    """Precision, recall and F1 (fractions) at each threshold, the frames scored, and the F1's
    bootstrap interval at each threshold.

    Attributes:
        frames: the annotated frames scored.
        at: threshold -> (P, R, F1).
        f1_interval: threshold -> (low, high), the 95 % percentile interval of a block bootstrap
            (:func:`bootstrap_blocks`: contiguous stretches of each recording resampled whole,
            as neighbouring frames are near-duplicates); empty where not computed.
    """

    frames: int
    at: Mapping[str, tuple[float, float, float]]
    f1_interval: Mapping[str, tuple[float, float]] = field(default_factory=dict)

    @classmethod
    def of(cls, evaluation: Any, *, weights: Any = None) -> Scores:
        at, interval = {}, {}
        for t in THRESHOLDS:
            s = evaluation.at(t)
            at[t] = (float(s.precision), float(s.recall), float(s.f1))
            if weights is not None:
                f1 = score_intervals(evaluation, t, weights=weights).f1
                interval[t] = (float(f1.low), float(f1.high))
        return cls(frames=int(evaluation.n_frames), at=at, f1_interval=interval)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"frames": self.frames}
        for t, (p, r, f) in self.at.items():
            out[f"T={t}"] = {"precision": p, "recall": r, "f1": f}
            if t in self.f1_interval:
                low, high = self.f1_interval[t]
                out[f"T={t}"]["f1_interval"] = [json_float(low), json_float(high)]
        return out


def bootstrap_blocks(frames: Sequence[Frame], blocks: int = BLOCKS_PER_SEQUENCE) -> list[str]:
    """Each frame's block: its sequence cut, by position in time, into ``blocks`` contiguous
    stretches of (nearly) equal length, the clusters a benchmark interval resamples."""
    position: dict[str, int] = {}
    sizes: dict[str, int] = {}
    for frame in frames:
        sizes[frame.sequence] = sizes.get(frame.sequence, 0) + 1
    out = []
    for frame in frames:
        k = position.get(frame.sequence, 0)
        position[frame.sequence] = k + 1
        out.append(f"{frame.sequence}#{k * blocks // sizes[frame.sequence]}")
    return out


def _weights(label: str, frames: Sequence[Frame]) -> Any:
    """The bootstrap weights of a dataset's scored frames: the same for every detector scored on
    those frames (a paired bootstrap), from the dataset's label alone."""
    rng = derive_rng(BOOTSTRAP_SEED, Role.BENCHMARK_BOOTSTRAP, zlib.crc32(label.encode()))
    return bootstrap_weights(bootstrap_blocks(frames), rng=rng, resamples=BOOTSTRAP_RESAMPLES)


@dataclass(frozen=True)
class Cell:
    """One detector on one dataset.

    Attributes:
        dataset: the dataset's label; ``detector`` the detector's.
        scores: over the dataset's scored frames (None when skipped).
        by_sequence: sequence -> scores.
        skipped: why the detector did not run on this dataset, or None.
        seconds: the wall time of the prediction.
        predictions: one partition per scored frame (for the recording).
    """

    dataset: str
    detector: str
    scores: Scores | None
    by_sequence: Mapping[str, Scores] = field(default_factory=dict)
    skipped: str | None = None
    seconds: float = 0.0
    predictions: tuple[tuple[Group, ...], ...] = ()
    temporal: Mapping[str, Any] | None = None


@dataclass(frozen=True)
class Benchmark:
    """Every cell, and the specs that made them.

    Attributes:
        run: the run that made it (`run_benchmark`), whose datasets this process has read,
            if it scored them here; None for a benchmark made otherwise.
    """

    datasets: tuple[DatasetSpec, ...]
    detectors: tuple[DetectorSpec, ...]
    cells: tuple[Cell, ...]
    seconds: float
    run: str | None = field(default=None, compare=False, repr=False)

    def scored_frames(self, dataset: DatasetSpec) -> tuple[Frame, ...]:
        """The frames of ``dataset`` its cells scored (`DatasetSpec.frames`), read once in this
        process: the run's own reading where the run scored the dataset here."""
        return dataset.frames(_load_once(dataset, self.run))

    def cell_frames(self, dataset: DatasetSpec, detector: DetectorSpec) -> tuple[Frame, ...]:
        """The frames ``detector``'s cell scored on ``dataset``: the dataset's scored frames, or
        their test part for a detector that learns on the rest (:func:`scored_part`)."""
        return self.scored_frames(scored_part(dataset, detector))

    def recorded(
        self, dataset: DatasetSpec
    ) -> tuple[list[Frame], dict[str, list[tuple[Group, ...]]]]:
        """What a recording of ``dataset`` shows: the frames every detector scored on it (its
        test part where one learns on the rest, ``gcff-tuned``), and each scored detector's
        partition of each of them, by the detector's key."""
        scored = {}  # detector key -> (the frames its cell scored, its partition of each)
        for detector in self.detectors:
            cell = self.cell(dataset, detector)
            if cell.scores is not None:
                scored[detector.key] = (self.cell_frames(dataset, detector), cell.predictions)
        if not scored:
            return [], {}
        common = set.intersection(*({_at(f) for f in part} for part, _ in scored.values()))
        frames = [f for f in self.scored_frames(dataset) if _at(f) in common]
        predictions = {
            key: [p for f, p in zip(part, partitions, strict=True) if _at(f) in common]
            for key, (part, partitions) in scored.items()
        }
        return frames, predictions

    def cell(self, dataset: DatasetSpec, detector: DetectorSpec) -> Cell:
        for cell in self.cells:
            if cell.dataset == dataset.label and cell.detector == detector.label:
                return cell
        raise KeyError((dataset.label, detector.label))

    def common_datasets(self) -> tuple[str, ...]:
        """The labels of the datasets every detector was scored on."""
        return tuple(
            d.label
            for d in self.datasets
            if all(self.cell(d, m).scores is not None for m in self.detectors)
        )

    def means(self, datasets: Sequence[str] | None = None) -> dict[str, dict[str, Any]]:
        """Detector label -> mean P, R, F1 over the datasets it was scored on (or over
        ``datasets``, labels), per threshold."""
        out: dict[str, dict[str, Any]] = {}
        for detector in self.detectors:
            scored = [
                c.scores
                for c in self.cells
                if c.detector == detector.label
                and c.scores
                and (datasets is None or c.dataset in datasets)
            ]
            entry: dict[str, Any] = {"datasets": len(scored)}
            for t in THRESHOLDS:
                values = [s.at[t] for s in scored]
                entry[t] = (
                    tuple(sum(v[k] for v in values) / len(values) for k in range(3))
                    if values
                    else None
                )
            out[detector.label] = entry
        return out

    def published(self, dataset: DatasetSpec, detector: DetectorSpec) -> tuple | None:
        """The published (P, R, F1, source) for this row, where the field has one."""
        if detector.spec == GCFF_ONE or detector.spec.startswith(REFORM_PREFIX):
            return PUBLISHED.get((dataset.name, detector.kind))
        return None


def _temporal(label: str, frames: Sequence[Frame], predictions: Sequence[Any]) -> dict[str, Any]:
    """The group events of ``predictions`` scored in time (`reform.evaluate_events`), matched
    within 1 s or the dataset's frame interval where longer, with intervals over sequences; or
    ``{"skipped": why}`` where the frames cannot be scored in time (one frame per sequence)."""
    from reform.temporal import DEFAULT_TOLERANCE_S, evaluate_events, frame_interval

    try:
        tolerance = max(DEFAULT_TOLERANCE_S, frame_interval(frames))
        rng = derive_rng(BOOTSTRAP_SEED, Role.TEMPORAL_BOOTSTRAP, zlib.crc32(label.encode()))
        return evaluate_events(frames, predictions, tolerance_s=tolerance, rng=rng).to_json()
    except ValueError as exc:
        return {"skipped": " ".join(str(exc).split())}


# The datasets this process has read in the last run (`run_benchmark`) it took part in: the
# cells of one dataset that run here (one process, or each worker) and the recordings of the
# run read it once, whichever detectors they score; let go when the next run starts here.
_LOADED: dict[str, Any] = {"run": None, "datasets": {}}


def _load_once(dataset_spec: DatasetSpec, run: str | None) -> Dataset:
    """``dataset_spec.load()``, read once per process in run ``run`` (None: read now)."""
    if run is None:
        return dataset_spec.load()
    if _LOADED["run"] != run:  # a new run: the last run's datasets are let go
        _LOADED.update(run=run, datasets={})
    key = replace(dataset_spec, split="all", train_fraction=DEFAULT_TRAIN_FRACTION)
    if key not in _LOADED["datasets"]:
        _LOADED["datasets"][key] = dataset_spec.load()
    return _LOADED["datasets"][key]


def read_for_run(
    datasets: Sequence[DatasetSpec],
    detectors: Sequence[DetectorSpec],
    run: str | None = None,
    *,
    memory: tuple[int, str] | None = None,
    hint: str = "",
) -> str:
    """Reads each of ``datasets`` into this process for run ``run`` (a new run when None), as
    the run's recordings and its cells here read it (once), and refuses one that a cell would
    have nothing to score on (no annotated frame in the part of it that a detector of
    ``detectors`` is scored on), or, with ``memory``, a frame a detector would take more memory
    on: before any cell runs. Returns the run's id, for `run_benchmark`.

    Args:
        memory: the bytes one frame may take a detector and how a message names them
            (``(2**30, "--max-memory 1 GiB")``), or None to size nothing.
        hint: what to do about a frame too large, appended to the message.

    Raises:
        ValueError: ``"<path>: the dataset has no annotated frames to score"`` (or its time
            split's test part has none).
        reform.detectors.FrameTooLarge: a frame too large for ``memory``
            (`reform.detectors.check_frame_memory`).
        DataFormatError: a dataset file is malformed.
    """
    run = run or f"{os.getpid()}-{time.time_ns()}"
    limit, limit_text = memory or (0, "")
    sizers = {} if memory is None else {d: d.sizer() for d in detectors}
    for dataset_spec in datasets:
        dataset = _load_once(dataset_spec, run)
        for part in dict.fromkeys(scored_part(dataset_spec, d) for d in detectors):
            if not part.frames(dataset):
                raise ValueError(_nothing_to_score(part))
        for detector_spec, sizer in sizers.items():
            check_frame_memory(
                detector_spec.label,
                sizer,
                scored_part(dataset_spec, detector_spec).frames(dataset),
                limit=limit,
                limit_text=limit_text,
                source=dataset_spec.label,
                hint=hint,
            )
    return run


def _nothing_to_score(dataset_spec: DatasetSpec) -> str:
    part = (
        "the test part of the dataset's time split"
        if dataset_spec.split == "test"
        else ("the dataset")
    )
    return f"{dataset_spec.path}: {part} has no annotated frames to score"


def _at(frame: Frame) -> tuple[str, float]:
    """A frame's place in its dataset: its sequence and time."""
    return frame.sequence, frame.time


def scored_part(dataset_spec: DatasetSpec, detector_spec: DetectorSpec) -> DatasetSpec:
    """The part of ``dataset_spec`` that ``detector_spec``'s cell scores: the test part of its
    time split for a detector that learns (it is fitted on the training part), else the whole."""
    return replace(dataset_spec, split="test") if detector_spec.learns else dataset_spec


def _score(
    dataset_spec: DatasetSpec,
    detector_spec: DetectorSpec,
    temporal: bool = False,
    run: str | None = None,
) -> Cell:
    """One cell: load (once per process in run ``run``), build, predict (checked), evaluate
    (and, with ``temporal``, score the group events in time). A detector that learns is fitted
    on the training part of the dataset's time split and scored on its test part only."""
    dataset = _load_once(dataset_spec, run)
    label = dataset_spec.label  # the row's dataset, whichever of its frames this cell scores
    training: tuple[Frame, ...] = ()
    dataset_spec = scored_part(dataset_spec, detector_spec)
    if detector_spec.learns:
        train, _ = time_split(dataset.frames, dataset_spec.train_fraction)
        training = tuple(f for f in train if f.groups is not None)
    frames = dataset_spec.frames(dataset)
    if not frames:  # read_for_run refuses it before any cell: the file changed since
        raise ValueError(_nothing_to_score(dataset_spec))
    if detector_spec.learns and not training:
        return Cell(label, detector_spec.label, None, skipped="no annotated frames to train on")
    detector, reason = detector_spec.build(dataset, training)
    if detector is None:
        return Cell(label, detector_spec.label, None, skipped=reason)
    start = time.perf_counter()
    predictions = run_detector(
        detector_spec.label, detector, frames, deadline_s=detector_spec.deadline_s, source=label
    )
    seconds = time.perf_counter() - start
    evaluation = evaluate(frames, predictions)
    by_sequence = {
        sequence: Scores.of(evaluation.select(sequence=sequence))
        for sequence in dict.fromkeys(f.sequence for f in frames)
    }
    return Cell(
        dataset=label,
        detector=detector_spec.label,
        scores=Scores.of(evaluation, weights=_weights(label, frames)),
        by_sequence=by_sequence,
        seconds=seconds,
        predictions=tuple(tuple(tuple(int(m) for m in g) for g in p) for p in predictions),
        temporal=_temporal(label, frames, predictions) if temporal else None,
    )


def _score_unit(unit: tuple[DatasetSpec, DetectorSpec, bool, str]) -> Cell:
    return _score(*unit)


def _describe_unit(unit: tuple[DatasetSpec, DetectorSpec, bool, str]) -> str:
    """What a cell is, in a message: ``"detector gcff on salsa"``."""
    return f"detector {unit[1].label} on {unit[0].label}"


def run_benchmark(
    datasets: Sequence[DatasetSpec],
    detectors: Sequence[DetectorSpec],
    *,
    jobs: int = 1,
    backend: str = "local",
    address: str | None = None,
    progress: Callable[[int, int, Cell], None] | None = None,
    executor: Executor | None = None,
    temporal: bool = False,
    run: str | None = None,
) -> Benchmark:
    """Runs every detector on every dataset (each read here first, `read_for_run`).

    Args:
        datasets: the datasets, in table order.
        detectors: the detectors, in table order; labels must be unique.
        jobs: local worker processes (``backend="local"``).
        backend: ``"local"`` or ``"ray"``.
        address: the Ray cluster's address (``backend="ray"``); None starts a local instance.
        progress: called as ``progress(done, total, cell)`` as each cell finishes.
        executor: where the cells run (`sim.executor.Executor`), instead of ``jobs``,
            ``backend`` and ``address``.
        temporal: also score each cell's group events in time (`Cell.temporal`).
        run: the id `read_for_run` returned for these datasets and detectors (they are read
            here once), or None to read them now.

    Raises:
        ValueError: no dataset or detector, a repeated label, an unknown backend, jobs < 1, a
            dataset with nothing to score (`read_for_run`).
        reform.detectors.DetectorError: a detector raised, or returned something that is not a
            partition of a frame's people (naming the detector and the frame).
        DataFormatError: a dataset file is malformed.
    """
    datasets, detectors = tuple(datasets), tuple(detectors)
    if not datasets:
        raise ValueError("datasets must name at least one dataset, got none")
    if not detectors:
        raise ValueError("detectors must name at least one detector, got none")
    for what, labels in (
        ("datasets", [d.label for d in datasets]),
        ("detectors", [d.label for d in detectors]),
    ):
        twice = sorted({x for x in labels if labels.count(x) > 1})
        if twice:
            raise ValueError(f"{what} must be distinct, got {twice} twice")
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs must be an integer >= 1, got {jobs!r}")
    # Each process reads a dataset once in this run, this one first (it refuses a dataset with
    # nothing to score before any cell, and writes the recordings): what it read is let go
    # when the next run starts here.
    if run is None:
        run = read_for_run(datasets, detectors)
    units = [(d, m, bool(temporal), run) for d in datasets for m in detectors]
    start = time.perf_counter()
    if executor is None:
        local = backend == "local"
        with Executor(backend, jobs=jobs if local else None, address=address) as own:
            cells = own.map(_score_unit, units, on_done=progress, describe=_describe_unit)
    else:
        cells = executor.map(_score_unit, units, on_done=progress, describe=_describe_unit)
    return Benchmark(
        datasets=datasets,
        detectors=detectors,
        cells=tuple(cells),
        seconds=time.perf_counter() - start,
        run=run,
    )


def percent(value: float | None) -> str:
    """A fraction as a percentage with one decimal, or a dash."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    return f"{100 * value:.1f}"
