"""Each detector's F1 at a place predicted on its venue twin, with an interval, before any label.

The twin's generated episodes are split in two by episode: detectors that learn (REFORM trained
on the twin, GCFF tuned on it) learn on the first part, and every detector is scored on the
second (at most `PREDICT_FRAMES` frames spread over it). The predicted F1 (T = 2/3) is that
score; its interval is the 95 % bootstrap of `reform.bootstrap` over those episodes (episodes
resampled, then frames within them).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

from reform.frame import Frame
from reform.seeding import derive_rng

__all__ = [
    "PREDICT_FRAMES",
    "Candidate",
    "Prediction",
    "catalogue_candidates",
    "mean_prediction",
    "predict",
    "split_episodes",
    "table",
]

PREDICT_FRAMES = 200  # twin frames each detector is scored on at most
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
    """

    label: str
    name: str
    options: Mapping[str, Any] = field(default_factory=dict)
    learns: str = ""
    detector: Any = field(default=None, compare=False)


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

    def to_json(self) -> dict[str, Any]:
        return {
            "detector": self.label,
            "f1": self.f1,
            "low": self.low,
            "high": self.high,
            "frames": self.frames,
            "note": self.note,
        }


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
        if any(o.type == "path" and o.default is None for o in info.options):
            continue  # needs a model file
        out.append(Candidate(name, name, learns="twin" if info.needs == "training" else ""))
    out.append(Candidate("reform (twin-trained)", "reform", learns="twin"))
    for label, options in (tuned or {}).items():
        out.append(Candidate(label, "gcff", dict(options)))
    return out


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


def predict(
    frames: Sequence[Frame],
    candidates: Sequence[Candidate],
    *,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
) -> list[Prediction]:
    """Each candidate's predicted F1 on the twin's ``frames`` (see the module docstring)."""
    from reform.bootstrap import bootstrap_weights, score_intervals
    from reform.detectors import DetectorError, run_detector
    from reform.metrics import evaluate
    from sim.twins.tune import tuning_frames

    learn, scored = split_episodes(frames)
    scored = tuning_frames(scored, PREDICT_FRAMES)
    weights = bootstrap_weights(
        [f.sequence for f in scored], rng=derive_rng(seed, BOOTSTRAP), resamples=RESAMPLES
    )
    out = []
    for candidate in candidates:
        if progress is not None:
            progress(candidate.label)
        try:
            detector = _detector(candidate, learn)
            predictions = run_detector(candidate.name, detector, scored)
        except (DetectorError, ValueError) as exc:
            note = " ".join(str(exc).split())[:160]
            out.append(Prediction(candidate.label, None, None, None, len(scored), note))
            continue
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
        out.append(
            Prediction(
                first.label,
                sum(p.f1 for p in row) / len(row),
                min(p.low for p in row),
                max(p.high for p in row),
                sum(p.frames for p in row),
                f"each twin: {each}",
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
    lines = [head, "", f"| detector | predicted F1 | {span} | note |", "|:--|--:|--:|:--|"]
    for p in rows:
        if p.f1 is None:
            lines.append(f"| {p.label} | - | - | {p.note} |")
        else:
            lines.append(
                f"| {p.label} | {100 * p.f1:.1f} | {100 * p.low:.1f}-{100 * p.high:.1f} | "
                f"{p.note} |"
            )
    return "\n".join(lines) + "\n"
