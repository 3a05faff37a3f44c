"""The Reform estimator: contract, predictions, exchangeable classifiers, invariances, bad input."""

from __future__ import annotations

import functools
import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sklearn.linear_model import Perceptron
from sklearn.tree import DecisionTreeClassifier
from toy_scenes import toy_frame, toy_frames
from traced import raised_peak

import reform.detector
import reform.gcff
from reform import (
    Dataset,
    Frame,
    Reform,
    frame_pair_features,
    greedy_reconstruction,
    pair_labels,
    partition_from_labels,
    relation_matrix,
    wrap_angle,
)
from reform.classifiers import (
    CLASSIFIERS,
    PARAM_GRIDS,
    bagged_trees,
    logistic_regression,
    make_classifier,
    weighted_knn,
)
from reform.detector import frame_bytes, training_pairs
from reform.features import pair_indices
from reform.gcff import Gcff, gcff_labels


@functools.cache
def training_frames() -> tuple[Frame, ...]:
    return tuple(toy_frames(0, 120))


@functools.cache
def held_out_frames() -> tuple[Frame, ...]:
    return tuple(toy_frames(1, 40, sizes=(2, 5, 3), loners=3))


@functools.cache
def fitted(name: str = "bagged-trees", threshold: float | None = None) -> Reform:
    return Reform(make_classifier(name), threshold=threshold).fit(training_frames())


def as_sets(partition) -> set[frozenset[int]]:
    return {frozenset(group) for group in partition}


def naive_predict(model: Reform, frame: Frame):
    """Per frame: features, one scikit-learn predict, the reference reconstruction."""
    order = np.argsort(frame.ids)
    ordered = Frame(ids=frame.ids[order], position=frame.position[order], yaw=frame.yaw[order])
    n = ordered.n_people
    if n < 2:
        return tuple((int(k),) for k in ordered.ids)
    labels = model.classifier_.predict(frame_pair_features(ordered, features=model.features_))
    rows = greedy_reconstruction(relation_matrix(labels, n), variant=model.reconstruction)
    return tuple(tuple(int(ordered.ids[r]) for r in group) for group in rows)


@pytest.mark.parametrize("name", list(CLASSIFIERS))
def test_learns_the_toy_scenes(name):
    model = fitted(name)
    predictions = model.predict(held_out_frames())
    frames = held_out_frames()
    exact = sum(
        as_sets(p) == as_sets(f.partition()) for p, f in zip(predictions, frames, strict=True)
    )
    assert exact >= 0.9 * len(held_out_frames())
    for prediction, frame in zip(predictions, held_out_frames(), strict=True):
        assert sorted(k for g in prediction for k in g) == sorted(frame.ids.tolist())


@pytest.mark.parametrize("name", list(CLASSIFIERS))
@pytest.mark.parametrize("threshold", [None, 0.3])
def test_fast_path_equals_scikit_learn(name, threshold):
    model = fitted(name, threshold)
    slow = clone(model).set_params(fast=False).fit(training_frames())
    frames = held_out_frames() + tuple(toy_frames(5, 30, sizes=(4, 4, 2, 3), loners=6))
    assert model.predict(frames) == slow.predict(frames)
    if threshold is None:
        assert model.predict(frames) == [naive_predict(model, f) for f in frames]


def test_predicts_one_frame_as_in_a_batch():
    model = fitted()
    frames = held_out_frames()
    batch = model.predict(frames)
    assert [model.predict([f])[0] for f in frames] == batch


def test_is_a_textbook_estimator():
    model = Reform(weighted_knn(n_neighbors=3), threshold=0.4, reconstruction="intersection")
    params = model.get_params(deep=False)
    assert params["threshold"] == 0.4 and params["reconstruction"] == "intersection"
    twin = clone(model)
    assert twin.get_params()["classifier__knn__n_neighbors"] == 3
    assert twin.classifier is not model.classifier
    assert not hasattr(twin, "classifier_")
    twin.set_params(classifier__knn__n_neighbors=5, fast=False)
    assert twin.classifier.get_params()["knn__n_neighbors"] == 5
    assert model.fit(training_frames()) is model
    assert model.classifier.get_params()["knn__n_neighbors"] == 3  # the parameter is not fitted
    assert model.features_ == ("distance", "effort_angle")
    assert model.training_summary_["frames"] == 120
    assert model.training_summary_["pairs"] == 120 * 55
    assert Reform().get_params()["classifier"] is None


def test_default_classifier_is_bagged_trees():
    model = Reform().fit(training_frames()[:30])
    assert type(model.classifier_).__name__ == "BaggingClassifier"
    assert model.classifier_.n_estimators == 30


def test_ready_made_classifiers_and_grids():
    assert (
        set(CLASSIFIERS)
        == set(PARAM_GRIDS)
        == {
            "weighted-knn",
            "bagged-trees",
            "logistic-regression",
        }
    )
    for name, grid in PARAM_GRIDS.items():
        classifier = make_classifier(name)
        for parameter in grid:
            assert parameter in classifier.get_params()
    assert weighted_knn().get_params()["knn__weights"] == "distance"
    assert bagged_trees(min_samples_leaf=7).get_params()["estimator__min_samples_leaf"] == 7
    assert logistic_regression(C=0.5).get_params()["logreg__C"] == 0.5
    with pytest.raises(ValueError, match="classifier must be one of .* got 'svm'"):
        make_classifier("svm")


def test_any_scikit_learn_classifier_is_exchangeable():
    model = Reform(DecisionTreeClassifier(max_depth=4, random_state=0)).fit(training_frames())
    assert model.predict(held_out_frames()) == clone(model).set_params(fast=False).fit(
        training_frames()
    ).predict(held_out_frames())


def test_frames_of_zero_one_and_two_people():
    model = fitted()
    rng = np.random.default_rng(0)
    empty = Frame(ids=np.zeros(0, int), position=np.zeros((0, 2)), yaw=np.zeros(0))
    alone = Frame(ids=[4], position=[[1.0, 2.0]], yaw=[0.3])
    facing = Frame(ids=[9, 2], position=[[0.0, 0.0], [1.0, 0.0]], yaw=[0.0, math.pi])
    apart = Frame(ids=[9, 2], position=[[0.0, 0.0], [9.0, 0.0]], yaw=[math.pi, 0.0])
    mixed = [toy_frame(rng), empty, alone, facing, apart, toy_frame(rng, sizes=(2,), loners=0)]
    predictions = model.predict(mixed)
    assert predictions[1] == ()
    assert predictions[2] == ((4,),)
    assert predictions[3] == ((2, 9),)
    assert predictions[4] == ((2,), (9,))
    assert predictions[5] == ((1, 2),)
    assert predictions[0] == model.predict([mixed[0]])[0]


def test_robots_are_carried_through():
    model = Reform(features=("distance", "effort_angle", "involves_robot"))
    frames = [f.replace(kinds=("robot",) + f.kinds[1:]) for f in training_frames()]
    model.fit(frames)
    frame = frames[0]
    prediction = model.predict([frame])[0]
    assert sorted(k for g in prediction for k in g) == sorted(frame.ids.tolist())
    assert model.features_[-1] == "involves_robot"


def test_row_order_and_id_names_do_not_matter():
    model = fitted()
    frame = held_out_frames()[0]
    order = np.random.default_rng(2).permutation(frame.n_people)
    shuffled = frame.replace(
        ids=frame.ids[order] * 10 + 100,  # same order of ids, other names
        position=frame.position[order],
        yaw=frame.yaw[order],
        groups=tuple(tuple(k * 10 + 100 for k in g) for g in frame.groups),
    )
    expected = {frozenset(k * 10 + 100 for k in g) for g in model.predict([frame])[0]}
    assert as_sets(model.predict([shuffled])[0]) == expected


def test_predict_pairs_follows_the_frames_rows():
    model = fitted()
    frame = held_out_frames()[3]
    order = np.random.default_rng(7).permutation(frame.n_people)
    shuffled = frame.replace(
        ids=frame.ids[order], position=frame.position[order], yaw=frame.yaw[order]
    )
    pairs = model.predict_pairs([shuffled])[0]
    truth = pair_labels(shuffled).astype(bool)
    assert pairs.shape == truth.shape
    assert np.mean(pairs == truth) > 0.95
    matrix = model.predict_relation_matrix(shuffled)
    assert matrix.shape == (frame.n_people, frame.n_people)
    assert np.array_equal(matrix, matrix.T) and matrix.diagonal().all()
    rebuilt = greedy_reconstruction(matrix)
    assert as_sets(partition_from_labels(_labels_of(rebuilt, frame.n_people), shuffled.ids)) == (
        as_sets(model.predict([shuffled])[0])
    )


def _labels_of(partition, n):
    labels = np.zeros(n, dtype=int)
    for group in partition:
        labels[list(group)] = group[0]
    return labels


def test_accepts_a_dataset():
    dataset = Dataset(frames=training_frames()[:20], name="toy")
    model = Reform(logistic_regression()).fit(dataset)
    assert len(model.predict(dataset)) == 20


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    shift=st.tuples(st.floats(-50, 50), st.floats(-50, 50)),
    turn=st.floats(-math.pi, math.pi),
)
def test_predictions_are_invariant_under_moving_and_relabelling_the_scene(seed, shift, turn):
    model = fitted()
    rng = np.random.default_rng(seed)
    frame = toy_frame(rng, sizes=tuple(rng.integers(2, 6, size=3)), loners=int(rng.integers(0, 4)))
    rotation = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    order = rng.permutation(frame.n_people)
    moved = frame.replace(
        ids=frame.ids[order],
        position=(frame.position @ rotation.T + shift)[order],
        yaw=wrap_angle(frame.yaw + turn)[order],
    )
    assert as_sets(model.predict([moved])[0]) == as_sets(model.predict([frame])[0])


def test_predict_before_fit_is_refused():
    with pytest.raises(NotFittedError, match="not fitted yet"):
        Reform().predict(held_out_frames())
    with pytest.raises(NotFittedError, match="not fitted yet"):
        Reform().predict_pairs(held_out_frames())


def test_fit_refuses_frames_without_ground_truth():
    frames = list(training_frames()[:5])
    frames[2] = frames[2].replace(groups=None)
    with pytest.raises(
        ValueError,
        match=r"1 of 5 frames have none \(first: frames\[2\], sequence 'toy', time 2 s\)",
    ):
        Reform().fit(frames)
    with pytest.raises(ValueError, match="fit needs annotated frames, got none"):
        Reform().fit([])


def test_fit_refuses_frames_that_teach_nothing():
    alone = Frame(ids=[1], position=[[0.0, 0.0]], yaw=[0.0], groups=())
    with pytest.raises(ValueError, match="at least 2 people, got 1 frames of 0 or 1"):
        Reform().fit([alone])
    strangers = Frame(ids=[1, 2], position=[[0.0, 0.0], [5.0, 0.0]], yaw=[0.0, 0.0], groups=())
    with pytest.raises(ValueError, match="pairs of both kinds, got 1 pairs, all apart"):
        Reform().fit([strangers])


def test_threshold_needs_predict_proba():
    with pytest.raises(
        ValueError, match="threshold=0.3 needs a classifier with predict_proba, got Perceptron"
    ):
        Reform(Perceptron(), threshold=0.3).fit(training_frames()[:5])
    model = Reform(Perceptron(random_state=0)).fit(training_frames()[:20])  # no threshold: fine
    assert len(model.predict(held_out_frames()[:2])) == 2


@pytest.mark.parametrize("threshold", [0.0, 1.0, 1.5, -0.2, "0.5", True])
def test_threshold_must_be_a_probability(threshold):
    with pytest.raises(ValueError, match="threshold must be None or a probability in \\(0, 1\\)"):
        Reform(threshold=threshold).fit(training_frames()[:5])


def test_bad_parameters_are_named():
    with pytest.raises(ValueError, match="reconstruction must be one of"):
        Reform(reconstruction="best").fit(training_frames()[:5])
    with pytest.raises(ValueError, match="features must be among"):
        Reform(features=("distance", "gaze")).fit(training_frames()[:5])
    with pytest.raises(
        TypeError, match="predict takes reform.Frame objects, got dict at frames\\[0\\]"
    ):
        fitted().predict([{"ids": [1]}])


def test_threshold_moves_the_decision():
    low = fitted("logistic-regression", 0.05)
    high = fitted("logistic-regression", 0.95)
    frames = held_out_frames()
    together_low = sum(p.sum() for p in low.predict_pairs(frames))
    together_high = sum(p.sum() for p in high.predict_pairs(frames))
    assert together_low > together_high


# --------------------------------------------------------------------------------------------
# Frames too large: REFORM and GCFF refuse them, naming them, before allocating

CROWD = 2_000_000  # people in one frame: 1,999,999,000,000 pairs
REFUSAL_PEAK_BYTES = 20 * 2**20  # bytes: what a refused frame may allocate while refused


@functools.cache
def crowd() -> Frame:
    rng = np.random.default_rng(0)
    return Frame(
        ids=np.arange(CROWD),
        position=rng.uniform(0.0, 2_000.0, (CROWD, 2)),
        yaw=rng.uniform(-np.pi, np.pi, CROWD),
        groups=(),
        time=12.5,
        sequence="stadium",
    )


def test_frame_bytes_follow_the_measured_costs():
    # Hand-computed: 64 people make 2,016 pairs, 65 make 2,080; Greedy Reconstruction adds
    # nothing per pair (it keeps only the pairs predicted together).
    assert frame_bytes(64) == 2_016 * 40
    assert frame_bytes(65) == 2_080 * 40
    assert frame_bytes(64, predict=False) == 2_016 * 88
    assert frame_bytes(1) == frame_bytes(0) == 0


@pytest.mark.parametrize(
    ("call", "work"),
    [
        (lambda: fitted().predict([held_out_frames()[0], crowd()]), "classify and reconstruct"),
        (lambda: fitted().predict_pairs([crowd()]), "classify and reconstruct"),
        (lambda: Reform().fit([*training_frames()[:5], crowd()]), "deconstruct"),
        (lambda: training_pairs([crowd()]), "deconstruct"),
    ],
    ids=["predict", "predict_pairs", "fit", "training_pairs"],
)
def test_reform_refuses_a_frame_whose_pairs_cannot_fit(call, work):
    crowd()
    fitted()
    error, peak = raised_peak(call, ValueError)
    assert re.fullmatch(
        r"the frame at time 12.5 s of sequence 'stadium' holds 2,000,000 people: "
        r"1,999,999,000,000 pairs, which would take about [\d,.]+ GiB to " + work + r", more "
        r"than reform.detector.MAX_FRAME_BYTES = 8 GiB",
        str(error),
    ), str(error)
    assert peak < REFUSAL_PEAK_BYTES


def test_the_bound_is_the_module_constant(monkeypatch):
    model = fitted()
    frames = held_out_frames()
    largest = max(f.n_people for f in frames)
    monkeypatch.setattr(reform.detector, "MAX_FRAME_BYTES", frame_bytes(largest))
    assert len(model.predict(frames)) == len(frames)  # at the bound: predicted as before
    monkeypatch.setattr(reform.detector, "MAX_FRAME_BYTES", frame_bytes(largest) - 1)
    with pytest.raises(ValueError, match=f"holds {largest} people: .* more than reform.detector"):
        model.predict(frames)


def test_pair_indices_refuse_more_than_max_pairs():
    with pytest.raises(
        ValueError,
        match=r"a frame of 2,000,000 people has 1,999,999,000,000 pairs, more than "
        r"reform.features.MAX_PAIRS = 1,073,741,824: their indices alone would take 29,802 GiB",
    ):
        pair_indices(CROWD)


def test_gcff_refuses_a_frame_whose_costs_cannot_fit():
    crowd()
    error, peak = raised_peak(lambda: Gcff().predict([held_out_frames()[0], crowd()]), ValueError)
    assert str(error) == (
        "the frame at time 12.5 s of sequence 'stadium' (2,000,000 people): GCFF's costs for "
        "2,000,000 people and 2,000,000 candidate groups would take about 119,209.3 GiB, more "
        "than reform.gcff.MAX_FRAME_BYTES = 8 GiB"
    )  # 2e6 * 2e6 cells of 32 bytes
    assert peak < REFUSAL_PEAK_BYTES


def test_gcff_refuses_a_crowd_too_dense_for_its_visibility_penalty(monkeypatch):
    # 300 people within half a metre: every centre's neighbourhood holds everyone.
    rng = np.random.default_rng(1)
    dense = Frame(
        ids=np.arange(300), position=rng.uniform(0, 0.5, (300, 2)), yaw=rng.uniform(-3, 3, 300)
    )
    monkeypatch.setattr(reform.gcff, "MAX_FRAME_BYTES", 300 * 300 * reform.gcff.CELL_BYTES)
    with pytest.raises(ValueError) as info:
        Gcff().predict([dense])
    assert re.fullmatch(
        r"the frame at time 0 s \(300 people\): GCFF's costs for 300 people and 300 candidate "
        r"groups with [\d,]+ \(group, person, person\) visibility triples would take about "
        r"[\d.]+ GiB, more than reform.gcff.MAX_FRAME_BYTES = 0.00268221 GiB",
        str(info.value),
    ), str(info.value)
    with pytest.raises(ValueError, match=r"GCFF's costs for 300 people and 300 candidate groups"):
        gcff_labels(dense.position, dense.yaw, stride=0.7, mdl=1.0)
