"""REFORM (Hedayati et al., IROS 2020): split a frame into pairs, classify them, rebuild groups.

:class:`Reform` is a scikit-learn estimator over frames: ``fit`` learns a pairwise classifier
from the pairs of annotated frames, ``predict`` returns each frame's full partition of its
people into F-formations and singletons.

Within a frame, people are taken in order of their ids, so Greedy Reconstruction's tie-break
("lowest pair first") refers to ids and a frame's prediction does not depend on the order its
rows are stored in.

The defaults are the paper's method. Three options go beyond it, each compared in
``docs/guide/reform.md`` ("Options beyond the paper"): scale-free pair features
(``features="relative"``, :mod:`reform.features`), correlation clustering over the pair
probabilities (``reconstruction="correlation"``, :mod:`reform.reconstruction`) and calibrated
probabilities (``calibration="sigmoid"`` or ``"isotonic"``).
"""

from __future__ import annotations

import contextlib
import gc
import math
import operator
import time
from collections.abc import Iterable, Iterator, Sequence
from typing import Any

import numpy as np
from scipy.spatial import KDTree
from sklearn.base import BaseEstimator, clone
from sklearn.utils.validation import check_is_fitted

from reform.classifiers import bagged_trees
from reform.fast import PairClassifier, compile_classifier, sklearn_pair_labels
from reform.features import (
    DEFAULT_FEATURES,
    DISTANCE,
    batch_pair_features,
    check_features,
    frame_arrays,
    frame_pair_features,
    pair_indices,
)
from reform.frame import Frame, Group, check_frames
from reform.metrics import pair_labels
from reform.reconstruction import (
    CORRELATION,
    UNION,
    batch_correlation_labels,
    batch_greedy_labels,
    check_reconstruction,
    graph_greedy_labels,
)
from reform.splits import time_blocks

CHUNK_PAIRS = 1 << 18  # pairs classified at once when predicting many frames
# Seconds a detector spends in its scikit-learn classifier before it compiles it (reform.fast),
# about what compiling Bagged Trees' table takes (0.2 s): a short run (a few hundred frames of a
# party: 0.06 s) is not worth it, a long run, a stream of frames or a crowd is, and no run
# spends more than twice what the better choice would have (same labels either way).
COMPILE_AFTER_S = 0.2
LARGE_FRAME_PEOPLE = 256  # frames of more people are predicted one by one, keeping only the
# pairs predicted together (Reform.predict notes)
SEARCH_MARGIN = 1e-9  # relative: the neighbour search reaches this much beyond the distance
# from which the classifier says apart, so that its own rounding can only add pairs
MAX_FRAME_BYTES = 8 * 2**30  # bytes: the most predicting (or fitting on) one frame may take; a
# frame whose pairs would take more is refused, naming it, before anything is allocated
# Memory per pair, measured with tracemalloc at the peak of predict and training_pairs on frames
# of 64 to 2,000 people (a frame of n people has n(n-1)/2 pairs):
PAIR_BYTES = 40  # bytes per pair predicted: indices, features, labels, temporaries
SMALL_FRAME_PAIR_BYTES = 256  # bytes per pair of a frame of LARGE_FRAME_PEOPLE or fewer: the
# Relation Matrix, the pair features and the reconstruction's working copies
TRAINING_PAIR_BYTES = 88  # bytes per pair of training_pairs: features, labels, indices
CALIBRATIONS = ("sigmoid", "isotonic")  # sklearn.calibration.CalibratedClassifierCV methods
CALIBRATION_FOLDS = 5  # stretches of time per sequence (reform.time_blocks), one fold each
# Options added after the first model files: left out of a saved model while at their default,
# so that a default model's file stays the one earlier versions wrote (see __getstate__).
_LATER_DEFAULTS = {"calibration": None}

Partition = tuple[Group, ...]

__all__ = ["MAX_FRAME_BYTES", "Reform", "frame_bytes", "training_pairs"]


class Reform(BaseEstimator):
    """REFORM F-formation detector.

    Args:
        classifier: an unfitted scikit-learn classifier for pairs (cloned at ``fit``); None for
            the ready-made bagged trees (:func:`reform.classifiers.bagged_trees`).
        features: pair features, names from :data:`reform.features.FEATURES`; the paper's are
            Distance and Effort Angle (the default).
            A feature set's name is accepted too: ``"paper"`` (the same two) or ``"relative"``
            (scale-free: distances divided by the frame's own scale, see
            :mod:`reform.features`), for models that must work on datasets of other scales.
        reconstruction: ``"union"`` (the paper's Greedy Reconstruction), ``"intersection"``, or
            ``"correlation"``: correlation clustering over the pair probabilities (needs a
            classifier with ``predict_proba``; :mod:`reform.reconstruction`).
        threshold: None to take the classifier's own decision; else a probability in (0, 1): a
            pair is together when ``predict_proba`` gives it at least this. Needs a classifier
            with ``predict_proba``. With ``"correlation"``, the probability at which a pair
            weighs nothing (None: 0.5).
        fast: classify with the compiled classifier of :mod:`reform.fast` (same labels, much
            faster), compiled once it pays: after `COMPILE_AFTER_S` spent in scikit-learn's,
            at a crowd's frame, or at `compile`. False calls the scikit-learn classifier once
            per batch.
        calibration: None (the classifier's own probabilities), ``"sigmoid"`` (Platt) or
            ``"isotonic"``: the classifier is wrapped in scikit-learn's
            ``CalibratedClassifierCV``, whose folds are stretches of time
            (:func:`reform.time_blocks`, `CALIBRATION_FOLDS` per sequence, ``GroupKFold``): in
            each fold a copy of the classifier is fitted on the other stretches and calibrated
            on the held-out one, so no calibration is learnt on the neighbours of the frames
            its classifier trained on; the probability is the folds' average (scikit-learn's
            ``ensemble=True``: one classifier per fold, so predicting costs that many times
            more). Changes the decision (argmax of the calibrated probability) and what
            ``"correlation"`` weighs.

    Attributes:
        classifier_: the fitted pair classifier.
        features_: the features it was fitted on.
        training_summary_: what it was trained on: frames, pairs, together pairs, sequences,
            people per frame.
    """

    def __init__(
        self,
        classifier: Any = None,
        *,
        features: str | Sequence[str] = DEFAULT_FEATURES,
        reconstruction: str = UNION,
        threshold: float | None = None,
        fast: bool = True,
        calibration: str | None = None,
    ) -> None:
        self.classifier = classifier
        self.features = features
        self.reconstruction = reconstruction
        self.threshold = threshold
        self.fast = fast
        self.calibration = calibration

    # ----------------------------------------------------------------------------------------
    # scikit-learn protocol

    def fit(self, frames: Iterable[Frame], y: None = None) -> Reform:  # noqa: ARG002 (sklearn API)
        """Learns the pair classifier from the pairs of annotated frames.

        Args:
            frames: annotated frames (a :class:`reform.Dataset` works too).
            y: ignored; the labels come from the frames' ground truth.

        Returns:
            self.

        Raises:
            ValueError: no frames, a frame without ground truth, no pairs, pairs of one label
                only, a bad parameter.
            TypeError: an entry that is not a Frame.
        """
        frames = check_frames(frames, caller="fit")
        features = check_features(self.features)
        check_reconstruction(self.reconstruction)
        check_calibration(self.calibration)
        classifier = bagged_trees() if self.classifier is None else clone(self.classifier)
        _check_threshold(self.threshold, classifier)
        if self.reconstruction == CORRELATION and not hasattr(classifier, "predict_proba"):
            raise ValueError(
                f"reconstruction={CORRELATION!r} needs a classifier with predict_proba, "
                f"got {type(classifier).__name__}, which has none"
            )
        if not frames:
            raise ValueError("fit needs annotated frames, got none")
        missing = [k for k, frame in enumerate(frames) if frame.groups is None]
        if missing:
            first = frames[missing[0]]
            raise ValueError(
                f"fit needs ground truth in every frame: {len(missing)} of {len(frames)} frames "
                f"have none (first: frames[{missing[0]}], sequence {first.sequence!r}, "
                f"time {first.time:g} s); "
                "pass only annotated frames, e.g. dataset.annotated()"
            )
        _check_frame_sizes(frames, predict=False)
        x, y_all, frame_of_pair = training_pairs(frames, features=features)
        if y_all.size == 0:
            raise ValueError(
                f"fit needs frames with at least 2 people, got {len(frames)} frames of 0 or 1"
            )
        together = int(y_all.sum())
        if together in (0, y_all.size):
            kind = "apart (the ground truth holds no F-formation)" if together == 0 else "together"
            raise ValueError(f"fit needs pairs of both kinds, got {y_all.size} pairs, all {kind}")
        if self.calibration is None:
            classifier.fit(x, y_all)
        else:
            classifier = _calibrated_fit(
                classifier, self.calibration, x, y_all, time_blocks_of(frames)[frame_of_pair]
            )
        classes = np.asarray(classifier.classes_)
        if classes.tolist() != [0, 1]:
            raise ValueError(f"classifier must learn classes [0, 1], got {classes.tolist()}")
        self.classifier_ = classifier
        self.features_ = features
        self.training_summary_ = _summary(frames, y_all)
        self._compiled = None
        self._sklearn_s = 0.0
        return self

    def compile(self) -> Reform:
        """Compiles the classifier now (:mod:`reform.fast`) rather than once it pays: for
        timing a long run's pace from its first frame. Same labels; no-op without ``fast``."""
        check_is_fitted(self, "classifier_")
        self._pair_classifier(now=True)
        return self

    max_frame_bytes = MAX_FRAME_BYTES  # the most it takes on one frame (larger are refused)

    def frame_bytes(self, n_people: int) -> int:
        """Bytes it takes at its peak to predict one frame of ``n_people``: up to
        `LARGE_FRAME_PEOPLE`, `SMALL_FRAME_PAIR_BYTES` a pair (the whole Relation Matrix and
        its reconstruction); beyond, what its guard counts (:func:`frame_bytes`: every pair
        classified at once; a crowd's sparse pair graph takes less)."""
        if n_people <= LARGE_FRAME_PEOPLE:
            return n_people * (n_people - 1) // 2 * SMALL_FRAME_PAIR_BYTES
        return frame_bytes(n_people)

    def predict(self, frames: Iterable[Frame]) -> list[Partition]:
        """Each frame's F-formations as a full partition of its people.

        Args:
            frames: frames (annotated or not), any number of people each.

        Returns:
            One partition per frame: tuples of person ids, groups ordered by their smallest id,
            members ascending, singletons included.

        A frame of more than `LARGE_FRAME_PEOPLE` people (a crowd) is predicted on its own:
        its pairs are classified a chunk at a time, only those predicted together are kept,
        and Greedy Reconstruction runs on each connected component of them
        (:func:`reform.reconstruction.graph_greedy_labels`), so memory grows with the people
        and the pairs predicted together, not with the square of the people. Where the
        compiled classifier says apart for every pair from some Distance on, whatever its
        other features (a tree ensemble's table knows it: :mod:`reform.fast`), only the pairs
        closer than that are classified, found with a k-d tree; every other pair would be
        classified apart. Same partitions as classifying every pair.

        Raises:
            ValueError: a frame whose pairs would take more than `MAX_FRAME_BYTES` to classify
                and reconstruct (:func:`frame_bytes`), naming it, before any frame is predicted.
        """
        check_is_fitted(self, "classifier_")
        return self._run(check_frames(frames, caller="predict"), partitions=True, pairs=False)[0]

    def predict_pairs(self, frames: Iterable[Frame]) -> list[np.ndarray]:
        """The classifier's pair labels, before reconstruction.

        Args:
            frames: frames.

        Returns:
            Per frame, (n(n-1)/2,) bool labels over the frame's rows in
            :func:`reform.features.pair_indices` order (the order of
            :func:`reform.metrics.pair_labels`).
        """
        check_is_fitted(self, "classifier_")
        return self._run(
            check_frames(frames, caller="predict_pairs"), partitions=False, pairs=True
        )[1]

    def _run(
        self, frames: Sequence[Frame], *, partitions: bool, pairs: bool
    ) -> tuple[list[Partition], list[np.ndarray]]:
        """Partitions and/or pair labels of frames, classified once, in chunks of one size."""
        _check_frame_sizes(frames, predict=True)
        out: list[Partition] = [()] * len(frames) if partitions else []
        out_pairs: list[np.ndarray] = [np.zeros(0, dtype=bool)] * len(frames) if pairs else []
        crowd = partitions and not pairs and self.reconstruction != CORRELATION
        for n, positions in _by_size(frames).items():
            if n < 2:
                if partitions:
                    for k in positions:
                        out[k] = tuple((int(person),) for person in np.sort(frames[k].ids))
                continue
            if crowd and n > LARGE_FRAME_PEOPLE:
                for k in positions:
                    out[k] = self._predict_crowd(frames[k])
                continue
            i, j = pair_indices(n)
            step = max(1, CHUNK_PAIRS // i.size)
            for start in range(0, len(positions), step):
                chunk = positions[start : start + step]
                chunk_frames = [frames[k] for k in chunk]
                correlation = partitions and self.reconstruction == CORRELATION
                if correlation:
                    ids, probability = self._classify_chunk(chunk_frames, n, proba=True)
                    labels = batch_correlation_labels(probability, n, threshold=self.threshold)
                if pairs or not correlation:
                    ids, pair_labels = self._classify_chunk(chunk_frames, n)
                if partitions:
                    if not correlation:
                        labels = batch_greedy_labels(pair_labels, n, variant=self.reconstruction)
                    for k, partition in zip(chunk, _partitions(labels, ids), strict=True):
                        out[k] = partition
                if pairs:
                    for k, row in zip(chunk, pair_labels, strict=True):
                        out_pairs[k] = _frame_order(row, frames[k].ids, i, j)
        return out, out_pairs

    def _predict_crowd(self, frame: Frame) -> Partition:
        """One large frame's partition from the pairs predicted together (see :meth:`predict`)."""
        order = _id_order(frame)
        ordered = frame if order is None else _reordered(frame, order)
        arrays = frame_arrays(ordered)
        compiled = self._pair_classifier(now=True)  # a crowd pays, and its table skips far pairs
        first, second = [np.zeros(0, dtype=np.intp)], [np.zeros(0, dtype=np.intp)]
        for i, j in self._candidate_pairs(arrays["position"], compiled):
            x = batch_pair_features(
                arrays["position"][None],
                arrays["yaw"][None],
                features=self.features_,
                head_position=_one(arrays["head_position"]),
                head_yaw=_one(arrays["head_yaw"]),
                is_robot=_one(arrays["is_robot"]),
                pairs=(i, j),
            )[0]
            if compiled is None:
                together = self._sklearn_labels(x)
            else:
                together = compiled.predict(x)
            first.append(i[together])
            second.append(j[together])
        labels = graph_greedy_labels(
            ordered.n_people,
            np.concatenate(first),
            np.concatenate(second),
            variant=self.reconstruction,
        )
        return _partitions(labels[None], ordered.ids[None])[0]

    def _candidate_pairs(
        self, position: np.ndarray, compiled: PairClassifier | None
    ) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """Rows ``(i, j)``, ``i < j``, of the pairs a crowd's classifier must see, a chunk at a
        time: those closer than the Distance from which it says apart, else all."""
        apart = None
        if compiled is not None and DISTANCE in self.features_:
            apart = compiled.apart_from(self.features_.index(DISTANCE))
        if apart is None:
            yield from _row_blocks(position.shape[0], CHUNK_PAIRS)
            return
        if apart <= 0:  # every pair is apart
            return
        near = KDTree(position).query_pairs(apart * (1 + SEARCH_MARGIN), output_type="ndarray")
        near = near.astype(np.intp, copy=False)
        for start in range(0, near.shape[0], CHUNK_PAIRS):
            yield near[start : start + CHUNK_PAIRS, 0], near[start : start + CHUNK_PAIRS, 1]

    def predict_pair_proba(self, frames: Iterable[Frame]) -> list[np.ndarray]:
        """The classifier's pair probabilities (of being together), before reconstruction.

        Args:
            frames: frames.

        Returns:
            Per frame, (n(n-1)/2,) float64 probabilities over the frame's rows in
            :func:`reform.features.pair_indices` order.

        Raises:
            ValueError: the classifier has no ``predict_proba``.
        """
        check_is_fitted(self, "classifier_")
        frames = check_frames(frames, caller="predict_pair_proba")
        if not hasattr(self.classifier_, "predict_proba"):
            raise ValueError(
                f"predict_pair_proba needs a classifier with predict_proba, "
                f"got {type(self.classifier_).__name__}, which has none"
            )
        _check_frame_sizes(frames, predict=True)
        out = [np.zeros(0)] * len(frames)
        for n, positions in _by_size(frames).items():
            if n < 2:
                continue
            i, j = pair_indices(n)
            step = max(1, CHUNK_PAIRS // i.size)
            for start in range(0, len(positions), step):
                chunk = positions[start : start + step]
                _, probability = self._classify_chunk([frames[k] for k in chunk], n, proba=True)
                for k, row in zip(chunk, probability, strict=True):
                    out[k] = _frame_order(row, frames[k].ids, i, j)
        return out

    def predict_relation_matrix(self, frame: Frame) -> np.ndarray:
        """The Relation Matrix of one frame, rows and columns in the frame's row order.

        Returns:
            (n, n) bool, symmetric, diagonal True.
        """
        n = frame.n_people
        labels = self.predict_pairs([frame])[0]
        matrix = np.eye(n, dtype=bool)
        i, j = pair_indices(n)
        matrix[i, j] = labels
        matrix[j, i] = labels
        return matrix

    # ----------------------------------------------------------------------------------------
    # internals

    def __getstate__(self) -> dict[str, Any]:
        state = dict(super().__getstate__())  # object.__getstate__ gives the live __dict__
        state.pop("_compiled", None)  # derived from classifier_, rebuilt on demand
        state.pop("_sklearn_s", None)
        for name, default in _LATER_DEFAULTS.items():
            if name in state and state[name] is default:
                del state[name]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        super().__setstate__({**_LATER_DEFAULTS, **state})

    def _pair_classifier(self, *, now: bool = False) -> PairClassifier | None:
        """The compiled classifier (None: classify with scikit-learn's), compiled once it pays:
        ``now``, or once this detector has spent `COMPILE_AFTER_S` in scikit-learn's
        (`_sklearn_labels`); never without ``fast``."""
        compiled = getattr(self, "_compiled", None)
        if compiled is None and self.fast and (now or self._sklearn_seconds() >= COMPILE_AFTER_S):
            compiled = compile_classifier(self.classifier_, threshold=self.threshold)
            self._compiled = compiled
        return compiled

    def _sklearn_seconds(self) -> float:
        return getattr(self, "_sklearn_s", 0.0)

    def _sklearn_labels(self, x: np.ndarray) -> np.ndarray:
        """Pair labels by the scikit-learn classifier, its time counted (`_pair_classifier`)."""
        started = time.perf_counter()
        labels = sklearn_pair_labels(self.classifier_, x, threshold=self.threshold)
        self._sklearn_s = self._sklearn_seconds() + time.perf_counter() - started
        return labels

    def _classify_chunk(
        self, frames: list[Frame], n: int, *, proba: bool = False
    ) -> tuple[np.ndarray, np.ndarray]:
        """(F, n) ids in id order and (F, n(n-1)/2) bool pair labels of frames of n people
        (float64 probabilities of being together with ``proba``)."""
        count = len(frames)
        ids = np.concatenate([frame.ids for frame in frames]).reshape(count, n)
        position = np.concatenate([frame.position for frame in frames]).reshape(count, n, 2)
        yaw = np.concatenate([frame.yaw for frame in frames]).reshape(count, n)
        head_position = head_yaw = is_robot = None
        features = self.features_
        if any(name.startswith("head_") for name in features):
            head_position = np.stack(
                [
                    np.full((n, 2), np.nan) if f.head_position is None else f.head_position
                    for f in frames
                ]
            )
            head_yaw = np.stack(
                [np.full(n, np.nan) if f.head_yaw is None else f.head_yaw for f in frames]
            )
        if "involves_robot" in features:
            is_robot = np.stack([frame.is_robot for frame in frames])
        if not np.all(ids[:, 1:] > ids[:, :-1]):
            order = np.argsort(ids, axis=1, kind="stable")
            ids = np.take_along_axis(ids, order, axis=1)
            position = np.take_along_axis(position, order[..., None], axis=1)
            yaw = np.take_along_axis(yaw, order, axis=1)
            if head_position is not None:
                head_position = np.take_along_axis(head_position, order[..., None], axis=1)
                head_yaw = np.take_along_axis(head_yaw, order, axis=1)
            if is_robot is not None:
                is_robot = np.take_along_axis(is_robot, order, axis=1)
        x = batch_pair_features(
            position,
            yaw,
            features=features,
            head_position=head_position,
            head_yaw=head_yaw,
            is_robot=is_robot,
        )
        flat = x.reshape(-1, x.shape[-1])
        if proba:
            column = int(np.flatnonzero(np.asarray(self.classifier_.classes_) == 1)[0])
            probability = np.asarray(self.classifier_.predict_proba(flat), dtype=np.float64)
            return ids, probability[:, column].reshape(len(frames), -1)
        compiled = self._pair_classifier()
        if compiled is None:
            labels = self._sklearn_labels(flat)
        else:
            labels = compiled.predict(flat)
        return ids, labels.reshape(len(frames), -1)


def training_pairs(
    frames: Sequence[Frame], *, features: Sequence[str] = DEFAULT_FEATURES
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The deconstruction of annotated frames into labelled pairs, as :meth:`Reform.fit` sees it.

    People are taken in order of their ids in every frame.

    Args:
        frames: annotated frames.
        features: pair features.

    Returns:
        ``(x, y, frame)``: (m, k) float64 features, (m,) int64 labels (1 = same F-formation),
        (m,) int64 index of each pair's frame in ``frames``.

    Raises:
        ValueError: a frame whose pairs would take more than `MAX_FRAME_BYTES`, naming it.
    """
    features = check_features(features)
    _check_frame_sizes(frames, predict=False)
    x_parts, y_parts, frame_parts = [], [], []
    for k, frame in enumerate(frames):
        order = _id_order(frame)
        ordered = frame if order is None else _reordered(frame, order)
        x_parts.append(frame_pair_features(ordered, features=features))
        y_parts.append(pair_labels(ordered))
        frame_parts.append(np.full(y_parts[-1].size, k, dtype=np.int64))
    if not x_parts:
        return np.zeros((0, len(features))), np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(x_parts), np.concatenate(y_parts), np.concatenate(frame_parts)


def _frame_order(labels: np.ndarray, ids: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Pair values (labels or probabilities) over people in id order -> the same pairs over the
    frame's own rows."""
    if np.all(ids[1:] > ids[:-1]):
        return labels.copy()
    n = ids.size
    order = np.argsort(ids, kind="stable")  # row s in id order is frame row order[s]
    matrix = np.zeros((n, n), dtype=labels.dtype)
    matrix[order[i], order[j]] = labels
    matrix[order[j], order[i]] = labels
    return matrix[i, j]


def frame_bytes(n_people: int, *, predict: bool = True) -> int:
    """Bytes of memory REFORM takes at its peak on one frame of ``n_people``: classifying all
    its pairs at once (pair features and labels, as ``predict_pairs`` does; ``predict`` on a
    crowd takes less, see :meth:`Reform.predict`), or with ``predict=False`` turning it into
    training pairs."""
    pairs = n_people * (n_people - 1) // 2
    return pairs * (PAIR_BYTES if predict else TRAINING_PAIR_BYTES)


def _row_blocks(n: int, chunk: int) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """All pairs ``(i, j)``, ``i < j``, of ``n`` people in :func:`pair_indices` order, in
    blocks of whole rows of about ``chunk`` pairs (at least one row)."""
    row = 0
    while row < n - 1:
        stop, size = row, 0
        while stop < n - 1 and (size == 0 or size + (n - 1 - stop) <= chunk):
            size += n - 1 - stop
            stop += 1
        counts = n - 1 - np.arange(row, stop)
        i = np.repeat(np.arange(row, stop), counts)
        starts = np.cumsum(counts) - counts
        j = i + 1 + (np.arange(size) - np.repeat(starts, counts))
        yield i, j
        row = stop


def _one(array: np.ndarray | None) -> np.ndarray | None:
    """An array of one frame as a batch of one."""
    return None if array is None else array[None]


def _check_frame_sizes(frames: Sequence[Frame], *, predict: bool) -> None:
    """Refuses the first frame whose pairs would take more than `MAX_FRAME_BYTES`, before any
    of them is deconstructed."""
    for size in sorted({frame.n_people for frame in frames}, reverse=True):
        needed = frame_bytes(size, predict=predict)
        if needed <= MAX_FRAME_BYTES:
            return
        frame = next(f for f in frames if f.n_people == size)
        sequence = f" of sequence {frame.sequence!r}" if frame.sequence else ""
        work = "classify and reconstruct" if predict else "deconstruct"
        raise ValueError(
            f"the frame at time {frame.time:g} s{sequence} holds {size:,} people: "
            f"{size * (size - 1) // 2:,} pairs, which would take about {needed / 2**30:,.1f} GiB "
            f"to {work}, more than reform.detector.MAX_FRAME_BYTES = {MAX_FRAME_BYTES / 2**30:g} "
            "GiB"
        )


def check_calibration(calibration: str | None) -> str | None:
    """Validates the ``calibration`` option: None or one of `CALIBRATIONS`."""
    if calibration is not None and (
        not isinstance(calibration, str) or calibration not in CALIBRATIONS
    ):
        raise ValueError(f"calibration must be None or one of {CALIBRATIONS}, got {calibration!r}")
    return calibration


def time_blocks_of(frames: Sequence[Frame]) -> np.ndarray:
    """The calibration folds' groups: each frame's stretch of time (`CALIBRATION_FOLDS` per
    sequence, :func:`reform.time_blocks`)."""
    return time_blocks(frames, CALIBRATION_FOLDS)


def _calibrated_fit(
    classifier: Any, method: str, x: np.ndarray, y: np.ndarray, groups: np.ndarray
) -> Any:
    """``CalibratedClassifierCV(classifier, method)`` fitted on the pairs, its folds the
    stretches of time ``groups`` (``GroupKFold``). (``ensemble=False`` would keep one classifier,
    but scikit-learn 1.9 does not hand the groups to its folds there.)"""
    from sklearn import config_context
    from sklearn.calibration import CalibratedClassifierCV
    from sklearn.model_selection import GroupKFold

    n_groups = np.unique(groups).size
    if n_groups < 2:
        raise ValueError(
            f"calibration={method!r} needs training frames spread over at least 2 stretches of "
            f"time (reform.time_blocks), got {n_groups}"
        )
    folds = GroupKFold(n_splits=min(CALIBRATION_FOLDS, n_groups))
    for k, (_, held_out) in enumerate(folds.split(x, y, groups)):
        kinds = np.unique(y[held_out]).size
        rest = np.unique(np.delete(y, held_out)).size
        if kinds < 2 or rest < 2:
            raise ValueError(
                f"calibration={method!r}: fold {k} of {folds.n_splits} (stretches of time) "
                "holds pairs of one label only, on its held-out or its training side; train "
                "on more frames, or without calibration"
            )
    calibrated = CalibratedClassifierCV(classifier, method=method, cv=folds, ensemble=True)
    with config_context(enable_metadata_routing=True):  # hands the groups to the folds
        return calibrated.fit(x, y, groups=groups)


def _check_threshold(threshold: float | None, classifier: Any) -> None:
    if threshold is None:
        return
    if (
        isinstance(threshold, bool)
        or not isinstance(threshold, (int, float))
        or not 0 < threshold < 1
    ):
        raise ValueError(f"threshold must be None or a probability in (0, 1), got {threshold!r}")
    if not math.isfinite(threshold):
        raise ValueError(f"threshold must be finite, got {threshold!r}")
    if not hasattr(classifier, "predict_proba"):
        raise ValueError(
            f"threshold={threshold} needs a classifier with predict_proba, "
            f"got {type(classifier).__name__}, which has none"
        )


def _id_order(frame: Frame) -> np.ndarray | None:
    ids = frame.ids
    if ids.size < 2 or np.all(ids[1:] > ids[:-1]):
        return None
    return np.argsort(ids, kind="stable")


def _reordered(frame: Frame, order: np.ndarray) -> Frame:
    return frame.replace(
        ids=frame.ids[order],
        position=frame.position[order],
        yaw=frame.yaw[order],
        kinds=tuple(frame.kinds[k] for k in order),
        head_position=None if frame.head_position is None else frame.head_position[order],
        head_yaw=None if frame.head_yaw is None else frame.head_yaw[order],
    )


def _by_size(frames: Sequence[Frame]) -> dict[int, list[int]]:
    groups: dict[int, list[int]] = {}
    for k, frame in enumerate(frames):
        groups.setdefault(frame.n_people, []).append(k)
    return groups


def _partitions(labels: np.ndarray, ids: np.ndarray) -> list[Partition]:
    """Partitions from (F, n) group labels and (F, n) ids, in id order.

    Sorting each frame's people by label lines its groups up (a group's label is its first
    member, so groups come ordered by their smallest id). Over the whole chunk, the sorted ids
    form one tuple and every group is a slice of it: one ``operator.itemgetter`` call cuts all
    groups, and each frame's partition is a slice of the tuple of groups.
    """
    n_frames, n = labels.shape
    if n_frames == 0:
        return []
    order = np.argsort(labels, axis=1, kind="stable")
    sorted_labels = np.take_along_axis(labels, order, axis=1)
    sorted_ids = np.take_along_axis(ids, order, axis=1)
    opens = np.ones((n_frames, n), dtype=bool)  # a group starts here
    np.not_equal(sorted_labels[:, 1:], sorted_labels[:, :-1], out=opens[:, 1:])
    starts = np.flatnonzero(opens)
    ends = np.append(starts[1:], n_frames * n)
    frame_end = np.cumsum(np.count_nonzero(opens, axis=1)).tolist()
    with _collector_paused():  # tuples of ints cannot form cycles: spare the collector's scans
        flat = tuple(sorted_ids.ravel().tolist())
        cut = operator.itemgetter(*map(slice, starts.tolist(), ends.tolist()))
        groups = cut(flat) if starts.size > 1 else (cut(flat),)
        return [groups[a:b] for a, b in zip([0, *frame_end[:-1]], frame_end, strict=True)]


@contextlib.contextmanager
def _collector_paused() -> Iterator[None]:
    """Pauses Python's cyclic garbage collector while building many acyclic tuples."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def _summary(frames: Sequence[Frame], targets: np.ndarray) -> dict[str, Any]:
    people = [frame.n_people for frame in frames]
    sequences = sorted({frame.sequence for frame in frames})
    spans = {}
    for name in sequences:
        times = [frame.time for frame in frames if frame.sequence == name]
        spans[name] = [float(min(times)), float(max(times))]
    return {
        "frames": len(frames),
        "pairs": int(targets.size),
        "together_pairs": int(targets.sum()),
        "people_per_frame": [int(min(people)), int(max(people))],
        "sequences": sequences,
        "time_span_s": spans,
    }
