"""Which detected group is which true group: a one-to-one matching for pictures.

The evaluation protocol (`reform.metrics`) asks whether a detected F-formation matches a true
one at a threshold T. A picture asks a softer question: which true group does each detected
group stand for, so that it can wear that group's colour? `match_groups` answers it with the
assignment that maximises the total Jaccard index ``|A ∩ B| / |A ∪ B|`` of the matched pairs;
only pairs that share at least one member are matched, so a detected group overlapping no true
group stays unmatched.

The groups of a frame overlap a few others at most, so the assignment is solved for each set of
groups joined by overlaps on its own (a lone overlapping pair is simply matched), by the
Hungarian algorithm on a handful of groups: in plain Python, as importing
`scipy.optimize.linear_sum_assignment` (with all of scipy.optimize) would cost a recording or a
figure more CPU time than every matching it makes.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np

__all__ = ["jaccard_matrix", "match_groups"]

# The tie-breaking penalties of all pairs of a matching add up to less than this, far below any
# difference between two sums of Jaccard indices of groups of real sizes.
_TIE_BREAK = 1e-9


def _sets(groups: Iterable[Iterable[int]]) -> list[frozenset[int]]:
    return [frozenset(int(m) for m in group) for group in groups]


def jaccard_matrix(
    reference: Sequence[Iterable[int]], others: Sequence[Iterable[int]]
) -> np.ndarray:
    """(len(others), len(reference)) Jaccard index of every pair of groups (0 for empty ones).

    Args:
        reference: groups of person ids, e.g. the ground truth's F-formations.
        others: groups of person ids, e.g. a detector's F-formations.
    """
    ref, oth = _sets(reference), _sets(others)
    out = np.zeros((len(oth), len(ref)))
    for i, a in enumerate(oth):
        for j, b in enumerate(ref):
            union = len(a | b)
            if union:
                out[i, j] = len(a & b) / union
    return out


def match_groups(
    reference: Sequence[Iterable[int]], others: Sequence[Iterable[int]]
) -> list[int | None]:
    """For each group of ``others``, the index of the ``reference`` group it is matched to, or
    None.

    The matching is one-to-one and maximises the summed Jaccard index of the matched pairs;
    pairs sharing no member are never matched. Among matchings of equal sum, the one with the
    smallest sum of ``i * len(reference) + j`` over its pairs ``(i, j)`` wins (earlier groups
    first), so the result is fully determined by the inputs.

    Args:
        reference: groups of person ids (e.g. the true F-formations of a frame).
        others: groups of person ids (e.g. a detector's F-formations of that frame).

    Returns:
        ``len(others)`` entries: an index into ``reference``, or None when unmatched.
    """
    score = jaccard_matrix(reference, others)
    n, m = score.shape
    out: list[int | None] = [None] * n
    if not score.any():
        return out
    # Pairs that share no member are never matched; a tiny penalty per pair index breaks ties.
    order = np.arange(n)[:, None] * m + np.arange(m)[None, :]
    gain = score - _TIE_BREAK * (1 + order) / (n * m + 1) ** 2
    for rows, cols in _overlapping(score > 0.0):
        if len(rows) == 1 and len(cols) == 1:
            out[rows[0]] = cols[0]
            continue
        block = gain[np.ix_(rows, cols)]
        for r, c in _best_assignment(np.where(score[np.ix_(rows, cols)] > 0.0, block, -1.0)):
            out[rows[r]] = cols[c]
    return out


def _overlapping(overlap: np.ndarray) -> list[tuple[list[int], list[int]]]:
    """The sets of rows and columns of ``overlap`` (bool, (n, m)) joined by its True entries,
    each as (rows, columns) in increasing order; rows and columns joined to nothing left out."""
    n, m = overlap.shape
    parent = list(range(n + m))

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    for i, j in zip(*np.nonzero(overlap), strict=True):
        a, b = root(int(i)), root(n + int(j))
        if a != b:
            parent[max(a, b)] = min(a, b)
    found: dict[int, tuple[list[int], list[int]]] = {}
    for i in np.flatnonzero(overlap.any(axis=1)).tolist():
        found.setdefault(root(i), ([], []))[0].append(i)
    for j in np.flatnonzero(overlap.any(axis=0)).tolist():
        found[root(n + j)][1].append(j)
    return list(found.values())


def _best_assignment(gain: np.ndarray) -> list[tuple[int, int]]:
    """The pairs (row, column) of the one-to-one matching of largest summed ``gain``,
    pairs of gain <= 0 left unmatched: the Hungarian algorithm (shortest augmenting paths) on
    the square matrix with an "unmatched" slot of gain 0 for every row and column."""
    n_rows, n_cols = gain.shape
    size = n_rows + n_cols
    cost = np.zeros((size, size))
    cost[:n_rows, :n_cols] = -gain
    rows = cost.tolist()
    u, v = [0.0] * (size + 1), [0.0] * (size + 1)
    owner, way = [0] * (size + 1), [0] * (size + 1)  # owner[j]: the row (from 1) of column j
    for i in range(1, size + 1):
        owner[0], j0 = i, 0
        least, used = [math.inf] * (size + 1), [False] * (size + 1)
        while True:
            used[j0] = True
            i0, delta, j1 = owner[j0], math.inf, 0
            row, ui = rows[i0 - 1], u[i0]
            for j in range(1, size + 1):
                if not used[j]:
                    reduced = row[j - 1] - ui - v[j]
                    if reduced < least[j]:
                        least[j], way[j] = reduced, j0
                    if least[j] < delta:
                        delta, j1 = least[j], j
            for j in range(size + 1):
                if used[j]:
                    u[owner[j]] += delta
                    v[j] -= delta
                else:
                    least[j] -= delta
            j0 = j1
            if owner[j0] == 0:
                break
        while j0:
            j1 = way[j0]
            owner[j0] = owner[j1]
            j0 = j1
    return sorted(
        (owner[j] - 1, j - 1)
        for j in range(1, n_cols + 1)
        if owner[j] - 1 < n_rows and gain[owner[j] - 1, j - 1] > 0.0
    )
