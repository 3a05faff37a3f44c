"""Matching detected groups to true groups for pictures: hand-worked cases and optimality."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from reform import jaccard_matrix, match_groups


def test_hand_worked_matchings() -> None:
    truth = [(1, 2, 3, 4), (5, 6)]
    # {1,2} and {3,4} both have Jaccard 1/2 with {1,2,3,4}: the earlier one takes it; {7,8}
    # overlaps nothing; {5,6,9} has Jaccard 2/3 with {5,6}.
    assert match_groups(truth, [(1, 2), (3, 4), (7, 8), (5, 6, 9)]) == [0, None, None, 1]
    # One detected group over two true ones: the larger overlap (3/5 against 2/5).
    assert match_groups([(1, 2, 3), (4, 5)], [(1, 2, 3, 4, 5)]) == [0]
    # One to one: the best total, not each group's best. {1,2,3} prefers A (3/4 vs 3/5) but
    # giving A to {1,2,3,4} (1) and B to {1,2,3} (3/5) sums to 1.6 > 3/4 + 1/2.
    a, b = (1, 2, 3, 4), (1, 2, 3, 9, 10)
    assert match_groups([a, b], [(1, 2, 3), (1, 2, 3, 4)]) == [1, 0]
    assert match_groups([], [(1, 2)]) == [None]
    assert match_groups([(1, 2)], []) == []
    np.testing.assert_allclose(jaccard_matrix([(1, 2), (3, 4)], [(2, 3)]), [[1 / 3, 1 / 3]])


def _best_total(truth, detected) -> float:
    """The largest summed Jaccard index of any one-to-one matching, by trying them all."""
    score = jaccard_matrix(truth, detected)
    best = 0.0
    slots = list(range(len(truth))) + [None] * len(detected)
    for pick in set(itertools.permutations(slots, len(detected))):
        best = max(best, sum(score[i, j] for i, j in enumerate(pick) if j is not None))
    return best


groups = st.lists(st.frozensets(st.integers(0, 9), min_size=1, max_size=5), min_size=0, max_size=4)


@settings(max_examples=150, deadline=None)
@given(truth=groups, detected=groups)
def test_matching_is_one_to_one_overlapping_and_optimal(truth, detected) -> None:
    truth, detected = [sorted(g) for g in truth], [sorted(g) for g in detected]
    matched = match_groups(truth, detected)
    assert len(matched) == len(detected)
    taken = [j for j in matched if j is not None]
    assert len(taken) == len(set(taken))
    score = jaccard_matrix(truth, detected)
    for i, j in enumerate(matched):
        if j is not None:
            assert score[i, j] > 0.0
    total = sum(score[i, j] for i, j in enumerate(matched) if j is not None)
    assert total == pytest.approx(_best_total(truth, detected), abs=1e-9)


def _penalised_total(truth, detected, matched) -> float:
    """The summed Jaccard index of a matching less its tie-breaking penalties."""
    n, m = len(detected), len(truth)
    score = jaccard_matrix(truth, detected)
    return sum(
        score[i, j] - 1e-9 * (1 + i * m + j) / (n * m + 1) ** 2
        for i, j in enumerate(matched)
        if j is not None
    )


def test_as_good_a_matching_as_scipys_assignment() -> None:
    """Random frames of up to 30 people: the matching scores what scipy's assignment on the
    square matrix with an "unmatched" slot for every group scores, tie-breaking penalties
    included (it once made the matching; an exact tie between two matchings may be resolved
    either way)."""
    from scipy.optimize import linear_sum_assignment

    rng = np.random.default_rng(0)
    for _ in range(300):
        people = int(rng.integers(1, 30))
        parts = []
        for _side in range(2):
            labels = rng.integers(0, int(rng.integers(1, people + 1)), size=people)
            parts.append([np.flatnonzero(labels == g).tolist() for g in np.unique(labels)])
        truth, detected = parts
        score = jaccard_matrix(truth, detected)
        n, m = score.shape
        gain = np.zeros((n + m, m + n))
        order = np.arange(n)[:, None] * m + np.arange(m)[None, :]
        gain[:n, :m] = np.where(score > 0.0, score - 1e-9 * (1 + order) / (n * m + 1) ** 2, -1)
        theirs: list[int | None] = [None] * n
        for i, j in zip(*linear_sum_assignment(gain, maximize=True), strict=True):
            if i < n and j < m and score[i, j] > 0.0:
                theirs[i] = int(j)
        ours = match_groups(truth, detected)
        taken = [j for j in ours if j is not None]
        assert len(taken) == len(set(taken))
        assert _penalised_total(truth, detected, ours) == pytest.approx(
            _penalised_total(truth, detected, theirs), abs=1e-13
        )
