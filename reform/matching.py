"""Which detected group is which true group: a one-to-one matching for pictures.

The evaluation protocol (`reform.metrics`) asks whether a detected F-formation matches a true
one at a threshold T. A picture asks a softer question: which true group does each detected
group stand for, so that it can wear that group's colour? `match_groups` answers it with the
assignment that maximises the total Jaccard index ``|A ∩ B| / |A ∪ B|`` of the matched pairs
(Hungarian algorithm, `scipy.optimize.linear_sum_assignment`); only pairs that share at least
one member are matched, so a detected group overlapping no true group stays unmatched.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

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
    # Square, with a free "unmatched" slot for every group on both sides (score 0); pairs that
    # share no member score below it, and a tiny penalty per pair index breaks ties.
    gain = np.zeros((n + m, m + n))
    order = np.arange(n)[:, None] * m + np.arange(m)[None, :]
    penalty = _TIE_BREAK * (1 + order) / (n * m + 1) ** 2
    gain[:n, :m] = np.where(score > 0.0, score - penalty, -1.0)
    rows, cols = linear_sum_assignment(gain, maximize=True)
    for i, j in zip(rows.tolist(), cols.tolist(), strict=True):
        if i < n and j < m and score[i, j] > 0.0:
            out[i] = j
    return out
