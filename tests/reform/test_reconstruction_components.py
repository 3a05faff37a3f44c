"""Greedy Reconstruction one connected component at a time (``graph_greedy_labels``) gives the
partition of the whole-matrix reference (``greedy_reconstruction``) on every frame: random
Relation Matrices and adversarial ones (ties, chains of cliques joined by weak links, many
singletons, one giant component beyond one machine word)."""

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
from reform.reconstruction import GREEDY_VARIANTS, graph_greedy_labels

VARIANTS = st.sampled_from(GREEDY_VARIANTS)


def assert_same_as_reference(labels: np.ndarray, n: int, variant: str) -> None:
    """The component-wise partition of the pairs ``labels`` equals the reference's."""
    i, j = pair_indices(n)
    pairs = np.flatnonzero(labels)
    got = graph_greedy_labels(n, i[pairs], j[pairs], variant=variant)
    expected = greedy_reconstruction(relation_matrix(labels, n), variant=variant)
    assert partition_from_labels(got, range(n)) == expected


def from_edges(n: int, edges: list[tuple[int, int]]) -> np.ndarray:
    """Pair labels of ``n`` people with ``edges`` predicted together."""
    matrix = np.zeros((n, n), dtype=bool)
    for a, b in edges:
        matrix[a, b] = matrix[b, a] = True
    i, j = pair_indices(n)
    return matrix[i, j]


@settings(max_examples=300, deadline=None)
@given(
    n=st.integers(0, 140),
    density=st.sampled_from([0.005, 0.02, 0.06, 0.2, 0.6, 0.97]),
    seed=st.integers(0, 2**32 - 1),
    variant=VARIANTS,
)
def test_random_frames_give_the_reference_partition(n, density, seed, variant):
    i, _ = pair_indices(n)
    labels = np.random.default_rng(seed).random(i.size) < density
    assert_same_as_reference(labels, n, variant)


@settings(max_examples=150, deadline=None)
@given(
    sizes=st.lists(st.integers(1, 9), min_size=1, max_size=25),
    drop=st.sampled_from([0.0, 0.05, 0.2]),
    links=st.sampled_from([0.0, 0.002, 0.01, 0.05]),
    seed=st.integers(0, 2**32 - 1),
    variant=VARIANTS,
)
def test_noisy_groups_joined_by_weak_links(sizes, drop, links, seed, variant):
    # Cliques with some of their pairs missed, stray pairs linking them (so components chain
    # several groups together), people shuffled so groups interleave in row order.
    rng = np.random.default_rng(seed)
    truth = rng.permutation(np.repeat(np.arange(len(sizes)), sizes))
    n = truth.size
    i, j = pair_indices(n)
    together = truth[i] == truth[j]
    labels = np.where(together, rng.random(i.size) >= drop, rng.random(i.size) < links)
    assert_same_as_reference(labels, n, variant)


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(65, 200),
    reach=st.integers(1, 4),
    seed=st.integers(0, 2**32 - 1),
    variant=VARIANTS,
)
def test_one_giant_chain_beyond_one_word(n, reach, seed, variant):
    # People on a line, each predicted together with the next `reach` ones (and a few misses):
    # one component of more than 64 people whose agreements tie all along.
    rng = np.random.default_rng(seed)
    order = rng.permutation(n)
    i, j = pair_indices(n)
    labels = (np.abs(order[i] - order[j]) <= reach) & (rng.random(i.size) < 0.95)
    assert_same_as_reference(labels, n, variant)


@pytest.mark.parametrize("variant", GREEDY_VARIANTS)
@pytest.mark.parametrize(
    ("case", "n", "edges"),
    [
        # Every pair ties: a cycle's pairs all agree on 2; the lowest pair goes first.
        ("cycle", 7, [(k, (k + 1) % 7) for k in range(7)]),
        # A complete bipartite graph: all pairs agree on 2 (the two of them), ties everywhere.
        ("bipartite", 8, [(a, b) for a in range(4) for b in range(4, 8)]),
        # A star: the centre's pairs tie; union takes everyone, intersection only the lowest.
        ("star", 6, [(0, k) for k in range(1, 6)]),
        # Two triangles joined through a weak link (2, 3).
        ("bridge", 6, [(0, 1), (0, 2), (1, 2), (2, 3), (3, 4), (3, 5), (4, 5)]),
        # Many singletons around one pair.
        ("singletons", 40, [(17, 33)]),
        ("nobody", 30, []),
    ],
)
def test_adversarial_small_frames(case, n, edges, variant):
    assert_same_as_reference(from_edges(n, edges), n, variant)


@pytest.mark.parametrize("variant", GREEDY_VARIANTS)
def test_one_giant_component_of_nearly_everyone(variant):
    # 150 people, each pair predicted together unless a sparse random pattern says no: one
    # component, beliefs all different, many ties.
    n = 150
    i, _ = pair_indices(n)
    labels = np.random.default_rng(7).random(i.size) < 0.97
    assert_same_as_reference(labels, n, variant)


def test_everyone_together_is_one_group_and_nobody_is_singletons():
    n = 300
    i, j = pair_indices(n)
    assert graph_greedy_labels(n, i, j).tolist() == [0] * n
    assert graph_greedy_labels(n, [], []).tolist() == list(range(n))
    assert graph_greedy_labels(0, [], []).tolist() == []


def test_pairs_in_any_order_and_repeated_give_the_same_labels():
    rng = np.random.default_rng(3)
    n = 90
    i, j = pair_indices(n)
    pairs = np.flatnonzero(rng.random(i.size) < 0.05)
    expected = graph_greedy_labels(n, i[pairs], j[pairs])
    shuffled = rng.permutation(np.concatenate([pairs, pairs[:40]]))
    assert graph_greedy_labels(n, i[shuffled], j[shuffled]).tolist() == expected.tolist()


@pytest.mark.parametrize("n", [65, 100])
def test_batch_beyond_one_word_reconstructs_each_frame_alone(n):
    # Frames of a batch are one graph to graph_greedy_labels: none may reach into another.
    rng = np.random.default_rng(n)
    i, _ = pair_indices(n)
    stack = rng.random((7, i.size)) < rng.choice([0.01, 0.04, 0.3], size=(7, 1))
    for variant in GREEDY_VARIANTS:
        labels = batch_greedy_labels(stack, n, variant=variant)
        for row, frame_labels in zip(stack, labels, strict=True):
            expected = greedy_reconstruction(relation_matrix(row, n), variant=variant)
            assert partition_from_labels(frame_labels, range(n)) == expected


def test_bad_pairs_are_named():
    with pytest.raises(ValueError, match=r"pairs must satisfy 0 <= first < second < n=3"):
        graph_greedy_labels(3, [1], [0])
    with pytest.raises(ValueError, match=r"pairs must satisfy 0 <= first < second < n=3"):
        graph_greedy_labels(3, [0], [3])
    with pytest.raises(ValueError, match=r"first and second must have one shape, got \(2,\)"):
        graph_greedy_labels(3, [0, 1], [2])
    with pytest.raises(ValueError, match=r"n must be >= 0, got -1"):
        graph_greedy_labels(-1, [], [])
    with pytest.raises(ValueError, match="reconstruction must be one of .* got 'mean'"):
        graph_greedy_labels(3, [0], [1], variant="mean")
