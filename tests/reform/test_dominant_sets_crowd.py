"""Dominant sets and GTCG on crowds: why they peel the whole frame at once (the ``Crowds``
paragraphs of ``reform.dominant_sets`` and ``reform.gtcg``). Far-away people change the groups
through the peeling's global stopping rule, and GTCG's frustums that share no bin keep an
affinity; these tests pin both, so that a crowd path cutting the frame into parts would have to
say what it changes."""

from __future__ import annotations

import numpy as np
import pytest

from reform.dominant_sets import dominant_set_labels
from reform.gtcg import SIGMA, frustum_affinity, frustum_samples

# A clique {0, 1, 2} of affinity 1, a weak pair {3, 4} (0.2), and 3 drawn to 0 (0.5): peeled
# alone it gives the clique, then {3, 4}, which 0 (already taken) breaks, so the peeling stops
# (hand-computed in test_dominant_sets.py).
CLIQUE_AND_PAIR = np.array(
    [
        [0.0, 1.0, 1.0, 0.5, 0.0],
        [1.0, 0.0, 1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0, 0.0, 0.0],
        [0.5, 0.0, 0.0, 0.0, 0.2],
        [0.0, 0.0, 0.0, 0.2, 0.0],
    ]
)


def with_far_pair(affinity: float) -> np.ndarray:
    """CLIQUE_AND_PAIR and a pair {5, 6} that shares no affinity with anyone of it."""
    matrix = np.zeros((7, 7))
    matrix[:5, :5] = CLIQUE_AND_PAIR
    matrix[5, 6] = matrix[6, 5] = affinity
    return matrix


def test_a_set_that_is_not_dominant_leaves_far_away_people_alone():
    # Hand-computed: the far pair is a group on its own; peeled with the rest it is one only if
    # the replicator dynamics reach it before {3, 4} stops the peeling. At 0.15 its payoff
    # (2 * 0.25 * 0.15 = 0.075) loses the race to {3, 4}'s 0.1: it is left alone; at 0.3
    # (0.15) it wins and stays a group.
    assert dominant_set_labels(with_far_pair(0.15)[5:, 5:]).tolist() == [0, 0]
    assert dominant_set_labels(with_far_pair(0.15)).tolist() == [0, 0, 0, 1, 2, 3, 4]
    assert dominant_set_labels(with_far_pair(0.3)).tolist() == [0, 0, 0, 2, 3, 1, 1]
    # Without the global context every part is peeled to its end, far pair included.
    labels = dominant_set_labels(with_far_pair(0.15), global_context=False)
    assert labels.tolist() == [0, 0, 0, 1, 1, 2, 2]


@pytest.mark.parametrize("zero_disjoint", [False, True])
def test_far_apart_frustums_keep_the_disjoint_affinity(zero_disjoint):
    # Two facing pairs 100 m apart: frustums 1.7 m long share no bin across the pairs, whose
    # divergence is then 1 and affinity exp(-1 / sigma) (0 with zero_disjoint).
    local = frustum_samples(np.random.default_rng(0), samples=200, length=1.7, aperture=2.8)
    position = np.array([[0.0, 0.0], [1.0, 0.0], [100.0, 0.0], [101.0, 0.0]])
    yaw = np.array([0.0, np.pi, 0.0, np.pi])
    affinity = frustum_affinity(
        position, yaw, local=local, sigma=SIGMA, bin_size=0.2, zero_disjoint=zero_disjoint
    )
    far = 0.0 if zero_disjoint else np.exp(-1.0 / SIGMA)
    assert np.all(affinity[:2, 2:] == far)
    assert np.all(affinity[:2, 2:] == affinity[2:, :2].T)
    assert affinity[0, 1] > far + 0.1  # the pairs themselves attend to one place
