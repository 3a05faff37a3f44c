"""The proximity baseline (reform.proximity): connected components of people within a distance."""

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
from reform.proximity import Proximity, proximity_labels


def frame(xy, yaw=None, ids=None) -> Frame:
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    n = len(xy)
    return Frame(
        ids=np.arange(1, n + 1) if ids is None else ids,
        position=xy,
        yaw=np.zeros(n) if yaw is None else yaw,
    )


def as_sets(partition) -> set[frozenset[int]]:
    return {frozenset(g) for g in partition}


def test_a_chain_of_close_people_is_one_group():
    # Hand-computed: 1-2 and 2-3 are 0.9 m apart (linked at 1.0 m), 1-3 1.8 m (not linked, but
    # joined through 2); 4 is 3.2 m from 3. Single linkage: {1, 2, 3}, {4}.
    scene = frame([[0, 0], [0.9, 0], [1.8, 0], [5.0, 0]])
    assert Proximity(distance=1.0).predict([scene]) == [((1, 2, 3), (4,))]


def test_the_distance_links_at_most_its_value():
    # Exactly 1.0 m apart (both coordinates exact in binary): linked at 1.0, not at 0.999.
    scene = frame([[0, 0], [1.0, 0]])
    assert Proximity(distance=1.0).predict([scene]) == [((1, 2),)]
    assert Proximity(distance=0.999).predict([scene]) == [((1,), (2,))]


def test_orientation_is_ignored():
    # Back to back 0.5 m apart: together for proximity, whatever they face.
    scene = frame([[0, 0], [0.5, 0]], yaw=[np.pi, 0.0])
    assert Proximity(distance=1.0).predict([scene]) == [((1, 2),)]


def test_labels_follow_the_first_row_of_each_component():
    labels = proximity_labels(np.array([[9.0, 0], [0, 0], [9.5, 0], [0.5, 0]]), distance=1.0)
    assert labels.tolist() == [0, 1, 0, 1]


def test_a_party_is_linked_pair_by_pair_as_a_crowds_tree_links_it():
    # Up to 64 people the pairs are compared one by one, beyond it a k-d tree finds them: on the
    # same frames both give the same labels, people exactly at the distance included (quarter
    # metres on a grid and distances of quarter metres are exact in binary).
    from reform.proximity import _dense_labels, _tree_labels

    rng = np.random.default_rng(11)
    for k in range(400):
        n = int(rng.integers(1, 65))
        on_grid = k % 2 == 0
        xy = rng.integers(0, 16, (n, 2)) * 0.25 if on_grid else rng.uniform(0, 8, (n, 2))
        distance = float(rng.choice([0.25, 0.5, 0.8, 1.0, 1.5]))
        dense = _dense_labels(xy, distance)
        assert dense.dtype == np.int64
        assert dense.tolist() == _tree_labels(xy, distance).tolist(), (xy, distance)
    crowd = rng.uniform(0, 40, (300, 2))  # beyond 64 people the tree answers: the same groups
    assert proximity_labels(crowd, distance=1.0).tolist() == _dense_labels(crowd, 1.0).tolist()


def test_nobody_one_and_two_people():
    nobody = Frame(ids=np.zeros(0, np.int64), position=np.zeros((0, 2)), yaw=np.zeros(0))
    assert Proximity().predict([nobody, frame([[0, 0]], ids=[7])]) == [(), ((7,),)]
    assert Proximity().predict([frame([[0, 0], [3, 0]])]) == [((1,), (2,))]


def test_the_same_answer_every_time_and_for_any_listing():
    rng = np.random.default_rng(3)
    xy = rng.uniform(0, 6, (30, 2))
    first = as_sets(Proximity().predict([frame(xy)])[0])
    order = rng.permutation(30)
    again = as_sets(Proximity().predict([frame(xy[order], ids=np.arange(1, 31)[order])])[0])
    assert first == again == as_sets(Proximity().predict([frame(xy)])[0])


@pytest.mark.parametrize(
    ("value", "got"), [(-1, "a int (-1)"), (0.0, "a float (0.0)"), (1e3, "a float (1000.0)")]
)
def test_distance_out_of_range_is_one_line(value, got):
    with pytest.raises(DetectorError) as raised:
        make_detector("proximity", distance=value)
    message = str(raised.value)
    assert message == (
        f"detector 'proximity': option distance expects a float in m from 0.01 to 100, got {got}"
    )
    assert "\n" not in message


def test_the_estimator_refuses_a_bad_distance_itself():
    with pytest.raises(ValueError, match=r"^distance must be a number in \(0, 100\], got -1$"):
        Proximity(distance=-1).fit([])


def test_declared_defaults_are_the_estimators():
    declared = {o.name: o.default for o in detector_info("proximity").options}
    signature = inspect.signature(Proximity).parameters
    assert declared == {name: signature[name].default for name in declared}


def test_dense_scenes_keep_their_groups_turned_moved_and_relabelled():
    assert_same_groups_moved_and_relabelled(Proximity(), seed=34)


# The default distance, 0.8 m, was chosen on SALSA's training split alone. Babble's people stand
# farther apart (a person's nearest neighbour is a median 0.97 m away; 7 % of them are within
# 0.8 m), so almost nobody links: F1 9.5 at T = 2/3 against the majority baseline's 9.6. Choosing
# the distance on Babble to pass would score Babble with a setting chosen on it, so the case
# stays, marked: strict, it fails loudly when a default that transfers makes it pass.
BABBLE_UNLINKED = pytest.mark.xfail(
    strict=True, reason="0.8 m, chosen on SALSA's training split, links almost no one on Babble"
)


@pytest.mark.parametrize(
    "name",
    [pytest.param(n, marks=BABBLE_UNLINKED) if n == "babble" else n for n in REAL_DATASETS],
)
def test_beats_the_majority_baseline_on_real_data(shared_datasets, name):
    assert_beats_majority("proximity", annotated_frames(shared_datasets, name))
