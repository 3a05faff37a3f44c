"""GTCG (reform.gtcg): frustum samples, frustum affinities and the detector."""

from __future__ import annotations

import inspect

import numpy as np
import pytest
from field_scores import (
    REAL_DATASETS,
    annotated_frames,
    assert_beats_majority,
    assert_same_groups_moved_and_relabelled,
)

from reform import DetectorError, Frame, detector_info, make_detector
from reform.gtcg import Gtcg, frustum_affinity, frustum_samples


def frame(xy, yaw, ids=None, head_yaw=None) -> Frame:
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    n = len(xy)
    heads = {}
    if head_yaw is not None:
        head_yaw = np.asarray(head_yaw, dtype=float)
        heads = {
            "head_position": np.where(np.isnan(head_yaw)[:, None], np.nan, xy),
            "head_yaw": head_yaw,
        }
    return Frame(
        ids=np.arange(1, n + 1) if ids is None else ids,
        position=xy,
        yaw=np.asarray(yaw, dtype=float),
        **heads,
    )


def local(samples: int = 2000, length: float = 1.7, seed: int = 0) -> np.ndarray:
    return frustum_samples(
        np.random.default_rng(seed), samples=samples, length=length, aperture=np.deg2rad(160)
    )


def test_frustum_samples_follow_the_cviu_model():
    points = local(samples=20_000)
    radius = np.hypot(points[:, 0], points[:, 1])
    angle = np.arctan2(points[:, 1], points[:, 0])
    assert points.shape == (20_000, 2)
    assert radius.max() <= 1.7
    # Beta(0.8, 1.1) has mean 0.8 / 1.9 of the length; directions N(0, 80° / 3).
    assert radius.mean() == pytest.approx(1.7 * 0.8 / 1.9, rel=0.02)
    assert angle.std() == pytest.approx(np.deg2rad(80) / 3, rel=0.03)
    np.testing.assert_array_equal(local(), local())  # one seed, one frustum


def test_far_apart_frustums_diverge_fully():
    # Hand-computed: 10 m apart, frustums of 1.7 m share no bin: JS = 1, affinity exp(-1/σ).
    affinity = frustum_affinity(
        [[0, 0], [10, 0]], [0.0, np.pi], local=local(), sigma=0.6, bin_size=0.3
    )
    assert affinity[0, 1] == affinity[1, 0] == np.exp(-1 / 0.6)
    assert affinity[0, 0] == affinity[1, 1] == 0.0


def test_one_pose_twice_is_full_affinity():
    # Hand-computed: the same spot and heading give the same histogram: JS = 0, affinity 1.
    affinity = frustum_affinity(
        [[2, 3], [2, 3]], [0.4, 0.4], local=local(), sigma=0.6, bin_size=0.3
    )
    assert affinity[0, 1] == 1.0


def test_affinities_do_not_depend_on_the_listing():
    rng = np.random.default_rng(1)
    xy = rng.uniform(0, 4, (8, 2))
    yaw = rng.uniform(-np.pi, np.pi, 8)
    order = rng.permutation(8)
    a = frustum_affinity(xy, yaw, local=local(), sigma=0.6, bin_size=0.3)
    b = frustum_affinity(xy[order], yaw[order], local=local(), sigma=0.6, bin_size=0.3)
    np.testing.assert_allclose(b, a[np.ix_(order, order)], rtol=1e-12, atol=0)
    np.testing.assert_allclose(a, a.T, rtol=1e-12, atol=0)


def test_two_facing_and_one_far_away():
    # With σ = 0.2 the affinity of anyone far away is exp(-5); the facing pair is a dominant
    # set when its affinity beats twice that (3 earns exp(-5) against the pair's barycentre,
    # whose payoff is a/2), i.e. when its divergence is below 1 - 0.2 ln 2 = 0.861.
    scene = frame([[0, 0], [1.2, 0], [20, 0]], [0.0, np.pi, 0.0])
    affinity = frustum_affinity(scene.position, scene.yaw, local=local(), sigma=0.2, bin_size=0.3)
    assert -0.2 * np.log(affinity[0, 1]) < 1 - 0.2 * np.log(2)
    assert Gtcg(sigma=0.2).predict([scene]) == [((1, 2), (3,))]


def test_two_people_apart_pair_up_unless_disjoint_frustums_count_zero():
    # Hand-computed: 4 m apart facing away, the frustums share no bin, so their affinity is the
    # floor exp(-1/σ) > 0; with nobody else, that pair is a dominant set (as in the authors'
    # code). With zero_disjoint the floor is taken off: no payoff at all, each alone.
    scene = frame([[0, 0], [4, 0]], [np.pi, 0.0])
    assert Gtcg().predict([scene]) == [((1, 2),)]
    assert Gtcg(zero_disjoint=True).predict([scene]) == [((1,), (2,))]


def test_several_frames_average_the_affinities_of_the_past():
    # Hand-computed, with zero_disjoint (frustums sharing no bin count 0). At t = 0, 1 and 2
    # face each other 1.2 m apart (a positive affinity); at t = 1, 2 stands 10 m away and 4,
    # absent before, 20 m away: every frustum is disjoint, every affinity 0, everyone alone.
    # Averaged over both frames (frames=2), 1 and 2 keep half their t = 0 affinity and nobody
    # else has any: at t = 1 they are a pair. A frame of another sequence is not mixed in.
    before = Frame(
        ids=[1, 2, 3],
        position=[[0, 0], [1.2, 0], [30, 0]],
        yaw=[0.0, np.pi, 0.0],
        time=0.0,
        sequence="s",
    )
    after = Frame(
        ids=[1, 2, 3, 4],
        position=[[0, 0], [10, 0], [30, 0], [20, 0]],
        yaw=[0.0, np.pi, 0.0, 0.0],
        time=1.0,
        sequence="s",
    )
    other = after.replace(sequence="t")
    alone = ((1,), (2,), (3,), (4,))
    assert Gtcg(zero_disjoint=True).predict([before, after])[1] == alone
    both = Gtcg(zero_disjoint=True, frames=2).predict([before, after, other])
    assert both[1] == ((1, 2), (3,), (4,))
    assert both[2] == alone


def test_a_missing_head_falls_back_to_the_body():
    scene = frame([[0, 0], [1.2, 0], [20, 0]], [0.0, np.pi, 0.0], head_yaw=[np.nan, np.nan, 0.0])
    assert Gtcg(sigma=0.2, orientation="head").predict([scene]) == [((1, 2), (3,))]


def test_nobody_one_and_two_people():
    nobody = Frame(ids=np.zeros(0, np.int64), position=np.zeros((0, 2)), yaw=np.zeros(0))
    one = frame([[0, 0]], [0.0], ids=[7])
    assert Gtcg().predict([nobody, one]) == [(), ((7,),)]


def test_the_same_answer_twice_and_for_one_seed():
    rng = np.random.default_rng(5)
    scene = frame(rng.uniform(0, 5, (20, 2)), rng.uniform(-np.pi, np.pi, 20))
    first = Gtcg(random_state=3).predict([scene])
    assert first == Gtcg(random_state=3).predict([scene]) == Gtcg(random_state=3).predict([scene])


@pytest.mark.parametrize(
    ("option", "value", "expected"),
    [
        ("sigma", -1, "a float from 0.001 to 100, got a int (-1)"),
        ("bin", 0.0, "a float in m from 0.01 to 100, got a float (0.0)"),
        ("samples", 2.5, "an int from 10 to 100,000, got a float (2.5)"),
    ],
)
def test_options_out_of_range_are_one_line(option, value, expected):
    with pytest.raises(DetectorError) as raised:
        make_detector("gtcg", **{option: value})
    assert str(raised.value) == f"detector 'gtcg': option {option} expects {expected}"


def test_the_estimator_refuses_bad_parameters_itself():
    with pytest.raises(ValueError, match=r"^sigma must be a number in \(0, 100\], got -1$"):
        Gtcg(sigma=-1).fit([])
    with pytest.raises(ValueError, match=r"^samples must be an integer in \[10, 100000\]"):
        Gtcg(samples=3).fit([])


def test_declared_defaults_are_the_estimators():
    declared = {o.name: o.default for o in detector_info("gtcg").options}
    signature = inspect.signature(Gtcg).parameters
    assert declared == {name: signature[name].default for name in declared}


def test_dense_scenes_keep_their_groups_turned_moved_and_relabelled():
    assert_same_groups_moved_and_relabelled(Gtcg(), seed=31)


@pytest.mark.parametrize("name", REAL_DATASETS)
def test_beats_the_majority_baseline_on_real_data(shared_datasets, name):
    assert_beats_majority("gtcg", annotated_frames(shared_datasets, name))
