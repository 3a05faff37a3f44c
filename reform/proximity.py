"""The proximity baseline: people standing within a distance of each other are one group.

Groups are the connected components of the graph joining every two people at most ``distance``
metres apart (single-linkage clustering cut at ``distance``). Orientation is ignored: two
people back to back are as together as two people face to face. Every F-formation detector that
reads orientation must beat it; where one does not, orientation is not helping.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from reform._params import check_number
from reform.estimator import Estimator
from reform.frame import Frame, Group, check_frames
from reform.gcff import labels_to_partition

__all__ = ["DISTANCE_M", "Proximity", "proximity_labels"]

# Chosen on SALSA's training split alone, by benchmarks/choose_field_defaults.py.
DISTANCE_M = 0.8  # metres: the default link distance
MAX_DISTANCE_M = 100.0  # metres: the largest distance accepted
_DENSE_PEOPLE = 64  # a frame of at most this many people is linked pair by pair


def proximity_labels(position: np.ndarray, *, distance: float) -> np.ndarray:
    """(n,) int64 labels of the connected components of "at most ``distance`` apart".

    Labels are numbered in order of each component's first row, so that they do not depend on
    anything but the rows' order (the groups themselves do not depend on it at all).

    Args:
        position: (n, 2) positions, metres.
        distance: the link distance, metres.
    """
    position = np.asarray(position, dtype=np.float64)
    n = position.shape[0]
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    if n <= _DENSE_PEOPLE:
        return _dense_labels(position, distance)
    return _tree_labels(position, distance)


def _tree_labels(position: np.ndarray, distance: float) -> np.ndarray:
    """`proximity_labels` for a crowd: the pairs within reach from a k-d tree, the components
    of their sparse graph."""
    n = len(position)
    pairs = cKDTree(position).query_pairs(distance, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    _, first = np.unique(labels, return_index=True)
    order = np.argsort(np.argsort(first))  # component -> rank of its first row
    return order[labels].astype(np.int64)


def _dense_labels(position: np.ndarray, distance: float) -> np.ndarray:
    """`proximity_labels` for a few people: every pair's squared distance against the link's
    square, and each person labelled by the first row of their component (the smallest row
    index among those it reaches, spread along the links until nothing changes), then those
    numbered in order. The tree and the sparse graph cost a frame of a party some 0.3 ms in
    set-up alone; a twin's fit labels thousands of such frames."""
    dx = position[:, None, 0] - position[None, :, 0]
    dy = position[:, None, 1] - position[None, :, 1]
    linked = dx * dx + dy * dy <= distance * distance
    n = len(position)
    first = np.arange(n)
    while True:
        reached = np.where(linked, first[None, :], n).min(axis=1)
        spread = np.minimum(first, reached)
        if np.array_equal(spread, first):
            break
        first = spread
    _, labels = np.unique(first, return_inverse=True)  # first rows ascending: in row order
    return labels.astype(np.int64)


class Proximity(Estimator):
    """Proximity baseline: groups are people linked by distances of at most ``distance``.

    Follows the detector protocol: ``fit(frames) -> self`` (nothing to learn) and
    ``predict(frames)`` -> one full partition per frame, singletons included.

    Args:
        distance: the link distance, metres (greater than 0).

    Example:
        >>> Proximity(distance=1.5).predict(frames)[0]     # doctest: +SKIP
        ((1, 2, 3), (4,), (5, 6))
    """

    def __init__(self, *, distance: float = DISTANCE_M) -> None:
        self.distance = distance

    def _validate(self) -> float:
        return check_number("distance", self.distance, low=0.0, high=MAX_DISTANCE_M, open_low=True)

    def fit(self, frames: Sequence[Frame]) -> Proximity:
        """Checks the parameters and ``frames``; returns ``self`` (nothing to learn)."""
        self._validate()
        check_frames(frames)
        return self

    def predict(self, frames: Sequence[Frame]) -> list[tuple[Group, ...]]:
        """One partition per frame: groups in order of their first member's row."""
        distance = self._validate()
        return [
            labels_to_partition(frame.ids, proximity_labels(frame.position, distance=distance))
            for frame in check_frames(frames)
        ]

    def __sklearn_is_fitted__(self) -> bool:
        return True
