"""Fast pairwise classification: a fitted scikit-learn classifier compiled for REFORM's use.

REFORM classifies every pair of every frame. Calling scikit-learn once per frame spends most of
its time in input validation and, for an ensemble, in one call per tree. This module turns a
fitted classifier into an object whose ``predict(X)`` gives **the same labels** as the
classifier, much faster, for whole batches and for single frames alike:

* **Tree ensembles** (bagged trees, random forests, extra trees, a single tree) on two features
  are compiled into one exact lookup table. Every tree splits on thresholds; over all trees the
  thresholds of each feature cut its axis into intervals, and the ensemble's decision is
  constant on each cell of the grid they make. The table holds that decision per cell, computed
  from the trees' leaves with summed-area (prefix-sum) accumulation; a query is two rank
  look-ups (bucketed on the float32 bit pattern the trees compare) and one table read. Where the
  accumulated vote is within rounding distance of a tie, the cell is decided by the classifier
  itself on a point of that cell, so the table reproduces scikit-learn's floating-point ties.
  Larger grids (or more features) fall back to evaluating each tree with its own ``apply``.
* **Logistic regression** (optionally after ``StandardScaler``) is a dot product, done with the
  same operations scikit-learn uses.
* **k-nearest neighbours** (optionally after ``StandardScaler``) queries the classifier's own
  KD-tree or ball tree directly and applies scikit-learn's weighting and vote.
* Anything else is called once per batch, which is already exact and far cheaper than once per
  frame.

The decision rule: with ``threshold=None`` a pair is together when ``predict`` says class 1;
with a threshold ``t``, when ``predict_proba(X)[:, 1] >= t``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from sklearn.ensemble import BaggingClassifier, ExtraTreesClassifier, RandomForestClassifier
from sklearn.linear_model import LogisticRegression
from sklearn.neighbors import KNeighborsClassifier
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.tree import DecisionTreeClassifier, ExtraTreeClassifier

MAX_GRID_CELLS = 1 << 26  # cells of a compiled tree-ensemble table (one byte each): 64 MiB
_BAND_CELLS = 1 << 21  # cells accumulated at once while compiling a table
_TIE_MARGIN = 1e-7  # vote margins closer to a tie than this are settled by the classifier
_MAX_BUCKETS = 1 << 22  # rank look-up buckets per feature
_BUCKET_TARGET = 3  # aim for at most this many thresholds per bucket

__all__ = [
    "MAX_GRID_CELLS",
    "PairClassifier",
    "compile_classifier",
    "sklearn_pair_labels",
]


class PairClassifier(Protocol):
    """A compiled pairwise classifier."""

    kind: str  # how it evaluates: "tree-table", "tree-apply", "linear", "neighbors", "sklearn"
    exact: bool  # True when its labels equal the classifier's own, by construction

    def predict(self, features: np.ndarray) -> np.ndarray:
        """(m, k) float64 pair features -> (m,) bool: together or not."""
        ...

    def apart_from(self, column: int) -> float | None:
        """A value of feature ``column`` from which every pair is apart, whatever its other
        features: a pair whose feature is at least this is never together. None when no such
        value is known."""
        ...


class _Exact:
    """A compiled form of this module: its labels equal the classifier's own, by construction
    (each names its ``kind``)."""

    kind: str
    exact = True

    def apart_from(self, column: int) -> float | None:  # noqa: ARG002 (the protocol's)
        return None


def sklearn_pair_labels(
    classifier: Any, features: np.ndarray, *, threshold: float | None = None
) -> np.ndarray:
    """The classifier's own decision for pair features (the reference every compiled form matches).

    Args:
        classifier: a fitted scikit-learn classifier with classes ``[0, 1]``.
        features: (m, k) float64 pair features.
        threshold: None to use ``predict``; else a probability in (0, 1) for ``predict_proba``.

    Returns:
        (m,) bool labels.
    """
    features = np.asarray(features, dtype=np.float64)
    if features.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    if threshold is None:
        return np.asarray(classifier.predict(features)) == 1
    column = int(np.flatnonzero(np.asarray(classifier.classes_) == 1)[0])
    return np.asarray(classifier.predict_proba(features))[:, column] >= threshold


@dataclass(frozen=True, eq=False)
class _SklearnPairs(_Exact):
    """Any classifier: one call per batch."""

    classifier: Any
    threshold: float | None
    kind = "sklearn"

    def predict(self, features: np.ndarray) -> np.ndarray:
        return sklearn_pair_labels(self.classifier, features, threshold=self.threshold)


def compile_classifier(
    classifier: Any, *, threshold: float | None = None, max_cells: int = MAX_GRID_CELLS
) -> PairClassifier:
    """Compiles a fitted classifier for fast pair classification, labels unchanged.

    Args:
        classifier: a fitted scikit-learn classifier (or pipeline) with classes ``[0, 1]``.
        threshold: None for ``predict``'s decision, else the ``predict_proba`` threshold.
        max_cells: largest tree-ensemble table to build; larger ensembles use ``apply``.

    Returns:
        A :class:`PairClassifier`.
    """
    scalers, final = _split_scalers(classifier)
    if final is None:
        return _SklearnPairs(classifier, threshold)
    trees = _tree_ensemble(final)
    if trees is not None and not scalers:
        ensemble = _TreeEnsemble.from_estimator(final, trees)
        if ensemble.n_features == 2:
            table = _TreeTable.build(classifier, ensemble, threshold=threshold, max_cells=max_cells)
            if table is not None:
                return table
        return _TreeApply(classifier, ensemble, threshold)
    if _is_logistic(final):
        return _LinearPairs(classifier, scalers, final, threshold)
    if _is_neighbors(final) and threshold is None:
        return _NeighborsPairs(scalers, final)
    return _SklearnPairs(classifier, threshold)


# --------------------------------------------------------------------------------------------
# Recognising the classifier


def _split_scalers(classifier: Any) -> tuple[tuple[Any, ...], Any | None]:
    """(StandardScaler steps, final estimator) of a pipeline, or ((), classifier)."""

    if not isinstance(classifier, Pipeline):
        return (), classifier
    steps = [step for _, step in classifier.steps if step not in (None, "passthrough")]
    *head, final = steps
    if not all(type(step) is StandardScaler for step in head):
        return (), None
    return tuple(head), final


def _scale(scalers: tuple[Any, ...], features: np.ndarray) -> np.ndarray:
    """``StandardScaler.transform`` of each scaler, with its own operations (subtract, divide)."""
    for scaler in scalers:
        features = np.array(features, dtype=np.float64, copy=True)
        if scaler.with_mean:
            features -= scaler.mean_
        if scaler.with_std:
            features /= scaler.scale_
    return features


def _tree_ensemble(estimator: Any) -> list[tuple[Any, np.ndarray]] | None:
    """[(tree_, feature columns)] of a supported tree classifier, else None."""

    def is_tree(model: Any) -> bool:
        return (
            type(model) in (DecisionTreeClassifier, ExtraTreeClassifier) and model.n_outputs_ == 1
        )

    n_features = getattr(estimator, "n_features_in_", None)
    if n_features is None:
        return None
    all_columns = np.arange(n_features)
    if is_tree(estimator):
        return [(estimator.tree_, all_columns)]
    if type(estimator) in (RandomForestClassifier, ExtraTreesClassifier):
        if estimator.n_outputs_ != 1:
            return None
        return [(tree.tree_, all_columns) for tree in estimator.estimators_]
    if type(estimator) is BaggingClassifier:
        if not all(is_tree(tree) for tree in estimator.estimators_):
            return None
        if any(len(tree.classes_) != len(estimator.classes_) for tree in estimator.estimators_):
            return None
        return [
            (tree.tree_, np.asarray(columns))
            for tree, columns in zip(
                estimator.estimators_, estimator.estimators_features_, strict=True
            )
        ]
    return None


def _is_logistic(estimator: Any) -> bool:
    return type(estimator) is LogisticRegression and np.asarray(estimator.coef_).shape[0] == 1


def _is_neighbors(estimator: Any) -> bool:
    return (
        type(estimator) is KNeighborsClassifier
        and len(estimator.classes_) == 2
        and estimator.weights in ("uniform", "distance")
        and getattr(estimator, "_fit_method", None) in ("kd_tree", "ball_tree")
        and not estimator.outputs_2d_
    )


# --------------------------------------------------------------------------------------------
# Logistic regression and nearest neighbours


@dataclass(frozen=True, eq=False)
class _LinearPairs(_Exact):
    """Logistic regression as an elementwise dot product.

    scikit-learn computes ``X @ coef_.T + intercept_`` with BLAS, which for two columns is
    slower than the arithmetic itself and may round differently (fused multiply-adds). The sum is
    computed here elementwise; where its sign (or its side of the threshold) could depend on
    that last-bit rounding, the classifier itself decides.
    """

    classifier: Any
    scalers: tuple[Any, ...]
    model: Any
    threshold: float | None
    kind = "linear"

    def predict(self, features: np.ndarray) -> np.ndarray:
        features = np.asarray(features, dtype=np.float64)
        scaled = _scale(self.scalers, features)
        coef = np.asarray(self.model.coef_, dtype=np.float64)[0]
        intercept = float(np.asarray(self.model.intercept_, dtype=np.float64)[0])
        score = np.full(scaled.shape[0], intercept)
        size = np.full(scaled.shape[0], abs(intercept))
        for column, weight in enumerate(coef.tolist()):
            term = scaled[:, column] * weight
            score += term
            size += np.abs(term)
        positive = int(np.flatnonzero(np.asarray(self.model.classes_) == 1)[0])
        cut = 0.0 if self.threshold is None else _logit(self.threshold)
        if positive != 1:
            score, cut = -score, -cut
        # Rounding of a sum of k + 1 terms stays far below 8 (k + 1) ulp of their magnitudes;
        # with a threshold, expit's own rounding moves the cut by about eps / (p (1 - p)).
        eps = np.finfo(np.float64).eps
        slack = 0.0 if self.threshold is None else 8 * eps / (self.threshold * (1 - self.threshold))
        doubt = np.abs(score - cut) <= 8 * (coef.size + 1) * eps * (size + abs(cut)) + slack
        together = score > cut if self.threshold is None else score >= cut
        if doubt.any():
            rows = np.flatnonzero(doubt)
            together[rows] = sklearn_pair_labels(
                self.classifier, features[rows], threshold=self.threshold
            )
        return together


def _logit(p: float) -> float:
    """The score at which ``expit(score) == p``."""
    return float(np.log(p) - np.log1p(-p))


@dataclass(frozen=True, eq=False)
class _NeighborsPairs(_Exact):
    scalers: tuple[Any, ...]
    model: Any
    kind = "neighbors"

    def predict(self, features: np.ndarray) -> np.ndarray:
        model = self.model
        scaled = _scale(self.scalers, features)
        if scaled.shape[0] == 0:
            return np.zeros(0, dtype=bool)
        distance, index = model._tree.query(scaled, model.n_neighbors, return_distance=True)
        votes = model._y[index]  # class indices
        if model.weights == "distance":
            with np.errstate(divide="ignore"):
                weights = 1.0 / distance
            infinite = np.isinf(weights)
            infinite_row = np.any(infinite, axis=1)
            weights[infinite_row] = infinite[infinite_row]
        else:
            weights = np.ones_like(distance)
        # sklearn.utils.extmath.weighted_mode for two classes, with its own sums: class 1 wins
        # only with strictly more weight than class 0.
        weight_0 = np.sum((votes == 0) * weights, axis=1)
        weight_1 = np.sum((votes == 1) * weights, axis=1)
        winner = (weight_1 > weight_0).astype(np.intp)
        return np.asarray(model.classes_).take(winner) == 1


# --------------------------------------------------------------------------------------------
# Tree ensembles


@dataclass(frozen=True, eq=False)
class _TreeEnsemble:
    """The trees of an ensemble as flat arrays, in the ensemble's order."""

    trees: tuple[Any, ...]  # sklearn Tree objects
    columns: tuple[np.ndarray, ...]  # feature columns each tree sees
    proba: tuple[np.ndarray, ...]  # (n_nodes, 2) class proportions per node, classes [0, 1]
    n_features: int
    positive: int  # column of class 1 in the classifier's classes_

    @classmethod
    def from_estimator(cls, estimator: Any, trees: list[tuple[Any, np.ndarray]]) -> _TreeEnsemble:
        classes = np.asarray(estimator.classes_)
        positive = int(np.flatnonzero(classes == 1)[0])
        return cls(
            trees=tuple(tree for tree, _ in trees),
            columns=tuple(np.asarray(columns, dtype=np.intp) for _, columns in trees),
            proba=tuple(
                np.ascontiguousarray(tree.value[:, 0, :], dtype=np.float64) for tree, _ in trees
            ),
            n_features=int(estimator.n_features_in_),
            positive=positive,
        )

    @property
    def n_trees(self) -> int:
        return len(self.trees)


def _decide(
    positive_sum: np.ndarray, negative_sum: np.ndarray, n_trees: int, threshold: float | None
) -> tuple[np.ndarray, np.ndarray]:
    """Decision from summed class proportions, and where it is too close to a tie to trust."""
    if threshold is None:
        margin = positive_sum - negative_sum
    else:
        margin = positive_sum / n_trees - threshold
    return margin > 0, np.abs(margin) <= _TIE_MARGIN * max(1, n_trees)


@dataclass(frozen=True, eq=False)
class _TreeApply(_Exact):
    """Each tree evaluated with its own compiled ``apply``; ties settled by the classifier."""

    classifier: Any
    ensemble: _TreeEnsemble
    threshold: float | None
    kind = "tree-apply"

    def predict(self, features: np.ndarray) -> np.ndarray:
        features = np.asarray(features, dtype=np.float64)
        m = features.shape[0]
        if m == 0:
            return np.zeros(0, dtype=bool)
        as_float32 = features.astype(np.float32)  # what scikit-learn's trees compare
        sums = np.zeros((m, 2))
        for tree, columns, proba in zip(
            self.ensemble.trees, self.ensemble.columns, self.ensemble.proba, strict=True
        ):
            leaves = tree.apply(np.ascontiguousarray(as_float32[:, columns]))
            sums += proba[leaves]
        positive = self.ensemble.positive
        together, tied = _decide(
            sums[:, positive], sums[:, 1 - positive], self.ensemble.n_trees, self.threshold
        )
        if tied.any():
            rows = np.flatnonzero(tied)
            together[rows] = sklearn_pair_labels(
                self.classifier, features[rows], threshold=self.threshold
            )
        return together


def _float32_key(values: np.ndarray) -> np.ndarray:
    """Order-preserving int32 key of float32 values (negative floats flipped, -0 just below +0)."""
    bits = np.ascontiguousarray(values, dtype=np.float32).view(np.int32)
    return bits ^ ((bits >> 31) & np.int32(0x7FFFFFFF))


def _step_float32(thresholds: np.ndarray) -> np.ndarray:
    """The smallest float32 strictly above each float64 threshold (a tree goes right from there)."""
    rounded = thresholds.astype(np.float32)
    below = rounded.astype(np.float64) <= thresholds
    rounded[below] = np.nextafter(rounded[below], np.float32(np.inf))
    return rounded


def _bucket(key: np.ndarray, low: int, high: int, shift: int) -> np.ndarray:
    """``(clip(key, low, high) - low) >> shift``, in int32 when the span allows."""
    if high - low < 2**31:  # thresholds of one sign: the span fits in int32
        bucket = np.clip(key, np.int32(low), np.int32(high))
        bucket -= np.int32(low)
    else:
        bucket = np.clip(key.astype(np.int64), low, high)
        bucket -= low
    bucket >>= shift
    return bucket


def _step_keys(thresholds: np.ndarray) -> np.ndarray:
    """Sorted int64 keys of the first float32 above each threshold: rank(x) = #keys <= key(x)."""
    return np.sort(
        _float32_key(_step_float32(np.asarray(thresholds, dtype=np.float64))).astype(np.int64)
    )


@dataclass(frozen=True, eq=False)
class _RankIndex:
    """Exact rank of float32 values among sorted thresholds: the number of thresholds below.

    Buckets on the high bits of the float32 key give the rank of a bucket's start; a handful of
    comparisons with the thresholds inside the bucket finish it.
    """

    n_thresholds: int
    low_key: int
    high_key: int
    shift: int
    base: np.ndarray  # (buckets,) int32: thresholds below each bucket's first key
    inside: np.ndarray  # (K, buckets) int32: step keys inside each bucket, padded with int32 max

    @classmethod
    def build(cls, thresholds: np.ndarray) -> _RankIndex:
        steps = _step_keys(thresholds)
        if steps.size == 0:
            empty = np.zeros((0, 1), dtype=np.int32)
            return cls(0, 0, 0, 0, np.zeros(1, dtype=np.int32), empty)
        low, high = int(steps[0]), int(steps[-1])
        span = high - low
        shift = max(0, span.bit_length() - int(np.log2(max(1, steps.size // _BUCKET_TARGET)) + 1))
        while True:
            n_buckets = (span >> shift) + 1
            bucket = (steps - low) >> shift
            counts = np.bincount(bucket, minlength=n_buckets)
            widest = int(counts.max())
            if widest <= _BUCKET_TARGET or shift == 0 or ((span >> (shift - 1)) + 1) > _MAX_BUCKETS:
                break
            shift -= 1
        base = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int32)
        inside = np.full((widest, n_buckets), np.iinfo(np.int32).max, dtype=np.int32)
        slot = np.arange(steps.size) - base[bucket]
        inside[slot, bucket] = steps
        return cls(int(steps.size), low, high, shift, base, inside)

    def rank(self, values: np.ndarray) -> np.ndarray:
        """(m,) float32 values -> (m,) int32 ranks in ``[0, n_thresholds]``."""
        return self.rank_keys(_float32_key(values))

    def rank_keys(self, key: np.ndarray) -> np.ndarray:
        """(m,) int32 keys (:func:`_float32_key`) -> (m,) int32 ranks."""
        if self.n_thresholds == 0:
            return np.zeros(key.shape, dtype=np.int32)
        bucket = _bucket(key, self.low_key, self.high_key, self.shift)
        rank = self.base[bucket]
        for column in self.inside:
            rank += column[bucket] <= key
        return rank


_COARSE_BUCKETS = 1 << 10  # coarse cells per feature in front of a tree table
_MIXED = 2  # coarse code: the coarse cell holds both decisions, look the fine cell up


@dataclass(frozen=True, eq=False)
class _Coarse:
    """Coarse buckets of one feature's float32 keys, with the rank range each one spans."""

    low_key: int
    high_key: int
    shift: int
    count: int
    first_rank: np.ndarray  # (count,) rank of the bucket's first key
    last_rank: np.ndarray  # (count,) rank of its last key

    @classmethod
    def build(cls, thresholds: np.ndarray) -> _Coarse:
        steps = _step_keys(thresholds)
        if steps.size == 0:
            zero = np.zeros(1, dtype=np.intp)
            return cls(0, 0, 0, 1, zero, zero)
        low, high = int(steps[0]), int(steps[-1])
        span = high - low
        shift = max(0, span.bit_length() - (_COARSE_BUCKETS.bit_length() - 1))
        count = (span >> shift) + 1
        starts = low + (np.arange(count, dtype=np.int64) << shift)
        ends = np.minimum(starts + (1 << shift) - 1, high)
        first_rank = np.searchsorted(steps, starts, side="right")
        last_rank = np.searchsorted(steps, ends, side="right")
        first_rank[0] = 0  # keys below the lowest step fall in bucket 0
        last_rank[-1] = steps.size  # keys above the highest fall in the last
        return cls(low, high, shift, count, first_rank, last_rank)

    def bucket(self, key: np.ndarray) -> np.ndarray:
        return _bucket(key, self.low_key, self.high_key, self.shift)


def _range_reduce(
    ufunc: np.ufunc, array: np.ndarray, first: np.ndarray, last: np.ndarray, axis: int
) -> np.ndarray:
    """``ufunc`` over the inclusive index ranges ``[first[c], last[c]]`` along ``axis``."""
    pad_shape = list(array.shape)
    pad_shape[axis] = 1
    padded = np.concatenate([array, np.zeros(pad_shape, dtype=array.dtype)], axis=axis)
    bounds = np.empty(2 * first.size, dtype=np.intp)
    bounds[0::2] = first
    bounds[1::2] = last + 1
    return np.take(
        ufunc.reduceat(padded, bounds, axis=axis), np.arange(0, bounds.size, 2), axis=axis
    )


@dataclass(frozen=True, eq=False)
class _TreeTable(_Exact):
    """A two-feature tree ensemble compiled into one decision table over its threshold grid.

    In front of it sits a coarse table over buckets of the features' float32 keys: where a
    coarse cell covers fine cells of one decision only (most of the plane), that decision is
    read directly; the rest look up their exact fine cell.
    """

    ranks: tuple[_RankIndex, _RankIndex]
    table: np.ndarray  # (cells_0 * cells_1,) uint8 decisions, row-major over (rank_0, rank_1)
    width: int  # cells along feature 1
    coarse: tuple[_Coarse, _Coarse]
    coarse_table: np.ndarray  # (count_0 * count_1,) uint8: 0, 1 or _MIXED
    apart: tuple[float | None, float | None]  # per feature: apart from this value on (-inf:
    # the table never says together), None when its highest cells say together somewhere
    kind = "tree-table"

    def apart_from(self, column: int) -> float | None:
        """The smallest float32 above the threshold past which feature ``column``'s cells all
        say apart (a float32 input at or beyond it falls in those cells; so does a float64
        input, which rounds to a float32 at least as large)."""
        return self.apart[column]

    def predict(self, features: np.ndarray) -> np.ndarray:
        features = np.asarray(features, dtype=np.float64)
        key_0 = _float32_key(features[:, 0].astype(np.float32))
        key_1 = _float32_key(features[:, 1].astype(np.float32))
        cell = self.coarse[0].bucket(key_0).astype(np.intp)
        cell *= self.coarse[1].count
        cell += self.coarse[1].bucket(key_1)
        code = self.coarse_table[cell]
        together = code == 1
        mixed = np.flatnonzero(code == _MIXED)
        if mixed.size:
            row = self.ranks[0].rank_keys(key_0[mixed]).astype(np.intp)
            row *= self.width
            row += self.ranks[1].rank_keys(key_1[mixed])
            together[mixed] = self.table[row].view(bool)
        return together

    @classmethod
    def build(
        cls, classifier: Any, ensemble: _TreeEnsemble, *, threshold: float | None, max_cells: int
    ) -> _TreeTable | None:
        thresholds = [[], []]
        for tree, columns in zip(ensemble.trees, ensemble.columns, strict=True):
            internal = tree.children_left >= 0
            for local, feature in enumerate(columns.tolist()):
                thresholds[feature].append(tree.threshold[internal & (tree.feature == local)])
        axes = [
            np.unique(np.concatenate(values)) if values else np.zeros(0) for values in thresholds
        ]
        shape = (axes[0].size + 1, axes[1].size + 1)
        if shape[0] * shape[1] > max_cells:
            return None
        leaves = _leaf_rectangles(ensemble, axes)
        table = _accumulate(leaves, shape, ensemble.n_trees, threshold)
        _settle_ties(classifier, table, axes, threshold)
        coarse = (_Coarse.build(axes[0]), _Coarse.build(axes[1]))
        lowest = table
        highest = table
        for axis, buckets in ((1, coarse[1]), (0, coarse[0])):
            lowest = _range_reduce(np.minimum, lowest, buckets.first_rank, buckets.last_rank, axis)
            highest = _range_reduce(
                np.maximum, highest, buckets.first_rank, buckets.last_rank, axis
            )
        coarse_table = np.where(lowest == highest, lowest, _MIXED).astype(np.uint8)
        apart = tuple(_apart_from(table.any(axis=1 - axis), axes[axis]) for axis in (0, 1))
        return cls(
            ranks=(_RankIndex.build(axes[0]), _RankIndex.build(axes[1])),
            table=table.ravel().astype(np.uint8),
            width=shape[1],
            coarse=coarse,
            coarse_table=coarse_table.ravel(),
            apart=apart,
        )


def _apart_from(together: np.ndarray, axis: np.ndarray) -> float | None:
    """From which value of a feature every cell says apart: ``together`` (cells,) holds
    whether any cell of each rank of the feature says together, ``axis`` (cells - 1,) the
    sorted thresholds between ranks (rank r+1 starts above threshold r)."""
    ranks = np.flatnonzero(together)
    if ranks.size == 0:
        return -math.inf
    last = int(ranks[-1])
    if last == axis.size:
        return None
    return float(_step_float32(axis[last : last + 1])[0])


@dataclass(frozen=True)
class _Leaves:
    """Leaf rectangles of all trees in rank coordinates: cells [lo, hi) along each feature."""

    lo: np.ndarray  # (L, 2) intp
    hi: np.ndarray  # (L, 2) intp
    positive: np.ndarray  # (L,) float64 class-1 proportion
    negative: np.ndarray  # (L,) float64 class-0 proportion


def _leaf_rectangles(ensemble: _TreeEnsemble, axes: list[np.ndarray]) -> _Leaves:
    lows, highs, positives, negatives = [], [], [], []
    cells = np.array([axes[0].size + 1, axes[1].size + 1])
    for tree, columns, proba in zip(ensemble.trees, ensemble.columns, ensemble.proba, strict=True):
        n_nodes = tree.node_count
        left, right = tree.children_left, tree.children_right
        feature = np.where(left >= 0, columns[np.maximum(tree.feature, 0)], -1)
        cut = np.zeros(n_nodes, dtype=np.intp)  # rank of each internal node's threshold
        for axis in (0, 1):
            on_axis = feature == axis
            cut[on_axis] = np.searchsorted(axes[axis], tree.threshold[on_axis])
        lo = np.zeros((n_nodes, 2), dtype=np.intp)
        hi = np.broadcast_to(cells, (n_nodes, 2)).copy()
        frontier = np.array([0])
        while frontier.size:
            internal = frontier[left[frontier] >= 0]
            if internal.size == 0:
                break
            axis = feature[internal]
            for child, is_left in ((left[internal], True), (right[internal], False)):
                lo[child] = lo[internal]
                hi[child] = hi[internal]
                # x <= threshold (left) <=> rank(x) <= cut; right: rank(x) >= cut + 1
                if is_left:
                    hi[child, axis] = np.minimum(hi[internal, axis], cut[internal] + 1)
                else:
                    lo[child, axis] = np.maximum(lo[internal, axis], cut[internal] + 1)
            frontier = np.concatenate([left[internal], right[internal]])
        leaf = np.flatnonzero(left < 0)
        keep = leaf[np.all(hi[leaf] > lo[leaf], axis=1)]
        lows.append(lo[keep])
        highs.append(hi[keep])
        positives.append(proba[keep, ensemble.positive])
        negatives.append(proba[keep, 1 - ensemble.positive])
    return _Leaves(
        lo=np.concatenate(lows),
        hi=np.concatenate(highs),
        positive=np.concatenate(positives),
        negative=np.concatenate(negatives),
    )


_TIED = 2  # table code of a cell whose vote is within rounding distance of a tie


def _accumulate(
    leaves: _Leaves, shape: tuple[int, int], n_trees: int, threshold: float | None
) -> np.ndarray:
    """The decision of every cell (1 together, 0 not, ``_TIED`` to settle), band by band.

    Counts of pure leaves (all class 1 or all class 0) add up exactly as integers; only cells
    where some tree sits in a mixed leaf carry a floating-point sum that can round.
    """
    rows, width = shape
    pure_positive = (leaves.positive == 1.0) & (leaves.negative == 0.0)
    pure_negative = (leaves.negative == 1.0) & (leaves.positive == 0.0)
    mixed = ~(pure_positive | pure_negative)
    if threshold is None:
        mixed_value = leaves.positive - leaves.negative
    else:
        mixed_value = leaves.positive.copy()
    count_value = pure_positive.astype(np.int32)
    mixed_count = mixed.astype(np.int32)
    mixed_value = np.where(mixed, mixed_value, 0.0)

    # Each leaf opens at row lo[0] and closes at row hi[0]; along a row it spans [lo[1], hi[1]).
    event_row = np.concatenate([leaves.lo[:, 0], leaves.hi[:, 0]])
    sign = np.concatenate(
        [np.ones(len(leaves.lo), dtype=np.int32), -np.ones(len(leaves.lo), dtype=np.int32)]
    )
    event_lo = np.concatenate([leaves.lo[:, 1], leaves.lo[:, 1]])
    event_hi = np.concatenate([leaves.hi[:, 1], leaves.hi[:, 1]])
    event_count = np.concatenate([count_value, count_value]) * sign
    event_mixed = np.concatenate([mixed_count, mixed_count]) * sign
    event_value = np.concatenate([mixed_value, mixed_value]) * sign
    order = np.argsort(event_row, kind="stable")
    event_row, event_lo, event_hi = event_row[order], event_lo[order], event_hi[order]
    event_count, event_mixed, event_value = (
        event_count[order],
        event_mixed[order],
        event_value[order],
    )

    decision = np.empty(shape, dtype=np.uint8)
    carry_count = np.zeros(width + 1, dtype=np.int32)
    carry_mixed = np.zeros(width + 1, dtype=np.int32)
    carry_value = np.zeros(width + 1, dtype=np.float64)
    band = max(1, min(rows, _BAND_CELLS // (width + 1)))
    for start in range(0, rows, band):
        stop = min(rows, start + band)
        first, last = np.searchsorted(event_row, [start, stop])
        r = event_row[first:last] - start
        lo, hi = event_lo[first:last], event_hi[first:last]
        sums = []
        for carry, values, dtype in (
            (carry_count, event_count[first:last], np.int32),
            (carry_mixed, event_mixed[first:last], np.int32),
            (carry_value, event_value[first:last], np.float64),
        ):
            delta = np.zeros((stop - start, width + 1), dtype=dtype)
            np.add.at(delta, (r, lo), values)
            np.add.at(delta, (r, hi), -values)
            np.cumsum(delta, axis=1, out=delta)
            np.cumsum(delta, axis=0, out=delta)
            delta += carry
            carry[:] = delta[-1]
            sums.append(delta[:, :width])
        positive_count, mixed_trees, mixed_sum = sums
        pure_trees = n_trees - mixed_trees
        if threshold is None:
            exact_margin = 2 * positive_count - pure_trees  # (#class-1) - (#class-0) of pure leaves
            margin = exact_margin + mixed_sum
            together = margin > 0
        else:
            margin = (positive_count + mixed_sum) / n_trees - threshold
            together = margin >= 0
        tied = (mixed_trees > 0) & (np.abs(margin) <= _TIE_MARGIN * n_trees)
        if threshold is not None:
            # With pure leaves only, the probability is an exact ratio: compare it as sklearn does.
            all_pure = mixed_trees == 0
            together = np.where(all_pure, positive_count / n_trees >= threshold, together)
        block = together.astype(np.uint8)
        block[tied] = _TIED
        decision[start:stop] = block
    return decision


def _cell_points(axis: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A float32 value inside each cell ``(axis[c-1], axis[c]]``, and whether the cell holds one."""
    if axis.size == 0:
        return np.zeros(cells.shape, dtype=np.float32), np.ones(cells.shape, dtype=bool)
    lower = np.where(cells > 0, axis[np.maximum(cells - 1, 0)], -np.inf)
    point = _step_float32(lower) if lower.size else lower.astype(np.float32)
    point = np.where(np.isneginf(lower), np.float32(np.finfo(np.float32).min), point).astype(
        np.float32
    )
    upper_ok = (cells >= axis.size) | (
        point.astype(np.float64) <= axis[np.minimum(cells, axis.size - 1)]
    )
    return point, upper_ok


def _settle_ties(
    classifier: Any, table: np.ndarray, axes: list[np.ndarray], threshold: float | None
) -> None:
    """Cells whose vote rounds near a tie: ask the classifier at a point of the cell."""
    rows, columns = np.nonzero(table == _TIED)
    if rows.size == 0:
        return
    x0, ok0 = _cell_points(axes[0], rows)
    x1, ok1 = _cell_points(axes[1], columns)
    reachable = ok0 & ok1
    table[rows[~reachable], columns[~reachable]] = 0  # no float32 input falls in these cells
    rows, columns = rows[reachable], columns[reachable]
    if rows.size:
        points = np.stack([x0[reachable], x1[reachable]], axis=1).astype(np.float64)
        table[rows, columns] = sklearn_pair_labels(classifier, points, threshold=threshold)
