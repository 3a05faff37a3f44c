"""Reform's options beyond the paper: scale-free features, correlation clustering over the pair
probabilities, calibrated probabilities. Defaults unchanged, each option checked for what it
promises, bad values refused in one line, every combination keeps the detector contract."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from sklearn.linear_model import Perceptron
from sklearn.metrics import log_loss
from sklearn.model_selection import GroupKFold
from test_detector import as_sets, held_out_frames, training_frames
from toy_scenes import toy_frames

from reform import (
    Frame,
    Reform,
    complete_partition,
    frame_pair_features,
    partition_from_labels,
    wrap_angle,
)
from reform.classifiers import logistic_regression, weighted_knn
from reform.detector import CALIBRATION_FOLDS
from reform.detector_checks import check_detector
from reform.features import DEFAULT_FEATURES
from reform.metrics import pair_labels
from reform.reconstruction import correlation_clustering, pair_weights


@functools.cache
def fitted(**options) -> Reform:
    return Reform(**options).fit(training_frames())


def noisy_frames(seed: int, count: int) -> tuple[Frame, ...]:
    """Toy frames with their poses blurred (0.25 m, 0.9 rad): pairs a classifier can mistake."""
    rng = np.random.default_rng(seed + 1000)
    return tuple(
        f.replace(
            position=f.position + rng.normal(0.0, 0.25, f.position.shape),
            yaw=wrap_angle(f.yaw + rng.normal(0.0, 0.9, f.yaw.shape)),
        )
        for f in toy_frames(seed, count)
    )


def scaled(frame: Frame, factor: float) -> Frame:
    head = None if frame.head_position is None else frame.head_position * factor
    return frame.replace(position=frame.position * factor, head_position=head)


def test_the_defaults_are_the_papers_method():
    params = Reform().get_params()
    assert params["features"] == DEFAULT_FEATURES
    assert params["reconstruction"] == "union"
    assert params["calibration"] is None
    assert repr(Reform()) == "Reform()"
    # A default model saves the state it saved before the options existed.
    assert "calibration" not in fitted().__getstate__()
    assert fitted(calibration="sigmoid").__getstate__()["calibration"] == "sigmoid"
    # "paper" names the same features, and the same model.
    paper = fitted(features="paper")
    assert paper.features_ == DEFAULT_FEATURES
    assert paper.predict(held_out_frames()) == fitted().predict(held_out_frames())


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("features", "scale-free", r"features must be a feature set \('paper', 'relative'\) or"),
        ("reconstruction", "graph-cut", r"reconstruction must be one of \('union', "),
        ("reconstruction", None, r"reconstruction must be one of .*, got None"),
        ("calibration", "platt", r"calibration must be None or one of \('sigmoid', 'isotonic'\)"),
        ("calibration", True, r"calibration must be None or one of .*, got True"),
    ],
)
def test_bad_option_values_are_refused_in_one_line(option, value, message):
    with pytest.raises(ValueError, match=message) as caught:
        Reform(**{option: value}).fit(training_frames()[:5])
    assert "\n" not in str(caught.value)


def test_correlation_needs_pair_probabilities():
    with pytest.raises(
        ValueError, match="reconstruction='correlation' needs a classifier with predict_proba"
    ):
        Reform(Perceptron(), reconstruction="correlation").fit(training_frames()[:5])


# ------------------------------------------------------------------------------------------------
# Scale-free features


@pytest.mark.parametrize("factor", [0.01, 0.37, 2.5, 100.0])
def test_relative_features_detect_the_same_groups_at_any_scale(factor):
    model = fitted(features="relative")
    frames = held_out_frames()
    assert model.predict([scaled(f, factor) for f in frames]) == model.predict(frames)


def test_the_papers_features_do_depend_on_scale():
    # The same scenes three times larger: the paper's Distance no longer sees the circles.
    frames = held_out_frames()
    model = fitted()
    assert model.predict([scaled(f, 3.0) for f in frames]) != model.predict(frames)


def test_relative_features_find_the_toy_groups():
    predicted = fitted(features="relative").predict(held_out_frames())
    hits = sum(
        as_sets(p) == as_sets(complete_partition(f.groups, f.ids.tolist()))
        for p, f in zip(predicted, held_out_frames(), strict=True)
    )
    assert hits >= 0.9 * len(held_out_frames())


# ------------------------------------------------------------------------------------------------
# Correlation clustering


def reference_correlation(model: Reform, frame: Frame):
    """Per frame: features in id order, scikit-learn's predict_proba, correlation clustering."""
    order = np.argsort(frame.ids, kind="stable")
    ordered = frame.replace(
        ids=frame.ids[order],
        position=frame.position[order],
        yaw=frame.yaw[order],
        kinds=tuple(frame.kinds[k] for k in order),
    )
    n = ordered.n_people
    p = model.classifier_.predict_proba(frame_pair_features(ordered, features=model.features_))
    i, j = np.triu_indices(n, 1)
    w = np.zeros((n, n))
    w[i, j] = w[j, i] = pair_weights(p[:, 1], threshold=model.threshold)
    return as_sets(partition_from_labels(correlation_clustering(w), ordered.ids.tolist()))


@pytest.mark.parametrize("threshold", [None, 0.3])
def test_correlation_is_clustering_of_the_pair_probabilities(threshold):
    model = Reform(logistic_regression(), reconstruction="correlation", threshold=threshold)
    model.fit(training_frames())
    frames = held_out_frames()
    for frame, partition in zip(frames, model.predict(frames), strict=True):
        assert as_sets(partition) == reference_correlation(model, frame)
    # The pair labels before reconstruction are still the classifier's decision.
    greedy = Reform(logistic_regression(), threshold=threshold).fit(training_frames())
    for a, b in zip(model.predict_pairs(frames), greedy.predict_pairs(frames), strict=True):
        np.testing.assert_array_equal(a, b)


def test_predict_pair_proba_follows_the_frames_rows():
    model = fitted(reconstruction="correlation")
    frame = held_out_frames()[0]
    flipped = frame.replace(
        ids=frame.ids[::-1],
        position=frame.position[::-1],
        yaw=frame.yaw[::-1],
        kinds=frame.kinds[::-1],
    )
    p, q = model.predict_pair_proba([frame, flipped])
    n = frame.n_people
    i, j = np.triu_indices(n, 1)
    square = np.zeros((n, n))
    square[i, j] = square[j, i] = p
    np.testing.assert_allclose(q, square[::-1, ::-1][i, j])
    expected = model.classifier_.predict_proba(frame_pair_features(frame))[:, 1]
    np.testing.assert_allclose(p, expected)
    with pytest.raises(
        ValueError, match="predict_pair_proba needs a classifier with predict_proba"
    ):
        Reform(Perceptron(random_state=0)).fit(training_frames()[:20]).predict_pair_proba([frame])


# ------------------------------------------------------------------------------------------------
# Calibration


def test_calibration_folds_are_stretches_of_time():
    model = fitted(classifier=weighted_knn(), calibration="sigmoid")
    calibrated = model.classifier_
    assert type(calibrated).__name__ == "CalibratedClassifierCV"
    assert isinstance(calibrated.cv, GroupKFold) and calibrated.cv.n_splits == CALIBRATION_FOLDS
    assert len(calibrated.calibrated_classifiers_) == CALIBRATION_FOLDS
    # Frames of one stretch of time cannot be calibrated out of fold.
    with pytest.raises(ValueError, match="at least 2 stretches of time .*, got 1"):
        Reform(calibration="sigmoid").fit(training_frames()[:1])


@pytest.mark.parametrize("method", ["sigmoid", "isotonic"])
def test_calibration_improves_the_probabilities_of_an_overconfident_classifier(method):
    # Distance-weighted KNN says 0 or 1 for most pairs; the calibrated probabilities lose less
    # on held-out frames (log loss, the quantity a probability is judged by).
    train, test = noisy_frames(0, 120), noisy_frames(1, 40)
    y = np.concatenate([pair_labels(f) for f in test])
    losses = {}
    for calibration in (None, method):
        model = Reform(weighted_knn(), calibration=calibration).fit(train)
        p = np.concatenate(model.predict_pair_proba(test))
        losses[calibration] = log_loss(y, np.clip(p, 1e-6, 1 - 1e-6))
    assert losses[method] < losses[None]


# ------------------------------------------------------------------------------------------------
# The contract, for every option


@pytest.mark.parametrize(
    "options",
    [
        {"features": "relative"},
        {"reconstruction": "correlation"},
        {"calibration": "isotonic"},
        {"features": "relative", "reconstruction": "correlation", "calibration": "sigmoid"},
    ],
    ids=lambda options: ",".join(f"{k}={v}" for k, v in options.items()),
)
def test_every_option_keeps_the_detector_contract(options):
    # Rigid motion, relabelling, a partition per frame, the same answer twice, tiny frames.
    check_detector(fitted(**options), name=f"reform {options}")
