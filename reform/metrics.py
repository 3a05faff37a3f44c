"""The field's evaluation protocol for F-formation detectors (GCFF's ``ff_evalgroups.m``).

Two families of scores, both over the *annotated* frames only:

* **Pairwise accuracy.** Every frame of ``n`` people becomes its ``n(n-1)/2`` unordered pairs;
  a pair's label is 1 when both people are in the same group. The accuracy is the share of pairs,
  pooled over all frames, whose predicted label equals the true label.
* **Group precision and recall at a threshold T** (T = 2/3 is the field's "card" setting, T = 1
  the exact "all" setting). Per frame, singletons are deleted from both the detected and the
  true groups (``ff_deletesingletons.m``). A true group ``G`` is matched when some detected
  group ``D`` has ``|G ∩ D| / max(|G|, |D|) >= T``; the comparison is done exactly, in integers
  (``q·|G∩D| >= p·max`` for ``T = p/q``), so that 2 of 3 passes 2/3 with no rounding doubt.
  TP = matched true groups, FP = #detected − TP, FN = #true − TP, P = TP/(TP+FP),
  R = TP/(TP+FN), with the reference's degenerate frames: no detected and no true groups →
  P = R = 1; true groups but no detections → P = 1, R = 0; detections but no true groups →
  P = 0, R = 1. (One rule gives all three: P = 1 when nothing is detected, R = 1 when there is
  nothing to find.) Over a sequence, P̄ and R̄ are the *means of the per-frame* P and R and
  F1 = 2·P̄·R̄/(P̄+R̄), the F1 of the means (0 when both are 0), as GCFF's ``example_GCFF.m``
  computes it. Micro-averaged P/R/F1 (TP, FP, FN summed over frames) and breakdowns by group
  size are reported beside it.

The matching, as the reference code does it (``ff_evalgroups.m``, cardmode off, read at
franzsetti/GCFF @ c84c1002): for each true group in turn, it scans the detected groups in order
and counts one true positive at the first detected group that passes the threshold, then stops
(``break``). So each true group counts at most once, and detected groups are *not* used up: the
same detected group may be scanned again for the next true group. For T > 1/2 and disjoint
groups this makes no difference and the order of the scan is irrelevant: a detected group ``D``
passing for two disjoint true groups would need ``|G1∩D| + |G2∩D| > |D|``, which is impossible,
and likewise a true group can pass with at most one of the disjoint detected groups. The matching
is therefore one-to-one, TP equals the number of matched detected groups, and FP = #detected − TP
equals the unmatched detected groups. For T <= 1/2 the reference rule would let one detected group
count for two true groups and give FP < 0, so thresholds must lie in (1/2, 1].

The per-size breakdown follows the reference's ``cardmode``: recall per true-group size (true
groups of that size, how many were matched) and precision per detected-group size (detected
groups of that size, how many matched a true group), pooled over frames.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from reform.frame import Frame, Group
from reform.json_values import json_float

__all__ = [
    "JSON_SCHEMA_VERSION",
    "PROTOCOL",
    "THRESHOLDS",
    "T_ONE",
    "T_TWO_THIRDS",
    "Evaluation",
    "MicroScores",
    "SizeScores",
    "ThresholdScores",
    "check_partition",
    "evaluate",
    "f1_score",
    "pair_labels",
]

T_TWO_THIRDS = Fraction(2, 3)  # the field's "card" threshold, the paper's setting
T_ONE = Fraction(1)  # exact match ("all")
THRESHOLDS = (T_TWO_THIRDS, T_ONE)

# Version of the JSON written by Evaluation.to_json (docs/json-schema.md).
JSON_SCHEMA_VERSION = 1

# The protocol this module implements, as every JSON result states it.
PROTOCOL = "ff_evalgroups: singletons dropped; frame-mean P and R; F1 of the means"


def f1_score(precision: float, recall: float) -> float:
    """Harmonic mean ``2PR/(P+R)``; 0 when both are 0."""
    total = precision + recall
    return 0.0 if total == 0 else 2.0 * precision * recall / total


def _threshold(value: Any) -> Fraction:
    """An exact threshold in (1/2, 1] from a Fraction, an int or a string such as ``"2/3"``."""
    if isinstance(value, bool) or isinstance(value, float):
        raise ValueError(
            "threshold must be exact (a fractions.Fraction, an int or a string like '2/3'), "
            f"got {type(value).__name__} {value!r}"
        )
    try:
        threshold = Fraction(value)
    except (TypeError, ValueError, ZeroDivisionError) as exc:
        raise ValueError(f"threshold must be a fraction like '2/3', got {value!r}") from exc
    if not Fraction(1, 2) < threshold <= 1:
        raise ValueError(
            f"threshold must lie in (1/2, 1] (at or below 1/2 one detected group could match two "
            f"true groups), got {threshold}"
        )
    return threshold


def _labels(
    groups: Iterable[Sequence[int]], ids: np.ndarray, *, where: str, strict: bool
) -> np.ndarray:
    """(n,) int64 group index of each row of ``ids``; ``strict`` demands a full partition."""
    row_of = {int(person): row for row, person in enumerate(ids.tolist())}
    labels = np.full(ids.size, -1, dtype=np.int64)
    if isinstance(groups, (str, bytes)) or not isinstance(groups, Iterable):
        raise ValueError(f"{where}: expected a sequence of groups of person ids, found {groups!r}")
    n_groups = 0
    for g, group in enumerate(groups):
        if isinstance(group, (str, bytes)) or not isinstance(group, Iterable):
            raise ValueError(
                f"{where}: group {g} must be a sequence of person ids, found {group!r}"
            )
        members = list(group)
        if not members:
            raise ValueError(f"{where}: group {g} is empty")
        for member in members:
            if isinstance(member, (bool, np.bool_)) or not isinstance(member, (int, np.integer)):
                raise ValueError(
                    f"{where}: group {g} holds {member!r}, expected an integer person id"
                )
            row = row_of.get(int(member))
            if row is None:
                raise ValueError(
                    f"{where}: person {int(member)} (group {g}) is not in the frame "
                    f"(ids {sorted(row_of)})"
                )
            if labels[row] >= 0:
                raise ValueError(
                    f"{where}: person {int(member)} appears twice (again in group {g})"
                )
            labels[row] = n_groups
        n_groups += 1
    missing = labels < 0
    if np.any(missing):
        if strict:
            raise ValueError(
                f"{where}: person {int(ids[missing][0])} is in no group; a prediction must be a "
                "full partition of the frame's ids, singletons included"
            )
        labels[missing] = n_groups + np.arange(int(missing.sum()))
    return labels


def check_partition(
    partition: Iterable[Sequence[int]], frame: Frame, *, where: str = "partition"
) -> None:
    """Checks that ``partition`` covers every id of ``frame`` exactly once.

    Raises:
        ValueError: naming ``where`` and the first offending person (unknown, listed twice or
            in no group) or an empty or malformed group.
    """
    _labels(partition, frame.ids, where=where, strict=True)


def _pair_equal(labels: np.ndarray) -> np.ndarray:
    """(n(n-1)/2,) bool: same label, for the pairs ``np.triu_indices(n, 1)``."""
    rows, cols = np.triu_indices(labels.size, k=1)
    return labels[rows] == labels[cols]


def pair_labels(frame: Frame, groups: Iterable[Sequence[int]] | None = None) -> np.ndarray:
    """Pair labels of one frame: 1 when the two people are in the same group, else 0.

    Args:
        frame: the frame; its row order defines the pairs.
        groups: groups of the frame's ids (people in no group are alone). ``None`` takes the
            frame's ground truth.

    Returns:
        (n(n-1)/2,) int64 labels, for the pairs ``(i, j)`` of rows in ``np.triu_indices(n, 1)``
        order (row-major, i < j).

    Raises:
        ValueError: if ``groups`` is None and the frame is not annotated, or ``groups`` names
            people not in the frame or someone twice.
    """
    if groups is None:
        if frame.groups is None:
            raise ValueError("frame is not annotated: pass groups or use an annotated frame")
        groups = frame.groups
    labels = _labels(groups, frame.ids, where="groups", strict=False)
    return _pair_equal(labels).astype(np.int64)


@dataclass(frozen=True)
class MicroScores:
    """Counts pooled over frames, and the precision, recall and F1 they give.

    Precision is 1 when nothing was detected and recall is 1 when there was nothing to find
    (the same conventions as the per-frame scores).
    """

    tp: int
    fp: int
    fn: int

    @property
    def precision(self) -> float:
        detected = self.tp + self.fp
        return 1.0 if detected == 0 else self.tp / detected

    @property
    def recall(self) -> float:
        true = self.tp + self.fn
        return 1.0 if true == 0 else self.tp / true

    @property
    def f1(self) -> float:
        return f1_score(self.precision, self.recall)


@dataclass(frozen=True)
class SizeScores:
    """Matching results for one group size, pooled over frames.

    Attributes:
        size: group size (people).
        true_groups: true F-formations of this size.
        true_matched: of them, how many were matched (recall numerator).
        detected_groups: detected F-formations of this size.
        detected_matched: of them, how many matched a true group (precision numerator).
    """

    size: int
    true_groups: int
    true_matched: int
    detected_groups: int
    detected_matched: int

    @property
    def recall(self) -> float | None:
        """Share of true groups of this size that were matched; None when there were none."""
        return None if self.true_groups == 0 else self.true_matched / self.true_groups

    @property
    def precision(self) -> float | None:
        """Share of detected groups of this size that matched; None when none were detected."""
        return None if self.detected_groups == 0 else self.detected_matched / self.detected_groups


@dataclass(frozen=True, eq=False)
class ThresholdScores:
    """Scores at one matching threshold.

    Attributes:
        threshold: T, exact.
        precision: P̄, the mean of the per-frame precisions.
        recall: R̄, the mean of the per-frame recalls.
        f1: ``2·P̄·R̄/(P̄+R̄)``, the F1 of the means.
        micro: TP, FP, FN summed over frames, and their P/R/F1.
        by_size: one entry per group size seen (true or detected), increasing.
        frame_precision: (n_frames,) float64 per-frame precision.
        frame_recall: (n_frames,) float64 per-frame recall.
        frame_tp, frame_fp, frame_fn: (n_frames,) int64 per-frame counts.
    """

    threshold: Fraction
    precision: float
    recall: float
    f1: float
    micro: MicroScores
    by_size: tuple[SizeScores, ...]
    frame_precision: np.ndarray
    frame_recall: np.ndarray
    frame_tp: np.ndarray
    frame_fp: np.ndarray
    frame_fn: np.ndarray


def _readonly(array: np.ndarray) -> np.ndarray:
    array = np.array(array, copy=True)
    array.flags.writeable = False
    return array


@dataclass(frozen=True, eq=False)
class Evaluation:
    """Per-frame evaluation records of one detector on the annotated frames of a dataset.

    Aggregates are computed from the records on demand, so a subset (``select``) is scored by
    exactly the same code. Build it with :func:`evaluate`.

    Attributes:
        thresholds: the thresholds scored, exact.
        frame_index: (n_frames,) int64 position of each evaluated frame in the input.
        sequence: n_frames sequence names.
        time: (n_frames,) float64 time stamps, seconds.
        pairs: (n_frames,) int64 number of pairs per frame.
        pairs_correct: (n_frames,) int64 pairs whose predicted label equals the true label.
        pairs_true_together: (n_frames,) int64 pairs together in the ground truth.
        pairs_predicted_together: (n_frames,) int64 pairs predicted together.
        true_frame: (n_true,) int64 frame (row of the records) of each true F-formation.
        true_size: (n_true,) int64 size of each true F-formation.
        true_matched: (n_thresholds, n_true) bool: matched at each threshold.
        detected_frame: (n_detected,) int64 frame of each detected F-formation.
        detected_size: (n_detected,) int64 size of each detected F-formation.
        detected_matched: (n_thresholds, n_detected) bool: matched a true group.
    """

    thresholds: tuple[Fraction, ...]
    frame_index: np.ndarray
    sequence: tuple[str, ...]
    time: np.ndarray
    pairs: np.ndarray
    pairs_correct: np.ndarray
    pairs_true_together: np.ndarray
    pairs_predicted_together: np.ndarray
    true_frame: np.ndarray
    true_size: np.ndarray
    true_matched: np.ndarray
    detected_frame: np.ndarray
    detected_size: np.ndarray
    detected_matched: np.ndarray

    def __post_init__(self) -> None:
        for name in (
            "frame_index",
            "time",
            "pairs",
            "pairs_correct",
            "pairs_true_together",
            "pairs_predicted_together",
            "true_frame",
            "true_size",
            "true_matched",
            "detected_frame",
            "detected_size",
            "detected_matched",
        ):
            object.__setattr__(self, name, _readonly(getattr(self, name)))
        object.__setattr__(self, "thresholds", tuple(_threshold(t) for t in self.thresholds))
        object.__setattr__(self, "sequence", tuple(self.sequence))
        n = self.frame_index.size
        if len(self.sequence) != n or self.time.shape != (n,):
            raise ValueError(f"sequence and time must have {n} entries")
        k = len(self.thresholds)
        if self.true_matched.shape != (k, self.true_size.size):
            raise ValueError(
                f"true_matched must have shape {(k, self.true_size.size)}, "
                f"got {self.true_matched.shape}"
            )
        if self.detected_matched.shape != (k, self.detected_size.size):
            raise ValueError(
                f"detected_matched must have shape {(k, self.detected_size.size)}, "
                f"got {self.detected_matched.shape}"
            )

    @property
    def n_frames(self) -> int:
        """Number of annotated frames evaluated."""
        return int(self.frame_index.size)

    @property
    def pairwise_accuracy(self) -> float:
        """Share of pairs, pooled over frames, labelled correctly (NaN when there are none)."""
        total = int(self.pairs.sum())
        return math.nan if total == 0 else int(self.pairs_correct.sum()) / total

    def __getitem__(self, threshold: Any) -> ThresholdScores:
        return self.at(threshold)

    def at(self, threshold: Any) -> ThresholdScores:
        """Scores at ``threshold`` (one of ``self.thresholds``; ``"2/3"`` or ``Fraction(2, 3)``)."""
        t = _threshold(threshold)
        if t not in self.thresholds:
            raise KeyError(
                f"threshold {t} was not evaluated (thresholds {[str(x) for x in self.thresholds]})"
            )
        k = self.thresholds.index(t)
        n = self.n_frames
        n_true = np.bincount(self.true_frame, minlength=n)
        n_detected = np.bincount(self.detected_frame, minlength=n)
        tp = np.bincount(self.true_frame, weights=self.true_matched[k], minlength=n).astype(
            np.int64
        )
        fp = n_detected - tp
        fn = n_true - tp
        with np.errstate(divide="ignore", invalid="ignore"):
            frame_precision = np.where(n_detected > 0, tp / np.maximum(n_detected, 1), 1.0)
            frame_recall = np.where(n_true > 0, tp / np.maximum(n_true, 1), 1.0)
        precision = float(frame_precision.mean()) if n else math.nan
        recall = float(frame_recall.mean()) if n else math.nan
        micro = MicroScores(tp=int(tp.sum()), fp=int(fp.sum()), fn=int(fn.sum()))
        return ThresholdScores(
            threshold=t,
            precision=precision,
            recall=recall,
            f1=f1_score(precision, recall),
            micro=micro,
            by_size=self._by_size(k),
            frame_precision=_readonly(frame_precision),
            frame_recall=_readonly(frame_recall),
            frame_tp=_readonly(tp),
            frame_fp=_readonly(fp),
            frame_fn=_readonly(fn),
        )

    def _by_size(self, k: int) -> tuple[SizeScores, ...]:
        sizes = np.concatenate([self.true_size, self.detected_size])
        if sizes.size == 0:
            return ()
        m = int(sizes.max()) + 1
        true_n = np.bincount(self.true_size, minlength=m)
        true_hit = np.bincount(self.true_size, weights=self.true_matched[k], minlength=m)
        det_n = np.bincount(self.detected_size, minlength=m)
        det_hit = np.bincount(self.detected_size, weights=self.detected_matched[k], minlength=m)
        return tuple(
            SizeScores(
                size=s,
                true_groups=int(true_n[s]),
                true_matched=int(true_hit[s]),
                detected_groups=int(det_n[s]),
                detected_matched=int(det_hit[s]),
            )
            for s in range(m)
            if true_n[s] or det_n[s]
        )

    def select(self, mask: Any = None, *, sequence: str | None = None) -> Evaluation:
        """The records of a subset of the frames, e.g. one sequence.

        Args:
            mask: (n_frames,) bool over the evaluated frames, or None for all.
            sequence: keep only frames of this sequence.
        """
        keep = np.ones(self.n_frames, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        if keep.shape != (self.n_frames,):
            raise ValueError(f"mask must have shape ({self.n_frames},), got {keep.shape}")
        if sequence is not None:
            keep = keep & (np.asarray(self.sequence, dtype=object) == sequence)
        new_row = np.cumsum(keep) - 1
        true_keep = keep[self.true_frame]
        det_keep = keep[self.detected_frame]
        return Evaluation(
            thresholds=self.thresholds,
            frame_index=self.frame_index[keep],
            sequence=tuple(s for s, k in zip(self.sequence, keep, strict=True) if k),
            time=self.time[keep],
            pairs=self.pairs[keep],
            pairs_correct=self.pairs_correct[keep],
            pairs_true_together=self.pairs_true_together[keep],
            pairs_predicted_together=self.pairs_predicted_together[keep],
            true_frame=new_row[self.true_frame[true_keep]],
            true_size=self.true_size[true_keep],
            true_matched=self.true_matched[:, true_keep],
            detected_frame=new_row[self.detected_frame[det_keep]],
            detected_size=self.detected_size[det_keep],
            detected_matched=self.detected_matched[:, det_keep],
        )

    def to_json(
        self,
        *,
        detector: str,
        dataset: str,
        detector_params: Mapping[str, Any] | None = None,
        source: str | None = None,
        per_frame: bool = False,
    ) -> dict[str, Any]:
        """A JSON-ready dict in the documented schema (docs/json-schema.md).

        Args:
            detector: the detector's name, e.g. ``"majority"``.
            dataset: the dataset's name, e.g. ``"salsa"``.
            detector_params: the detector's parameters (``get_params()``), JSON-ready.
            source: where the dataset came from (a path).
            per_frame: also list every frame's scores under ``"per_frame"``.
        """
        from reform import __version__

        result: dict[str, Any] = {
            "schema_version": JSON_SCHEMA_VERSION,
            "kind": "reform-sim/evaluation",
            "reform_version": __version__,
            "protocol": PROTOCOL,
            "detector": detector,
            "detector_params": dict(detector_params or {}),
            "dataset": dataset,
            "source": source,
            "frames": self.n_frames,
            "sequences": {s: int(c) for s, c in _count(self.sequence).items()},
            "pairs": {
                "total": int(self.pairs.sum()),
                "correct": int(self.pairs_correct.sum()),
                "true_together": int(self.pairs_true_together.sum()),
                "predicted_together": int(self.pairs_predicted_together.sum()),
            },
            "pairwise_accuracy": json_float(self.pairwise_accuracy),
            "thresholds": [str(t) for t in self.thresholds],
        }
        scores = [self.at(t) for t in self.thresholds]
        for s in scores:
            result[str(s.threshold)] = {
                "precision": json_float(s.precision),
                "recall": json_float(s.recall),
                "f1": json_float(s.f1),
                "micro": {
                    "precision": s.micro.precision,
                    "recall": s.micro.recall,
                    "f1": s.micro.f1,
                    "tp": s.micro.tp,
                    "fp": s.micro.fp,
                    "fn": s.micro.fn,
                },
                "by_size": [
                    {
                        "size": b.size,
                        "true_groups": b.true_groups,
                        "true_matched": b.true_matched,
                        "recall": b.recall,
                        "detected_groups": b.detected_groups,
                        "detected_matched": b.detected_matched,
                        "precision": b.precision,
                    }
                    for b in s.by_size
                ],
            }
        names = list(dict.fromkeys(self.sequence))
        if len(names) > 1:
            result["by_sequence"] = {
                name: self._summary(self.select(sequence=name)) for name in names
            }
        if per_frame:
            result["per_frame"] = [
                {
                    "index": int(self.frame_index[i]),
                    "sequence": self.sequence[i],
                    "time": float(self.time[i]),
                    "pairs": int(self.pairs[i]),
                    "pairs_correct": int(self.pairs_correct[i]),
                    **{
                        str(s.threshold): {
                            "precision": float(s.frame_precision[i]),
                            "recall": float(s.frame_recall[i]),
                            "tp": int(s.frame_tp[i]),
                            "fp": int(s.frame_fp[i]),
                            "fn": int(s.frame_fn[i]),
                        }
                        for s in scores
                    },
                }
                for i in range(self.n_frames)
            ]
        return result

    @staticmethod
    def _summary(evaluation: Evaluation) -> dict[str, Any]:
        """Frames, pairwise accuracy and frame-mean P/R/F1 per threshold, JSON-ready."""
        summary: dict[str, Any] = {
            "frames": evaluation.n_frames,
            "pairwise_accuracy": json_float(evaluation.pairwise_accuracy),
        }
        for t in evaluation.thresholds:
            s = evaluation.at(t)
            summary[str(t)] = {
                "precision": json_float(s.precision),
                "recall": json_float(s.recall),
                "f1": json_float(s.f1),
            }
        return summary


def _count(items: Iterable[str]) -> dict[str, int]:
    counts: dict[str, int] = {}
    for item in items:
        counts[item] = counts.get(item, 0) + 1
    return counts


def _describe(frame: Frame, index: int) -> str:
    where = f"predictions[{index}]"
    details = []
    if frame.sequence:
        details.append(f"sequence {frame.sequence!r}")
    details.append(f"time {frame.time:g} s")
    return f"{where} ({', '.join(details)})"


_INT_TYPES = (int, np.integer)
_BOOL_TYPES = (bool, np.bool_)


def _raise_first_error(partitions: Sequence[Any], frames: Sequence[Frame], *, strict: bool) -> None:
    """Finds and raises the first malformed partition, with its frame in the message."""
    for index, (partition, frame) in enumerate(zip(partitions, frames, strict=True)):
        _labels(partition, frame.ids, where=_describe(frame, index), strict=strict)
    raise ValueError("predictions are malformed (no single frame could be blamed)")


def _group_ids(
    partitions: Sequence[Any],
    frames: Sequence[Frame],
    *,
    person_frame: np.ndarray,
    person_code: np.ndarray,
    vocabulary: np.ndarray,
    strict: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Global group index of every person of every frame, vectorised over frames.

    Args:
        partitions: one sequence of groups per frame.
        frames: the frames.
        person_frame: (P,) frame of each person, all frames' people concatenated.
        person_code: (P,) index of each person's id in ``vocabulary``.
        vocabulary: sorted unique ids of all frames.
        strict: demand full partitions; otherwise people in no group become singletons.

    Returns:
        ``gid`` (P,) group of each person (groups numbered across frames, in frame order) and
        ``group_frame`` (n_groups,) the frame of each group.

    Raises:
        ValueError: for the first frame whose partition is malformed (see ``_labels``).
    """
    n_people = person_frame.size
    try:
        partitions = [tuple(partition) for partition in partitions]
        groups = [tuple(group) for partition in partitions for group in partition]
        members = [member for group in groups for member in group]
        types = set(map(type, members))
        if not all(issubclass(t, _INT_TYPES) and not issubclass(t, _BOOL_TYPES) for t in types):
            raise TypeError("non-integer person id")
        member_ids = np.array(members, dtype=np.int64)
    except (TypeError, ValueError, OverflowError):
        _raise_first_error(partitions, frames, strict=strict)
    n_groups = np.array([len(partition) for partition in partitions], dtype=np.int64)
    group_size = np.array([len(group) for group in groups], dtype=np.int64)
    group_frame = np.repeat(np.arange(len(partitions), dtype=np.int64), n_groups)
    member_group = np.repeat(np.arange(len(groups), dtype=np.int64), group_size)
    member_frame = group_frame[member_group]

    # Find each member among the people of its frame: keys (frame, id code), sorted.
    code = np.searchsorted(vocabulary, member_ids).clip(max=max(vocabulary.size - 1, 0))
    known = vocabulary[code] == member_ids if vocabulary.size else np.zeros(member_ids.size, bool)
    width = max(vocabulary.size, 1)
    person_key = person_frame * width + person_code
    member_key = member_frame * width + code
    order = np.argsort(person_key, kind="stable")
    position = np.searchsorted(person_key[order], member_key).clip(max=max(n_people - 1, 0))
    row = order[position] if n_people else position
    found = known & (person_key[row] == member_key) if n_people else known
    listed = np.bincount(row[found], minlength=n_people)
    if (
        not found.all()
        or np.any(listed > 1)
        or np.any(group_size == 0)
        or (strict and np.any(listed == 0))
    ):
        _raise_first_error(partitions, frames, strict=strict)
    gid = np.full(n_people, -1, dtype=np.int64)
    gid[row] = member_group
    if not strict:
        alone = np.flatnonzero(gid < 0)
        gid[alone] = len(groups) + np.arange(alone.size)
        group_frame = np.concatenate([group_frame, person_frame[alone]])
    return gid, group_frame


def _unseen_members(
    frames: Sequence[Frame], true_gid: np.ndarray, true_frame: np.ndarray, n_people: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Members of each true group who are absent from their frame, and the true groups' frames
    with one true group appended per listed group that has no member present.

    Returns:
        ``unseen`` (n_groups',) absent members per true group and ``true_frame`` (n_groups',).
    """
    start = np.concatenate([[0], np.cumsum(n_people)[:-1]]).astype(np.int64)
    extra_unseen: list[int] = []
    extra_frame: list[int] = []
    unseen = np.zeros(true_frame.size, dtype=np.int64)
    for index, frame in enumerate(frames):
        if frame.listed_groups is None or frame.groups is None:
            continue
        row_of = {int(person): row for row, person in enumerate(frame.ids.tolist())}
        for group in frame.listed_groups:
            rows = [row_of[m] for m in group if m in row_of]
            absent = len(group) - len(rows)
            if rows:
                unseen[true_gid[start[index] + rows[0]]] += absent
            else:
                extra_unseen.append(absent)
                extra_frame.append(index)
    if extra_unseen:
        unseen = np.concatenate([unseen, np.array(extra_unseen, dtype=np.int64)])
        true_frame = np.concatenate([true_frame, np.array(extra_frame, dtype=np.int64)])
    return unseen, true_frame


def _pairs(size: np.ndarray) -> np.ndarray:
    return size * (size - 1) // 2


def evaluate(
    frames: Sequence[Frame],
    predictions: Sequence[Sequence[Group]],
    *,
    thresholds: Iterable[Any] = THRESHOLDS,
) -> Evaluation:
    """Scores predicted partitions against the ground truth of the annotated frames.

    Args:
        frames: the frames (a Dataset works too). Frames without ground truth are skipped.
        predictions: one partition per frame, in the same order: groups (tuples of person ids)
            covering every id of the frame exactly once, singletons included. Every prediction
            is checked, also those of frames without ground truth.
        thresholds: matching thresholds, exact (``Fraction``, int or ``"p/q"``), each in (1/2, 1].

    Returns:
        The per-frame records; ``.pairwise_accuracy``, ``.at("2/3")`` etc. give the scores.

    Raises:
        ValueError: if the lengths differ, a prediction is not a partition of its frame's ids
            (the message names the frame's index, sequence and time and the person), no frame is
            annotated, or a threshold is not exact or lies outside (1/2, 1].
    """
    frames = tuple(frames)
    predictions = list(predictions)
    thresholds = tuple(dict.fromkeys(_threshold(t) for t in thresholds))
    if not thresholds:
        raise ValueError("thresholds must hold at least one threshold, got none")
    if len(predictions) != len(frames):
        raise ValueError(
            f"predictions must hold one partition per frame: expected {len(frames)}, "
            f"found {len(predictions)}"
        )
    for index, frame in enumerate(frames):
        if not isinstance(frame, Frame):
            raise ValueError(f"frames[{index}] must be a reform.Frame, got {type(frame).__name__}")
    annotated = np.array([frame.groups is not None for frame in frames], dtype=bool)

    # Everyone of every frame, concatenated; ids coded into one sorted vocabulary.
    n_people = np.array([frame.n_people for frame in frames], dtype=np.int64)
    person_frame = np.repeat(np.arange(len(frames), dtype=np.int64), n_people)
    all_ids = np.concatenate([frame.ids for frame in frames]) if frames else np.zeros(0, np.int64)
    vocabulary, person_code = np.unique(all_ids, return_inverse=True)
    coding = {
        "person_frame": person_frame,
        "person_code": person_code.reshape(-1),
        "vocabulary": vocabulary,
    }
    pred_gid, pred_frame = _group_ids(predictions, frames, strict=True, **coding)
    if not annotated.any():
        raise ValueError(
            f"frames must include annotated frames (with ground truth), found none of {len(frames)}"
        )
    truth = [frame.groups if frame.groups is not None else () for frame in frames]
    true_gid, true_frame = _group_ids(truth, frames, strict=False, **coding)
    # Ground-truth members absent from their frame (``Frame.listed_groups``) count in the size
    # of their true group, and a listed group with no one present is a true group of its own.
    unseen, true_frame = _unseen_members(frames, true_gid, true_frame, n_people)

    # Only the annotated frames' people count; groups of other frames end up of size 0.
    keep = annotated[person_frame]
    true_gid, pred_gid = true_gid[keep], pred_gid[keep]
    present_size = np.bincount(true_gid, minlength=true_frame.size)
    true_size = present_size + unseen
    pred_size = np.bincount(pred_gid, minlength=pred_frame.size)
    # Non-empty cells of the contingency table (true group x detected group): |G ∩ D|.
    cell, overlap = np.unique(true_gid * max(pred_frame.size, 1) + pred_gid, return_counts=True)
    cell_true, cell_pred = np.divmod(cell, max(pred_frame.size, 1))
    largest = np.maximum(true_size[cell_true], pred_size[cell_pred])
    # Singletons dropped: only cells between groups of two or more can match.
    candidate = (true_size[cell_true] >= 2) & (pred_size[cell_pred] >= 2)
    true_hit = np.zeros((len(thresholds), true_frame.size), dtype=bool)
    pred_hit = np.zeros((len(thresholds), pred_frame.size), dtype=bool)
    for k, t in enumerate(thresholds):
        # |G∩D| / max(|G|, |D|) >= p/q, exactly: q·|G∩D| >= p·max.
        hit = candidate & (t.denominator * overlap >= t.numerator * largest)
        true_hit[k, cell_true[hit]] = True
        pred_hit[k, cell_pred[hit]] = True

    row_of_frame = np.cumsum(annotated) - 1
    n_rows = int(annotated.sum())
    true_ff = true_size >= 2
    pred_ff = pred_size >= 2
    pairs = _pairs(n_people[annotated])
    true_in = annotated[true_frame]
    pred_in = annotated[pred_frame]
    # Pairs are the frame's people's: absent members form none.
    true_together = np.bincount(
        row_of_frame[true_frame[true_in]], weights=_pairs(present_size[true_in]), minlength=n_rows
    ).astype(np.int64)
    pred_together = np.bincount(
        row_of_frame[pred_frame[pred_in]], weights=_pairs(pred_size[pred_in]), minlength=n_rows
    ).astype(np.int64)
    both_together = np.bincount(
        row_of_frame[true_frame[cell_true]], weights=_pairs(overlap), minlength=n_rows
    ).astype(np.int64)
    return Evaluation(
        thresholds=thresholds,
        frame_index=np.flatnonzero(annotated),
        sequence=tuple(frame.sequence for frame in frames if frame.groups is not None),
        time=np.array([frame.time for frame in frames if frame.groups is not None], dtype=float),
        pairs=pairs,
        pairs_correct=pairs - true_together - pred_together + 2 * both_together,
        pairs_true_together=true_together,
        pairs_predicted_together=pred_together,
        true_frame=row_of_frame[true_frame[true_ff]],
        true_size=true_size[true_ff],
        true_matched=true_hit[:, true_ff],
        detected_frame=row_of_frame[pred_frame[pred_ff]],
        detected_size=pred_size[pred_ff],
        detected_matched=pred_hit[:, pred_ff],
    )
