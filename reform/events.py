"""Groups in time: the events of a sequence of annotated frames, and the groups' identities.

A frame's groups are a partition of its people; only F-formations (groups of two or more) are
groups here, a person alone is in none. Between two consecutive annotated frames of one sequence
the F-formations change; this module names the change.

**Flows.** Between an F-formation ``A`` of the earlier frame and ``B`` of the later one the flow
is ``|A ∩ B|``. A flow of two or more people is a *group flow*: part of a conversation moved on
together. ``A``'s *successors* are the later F-formations it has a group flow into; ``B``'s
*predecessors* the earlier ones with a group flow into it. A flow of one is a person moving.

**Events**, each at the time of the later frame (the first frame showing the change):

* ``forms``: ``B`` has no predecessor (members: ``B``).
* ``dissolves``: ``A`` has no successor (members: ``A``). A pair losing one member dissolves.
* ``joins``: a person of ``B`` in none of its predecessors (``B`` has at least one), one event
  per person (members: ``B``, person: who joined).
* ``leaves``: a person of ``A`` in none of its successors (``A`` has at least one), one event
  per person, whether they stand alone now, joined another group or left the scene (members:
  ``A``, person: who left).
* ``merges``: ``B`` has two or more predecessors (members: ``B``; parts: the predecessors).
* ``splits``: ``A`` has two or more successors (members: ``A``; parts: the successors).

The rules depend on the flows alone, so a person who leaves one group and joins another gives
both a ``leaves`` and a ``joins`` event, and part of a group moving into another group is both a
split and a merge. Groups of a sequence's first annotated frame are there from its start (no
``forms``), and those of its last frame do not dissolve.

**Identity.** Every F-formation carries a track id, one identity over time. A later F-formation
continues the track of the earlier F-formation with which it shares the most members, provided
they share at least two (a group flow): the pairs ``(A, B)`` with a group flow are taken in
order of decreasing ``|A ∩ B|``, each ``A`` and ``B`` at most once. Ties go to the older track
(smaller id: in a merge of equals the older group goes on), then to the later F-formation
holding the smallest person id (in a split into equal parts, the part with the smallest id goes
on). Every other later F-formation starts a new track. Track ids count up from 1 over the whole
input, in order of first appearance, so a track id names one group in one sequence. An event's
``group`` is the track it concerns: the group formed, dissolved, joined, left, merged into (the
track that goes on), or split.

**Sequences.** Frames are taken sequence by sequence (`Frame.sequence`, in order of first
appearance; frames of different sequences may interleave); within a sequence the times must
increase strictly in the order given. Frames without ground truth are skipped: the events are
those between consecutive *annotated* frames, and a sequence needs two of them.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from reform.frame import Frame, Group, check_frames
from reform.json_values import json_record

__all__ = [
    "DISSOLVES",
    "EVENT_KINDS",
    "FORMS",
    "JOINS",
    "LEAVES",
    "MERGES",
    "SPLITS",
    "GroupEvent",
    "GroupTracks",
    "group_events",
    "partition_events",
    "partition_tracks",
    "track_groups",
]

FORMS = "forms"
DISSOLVES = "dissolves"
JOINS = "joins"
LEAVES = "leaves"
MERGES = "merges"
SPLITS = "splits"
EVENT_KINDS = (FORMS, DISSOLVES, JOINS, LEAVES, MERGES, SPLITS)  # also the order within a frame

# Shared members an earlier and a later F-formation need for the later to carry the earlier's
# identity: people.
MIN_CARRIED = 2

_KIND_ORDER = {kind: k for k, kind in enumerate(EVENT_KINDS)}


@dataclass(frozen=True)
class GroupEvent:
    """One change of the groups between two consecutive annotated frames of a sequence.

    Attributes:
        kind: one of :data:`EVENT_KINDS`.
        sequence: the sequence (recording, episode) it happened in.
        time: seconds, the time of the first frame showing the change.
        frame: index of that frame in the frames given.
        group: track id of the group concerned (see the module's description).
        members: the group's person ids, sorted: after the change for ``forms``, ``joins`` and
            ``merges``, before it for ``dissolves``, ``leaves`` and ``splits``.
        person: who joined or left, for ``joins`` and ``leaves``; None otherwise.
        parts: for ``merges`` the groups that merged (as they were before), for ``splits`` the
            groups it split into (as they are after), each sorted, ordered by track; else empty.
        part_tracks: the track id of each of ``parts``.
    """

    kind: str
    sequence: str
    time: float
    frame: int
    group: int
    members: Group
    person: int | None = None
    parts: tuple[Group, ...] = ()
    part_tracks: tuple[int, ...] = ()

    def to_json(self) -> dict[str, Any]:
        return json_record(self)

    @classmethod
    def from_json(cls, data: Any) -> GroupEvent:
        """The event :meth:`to_json` wrote (after a round trip through JSON text).

        Raises:
            ValueError: ``data`` is not such an object (a missing field, an unknown kind, a
                value of the wrong type), naming what is wrong.
        """
        try:
            kind = data["kind"]
            if kind not in EVENT_KINDS:
                raise ValueError(f"kind must be one of {EVENT_KINDS}, got {kind!r}")
            person = data.get("person")
            event = cls(
                kind=str(kind),
                sequence=str(data["sequence"]),
                time=float(data["time"]),
                frame=_int(data["frame"]),
                group=_int(data["group"]),
                members=tuple(_int(m) for m in data["members"]),
                person=None if person is None else _int(person),
                parts=tuple(tuple(_int(m) for m in part) for part in data.get("parts", ())),
                part_tracks=tuple(_int(t) for t in data.get("part_tracks", ())),
            )
        except KeyError as exc:
            raise ValueError(f"no field {exc} in {data!r}") from None
        except (TypeError, AttributeError) as exc:
            raise ValueError(f"{exc} in {data!r}") from None
        if len(event.parts) != len(event.part_tracks):
            raise ValueError(
                f"one track per part expected, got {len(event.parts)} parts and "
                f"{len(event.part_tracks)} tracks in {data!r}"
            )
        return event


def _int(value: Any) -> int:
    """``value`` if it is an int (not a bool), else a TypeError."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"expected an integer, got {value!r}")
    return value


@dataclass(frozen=True, eq=False)
class GroupTracks:
    """Tracked F-formations as spans: one row per stretch of consecutive annotated frames over
    which one track keeps the same members.

    Attributes:
        track: (n_spans,) int64 track id.
        sequence: n_spans sequence names.
        first: (n_spans,) int64 index (in the frames given) of the span's first frame.
        last: (n_spans,) int64 index of its last frame.
        start: (n_spans,) float64 time of its first frame, seconds.
        end: (n_spans,) float64 time of its last frame, seconds.
        members: n_spans groups of person ids, each sorted.
    """

    track: np.ndarray
    sequence: tuple[str, ...]
    first: np.ndarray
    last: np.ndarray
    start: np.ndarray
    end: np.ndarray
    members: tuple[Group, ...]

    def __post_init__(self) -> None:
        n = len(self.members)
        for name, dtype in (
            ("track", np.int64),
            ("first", np.int64),
            ("last", np.int64),
            ("start", np.float64),
            ("end", np.float64),
        ):
            array = np.array(getattr(self, name), dtype=dtype, copy=True)
            if array.shape != (n,):
                raise ValueError(f"{name} must have shape ({n},), got {array.shape}")
            array.flags.writeable = False
            object.__setattr__(self, name, array)
        if len(self.sequence) != n:
            raise ValueError(f"sequence must have {n} entries, got {len(self.sequence)}")

    def __len__(self) -> int:
        return len(self.members)

    @property
    def n_tracks(self) -> int:
        """Number of distinct tracks."""
        return int(np.unique(self.track).size)

    def at(self, index: int) -> dict[int, Group]:
        """Track id -> members of the F-formations of the frame ``index`` (of the frames given);
        empty for a frame outside every span."""
        rows = np.flatnonzero((self.first <= index) & (index <= self.last))
        return {int(self.track[r]): self.members[r] for r in rows}


@dataclass(frozen=True)
class _Sequence:
    """The annotated frames of one sequence: input indices, times and groups."""

    name: str
    index: np.ndarray  # (n,) int64 positions in the input
    time: np.ndarray  # (n,) float64 seconds
    groups: list[Any]  # n partitions (tuples of groups of person ids)


@dataclass
class _Tracking:
    """What following one sequence's F-formations gives: spans and events."""

    spans: list[tuple[int, str, int, int, float, float, Group]]
    events: list[GroupEvent]
    # Per change: (position in the sequence, {track: frozenset of members}); the F-formations
    # hold from that position to the next change's.
    states: list[tuple[int, dict[int, frozenset[int]]]]


def _where(frame: Frame, index: int, name: str = "frames") -> str:
    """``frames[3] (sequence 'a', time 1.5 s)``: a frame, as messages name it."""
    return f"{name}[{index}] (sequence {frame.sequence!r}, time {frame.time:g} s)"


def _split_sequences(frames: Sequence[Frame], *, caller: str) -> list[_Sequence]:
    """The annotated frames of each sequence, checked: times strictly increasing within each
    sequence, and at least two annotated frames in each.

    Raises:
        TypeError: if an entry is not a Frame.
        ValueError: for the first frame out of time order or at a repeated time (naming the
            sequence, both frames and both times), a sequence with fewer than two annotated
            frames, or no frames at all.
    """
    frames = check_frames(frames, caller=caller)
    if not frames:
        raise ValueError(f"{caller} needs frames: expected annotated frames, found none")
    last: dict[str, int] = {}
    for k, frame in enumerate(frames):
        before = last.get(frame.sequence)
        if before is not None and not frame.time > frames[before].time:
            raise _order_error(frame, k, before, frames[before].time)
        last[frame.sequence] = k
    chosen: dict[str, list[int]] = {}
    for k, frame in enumerate(frames):
        chosen.setdefault(frame.sequence, [])
        if frame.groups is not None:
            chosen[frame.sequence].append(k)
    out = []
    for name, rows in chosen.items():
        if len(rows) < 2:
            found = f"only frames[{rows[0]}]" if rows else "none"
            raise ValueError(
                f"sequence {name!r} has {len(rows)} annotated frame(s) ({found}): expected at "
                "least two to find events between"
            )
        out.append(
            _Sequence(
                name=name,
                index=np.array(rows, dtype=np.int64),
                time=np.array([frames[k].time for k in rows], dtype=np.float64),
                groups=[frames[k].groups for k in rows],
            )
        )
    return out


class _Row(NamedTuple):
    """A frame given by its sequence, time and groups (None: not annotated), as messages name
    it."""

    sequence: str
    time: float
    groups: Any


def _split_partitions(
    partitions: Iterable[Any], times: Any, sequences: Any, *, caller: str, skip_short: bool
) -> list[_Sequence]:
    """`_split_sequences` of partitions given with their times (seconds) and sequence names (one
    name for all, or one per partition), without an object per frame: the same sequences, the
    same refusals; with ``skip_short`` a sequence with fewer than two annotated frames is left
    out (it has no events) instead of refused."""
    partitions = list(partitions)
    n = len(partitions)
    time = np.asarray(times, dtype=np.float64)
    if time.shape != (n,):
        raise ValueError(
            f"{caller}: times must have shape ({n},), one per partition, got {time.shape}"
        )
    if not np.all(np.isfinite(time)):
        k = int(np.flatnonzero(~np.isfinite(time))[0])
        raise ValueError(f"{caller}: times must be finite seconds, got {time[k]} at times[{k}]")
    if isinstance(sequences, str):
        indices = {sequences: np.arange(n)} if n else {}
    else:
        names = np.array([str(name) for name in sequences], dtype=object)
        if names.shape != (n,):
            raise ValueError(
                f"{caller}: sequences must be one name or one per partition ({n}), got {names.size}"
            )
        indices = {name: np.flatnonzero(names == name) for name in dict.fromkeys(names.tolist())}
    if not n:
        raise ValueError(f"{caller} needs frames: expected annotated frames, found none")
    first_bad = None  # (k, before, sequence): the first frame, in the order given, out of order
    for name, index in indices.items():
        bad = np.flatnonzero(np.diff(time[index]) <= 0)
        if bad.size and (first_bad is None or index[bad[0] + 1] < first_bad[0]):
            first_bad = (int(index[bad[0] + 1]), int(index[bad[0]]), name)
    if first_bad is not None:
        k, before, name = first_bad
        raise _order_error(_Row(name, float(time[k]), None), k, before, float(time[before]))
    groups = _read_partitions(partitions)
    annotated = np.array([g is not None for g in groups], dtype=bool)
    out = []
    for name, index in indices.items():
        rows = index[annotated[index]]
        if rows.size < 2:
            if skip_short:
                continue
            found = f"only frames[{rows[0]}]" if rows.size else "none"
            raise ValueError(
                f"sequence {name!r} has {rows.size} annotated frame(s) ({found}): expected at "
                "least two to find events between"
            )
        out.append(
            _Sequence(
                name=name,
                index=rows.astype(np.int64),
                time=time[rows],
                groups=[groups[k] for k in rows.tolist()],
            )
        )
    return out


def _read_partitions(partitions: list[Any]) -> list[Any]:
    """Each partition as tuples of int ids (None stays None); one repeating the previous one is
    read once (and shared)."""
    out, last_raw, last = [], None, None
    for groups in partitions:
        if groups is not last_raw:
            if groups is None or last_raw is None or not _same(groups, last_raw):
                last = None if groups is None else tuple(tuple(int(m) for m in g) for g in groups)
            last_raw = groups
        out.append(last)
    return out


def _same(a: Any, b: Any) -> bool:
    """Whether two partitions are equal as given (False when they cannot be compared so, as
    arrays cannot)."""
    try:
        return bool(a == b)
    except (TypeError, ValueError):
        return False


def _order_error(frame: Any, k: int, before: int, earlier: float) -> ValueError:
    """The error for ``frame`` (``frames[k]``) at or before the time ``earlier`` of
    ``frames[before]``, the previous frame of its sequence."""
    if frame.time == earlier:
        return ValueError(
            f"{_where(frame, k)} repeats the time of frames[{before}] in sequence "
            f"{frame.sequence!r}: expected a time after {earlier:g} s, found {frame.time:g} s"
        )
    return ValueError(
        f"{_where(frame, k)} is out of time order in sequence {frame.sequence!r}: expected a "
        f"time after {earlier:g} s (frames[{before}]), found {frame.time:g} s"
    )


def _fformations(groups: Iterable[Iterable[int]]) -> list[frozenset[int]]:
    return [frozenset(g) for g in groups if len(g) >= MIN_CARRIED]


def _follow(sequence: _Sequence, next_track: int) -> tuple[_Tracking, int]:
    """Tracks and events of one sequence; new tracks are numbered from ``next_track``.

    Only frames whose F-formations differ from the previous annotated frame's are visited
    beyond a comparison of their groups.

    Returns:
        The tracking and the next unused track id.
    """
    index, time, name = sequence.index.tolist(), sequence.time.tolist(), sequence.name
    events: list[GroupEvent] = []
    states: list[tuple[int, dict[int, frozenset[int]]]] = []
    spans: list[tuple[int, str, int, int, float, float, Group]] = []
    opened: dict[int, int] = {}  # track -> position where its current span began
    prev: dict[int, frozenset[int]] = {}
    prev_raw: Any = None
    prev_set: frozenset[frozenset[int]] = frozenset()

    def close(track: int, members: frozenset[int], until: int) -> None:
        begin = opened.pop(track)
        spans.append(
            (
                track,
                name,
                index[begin],
                index[until],
                time[begin],
                time[until],
                tuple(sorted(members)),
            )
        )

    for pos, raw in enumerate(sequence.groups):
        if raw == prev_raw:
            continue
        prev_raw = raw
        current = _fformations(raw)
        current_set = frozenset(current)
        if pos and current_set == prev_set:
            continue
        prev_set = current_set
        current.sort(key=min)
        if pos == 0:
            now = {}
            for members in current:
                now[next_track] = members
                opened[next_track] = 0
                next_track += 1
            prev = now
            states.append((0, now))
            continue
        now, frame_events = _transition(prev, current, next_track, name, time[pos], index[pos])
        next_track += sum(1 for track in now if track not in prev)
        for track, members in prev.items():
            if now.get(track) != members:
                close(track, members, pos - 1)
        for track, members in now.items():
            if prev.get(track) != members:
                opened[track] = pos
        events.extend(frame_events)
        states.append((pos, now))
        prev = now
    end = len(index) - 1
    for track, members in prev.items():
        close(track, members, end)
    return _Tracking(spans=spans, events=events, states=states), next_track


def _transition(
    prev: dict[int, frozenset[int]],
    current: list[frozenset[int]],
    next_track: int,
    sequence: str,
    time: float,
    frame: int,
) -> tuple[dict[int, frozenset[int]], list[GroupEvent]]:
    """The tracks of ``current`` (sorted by smallest member) and the events from ``prev``."""
    successors: dict[int, list[int]] = {track: [] for track in prev}
    predecessors: list[list[int]] = [[] for _ in current]
    candidates = []
    for track, before in prev.items():
        for j, after in enumerate(current):
            shared = len(before & after)
            if shared >= MIN_CARRIED:
                successors[track].append(j)
                predecessors[j].append(track)
                candidates.append((-shared, track, j))  # j orders by smallest member
    candidates.sort()
    track_of: list[int | None] = [None] * len(current)
    taken: set[int] = set()
    for _, track, j in candidates:
        if track not in taken and track_of[j] is None:
            track_of[j] = track
            taken.add(track)
    for j in range(len(current)):
        if track_of[j] is None:
            track_of[j] = next_track
            next_track += 1
    now = {int(track_of[j]): current[j] for j in range(len(current))}  # type: ignore[arg-type]

    events = []

    def add(kind: str, group: int, members: frozenset[int], **extra: Any) -> None:
        events.append(
            GroupEvent(kind, sequence, time, frame, group, tuple(sorted(members)), **extra)
        )

    def parts(tracks: list[int], groups: dict[int, frozenset[int]]) -> dict[str, Any]:
        tracks = sorted(tracks)
        return {
            "parts": tuple(tuple(sorted(groups[t])) for t in tracks),
            "part_tracks": tuple(tracks),
        }

    for j, after in enumerate(current):
        track = int(track_of[j])  # type: ignore[arg-type]
        sources = predecessors[j]
        if not sources:
            add(FORMS, track, after)
            continue
        if len(sources) >= 2:
            add(MERGES, track, after, **parts(sources, prev))
        stayed = frozenset().union(*(prev[t] for t in sources))
        for person in sorted(after - stayed):
            add(JOINS, track, after, person=person)
    for track, before in prev.items():
        targets = successors[track]
        if not targets:
            add(DISSOLVES, track, before)
            continue
        if len(targets) >= 2:
            add(SPLITS, track, before, **parts([int(track_of[j]) for j in targets], now))  # type: ignore[arg-type]
        went = frozenset().union(*(current[j] for j in targets))
        for person in sorted(before - went):
            add(LEAVES, track, before, person=person)
    events.sort(key=lambda e: (_KIND_ORDER[e.kind], e.group, -1 if e.person is None else e.person))
    return now, events


def _track_all(
    frames: Sequence[Frame], *, caller: str, rows: list[_Sequence] | None = None
) -> tuple[list[_Sequence], list[_Tracking]]:
    """Every sequence of ``frames`` (or the sequences ``rows`` already split), checked, and its
    tracking."""
    sequences = _split_sequences(frames, caller=caller) if rows is None else rows
    out, next_track = [], 1
    for sequence in sequences:
        followed, next_track = _follow(sequence, next_track)
        out.append(followed)
    return sequences, out


def _spans_to_tracks(followed: Iterable[_Tracking]) -> GroupTracks:
    spans = sorted(
        (span for f in followed for span in f.spans), key=lambda s: (s[2], s[0])
    )  # by first frame, then track
    return GroupTracks(
        track=np.array([s[0] for s in spans], dtype=np.int64),
        sequence=tuple(s[1] for s in spans),
        first=np.array([s[2] for s in spans], dtype=np.int64),
        last=np.array([s[3] for s in spans], dtype=np.int64),
        start=np.array([s[4] for s in spans], dtype=np.float64),
        end=np.array([s[5] for s in spans], dtype=np.float64),
        members=tuple(s[6] for s in spans),
    )


def group_events(frames: Sequence[Frame]) -> list[GroupEvent]:
    """The events of the ground truth of ``frames``: groups forming, dissolving, merging and
    splitting, people joining and leaving (definitions in the module's description).

    Args:
        frames: the frames (a Dataset works too), sequence by sequence in time order; frames
            without ground truth are skipped.

    Returns:
        The events, sequence by sequence (in order of first appearance), in time order; within
        a frame by kind (in :data:`EVENT_KINDS` order), then track, then person.

    Raises:
        TypeError: if an entry is not a Frame.
        ValueError: before any work, for a frame out of time order or at a time its sequence
            already had, or a sequence with fewer than two annotated frames; the message names
            the sequence, the frame and what was expected.
    """
    _, followed = _track_all(frames, caller="group_events")
    return [event for f in followed for event in f.events]


def track_groups(frames: Sequence[Frame]) -> GroupTracks:
    """The identities of the ground truth's F-formations over time, as spans (see
    :class:`GroupTracks`; the rule is in the module's description).

    Args:
        frames: as for :func:`group_events`.

    Raises:
        TypeError, ValueError: as :func:`group_events`.
    """
    _, followed = _track_all(frames, caller="track_groups")
    return _spans_to_tracks(followed)


def partition_events(
    partitions: Iterable[Any],
    *,
    times: Any,
    sequences: str | Sequence[str],
    skip_short: bool = False,
) -> list[GroupEvent]:
    """:func:`group_events` of groups given without Frames: one partition per frame (groups of
    person ids, None where the frame is not annotated), with each frame's time and sequence.
    What a detector predicts, or a simulation's groups, gives its events so.

    Args:
        partitions: one partition (or None) per frame, sequence by sequence in time order.
        times: (n_frames,) seconds, each frame's time in its sequence.
        sequences: the sequence of every frame: one name for all, or one per frame.
        skip_short: leave out a sequence with fewer than two annotated frames (it has no
            events) instead of refusing it.

    Returns:
        The events, as :func:`group_events` gives them; ``frame`` indexes ``partitions``.

    Raises:
        ValueError: as :func:`group_events`, and for times or sequences not one per partition.
    """
    followed = _follow_partitions(
        partitions, times, sequences, caller="partition_events", skip_short=skip_short
    )
    return [event for f in followed for event in f.events]


def partition_tracks(
    partitions: Iterable[Any],
    *,
    times: Any,
    sequences: str | Sequence[str],
    skip_short: bool = False,
) -> GroupTracks:
    """:func:`track_groups` of groups given without Frames (arguments as for
    :func:`partition_events`)."""
    followed = _follow_partitions(
        partitions, times, sequences, caller="partition_tracks", skip_short=skip_short
    )
    return _spans_to_tracks(followed)


def _follow_partitions(
    partitions: Iterable[Any], times: Any, sequences: Any, *, caller: str, skip_short: bool
) -> list[_Tracking]:
    """The tracking of every sequence of partitions given with their times and sequences (one
    pass gives both the events and the tracks)."""
    split = _split_partitions(partitions, times, sequences, caller=caller, skip_short=skip_short)
    if not split:
        return []
    _, followed = _track_all((), caller=caller, rows=split)
    return followed
