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
