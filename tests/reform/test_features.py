"""Pair features: hand-computed Distance and Effort Angle, symmetry, invariance, options, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from reform import (
    DEFAULT_FEATURES,
    Frame,
    batch_pair_features,
    effort_angle,
    frame_pair_features,
    pair_indices,
    wrap_angle,
)
from reform.features import (
    DISTANCE,
    EFFORT_ANGLE,
    HEAD_DISTANCE,
    HEAD_EFFORT_ANGLE,
    INVOLVES_ROBOT,
    LARGER_TURN,
    OSPACE_DISTANCE,
    RELATIVE_DISTANCE,
    check_features,
    frame_scale,
)

PI = math.pi


def ea(p_i, yaw_i, p_j, yaw_j) -> float:
    return float(effort_angle(np.array(p_i, float), yaw_i, np.array(p_j, float), yaw_j))


# Hand-computed cases: i at the origin, j one metre along +x, so phi_ij = 0 and phi_ji = pi.
@pytest.mark.parametrize(
    ("yaw_i", "yaw_j", "expected", "case"),
    [
        (0.0, PI, 0.0, "face to face"),
        (PI, 0.0, 2 * PI, "back to back"),
        (-PI, 0.0, 2 * PI, "back to back, yaw -pi"),
        (0.0, 0.0, PI, "i faces j, j faces away"),
        (0.0, PI / 2, PI / 2, "i faces j, j perpendicular"),
        (PI / 2, PI / 2, PI, "side by side, both facing +y"),
        (PI / 2, -PI / 2, PI, "perpendicular, facing opposite ways"),
        (PI / 2, PI, PI / 2, "i perpendicular, j faces i"),
        (-PI / 2, PI / 2, PI, "both perpendicular, mirrored"),
        (PI / 4, 3 * PI / 4, PI / 2, "both turned 45 degrees toward +y"),
    ],
)
def test_effort_angle_hand_computed(yaw_i, yaw_j, expected, case):
    assert ea((0, 0), yaw_i, (1, 0), yaw_j) == pytest.approx(expected, abs=1e-12), case


def test_effort_angle_is_symmetric_in_the_pair():
    rng = np.random.default_rng(3)
    p = rng.normal(size=(500, 2, 2)) * 3
    yaw = rng.uniform(-PI, PI, size=(500, 2))
    forward = effort_angle(p[:, 0], yaw[:, 0], p[:, 1], yaw[:, 1])
    backward = effort_angle(p[:, 1], yaw[:, 1], p[:, 0], yaw[:, 0])
    np.testing.assert_allclose(forward, backward, atol=1e-12)


def test_distance_and_pair_order_hand_computed():
    frame = Frame(
        ids=[7, 3, 5],
        position=[[0.0, 0.0], [3.0, 4.0], [0.0, -2.0]],
        yaw=[0.0, 0.0, PI / 2],
    )
    x = frame_pair_features(frame)
    i, j = pair_indices(3)
    assert (i.tolist(), j.tolist()) == ([0, 0, 1], [1, 2, 2])  # rows, not ids
    assert x.shape == (3, 2)
    np.testing.assert_allclose(x[:, 0], [5.0, 2.0, math.hypot(3, 6)])
    # pair (row 0, row 2): j straight below i (phi = -pi/2); i faces +x: a_i = pi/2;
    # j faces +y, i.e. straight at i: a_j = 0.
    assert x[1, 1] == pytest.approx(PI / 2)


def test_frames_of_zero_and_one_person_have_no_pairs():
    for n in (0, 1):
        frame = Frame(ids=np.arange(n), position=np.zeros((n, 2)), yaw=np.zeros(n))
        assert frame_pair_features(frame).shape == (0, 2)
        assert frame_pair_features(frame, features=(DISTANCE,)).shape == (0, 1)


def test_batch_equals_frame_by_frame_bit_for_bit():
    rng = np.random.default_rng(4)
    position = rng.normal(size=(40, 9, 2)) * 4
    yaw = rng.uniform(-PI, PI, size=(40, 9))
    batch = batch_pair_features(position, yaw)
    for f in range(40):
        frame = Frame(ids=np.arange(9), position=position[f], yaw=yaw[f])
        assert np.array_equal(batch[f], frame_pair_features(frame))


@pytest.mark.parametrize("n", [9, 600], ids=["scale-from-pairs", "scale-from-a-tree"])
def test_chosen_pairs_have_the_values_they_have_among_all_pairs(n):
    # Every feature of a chosen pair, bit for bit, in the order asked: the frame's scale (for
    # the scale-free features) stays that of all its people.
    rng = np.random.default_rng(n)
    position = rng.normal(size=(2, n, 2)) * 4
    yaw = rng.uniform(-PI, PI, size=(2, n))
    head_position = position + rng.normal(size=position.shape) * 0.1
    head_position[:, ::3] = np.nan
    head_yaw = np.where(rng.random((2, n)) < 0.3, np.nan, yaw + 0.2)
    robot = rng.random((2, n)) < 0.1
    everything = (*DEFAULT_FEATURES, HEAD_DISTANCE, HEAD_EFFORT_ANGLE, INVOLVES_ROBOT)
    everything += (RELATIVE_DISTANCE, OSPACE_DISTANCE, LARGER_TURN)
    arrays = {"head_position": head_position, "head_yaw": head_yaw, "is_robot": robot}
    all_pairs = batch_pair_features(position, yaw, features=everything, **arrays)
    i, j = pair_indices(n)
    chosen = rng.permutation(i.size)[: max(3, i.size // 50)]
    some = batch_pair_features(
        position, yaw, features=everything, pairs=(i[chosen], j[chosen]), **arrays
    )
    assert np.array_equal(some, all_pairs[:, chosen], equal_nan=True)
    none = batch_pair_features(position, yaw, features=everything, pairs=([], []), **arrays)
    assert none.shape == (2, 0, len(everything))


def test_chosen_pairs_must_be_rows_of_the_frame():
    position, yaw = np.zeros((1, 3, 2)), np.zeros((1, 3))
    with pytest.raises(ValueError, match=r"pairs must hold rows in \[0, 3\), got rows out of"):
        batch_pair_features(position, yaw, pairs=([0], [3]))
    with pytest.raises(ValueError, match=r"pairs must be two \(m,\) arrays of rows, got \(2,\)"):
        batch_pair_features(position, yaw, pairs=([0, 1], [2]))


def test_head_features_use_head_and_fall_back_to_body():
    frame = Frame(
        ids=[1, 2, 3],
        position=[[0.0, 0.0], [1.0, 0.0], [0.0, 2.0]],
        yaw=[PI, 0.0, 0.0],  # bodies back to back for (1, 2)
        head_position=[[0.0, 0.1], [1.0, 0.1], [np.nan, np.nan]],
        head_yaw=[0.0, PI, np.nan],  # heads face to face; person 3's head unknown
    )
    x = frame_pair_features(frame, features=(EFFORT_ANGLE, HEAD_EFFORT_ANGLE, HEAD_DISTANCE))
    assert x[0, 0] == pytest.approx(2 * PI)
    assert x[0, 1] == pytest.approx(0.0)
    assert x[0, 2] == pytest.approx(1.0)
    # person 3 has no head: the pair (1, 3) uses 1's head and 3's body.
    expected = ea((0.0, 0.1), 0.0, (0.0, 2.0), 0.0)
    assert x[1, 1] == pytest.approx(expected)
    body_only = Frame(ids=[1, 2, 3], position=frame.position, yaw=frame.yaw)
    y = frame_pair_features(body_only, features=(EFFORT_ANGLE, HEAD_EFFORT_ANGLE))
    np.testing.assert_array_equal(y[:, 0], y[:, 1])


def test_involves_robot_flags_pairs_with_a_robot():
    frame = Frame(
        ids=[1, 2, 3],
        position=[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        yaw=[0.0, 0.0, 0.0],
        kinds=("human", "robot", "human"),
    )
    x = frame_pair_features(frame, features=(INVOLVES_ROBOT,))
    assert x[:, 0].tolist() == [1.0, 0.0, 1.0]  # (1,2) (1,3) (2,3)


def test_check_features_rejects_bad_lists():
    assert check_features(list(DEFAULT_FEATURES)) == DEFAULT_FEATURES
    with pytest.raises(ValueError, match="features must be among .* got 'speed'"):
        check_features(("distance", "speed"))
    with pytest.raises(ValueError, match="must not repeat, got \\['distance'\\]"):
        check_features(("distance", "distance"))
    with pytest.raises(ValueError, match="a feature set .* or a sequence of feature names"):
        check_features("distance")
    with pytest.raises(ValueError, match="at least one"):
        check_features(())


def test_batch_features_rejects_bad_shapes():
    with pytest.raises(
        ValueError, match=r"position must have shape \(frames, people, 2\), got \(3, 2\)"
    ):
        batch_pair_features(np.zeros((3, 2)), np.zeros(3))
    with pytest.raises(ValueError, match=r"yaw must have shape \(1, 3\), got \(3,\)"):
        batch_pair_features(np.zeros((1, 3, 2)), np.zeros(3))


coordinates = st.floats(-20, 20, allow_nan=False)
angles = st.floats(-PI, PI, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(
    xi=coordinates, yi=coordinates, xj=coordinates, yj=coordinates,
    yaw_i=angles, yaw_j=angles,
    dx=coordinates, dy=coordinates, turn=angles,
)  # fmt: skip
def test_features_are_invariant_under_moving_the_scene(xi, yi, xj, yj, yaw_i, yaw_j, dx, dy, turn):
    p = np.array([[xi, yi], [xj, yj]])
    if np.linalg.norm(p[1] - p[0]) < 1e-6:
        return  # no direction between two people at one spot
    yaw = np.array([yaw_i, yaw_j])
    before = batch_pair_features(p[None], yaw[None])[0, 0]
    rotation = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    moved = p @ rotation.T + [dx, dy]
    after = batch_pair_features(moved[None], wrap_angle(yaw + turn)[None])[0, 0]
    assert 0.0 <= before[1] <= 2 * PI
    np.testing.assert_allclose(after, before, atol=1e-9)


# ------------------------------------------------------------------------------------------------
# Scale-free features (the "relative" set)

SCALE_FREE = (RELATIVE_DISTANCE, OSPACE_DISTANCE, LARGER_TURN, EFFORT_ANGLE)


def test_feature_sets_resolve_by_name():
    assert check_features("paper") == DEFAULT_FEATURES
    assert check_features("relative") == (RELATIVE_DISTANCE, OSPACE_DISTANCE)
    with pytest.raises(ValueError, match=r"features must be a feature set \('paper', 'relative'\)"):
        check_features("scale-free")


def test_frame_scale_is_the_median_nearest_neighbour_distance():
    # Hand-computed: nearest neighbours 1, 1, 2 (the third person 2 m from the second) and 5.
    position = np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0], [3.0, 5.0]])
    assert frame_scale(position) == pytest.approx(1.5)  # median of 1, 1, 2, 5
    assert frame_scale(position[:2]) == 1.0  # two people: their distance
    assert frame_scale(np.array([[0.0, 0.0], [3.0, 4.0]])) == 5.0
    assert frame_scale(position[:1]) == 1.0  # one person: no scale to measure
    assert frame_scale(np.zeros((0, 2))) == 1.0
    # People sharing a spot are left out of the median; all sharing: scale 1.
    shared = np.array([[0.0, 0.0], [0.0, 0.0], [2.0, 0.0], [2.0, 3.0]])
    assert frame_scale(shared) == pytest.approx(2.5)  # median of 2 and 3
    assert frame_scale(np.zeros((3, 2))) == 1.0
    with pytest.raises(ValueError, match=r"position must have shape \(frames, people, 2\)"):
        frame_scale(np.zeros((2, 3)))


def test_two_people_face_to_face_share_an_o_space():
    # Hand-computed: 2 m apart, facing each other: scale 2, relative distance 1, the o-space
    # centres (1 m in front of each) coincide, neither turns.
    x = batch_pair_features(
        np.array([[[0.0, 0.0], [2.0, 0.0]]]), np.array([[0.0, PI]]), features=SCALE_FREE
    )[0, 0]
    assert x == pytest.approx([1.0, 0.0, 0.0, 0.0], abs=1e-12)
    # Back to back: centres 1 m behind each, 4 m apart = 2 scales; each turns pi.
    x = batch_pair_features(
        np.array([[[0.0, 0.0], [2.0, 0.0]]]), np.array([[PI, 0.0]]), features=SCALE_FREE
    )[0, 0]
    assert x == pytest.approx([1.0, 2.0, PI, 2 * PI], abs=1e-12)


def test_large_frames_measure_their_scale_with_a_tree():
    # Above _SCALE_MATRIX_PEOPLE the nearest neighbours come from a k-d tree: same scale.
    rng = np.random.default_rng(3)
    position = rng.uniform(0, 40, (1, 600, 2))
    i, j = pair_indices(600)
    d = np.hypot(*np.moveaxis(position[:, j] - position[:, i], -1, 0))
    matrix = np.full((600, 600), np.inf)
    matrix[i, j] = d[0]
    matrix[j, i] = d[0]
    assert frame_scale(position)[0] == pytest.approx(np.median(matrix.min(axis=1)), rel=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(2, 9),
    factor=st.floats(1e-3, 1e3),
    turn=st.floats(-PI, PI),
    shift=st.tuples(st.floats(-100, 100), st.floats(-100, 100)),
)
def test_scale_free_features_ignore_scale_and_rigid_motion(seed, n, factor, turn, shift):
    rng = np.random.default_rng(seed)
    position = rng.uniform(-5, 5, (1, n, 2))
    yaw = rng.uniform(-PI, PI, (1, n))
    before = batch_pair_features(position, yaw, features=SCALE_FREE)
    c, s = math.cos(turn), math.sin(turn)
    moved = factor * position @ np.array([[c, s], [-s, c]]) + np.array(shift)
    after = batch_pair_features(moved, wrap_angle(yaw + turn), features=SCALE_FREE)
    np.testing.assert_allclose(after, before, atol=1e-7)
    # The paper's Distance is not scale-free (a check that the test can fail):
    if abs(factor - 1) > 1e-3:
        d_before = batch_pair_features(position, yaw, features=(DISTANCE,))
        d_after = batch_pair_features(factor * position, yaw, features=(DISTANCE,))
        assert not np.allclose(d_after, d_before)
