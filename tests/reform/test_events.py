"""Group events and identities over time (reform.events): every kind hand-computed, the identity
rule's ties, sequences, and every refusal of bad input."""

from __future__ import annotations

import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from toy_scenes import line_frame

from reform import (
    GroupEvent,
    group_events,
    partition_events,
    partition_tracks,
    track_groups,
)
from reform.events import DISSOLVES, EVENT_KINDS, FORMS, JOINS, LEAVES, MERGES, SPLITS

IDS = (1, 2, 3, 4, 5, 6)


def frames_of(*partitions, ids=IDS, sequence="s", step=1.0):
    """One frame per partition (its F-formations), times 0, step, 2 step, ..."""
    return [
        line_frame(ids, groups, time=k * step, sequence=sequence)
        for k, groups in enumerate(partitions)
    ]


def summary(events):
    """(kind, time, group, members, person) of each event: what the hand computation gives."""
    return [(e.kind, e.time, e.group, e.members, e.person) for e in events]


# --- one event of each kind, hand-computed --------------------------------------------------------


@pytest.mark.parametrize(
    ("before", "after", "expected"),
    [
        pytest.param([(1, 2)], [(1, 2, 3)], [(JOINS, 1.0, 1, (1, 2, 3), 3)], id="3 joins {1,2}"),
        pytest.param(
            [(1, 2, 3)], [(1, 2)], [(LEAVES, 1.0, 1, (1, 2, 3), 3)], id="3 leaves {1,2,3}"
        ),
        pytest.param([], [(2, 1)], [(FORMS, 1.0, 1, (1, 2), None)], id="{1,2} forms"),
        pytest.param([(1, 2)], [], [(DISSOLVES, 1.0, 1, (1, 2), None)], id="{1,2} dissolves"),
        pytest.param(
            [(1, 2)],
            [(1,), (2,)],
            [(DISSOLVES, 1.0, 1, (1, 2), None)],
            id="a pair losing one member dissolves: no leaves",
        ),
        pytest.param(
            [(1, 2)],
            [(2, 3)],
            [(FORMS, 1.0, 2, (2, 3), None), (DISSOLVES, 1.0, 1, (1, 2), None)],
            id="a pair swapping a member: one shared person carries no identity",
        ),
        pytest.param(
            [(1, 2, 3), (4, 5)],
            [(1, 2), (3, 4, 5)],
            [(JOINS, 1.0, 2, (3, 4, 5), 3), (LEAVES, 1.0, 1, (1, 2, 3), 3)],
            id="3 moves from one group to another: leaves and joins",
        ),
        pytest.param(
            [(1, 2, 3)],
            [(1, 2, 3)],
            [],
            id="no change, no event",
        ),
        pytest.param(
            [(1, 2), (3, 4, 5)],
            [(5, 4, 3), (2, 1)],
            [],
            id="the same groups in another order: no event",
        ),
    ],
)
def test_one_change_gives_the_hand_computed_events(before, after, expected):
    assert summary(group_events(frames_of(before, after))) == expected


def test_two_groups_merge_into_the_older_groups_identity():
    events = group_events(frames_of([(1, 2)], [(1, 2), (3, 4)], [(1, 2, 3, 4)]))
    # hand-computed: {1,2} is track 1 from the start, {3,4} forms as track 2 at t=1; at t=2 both
    # flow two people into {1,2,3,4}: a tie on overlap, so the older track 1 goes on.
    assert summary(events) == [
        (FORMS, 1.0, 2, (3, 4), None),
        (MERGES, 2.0, 1, (1, 2, 3, 4), None),
    ]
    merge = events[1]
    assert merge.parts == ((1, 2), (3, 4))
    assert merge.part_tracks == (1, 2)
    assert merge.frame == 2


def test_a_group_splits_and_the_part_with_the_smallest_id_keeps_its_identity():
    events = group_events(frames_of([(1, 2, 3, 4)], [(3, 4), (1, 2)]))
    # hand-computed: both parts share two members with track 1 (a tie); {1,2} holds the smallest
    # id and goes on as track 1, {3,4} becomes track 2.
    assert summary(events) == [(SPLITS, 1.0, 1, (1, 2, 3, 4), None)]
    assert events[0].parts == ((1, 2), (3, 4))
    assert events[0].part_tracks == (1, 2)


def test_the_part_sharing_the_most_members_keeps_the_identity():
    tracks = track_groups(frames_of([(1, 2, 3, 4, 5)], [(1, 2), (3, 4, 5)]))
    # hand-computed: {3,4,5} shares 3 members with track 1, {1,2} only 2.
    assert tracks.at(1) == {1: (3, 4, 5), 2: (1, 2)}


def test_a_merge_joined_by_a_newcomer_gives_a_merge_and_a_join():
    events = group_events(frames_of([(1, 2), (3, 4)], [(1, 2, 3, 4, 5)]))
    assert summary(events) == [
        (JOINS, 1.0, 1, (1, 2, 3, 4, 5), 5),
        (MERGES, 1.0, 1, (1, 2, 3, 4, 5), None),
    ]


def test_part_of_a_group_moving_into_another_is_a_split_and_a_merge():
    events = group_events(frames_of([(1, 2, 3, 4), (5, 6)], [(1, 2), (3, 4, 5, 6)]))
    # hand-computed: track 1 {1,2,3,4} flows 2 into each part (tie: {1,2} goes on as track 1);
    # {3,4,5,6} gets track 2 from {5,6} (two shared, the only free track).
    assert summary(events) == [
        (MERGES, 1.0, 2, (3, 4, 5, 6), None),
        (SPLITS, 1.0, 1, (1, 2, 3, 4), None),
    ]
    assert events[0].parts == ((1, 2, 3, 4), (5, 6))
    assert events[1].parts == ((1, 2), (3, 4, 5, 6))


def test_a_person_leaving_the_scene_leaves_the_group():
    frames = [
        line_frame([1, 2, 3], [(1, 2, 3)], time=0.0),
        line_frame([1, 2], [(1, 2)], time=1.0),
    ]
    assert summary(group_events(frames)) == [(LEAVES, 1.0, 1, (1, 2, 3), 3)]


def test_the_first_frames_groups_do_not_form_and_the_last_frames_do_not_dissolve():
    assert group_events(frames_of([(1, 2), (3, 4)], [(1, 2), (3, 4)])) == []


def test_a_sequence_of_every_kind_in_order():
    events = group_events(
        frames_of(
            [(1, 2, 3)],
            [(1, 2, 3, 4)],
            [(1, 2, 3, 4), (5, 6)],
            [(1, 2, 3, 4, 5, 6)],
            [(1, 2, 3), (4, 5, 6)],
            [(1, 2), (4, 5, 6)],
            [(4, 5, 6)],
            [],
        )
    )
    # hand-computed, frame by frame (the "Groups in time" guide walks through it)
    assert summary(events) == [
        (JOINS, 1.0, 1, (1, 2, 3, 4), 4),
        (FORMS, 2.0, 2, (5, 6), None),
        (MERGES, 3.0, 1, (1, 2, 3, 4, 5, 6), None),
        (SPLITS, 4.0, 1, (1, 2, 3, 4, 5, 6), None),
        (LEAVES, 5.0, 1, (1, 2, 3), 3),
        (DISSOLVES, 6.0, 1, (1, 2), None),
        (DISSOLVES, 7.0, 3, (4, 5, 6), None),
    ]
    assert [e.frame for e in events] == [1, 2, 3, 4, 5, 6, 7]


def test_events_within_a_frame_are_ordered_by_kind_then_track_then_person():
    events = group_events(frames_of([(1, 2), (3, 4, 5)], [(1, 2, 6), (3,), (4, 5)]))
    kinds = [e.kind for e in events]
    assert kinds == sorted(kinds, key=EVENT_KINDS.index)
    assert summary(events) == [(JOINS, 1.0, 1, (1, 2, 6), 6), (LEAVES, 1.0, 2, (3, 4, 5), 3)]


# --- frames without ground truth, sequences -------------------------------------------------------


def test_frames_without_ground_truth_are_skipped():
    frames = frames_of([(1, 2)], [(1, 2)], [(1, 2, 3)])
    frames[1] = frames[1].replace(groups=None)
    # the join is seen at the next annotated frame, frames[2]
    assert [(e.kind, e.frame, e.time) for e in group_events(frames)] == [(JOINS, 2, 2.0)]


def test_sequences_are_followed_apart_with_distinct_track_ids():
    a = frames_of([(1, 2)], [(1, 2, 3)], sequence="a")
    b = frames_of([(4, 5)], [], sequence="b")
    interleaved = [a[0], b[0], a[1], b[1]]
    events = group_events(interleaved)
    assert [(e.sequence, e.kind, e.group, e.frame) for e in events] == [
        ("a", JOINS, 1, 2),
        ("b", DISSOLVES, 2, 3),
    ]


def test_track_groups_gives_one_span_per_stretch_of_unchanged_members():
    tracks = track_groups(frames_of([(1, 2)], [(1, 2)], [(1, 2, 3)], [(1, 2, 3)], [(4, 5)]))
    # hand-computed: track 1 is {1,2} over frames 0-1 and {1,2,3} over 2-3, then dissolves;
    # {4,5} forms as track 2 at frame 4.
    assert tracks.track.tolist() == [1, 1, 2]
    assert tracks.first.tolist() == [0, 2, 4]
    assert tracks.last.tolist() == [1, 3, 4]
    assert tracks.start.tolist() == [0.0, 2.0, 4.0]
    assert tracks.end.tolist() == [1.0, 3.0, 4.0]
    assert tracks.members == ((1, 2), (1, 2, 3), (4, 5))
    assert tracks.n_tracks == 2
    assert tracks.at(2) == {1: (1, 2, 3)}
    assert tracks.at(4) == {2: (4, 5)}


def test_the_events_are_json_ready():
    (event,) = group_events(frames_of([(1, 2)], [(1, 2), (3, 4)]))
    assert event.to_json() == {
        "kind": "forms",
        "sequence": "s",
        "time": 1.0,
        "frame": 1,
        "group": 2,
        "members": [3, 4],
        "person": None,
        "parts": [],
        "part_tracks": [],
    }
    assert isinstance(event, GroupEvent)


# --- properties -----------------------------------------------------------------------------------

labels = st.lists(st.integers(0, 4), min_size=6, max_size=6)


def partition(row):
    groups: dict[int, list[int]] = {}
    for person, label in zip(IDS, row, strict=True):
        groups.setdefault(label, []).append(person)
    return [tuple(g) for g in groups.values()]


@settings(max_examples=60, deadline=None)
@given(st.lists(labels, min_size=2, max_size=12))
def test_tracks_cover_every_frames_fformations_and_never_come_back(rows):
    frames = frames_of(*(partition(row) for row in rows))
    tracks = track_groups(frames)
    for k, frame in enumerate(frames):
        found = sorted(tracks.at(k).values())
        assert found == sorted(tuple(sorted(g)) for g in frame.fformations())
    for track in set(tracks.track.tolist()):
        rows_of_track = tracks.track == track
        first, last = tracks.first[rows_of_track], tracks.last[rows_of_track]
        # one identity is one unbroken stretch: its spans follow each other frame by frame
        assert (first[1:] == last[:-1] + 1).all()


@settings(max_examples=60, deadline=None)
@given(st.lists(labels, min_size=2, max_size=12))
def test_every_change_of_the_fformations_gives_an_event_and_no_change_none(rows):
    frames = frames_of(*(partition(row) for row in rows))
    changed = {
        k
        for k in range(1, len(frames))
        if set(map(frozenset, frames[k].fformations()))
        != set(map(frozenset, frames[k - 1].fformations()))
    }
    assert {e.frame for e in group_events(frames)} == changed


def test_the_same_frames_give_the_same_events_and_tracks():
    partitions = ([(1, 2, 3)], [(1, 2), (3, 4)], [(1, 2, 3, 4)], [(2, 3)], [])
    first, again = group_events(frames_of(*partitions)), group_events(frames_of(*partitions))
    assert first == again
    a, b = track_groups(frames_of(*partitions)), track_groups(frames_of(*partitions))
    assert a.track.tolist() == b.track.tolist() and a.members == b.members


# --- bad input, refused before any work -----------------------------------------------------------


def test_frames_out_of_time_order_are_refused():
    frames = frames_of([(1, 2)], [(1, 2)], [(1, 2)])
    frames[1], frames[2] = frames[2], frames[1]
    with pytest.raises(
        ValueError,
        match=r"^frames\[2\] \(sequence 's', time 1 s\) is out of time order in sequence 's': "
        r"expected a time after 2 s \(frames\[1\]\), found 1 s$",
    ):
        group_events(frames)


def test_a_repeated_time_is_refused():
    frames = frames_of([(1, 2)], [(1, 2)])
    frames[1] = frames[1].replace(time=0.0)
    with pytest.raises(
        ValueError,
        match=r"^frames\[1\] \(sequence 's', time 0 s\) repeats the time of frames\[0\] in "
        r"sequence 's': expected a time after 0 s, found 0 s$",
    ):
        track_groups(frames)


def test_a_sequence_with_a_single_annotated_frame_is_refused():
    frames = frames_of([(1, 2)], [(1, 2)], sequence="a") + frames_of([(1, 2)], sequence="b")
    with pytest.raises(
        ValueError,
        match=r"^sequence 'b' has 1 annotated frame\(s\) \(only frames\[2\]\): expected at least "
        r"two to find events between$",
    ):
        group_events(frames)


def test_a_sequence_without_annotated_frames_is_refused():
    frames = [f.replace(groups=None) for f in frames_of([(1, 2)], [(1, 2)])]
    with pytest.raises(ValueError, match=r"^sequence 's' has 0 annotated frame\(s\) \(none\)"):
        group_events(frames)


def test_no_frames_and_entries_that_are_not_frames_are_refused():
    with pytest.raises(ValueError, match="^group_events needs frames: expected annotated frames"):
        group_events([])
    with pytest.raises(TypeError, match=r"group_events takes reform.Frame objects, got tuple"):
        group_events([((1, 2),), ((1, 2),)])


# --- groups given without Frames, and events read back from JSON ----------------------------------


@settings(max_examples=60, deadline=None)
@given(st.lists(labels, min_size=2, max_size=12), st.lists(st.booleans(), min_size=12))
def test_partitions_give_the_events_and_tracks_of_their_frames(rows, annotated):
    frames = frames_of(*(partition(row) for row in rows))
    frames = [
        f if keep else f.replace(groups=None) for f, keep in zip(frames, annotated, strict=False)
    ]
    if sum(f.groups is not None for f in frames) < 2:
        frames[0], frames[-1] = (frames_of(partition(r))[0] for r in (rows[0], rows[-1]))
        frames[-1] = frames[-1].replace(time=float(len(frames) - 1))
    given_as = {
        "partitions": [f.groups for f in frames],
        "times": [f.time for f in frames],
        "sequences": "s",
    }
    assert partition_events(**given_as) == group_events(frames)
    tracks, expected = partition_tracks(**given_as), track_groups(frames)
    assert tracks.track.tolist() == expected.track.tolist()
    assert tracks.members == expected.members and tracks.n_tracks == expected.n_tracks


def test_partitions_of_several_sequences_and_short_ones_skipped_when_asked():
    partitions = [[(1, 2)], [(4, 5)], [(1, 2, 3)], [(7, 8)]]
    sequences = ["a", "b", "a", "c"]
    times = [0.0, 0.0, 1.0, 0.0]
    with pytest.raises(ValueError, match=r"sequence 'b' has 1 annotated frame\(s\)"):
        partition_events(partitions, times=times, sequences=sequences)
    events = partition_events(partitions, times=times, sequences=sequences, skip_short=True)
    assert [(e.sequence, e.kind, e.group, e.frame, e.person) for e in events] == [
        ("a", JOINS, 1, 2, 3)
    ]
    assert (
        partition_tracks(partitions, times=times, sequences=sequences, skip_short=True).n_tracks
        == 1
    )
    assert partition_events([[(1, 2)]], times=[0.0], sequences="s", skip_short=True) == []


def test_partitions_need_one_time_and_sequence_each():
    with pytest.raises(ValueError, match=r"times must have shape \(2,\), one per partition"):
        partition_events([[(1, 2)], [(1, 2)]], times=[0.0], sequences="s")
    with pytest.raises(ValueError, match=r"sequences must be one name or one per partition \(2\)"):
        partition_events([[(1, 2)], [(1, 2)]], times=[0.0, 1.0], sequences=["s"])
    with pytest.raises(ValueError, match=r"times must be finite seconds, got nan at times\[1\]"):
        partition_events([[(1, 2)], [(1, 2)]], times=[0.0, float("nan")], sequences="s")
    with pytest.raises(ValueError, match=r"frames\[1\] \(sequence 's', time 0 s\) repeats"):
        partition_events([[(1, 2)], [(1, 2)]], times=[0.0, 0.0], sequences="s")


def test_events_come_back_from_json():
    frames = frames_of([(1, 2, 3, 4)], [(1, 2), (3, 4, 5)], [(1, 2, 3, 4, 5)], [(1, 2, 3, 4)], [])
    events = group_events(frames)
    assert {e.kind for e in events} == {SPLITS, MERGES, LEAVES, JOINS, DISSOLVES}
    assert [GroupEvent.from_json(json.loads(json.dumps(e.to_json()))) for e in events] == events


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"kind": "meets"}, r"kind must be one of \('forms'"),
        ({"group": "1"}, r"expected an integer, got '1'"),
        ({"members": [1, True]}, r"expected an integer, got True"),
        ({"part_tracks": [1]}, r"one track per part expected, got 0 parts and 1 tracks"),
    ],
    ids=["kind", "group", "member", "parts"],
)
def test_malformed_json_events_are_named(change, message):
    (event,) = group_events(frames_of([(1, 2)], [(1, 2, 3)]))
    with pytest.raises(ValueError, match=message):
        GroupEvent.from_json(event.to_json() | change)
    without = {k: v for k, v in event.to_json().items() if k != "time"}
    with pytest.raises(ValueError, match=r"no field 'time'"):
        GroupEvent.from_json(without)


@pytest.mark.parametrize(
    "times",
    [
        [0.0, 0.0, 1.0, 1.0, 2.0, 0.5],
        [0.0, 0.0, 1.0, 1.0, 1.0, 3.0],
        [0.0, 5.0, 1.0, 4.0, 0.5, 6.0],
    ],
    ids=["out of order", "repeated", "b before a"],
)
def test_partitions_out_of_time_order_are_refused_as_frames_are(times):
    sequences = ["a", "b", "a", "b", "a", "b"]  # interleaved
    frames = [
        line_frame(IDS, [(1, 2)], time=t, sequence=name)
        for t, name in zip(times, sequences, strict=True)
    ]
    with pytest.raises(ValueError) as by_frames:
        group_events(frames)
    with pytest.raises(ValueError) as by_partitions:
        partition_events([f.groups for f in frames], times=times, sequences=sequences)
    assert str(by_partitions.value) == str(by_frames.value)
