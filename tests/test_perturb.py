"""Tracking errors on frames: reform.perturb.Perturbation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from reform import ROBOT, Frame
from reform.perturb import Perturbation, restrict_groups


def _frame(n: int = 6, *, robot: bool = True) -> Frame:
    rng = np.random.default_rng(3)
    ids = np.arange(1, n + 1) * 10
    kinds = ["human"] * n
    if robot:
        kinds[-1] = ROBOT
    head = rng.uniform(-2, 2, (n, 2))
    head_yaw = rng.uniform(-3, 3, n)
    head[1] = np.nan
    head_yaw[1] = np.nan
    return Frame(
        ids=ids,
        kinds=kinds,
        position=rng.uniform(-3, 3, (n, 2)),
        yaw=rng.uniform(-3, 3, n),
        head_position=head,
        head_yaw=head_yaw,
        groups=((10, 20, 30), (40, 50)),
        time=1.5,
        sequence="s",
    )


def test_zero_levels_change_nothing() -> None:
    frame = _frame()
    out = Perturbation().apply(frame, np.random.default_rng(0))
    assert Perturbation().is_identity
    assert out == frame


def test_same_seed_same_output_and_the_input_is_untouched() -> None:
    frame = _frame()
    before = frame.position.copy()
    perturbation = Perturbation(position_noise=0.2, yaw_noise=0.3, dropout=0.3)
    a = perturbation.apply_all([frame, frame], np.random.default_rng(7))
    b = perturbation.apply_all([frame, frame], np.random.default_rng(7))
    assert a == b
    np.testing.assert_array_equal(frame.position, before)


def test_common_random_numbers_scale_the_same_draws() -> None:
    frame = _frame(robot=False)
    small = Perturbation(position_noise=0.1, yaw_noise=0.05).apply(frame, np.random.default_rng(1))
    large = Perturbation(position_noise=0.3, yaw_noise=0.15).apply(frame, np.random.default_rng(1))
    np.testing.assert_allclose(
        large.position - frame.position, 3 * (small.position - frame.position)
    )
    small_turn = np.angle(np.exp(1j * (small.yaw - frame.yaw)))
    large_turn = np.angle(np.exp(1j * (large.yaw - frame.yaw)))
    np.testing.assert_allclose(large_turn, 3 * small_turn, atol=1e-12)


def test_dropouts_are_nested_along_a_sweep() -> None:
    frame = _frame(40, robot=False)
    kept = [
        set(Perturbation(dropout=p).apply(frame, np.random.default_rng(5)).ids.tolist())
        for p in (0.0, 0.2, 0.5, 0.8, 1.0)
    ]
    for wider, narrower in zip(kept, kept[1:], strict=False):
        assert narrower <= wider
    assert kept[0] == set(frame.ids.tolist()) and kept[-1] == set()


def test_dropped_people_leave_the_ground_truth() -> None:
    frame = _frame(robot=False)
    for seed in range(20):
        out = Perturbation(dropout=0.5).apply(frame, np.random.default_rng(seed))
        kept = set(out.ids.tolist())
        assert out.groups == restrict_groups(frame.groups, kept)
        assert all(set(g) <= kept and g for g in out.groups)
        rows = [frame.index_of(int(i)) for i in out.ids]
        np.testing.assert_array_equal(out.position, frame.position[rows])  # no noise asked


def test_robots_keep_their_pose_unless_asked() -> None:
    frame = _frame()
    robot = int(np.flatnonzero(frame.is_robot)[0])
    quiet = Perturbation(position_noise=0.5, yaw_noise=1.0, dropout=1.0)
    out = quiet.apply(frame, np.random.default_rng(0))
    assert out.ids.tolist() == [frame.ids[robot]]
    np.testing.assert_array_equal(out.position[0], frame.position[robot])
    assert out.yaw[0] == frame.yaw[robot]
    loud = Perturbation(position_noise=0.5, perturb_robots=True)
    moved = loud.apply(frame, np.random.default_rng(0))
    assert not np.array_equal(moved.position[robot], frame.position[robot])


def test_yaws_stay_wrapped_and_missing_heads_stay_missing() -> None:
    frame = _frame()
    out = Perturbation(yaw_noise=3.0).apply(frame, np.random.default_rng(2))
    assert np.all(np.abs(out.yaw) <= math.pi)
    assert np.isnan(out.head_yaw[1]) and np.all(np.isnan(out.head_position[1]))
    finite = ~np.isnan(out.head_yaw)
    assert np.all(np.abs(out.head_yaw[finite]) <= math.pi)


def test_noise_has_the_asked_spread() -> None:
    n = 20000
    frame = Frame(ids=np.arange(n), position=np.zeros((n, 2)), yaw=np.zeros(n))
    out = Perturbation(position_noise=0.3, yaw_noise=0.2).apply(frame, np.random.default_rng(4))
    assert abs(out.position.std() - 0.3) < 0.01  # 40,000 draws: sd of the sd ~ 0.001
    assert abs(out.yaw.std() - 0.2) < 0.01


def test_real_frames(salsa_dataset) -> None:
    frames = salsa_dataset.annotated()[:20]
    out = Perturbation(position_noise=0.1, dropout=0.3).apply_all(frames, np.random.default_rng(0))
    assert [f.time for f in out] == [f.time for f in frames]
    assert sum(f.n_people for f in out) < sum(f.n_people for f in frames)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"dropout": 1.5}, r"Perturbation.dropout must be in \[0, 1\], got 1.5"),
        ({"position_noise": -0.1}, r"Perturbation.position_noise must be >= 0 and finite"),
        ({"yaw_noise": math.inf}, r"Perturbation.yaw_noise must be >= 0 and finite"),
        ({"yaw_noise": "0.1"}, r"Perturbation.yaw_noise must be a number, got '0.1'"),
    ],
)
def test_bad_levels(kwargs, message) -> None:
    with pytest.raises(ValueError, match=message):
        Perturbation(**kwargs)


def test_bad_arguments() -> None:
    with pytest.raises(ValueError, match="rng must be a numpy.random.Generator, got int"):
        Perturbation().apply(_frame(), 3)
    with pytest.raises(ValueError, match="frame must be a reform.Frame, got dict"):
        Perturbation().apply({}, np.random.default_rng(0))
