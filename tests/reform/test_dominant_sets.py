"""Dominant sets (reform.dominant_sets): the replicator dynamics, the peeling with Hung & Kröse's
stopping rule, their affinity, and the detector."""

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

from reform import DetectorError, Frame, detector_info, make_detector, run_detector
from reform.dominant_sets import (
    DominantSets,
    dominant_set_labels,
    hung_krose_affinity,
    replicator_dynamics,
)


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


# A clique {0, 1, 2} of affinity 1, a weak pair {3, 4} (0.2), and 3 drawn to 0 (0.5).
CLIQUE_AND_PAIR = np.array(
    [
        [0.0, 1.0, 1.0, 0.5, 0.0],
        [1.0, 0.0, 1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0, 0.0, 0.0],
        [0.5, 0.0, 0.0, 0.0, 0.2],
        [0.0, 0.0, 0.0, 0.2, 0.0],
    ]
)


def test_replicator_dynamics_reach_the_clique():
    # Hand-computed: the clique's barycentre (1/3 each) earns 2/3; 3 earns 0.5 / 3 < 2/3 there
    # and 4 earns nothing, so their shares die out.
    shares = replicator_dynamics(CLIQUE_AND_PAIR)
    np.testing.assert_allclose(shares, [1 / 3, 1 / 3, 1 / 3, 0, 0], atol=1e-6)
    assert shares.sum() == pytest.approx(1.0)


def test_no_payoff_anywhere_leaves_the_centre():
    np.testing.assert_array_equal(replicator_dynamics(np.zeros((3, 3))), np.full(3, 1 / 3))


def test_peeling_stops_at_a_set_that_is_not_dominant_among_everyone():
    # Hand-computed. First set {0, 1, 2} (payoff 2/3; 3 earns 1/6 from it, 4 nothing). Among
    # 3 and 4 the set {3, 4} has payoff 2 * 0.5 * 0.5 * 0.2 = 0.1, but 0, already taken, earns
    # 0.5 * 0.5 = 0.25 >= 0.1 against it: not dominant among everyone, so peeling stops and 3
    # and 4 are alone. Without the global context {3, 4} is a group.
    assert dominant_set_labels(CLIQUE_AND_PAIR).tolist() == [0, 0, 0, 1, 2]
    labels = dominant_set_labels(CLIQUE_AND_PAIR, global_context=False)
    assert labels.tolist() == [0, 0, 0, 1, 1]


def test_a_dominant_pair_is_kept():
    # 3 and 4 at 0.6 with 0 at 0.5 to 3: 0 earns 0.25 < the pair's 0.3; kept.
    matrix = CLIQUE_AND_PAIR.copy()
    matrix[3, 4] = matrix[4, 3] = 0.6
    assert dominant_set_labels(matrix).tolist() == [0, 0, 0, 1, 1]


def test_affinity_is_a_gaussian_of_distance_between_people_in_each_others_view():
    # Hand-computed: 1 and 2 face each other 1 m apart: exp(-1 / (2 * 1.4²)); 3 stands 1 m
    # behind 2, facing away from it: 2 is out of 3's view (off by π > 110°), so 0.
    affinity = hung_krose_affinity(
        [[0, 0], [1, 0], [2, 0]], [0.0, np.pi, 0.0], sigma=1.4, field_of_view=np.deg2rad(220)
    )
    expected = np.exp(-1.0 / (2 * 1.4**2))
    assert affinity[0, 1] == affinity[1, 0] == pytest.approx(expected, rel=1e-15)
    assert affinity[1, 2] == affinity[2, 1] == 0.0
    assert affinity[0, 2] == 0.0  # 3 faces away from 1 as well
    assert np.all(np.diag(affinity) == 0)


def test_a_whole_field_of_view_ignores_orientation():
    affinity = hung_krose_affinity(
        [[0, 0], [2, 0]], [np.pi, 0.0], sigma=1.0, field_of_view=2 * np.pi
    )
    assert affinity[0, 1] == pytest.approx(np.exp(-2.0))


def test_two_facing_and_one_looking_away():
    # Hand-computed at the default sigma 1.6 m: 1 and 2 face each other 1 m apart (affinity
    # exp(-1 / (2 * 1.6²)) = exp(-1/5.12) > 0); 3 is behind 2 facing away: affinity 0 with both.
    # Groups {1, 2}, {3}.
    scene = frame([[0, 0], [1, 0], [2, 0]], [0.0, np.pi, 0.0])
    assert DominantSets().predict([scene]) == [((1, 2), (3,))]


def test_back_to_back_is_alone():
    scene = frame([[0, 0], [0.5, 0]], [np.pi, 0.0])
    assert DominantSets().predict([scene]) == [((1,), (2,))]


def test_a_missing_head_falls_back_to_the_body():
    # Heads: 1 looks away (but its body faces 2), 2's head is unseen (NaN: its body faces 1).
    scene = frame([[0, 0], [1, 0]], [0.0, np.pi], head_yaw=[np.pi, np.nan])
    assert DominantSets(orientation="body").predict([scene]) == [((1, 2),)]
    assert DominantSets(orientation="head").predict([scene]) == [((1,), (2,))]


def test_head_orientation_on_a_frame_without_heads_is_one_line():
    scene = frame([[0, 0], [1, 0]], [0.0, np.pi])
    with pytest.raises(DetectorError, match=r"orientation='head' needs head yaws") as raised:
        run_detector("dominant-sets", make_detector("dominant-sets", orientation="head"), [scene])
    assert "\n" not in str(raised.value)


def test_nobody_one_and_two_people():
    nobody = Frame(ids=np.zeros(0, np.int64), position=np.zeros((0, 2)), yaw=np.zeros(0))
    one = frame([[0, 0]], [0.0], ids=[7])
    two = frame([[0, 0], [1, 0]], [0.0, np.pi])
    assert DominantSets().predict([nobody, one, two]) == [(), ((7,),), ((1, 2),)]


def test_the_same_answer_twice():
    rng = np.random.default_rng(5)
    scene = frame(rng.uniform(0, 5, (25, 2)), rng.uniform(-np.pi, np.pi, 25))
    assert DominantSets().predict([scene]) == DominantSets().predict([scene])


@pytest.mark.parametrize(
    ("option", "value", "expected"),
    [
        ("sigma", -1, "a float in m from 0.01 to 100, got a int (-1)"),
        ("field_of_view", 7.0, "a float in rad from 0 to 6.2832, got a float (7.0)"),
        ("orientation", "eyes", "a str, one of body, head, got a str ('eyes')"),
    ],
)
def test_options_out_of_range_are_one_line(option, value, expected):
    with pytest.raises(DetectorError) as raised:
        make_detector("dominant-sets", **{option: value})
    assert str(raised.value) == f"detector 'dominant-sets': option {option} expects {expected}"


def test_the_estimator_refuses_bad_parameters_itself():
    with pytest.raises(ValueError, match=r"^sigma must be a number in \(0, 100\], got 0$"):
        DominantSets(sigma=0).fit([])
    with pytest.raises(ValueError, match=r"^global_context must be True or False, got 'yes'$"):
        DominantSets(global_context="yes").fit([])


def test_declared_defaults_are_the_estimators():
    declared = {o.name: o.default for o in detector_info("dominant-sets").options}
    signature = inspect.signature(DominantSets).parameters
    assert declared == {name: signature[name].default for name in declared}


def test_dense_scenes_keep_their_groups_turned_moved_and_relabelled():
    assert_same_groups_moved_and_relabelled(DominantSets(), seed=33)


@pytest.mark.parametrize("name", REAL_DATASETS)
def test_beats_the_majority_baseline_on_real_data(shared_datasets, name):
    assert_beats_majority("dominant-sets", annotated_frames(shared_datasets, name))
