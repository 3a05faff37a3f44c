"""Hough voting (reform.hough): HVFF and multi-scale HVFF.

The hand-computed scenes run without vote noise (``position_sd = orientation_sd = 0``): every
vote of a person then lands on one point, ``stride`` in front of them, and a person's share at a
candidate centre ``d`` metres from that point is exactly ``1 - (d / radius)²`` (0 beyond).
"""

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
from reform.hough import Hvff, MultiScaleHvff, scale_strides, vote_noise

EXACT = {"position_sd": 0.0, "orientation_sd": 0.0}


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


def ring(k: int, radius: float, centre=(0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """``k`` people on a circle of ``radius`` around ``centre``, facing it."""
    angle = np.arange(k) * 2 * np.pi / k
    xy = np.asarray(centre) + radius * np.c_[np.cos(angle), np.sin(angle)]
    return xy, (angle + np.pi + np.pi) % (2 * np.pi) - np.pi


def test_vote_noise_is_seeded_and_its_first_vote_exact():
    offset, turn = vote_noise(
        np.random.default_rng(4), samples=50, position_sd=0.1, orientation_sd=0.2
    )
    again = vote_noise(np.random.default_rng(4), samples=50, position_sd=0.1, orientation_sd=0.2)
    np.testing.assert_array_equal(offset, again[0])
    np.testing.assert_array_equal(turn, again[1])
    assert offset.shape == (50, 2) and turn.shape == (50,)
    assert not offset[0].any() and turn[0] == 0.0


def test_a_facing_pair_votes_for_its_midpoint():
    # 1 and 2 face each other 1.4 m apart: both vote for (0.7, 0); 3, 5 m away, votes alone.
    scene = frame([[0, 0], [1.4, 0], [5, 0]], [0.0, np.pi, np.pi / 2])
    assert Hvff(stride=0.7, **EXACT).predict([scene]) == [((1, 2), (3,))]


def test_back_to_back_is_alone():
    scene = frame([[0, 0], [0.4, 0]], [np.pi, 0.0])
    assert Hvff(stride=0.7, **EXACT).predict([scene]) == [((1,), (2,))]


def test_a_person_backs_a_centre_holding_enough_of_their_votes():
    # 1 faces +x from the origin: votes at (0.7, 0). 2 faces -x from (1.4 + d, 0): votes at
    # (0.7 + d, 0). With radius 0.35 and min_share 0.2, 2's share at 1's vote is
    # 1 - (d / 0.35)²: 0.265 for d = 0.3 (a pair) and 0.111 for d = 0.33 (alone).
    for d, expected in ((0.3, ((1, 2),)), (0.33, ((1,), (2,)))):
        scene = frame([[0, 0], [1.4 + d, 0]], [0.0, np.pi])
        detector = Hvff(stride=0.7, radius=0.35, min_share=0.2, **EXACT)
        assert detector.predict([scene]) == [expected], d


def test_the_best_centre_wins_first():
    # Three on a circle of 0.7 m facing its centre, and a fourth 0.7 m from the centre's other
    # side looking at it sideways (votes 0.99 m off): the three's centre holds three full
    # shares (score 3 * e^ln3 = 9); the fourth backs nothing, and is alone.
    xy, yaw = ring(3, 0.7)
    scene = frame(np.vstack([xy, [[0, -0.7]]]), np.r_[yaw, 0.0])
    assert Hvff(stride=0.7, **EXACT).predict([scene]) == [((1, 2, 3), (4,))]


def test_scale_strides_are_the_radii_of_regular_polygons():
    # Hand-computed: spacing / (2 sin(π/k)) for k = 2, 3, 4, 6: s/2, s/√3, s/√2, s.
    np.testing.assert_allclose(
        scale_strides(1.2, 6)[[0, 1, 2, 4]], [0.6, 1.2 / np.sqrt(3), 1.2 / np.sqrt(2), 1.2]
    )


@pytest.mark.parametrize("k", [2, 3, 4, 5])
def test_multiscale_finds_a_ring_at_its_own_scale(k):
    # k people on the circle of scale k (radius spacing / (2 sin(π/k))) facing its centre: at
    # scale k all k votes land on the centre (k full shares), a group of exactly k.
    xy, yaw = ring(k, scale_strides(1.0, 6)[k - 2], centre=(3.0, -2.0))
    scene = frame(np.vstack([xy, [[20, 20]]]), np.r_[yaw, 0.0])
    expected = [(tuple(range(1, k + 1)), (k + 1,))]
    assert MultiScaleHvff(spacing=1.0, **EXACT).predict([scene]) == expected


def test_multiscale_wants_exactly_k_backers():
    # Two facing each other 0.5 m apart: at scale 2 (stride 0.5) their votes cross and land
    # 0.5 m apart, each share 1 - (0.5 / 0.5)² = 0 at the other's vote: no pair at scale 2.
    # At scale 3 (stride 0.577) they land 0.655 m apart: nothing either; larger scales are
    # further still. Single-scale HVFF with stride 0.25 pairs them.
    scene = frame([[0, 0], [0.5, 0]], [0.0, np.pi])
    assert MultiScaleHvff(spacing=1.0, radius=0.5, **EXACT).predict([scene]) == [((1,), (2,))]
    assert Hvff(stride=0.25, radius=0.5, **EXACT).predict([scene]) == [((1, 2),)]


def test_a_missing_head_falls_back_to_the_body():
    scene = frame([[0, 0], [1.4, 0]], [0.0, np.pi], head_yaw=[np.nan, np.pi / 2])
    assert Hvff(stride=0.7, **EXACT).predict([scene]) == [((1, 2),)]
    assert Hvff(stride=0.7, orientation="head", **EXACT).predict([scene]) == [((1,), (2,))]


@pytest.mark.parametrize("detector", [Hvff(), MultiScaleHvff()], ids=["hvff", "multiscale"])
def test_nobody_one_and_two_people(detector):
    nobody = Frame(ids=np.zeros(0, np.int64), position=np.zeros((0, 2)), yaw=np.zeros(0))
    one = frame([[0, 0]], [0.0], ids=[7])
    two = frame([[0, 0], [1.0, 0]], [0.0, np.pi])
    assert detector.predict([nobody, one, two]) == [(), ((7,),), ((1, 2),)]


@pytest.mark.parametrize("cls", [Hvff, MultiScaleHvff], ids=["hvff", "multiscale"])
def test_one_seed_one_answer(cls):
    rng = np.random.default_rng(8)
    frames = [frame(rng.uniform(0, 6, (30, 2)), rng.uniform(-np.pi, np.pi, 30)) for _ in range(3)]
    first = cls(random_state=11).predict(frames)
    assert first == cls(random_state=11).predict(frames)


@pytest.mark.parametrize(
    ("name", "option", "value", "expected"),
    [
        ("hvff", "radius", -1, "a float in m from 0.01 to 10, got a int (-1)"),
        ("hvff", "min_share", 1.5, "a float from 0.01 to 1, got a float (1.5)"),
        ("hvff-multiscale", "max_size", 1, "an int from 2 to 20, got a int (1)"),
        ("hvff-multiscale", "spacing", "wide", "a float in m from 0.01 to 100, got a str ('wide')"),
    ],
)
def test_options_out_of_range_are_one_line(name, option, value, expected):
    with pytest.raises(DetectorError) as raised:
        make_detector(name, **{option: value})
    assert str(raised.value) == f"detector {name!r}: option {option} expects {expected}"


def test_the_estimators_refuse_bad_parameters_themselves():
    with pytest.raises(ValueError, match=r"^stride must be a number in \[0, 100\], got -0.5$"):
        Hvff(stride=-0.5).fit([])
    with pytest.raises(ValueError, match=r"^max_size must be an integer in \[2, 20\], got 30$"):
        MultiScaleHvff(max_size=30).fit([])


@pytest.mark.parametrize(("name", "cls"), [("hvff", Hvff), ("hvff-multiscale", MultiScaleHvff)])
def test_declared_defaults_are_the_estimators(name, cls):
    declared = {o.name: o.default for o in detector_info(name).options}
    signature = inspect.signature(cls).parameters
    assert declared == {option: signature[option].default for option in declared}


@pytest.mark.parametrize("cls", [Hvff, MultiScaleHvff], ids=["hvff", "multiscale"])
def test_dense_scenes_keep_their_groups_turned_moved_and_relabelled(cls):
    assert_same_groups_moved_and_relabelled(cls(), seed=32)


@pytest.mark.parametrize("name", REAL_DATASETS)
@pytest.mark.parametrize("detector", ["hvff", "hvff-multiscale"])
def test_beats_the_majority_baseline_on_real_data(shared_datasets, detector, name):
    assert_beats_majority(detector, annotated_frames(shared_datasets, name))
