"""Temporal metrics of a detector (reform.temporal): matching, latency, flicker and identity
switches hand-computed; a detector equal to the truth scores perfectly; every refusal of bad
input."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from toy_scenes import line_frame

from reform import TemporalEvaluation, evaluate_events
from reform.events import EVENT_KINDS, JOINS, LEAVES

IDS = (1, 2, 3, 4, 5, 6)


def frames_of(*partitions, sequence="s", step=1.0, ids=IDS):
    """One true frame per partition (its F-formations), times 0, step, 2 step, ..."""
    return [
        line_frame(ids, groups, time=k * step, sequence=sequence)
        for k, groups in enumerate(partitions)
    ]


def detected(*partitions, ids=IDS):
    """The detector's full partitions (singletons added), one per frame."""
    out = []
    for groups in partitions:
        grouped = {m for g in groups for m in g}
        out.append(tuple(map(tuple, groups)) + tuple((i,) for i in ids if i not in grouped))
    return out


def score(truth, detection, **kwargs) -> TemporalEvaluation:
    return evaluate_events(frames_of(*truth), detected(*detection), **kwargs)


# --- hand-computed cases ------------------------------------------------------------------------


def test_a_late_join_is_matched_with_its_latency():
    # Truth: 3 joins {1,2} at t=1 s. Detection: at t=2 s, one frame (1 s) late.
    truth = ([(1, 2)], [(1, 2, 3)], [(1, 2, 3)], [(1, 2, 3)])
    late = ([(1, 2)], [(1, 2)], [(1, 2, 3)], [(1, 2, 3)])
    ev = score(truth, late, tolerance_s=1.0)
    assert ev.matches == ((0, 0),)
    assert ev.latency_s.tolist() == [1.0]
    assert (ev.latency_median_s, ev.latency_p95_s) == (1.0, 1.0)
    assert ev.kind(JOINS).recall == 1.0 and ev.kind(JOINS).precision == 1.0
    assert ev.false_events == 0


def test_a_detection_later_than_the_tolerance_is_a_miss_and_a_false_event():
    truth = ([(1, 2)], [(1, 2, 3)], [(1, 2, 3)], [(1, 2, 3)])
    too_late = ([(1, 2)], [(1, 2)], [(1, 2)], [(1, 2, 3)])  # 2 s late
    ev = score(truth, too_late, tolerance_s=1.0)
    assert ev.matches == ()
    assert (ev.recall, ev.precision) == (0.0, 0.0)
    assert (ev.latency_median_s, ev.latency_p95_s) == (None, None)
    # hand-computed: one unmatched detected event over 3 s = 0.05 min -> 20 per minute
    assert ev.false_events == 1
    assert ev.false_events_per_minute == pytest.approx(20.0)
    # the same detection is matched with a window of 2 s
    assert score(truth, too_late, tolerance_s=2.0).latency_s.tolist() == [2.0]


def test_a_flicker_gives_two_false_events_per_its_minutes():
    # Truth: {1,2,3} throughout, 7 frames (6 s). Detection: 3 stands alone for one frame.
    truth = [[(1, 2, 3)]] * 7
    flicker = [[(1, 2, 3)]] * 3 + [[(1, 2)]] + [[(1, 2, 3)]] * 3
    ev = score(truth, flicker)
    assert [(e.kind, e.person, e.time) for e in ev.detected_events] == [
        (LEAVES, 3, 3.0),
        (JOINS, 3, 4.0),
    ]
    assert ev.true_events == ()
    assert (ev.recall, ev.precision) == (None, 0.0)
    # hand-computed: 2 false events in 6 s = 0.1 min
    assert ev.false_events == 2
    assert ev.false_events_per_minute == pytest.approx(20.0)
    assert ev.minutes == pytest.approx(0.1)
    assert ev.identity_switches == 0  # {1,2} still matches {1,2,3} at 2/3, under one track


def test_a_detected_group_that_dissolves_and_forms_again_is_an_identity_switch():
    # Truth: {1,2,3} throughout. Detection: {1,2,3} (track 1), nothing, {1,2,3} again (track 2).
    truth = [[(1, 2, 3)]] * 3
    ev = score(truth, ([(1, 2, 3)], [], [(1, 2, 3)]))
    assert ev.identity_switches == 1  # matched to track 1, then (after a gap) to track 2
    assert [e.kind for e in ev.detected_events] == ["dissolves", "forms"]
    assert ev.false_events == 2


def test_an_identity_switch_without_a_gap():
    # Truth: {1,...,6} throughout. Detection: {1,2,3,4} (track 1) and {5,6} (track 2), then
    # {1,2} and {3,4,5,6}: a tie on two shared members; {1,2} keeps track 1 and {3,4,5,6}
    # goes on as track 2. The true group matches {1,2,3,4} (4/6 >= 2/3), then {3,4,5,6}.
    truth = [[(1, 2, 3, 4, 5, 6)]] * 2
    ev = score(truth, ([(1, 2, 3, 4), (5, 6)], [(1, 2), (3, 4, 5, 6)]))
    assert ev.identity_switches == 1


def test_matching_is_one_to_one_and_greedy_by_time_then_the_earlier_true_event():
    # Truth: 3 joins at t=2, leaves at t=3, joins again at t=4. Detection: one join at t=3,
    # 1 s from both true joins: the earlier true join takes it.
    truth = ([(1, 2)], [(1, 2)], [(1, 2, 3)], [(1, 2)], [(1, 2, 3)], [(1, 2, 3)])
    detection = ([(1, 2)], [(1, 2)], [(1, 2)], [(1, 2, 3)], [(1, 2, 3)], [(1, 2, 3)])
    ev = score(truth, detection, tolerance_s=1.0)
    assert [(e.kind, e.time) for e in ev.true_events] == [
        (JOINS, 2.0),
        (LEAVES, 3.0),
        (JOINS, 4.0),
    ]
    assert ev.matches == ((0, 0),)
    assert ev.latency_s.tolist() == [1.0]
    assert (ev.kind(JOINS).recall, ev.kind(JOINS).precision) == (0.5, 1.0)
    assert ev.kind(LEAVES).recall == 0.0 and ev.kind(LEAVES).precision is None


def test_equal_gaps_between_floating_point_times_tie_and_go_to_the_earlier_true_event():
    # 10 Hz: true joins at 0.7 s and 0.9 s, a detected join at 0.8 s; in floating point
    # 0.8 - 0.7 = 0.10000000000000009 but 0.9 - 0.8 = 0.09999999999999998: a tie all the same.
    truth = [[(1, 2)]] * 7 + [[(1, 2, 3)], [(1, 2)], [(1, 2, 3)]]
    detection = [[(1, 2)]] * 8 + [[(1, 2, 3)]] * 2
    frames = [line_frame(IDS, groups, time=k / 10) for k, groups in enumerate(truth)]
    ev = evaluate_events(frames, detected(*detection), tolerance_s=0.1)
    assert [(e.kind, e.time) for e in ev.true_events if e.kind == JOINS] == [
        (JOINS, pytest.approx(0.7)),
        (JOINS, pytest.approx(0.9)),
    ]
    assert ev.matches == ((0, 0),)


@pytest.mark.parametrize(
    ("true_group", "detected_group", "matched"),
    [
        # hand-computed: the groups joined, at |G ∩ D| / max(|G|, |D|) >= 2/3
        pytest.param((1, 2, 3), (1, 2, 3), True, id="same group"),
        pytest.param((1, 2, 3), (1, 2, 3, 4), True, id="3 of 4 passes"),
        pytest.param((1, 2, 3), (1, 3, 4, 5), False, id="2 of 4 fails"),
    ],
)
def test_a_join_matches_when_its_groups_match_at_two_thirds(true_group, detected_group, matched):
    before = tuple(m for m in true_group if m != 3)
    truth = ([before], [true_group])
    detection = ([tuple(m for m in detected_group if m != 3)], [detected_group])
    ev = score(truth, detection)
    assert [e.kind for e in ev.detected_events] == [JOINS]
    assert bool(ev.matches) is matched


def test_a_join_of_another_person_does_not_match():
    ev = score(([(1, 2, 3)], [(1, 2, 3, 4)]), ([(1, 2, 3)], [(1, 2, 3, 5)]))
    assert ev.matches == ()


def test_a_tolerance_of_one_frame_interval_matches_one_frame_late_despite_rounding():
    # 10 Hz: times k / 10; 1.1 - 1.0 is 0.10000000000000009 in floating point.
    frames = [line_frame(IDS, [(1, 2)] if k < 11 else [(1, 2, 3)], time=k / 10) for k in range(13)]
    late = detected(*([[(1, 2)]] * 12 + [[(1, 2, 3)]]))
    ev = evaluate_events(frames, late, tolerance_s=0.1)
    assert ev.latency_s.tolist() == pytest.approx([0.1])


def test_observed_frames_with_other_people_can_be_the_detection():
    truth = frames_of([(1, 2)], [(1, 2, 3)])
    observed = [
        line_frame([1, 2], [(1, 2)], time=0.0, sequence="s"),
        line_frame([1, 2, 3], [(1, 2, 3)], time=1.0, sequence="s"),
    ]
    ev = evaluate_events(truth, observed)
    assert ev.matches == ((0, 0),) and ev.recall == 1.0


# --- a detector equal to the truth ------------------------------------------------------------

labels = st.lists(st.integers(0, 4), min_size=6, max_size=6)


def partition(row):
    groups: dict[int, list[int]] = {}
    for person, label in zip(IDS, row, strict=True):
        groups.setdefault(label, []).append(person)
    return [tuple(g) for g in groups.values()]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.lists(labels, min_size=2, max_size=10), min_size=1, max_size=3))
def test_the_truth_as_detection_scores_perfectly(sequences):
    frames = [
        frame
        for s, rows in enumerate(sequences)
        for frame in frames_of(*(partition(r) for r in rows), sequence=f"seq{s}", step=0.5)
    ]
    ev = evaluate_events(frames, [f.partition() for f in frames], rng=np.random.default_rng(0))
    expected = 1.0 if ev.true_events else None
    assert (ev.recall, ev.precision) == (expected, expected)
    for kind in ev.by_kind:
        assert kind.matched == kind.true_events == kind.detected_events
        assert kind.recall == kind.precision == (1.0 if kind.true_events else None)
    assert ev.detected_events == ev.true_events
    assert set(ev.latency_s.tolist()) <= {0.0}
    assert ev.latency_median_s == (0.0 if ev.true_events else None)
    assert ev.false_events == 0 and ev.false_events_per_minute == 0.0
    assert ev.identity_switches == 0


# --- results, intervals, determinism ------------------------------------------------------------


def two_sequences():
    a = frames_of([(1, 2)], [(1, 2, 3)], [(1, 2, 3)], [(1, 2)], sequence="a")
    b = frames_of([(4, 5)], [(4, 5)], [], [(4, 5, 6)], sequence="b")
    detection = detected([(1, 2)], [(1, 2)], [(1, 2, 3)], [(1, 2, 3)]) + detected(
        [(4, 5)], [], [], [(4, 5, 6)]
    )
    return a + b, detection


def test_the_results_are_json_ready_with_intervals_over_sequences():
    frames, detection = two_sequences()
    ev = evaluate_events(frames, detection, rng=np.random.default_rng(1), resamples=200)
    result = json.loads(json.dumps(ev.to_json(events=True)))
    assert result["kind"] == "reform-sim/temporal-evaluation"
    assert result["sequences"] == ["a", "b"]
    assert result["frames"] == 8
    assert set(result["by_kind"]) == set(EVENT_KINDS)
    assert set(result["intervals"]) == {
        "recall",
        "precision",
        "latency_median_s",
        "latency_p95_s",
        "false_events_per_minute",
        "identity_switches",
    }
    for interval in result["intervals"].values():
        assert interval["low"] <= interval["high"]
    assert len(result["events"]["true"]) == len(ev.true_events)
    assert result["events"]["matches"] == [list(pair) for pair in ev.matches]
    # hand-computed: truth a: join t=1, leave t=3; b: dissolve t=2, forms t=3 (4 events).
    # Detection a: join t=2 (matched, 1 s late); b: dissolve t=1 (matched, 1 s early), forms
    # t=3 (matched): 3 of the 4 true events found, the 3 detected events all matched.
    assert (ev.recall, ev.precision) == (0.75, 1.0)
    assert sorted(ev.latency_s.tolist()) == [-1.0, 0.0, 1.0]


def test_a_single_sequence_or_no_generator_gives_no_intervals():
    frames, detection = two_sequences()
    assert evaluate_events(frames, detection).intervals is None
    one = evaluate_events(frames[:4], detection[:4], rng=np.random.default_rng(1))
    assert one.intervals is None


def test_the_same_inputs_and_seed_give_the_same_results():
    frames, detection = two_sequences()
    first = evaluate_events(frames, detection, rng=np.random.default_rng(7), resamples=100)
    again = evaluate_events(frames, detection, rng=np.random.default_rng(7), resamples=100)
    assert first.to_json(events=True) == again.to_json(events=True)


def test_the_callers_predictions_are_not_changed():
    frames, detection = two_sequences()
    copy = [tuple(tuple(g) for g in p) for p in detection]
    evaluate_events(frames, detection)
    assert detection == copy


# --- bad input, refused before any work ---------------------------------------------------------


def test_frames_out_of_time_order_are_refused():
    frames = frames_of([(1, 2)], [(1, 2)], [(1, 2)])
    frames[0], frames[1] = frames[1], frames[0]
    with pytest.raises(
        ValueError, match=r"^frames\[1\] \(sequence 's', time 0 s\) is out of time order"
    ):
        evaluate_events(frames, [f.partition() for f in frames])


def test_a_repeated_time_is_refused():
    frames = frames_of([(1, 2)], [(1, 2)])
    frames[1] = frames[1].replace(time=0.0)
    with pytest.raises(ValueError, match=r"^frames\[1\] .* repeats the time of frames\[0\]"):
        evaluate_events(frames, [f.partition() for f in frames])


def test_a_sequence_with_a_single_annotated_frame_is_refused():
    frames = frames_of([(1, 2)], sequence="ep3")
    with pytest.raises(ValueError, match=r"^sequence 'ep3' has 1 annotated frame\(s\)"):
        evaluate_events(frames, [f.partition() for f in frames])


def test_a_tolerance_below_the_frame_interval_is_refused():
    frames = frames_of([(1, 2)], [(1, 2)], [(1, 2)], step=0.5)
    with pytest.raises(
        ValueError,
        match=r"^tolerance_s must be at least the frame interval of sequence 's' \(frames\[0\] "
        r"to frames\[2\]\): expected >= 0.5 s \(the median step between its annotated frames\), "
        r"got 0.25 s$",
    ):
        evaluate_events(frames, [f.partition() for f in frames], tolerance_s=0.25)


def test_predictions_of_another_length_are_refused():
    frames = frames_of([(1, 2)], [(1, 2)])
    with pytest.raises(
        ValueError,
        match=r"^predictions must hold one partition \(or Frame\) per frame: expected 2, found 1$",
    ):
        evaluate_events(frames, [frames[0].partition()])


def test_detected_frames_at_other_times_or_sequences_are_refused():
    frames = frames_of([(1, 2)], [(1, 2)])
    shifted = [frames[0], frames[1].replace(time=1.5)]
    with pytest.raises(
        ValueError,
        match=r"^predictions\[1\] \(sequence 's', time 1.5 s\) does not align with frames\[1\] "
        r"\(sequence 's', time 1 s\): expected the same sequence and time$",
    ):
        evaluate_events(frames, shifted)
    renamed = [frames[0].replace(sequence="other"), frames[1]]
    with pytest.raises(ValueError, match=r"^predictions\[0\] \(sequence 'other', time 0 s\)"):
        evaluate_events(frames, renamed)


def test_a_detected_frame_without_groups_is_refused():
    frames = frames_of([(1, 2)], [(1, 2)])
    with pytest.raises(ValueError, match=r"^predictions\[1\] .* has no groups: expected"):
        evaluate_events(frames, [frames[0], frames[1].replace(groups=None)])


def test_a_prediction_that_is_not_a_partition_is_refused():
    frames = frames_of([(1, 2)], [(1, 2)])
    bad = [frames[0].partition(), ((1, 2), (3, 4), (5, 6, 9))]
    with pytest.raises(
        ValueError, match=r"^predictions\[1\] \(sequence 's', time 1 s\): person 9 \(group 2\)"
    ):
        evaluate_events(frames, bad)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"tolerance_s": "1"}, r"^tolerance_s must be a number of seconds, got '1'$"),
        ({"tolerance_s": float("inf")}, r"^tolerance_s must be finite, got inf$"),
        ({"rng": 3}, r"^rng must be a numpy.random.Generator or None, got int$"),
        ({"resamples": 0}, r"^resamples must be an int >= 1, got 0$"),
        ({"level": 1.0}, r"^level must lie in \(0, 1\), got 1.0$"),
    ],
)
def test_bad_options_are_refused(options, message):
    frames = frames_of([(1, 2)], [(1, 2)])
    with pytest.raises(ValueError, match=message):
        evaluate_events(frames, [f.partition() for f in frames], **options)
