"""Temporal metrics of a detector: its group events against the ground truth's, and how well it
keeps a group's identity (the definitions, with worked examples, are in the "Groups in time"
guide).

The events of the true and of the detected groups follow the same rules (`reform.events`), on
the same annotated frames. Then:

* **Matching.** A detected event matches a true event when both are of the same kind, in the
  same sequence, at most ``tolerance_s`` apart (a nanosecond of slack absorbs floating-point
  times), the person is the same (``joins``, ``leaves``) and the groups they concern match at
  the field's threshold, ``|G ∩ D| / max(|G|, |D|) >= 2/3`` (the event's ``members``: the group
  formed, dissolved, joined, left, merged into or split). The matching is one-to-one and greedy:
  candidate pairs are taken in order of increasing time difference (to the nanosecond, so that
  equal gaps between floating-point times tie), then true event (time, position), then detected
  event (position), each event at most once.
* **Recall and precision**, per kind and pooled over kinds: matched true events over true
  events, matched detected events over detected events; None where there are none.
* **Latency** of a matched pair: the detected event's time minus the true one's, seconds
  (negative when the detector was early); its median and 95th percentile (numpy's linear
  interpolation) over the matched pairs, None without any.
* **False events per minute** (flicker): detected events that matched none, per minute of the
  sequences (each from its first to its last annotated frame).
* **Identity switches**, as CLEAR MOT counts them for objects: in every annotated frame each
  true F-formation is matched to the detected F-formation passing the 2/3 threshold with it
  (unique: T > 1/2); a switch is counted when a true group's matched detected track differs
  from the one it was last matched to, gaps without a match in between allowed.

With more than one sequence, percentile intervals come from a bootstrap over sequences
(`reform.bootstrap.bootstrap_weights` with one cluster per sequence): each resample draws the
sequences with replacement and pools their counts.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from reform.bootstrap import DEFAULT_LEVEL, DEFAULT_RESAMPLES, Interval, bootstrap_weights
from reform.events import (
    EVENT_KINDS,
    GroupEvent,
    _follow,
    _Sequence,
    _split_sequences,
    _Tracking,
    _where,
)
from reform.frame import Frame
from reform.json_values import json_float, json_record
from reform.metrics import T_TWO_THIRDS, check_partition

__all__ = [
    "DEFAULT_TOLERANCE_S",
    "MEMBER_THRESHOLD",
    "KindScores",
    "TemporalEvaluation",
    "check_temporal",
    "evaluate_events",
    "frame_interval",
]

DEFAULT_TOLERANCE_S = 1.0  # seconds between a true event and the detected event matching it
MEMBER_THRESHOLD = T_TWO_THIRDS  # |G ∩ D| / max(|G|, |D|) for two events' groups to match
_TIME_SLACK_S = 1e-9  # seconds: absorbs floating-point times (0.1 steps) in comparisons
_SLACK_DIGITS = 9  # decimals of a second kept when time differences are compared for ties
_P = MEMBER_THRESHOLD.numerator
_Q = MEMBER_THRESHOLD.denominator


@dataclass(frozen=True)
class KindScores:
    """Matching results for one kind of event.

    Attributes:
        kind: one of `reform.events.EVENT_KINDS`.
        true_events: events of this kind in the ground truth.
        detected_events: events of this kind in the detection.
        matched: matched pairs.
        recall: ``matched / true_events``; None when there are no true events.
        precision: ``matched / detected_events``; None when there are no detected events.
    """

    kind: str
    true_events: int
    detected_events: int
    matched: int
    recall: float | None
    precision: float | None

    def to_json(self) -> dict[str, Any]:
        return json_record(self)


@dataclass(frozen=True, eq=False)
class TemporalEvaluation:
    """Temporal scores of one detector on the annotated frames of some sequences. Build it with
    :func:`evaluate_events`.

    Attributes:
        tolerance_s: the matching window, seconds.
        sequences: names of the sequences, in order of first appearance.
        frames: annotated frames scored.
        minutes: summed length of the sequences, first to last annotated frame, minutes.
        by_kind: one entry per kind, in `reform.events.EVENT_KINDS` order.
        recall: matched true events over true events, all kinds; None without true events.
        precision: matched detected events over detected events; None without detected events.
        latency_median_s: median latency of the matched pairs, seconds; None without any.
        latency_p95_s: its 95th percentile, seconds; None without any.
        false_events: detected events that matched none.
        false_events_per_minute: ``false_events / minutes``.
        identity_switches: times a true group's matched detected track changed.
        true_events: the ground truth's events.
        detected_events: the detection's events (track ids of the detection's own tracking).
        matches: (true index, detected index) of each matched pair, by true index.
        latency_s: (n_matches,) float64 latency of each of ``matches``, seconds.
        intervals: bootstrap intervals over sequences of ``recall``, ``precision``,
            ``latency_median_s``, ``latency_p95_s``, ``false_events_per_minute`` and
            ``identity_switches``; None with a single sequence or no generator.
    """

    tolerance_s: float
    sequences: tuple[str, ...]
    frames: int
    minutes: float
    by_kind: tuple[KindScores, ...]
    recall: float | None
    precision: float | None
    latency_median_s: float | None
    latency_p95_s: float | None
    false_events: int
    false_events_per_minute: float
    identity_switches: int
    true_events: tuple[GroupEvent, ...]
    detected_events: tuple[GroupEvent, ...]
    matches: tuple[tuple[int, int], ...]
    latency_s: np.ndarray
    intervals: Mapping[str, Interval] | None = None

    def __post_init__(self) -> None:
        latency = np.array(self.latency_s, dtype=np.float64, copy=True)
        if latency.shape != (len(self.matches),):
            raise ValueError(
                f"latency_s must have shape ({len(self.matches)},), got {latency.shape}"
            )
        latency.flags.writeable = False
        object.__setattr__(self, "latency_s", latency)
        if self.intervals is not None:
            object.__setattr__(self, "intervals", MappingProxyType(dict(self.intervals)))

    def kind(self, kind: str) -> KindScores:
        """The scores of one kind of event (``"joins"``)."""
        for scores in self.by_kind:
            if scores.kind == kind:
                return scores
        raise KeyError(f"kind must be one of {EVENT_KINDS}, got {kind!r}")

    def to_json(self, *, events: bool = False) -> dict[str, Any]:
        """A JSON-ready dict: the scores, the per-kind counts and the intervals.

        Args:
            events: also list every true and detected event and the matched pairs.
        """
        result: dict[str, Any] = {
            "kind": "reform-sim/temporal-evaluation",
            "tolerance_s": self.tolerance_s,
            "member_threshold": str(MEMBER_THRESHOLD),
            "sequences": list(self.sequences),
            "frames": self.frames,
            "minutes": json_float(self.minutes),
            "recall": json_float(self.recall),
            "precision": json_float(self.precision),
            "by_kind": {s.kind: s.to_json() for s in self.by_kind},
            "latency_s": {
                "matched": len(self.matches),
                "median": json_float(self.latency_median_s),
                "p95": json_float(self.latency_p95_s),
            },
            "false_events": self.false_events,
            "false_events_per_minute": json_float(self.false_events_per_minute),
            "identity_switches": self.identity_switches,
            "true_events": len(self.true_events),
            "detected_events": len(self.detected_events),
            "intervals": None
            if self.intervals is None
            else {name: interval.to_json() for name, interval in self.intervals.items()},
        }
        if events:
            result["events"] = {
                "true": [e.to_json() for e in self.true_events],
                "detected": [e.to_json() for e in self.detected_events],
                "matches": [list(pair) for pair in self.matches],
            }
        return result


def _detected_groups(
    frames: Sequence[Frame], predictions: Sequence[Any], sequences: list[_Sequence]
) -> list[list[Any]]:
    """The detected groups of every sequence's annotated frames; partitions are checked to be
    partitions of their frame's ids (a partition repeated for the same people, once)."""
    out = []
    checked: tuple[Any, bytes] | None = None
    for sequence in sequences:
        groups = []
        for k in sequence.index.tolist():
            frame, prediction = frames[k], predictions[k]
            if isinstance(prediction, Frame):
                if prediction.groups is None:
                    raise ValueError(
                        f"{_where(prediction, k, 'predictions')} has no groups: expected the "
                        "detected groups of an annotated frame"
                    )
                groups.append(prediction.groups)
                continue
            key = (prediction, frame.ids.tobytes())
            if key != checked:
                check_partition(prediction, frame, where=_where(frame, k, "predictions"))
                checked = key
            groups.append(prediction)
        out.append(groups)
    return out


def _check_tolerance(tolerance_s: Any, sequences: list[_Sequence]) -> float:
    if isinstance(tolerance_s, bool) or not isinstance(tolerance_s, (int, float, np.number)):
        raise ValueError(f"tolerance_s must be a number of seconds, got {tolerance_s!r}")
    tolerance = float(tolerance_s)
    if not math.isfinite(tolerance):
        raise ValueError(f"tolerance_s must be finite, got {tolerance}")
    for sequence in sequences:
        interval = float(np.median(np.diff(sequence.time)))
        if tolerance < interval - _TIME_SLACK_S:
            first, last = int(sequence.index[0]), int(sequence.index[-1])
            raise ValueError(
                f"tolerance_s must be at least the frame interval of sequence "
                f"{sequence.name!r} (frames[{first}] to frames[{last}]): expected >= "
                f"{interval:g} s (the median step between its annotated frames), got "
                f"{tolerance:g} s"
            )
    return tolerance


def frame_interval(frames: Sequence[Frame]) -> float:
    """The longest of the sequences' frame intervals (each the median step between its
    annotated frames), seconds: the shortest tolerance every sequence of ``frames`` accepts.

    Raises:
        ValueError: as :func:`evaluate_events` refuses the frames, in one line.
    """
    sequences = _split_sequences(tuple(frames), caller="frame_interval")
    return max(float(np.median(np.diff(sequence.time))) for sequence in sequences)


def check_temporal(frames: Sequence[Frame], tolerance_s: float = DEFAULT_TOLERANCE_S) -> float:
    """Checks, before any detector runs, that ``frames`` can be scored in time with
    ``tolerance_s``, as :func:`evaluate_events` would; returns the tolerance.

    Raises:
        ValueError: one line naming the sequence and the frame (frames out of time order or at
            a repeated time, a sequence with fewer than two annotated frames) or the tolerance
            (below a sequence's frame interval).
    """
    sequences = _split_sequences(tuple(frames), caller="evaluate_events")
    return _check_tolerance(tolerance_s, sequences)


def _match(
    true: list[GroupEvent], detected: list[GroupEvent], tolerance: float
) -> tuple[list[tuple[int, int]], np.ndarray]:
    """One-to-one greedy matching by time difference (see the module's description).

    Returns:
        The matched (true, detected) index pairs, sorted, and their latencies.
    """
    window = tolerance + _TIME_SLACK_S
    by_key: dict[tuple[str, str], list[int]] = {}
    for j, event in enumerate(detected):
        by_key.setdefault((event.sequence, event.kind), []).append(j)
    times = {key: np.array([detected[j].time for j in rows]) for key, rows in by_key.items()}
    true_sets: dict[int, frozenset[int]] = {}
    detected_sets: dict[int, frozenset[int]] = {}
    candidates = []
    for i, event in enumerate(true):
        key = (event.sequence, event.kind)
        rows = by_key.get(key)
        if rows is None:
            continue
        lo = int(np.searchsorted(times[key], event.time - window, "left"))
        hi = int(np.searchsorted(times[key], event.time + window, "right"))
        for j in rows[lo:hi]:
            other = detected[j]
            if other.person != event.person:
                continue
            g = true_sets.setdefault(i, frozenset(event.members))
            d = detected_sets.setdefault(j, frozenset(other.members))
            if _Q * len(g & d) >= _P * max(len(g), len(d)):
                # Rounded to the slack, so that equal gaps between floating-point times tie.
                gap = round(abs(other.time - event.time), _SLACK_DIGITS)
                candidates.append((gap, event.time, i, j))
    candidates.sort()
    used_true: set[int] = set()
    used_detected: set[int] = set()
    pairs = []
    for _, _, i, j in candidates:
        if i not in used_true and j not in used_detected:
            used_true.add(i)
            used_detected.add(j)
            pairs.append((i, j))
    pairs.sort()
    latency = np.array([detected[j].time - true[i].time for i, j in pairs], dtype=np.float64)
    return pairs, latency


def _switches(truth: _Tracking, detection: _Tracking) -> int:
    """Identity switches of one sequence (see the module's description)."""
    changes = sorted(
        [(pos, 0, state) for pos, state in truth.states]
        + [(pos, 1, state) for pos, state in detection.states],
        key=lambda c: (c[0], c[1]),
    )
    true_now: dict[int, frozenset[int]] = {}
    track_of: dict[int, int] = {}  # person -> detected track
    size_of: dict[int, int] = {}  # detected track -> size
    last: dict[int, int] = {}  # true track -> detected track it was last matched to
    switches = 0
    for k, (pos, which, state) in enumerate(changes):
        if which == 0:
            true_now = state
        else:
            track_of = {m: track for track, members in state.items() for m in members}
            size_of = {track: len(members) for track, members in state.items()}
        if k + 1 < len(changes) and changes[k + 1][0] == pos:
            continue  # both changed at this frame: match once, after the second
        for true_track, members in true_now.items():
            shared: dict[int, int] = {}
            for m in members:
                d = track_of.get(m)
                if d is not None:
                    shared[d] = shared.get(d, 0) + 1
            for d, n in shared.items():
                if _Q * n >= _P * max(len(members), size_of[d]):
                    before = last.get(true_track)
                    switches += before is not None and before != d
                    last[true_track] = d
                    break
    return switches


def _ratio(numerator: np.ndarray, denominator: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(denominator > 0, numerator / np.maximum(denominator, 1e-300), np.nan)


def _optional(value: float) -> float | None:
    return None if not math.isfinite(value) else float(value)


def _percentiles(latency: np.ndarray) -> tuple[float, float]:
    if latency.size == 0:
        return math.nan, math.nan
    median, p95 = np.percentile(latency, [50.0, 95.0])
    return float(median), float(p95)


def _intervals(
    names: tuple[str, ...],
    tallies: dict[str, np.ndarray],
    latency: np.ndarray,
    latency_sequence: np.ndarray,
    point: dict[str, float],
    *,
    rng: np.random.Generator,
    resamples: int,
    level: float,
) -> dict[str, Interval]:
    weights = bootstrap_weights(list(names), rng=rng, resamples=resamples)  # (B, n_sequences)
    pooled = {name: weights @ values for name, values in tallies.items()}
    samples = {
        "recall": _ratio(pooled["true_matched"], pooled["true"]),
        "precision": _ratio(pooled["detected_matched"], pooled["detected"]),
        "false_events_per_minute": _ratio(pooled["false"], pooled["minutes"]),
        "identity_switches": pooled["switches"],
    }
    medians = np.full(resamples, np.nan)
    p95s = np.full(resamples, np.nan)
    for b in range(resamples):
        drawn = np.repeat(latency, weights[b, latency_sequence].astype(np.int64))
        medians[b], p95s[b] = _percentiles(drawn)
    samples["latency_median_s"] = medians
    samples["latency_p95_s"] = p95s
    tail = 50.0 * (1.0 - level)
    out = {}
    for name in (
        "recall",
        "precision",
        "latency_median_s",
        "latency_p95_s",
        "false_events_per_minute",
        "identity_switches",
    ):
        finite = samples[name][np.isfinite(samples[name])]
        low, high = np.percentile(finite, [tail, 100.0 - tail]) if finite.size else (np.nan,) * 2
        out[name] = Interval(float(point[name]), float(low), float(high))
    return out


def evaluate_events(
    frames: Sequence[Frame],
    predictions: Sequence[Any],
    *,
    tolerance_s: float = DEFAULT_TOLERANCE_S,
    rng: np.random.Generator | None = None,
    resamples: int = DEFAULT_RESAMPLES,
    level: float = DEFAULT_LEVEL,
) -> TemporalEvaluation:
    """Scores a detector's group events and identities against the ground truth's.

    Args:
        frames: the true frames (a Dataset works too), sequence by sequence in time order;
            frames without ground truth are skipped.
        predictions: one per frame, in the same order: a partition of the frame's ids (groups
            covering every id once, singletons included, as `reform.evaluate` takes them), or a
            `reform.Frame` of the same sequence and time holding the detected groups (an
            observed frame, whose people may differ).
        tolerance_s: largest time between a true event and a detected event that matches it,
            seconds; at least every sequence's frame interval (the median step between its
            annotated frames).
        rng: the generator of the bootstrap over sequences; None: no intervals.
        resamples: bootstrap resamples.
        level: coverage of the intervals, in (0, 1).

    Returns:
        The scores (see the module's description).

    Raises:
        TypeError: if an entry of ``frames`` is not a Frame.
        ValueError: before any work, one line naming the sequence and the frame: a frame out of
            time order or at a time its sequence already had, a sequence with fewer than two
            annotated frames, predictions of another length or whose frames do not align in
            sequence and time, a tolerance below a sequence's frame interval, or a prediction
            that is not a partition of its frame's ids.
    """
    frames = tuple(frames)
    sequences = _split_sequences(frames, caller="evaluate_events")
    predictions = list(predictions)
    if len(predictions) != len(frames):
        raise ValueError(
            f"predictions must hold one partition (or Frame) per frame: expected {len(frames)}, "
            f"found {len(predictions)}"
        )
    for k, (frame, prediction) in enumerate(zip(frames, predictions, strict=True)):
        if isinstance(prediction, Frame) and (
            prediction.sequence != frame.sequence or prediction.time != frame.time
        ):
            raise ValueError(
                f"{_where(prediction, k, 'predictions')} does not align with "
                f"{_where(frame, k)}: expected the same sequence and time"
            )
    tolerance = _check_tolerance(tolerance_s, sequences)
    if rng is not None and not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator or None, got {type(rng).__name__}")
    if isinstance(resamples, bool) or not isinstance(resamples, (int, np.integer)) or resamples < 1:
        raise ValueError(f"resamples must be an int >= 1, got {resamples!r}")
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must lie in (0, 1), got {level!r}")
    detected_groups = _detected_groups(frames, predictions, sequences)

    n = len(sequences)
    kinds = {kind: k for k, kind in enumerate(EVENT_KINDS)}
    true_count = np.zeros((n, len(EVENT_KINDS)), dtype=np.int64)
    detected_count = np.zeros_like(true_count)
    matched_count = np.zeros_like(true_count)
    switches = np.zeros(n, dtype=np.int64)
    minutes = np.array([(s.time[-1] - s.time[0]) / 60.0 for s in sequences])
    true_events: list[GroupEvent] = []
    detected_events: list[GroupEvent] = []
    matches: list[tuple[int, int]] = []
    latencies: list[np.ndarray] = []
    latency_sequence: list[np.ndarray] = []
    next_true = next_detected = 1
    for c, (sequence, groups) in enumerate(zip(sequences, detected_groups, strict=True)):
        truth, next_true = _follow(sequence, next_true)
        detection, next_detected = _follow(
            _Sequence(sequence.name, sequence.index, sequence.time, groups), next_detected
        )
        pairs, latency = _match(truth.events, detection.events, tolerance)
        for events, counts in ((truth.events, true_count), (detection.events, detected_count)):
            np.add.at(counts[c], [kinds[e.kind] for e in events], 1)
        np.add.at(matched_count[c], [kinds[truth.events[i].kind] for i, _ in pairs], 1)
        switches[c] = _switches(truth, detection)
        offset_true, offset_detected = len(true_events), len(detected_events)
        matches += [(i + offset_true, j + offset_detected) for i, j in pairs]
        true_events += truth.events
        detected_events += detection.events
        latencies.append(latency)
        latency_sequence.append(np.full(latency.size, c, dtype=np.int64))

    latency = np.concatenate(latencies)
    total_true, total_detected = true_count.sum(axis=0), detected_count.sum(axis=0)
    total_matched = matched_count.sum(axis=0)
    by_kind = tuple(
        KindScores(
            kind=kind,
            true_events=int(total_true[k]),
            detected_events=int(total_detected[k]),
            matched=int(total_matched[k]),
            recall=_optional(_ratio(total_matched[k], total_true[k])),
            precision=_optional(_ratio(total_matched[k], total_detected[k])),
        )
        for kind, k in kinds.items()
    )
    false_events = len(detected_events) - len(matches)
    recall = float(_ratio(np.float64(len(matches)), np.float64(len(true_events))))
    precision = float(_ratio(np.float64(len(matches)), np.float64(len(detected_events))))
    median, p95 = _percentiles(latency)
    total_minutes = float(minutes.sum())
    point = {
        "recall": recall,
        "precision": precision,
        "latency_median_s": median,
        "latency_p95_s": p95,
        "false_events_per_minute": false_events / total_minutes,
        "identity_switches": float(switches.sum()),
    }
    names = tuple(s.name for s in sequences)
    intervals = None
    if rng is not None and n > 1:
        tallies = {
            "true": true_count.sum(axis=1),
            "true_matched": matched_count.sum(axis=1),
            "detected": detected_count.sum(axis=1),
            "detected_matched": matched_count.sum(axis=1),
            "false": detected_count.sum(axis=1) - matched_count.sum(axis=1),
            "minutes": minutes,
            "switches": switches,
        }
        intervals = _intervals(
            names,
            {k: np.asarray(v, dtype=np.float64) for k, v in tallies.items()},
            latency,
            np.concatenate(latency_sequence),
            point,
            rng=rng,
            resamples=resamples,
            level=level,
        )
    return TemporalEvaluation(
        tolerance_s=tolerance,
        sequences=names,
        frames=int(sum(s.index.size for s in sequences)),
        minutes=total_minutes,
        by_kind=by_kind,
        recall=_optional(recall),
        precision=_optional(precision),
        latency_median_s=_optional(median),
        latency_p95_s=_optional(p95),
        false_events=false_events,
        false_events_per_minute=false_events / total_minutes,
        identity_switches=int(switches.sum()),
        true_events=tuple(true_events),
        detected_events=tuple(detected_events),
        matches=tuple(matches),
        latency_s=latency,
        intervals=intervals,
    )
