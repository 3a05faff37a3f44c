"""Two-stage bootstrap of the protocol's scores: reform.bootstrap."""

from __future__ import annotations

import numpy as np
import pytest

from reform import Frame, evaluate
from reform.bootstrap import bootstrap_weights, frame_intervals, score_intervals


def test_one_sequence_is_the_frame_bootstrap() -> None:
    weights = bootstrap_weights(["a"] * 7, rng=np.random.default_rng(0), resamples=50)
    assert weights.shape == (50, 7)
    np.testing.assert_array_equal(weights.sum(axis=1), 7)
    assert np.all(weights == np.round(weights)) and np.all(weights >= 0)


def test_sequences_are_drawn_whole() -> None:
    sequence = ["a"] * 3 + ["b"] * 5 + ["c"] * 2
    weights = bootstrap_weights(sequence, rng=np.random.default_rng(1), resamples=400)
    sizes = {"a": 3, "b": 5, "c": 2}
    labels = np.array(sequence)
    picks = np.stack([weights[:, labels == s].sum(axis=1) / n for s, n in sizes.items()], axis=1)
    np.testing.assert_array_equal(picks, np.round(picks))  # whole sequences
    np.testing.assert_array_equal(picks.sum(axis=1), 3)  # three draws of sequences
    assert np.any(picks == 0) and np.any(picks >= 2)  # with replacement


def test_same_rng_same_weights() -> None:
    a = bootstrap_weights(list("aabbb"), rng=np.random.default_rng(9), resamples=20)
    b = bootstrap_weights(list("aabbb"), rng=np.random.default_rng(9), resamples=20)
    np.testing.assert_array_equal(a, b)


def _frames_and_predictions():
    frames, predictions = [], []
    for k in range(12):
        frame = Frame(
            ids=[1, 2, 3, 4],
            position=[[0, 0], [1, 0], [5, 0], [6, 0]],
            yaw=[0, np.pi, 0, np.pi],
            groups=((1, 2), (3, 4)),
            time=k,
            sequence=f"episode-{k % 3}",
        )
        frames.append(frame)
        # every third frame misses the second group
        predictions.append(((1, 2), (3, 4)) if k % 3 else ((1, 2), (3,), (4,)))
    return frames, predictions


def test_point_estimates_are_the_evaluation_scores() -> None:
    frames, predictions = _frames_and_predictions()
    evaluation = evaluate(frames, predictions)
    weights = bootstrap_weights(evaluation.sequence, rng=np.random.default_rng(0), resamples=300)
    for threshold in ("2/3", "1"):
        scores = evaluation.at(threshold)
        intervals = score_intervals(evaluation, threshold, weights=weights)
        assert intervals.f1.value == pytest.approx(scores.f1)
        assert intervals.precision.value == pytest.approx(scores.precision)
        assert intervals.recall.value == pytest.approx(scores.recall)
        assert intervals.recall.low <= intervals.recall.value <= intervals.recall.high
        assert intervals.frames == 12 and intervals.sequences == 3


def test_episode_level_variation_widens_the_interval() -> None:
    # Recall 1 in two episodes, 0.5 in the third: frames within an episode agree, so the spread
    # comes from which episodes are drawn. Hand-computed: three draws of the third episode
    # (probability 1/27 > 2.5 %) give R = 0.5; none of it (8/27 > 2.5 %) gives R = 1.
    frames, predictions = _frames_and_predictions()
    predictions = [
        ((1, 2), (3, 4)) if f.sequence != "episode-0" else ((1, 2), (3,), (4,)) for f in frames
    ]
    evaluation = evaluate(frames, predictions)
    weights = bootstrap_weights(evaluation.sequence, rng=np.random.default_rng(2), resamples=2000)
    recall = score_intervals(evaluation, "2/3", weights=weights).recall
    assert recall.value == pytest.approx(5 / 6)
    assert recall.low == pytest.approx(0.5) and recall.high == pytest.approx(1.0)


def test_constant_scores_give_a_point_interval() -> None:
    weights = bootstrap_weights(list("aabbcc"), rng=np.random.default_rng(0), resamples=100)
    result = frame_intervals(np.full(6, 0.8), np.full(6, 0.5), weights=weights, sequences=3)
    expected = 2 * 0.8 * 0.5 / 1.3
    assert (result.f1.low, result.f1.value, result.f1.high) == pytest.approx((expected,) * 3)
    assert result.to_json()["f1"]["value"] == pytest.approx(expected)


def test_bad_input() -> None:
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="resamples must be an int >= 1, got 0"):
        bootstrap_weights(["a"], rng=rng, resamples=0)
    with pytest.raises(ValueError, match="rng must be a numpy.random.Generator"):
        bootstrap_weights(["a"], rng=0)
    with pytest.raises(ValueError, match="sequence must be a non-empty 1-D"):
        bootstrap_weights([], rng=rng)
    weights = bootstrap_weights(list("ab"), rng=rng, resamples=5)
    with pytest.raises(ValueError, match=r"weights must have shape \(resamples, 3\)"):
        frame_intervals(np.ones(3), np.ones(3), weights=weights, sequences=2)
    with pytest.raises(ValueError, match=r"level must lie in \(0, 1\), got 1.0"):
        frame_intervals(np.ones(2), np.ones(2), weights=weights, sequences=2, level=1.0)
