"""GCFF on crowds: beyond ``_SPARSE_PEOPLE`` people, alpha-expansion evaluates only the people a
move can relabel and decides clear energy changes by their sign. It must give what the dense
windowed sweep gives (itself tested against one move at a time in ``test_gcff.py``): the same
labels, the same energies along the way, the same number of moves, on crowds and on adversarial
costs (exact ties, moves that change the energy by zero, costs of every magnitude)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import reform.gcff as gcff_module
from reform import Frame, Gcff, wrap_angle
from reform.gcff import alpha_expansion, segment_points, unary_costs

PEOPLE = gcff_module._SPARSE_PEOPLE + 1


def dense(monkeypatch: pytest.MonkeyPatch, unary, labels, label_cost):
    """The dense windowed sweep on the same input, whatever its size."""
    with monkeypatch.context() as patch:
        patch.setattr(gcff_module, "_SPARSE_PEOPLE", 10**9)
        return alpha_expansion(unary, labels, label_cost=label_cost)


def assert_same_expansion(monkeypatch, unary, labels, label_cost):
    sparse = alpha_expansion(unary, labels, label_cost=label_cost)
    reference = dense(monkeypatch, unary, labels, label_cost)
    np.testing.assert_array_equal(sparse.labels, reference.labels)
    assert sparse.energies == reference.energies
    assert sparse.moves == reference.moves
    return sparse


def crowd(n: int, seed: int, *, density_per_m2: float) -> tuple[np.ndarray, np.ndarray]:
    """``n`` people (centimetres, radians): groups of 2-5 facing their centre and walkers."""
    rng = np.random.default_rng(seed)
    side = 100.0 * math.sqrt(n / density_per_m2)
    position, yaw = [], []
    while len(yaw) < n:
        size = int(min(rng.integers(1, 6), n - len(yaw)))
        centre = rng.uniform(0, side, 2)
        phase = rng.uniform(0, 2 * math.pi)
        for m in range(size):
            a = phase + 2 * math.pi * m / size + rng.normal(0, 0.2)
            p = centre + (45 + 10 * size) * np.array([math.cos(a), math.sin(a)]) * (size > 1)
            position.append(p + rng.normal(0, 8, 2))
            facing = math.atan2(*(centre - p)[::-1]) if size > 1 else rng.uniform(-4, 4)
            yaw.append(facing + rng.normal(0, 0.3))
    return np.array(position), wrap_angle(np.array(yaw))


@settings(max_examples=12, deadline=None)
@given(
    n=st.integers(PEOPLE, 420),
    seed=st.integers(0, 2**32 - 1),
    density=st.sampled_from([0.2, 0.5, 1.5]),
    stride_cm=st.sampled_from([50.0, 70.0]),
    mdl_cm2=st.sampled_from([6_000.0, 10_000.0, 30_000.0]),
)
def test_every_round_of_a_crowd_as_the_dense_sweep(n, seed, density, stride_cm, mdl_cm2):
    position, yaw = crowd(n, seed, density_per_m2=density)
    points = segment_points(position, yaw, stride=stride_cm)
    labels = np.arange(n)
    with pytest.MonkeyPatch.context() as monkeypatch:
        for _ in range(gcff_module.MAX_REFITS):  # as gcff_labels runs them
            costs = unary_costs(points, position, labels, mdl=mdl_cm2)
            result = assert_same_expansion(monkeypatch, costs, labels, mdl_cm2)
            _, renumbered = np.unique(result.labels, return_inverse=True)
            if np.array_equal(renumbered, labels):
                break
            labels = renumbered


@pytest.mark.parametrize(
    ("case", "label_cost"),
    [("ties", 10_000.0), ("ties", 0.0), ("zero-change swaps", 4.0), ("magnitudes", 1e4)],
)
def test_adversarial_costs_as_the_dense_sweep(monkeypatch, case, label_cost):
    rng = np.random.default_rng(len(case))
    n = PEOPLE + 40
    k = n
    if case == "ties":  # a few values only: equal deltas, equal energies, everywhere
        unary = rng.integers(0, 4, (n, k)) * 5_000.0
    elif case == "zero-change swaps":  # pairs whose two labels cost the same either way
        unary = np.full((n, k), 50.0)
        for a in range(0, n - 1, 2):
            unary[a, a] = unary[a + 1, a + 1] = unary[a, a + 1] = unary[a + 1, a] = 1.0
    else:  # squared distances beside visibility penalties of up to 1e200
        unary = rng.uniform(0, 1e5, (n, k))
        unary[rng.random((n, k)) < 0.05] = 10.0 ** rng.uniform(10, 200)
        np.fill_diagonal(unary, rng.uniform(0, 1e3, n))
    assert_same_expansion(monkeypatch, unary, np.arange(n), label_cost)
    # From grouped labels too (K larger than the labels used).
    assert_same_expansion(monkeypatch, unary, rng.integers(0, k // 3, n), label_cost)


def test_gcff_on_a_crowd_as_with_the_dense_sweep(monkeypatch):
    position, yaw = crowd(600, 3, density_per_m2=0.5)
    frame = Frame(ids=np.arange(600) + 1, position=position / 100, yaw=yaw)
    sparse = Gcff().predict([frame])
    monkeypatch.setattr(gcff_module, "_SPARSE_PEOPLE", 10**9)
    assert sparse == Gcff().predict([frame])
    assert any(len(group) > 1 for group in sparse[0])
