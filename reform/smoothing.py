"""Temporal filters: any detector's partitions made steadier over the frames of a sequence.

A detector that answers frame by frame flickers: a pair at the edge of its decision is together
in one frame and apart in the next, and every flip is a false join or leave
(:mod:`reform.temporal`). Two filters, each wrapping any detector:

* :class:`SlidingMajority`: a pair is together at time ``t`` when the wrapped detector put them
  together in more than half of the frames of the same sequence with times in
  ``(t - window, t]`` in which both were present. The window looks back only (a robot cannot
  wait for the future), so a real change shows after about half the window. The partition is
  rebuilt from the voted pairs by Greedy Reconstruction (:mod:`reform.reconstruction`).
* :class:`Hysteresis`: for detectors with pair probabilities (``predict_pair_proba``, REFORM's),
  a pair apart becomes together once its probability reaches ``high`` and a pair together
  becomes apart once it falls to ``low``; in between it keeps its last state. A pair seen for
  the first time, or again after a gap longer than ``window``, starts from the detector's own
  decision (probability at least one half).

Both filter the frames handed to one ``predict`` call, each sequence on its own, in time order
(whatever order the frames come in; the answer is in the order given). A frame's filtered
partition depends only on the frames of its sequence at or before it.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from typing import Any

import numpy as np

from reform.estimator import Estimator
from reform.features import pair_indices
from reform.frame import Frame, Group, check_frames, complete_partition
from reform.reconstruction import UNION, batch_greedy_labels, partition_from_labels

__all__ = ["Hysteresis", "SlidingMajority", "make_hysteresis", "make_smoothed"]

MAX_WINDOW_S = 3600.0  # seconds: the longest window either filter accepts
TIME_SLACK_S = 1e-6  # seconds: times this close to a window's edge count as on it
PAIR_BYTES = 256  # bytes per pair of a frame a filter holds: its key, vote or state in Python


def _check_window(window: Any, *, who: str) -> float:
    if isinstance(window, bool) or not isinstance(window, (int, float)):
        raise ValueError(f"{who}: window must be a number of seconds, got {window!r}")
    if not 0.0 < float(window) <= MAX_WINDOW_S:
        raise ValueError(f"{who}: window must lie in (0, {MAX_WINDOW_S:g}] seconds, got {window!r}")
    return float(window)


def _sequences(frames: Sequence[Frame]) -> list[list[int]]:
    """Indices of ``frames`` per sequence, each in time order."""
    by_sequence: dict[str, list[int]] = {}
    for index, frame in enumerate(frames):
        by_sequence.setdefault(frame.sequence, []).append(index)
    return [sorted(rows, key=lambda k: frames[k].time) for rows in by_sequence.values()]


def _pair_keys(ids: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows ``(i, j)`` of a frame's pairs and a key per pair that does not depend on row order."""
    i, j = pair_indices(len(ids))
    a, b = ids[i].astype(np.int64), ids[j].astype(np.int64)
    low, high = np.minimum(a, b), np.maximum(a, b)
    return i, j, (low << 32) | (high & 0xFFFFFFFF)


def _together(partition: Sequence[Group], ids: np.ndarray, i: np.ndarray, j: np.ndarray):
    """Whether rows ``i[k]`` and ``j[k]`` share a group of ``partition``."""
    label = {int(m): g for g, members in enumerate(partition) for m in members}
    rows = np.array([label.get(int(p), -1 - r) for r, p in enumerate(ids)], dtype=np.int64)
    return rows[i] == rows[j]


def _rebuild(together: np.ndarray, ids: np.ndarray) -> tuple[Group, ...]:
    """The partition Greedy Reconstruction makes of one frame's voted pairs."""
    n = len(ids)
    if n < 2:
        return tuple((int(p),) for p in ids)
    labels = batch_greedy_labels(together[None, :], n, variant=UNION)[0]
    return partition_from_labels(labels, ids.tolist())


class _Filter(Estimator):
    """What both filters share: the wrapped detector learns when the filter is fitted."""

    detector: Any

    def frame_bytes(self, n_people: int) -> int | None:
        """Bytes it takes at its peak on one frame of ``n_people``: the wrapped detector's
        (None when that does not say) and `PAIR_BYTES` a pair."""
        method = getattr(self.detector, "frame_bytes", None)
        inner = method(n_people) if callable(method) else None
        return None if inner is None else inner + n_people * (n_people - 1) // 2 * PAIR_BYTES

    def fit(self, frames: Sequence[Frame]) -> _Filter:
        """Fits the wrapped detector on ``frames`` when it learns; returns ``self``."""
        fit = getattr(self.detector, "fit", None)
        if callable(fit):
            self.detector = fit(frames) or self.detector
        return self

    def __sklearn_is_fitted__(self) -> bool:
        return True


class SlidingMajority(_Filter):
    """A detector's partitions voted over a window of past frames, pair by pair.

    Args:
        detector: any object with ``predict(frames)`` (fitted, if it learns).
        window: seconds looked back, the current frame included: (0, 3600].

    Example:
        >>> steady = SlidingMajority(Gcff(), window=2.0)   # doctest: +SKIP
        >>> steady.predict(frames)                          # doctest: +SKIP
    """

    def __init__(self, detector: Any = None, *, window: float = 2.0) -> None:
        self.detector = detector
        self.window = window

    def predict(self, frames: Sequence[Frame]) -> list[tuple[Group, ...]]:
        """One partition per frame, in the order given: the pair votes over each window."""
        window = _check_window(self.window, who="SlidingMajority")
        frames = check_frames(frames, caller="SlidingMajority.predict")
        raw = [
            complete_partition(p, f.ids.tolist())
            for p, f in zip(self.detector.predict(frames), frames, strict=True)
        ]
        out: list[tuple[Group, ...]] = [()] * len(frames)
        for rows in _sequences(frames):
            history: deque[tuple[float, list[int], list[bool]]] = deque()
            votes: dict[int, list[int]] = {}  # pair key -> [frames together, frames both seen]
            for k in rows:
                frame = frames[k]
                i, j, keys = _pair_keys(frame.ids)
                key_list = keys.tolist()
                together = _together(raw[k], frame.ids, i, j).tolist()
                history.append((frame.time, key_list, together))
                for key, both in zip(key_list, together, strict=True):
                    count = votes.setdefault(key, [0, 0])
                    count[0] += both
                    count[1] += 1
                while history[0][0] <= frame.time - window + TIME_SLACK_S:
                    _, old_keys, old_together = history.popleft()
                    for key, both in zip(old_keys, old_together, strict=True):
                        count = votes[key]
                        count[0] -= both
                        count[1] -= 1
                voted = np.array([2 * votes[key][0] > votes[key][1] for key in key_list], bool)
                out[k] = _rebuild(voted, frame.ids)
        return out


class Hysteresis(_Filter):
    """A detector's pair probabilities switched with two thresholds, pair by pair over time.

    Args:
        detector: a fitted detector with ``predict_pair_proba(frames)`` (per frame, the
            probabilities of its pairs in :func:`reform.features.pair_indices` order).
        high: probability at which a pair apart becomes together, in (0.5, 1).
        low: probability at which a pair together becomes apart, in (0, 0.5).
        window: seconds after which a pair not seen starts afresh, (0, 3600].
    """

    def __init__(
        self, detector: Any = None, *, high: float = 0.7, low: float = 0.3, window: float = 2.0
    ) -> None:
        self.detector = detector
        self.high = high
        self.low = low
        self.window = window

    def _check(self) -> float:
        window = _check_window(self.window, who="Hysteresis")
        for name, value, low, high in (("high", self.high, 0.5, 1.0), ("low", self.low, 0.0, 0.5)):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"Hysteresis: {name} must be a probability, got {value!r}")
            if not low < float(value) < high:
                raise ValueError(
                    f"Hysteresis: {name} must lie in ({low:g}, {high:g}), got {value!r}"
                )
        if not callable(getattr(self.detector, "predict_pair_proba", None)):
            raise ValueError(
                f"Hysteresis needs a detector with pair probabilities (predict_pair_proba), got "
                f"{type(self.detector).__name__}, which has none"
            )
        return window

    def predict(self, frames: Sequence[Frame]) -> list[tuple[Group, ...]]:
        """One partition per frame, in the order given: each pair switched with hysteresis."""
        window = self._check()
        frames = check_frames(frames, caller="Hysteresis.predict")
        probabilities = self.detector.predict_pair_proba(frames)
        out: list[tuple[Group, ...]] = [()] * len(frames)
        for rows in _sequences(frames):
            state: dict[int, tuple[bool, float]] = {}  # pair key -> (together, last seen)
            for k in rows:
                frame = frames[k]
                _, _, keys = _pair_keys(frame.ids)
                p = np.asarray(probabilities[k], dtype=np.float64)
                together = np.empty(len(keys), dtype=bool)
                for r, (key, q) in enumerate(zip(keys.tolist(), p.tolist(), strict=True)):
                    last = state.get(key)
                    fresh = last is None or frame.time - last[1] > window + TIME_SLACK_S
                    if fresh or math.isnan(q):
                        now = q >= 0.5
                    elif last[0]:
                        now = q > self.low
                    else:
                        now = q >= self.high
                    together[r] = now
                    state[key] = (now, frame.time)
                out[k] = _rebuild(together, frame.ids)
        return out


def _inner(wrapper: str, detector: str, *, needs: tuple[str, ...]) -> tuple[str, Any]:
    """The detector a filter wraps: a catalogued name (its defaults) or a settings file
    (`reform.settings`, what `reform-sim tune` writes), made by the catalogue."""
    from reform.detectors import DetectorError, detector_info, make_detector
    from reform.settings import read_settings

    if detector.endswith(".json"):
        settings = read_settings(detector)
        name, options = settings.detector, dict(settings.options)
    else:
        name, options = detector, {}
    info = detector_info(name)
    if info.needs not in needs or name in ("smoothed", "hysteresis"):
        what = {"": "runs as it is", "dataset": "needs a dataset", "training": "learns first"}
        raise DetectorError(
            f"detector {wrapper!r}: option detector={detector!r} {what[info.needs]}; "
            f"{wrapper} wraps a detector that "
            + (" or ".join(what[n] for n in needs))
            + " (give a catalogued name, or a settings file written by `reform-sim tune`)"
        )
    return name, make_detector(name, **options)


def make_smoothed(*, detector: str = "gcff", window: float = 2.0) -> SlidingMajority:
    """The catalogue's ``smoothed``: ``detector`` (a catalogued name that runs as it is, or a
    settings file) voted over ``window`` seconds by :class:`SlidingMajority`."""
    _, inner = _inner("smoothed", detector, needs=("",))
    _check_window(window, who="smoothed")
    return SlidingMajority(inner, window=window)


def make_hysteresis(
    *, detector: str = "reform-trained", high: float = 0.7, low: float = 0.3, window: float = 2.0
) -> Hysteresis:
    """The catalogue's ``hysteresis``: ``detector`` (a catalogued REFORM configuration, trained
    on the training frames the filter is given) switched by :class:`Hysteresis`."""
    _, inner = _inner("hysteresis", detector, needs=("training",))
    filtered = Hysteresis(inner, high=high, low=low, window=window)
    filtered._check()
    return filtered
