"""Tracking errors on frames: reform.TrackerNoise, the one noise model, and reform.Perturbation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from reform import ROBOT, Frame, Perturbation, TrackerNoise, restrict_groups, wrap_angle


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
        (
            {"position_noise": -0.1},
            r"Perturbation.position_noise must be a finite number >= 0, got -0.1",
        ),
        ({"yaw_noise": math.inf}, r"Perturbation.yaw_noise must be a finite number >= 0, got inf"),
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


def _documented_draws(seed: int, n: int) -> tuple[dict[str, np.ndarray], np.random.Generator]:
    """The draws of reform.perturb's module docstring, made by hand in its order, and the
    generator after them."""
    rng = np.random.default_rng(seed)
    draws = {
        "position": rng.standard_normal((n, 2)),
        "head_position": rng.standard_normal((n, 2)),
        "yaw": rng.standard_normal(n),
        "head_yaw": rng.standard_normal(n),
        "uniform": rng.random(n),
    }
    return draws, rng


def test_the_draws_follow_the_documented_order() -> None:
    # Expected values made from a fresh generator with the same seed, drawing in the order the
    # module docstring states: every noisy number is the truth plus the level times its draw.
    frame = _frame()
    noise = TrackerNoise(position_std=0.2, yaw_std=0.1, dropout=0.4)
    rng = np.random.default_rng(11)
    out = noise.apply(frame, rng)
    z, after = _documented_draws(11, frame.n_people)
    human = ~frame.is_robot
    keep = ~(human & (z["uniform"] < 0.4))
    assert out.ids.tolist() == frame.ids[keep].tolist()
    on = human[:, None]
    np.testing.assert_array_equal(
        out.position, (frame.position + np.where(on, 0.2 * z["position"], 0.0))[keep]
    )
    np.testing.assert_array_equal(
        out.yaw, wrap_angle(frame.yaw + np.where(human, 0.1 * z["yaw"], 0.0))[keep]
    )
    np.testing.assert_array_equal(
        out.head_position,
        (frame.head_position + np.where(on, 0.2 * z["head_position"], 0.0))[keep],
    )
    np.testing.assert_array_equal(
        out.head_yaw, wrap_angle(frame.head_yaw + np.where(human, 0.1 * z["head_yaw"], 0.0))[keep]
    )
    # Those draws and no others, whatever the levels: the generator is where the hand-made one
    # is.
    assert rng.random() == after.random()
    quiet = np.random.default_rng(11)
    TrackerNoise().apply(frame, quiet)
    assert quiet.random() == _documented_draws(11, frame.n_people)[1].random()


def test_exact_noisy_values() -> None:
    # Golden numbers: what default_rng(2030) (numpy's PCG64 stream) gives in the documented
    # order (position normals first, dropout uniforms last). This is the order Perturbation has
    # always drawn in, so they are also its numbers from before the sensor's and the
    # environments' copies were merged into TrackerNoise. Person 1 is dropped, and person 2's
    # yaw crosses pi and is wrapped.
    frame = Frame(
        ids=[1, 2, 3], position=[[0.0, 0.0], [1.0, 1.0], [2.0, -1.0]], yaw=[0.0, 3.0, -1.0]
    )
    out = Perturbation(position_noise=0.1, yaw_noise=0.2, dropout=0.3).apply(
        frame, np.random.default_rng(2030)
    )
    assert out.ids.tolist() == [2, 3]
    np.testing.assert_allclose(
        out.position,
        [[0.8633605309657189, 1.2601257679481148], [1.952287228148989, -1.0535418936682752]],
        rtol=0,
        atol=1e-15,
    )
    np.testing.assert_allclose(
        out.yaw, [-3.0512893561907948, -1.3178682573713512], rtol=0, atol=1e-15
    )


def test_perturbation_is_the_tracker_noise_on_whole_frames() -> None:
    frame = _frame()
    perturbation = Perturbation(position_noise=0.2, yaw_noise=0.3, dropout=0.3)
    assert perturbation.noise == TrackerNoise(position_std=0.2, yaw_std=0.3, dropout=0.3)
    for seed in range(5):
        assert perturbation.apply(frame, np.random.default_rng(seed)) == perturbation.noise.apply(
            frame, np.random.default_rng(seed)
        )


def test_tracked_affected_and_hidden_heads() -> None:
    frame = _frame()  # the last entry is a robot
    n = frame.n_people
    tracked = np.array([True, True, False, True, True, True])
    hidden = np.array([False, False, False, True, False, False])
    out = TrackerNoise(position_std=0.3).apply(
        frame, np.random.default_rng(0), tracked=tracked, hidden_heads=hidden
    )
    assert out.ids.tolist() == frame.ids[tracked].tolist()  # no dropout asked
    assert out.groups == ((10, 20), (40, 50))
    row = out.index_of(40)
    assert np.all(np.isnan(out.head_position[row])) and np.isnan(out.head_yaw[row])
    robot = out.index_of(60)
    np.testing.assert_array_equal(out.position[robot], frame.position[n - 1])  # not affected
    untouched = TrackerNoise(position_std=0.3).apply(
        frame, np.random.default_rng(0), affected=np.zeros(n, dtype=bool)
    )
    np.testing.assert_array_equal(untouched.position, frame.position)


def test_listed_groups_keep_the_people_dropped() -> None:
    # The annotation names person 99, whom the tracker never had; people the noise model drops
    # join them in listed_groups, and groups hold who remains.
    base = _frame(robot=False)
    frame = base.replace(listed_groups=((10, 20, 30, 99), (40, 50)))
    for seed in range(20):
        out = Perturbation(dropout=0.5).apply(frame, np.random.default_rng(seed))
        kept = set(out.ids.tolist())
        assert out.listed_groups == frame.listed_groups
        assert out.groups == restrict_groups(frame.groups, kept)
        assert set(out.unseen_members) == {10, 20, 30, 40, 50, 99} - kept
    # A frame with no listed_groups keeps none: the truth is restricted to who remains.
    out = Perturbation(dropout=0.5).apply(base, np.random.default_rng(0))
    assert out.listed_groups is None and out.groups == restrict_groups(base.groups, out.ids)


def test_restrict_groups() -> None:
    groups = ((1, 2, 3), (4, 5), (6,))
    assert restrict_groups(groups, {1, 3, 6}) == ((1, 3), (6,))
    assert restrict_groups(groups, np.array([4])) == ((4,),)
    assert restrict_groups(groups, []) == ()
    assert restrict_groups(None, [1]) is None


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"dropout": -0.1}, r"TrackerNoise.dropout must be in \[0, 1\], got -0.1"),
        (
            {"position_std": math.nan},
            r"TrackerNoise.position_std must be a finite number >= 0, got nan",
        ),
        ({"yaw_std": None}, r"TrackerNoise.yaw_std must be a number, got None"),
    ],
)
def test_bad_tracker_noise(kwargs, message) -> None:
    with pytest.raises(ValueError, match=message):
        TrackerNoise(**kwargs)


def test_bad_masks() -> None:
    frame = _frame()
    noise = TrackerNoise(position_std=0.1)
    with pytest.raises(ValueError, match=r"tracked must be a bool array of shape \(6,\), got"):
        noise.apply(frame, np.random.default_rng(0), tracked=np.ones(5, dtype=bool))
    with pytest.raises(ValueError, match=r"affected must be a bool array of shape \(6,\), got int"):
        noise.apply(frame, np.random.default_rng(0), affected=np.ones(6, dtype=int))
    with pytest.raises(ValueError, match=r"position must have shape \(2, 2\) and affected \(2,\)"):
        noise.perturb_poses(
            np.random.default_rng(0), np.zeros((3, 2)), np.zeros(2), affected=np.ones(2, bool)
        )
