"""Greedy Reconstruction: the paper's worked example, hand-made cases, properties, batch form."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from reform import (
    batch_greedy_labels,
    greedy_reconstruction,
    pair_indices,
    partition_from_labels,
    relation_matrix,
)
from reform.reconstruction import (
    PROBABILITY_CLIP,
    batch_correlation_labels,
    correlation_clustering,
    pair_weights,
)


def beliefs(rows: dict[int, list[int]], n: int) -> np.ndarray:
    matrix = np.zeros((n, n), dtype=bool)
    for row, members in rows.items():
        matrix[row, members] = True
    return matrix


def test_paper_worked_example():
    # Paper, Reconstruction section: B1 = {P1, P2, P3}, B2 = {P1, P3, P4}, B3 = {P1, P2, P3}
    # (rows 0..3 here); P4 believes only in itself. (1, 3) agrees on three people, more than
    # any pair with P2, so {P1, P2, P3} is emitted and P4 stays alone.
    matrix = beliefs({0: [0, 1, 2], 1: [0, 2, 3], 2: [0, 1, 2], 3: [3]}, 4)
    assert greedy_reconstruction(matrix) == ((0, 1, 2), (3,))


def test_paper_example_read_as_a_symmetric_relation_matrix():
    # A classifier's Relation Matrix is symmetric with a True diagonal: the same beliefs give
    # B2 = {1, 2, 3, 4} and B4 = {2, 4}. Then (1, 2), (1, 3) and (2, 3) all agree on three
    # people; the tie goes to the lowest pair, (1, 2), whose union takes P4 in (hand-computed).
    labels = {(0, 1): 1, (0, 2): 1, (1, 2): 1, (1, 3): 1}
    i, j = pair_indices(4)
    pairs = [labels.get((a, b), 0) for a, b in zip(i.tolist(), j.tolist(), strict=True)]
    matrix = relation_matrix(pairs, 4)
    assert matrix.tolist() == [
        [True, True, True, False],
        [True, True, True, True],
        [True, True, True, False],
        [False, True, False, True],
    ]
    assert greedy_reconstruction(matrix) == ((0, 1, 2, 3),)
    assert greedy_reconstruction(matrix, variant="intersection") == ((0, 1, 2), (3,))


def test_chain_union_versus_intersection():
    # 0-1 and 1-2 predicted together, 0-2 not: B0 = {0,1}, B1 = {0,1,2}, B2 = {1,2}.
    # (0,1) and (1,2) both agree on two; the tie goes to (0,1).
    matrix = relation_matrix([1, 0, 1], 3)
    assert greedy_reconstruction(matrix) == ((0, 1, 2),)  # B0 ∪ B1
    assert greedy_reconstruction(matrix, variant="intersection") == ((0, 1), (2,))


def test_cliques_come_out_as_they_are():
    truth = [0, 0, 1, 2, 1, 1, 3, 0]
    i, j = pair_indices(8)
    labels = np.array(truth)[i] == np.array(truth)[j]
    expected = ((0, 1, 7), (2, 4, 5), (3,), (6,))
    assert greedy_reconstruction(relation_matrix(labels, 8)) == expected
    assert partition_from_labels(batch_greedy_labels(labels[None], 8)[0], range(8)) == expected


def test_nobody_and_everybody_together():
    assert greedy_reconstruction(np.eye(4, dtype=bool)) == ((0,), (1,), (2,), (3,))
    assert greedy_reconstruction(np.ones((4, 4), dtype=bool)) == ((0, 1, 2, 3),)
    assert greedy_reconstruction(np.zeros((0, 0), dtype=bool)) == ()


def test_bad_input_is_named():
    with pytest.raises(ValueError, match=r"square \(n, n\) matrix, got shape \(2, 3\)"):
        greedy_reconstruction(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="reconstruction must be one of .* got 'mean'"):
        greedy_reconstruction(np.eye(2), variant="mean")
    with pytest.raises(ValueError, match=r"pair_labels must have shape \(frames, 3\) for n=3"):
        batch_greedy_labels(np.zeros((2, 4)), 3)
    with pytest.raises(ValueError, match=r"pair_labels must have shape \(6,\) for n=4"):
        relation_matrix(np.zeros(5), 4)


def partition_sets(partition) -> set[frozenset[int]]:
    return {frozenset(group) for group in partition}


@st.composite
def relation_matrices(draw, max_n: int = 14):
    n = draw(st.integers(0, max_n))
    i, j = pair_indices(n)
    density = draw(st.sampled_from([0.05, 0.2, 0.5, 0.9]))
    seed = draw(st.integers(0, 2**32 - 1))
    labels = np.random.default_rng(seed).random(i.size) < density
    return n, labels


@settings(max_examples=200, deadline=None)
@given(case=relation_matrices(), variant=st.sampled_from(["union", "intersection"]))
def test_reconstruction_is_always_a_partition(case, variant):
    n, labels = case
    matrix = relation_matrix(labels, n)
    partition = greedy_reconstruction(matrix, variant=variant)
    members = [person for group in partition for person in group]
    assert sorted(members) == list(range(n))
    for group in partition:
        assert list(group) == sorted(group)
        if len(group) >= 2:
            # a group never spans two connected components of the predicted graph
            inside = matrix[np.ix_(group, group)]
            reach = inside.copy()
            for _ in range(len(group)):
                reach = (reach.astype(int) @ inside.astype(int)) > 0
            assert reach.all()


@settings(max_examples=150, deadline=None)
@given(
    n_frames=st.integers(1, 8),
    n=st.integers(2, 12),
    seed=st.integers(0, 2**32 - 1),
    variant=st.sampled_from(["union", "intersection"]),
)
def test_batch_equals_reference(n_frames, n, seed, variant):
    i, _ = pair_indices(n)
    rng = np.random.default_rng(seed)
    stack = np.stack([rng.random(i.size) < rng.choice([0.1, 0.3, 0.6]) for _ in range(n_frames)])
    labels = batch_greedy_labels(stack, n, variant=variant)  # array path from 4 frames on
    for row, frame_labels in zip(stack, labels, strict=True):
        expected = greedy_reconstruction(relation_matrix(row, n), variant=variant)
        assert partition_from_labels(frame_labels, range(n)) == expected
        single = batch_greedy_labels(row[None], n, variant=variant)[0]  # small-batch path
        assert partition_from_labels(single, range(n)) == expected


@pytest.mark.parametrize("n", [53, 70])
def test_batch_equals_reference_beyond_one_word(n):
    rng = np.random.default_rng(n)
    i, _ = pair_indices(n)
    stack = rng.random((6, i.size)) < 0.04
    labels = batch_greedy_labels(stack, n)
    for row, frame_labels in zip(stack, labels, strict=True):
        expected = greedy_reconstruction(relation_matrix(row, n))
        assert partition_from_labels(frame_labels, range(n)) == expected


@settings(max_examples=100, deadline=None)
@given(
    sizes=st.lists(st.integers(1, 5), min_size=1, max_size=6),
    seed=st.integers(0, 2**32 - 1),
)
def test_cliques_survive_any_relabelling(sizes, seed):
    truth = np.repeat(np.arange(len(sizes)), sizes)
    order = np.random.default_rng(seed).permutation(truth.size)
    shuffled = truth[order]
    n = truth.size
    i, j = pair_indices(n)
    partition = greedy_reconstruction(relation_matrix(shuffled[i] == shuffled[j], n))
    expected = {frozenset(np.flatnonzero(shuffled == g).tolist()) for g in range(len(sizes))}
    assert partition_sets(partition) == expected


# ------------------------------------------------------------------------------------------------
# Correlation clustering over pair probabilities


def objective(weights: np.ndarray, labels: np.ndarray) -> float:
    together = labels[:, None] == labels[None, :]
    return float(np.triu(weights * together, k=1).sum())


def test_pair_weights_are_log_odds_from_the_threshold():
    # Hand-computed: logit(0.5) = 0, logit(0.9) = ln 9, logit(0.1) = -ln 9.
    w = pair_weights(np.array([0.5, 0.9, 0.1]))
    np.testing.assert_allclose(w, [0.0, np.log(9), -np.log(9)])
    assert pair_weights(np.array([0.3]), threshold=0.3)[0] == pytest.approx(0.0)
    clipped = pair_weights(np.array([0.0, 1.0]))
    np.testing.assert_allclose(clipped, [-np.log(999), np.log(999)])  # PROBABILITY_CLIP 1e-3
    assert PROBABILITY_CLIP == 1e-3


def test_one_confident_apart_splits_what_hard_votes_join():
    # Hand-made: 0-1 and 1-2 are likely together (0.6), 0-2 surely apart (0.01). Greedy
    # Reconstruction of the hard votes joins all three through 1; correlation clustering keeps
    # 0 and 2 apart (+0.41 + 0.41 - 4.6 < 0) and gives 1 to the lower of its two partners.
    p = np.array([[0.6, 0.01, 0.6]])  # pairs (0, 1), (0, 2), (1, 2)
    assert greedy_reconstruction(relation_matrix(p[0] > 0.5, 3)) == ((0, 1, 2),)
    labels = batch_correlation_labels(p, 3)
    assert labels.tolist() == [[0, 0, 2]]


def test_clear_blocks_come_out_whole():
    # Two blocks {0, 1, 2} and {3, 4}, person 5 alone: weights +2 within, -2 across.
    truth = np.array([0, 0, 0, 3, 3, 5])
    w = np.where(truth[:, None] == truth[None, :], 2.0, -2.0)
    assert correlation_clustering(w).tolist() == truth.tolist()


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, 12))
def test_correlation_clustering_is_a_local_optimum_partition(seed, n):
    rng = np.random.default_rng(seed)
    w = rng.normal(0.0, 2.0, (n, n))
    w = np.triu(w, 1) + np.triu(w, 1).T
    labels = correlation_clustering(w)
    assert labels.shape == (n,)
    # Canonical: each label is its group's first row.
    for label in set(labels.tolist()):
        assert label == int(np.flatnonzero(labels == label)[0])
    # No single person can move to another group, or alone, and raise the total.
    best = objective(w, labels)
    for v in range(n):
        for target in [*set(labels.tolist()), n]:  # n: a group of their own
            moved = labels.copy()
            moved[v] = target
            assert objective(w, moved) <= best + 1e-9
    # Deterministic, and the batch form gives the same.
    assert correlation_clustering(w).tolist() == labels.tolist()
    if n >= 2:
        i, j = pair_indices(n)
        p = 1 / (1 + np.exp(-w[i, j]))
        batch = batch_correlation_labels(p[None], n)[0]
        np.testing.assert_array_equal(batch, correlation_clustering(pair_weights(p)[_square(n)]))


def _square(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Index arrays that lay a frame's pair values out as its symmetric (n, n) matrix."""
    i, j = pair_indices(n)
    k = np.zeros((n, n), dtype=np.intp)
    k[i, j] = np.arange(i.size)
    k[j, i] = np.arange(i.size)
    return (k,)


def test_correlation_clustering_matches_exhaustive_search_on_small_frames():
    # The heuristic is not exact in general; on these seeded random frames of 6 people it finds
    # the best partition (all 203 partitions enumerated) in most of them, and never one worse
    # than all-singletons (0).
    rng = np.random.default_rng(7)
    optimal = 0
    for _ in range(40):
        w = rng.normal(-0.5, 2.0, (6, 6))
        w = np.triu(w, 1) + np.triu(w, 1).T
        found = objective(w, correlation_clustering(w))
        best = max(objective(w, np.array(p)) for p in _partitions(6))
        assert 0.0 <= found <= best + 1e-9
        optimal += found >= best - 1e-9
    assert optimal >= 36


def _partitions(n: int):
    """Every partition of n rows as a label list (restricted growth strings)."""

    def grow(prefix, top):
        if len(prefix) == n:
            yield prefix
            return
        for label in range(top + 2):
            yield from grow([*prefix, label], max(top, label))

    yield from grow([0], 0) if n else iter([[]])


def test_bad_weights_and_probabilities_are_refused():
    with pytest.raises(ValueError, match=r"weights must be a square \(n, n\) matrix"):
        correlation_clustering(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="weights must be finite"):
        correlation_clustering(np.array([[0.0, np.nan], [np.nan, 0.0]]))
    with pytest.raises(ValueError, match=r"probabilities must have shape \(frames, 3\) for n=3"):
        batch_correlation_labels(np.zeros((1, 2)), 3)
    with pytest.raises(
        ValueError, match="reconstruction must be one of \\('union', 'intersection'\\)"
    ):
        batch_greedy_labels(np.zeros((1, 3), dtype=bool), 3, variant="correlation")
