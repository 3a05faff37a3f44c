"""A detector's settings chosen on a venue twin's generated data, and the settings file it writes.

`tune_detector` searches the grid each catalogued option declares
(`reform.detectors.detector_info(name).options`, each `Option.grid`; the other options at their
defaults) and keeps the setting with the best F1 at T = 2/3 on the twin's frames; where options
declare which end of their grid groups fewer people together (`Option.lean`: GCFF's group cost,
low), it keeps instead, among the settings within `TIE_F1` of the best, the one nearest that
end. A twin's groups stand farther from their neighbours than a place's do, so a twin cannot see
the merges a costlier group makes: on the twins of the four datasets at hand (six seeds each)
the best setting on the twin fell 3.9 points short of the best on the recording's own labels,
the setting nearest the lean end within 2 points of it 1.6 (docs/guide/twins.md). REFORM is
trained on the twin instead: each of the paper's classifiers is trained on half of the twin's
episodes and scored on the other half, and the best is trained again on every episode.

The choice is written as a settings file of `reform.settings` (JSON: the detector, its
options, and beside them on what they were chosen and every setting's score), which
``detect``, ``evaluate`` and ``benchmark`` read with ``--settings FILE.json``.
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from reform.frame import Frame

__all__ = [
    "Tuned",
    "check_tunable",
    "crowd_limit",
    "detector_f1",
    "search_grid",
    "tune_detector",
    "tuning_frames",
    "write_tuned",
]

TUNE_FRAMES = 300  # frames of the twin each grid setting is scored on at most (spread out)
MIN_TUNE_FRAMES = 60  # ... and at least
TUNE_BUDGET = 12_000  # frames scored in all, over the grid: a larger grid scores fewer frames each
CROWD_PERSON_FRAMES = 30_000  # people in all each setting is scored on at most: fewer frames of a
# crowd (a frame's people the median), never fewer than MIN_TUNE_FRAMES; a party of 100 or fewer
# keeps its frames
THRESHOLD = Fraction(2, 3)  # the objective: F1 at T = 2/3, the field's protocol
TIE_F1 = 0.02  # settings this close to the best F1 on a twin are not told apart (lean, above)
REFORM = "reform"


@dataclass(frozen=True)
class Tuned:
    """A detector's settings chosen on a twin.

    Attributes:
        detector: the catalogue name.
        options: the chosen keyword arguments (``{}`` for REFORM: its model is ``model``).
        f1: F1 at T = 2/3 of the chosen setting on the twin (REFORM: on held-out episodes).
        grid: every setting tried, ``{"options": ..., "f1": ...}``.
        frames: twin frames the choice was scored on.
        model: REFORM's fitted estimator, trained on every twin episode (else None).
        rule: how the setting was chosen among the grid's, in words.
    """

    detector: str
    options: Mapping[str, Any]
    f1: float
    grid: tuple[Mapping[str, Any], ...] = ()
    frames: int = 0
    model: Any = field(default=None, compare=False)
    rule: str = "the best F1"


def crowd_limit(frames: Sequence[Frame], limit: int) -> int:
    """``limit`` frames, or fewer for a crowd: at most `CROWD_PERSON_FRAMES` people in all (the
    frames' median people a frame), at least `MIN_TUNE_FRAMES` frames."""
    people = float(np.median([f.n_people for f in frames])) if frames else 0.0
    if people * limit <= CROWD_PERSON_FRAMES:
        return limit
    return max(MIN_TUNE_FRAMES, int(CROWD_PERSON_FRAMES // people))


def tuning_frames(frames: Sequence[Frame], limit: int = TUNE_FRAMES) -> list[Frame]:
    """At most ``limit`` annotated frames, evenly spread over ``frames`` (same order)."""
    annotated = [f for f in frames if f.groups is not None]
    if len(annotated) <= limit:
        return annotated
    keep = np.unique(np.linspace(0, len(annotated) - 1, limit).round().astype(int))
    return [annotated[k] for k in keep]


def detector_f1(name: str, detector: Any, frames: Sequence[Frame]) -> float:
    """F1 at T = 2/3 (the field's protocol) of ``detector`` on the annotated ``frames``."""
    from reform.detectors import run_detector
    from reform.metrics import evaluate

    frames = [f for f in frames if f.groups is not None]
    predictions = run_detector(name, detector, frames)
    return float(evaluate(frames, predictions, thresholds=(THRESHOLD,)).at(THRESHOLD).f1)


def _grid(name: str) -> list[dict[str, Any]]:
    from reform.detectors import detector_info

    options = [o for o in detector_info(name).options if o.grid]
    if not options:
        return [{}]
    return [
        dict(zip([o.name for o in options], values, strict=True))
        for values in itertools.product(*(o.grid for o in options))
    ]


def _setting_f1(options: Mapping[str, Any], name: str, frames: Sequence[Frame]) -> float:
    """`detector_f1` of ``name`` made with ``options`` (a unit of work for a worker process)."""
    from reform.detectors import make_detector

    return detector_f1(name, make_detector(name, **options), frames)


def _leans(name: str) -> list[tuple[str, str]]:
    """(option, lean) of each of ``name``'s searched options that leans (`Option.lean`), in
    the options' order."""
    from reform.detectors import detector_info

    return [(o.name, o.lean) for o in detector_info(name).options if o.grid and o.lean]


def _leaning(name: str, grid: Sequence[Mapping[str, Any]], scores: Sequence[float]) -> int | None:
    """The index of the setting nearest the lean ends of ``name``'s options (`_leans`) among
    those within `TIE_F1` of the best score (the best of them on a tie, then the first in grid
    order); None when no option leans."""
    leans = _leans(name)
    if not leans:
        return None
    best = max(scores)
    near = [k for k, score in enumerate(scores) if score >= best - TIE_F1]

    def order(k: int) -> tuple:
        ends = tuple(grid[k][o] if lean == "low" else -grid[k][o] for o, lean in leans)
        return (*ends, -scores[k], k)

    return min(near, key=order)


def _lean_rule(name: str) -> str:
    ends = [f"{'lowest' if lean == 'low' else 'highest'} {o}" for o, lean in _leans(name)]
    return (
        f"among the settings within {100 * TIE_F1:g} points of the best F1, the one with the "
        f"{', then the '.join(ends)} (the end that groups fewer people together)"
    )


def search_grid(
    name: str, frames: Sequence[Frame], *, n_jobs: int = 1, lean: bool = False
) -> Tuned:
    """Every setting of ``name``'s declared grids scored on ``frames``; the best kept (the first
    in grid order on a tie), or with ``lean`` the setting nearest its options' lean ends among
    those within `TIE_F1` of the best (`_leaning`; the module docstring says why a twin leans).
    ``n_jobs`` > 1: the settings are scored on that many processes (the same scores)."""
    grid = _grid(name)
    if n_jobs > 1 and len(grid) > 1:
        from sim.executor import Executor

        executor = Executor("local", jobs=n_jobs, progress=False)
        scores = executor.map(_setting_f1, grid, shared=(name, list(frames)))
    else:
        scores = [_setting_f1(options, name, frames) for options in grid]
    best = int(np.argmax(scores))
    leaning = _leaning(name, grid, scores) if lean else None
    rule = "the best F1"
    if leaning is not None:
        best, rule = leaning, _lean_rule(name)
    return Tuned(
        detector=name,
        options=grid[best],
        f1=scores[best],
        grid=tuple({"options": o, "f1": s} for o, s in zip(grid, scores, strict=True)),
        frames=len(frames),
        rule=rule,
    )


def _train_reform(frames: Sequence[Frame]) -> Tuned:
    from reform.classifiers import CLASSIFIERS, make_classifier
    from reform.detector import Reform

    annotated = [f for f in frames if f.groups is not None]
    sequences = sorted({f.sequence for f in annotated})
    fit_on = set(sequences[::2])
    train = [f for f in annotated if f.sequence in fit_on]
    held = [f for f in annotated if f.sequence not in fit_on] or train
    if len({label for f in train for label in _pair_kinds(f)}) < 2:
        train = held = annotated  # half the episodes hold one kind of pair: train on all
    grid, scores = [], []
    for classifier in CLASSIFIERS:
        model = Reform(make_classifier(classifier)).fit(train)
        grid.append({"classifier": classifier})
        scores.append(detector_f1(REFORM, model, held))
    best = int(np.argmax(scores))
    model = Reform(make_classifier(grid[best]["classifier"])).fit(annotated)
    return Tuned(
        detector=REFORM,
        options={},
        f1=scores[best],
        grid=tuple({"options": o, "f1": s} for o, s in zip(grid, scores, strict=True)),
        frames=len(held),
        model=model,
    )


def _pair_kinds(frame: Frame) -> set[bool]:
    """Which kinds of pair (together, apart) ``frame`` holds."""
    n = frame.n_people
    together = sum(len(g) * (len(g) - 1) // 2 for g in frame.groups or ())
    kinds = set()
    if together:
        kinds.add(True)
    if together < n * (n - 1) // 2:
        kinds.add(False)
    return kinds


def check_tunable(name: str) -> str:
    """The catalogue name of ``name`` when a twin can tune it.

    Raises:
        ValueError: one line: an unknown detector, one that reads the settings a dataset ships
            (a twin has none) or one that learns on training frames of its own.
    """
    from reform.detectors import detector_info, detector_names

    if name not in detector_names():
        raise ValueError(
            f"--detector: expected a catalogued detector ({', '.join(detector_names())}), got "
            f"{name!r}"
        )
    info = detector_info(name)
    why = _not_tunable(info)
    if why is None:
        return info.name
    if info.needs in ("dataset", "training"):
        raise ValueError(f"--detector {name}: {why}; {_instead(info)}")
    raise ValueError(
        f"--detector {name}: {why}; tune a detector whose options a twin searches "
        f"({', '.join(tunable_detectors())})"
    )


def _not_tunable(info: Any) -> str | None:
    """Why a twin cannot tune the catalogued detector ``info``; None when it can (REFORM, and
    those with options a twin searches, `reform.detectors.Option.grid`, that need nothing but
    frames)."""
    if info.name == REFORM:
        return None
    if info.needs == "dataset":
        return "it reads the settings its dataset ships, which a twin has none of"
    if info.needs == "training":
        return "it fits itself on training frames"
    if info.runs_from_file:
        return "it runs from a model file trained for it, which a twin does not make"
    if not any(o.grid for o in info.options):
        return "it has no setting to choose"
    return None


def tunable_detectors() -> list[str]:
    """The catalogued detectors `check_tunable` takes (`_not_tunable`)."""
    from reform.detectors import detector_info, detector_names

    return [name for name in detector_names() if _not_tunable(detector_info(name)) is None]


def _instead(info: Any) -> str:
    """What to tune instead of ``info``'s detector: the tunable one of the same method (the
    paper both cite), else any tunable one."""
    from reform.detectors import detector_info

    tunable = tunable_detectors()
    same = [n for n in tunable if info.citation and detector_info(n).citation == info.citation]
    if same:
        return f"tune {same[0]} (the same method) instead"
    return f"tune a detector whose options a twin searches ({', '.join(tunable)})"


def tune_detector(name: str, frames: Sequence[Frame], *, n_jobs: int = 1) -> Tuned:
    """``name``'s settings chosen on the twin's ``frames`` (see the module docstring); a grid's
    settings scored on ``n_jobs`` processes.

    Raises:
        ValueError: one line for a detector a twin cannot tune: one that reads the settings a
            dataset ships (a twin has none) or learns on training frames of its own.
    """
    name = check_tunable(name)
    if name == REFORM:
        return _train_reform(frames)
    limit = int(min(TUNE_FRAMES, max(MIN_TUNE_FRAMES, TUNE_BUDGET // len(_grid(name)))))
    limit = crowd_limit(frames, limit)
    return search_grid(name, tuning_frames(frames, limit), n_jobs=n_jobs, lean=True)


def _plain(value: Any) -> Any:
    if isinstance(value, float):
        return float(f"{value:.6g}") if math.isfinite(value) else None
    return value


def write_tuned(
    path: str | os.PathLike[str], tuned: Tuned, *, chosen_on: Mapping[str, Any]
) -> Path:
    """Writes ``tuned`` as a `reform.settings` file: its options, and beside them ``chosen_on``
    (what the choice saw), the objective and every setting's score."""
    from reform.settings import write_settings

    return write_settings(
        path,
        tuned.detector,
        tuned.options,
        chosen_on=dict(chosen_on)
        | {
            "frames": tuned.frames,
            "objective": "F1 at T = 2/3",
            "rule": tuned.rule,
            "f1": _plain(tuned.f1),
        },
        grid=[
            {"options": {k: _plain(v) for k, v in g["options"].items()}, "f1": _plain(g["f1"])}
            for g in tuned.grid
        ],
    )
