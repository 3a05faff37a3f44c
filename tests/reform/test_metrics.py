"""The evaluation protocol (GCFF's ff_evalgroups.m): every rule, hand-computed, then pinned on
the original GCFF code's partitions of SALSA."""

from __future__ import annotations

import json
import math
from fractions import Fraction

import numpy as np
import pytest
from gcff_reference import read_reference_partitions
from hypothesis import given, settings
from hypothesis import strategies as st
from toy_scenes import line_frame as frame

from reform import T_ONE, T_TWO_THIRDS, evaluate
from reform.datasets import load_salsa
from reform.json_values import json_float
from reform.metrics import MicroScores, f1_score, pair_labels


def complete(groups, ids):
    """A full partition: ``groups`` plus singletons for everyone else."""
    grouped = {m for g in groups for m in g}
    return tuple(tuple(g) for g in groups) + tuple((i,) for i in ids if i not in grouped)


def score(truth, detected, ids, threshold=T_TWO_THIRDS):
    """(P, R, TP, FP, FN) of one frame."""
    ev = evaluate([frame(ids, truth)], [complete(detected, ids)], thresholds=[threshold])
    s = ev.at(threshold)
    return (
        float(s.frame_precision[0]),
        float(s.frame_recall[0]),
        int(s.frame_tp[0]),
        int(s.frame_fp[0]),
        int(s.frame_fn[0]),
    )


# --- matching at a threshold -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("truth", "detected", "at_two_thirds", "at_one"),
    [
        # hand-computed: |G∩D| / max(|G|, |D|) against 2/3 and 1
        pytest.param((1, 2, 3), (1, 2), True, False, id="2-of-3: 2/3 exactly passes 2/3"),
        pytest.param((1, 2, 3, 4, 5, 6), (1, 2, 3, 4), True, False, id="4-of-6: 4/6 = 2/3 passes"),
        pytest.param((1, 2, 3, 4, 5, 6), (1, 2, 3, 4, 7), True, False, id="4 of max(6,5)=6 passes"),
        pytest.param((1, 2, 3, 4), (1, 2, 3), True, False, id="3-of-4: 3/4 passes 2/3"),
        pytest.param((1, 2, 3, 4), (1, 2, 3, 5, 6), False, False, id="3 of max(4,5)=5 fails"),
        pytest.param((1, 2, 3, 4, 5), (1, 2, 3), False, False, id="3-of-5: 3/5 < 2/3 fails"),
        pytest.param((1, 2, 3), (1, 2, 3), True, True, id="identical groups pass both"),
        pytest.param((1, 2), (1, 3), False, False, id="pair: 1 of 2 fails"),
        pytest.param((1, 2), (1, 2, 3), True, False, id="pair inside a triple: 2/3 passes 2/3"),
        pytest.param((1, 2), (1, 2, 3, 4), False, False, id="pair inside a 4: 2/4 fails"),
        pytest.param((1, 2, 3), (1, 2, 4, 5), False, False, id="2 of max(3,4)=4 fails"),
    ],
)
def test_matching_rule(truth, detected, at_two_thirds, at_one):
    ids = range(1, 9)
    assert score([truth], [detected], ids, T_TWO_THIRDS)[2] == int(at_two_thirds)
    assert score([truth], [detected], ids, T_ONE)[2] == int(at_one)


def test_threshold_compared_exactly_in_integers():
    # hand-computed: 7 of 10 against T = 7/10 is equality, it must pass; 6 of 10 must not.
    ids = range(1, 13)
    truth = [tuple(range(1, 11))]
    assert score(truth, [tuple(range(1, 8))], ids, Fraction(7, 10))[2] == 1
    assert score(truth, [tuple(range(1, 7))], ids, Fraction(7, 10))[2] == 0
    # hand-computed: 9 of 12 against 3/4 is equality.
    ids = range(1, 14)
    truth = [tuple(range(1, 13))]
    assert score(truth, [tuple(range(1, 10))], ids, "3/4")[2] == 1
    assert score(truth, [tuple(range(1, 9))], ids, "3/4")[2] == 0


def test_each_true_group_counts_once_and_scan_order_is_irrelevant():
    # hand-computed: truth {1,2,3},{4,5,6}; detected {1,2},{3,4,5,6}: G1 matched by {1,2} (2/3),
    # G2 matched by {3,4,5,6} (3/4): TP 2 of 2 detected -> FP 0, FN 0.
    ids = range(1, 8)
    truth = [(1, 2, 3), (4, 5, 6)]
    detected = [(1, 2), (3, 4, 5, 6)]
    assert score(truth, detected, ids) == (1.0, 1.0, 2, 0, 0)
    assert score(truth, detected[::-1], ids) == (1.0, 1.0, 2, 0, 0)
    assert score(truth[::-1], detected, ids) == (1.0, 1.0, 2, 0, 0)
    # hand-computed: one detected group over two true groups matches neither (3/6 each).
    assert score(truth, [(1, 2, 3, 4, 5, 6)], ids) == (0.0, 0.0, 0, 1, 2)


@pytest.mark.parametrize("bad", [Fraction(1, 2), Fraction(1, 3), 0, Fraction(3, 2), 2])
def test_thresholds_outside_half_to_one_are_refused(bad):
    # At or below 1/2 one detected group could count for two true groups (FP < 0).
    with pytest.raises(ValueError, match=r"threshold must lie in \(1/2, 1\]"):
        evaluate([frame([1, 2], [])], [((1,), (2,))], thresholds=[bad])


def test_float_thresholds_are_refused():
    with pytest.raises(ValueError, match="threshold must be exact.*float 0.6666"):
        evaluate([frame([1, 2], [])], [((1,), (2,))], thresholds=[2 / 3])


# --- singletons and degenerate frames ----------------------------------------------------------


def test_singletons_are_dropped_from_both_sides():
    ids = range(1, 6)
    # hand-computed: only {1,2} counts on either side; singletons are never true positives.
    assert score([(1, 2), (3,), (4,)], [(1, 2)], ids) == (1.0, 1.0, 1, 0, 0)
    # hand-computed: a detected singleton {5} is no false positive (and a true one no false
    # negative).
    assert score([(1, 2)], [(1, 2), (5,)], ids) == (1.0, 1.0, 1, 0, 0)


def test_degenerate_frames():
    ids = range(1, 5)
    # hand-computed (ff_evalgroups.m conventions):
    # no detected and no true F-formation -> P = R = 1
    assert score([], [], ids) == (1.0, 1.0, 0, 0, 0)
    # true F-formations but none detected -> P = 1, R = 0
    assert score([(1, 2), (3, 4)], [], ids) == (1.0, 0.0, 0, 0, 2)
    # detections but no true F-formation -> P = 0, R = 1
    assert score([], [(1, 2, 3)], ids) == (0.0, 1.0, 0, 1, 0)


def test_ordinary_frame_precision_and_recall():
    # hand-computed: truth {1,2,3},{4,5},{6,7}; detected {1,2,3},{4,6},{5,7},{8,9}:
    # TP 1 ({1,2,3}), FP 4-1 = 3, FN 3-1 = 2, P 1/4, R 1/3.
    ids = range(1, 10)
    p, r, tp, fp, fn = score([(1, 2, 3), (4, 5), (6, 7)], [(1, 2, 3), (4, 6), (5, 7), (8, 9)], ids)
    assert (tp, fp, fn) == (1, 3, 2)
    assert p == pytest.approx(1 / 4) and r == pytest.approx(1 / 3)


# --- over a sequence ---------------------------------------------------------------------------


def two_frame_case():
    """Frame A matches 1 of 1; frame B: 3 true groups, 3 detected, 1 matched; frame C: none/none."""
    ids = list(range(1, 10))
    frames = [
        frame(ids, [(1, 2)], time=0.0),
        frame(ids, [(1, 2), (3, 4), (5, 6, 7)], time=1.0),
        frame(ids, [], time=2.0),
    ]
    predictions = [
        complete([(1, 2)], ids),
        complete([(1, 2), (3, 5), (4, 6, 8, 9)], ids),
        complete([], ids),
    ]
    return frames, predictions


def test_f1_of_frame_means_differs_from_micro():
    frames, predictions = two_frame_case()
    s = evaluate(frames, predictions).at(T_TWO_THIRDS)
    # hand-computed per frame (P, R): A (1, 1); B: {1,2} matched only -> (1/3, 1/3); C (1, 1).
    np.testing.assert_allclose(s.frame_precision, [1, 1 / 3, 1])
    np.testing.assert_allclose(s.frame_recall, [1, 1 / 3, 1])
    # hand-computed: P̄ = R̄ = (1 + 1/3 + 1)/3 = 7/9, F1 of the means 7/9.
    assert s.precision == pytest.approx(7 / 9)
    assert s.recall == pytest.approx(7 / 9)
    assert s.f1 == pytest.approx(7 / 9)
    # hand-computed micro: TP 1+1+0 = 2, FP 0+2+0 = 2, FN 0+2+0 = 2 -> P = R = F1 = 1/2.
    assert s.micro == MicroScores(tp=2, fp=2, fn=2)
    assert s.micro.precision == pytest.approx(0.5)
    assert s.micro.f1 == pytest.approx(0.5)


def test_f1_is_of_the_means_not_the_mean_of_f1s():
    # hand-computed: frame 1 P=1, R=0 (nothing detected); frame 2 P=0, R=1 (nothing true).
    # P̄ = R̄ = 1/2 -> F1 of means 1/2, while the mean of per-frame F1s would be 0.
    ids = [1, 2, 3]
    frames = [frame(ids, [(1, 2)]), frame(ids, [])]
    predictions = [complete([], ids), complete([(1, 2)], ids)]
    s = evaluate(frames, predictions).at("2/3")
    assert (s.precision, s.recall, s.f1) == (0.5, 0.5, 0.5)
    assert f1_score(0.0, 0.0) == 0.0


def test_per_size_breakdown():
    frames, predictions = two_frame_case()
    ev = evaluate(frames, predictions)
    # hand-computed at 2/3 -- true sizes: 2 (A), 2, 2, 3 (B); matched: both {1,2}.
    # detected sizes: 2 (A), 2, 2, 4 (B); matched: both {1,2}.
    by_size = {b.size: b for b in ev.at(T_TWO_THIRDS).by_size}
    assert sorted(by_size) == [2, 3, 4]
    assert (by_size[2].true_groups, by_size[2].true_matched) == (3, 2)
    assert (by_size[2].detected_groups, by_size[2].detected_matched) == (3, 2)
    assert by_size[2].recall == pytest.approx(2 / 3) and by_size[2].precision == pytest.approx(
        2 / 3
    )
    assert (by_size[3].true_groups, by_size[3].true_matched, by_size[3].detected_groups) == (
        1,
        0,
        0,
    )
    assert by_size[3].precision is None and by_size[3].recall == 0
    assert (by_size[4].true_groups, by_size[4].detected_groups, by_size[4].detected_matched) == (
        0,
        1,
        0,
    )
    assert by_size[4].recall is None and by_size[4].precision == 0


def test_pairwise_accuracy():
    # hand-computed: truth {1,2,3},{4}; predicted {1,2},{3,4}. Pairs (1,2) ok, (1,3) wrong,
    # (1,4) ok, (2,3) wrong, (2,4) ok, (3,4) wrong -> 3 of 6. Second frame: 2 people, truth
    # together, predicted apart -> 0 of 1. Pooled: 3 of 7.
    frames = [frame([1, 2, 3, 4], [(1, 2, 3)]), frame([5, 6], [(5, 6)])]
    predictions = [((1, 2), (3, 4)), ((5,), (6,))]
    ev = evaluate(frames, predictions)
    assert ev.pairs.tolist() == [6, 1]
    assert ev.pairs_correct.tolist() == [3, 0]
    assert ev.pairs_true_together.tolist() == [3, 1]
    assert ev.pairs_predicted_together.tolist() == [2, 0]
    assert ev.pairwise_accuracy == pytest.approx(3 / 7)


def test_pair_labels_order_and_groups():
    f = frame([7, 3, 9, 4], [(3, 4)])
    # pairs in np.triu_indices(4, 1) order over rows: (7,3) (7,9) (7,4) (3,9) (3,4) (9,4)
    assert pair_labels(f).tolist() == [0, 0, 0, 0, 1, 0]
    assert pair_labels(f, [(7, 9, 4)]).tolist() == [0, 1, 1, 0, 0, 1]
    with pytest.raises(ValueError, match="not annotated"):
        pair_labels(frame([1, 2], None))


# --- input checks ------------------------------------------------------------------------------


def test_only_annotated_frames_count():
    ids = [1, 2, 3]
    frames = [frame(ids, None, time=0.0), frame(ids, [(1, 2)], time=3.0)]
    predictions = [((1, 2, 3),), ((1, 2), (3,))]
    ev = evaluate(frames, predictions)
    assert ev.n_frames == 1
    assert ev.frame_index.tolist() == [1]
    assert ev.time.tolist() == [3.0]
    assert ev.at("2/3").precision == 1.0


@pytest.mark.parametrize(
    ("prediction", "message"),
    [
        (
            ((1, 2), (3,)),
            r"predictions\[1\] \(sequence 'session2', time 6.2 s\): person 4 is in no group",
        ),
        (((1, 2), (3, 4, 5)), r"predictions\[1\] .*person 5 \(group 1\) is not in the frame"),
        (((1, 2), (2, 3, 4)), r"predictions\[1\] .*person 2 appears twice"),
        (((1, 2), ()), r"predictions\[1\] .*group 1 is empty"),
        (((1, 2), ("3", 4)), r"predictions\[1\] .*expected an integer person id"),
    ],
)
def test_predictions_must_be_partitions(prediction, message):
    ids = [1, 2, 3, 4]
    frames = [
        frame(ids, [], sequence="session1"),
        frame(ids, [(1, 2)], time=6.2, sequence="session2"),
    ]
    good = ((1,), (2,), (3,), (4,))
    with pytest.raises(ValueError, match=message):
        evaluate(frames, [good, prediction])


def test_length_mismatch_and_no_annotated_frame():
    with pytest.raises(ValueError, match="expected 2, found 1"):
        evaluate([frame([1], []), frame([1], [])], [((1,),)])
    with pytest.raises(ValueError, match="annotated frames"):
        evaluate([frame([1], None)], [((1,),)])


def test_numpy_ids_accepted():
    ids = [1, 2, 3]
    prediction = (tuple(np.array([1, 2])), (np.int64(3),))
    assert evaluate([frame(ids, [(1, 2)])], [prediction]).at(T_ONE).recall == 1.0


# --- subsets and JSON --------------------------------------------------------------------------


def test_select_by_sequence_scores_the_subset():
    ids = [1, 2, 3]
    frames = [frame(ids, [(1, 2)], sequence="a"), frame(ids, [(1, 2)], sequence="b")]
    predictions = [((1, 2), (3,)), ((1,), (2,), (3,))]
    ev = evaluate(frames, predictions)
    a, b = ev.select(sequence="a"), ev.select(sequence="b")
    assert (a.n_frames, b.n_frames) == (1, 1)
    assert a.at(T_ONE).recall == 1.0 and b.at(T_ONE).recall == 0.0
    assert ev.at(T_ONE).recall == 0.5
    assert b.pairwise_accuracy == pytest.approx(2 / 3)


def test_to_json_schema():
    frames, predictions = two_frame_case()
    result = evaluate(frames, predictions).to_json(detector="d", dataset="toy", per_frame=True)
    result = json.loads(json.dumps(result))  # JSON-ready: no numpy scalars, no Fractions
    assert result["schema_version"] == 1
    assert (result["detector"], result["dataset"], result["frames"]) == ("d", "toy", 3)
    assert result["thresholds"] == ["2/3", "1"]
    for key in ("2/3", "1"):
        assert set(result[key]) >= {"precision", "recall", "f1", "micro", "by_size"}
        assert set(result[key]["micro"]) >= {"precision", "recall", "f1"}
    assert result["2/3"]["precision"] == pytest.approx(7 / 9)
    assert result["2/3"]["micro"]["tp"] == 2
    assert len(result["per_frame"]) == 3
    assert result["per_frame"][1]["2/3"] == {
        "precision": 1 / 3,
        "recall": 1 / 3,
        "tp": 1,
        "fp": 2,
        "fn": 2,
    }


# --- the protocol pinned on the original GCFF code's output ------------------------------------


@pytest.mark.parametrize(
    ("file", "two_thirds", "one"),
    [
        # The reference folder's README: the original GCFF code's partitions scored with this
        # protocol (P / R / F1 at T = 2/3 and at T = 1).
        ("salsa-body-stride70cm-mdl10000.txt", (0.848, 0.847, 0.847), (0.651, 0.651, 0.651)),
        ("salsa-body-stride50cm-mdl20000.txt", (0.842, 0.823, 0.833), (0.643, 0.631, 0.637)),
    ],
)
def test_reproduces_gcff_reference_scores_on_salsa(
    salsa_dir, gcff_reference_dir, file, two_thirds, one
):
    path = gcff_reference_dir / file
    dataset = load_salsa(salsa_dir)
    frames = dataset.annotated()
    reference = read_reference_partitions(path)
    assert [key for key, _ in reference] == [(f.sequence, f.time) for f in frames]
    ev = evaluate(frames, [partition for _, partition in reference])
    assert ev.n_frames == 1143
    for threshold, expected in ((T_TWO_THIRDS, two_thirds), (T_ONE, one)):
        s = ev.at(threshold)
        assert (round(s.precision, 3), round(s.recall, 3), round(s.f1, 3)) == expected


def test_pairwise_accuracy_is_nan_without_pairs():
    ev = evaluate([frame([1], [])], [((1,),)])
    assert math.isnan(ev.pairwise_accuracy)
    assert ev.to_json(detector="d", dataset="x")["pairwise_accuracy"] is None


def test_prediction_naming_a_person_of_another_frame():
    frames = [frame([1, 2], [(1, 2)]), frame([3, 4], [(3, 4)], time=3.0)]
    with pytest.raises(ValueError, match=r"predictions\[0\] .*person 3 \(group 0\) is not in"):
        evaluate(frames, [((1, 3), (2,)), ((3, 4),)])


def test_predictions_of_unannotated_frames_are_checked_too():
    frames = [frame([1, 2], None), frame([1, 2], [(1, 2)], time=3.0)]
    with pytest.raises(ValueError, match=r"predictions\[0\] .*person 2 is in no group"):
        evaluate(frames, [((1,),), ((1, 2),)])


def test_frames_of_different_sizes_and_odd_ids():
    # hand-computed: frame A (ids -5, 1000000007, 3): truth {-5, 3}, predicted the same:
    # TP 1, 3 of 3 pairs right. Frame B (one person): no pair, no group: P = R = 1.
    frames = [frame([-5, 1_000_000_007, 3], [(-5, 3)]), frame([8], [], time=1.0)]
    ev = evaluate(frames, [((3, -5), (1_000_000_007,)), ((8,),)])
    assert ev.pairs.tolist() == [3, 0] and ev.pairs_correct.tolist() == [3, 0]
    assert ev.at(T_ONE).frame_tp.tolist() == [1, 0]
    assert (ev.at(T_ONE).precision, ev.at(T_ONE).recall) == (1.0, 1.0)


def literal_ff_evalgroups(truth, detected, threshold):
    """ff_evalgroups.m transcribed line by line (cardmode off), on singleton-free group lists."""
    if not detected and not truth:
        return 1.0, 1.0, 0
    if not detected:
        return 1.0, 0.0, 0
    if not truth:
        return 0.0, 1.0, 0
    tp = 0
    for g in truth:
        for d in detected:
            if Fraction(len(set(g) & set(d)), max(len(g), len(d))) >= threshold:
                tp += 1
                break
    return tp / len(detected), tp / len(truth), tp


@st.composite
def frames_and_predictions(draw):
    n_frames = draw(st.integers(1, 6))
    frames, predictions = [], []
    for index in range(n_frames):
        n = draw(st.integers(0, 9))
        ids = draw(st.lists(st.integers(-50, 50), min_size=n, max_size=n, unique=True))
        true_labels = draw(st.lists(st.integers(0, 3), min_size=n, max_size=n))
        pred_labels = draw(st.lists(st.integers(0, 3), min_size=n, max_size=n))
        annotated = draw(st.booleans()) or index == 0

        def groups(labels, ids=ids):
            out = {}
            for person, label in zip(ids, labels, strict=True):
                out.setdefault(label, []).append(person)
            return tuple(tuple(g) for g in out.values())

        frames.append(frame(ids, groups(true_labels) if annotated else None, time=float(index)))
        predictions.append(groups(pred_labels))
    return frames, predictions


@given(frames_and_predictions())
@settings(max_examples=150, deadline=None)
def test_vectorised_protocol_equals_the_literal_reference(case):
    frames, predictions = case
    ev = evaluate(frames, predictions, thresholds=[T_TWO_THIRDS, T_ONE, Fraction(3, 4)])
    annotated = [(f, p) for f, p in zip(frames, predictions, strict=True) if f.groups is not None]
    assert ev.n_frames == len(annotated)
    for t in ev.thresholds:
        s = ev.at(t)
        for row, (f, p) in enumerate(annotated):
            truth = [g for g in f.partition() if len(g) > 1]
            detected = [g for g in p if len(g) > 1]
            precision, recall, tp = literal_ff_evalgroups(truth, detected, t)
            assert (s.frame_precision[row], s.frame_recall[row]) == (precision, recall)
            assert s.frame_tp[row] == tp
            assert s.frame_fp[row] == len(detected) - tp and s.frame_fn[row] == len(truth) - tp
    for row, (f, p) in enumerate(annotated):
        expected = pair_labels(f)
        assert ev.pairs[row] == expected.size
        assert ev.pairs_correct[row] == int(np.sum(expected == pair_labels(f, p)))


def test_json_float_is_a_float_or_null() -> None:
    for missing in (None, math.nan, math.inf, -math.inf):
        assert json_float(missing) is None
    assert json_float(np.float32(0.5)) == 0.5 and type(json_float(np.float32(0.5))) is float
