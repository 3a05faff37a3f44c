"""Each detector's F1 at a place predicted on its venue twin, with an interval, before any label.

The twin's generated episodes are split in two by episode: detectors that learn (REFORM trained
on the twin, GCFF tuned on it) learn on the first part, and every detector is scored on the
second (at most `PREDICT_FRAMES` frames spread over it). Without the place's recording, the
predicted F1 (T = 2/3) is that score; its interval is the 95 % bootstrap of `reform.bootstrap`
over those episodes (episodes resampled, then frames within them).

With the place's recording (its frames, groups removed: ``place``), the twin also says how a
detector's F1 follows from how well it agrees with the others, and the recording says how well
it agrees there. Every detector runs on the twin's scored frames and on the recording (at most
`PREDICT_FRAMES` frames spread over it); on each, the **consensus** is the partition of the
pairs that detectors holding more than half of the votes put together (`consensus`: the
catalogue's detectors vote, one vote a method, shared by the detectors citing its paper
(`method_weights`); the variants added beside them do not, nor does the majority baseline,
which puts no one together), and each detector's **agreement** is its F1 against that
consensus. A least-squares
line across the catalogue's detectors that group people, from agreement to F1 on the twin (where
the truth is known), is applied to each detector's agreement on the recording: the predicted F1
(`calibrated`). A detector that puts no one together (`NO_VOTE`) scores only on frames that hold
no group: its prediction is its agreement on the recording (the share of such frames by the
consensus), not the line's, which is drawn through detectors that group people and says nothing
that far from them. Where the twin is easier than the place, the detectors agree less on the
recording than on the twin, and the line carries that into the prediction; a detector that parts
from the others on the recording (one setting that fits the place badly) is predicted lower
there. The interval is the twin's, moved with the prediction. Fewer than `MIN_CONSENSUS` voting
detectors, or agreements on the twin that do not differ, leave the twin's own score.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np

from reform.frame import Frame
from reform.seeding import derive_rng

Partition = Sequence[Sequence[int]]  # one frame's groups, singletons included

__all__ = [
    "MIN_CONSENSUS",
    "NO_VOTE",
    "PREDICT_FRAMES",
    "Candidate",
    "Prediction",
    "agreements",
    "calibrated",
    "catalogue_candidates",
    "consensus",
    "line_through",
    "mean_prediction",
    "predict",
    "split_episodes",
    "table",
]

PREDICT_FRAMES = 200  # twin frames each detector is scored on at most (and place frames; fewer
# of a crowd: `sim.twins.tune.crowd_limit`)
MIN_CONSENSUS = 3  # voting detectors a consensus needs
NO_VOTE = ("majority",)  # catalogued detectors that put no one together: no vote in a consensus
RESAMPLES = 1000  # bootstrap resamples of the interval
THRESHOLD = Fraction(2, 3)
BOOTSTRAP = 21  # seed role of the bootstrap draws


@dataclass(frozen=True)
class Candidate:
    """A detector to predict for.

    Attributes:
        label: its name in tables (``gcff``, ``gcff (twin-tuned)``, ``reform (twin-trained)``).
        name: the catalogue name.
        options: its keyword arguments.
        learns: ``"twin"`` when it is fitted on the twin's training episodes first.
        detector: a ready detector (a model) instead of one made from name and options.
        votes: whether it votes in the detectors' consensus at a place (`consensus`) and
            fixes the line from agreement to F1: the catalogue's detectors at their defaults
            do; a variant added beside them (tuned or trained on the twin, a model file) is
            predicted through their consensus and line without moving them, so that adding
            one changes no other detector's prediction.
        method: the method it implements (the catalogue's citation of its paper; empty: its
            own): the detectors of one method share one vote in a consensus (`consensus`).
    """

    label: str
    name: str
    options: Mapping[str, Any] = field(default_factory=dict)
    learns: str = ""
    detector: Any = field(default=None, compare=False)
    votes: bool = True
    method: str = ""


@dataclass(frozen=True)
class Prediction:
    """A detector's predicted F1 at T = 2/3 (fractions), with its 95 % interval.

    ``f1`` is None (and ``note`` says why) when the detector could not run on the twin;
    ``detector`` is the detector as it ran (fitted on the twin where it learns), to be run
    unchanged where the prediction is checked.
    """

    label: str
    f1: float | None
    low: float | None
    high: float | None
    frames: int
    note: str = ""
    detector: Any = field(default=None, compare=False, repr=False)  # as run (fitted on the twin)
    twin_f1: float | None = None  # its F1 on the twin before a calibration at the place
    agreement: tuple[float, float] | None = None  # with the consensus: on the twin, at the place

    @property
    def on_twin(self) -> float | None:
        """Its F1 on the twin: ``f1`` itself unless it was calibrated at the place."""
        return self.f1 if self.twin_f1 is None else self.twin_f1

    def to_json(self) -> dict[str, Any]:
        out = {
            "detector": self.label,
            "f1": self.f1,
            "low": self.low,
            "high": self.high,
            "frames": self.frames,
            "note": self.note,
            "twin_f1": self.on_twin,
        }
        if self.agreement is not None:
            out["agreement_twin"], out["agreement_place"] = self.agreement
        return out


def split_episodes(frames: Sequence[Frame]) -> tuple[list[Frame], list[Frame]]:
    """The twin's annotated frames in two parts by episode: even episodes (training for the
    detectors that learn), odd ones (scored)."""
    annotated = [f for f in frames if f.groups is not None]
    sequences = sorted({f.sequence for f in annotated})
    learn = set(sequences[::2]) if len(sequences) > 1 else set()
    scored = [f for f in annotated if f.sequence not in learn]
    return [f for f in annotated if f.sequence in learn] or scored, scored


def catalogue_candidates(
    *, tuned: Mapping[str, Mapping[str, Any]] | None = None
) -> list[Candidate]:
    """Every catalogued detector a twin can run at its default setting (those that need a
    dataset's own settings or a model file are left out), ``gcff-tuned`` fitted on the twin,
    REFORM trained on the twin, and the ``tuned`` settings given (label -> options of gcff)."""
    from reform.detectors import detector_info, detector_names

    out = []
    for name in detector_names():
        info = detector_info(name)
        if info.needs == "dataset" or name == "reform":
            continue
        if info.runs_from_file:
            continue  # needs a model file
        learns = "twin" if info.needs == "training" else ""
        out.append(Candidate(name, name, learns=learns, method=_method(name)))
    out.append(Candidate("reform (twin-trained)", "reform", learns="twin", votes=False))
    for label, options in (tuned or {}).items():
        out.append(Candidate(label, "gcff", dict(options), votes=False))
    return out


def _method(name: str) -> str:
    """The method catalogued detector ``name`` implements: its paper's citation, or, for one
    that filters another (an option ``detector``), the filtered detector's at its default."""
    from reform.detectors import detector_info, detector_names

    info = detector_info(name)
    if info.citation:
        return info.citation
    base = next((o.default for o in info.options if o.name == "detector"), None)
    if isinstance(base, str) and base != name and base in detector_names():
        return _method(base)
    return ""


def _detector(candidate: Candidate, learn: Sequence[Frame]) -> Any:
    from reform.detectors import fit_detector, make_detector

    if candidate.detector is not None:
        return candidate.detector
    if candidate.name == "reform":
        from sim.twins.tune import tune_detector

        return tune_detector("reform", learn).model
    detector = make_detector(candidate.name, **candidate.options)
    if candidate.learns:
        detector = fit_detector(candidate.name, detector, learn)
    return detector


def consensus(
    frames: Sequence[Frame],
    partitions: Sequence[Sequence[Partition]],
    weights: Sequence[float] | None = None,
) -> list[Partition]:
    """Each frame's consensus of several detectors' ``partitions`` (one sequence per detector,
    a partition per frame): the people linked, in a chain, by pairs put in one group by
    detectors holding more than half of the votes (``weights``, one a detector; default 1
    each); everyone else alone."""
    from scipy.sparse.csgraph import connected_components

    from reform.gcff import labels_to_partition

    weights = np.ones(len(partitions)) if weights is None else np.asarray(weights, dtype=float)
    out = []
    total = float(weights.sum())
    for k, frame in enumerate(frames):
        ids = frame.ids.tolist()
        index = {person: j for j, person in enumerate(ids)}
        votes = np.zeros((len(ids), len(ids)))
        for partition, weight in zip(partitions, weights, strict=True):
            for group in partition[k]:
                rows = [index[m] for m in group]
                if len(rows) > 1:
                    votes[np.ix_(rows, rows)] += weight
        linked = 2 * votes > total + 1e-9
        np.fill_diagonal(linked, True)
        _, component = connected_components(linked, directed=False)
        out.append(labels_to_partition(ids, component))
    return out


def method_weights(methods: Mapping[str, str]) -> dict[str, float]:
    """Each voter's share of its method's one vote: ``methods`` (label -> the method it
    implements, empty for its own) -> 1 / the voters of that method. Variants of one method
    err together; one vote each would let a method with many variants outvote the others."""
    method = {label: m or label for label, m in methods.items()}
    sizes: dict[str, int] = {}
    for m in method.values():
        sizes[m] = sizes.get(m, 0) + 1
    return {label: 1.0 / sizes[m] for label, m in method.items()}


def agreements(
    frames: Sequence[Frame],
    partitions: Mapping[str, Sequence[Partition]],
    *,
    voters: Sequence[str] | Mapping[str, str] | None = None,
) -> dict[str, float] | None:
    """Each detector's F1 at T = 2/3 against the `consensus` of the detectors that vote
    (``voters``, default all, never `NO_VOTE`; given as label -> method, the detectors of one
    method share one vote, `method_weights`), on ``frames`` (their groups unread); None with
    fewer than `MIN_CONSENSUS` voters."""
    from reform.metrics import evaluate

    methods = dict(voters) if isinstance(voters, Mapping) else {}
    voting = set(partitions if voters is None else voters) - set(NO_VOTE)
    labels = [label for label in partitions if label in voting]
    if len(labels) < MIN_CONSENSUS or not frames:
        return None
    share = method_weights({label: methods.get(label, "") for label in labels})
    ballots = [partitions[label] for label in labels]
    agreed = [
        f.replace(groups=g)
        for f, g in zip(
            frames, consensus(frames, ballots, [share[label] for label in labels]), strict=True
        )
    ]
    return {
        label: float(evaluate(agreed, p, thresholds=(THRESHOLD,)).at(THRESHOLD).f1)
        for label, p in partitions.items()
    }


def line_through(x: Sequence[float], y: Sequence[float]) -> tuple[float, float] | None:
    """The least-squares line through the points (``x``, ``y``): its slope and intercept; None
    with fewer than two points or ``x`` that do not differ."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.size < 2 or np.ptp(x) < 1e-9:
        return None
    slope, intercept = np.polyfit(x, y, 1)
    return float(slope), float(intercept)


def calibrated(
    twin_f1: Mapping[str, float],
    on_twin: Mapping[str, float],
    at_place: Mapping[str, float],
    *,
    fitted_on: Sequence[str] | None = None,
) -> dict[str, float] | None:
    """Each detector's F1 at the place: the least-squares line from agreement to F1 across the
    detectors ``fitted_on`` (default all) on the twin (``on_twin``, ``twin_f1``), applied to
    every detector's agreement at the place (``at_place``), clipped to [0, 1]; None when the
    twin's agreements of those detectors do not differ."""
    labels = [label for label in twin_f1 if fitted_on is None or label in fitted_on]
    line = line_through([on_twin[label] for label in labels], [twin_f1[label] for label in labels])
    if line is None:
        return None
    slope, intercept = line
    return {
        label: float(np.clip(intercept + slope * at_place[label], 0.0, 1.0)) for label in twin_f1
    }


def predict(
    frames: Sequence[Frame],
    candidates: Sequence[Candidate],
    *,
    place: Sequence[Frame] | None = None,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
) -> list[Prediction]:
    """Each candidate's predicted F1 on the twin's ``frames``, calibrated by the agreement of
    the detectors on the ``place``'s frames when they are given (their groups are removed
    first, never read); see the module docstring."""
    from reform.bootstrap import bootstrap_weights, score_intervals
    from reform.detectors import DetectorError, run_detector
    from reform.metrics import evaluate
    from sim.twins.tune import crowd_limit, tuning_frames

    learn, scored = split_episodes(frames)
    scored = tuning_frames(scored, crowd_limit(scored, PREDICT_FRAMES))
    if place is not None:
        step = max(1, math.ceil(len(place) / crowd_limit(place, PREDICT_FRAMES)))
        place = [f.replace(groups=None, listed_groups=None) for f in place[::step]]
    weights = bootstrap_weights(
        [f.sequence for f in scored], rng=derive_rng(seed, BOOTSTRAP), resamples=RESAMPLES
    )
    out = []
    on_twin: dict[str, Sequence[Partition]] = {}
    on_place: dict[str, Sequence[Partition]] = {}
    for candidate in candidates:
        if progress is not None:
            progress(candidate.label)
        try:
            detector = _detector(candidate, learn)
            predictions = run_detector(candidate.name, detector, scored)
            if place is not None:
                on_place[candidate.label] = run_detector(candidate.name, detector, place)
        except (DetectorError, ValueError) as exc:
            note = " ".join(str(exc).split())[:160]
            out.append(Prediction(candidate.label, None, None, None, len(scored), note))
            continue
        on_twin[candidate.label] = predictions
        evaluation = evaluate(scored, predictions, thresholds=(THRESHOLD,))
        interval = score_intervals(evaluation, THRESHOLD, weights=weights).f1
        out.append(
            Prediction(
                candidate.label,
                float(evaluation.at(THRESHOLD).f1),
                float(interval.low),
                float(interval.high),
                len(scored),
                detector=detector,
            )
        )
    if place is None:
        return out
    catalogue = {c.label: c.method for c in candidates if c.votes}
    return _calibrate(out, on_twin, on_place, scored, place, catalogue)


def _calibrate(
    predictions: list[Prediction],
    on_twin: Mapping[str, Sequence[Partition]],
    on_place: Mapping[str, Sequence[Partition]],
    scored: Sequence[Frame],
    place: Sequence[Frame],
    catalogue: Mapping[str, str],
) -> list[Prediction]:
    """``predictions`` (the twin's scores) through `calibrated`, or as they are (their note
    says why) when no line can be drawn: the consensus and the line are the ``catalogue``
    detectors' (`Candidate.votes`; label -> the method it implements, one vote a method)."""
    twin_agrees = agreements(scored, on_twin, voters=catalogue)
    place_agrees = agreements(place, on_place, voters=catalogue)
    ran = {p.label: p.f1 for p in predictions if p.f1 is not None}
    line = None
    if twin_agrees is not None and place_agrees is not None:
        grouping = [label for label in catalogue if label not in NO_VOTE]
        line = calibrated(ran, twin_agrees, place_agrees, fitted_on=grouping)
    if line is None:
        why = "the twin's score: too few detectors agree or differ to calibrate it at the place"
        return [p if p.f1 is None else dataclasses.replace(p, note=why) for p in predictions]
    # A detector that puts no one together scores on the frames that hold no group, and the
    # consensus is the place's label-free word on which those are: its agreement there.
    line.update((label, place_agrees[label]) for label in NO_VOTE if label in line)
    out = []
    for p in predictions:
        if p.f1 is None:
            out.append(p)
            continue
        shift = line[p.label] - p.f1
        out.append(
            dataclasses.replace(
                p,
                f1=line[p.label],
                low=float(np.clip(p.low + shift, 0.0, 1.0)),
                high=float(np.clip(p.high + shift, 0.0, 1.0)),
                twin_f1=p.f1,
                agreement=(twin_agrees[p.label], place_agrees[p.label]),
            )
        )
    return out


def mean_prediction(runs: Sequence[Sequence[Prediction]]) -> list[Prediction]:
    """Each detector's prediction on several twins of one place (fitted with different seeds,
    each run of `predict` with the same candidates): the mean of their F1s, within the lowest
    low and the highest high of their intervals (the twins' episodes and their fits both), its
    ``note`` each twin's F1 (%). A detector a twin could not run keeps that twin's note and no
    F1."""
    out = []
    for row in zip(*runs, strict=True):
        first = row[0]
        failed = next((p for p in row if p.f1 is None), None)
        if failed is not None:
            out.append(Prediction(first.label, None, None, None, failed.frames, failed.note))
            continue
        each = ", ".join(f"{100 * p.f1:.1f}" for p in row)
        alone = [p.on_twin for p in row]
        agreed = [p.agreement for p in row if p.agreement is not None]
        out.append(
            Prediction(
                first.label,
                sum(p.f1 for p in row) / len(row),
                min(p.low for p in row),
                max(p.high for p in row),
                sum(p.frames for p in row),
                f"each twin: {each}",
                twin_f1=sum(alone) / len(alone),
                agreement=(
                    tuple(float(v) for v in np.mean(agreed, axis=0))
                    if len(agreed) == len(row)
                    else None
                ),
            )
        )
    return out


def table(predictions: Sequence[Prediction], *, place: str, twins: int = 1) -> str:
    """A Markdown table of ``predictions``, best first (``twins``: how many twins of the place
    they are the mean of, `mean_prediction`)."""
    rows = sorted(predictions, key=lambda p: -1.0 if p.f1 is None else -p.f1)
    if twins == 1:
        head = (
            f"Predicted F1 at T = 2/3 at {place}, on its venue twin (%, 95 % bootstrap interval "
            "over the twin's scored episodes):"
        )
    else:
        head = (
            f"Predicted F1 at T = 2/3 at {place}, the mean over {twins} venue twins fitted with "
            "different seeds (%, from the lowest to the highest end of their 95 % bootstrap "
            "intervals; each twin's F1 in the note):"
        )
    span = "95 % interval" if twins == 1 else "lowest-highest of the intervals"
    extra = []  # columns of predictions calibrated at the place
    if any(p.agreement is not None for p in rows):
        head = head.removesuffix(":") + (
            ", calibrated at the place by each detector's agreement with the detectors' "
            "consensus there, through the line from agreement to F1 on the twin; its F1 on the "
            "twin alone and its agreement on the twin and at the place beside it:"
        )
        extra = ["on the twin", "agreement: twin", "place"]
    header = ["detector", "predicted F1", span, *extra, "note"]
    lines = [
        head,
        "",
        "| " + " | ".join(header) + " |",
        "|:--|" + "--:|" * (len(header) - 2) + ":--|",
    ]
    for p in rows:
        if p.f1 is None or (extra and p.agreement is None):
            cells = ["-"] * (2 + len(extra))
        else:
            cells = [f"{100 * p.f1:.1f}", f"{100 * p.low:.1f}-{100 * p.high:.1f}"]
            if extra:
                cells += [f"{100 * v:.1f}" for v in (p.on_twin, *p.agreement)]
        lines.append("| " + " | ".join([p.label, *cells, p.note]) + " |")
    return "\n".join(lines) + "\n"
