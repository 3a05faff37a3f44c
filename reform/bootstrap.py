"""Bootstrap confidence intervals for the protocol's scores.

Neighbouring frames of one recording are near-duplicates, so resampling frames alone would make
intervals far too narrow. The bootstrap here is two-stage (a *cluster* bootstrap): each resample
draws the sequences (episodes, sessions) with replacement, then, within every drawn sequence, as
many frames as it has, with replacement. A sequence drawn twice contributes twice. With a single
sequence this is the ordinary frame bootstrap.

The resampling is expressed as weights (how many times each frame is drawn), so one set of
weights scores every detector evaluated on the same frames: intervals of two detectors come from
the same resamples (a paired bootstrap), and differences between them can be bootstrapped too.

The score of a resample follows the protocol (:mod:`reform.metrics`): P̄ and R̄ are the weighted
means of the per-frame precision and recall, F1 the F1 of those means. Intervals are percentile
intervals.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from reform.json_values import json_float, json_record
from reform.metrics import Evaluation

__all__ = [
    "DEFAULT_LEVEL",
    "DEFAULT_RESAMPLES",
    "Interval",
    "ScoreIntervals",
    "bootstrap_weights",
    "frame_intervals",
    "score_intervals",
]

DEFAULT_RESAMPLES = 1000  # bootstrap resamples
DEFAULT_LEVEL = 0.95  # coverage of the percentile intervals


@dataclass(frozen=True)
class Interval:
    """A point estimate and its bootstrap percentile interval.

    Attributes:
        value: the estimate on the data as observed.
        low: lower end of the interval.
        high: upper end of the interval.
    """

    value: float
    low: float
    high: float

    def to_json(self) -> dict[str, float | None]:
        return {k: json_float(getattr(self, k)) for k in ("value", "low", "high")}


@dataclass(frozen=True)
class ScoreIntervals:
    """Precision, recall and F1 (protocol: F1 of the frame means) at one threshold.

    Attributes:
        precision, recall, f1: each an :class:`Interval`.
        frames: annotated frames scored.
        sequences: sequences (the clusters resampled).
    """

    precision: Interval
    recall: Interval
    f1: Interval
    frames: int
    sequences: int

    def to_json(self) -> dict[str, Any]:
        return json_record(self)


def bootstrap_weights(
    sequence: Sequence[str] | npt.ArrayLike,
    *,
    rng: np.random.Generator,
    resamples: int = DEFAULT_RESAMPLES,
) -> np.ndarray:
    """Two-stage bootstrap weights: sequences with replacement, then frames within each.

    Args:
        sequence: (n_frames,) the sequence of each frame (the clusters).
        rng: the generator of the draws.
        resamples: number of resamples.

    Returns:
        (resamples, n_frames) float64: how many times each frame is drawn in each resample.
    """
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    if isinstance(resamples, bool) or not isinstance(resamples, (int, np.integer)) or resamples < 1:
        raise ValueError(f"resamples must be an int >= 1, got {resamples!r}")
    labels = np.asarray(sequence, dtype=object)
    if labels.ndim != 1 or labels.size == 0:
        raise ValueError(f"sequence must be a non-empty 1-D sequence of names, got {labels.shape}")
    names, cluster = np.unique(labels.astype(str), return_inverse=True)
    k = names.size
    picks = rng.multinomial(k, np.full(k, 1.0 / k), size=resamples)  # (B, k)
    weights = np.zeros((resamples, labels.size))
    for c in range(k):
        rows = np.flatnonzero(cluster == c)
        size = rows.size
        draws = rng.multinomial(picks[:, c] * size, np.full(size, 1.0 / size))  # (B, size)
        weights[:, rows] = draws
    return weights


def _interval(point: float, samples: np.ndarray, level: float) -> Interval:
    finite = samples[np.isfinite(samples)]
    if finite.size == 0:
        return Interval(point, math.nan, math.nan)
    tail = 50.0 * (1.0 - level)
    low, high = np.percentile(finite, [tail, 100.0 - tail])
    return Interval(float(point), float(low), float(high))


def frame_intervals(
    frame_precision: npt.ArrayLike,
    frame_recall: npt.ArrayLike,
    *,
    weights: np.ndarray,
    sequences: int,
    level: float = DEFAULT_LEVEL,
) -> ScoreIntervals:
    """Bootstrap intervals of P̄, R̄ and F1 from per-frame precision and recall.

    Args:
        frame_precision: (n_frames,) per-frame precision (``ThresholdScores.frame_precision``).
        frame_recall: (n_frames,) per-frame recall.
        weights: (resamples, n_frames) from :func:`bootstrap_weights`.
        sequences: how many sequences the frames come from (reported, not used).
        level: coverage of the interval, in (0, 1).

    Returns:
        The point estimates (frame means and the F1 of the means) and their intervals.
    """
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must lie in (0, 1), got {level!r}")
    precision = np.asarray(frame_precision, dtype=np.float64)
    recall = np.asarray(frame_recall, dtype=np.float64)
    n = precision.size
    if precision.shape != (n,) or recall.shape != (n,) or n == 0:
        raise ValueError(
            "frame_precision and frame_recall must be non-empty 1-D arrays of one length, got "
            f"shapes {precision.shape} and {recall.shape}"
        )
    weights = np.asarray(weights, dtype=np.float64)
    if weights.ndim != 2 or weights.shape[1] != n:
        raise ValueError(
            f"weights must have shape (resamples, {n}) for these {n} frames, got {weights.shape}"
        )
    total = weights.sum(axis=1)
    p = weights @ precision / total
    r = weights @ recall / total
    f1 = _f1(p, r)
    p_hat, r_hat = float(precision.mean()), float(recall.mean())
    return ScoreIntervals(
        precision=_interval(p_hat, p, level),
        recall=_interval(r_hat, r, level),
        f1=_interval(float(_f1(np.array([p_hat]), np.array([r_hat]))[0]), f1, level),
        frames=n,
        sequences=int(sequences),
    )


def _f1(p: np.ndarray, r: np.ndarray) -> np.ndarray:
    total = p + r
    return np.where(total > 0, 2.0 * p * r / np.where(total > 0, total, 1.0), 0.0)


def score_intervals(
    evaluation: Evaluation,
    threshold: Any,
    *,
    weights: np.ndarray,
    level: float = DEFAULT_LEVEL,
) -> ScoreIntervals:
    """Bootstrap intervals of P̄, R̄ and F1 of an evaluation at ``threshold``.

    Args:
        evaluation: the detector's evaluation; the weights must have been made for its frames,
            e.g. ``bootstrap_weights(evaluation.sequence, rng=...)``.
        threshold: matching threshold, e.g. ``"2/3"``.
        weights: (resamples, n_frames) from :func:`bootstrap_weights`.
        level: coverage of the interval, in (0, 1).

    Returns:
        The point estimates (as :meth:`Evaluation.at` gives them) and their intervals.
    """
    scores = evaluation.at(threshold)
    return frame_intervals(
        scores.frame_precision,
        scores.frame_recall,
        weights=weights,
        sequences=len(set(evaluation.sequence)),
        level=level,
    )
