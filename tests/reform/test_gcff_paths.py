"""GCFF's speed paths give the numpy path's answers exactly.

Up to ``_PLAIN_PEOPLE`` people, ``gcff_labels`` runs in plain Python; it must compute the same
costs bit for bit (``unary_costs``) and the same labels (``alpha_expansion``, itself tested
against one move at a time in ``test_gcff.py``), on scenes and on adversarial costs: exact ties,
moves that change the energy by zero, costs of every magnitude, someone on a group's centre.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import reform.gcff as gcff_module
from reform.gcff import alpha_expansion, gcff_labels, segment_points, unary_costs

PLAIN = gcff_module._PLAIN_PEOPLE


def numpy_labels(monkeypatch: pytest.MonkeyPatch, position, yaw, **params) -> np.ndarray:
    """``gcff_labels`` through the numpy path, whatever the frame's size."""
    with monkeypatch.context() as patch:
        patch.setattr(gcff_module, "_PLAIN_PEOPLE", 0)
        return gcff_labels(position, yaw, **params)


def small_scene(seed: int, n: int, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """``n`` people (metres, radians) of one kind of scene."""
    rng = np.random.default_rng(seed)
    if kind == "spread":
        return rng.uniform(0.0, 3.0, (n, 2)), rng.uniform(-4.0, 4.0, n)
    if kind == "lattice":  # positions and yaws on a lattice: exact ties everywhere
        return rng.integers(0, 6, (n, 2)) * 0.3, rng.integers(0, 8, n) * (math.pi / 4)
    if kind == "circle":  # everyone facing the centre, the first person on it
        angle = rng.uniform(0.0, 2 * math.pi, n)
        position = 0.7 * np.stack([np.cos(angle), np.sin(angle)], axis=1)
        position[0] = [1e-11, 0.0]
        return position, angle + math.pi
    # "packed": everyone within everyone's neighbourhood
    return rng.uniform(0.0, 0.8, (n, 2)), rng.uniform(-4.0, 4.0, n)


@settings(max_examples=150, deadline=None)
@given(
    n=st.integers(2, PLAIN),
    seed=st.integers(0, 2**32 - 1),
    kind=st.sampled_from(["spread", "lattice", "circle", "packed"]),
    stride=st.sampled_from([0.0, 0.5, 0.7]),
    mdl=st.sampled_from([0.1, 1.0, 3.0, 100.0]),
)
def test_few_people_as_the_numpy_path(n, seed, kind, stride, mdl):
    position, yaw = small_scene(seed, n, kind)
    plain = gcff_labels(position, yaw, stride=stride, mdl=mdl)
    with pytest.MonkeyPatch.context() as monkeypatch:
        np.testing.assert_array_equal(
            plain, numpy_labels(monkeypatch, position, yaw, stride=stride, mdl=mdl)
        )


@settings(max_examples=150, deadline=None)
@given(
    n=st.integers(2, PLAIN),
    seed=st.integers(0, 2**32 - 1),
    kind=st.sampled_from(["spread", "lattice", "circle", "packed"]),
    mdl_cm2=st.sampled_from([100.0, 10_000.0, 1e6]),
)
def test_plain_costs_are_unary_costs_bit_for_bit(n, seed, kind, mdl_cm2):
    position, yaw = small_scene(seed, n, kind)
    position_cm = position * 100
    points = segment_points(position_cm, yaw, stride=70.0)
    labels = np.unique(np.random.default_rng(seed).integers(0, n, n), return_inverse=True)[1]
    expected = unary_costs(points, position_cm, labels, mdl=mdl_cm2)
    plain = gcff_module._plain_unary(
        points.tolist(), position_cm.tolist(), labels.tolist(), mdl_cm2
    )
    np.testing.assert_array_equal(np.array(plain), expected)  # NaN-free, so exact equality


@pytest.mark.parametrize("label_cost", [0.0, 4.0, 5_000.0, 10_000.0])
@pytest.mark.parametrize("case", ["ties", "zero-change swaps", "magnitudes", "wide"])
def test_plain_expansion_as_alpha_expansion(case, label_cost):
    rng = np.random.default_rng(len(case) + int(label_cost))
    for _ in range(40):
        n = int(rng.integers(2, PLAIN + 1))
        k = int(rng.integers(1, 3 * n)) if case == "wide" else n
        if case == "ties":  # a few values only: equal deltas, equal energies
            unary = rng.integers(0, 4, (n, k)) * 5_000.0
        elif case == "zero-change swaps":  # pairs whose two labels cost the same either way
            unary = np.full((n, k), 50.0)
            for a in range(0, n - 1, 2):
                unary[a, a] = unary[a + 1, a + 1] = unary[a, a + 1] = unary[a + 1, a] = 1.0
        else:  # sums whose value depends on the order of their terms
            unary = rng.random((n, k)) * 10.0 ** rng.integers(-3, 12, (n, k))
            unary[rng.random((n, k)) < 0.05] = 10.0 ** rng.uniform(10, 200)
        for labels in (np.arange(n) % k, rng.integers(0, k, n)):
            expected = alpha_expansion(unary, labels, label_cost=label_cost).labels
            plain = gcff_module._plain_expansion(unary.tolist(), labels.tolist(), label_cost)
            np.testing.assert_array_equal(plain, expected)


def test_the_hidden_person_with_the_penalty_off_takes_the_plain_path_too(monkeypatch):
    # The plain path reads the module's constants at call time, as the numpy path does.
    position_cm = np.array([[0.0, 0.0], [120.0, 0.0], [210.0, 10.0]])
    yaw = np.array([0.0, math.pi, math.atan2(-10.0, 60.0 - 210.0)])
    assert gcff_labels(position_cm / 100, yaw, stride=0.7, mdl=1.0).tolist() == [0, 0, 1]
    monkeypatch.setattr(gcff_module, "VISIBILITY_COSINE", 1.1)
    assert gcff_labels(position_cm / 100, yaw, stride=0.7, mdl=1.0).tolist() == [0, 0, 0]


@settings(max_examples=10, deadline=None)
@given(
    n=st.integers(gcff_module._SPARSE_PEOPLE + 1, 400),
    seed=st.integers(0, 2**32 - 1),
    kind=st.sampled_from(["spread", "lattice", "packed"]),
    mdl_cm2=st.sampled_from([6_000.0, 10_000.0, 30_000.0]),
)
def test_a_crowds_reused_rows_are_the_costs_computed_afresh(n, seed, kind, mdl_cm2):
    """A crowd's refits keep the rows of unchanged groups: every refit's costs must be those
    computed from nothing, bit for bit, through all the refits of a run."""
    position, yaw = small_scene(seed, n, kind)
    position_cm = position * (100 * math.sqrt(n / 12))  # as dense as the small scenes
    points = segment_points(position_cm, yaw, stride=70.0)
    labels = np.arange(n)
    buffer = gcff_module._CostBuffer(n)
    for _ in range(gcff_module.MAX_REFITS):
        costs = gcff_module._group_costs(points, position_cm, labels, mdl=mdl_cm2, buffer=buffer)
        fresh = unary_costs(points, position_cm, labels, mdl=mdl_cm2)
        np.testing.assert_array_equal(costs.T, fresh)
        expanded = alpha_expansion(costs.T, labels, label_cost=mdl_cm2).labels
        expanded = np.unique(expanded, return_inverse=True)[1]
        if np.array_equal(expanded, labels):
            break
        labels = expanded
