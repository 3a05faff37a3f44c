"""Conversational groups on the floor: ground truth and each detector as its own entity tree.

``world/groups/<name>`` (``truth``, ``reform``, ``gcff``, ...), each toggleable on its own:

* ``members``: a flat disc under every person (a solid cylinder), coloured by their group
  (grey when alone), with the person id and the index of their group in the partition as extra
  components;
* ``centres``: each F-formation's o-space centre (the mean of its members' positions, as in
  Characterisation), labelled by its group;
* ``circles``: a ring around each centre whose radius is the group's Tightness (a flat open
  cylinder, one instance per group).

Groups are coloured through an annotation context (one class per group track): a group keeps its
colour from frame to frame while it keeps a majority of its members, and a detected group
matched to a true group of its frame (`reform.match_groups`: the one-to-one matching of largest
summed Jaccard index) takes that group's colour; unmatched groups take colours of their own.

For detectors, on annotated frames, mistakes are drawn under ``world/groups/<name>/mistakes``:
``missed`` (true F-formations no detected group matches, red rings), ``spurious`` (detected
F-formations that match no true group, magenta rings) and ``wrong_members`` (in a matched pair,
people the detected group added, ``extra``, or left out, ``missing``).

Partitions change seldom from one frame to the next, so the work is done once per distinct
partition and once per change, and spread over the frames with numpy.
"""

from __future__ import annotations

import functools
import itertools
import weakref
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import rerun as rr

from reform import T_TWO_THIRDS, Evaluation, Frame, Group, complete_partition, evaluate
from reform.matching import match_groups
from sim.recording import _colours
from sim.recording._columns import (
    FrameColumns,
    annotation_context,
    at_height,
    ragged_arange,
    send_rows,
    slices_equal,
    value_columns,
)
from sim.recording._timeline import Clock

__all__ = [
    "GROUPS_ROOT",
    "TRUTH",
    "GroupLayout",
    "LoggedGroups",
    "Stretches",
    "group_tracks",
    "log_groups",
    "stretches",
    "truth_partitions",
]

GROUPS_ROOT = "world/groups"
TRUTH = "truth"
MEMBER_RADIUS_M = 0.30  # metres: the truth's disc under a person
DISC_HEIGHT_M = 0.01  # metres: discs are flat solid cylinders
MEMBER_RADIUS_STEP_M = 0.07  # metres: each next tree's discs are smaller, so all stay visible
MIN_MEMBER_RADIUS_M = 0.08  # metres
CENTRE_RADIUS_M = 0.06  # metres
RING_HEIGHT_M = 0.02  # metres: circles are drawn as flat open cylinders (two rings)
RING_LINE_M = 0.01  # metres, line thickness
MIN_CIRCLE_M = 0.15  # metres: smallest circle drawn
MISTAKE_MARGIN_M = 0.25  # metres: mistake circles ring the group's circle
WRONG_MEMBER_Z_M = 0.35  # metres
WRONG_MEMBER_RADIUS_M = 0.12  # metres
TRUTH_Z_M = 0.01  # metres: height of the truth tree's drawings (layer 0)
LAYER_STEP_M = 0.02  # metres: each next tree (layer) is drawn this much higher
_DENSE_LOOKUP_CELLS = 4_000_000  # (frame, person) cells of a lookup table (32 MB of int64)

Partition = Sequence[Group]


@dataclass(frozen=True, eq=False)
class GroupLayout:
    """The groups of a run, flattened: one row per person, one row per F-formation.

    Attributes:
        counts: (n_frames,) people per frame with a partition (0 where none).
        person_frame, person_id, person_group: (n_people_rows,) frame index, person id and index
            of the person's group in that frame's partition.
        person_row: (n_people_rows,) the person's row in the run's columns.
        person_position: (n_people_rows, 2) metres.
        group_frame: (n_fformations,) frame index of each F-formation (two or more people).
        group_key: (n_fformations,) index of each F-formation's members in ``members_table``.
        group_set: (n_fformations,) index of each F-formation's member set in ``sets``.
        members_table: the distinct F-formations, as tuples of ids in the order given.
        sets: the distinct F-formations as sets of ids.
        group_centre: (n_fformations, 2) metres, mean of the members' positions.
        group_radius: (n_fformations,) metres, the group's Tightness.
        group_of_person: (n_people_rows,) row of the person's F-formation, -1 when alone.
    """

    counts: np.ndarray
    person_frame: np.ndarray
    person_id: np.ndarray
    person_group: np.ndarray
    person_row: np.ndarray
    person_position: np.ndarray
    group_frame: np.ndarray
    group_key: np.ndarray
    group_set: np.ndarray
    members_table: tuple[Group, ...]
    sets: tuple[frozenset[int], ...]
    group_centre: np.ndarray
    group_radius: np.ndarray
    group_of_person: np.ndarray

    @classmethod
    def of(
        cls,
        frames: Sequence[Frame] | FrameColumns,
        partitions: Sequence[Partition | None],
        *,
        what: str,
    ) -> GroupLayout:
        """Lays out ``partitions[i]`` (a full partition of frame ``i``'s ids, or None).

        Raises:
            ValueError: if there is not one partition per frame, or one is not a full
                partition of its frame's ids (naming ``what``, the frame and the person).
        """
        columns = FrameColumns.coerce(frames)
        n = len(columns)
        if len(partitions) != n:
            raise ValueError(
                f"{what} must hold one partition per frame: expected {n}, found {len(partitions)}"
            )
        table = _Patterns()
        pattern = table.index(partitions, columns, what)
        has = pattern >= 0
        with_partition = np.flatnonzero(has)
        kinds = pattern[has]
        size = table.size[kinds]
        person_frame = np.repeat(with_partition, size)
        pick = np.repeat(table.start[kinds], size) + ragged_arange(size)
        person_id = table.member[pick]
        rows = _locate(columns, person_frame, person_id)
        _check_partitions(columns, partitions, what, has, person_frame, rows)
        counts = np.zeros(n, dtype=np.int64)
        counts[with_partition] = size
        n_ff = table.n_ff[kinds]
        group_frame = np.repeat(with_partition, n_ff)
        ff_pick = np.repeat(table.ff_start[kinds], n_ff) + ragged_arange(n_ff)
        ff_counts = np.zeros(n, dtype=np.int64)
        ff_counts[with_partition] = n_ff
        first_ff = np.concatenate([[0], np.cumsum(ff_counts)])
        local_ff = table.member_ff[pick]
        group_of_person = np.where(local_ff >= 0, first_ff[person_frame] + local_ff, -1)
        person_position = columns.position[rows]
        n_groups = group_frame.size
        member = group_of_person >= 0
        group_size = np.bincount(group_of_person[member], minlength=n_groups).astype(np.float64)
        centre = np.zeros((n_groups, 2))
        radius = np.zeros(n_groups)
        if n_groups:
            for axis in (0, 1):
                centre[:, axis] = (
                    np.bincount(
                        group_of_person[member],
                        weights=person_position[member, axis],
                        minlength=n_groups,
                    )
                    / group_size
                )
            offset = person_position[member] - centre[group_of_person[member]]
            distance = np.sqrt(offset[:, 0] * offset[:, 0] + offset[:, 1] * offset[:, 1])
            radius = (
                np.bincount(group_of_person[member], weights=distance, minlength=n_groups)
                / group_size
            )
        return cls(
            counts=counts,
            person_frame=person_frame,
            person_id=person_id,
            person_group=table.member_group[pick],
            person_row=rows,
            person_position=person_position,
            group_frame=group_frame,
            group_key=table.ff_key[ff_pick],
            group_set=table.ff_set[ff_pick],
            members_table=tuple(table.members),
            sets=tuple(table.sets),
            group_centre=centre,
            group_radius=radius,
            group_of_person=group_of_person,
        )

    @classmethod
    def truth(cls, frames: Sequence[Frame] | FrameColumns) -> GroupLayout:
        """The ground truth's layout (each annotated frame's full partition), worked out once
        per columns object."""
        columns = FrameColumns.coerce(frames)
        layout = _TRUTH_LAYOUTS.get(columns)
        if layout is None:
            layout = cls.of(columns, truth_partitions(columns), what=f"{TRUTH} partitions")
            _TRUTH_LAYOUTS[columns] = layout
        return layout

    @functools.cached_property
    def group_members(self) -> tuple[Group, ...]:
        """The members of each F-formation, tuples of ids."""
        table = self.members_table
        return tuple(table[k] for k in self.group_key.tolist())

    @functools.cached_property
    def group_counts(self) -> np.ndarray:
        """(n_frames,) F-formations per frame."""
        return np.bincount(self.group_frame, minlength=self.counts.size).astype(np.int64)

    @functools.cached_property
    def group_starts(self) -> np.ndarray:
        """(n_frames + 1,) first F-formation row of each frame, then the row count."""
        return np.concatenate([[0], np.cumsum(self.group_counts)]).astype(np.int64)

    @functools.cached_property
    def group_size(self) -> np.ndarray:
        """(n_fformations,) people per F-formation."""
        sizes = np.fromiter(map(len, self.members_table), dtype=np.int64)
        return sizes[self.group_key]

    @functools.cached_property
    def group_person_start(self) -> np.ndarray:
        """(n_fformations,) first person row of each F-formation (its members are adjacent)."""
        member = np.flatnonzero(self.group_of_person >= 0)
        rows = np.searchsorted(self.group_of_person[member], np.arange(self.group_frame.size))
        return member[rows]


# Columns -> the layout of their ground truth (the truth tree and every detector's mistakes use
# it); columns are immutable, and an entry goes when its columns do.
_TRUTH_LAYOUTS: weakref.WeakKeyDictionary[FrameColumns, GroupLayout] = weakref.WeakKeyDictionary()


class _Patterns:
    """The distinct partitions of a run, each flattened once."""

    def __init__(self) -> None:
        self.members: list[Group] = []  # distinct F-formations (ordered)
        self.sets: list[frozenset[int]] = []  # distinct F-formations (as sets)
        self._key_of: dict[Group, int] = {}
        self._set_of: dict[frozenset[int], int] = {}
        self._parts: list[tuple[list[int], list[int], list[int], list[int], list[int]]] = []

    def index(
        self, partitions: Sequence[Partition | None], columns: FrameColumns, what: str
    ) -> np.ndarray:
        """(n_frames,) int64 the pattern of each frame's partition, -1 where none; then the
        flattened patterns are in ``member``, ``member_group``, ``member_ff``, ``start``,
        ``size``, ``ff_key``, ``ff_set``, ``ff_start``, ``n_ff``."""
        n = len(partitions)

        def pairs() -> Any:  # each partition with the next, afresh on every call
            return zip(partitions, itertools.islice(partitions, 1, None), strict=False)

        try:  # where each partition differs from the one before: one pass, in bulk
            same = np.fromiter(
                (a is b or (a == b) is True for a, b in pairs()), dtype=bool, count=max(n - 1, 0)
            )
        except (TypeError, ValueError):  # partitions holding arrays: compare one by one
            same = np.array([_equal(a, b) for a, b in pairs()], dtype=bool).reshape(-1)
        changes = np.flatnonzero(np.concatenate([[True], ~same])) if n else np.zeros(0, int)
        known: dict[Any, int] = {}
        kinds = []
        for f in changes.tolist():
            partition = partitions[f]
            if partition is None:
                kinds.append(-1)
                continue
            try:
                kind = known.get(partition, -1)
                hashable = True
            except TypeError:  # lists, arrays: keyed by their canonical form
                kind, hashable = -1, False
            if kind < 0:
                canonical = _canonical(partition, what, f, columns)
                kind = known.get(canonical, -1)
                if kind < 0:
                    kind = known[canonical] = self._add(canonical)
                if hashable:
                    known[partition] = kind
            kinds.append(kind)
        pattern = np.asarray(kinds, dtype=np.int64)[
            np.searchsorted(changes, np.arange(n), side="right") - 1
        ]
        self._flatten()
        return pattern

    def _add(self, partition: tuple[Group, ...]) -> int:
        member: list[int] = []
        member_group: list[int] = []
        member_ff: list[int] = []
        ff_key: list[int] = []
        ff_set: list[int] = []
        for gi, group in enumerate(partition):
            ff = -1
            if len(group) >= 2:
                ff = len(ff_key)
                key = self._key_of.get(group)
                if key is None:
                    key = self._key_of[group] = len(self.members)
                    self.members.append(group)
                as_set = frozenset(group)
                index = self._set_of.get(as_set)
                if index is None:
                    index = self._set_of[as_set] = len(self.sets)
                    self.sets.append(as_set)
                ff_key.append(key)
                ff_set.append(index)
            member.extend(group)
            member_group.extend([gi] * len(group))
            member_ff.extend([ff] * len(group))
        self._parts.append((member, member_group, member_ff, ff_key, ff_set))
        return len(self._parts) - 1

    def _flatten(self) -> None:
        def joined(k: int) -> np.ndarray:
            return np.array([v for part in self._parts for v in part[k]], dtype=np.int64)

        self.member, self.member_group, self.member_ff = joined(0), joined(1), joined(2)
        self.ff_key, self.ff_set = joined(3), joined(4)
        self.size = np.array([len(p[0]) for p in self._parts], dtype=np.int64)
        self.n_ff = np.array([len(p[3]) for p in self._parts], dtype=np.int64)
        self.start = np.concatenate([[0], np.cumsum(self.size)[:-1]]).astype(np.int64)
        self.ff_start = np.concatenate([[0], np.cumsum(self.n_ff)[:-1]]).astype(np.int64)


def _equal(a: Any, b: Any) -> bool:
    """``a == b`` for partitions, False where the comparison is not a plain truth value."""
    try:
        return (a == b) is True
    except (TypeError, ValueError):
        return False


def _canonical(partition: Partition, what: str, f: int, columns: FrameColumns) -> tuple[Group, ...]:
    groups = tuple(tuple(map(int, group)) for group in partition)
    for gi, group in enumerate(groups):
        if not group:
            raise ValueError(f"{_where(what, f, columns)}: group {gi} is empty")
    return groups


def truth_partitions(columns: FrameColumns) -> list[tuple[Group, ...] | None]:
    """Each frame's ground truth as a full partition (None where not annotated); consecutive
    frames with the same people and groups share one partition object."""
    same_people = columns.same_people_as_previous()
    out: list[tuple[Group, ...] | None] = [None] * len(columns)
    last_frame = -2
    last_groups: Any = None
    last: tuple[Group, ...] | None = None
    for f, groups in enumerate(columns.groups):
        if groups is None:
            continue
        if not (
            last_frame == f - 1
            and same_people[f]
            and (groups is last_groups or groups == last_groups)
        ):
            last = complete_partition(groups, columns.ids_of(f).tolist())
            last_groups = groups
        out[f] = last
        last_frame = f
    return out


@dataclass(frozen=True, eq=False)
class LoggedGroups:
    """What :func:`log_groups` drew.

    Attributes:
        layout: the groups, flattened.
        tracks: (n_fformations,) each F-formation's track (its colour class).
        columns: the frames the groups belong to.
        rows: (n_frames,) each frame's row on the run's clock.
        evaluation: for a detector's tree on frames with ground truth, its evaluation.
    """

    layout: GroupLayout
    tracks: np.ndarray
    columns: FrameColumns
    rows: np.ndarray
    evaluation: Evaluation | None = None


def _locate(columns: FrameColumns, member_frame: np.ndarray, member_id: np.ndarray) -> np.ndarray:
    """(n,) int64 row of each (frame, person id) in the columns, -1 when absent."""
    known = columns.known_ids
    rows = np.full(member_id.size, -1, dtype=np.int64)
    if known.size == 0 or member_id.size == 0:
        return rows
    rank = np.minimum(np.searchsorted(known, member_id), known.size - 1)
    found = known[rank] == member_id
    n_frames = len(columns)
    if n_frames * known.size <= _DENSE_LOOKUP_CELLS:
        table = np.full((n_frames, known.size), -1, dtype=np.int64)
        table[columns.frame, np.searchsorted(known, columns.ids)] = np.arange(columns.ids.size)
        rows[found] = table[member_frame[found], rank[found]]
        return rows
    key = columns.frame * known.size + np.searchsorted(known, columns.ids)
    order = np.argsort(key, kind="stable")
    wanted = member_frame * known.size + rank
    at = np.minimum(np.searchsorted(key[order], wanted), key.size - 1)
    found &= key[order][at] == wanted
    rows[found] = order[at[found]]
    return rows


def _check_partitions(
    columns: FrameColumns,
    partitions: Sequence[Partition | None],
    what: str,
    has_partition: np.ndarray,
    member_frame: np.ndarray,
    rows: np.ndarray,
) -> None:
    """Raises for the first frame whose partition names a stranger, someone twice, or misses
    someone."""
    n = len(columns)
    expected = np.where(has_partition, columns.counts, 0)
    covered = np.bincount(rows[rows >= 0], minlength=columns.ids.size)
    per_frame = np.bincount(member_frame, minlength=n)
    bad = np.zeros(n, dtype=bool)
    bad[member_frame[rows < 0]] = True
    bad[columns.frame[covered > 1]] = True
    bad |= per_frame != expected
    if not np.any(bad):
        return
    f = int(np.flatnonzero(bad)[0])
    ids = columns.ids_of(f).tolist()
    present = set(ids)
    seen: set[int] = set()
    for gi, group in enumerate(partitions[f]):
        for m in (int(x) for x in group):
            if m not in present or m in seen:
                problem = "appears twice" if m in seen else "is not in the frame"
                raise ValueError(
                    f"{_where(what, f, columns)}: person {m} (group {gi}) {problem}; "
                    f"expected a full partition of ids {ids}"
                )
            seen.add(m)
    missing = next(i for i in ids if i not in seen)
    raise ValueError(
        f"{_where(what, f, columns)}: person {missing} is in no group; "
        "expected a full partition of the frame's ids, singletons included"
    )


def _where(what: str, index: int, columns: FrameColumns) -> str:
    return f"{what}[{index}] ({columns.describe(index)})"


@dataclass(frozen=True, eq=False)
class Stretches:
    """Where a run's F-formations change.

    Attributes:
        processed: (m,) int64 the frames with a partition.
        previous: (m,) int64 the processed frame before each in its sequence, -1 for none.
        fresh: (m,) bool, False where a frame holds the F-formations of its previous one, in
            the same order and with the same imposed tracks (its tracks are then the previous
            frame's).
        head: (n_frames,) int64 for each processed frame, the fresh frame whose F-formations it
            repeats (itself when fresh); -1 elsewhere.
    """

    processed: np.ndarray
    previous: np.ndarray
    fresh: np.ndarray
    head: np.ndarray

    def changes(self) -> Iterator[tuple[int, int]]:
        """Each fresh frame in order, with the fresh frame whose F-formations the frame before
        it holds (-1 at the start of a sequence)."""
        for i in np.flatnonzero(self.fresh).tolist():
            p = int(self.previous[i])
            yield int(self.processed[i]), int(self.head[p]) if p >= 0 else -1


def stretches(
    layout: GroupLayout, segment: np.ndarray, fixed: np.ndarray | None = None
) -> Stretches:
    """Where the F-formations of ``layout`` change.

    Args:
        layout: the groups.
        segment: (n_frames,) index of each frame's run of consecutive frames of one sequence.
        fixed: (n_fformations,) a track imposed on each F-formation, -1 for none.
    """
    processed = np.flatnonzero(layout.counts > 0)
    previous = np.full(processed.size, -1, dtype=np.int64)
    if processed.size > 1:
        same_segment = segment[processed[1:]] == segment[processed[:-1]]
        previous[1:] = np.where(same_segment, processed[:-1], -1)
    fresh = np.ones(processed.size, dtype=bool)
    follow = np.flatnonzero(previous >= 0)
    if follow.size:
        now, before = processed[follow], previous[follow]
        starts = layout.group_starts
        same = slices_equal(layout.group_set, starts, now, before)
        if fixed is not None:
            same &= slices_equal(fixed, starts, now, before)
        fresh[follow] = ~same
    head = np.full(layout.counts.size, -1, dtype=np.int64)
    if processed.size:
        last_fresh = np.maximum.accumulate(np.where(fresh, np.arange(processed.size), 0))
        head[processed] = processed[last_fresh]
    return Stretches(processed=processed, previous=previous, fresh=fresh, head=head)


def group_tracks(
    layout: GroupLayout,
    segment: np.ndarray,
    *,
    fixed: np.ndarray | None = None,
    first_track: int = 1,
) -> np.ndarray:
    """(n_fformations,) track id of each F-formation: stable while a group keeps a majority.

    An F-formation continues the track of a group of the previous frame with a partition (same
    sequence) when each holds more than half of the larger one (``2·|A∩B| > max(|A|, |B|)``,
    so the match is unique); otherwise it starts a new track. Frames without a partition keep
    the tracks alive across the gap.

    Args:
        layout: the groups.
        segment: (n_frames,) index of each frame's run of consecutive frames of one sequence
            (``FrameColumns.segment``).
        fixed: (n_fformations,) tracks imposed on some F-formations (-1 elsewhere), e.g. a
            detected group takes the track of the true group it matches.
        first_track: the first new track's id.
    """
    n_ff = layout.group_frame.size
    fixed = np.full(n_ff, -1, dtype=np.int64) if fixed is None else np.asarray(fixed, np.int64)
    tracks = np.zeros(n_ff, dtype=np.int64)
    next_track = max(first_track, int(fixed.max(initial=-1)) + 1)
    runs = stretches(layout, segment, fixed)
    starts = layout.group_starts.tolist()
    sets, group_set, imposed = layout.sets, layout.group_set.tolist(), fixed.tolist()
    state: dict[int, list[tuple[frozenset[int], int]]] = {-1: []}
    for f, before_frame in runs.changes():
        before = state[before_frame]
        rows = range(starts[f], starts[f + 1])
        used = {imposed[r] for r in rows if imposed[r] >= 0}
        current: list[tuple[frozenset[int], int]] = []
        for r in rows:
            members = sets[group_set[r]]
            track = imposed[r] if imposed[r] >= 0 else _continued(members, before, used)
            if track is None:
                track = next_track
                next_track += 1
            used.add(track)
            tracks[r] = track
            current.append((members, track))
        state[f] = current
    repeat = runs.processed[~runs.fresh]
    if repeat.size:
        lengths = layout.group_counts[repeat]
        local = ragged_arange(lengths)
        source = np.repeat(layout.group_starts[runs.head[repeat]], lengths) + local
        tracks[np.repeat(layout.group_starts[repeat], lengths) + local] = tracks[source]
    return tracks


def _continued(
    members: frozenset[int], before: list[tuple[frozenset[int], int]], used: set[int]
) -> int | None:
    """The track of the first group of ``before`` (members, track) whose track is not ``used``
    and that shares a strict majority of the larger group with ``members``; None for none."""
    for old, track in before:
        if track not in used and 2 * len(members & old) > max(len(members), len(old)):
            return track
    return None


@dataclass(frozen=True, eq=False)
class _Matches:
    """A detector's F-formations against the true ones, on the evaluated frames.

    Attributes:
        evaluated: (n_frames,) bool, frames the evaluation scored.
        true_matched: (n_true,) bool, true F-formation matched at T = 2/3.
        detected_matched: (n_detected,) bool, detected F-formation matched a true one.
        pair_detected, pair_true: (n_pairs,) every (detected, true) F-formation pair of an
            evaluated frame, detected-major.
        overlap: (n_pairs,) shared members of each pair.
    """

    evaluated: np.ndarray
    true_matched: np.ndarray
    detected_matched: np.ndarray
    pair_detected: np.ndarray
    pair_true: np.ndarray
    overlap: np.ndarray


def _present_truth(columns: FrameColumns) -> list[Frame] | None:
    """The frames with their ground truth as drawn, over the people present, where an
    annotation names someone absent (`reform.Frame.listed_groups`: the evaluation scores the
    group as listed, the drawing can show only who is there); None when none does."""
    frames = columns.frames
    if frames is None or all(f.listed_groups is None for f in frames):
        return None
    return [f if f.listed_groups is None else f.replace(listed_groups=None) for f in frames]


def _matches(evaluation: Evaluation, layout: GroupLayout, truth: GroupLayout) -> _Matches:
    """Which groups matched at T = 2/3, read from the evaluation's records."""
    k = evaluation.thresholds.index(T_TWO_THIRDS)
    n = layout.counts.size
    scored = np.asarray(evaluation.frame_index, dtype=np.int64)
    outside = np.flatnonzero((scored < 0) | (scored >= n))
    if outside.size:
        raise ValueError(
            f"evaluation does not belong to these frames: it scores frame "
            f"{int(scored[outside[0]])}, expected one of {n}"
        )
    true_counts = np.bincount(evaluation.true_frame, minlength=scored.size)
    detected_counts = np.bincount(evaluation.detected_frame, minlength=scored.size)
    ours_true = truth.group_counts[scored]
    ours_detected = layout.group_counts[scored]
    bad = np.flatnonzero((true_counts != ours_true) | (detected_counts != ours_detected))
    if bad.size:
        r = int(bad[0])
        raise ValueError(
            f"evaluation does not belong to these frames and partitions (frame {scored[r]}: "
            f"{ours_true[r]} true and {ours_detected[r]} detected F-formations, evaluation has "
            f"{true_counts[r]} and {detected_counts[r]})"
        )
    evaluated = np.zeros(n, dtype=bool)
    evaluated[scored] = True
    true_matched = np.zeros(truth.group_frame.size, dtype=bool)
    true_matched[evaluated[truth.group_frame]] = evaluation.true_matched[k]
    detected_matched = np.zeros(layout.group_frame.size, dtype=bool)
    detected_matched[evaluated[layout.group_frame]] = evaluation.detected_matched[k]
    # Every (detected, true) pair of an evaluated frame, and how many members they share.
    n_detected = layout.group_counts[scored]
    n_true = truth.group_counts[scored]
    n_pairs = n_detected * n_true
    local = ragged_arange(n_pairs)
    width = np.repeat(n_true, n_pairs)
    pair_detected = np.repeat(layout.group_starts[scored], n_pairs) + local // np.maximum(width, 1)
    pair_true = np.repeat(truth.group_starts[scored], n_pairs) + local % np.maximum(width, 1)
    n_sets = max(len(truth.sets), 1)
    cell = layout.group_set[pair_detected] * n_sets + truth.group_set[pair_true]
    cells, inverse = np.unique(cell, return_inverse=True)
    shared = np.array(
        [len(layout.sets[c // n_sets] & truth.sets[c % n_sets]) for c in cells.tolist()],
        dtype=np.int64,
    )
    return _Matches(
        evaluated=evaluated,
        true_matched=true_matched,
        detected_matched=detected_matched,
        pair_detected=pair_detected,
        pair_true=pair_true,
        overlap=shared[inverse.reshape(-1)] if cells.size else np.zeros(0, dtype=np.int64),
    )


def log_groups(
    rec: rr.RecordingStream,
    frames: Sequence[Frame] | FrameColumns,
    partitions: Sequence[Partition | None] | None = None,
    *,
    name: str = TRUTH,
    clock: Clock | None = None,
    evaluation: Evaluation | None = None,
    truth: LoggedGroups | None = None,
    layer: int | None = None,
    first_track: int | None = None,
) -> LoggedGroups:
    """Logs one entity tree of groups, ``world/groups/<name>``, for a finished run.

    Args:
        rec: the recording stream.
        frames: the frames the groups belong to (positions are drawn from them), in time order,
            as ``reform.Frame`` objects or :class:`FrameColumns`.
        partitions: one full partition per frame (None where unknown); default: the frames'
            ground truth (None for frames without).
        name: the tree's name, ``"truth"`` or a detector's (``"reform"``, ``"gcff"``).
        clock: the run's clock; default: the clock of ``frames``.
        evaluation: ``reform.evaluate(frames, partitions)``, for the mistakes and the colours
            of matched groups; computed here when None and the frames carry ground truth.
        truth: the truth tree's :func:`log_groups` result, so that a detected group matched
            to a true group of its frame (`reform.match_groups`: the one-to-one matching of
            largest summed Jaccard index) shares its colour.
        layer: stacking order of the tree: 0 (truth, default for it) is drawn lowest with the
            largest discs, each next layer higher with smaller discs (default for detectors: 1;
            give the k-th detector k + 1).
        first_track: the first track (colour class) of groups no true group matches; default:
            one past the truth's. Give each detector one past the previous trees' tracks so
            that unmatched groups of different detectors never share a colour.

    Returns:
        What was drawn (pass the truth tree's as ``truth`` to the detectors' calls).

    Raises:
        ValueError: if a partition is not a full partition of its frame's ids (naming the
            frame and the person) or a frame matches no frame of ``clock``.
    """
    columns = FrameColumns.coerce(frames)
    clock = Clock.from_columns(columns) if clock is None else clock
    rows = clock.rows_of_columns(columns)
    is_truth = partitions is None
    if is_truth:
        layout = GroupLayout.truth(columns)
    else:
        layout = GroupLayout.of(columns, partitions, what=f"{name} partitions")
    layer = (0 if is_truth else 1) if layer is None else int(layer)
    if layer < 0:
        raise ValueError(f"layer must be >= 0, got {layer}")
    z = TRUTH_Z_M + layer * LAYER_STEP_M
    disc = max(MEMBER_RADIUS_M - layer * MEMBER_RADIUS_STEP_M, MIN_MEMBER_RADIUS_M)
    root = f"{GROUPS_ROOT}/{name}"

    fixed = None
    matches = None
    true_layout = None
    if not is_truth:
        if evaluation is None and any(g is not None for g in columns.groups):
            if columns.frames is None:
                raise ValueError(
                    f"scoring {name} needs the frames it ran on: pass evaluation=, or columns "
                    "made with FrameColumns.of(frames)"
                )
            evaluation = evaluate(columns.frames, partitions)
        if evaluation is not None:
            drawn = _present_truth(columns)  # matched against the truth drawn, scored as listed
            matched = evaluation if drawn is None else evaluate(drawn, partitions)
            true_layout = GroupLayout.truth(columns)
            matches = _matches(matched, layout, true_layout)
    if not is_truth and truth is not None:
        fixed = _inherit_tracks(layout, rows, truth)
    if first_track is None:
        first_track = 1 if truth is None else int(truth.tracks.max(initial=0)) + 1
    tracks = group_tracks(layout, columns.segment, fixed=fixed, first_track=first_track)

    n_tracks = int(tracks.max(initial=0))
    label = "group" if is_truth else f"{name} group"
    rec.log(
        root,
        annotation_context(
            [(0, "alone", _colours.SINGLETON)]
            + [(t, f"{label} {t}", _colours.group_colour(t)) for t in range(1, n_tracks + 1)]
        ),
        static=True,
    )
    times = clock.columns(rows)
    person_class = np.append(tracks, 0)[layout.group_of_person]  # -1 (alone) picks the 0
    _send_cylinders(
        rec,
        f"{root}/members",
        times,
        layout.counts,
        centres=layout.person_position,
        z=z,
        height=DISC_HEIGHT_M,
        fill_mode=rr.components.FillMode.Solid,
        radius=disc,
        show_labels=False,
        class_ids=person_class.astype(np.uint16),
        extra=value_columns(
            layout.counts, person_id=layout.person_id, group_index=layout.person_group
        ),
    )
    group_class = tracks.astype(np.uint16)
    send_rows(
        rec,
        f"{root}/centres",
        rr.Points3D.from_fields(radii=[CENTRE_RADIUS_M], show_labels=False),
        times,
        rr.Points3D.columns(
            positions=at_height(layout.group_centre, z + 0.005), class_ids=group_class
        ).partition(layout.group_counts),
    )
    _send_cylinders(
        rec,
        f"{root}/circles",
        times,
        layout.group_counts,
        centres=layout.group_centre,
        z=z + RING_HEIGHT_M / 2,
        height=RING_HEIGHT_M,
        fill_mode=rr.components.FillMode.MajorWireframe,
        radii=np.maximum(layout.group_radius, MIN_CIRCLE_M),
        line_radius=RING_LINE_M,
        show_labels=False,
        class_ids=group_class,
    )
    if matches is not None:
        _log_mistakes(rec, root, layout, true_layout, matches, times, z=z)
    return LoggedGroups(
        layout=layout,
        tracks=tracks,
        columns=columns,
        rows=rows,
        evaluation=evaluation,
    )


def _inherit_tracks(layout: GroupLayout, rows: np.ndarray, truth: LoggedGroups) -> np.ndarray:
    """(n_fformations,) for each detected F-formation matched to an F-formation of the truth
    tree at the same clock row (`reform.match_groups`: largest summed Jaccard index, one to
    one), that group's track; -1 elsewhere.

    The truth tree may hold more people than the detector saw (the world's frames against the
    robot's view): a detected group matches the true group it overlaps most, seen or not.
    """
    fixed = np.full(layout.group_frame.size, -1, dtype=np.int64)
    tree = truth.layout
    if not layout.group_frame.size or not tree.group_frame.size:
        return fixed
    truth_frame = np.full(int(max(rows.max(initial=-1), truth.rows.max(initial=-1))) + 1, -1)
    truth_frame[truth.rows] = np.arange(truth.rows.size)
    starts, tree_starts = layout.group_starts.tolist(), tree.group_starts.tolist()
    group_set, tree_set = layout.group_set.tolist(), tree.group_set.tolist()
    tracks = truth.tracks.tolist()
    known: dict[tuple[tuple[int, ...], tuple[int, ...]], list[int | None]] = {}
    for f in np.flatnonzero(layout.group_counts).tolist():
        t = int(truth_frame[rows[f]]) if rows[f] >= 0 else -1
        if t < 0 or tree_starts[t] == tree_starts[t + 1]:
            continue
        mine = tuple(group_set[starts[f] : starts[f + 1]])
        theirs = tuple(tree_set[tree_starts[t] : tree_starts[t + 1]])
        matched = known.get((mine, theirs))
        if matched is None:
            matched = known[(mine, theirs)] = match_groups(
                [tree.sets[k] for k in theirs], [layout.sets[k] for k in mine]
            )
        for k, j in enumerate(matched):
            if j is not None:
                fixed[starts[f] + k] = tracks[tree_starts[t] + j]
    return fixed


def _log_mistakes(
    rec: rr.RecordingStream,
    root: str,
    layout: GroupLayout,
    true_layout: GroupLayout,
    matches: _Matches,
    times: list[rr.TimeColumn],
    *,
    z: float,
) -> None:
    n = layout.counts.size
    d, t, shared = matches.pair_detected, matches.pair_true, matches.overlap
    same = (shared == layout.group_size[d]) & (shared == true_layout.group_size[t])
    exact = np.zeros(true_layout.group_frame.size, dtype=bool)
    exact[t[same]] = True
    scored = matches.evaluated[true_layout.group_frame]
    missed = np.flatnonzero(scored & ~matches.true_matched)
    wrong = np.flatnonzero(scored & matches.true_matched & ~exact)
    # Each wrongly matched true group's partner: the detected group sharing most members (the
    # first such in the partition's order).
    order = np.lexsort((d, -shared, t))
    first_true, first = np.unique(t[order], return_index=True)
    partner_of = np.full(true_layout.group_frame.size, -1, dtype=np.int64)
    partner_of[first_true] = d[order][first]
    partner = partner_of[wrong]

    # The people the partner added (extra) or left out (missing), per wrong group, sorted.
    n_rows = max(
        int(layout.person_row.max(initial=-1)), int(true_layout.person_row.max(initial=-1))
    )
    true_group_of_row = np.full(n_rows + 1, -1, dtype=np.int64)
    true_group_of_row[true_layout.person_row] = true_layout.group_of_person
    detected_group_of_row = np.full(n_rows + 1, -1, dtype=np.int64)
    detected_group_of_row[layout.person_row] = layout.group_of_person
    extra_size = layout.group_size[partner]
    extra_owner = np.repeat(np.arange(wrong.size), extra_size)
    extra_at = np.repeat(layout.group_person_start[partner], extra_size) + ragged_arange(extra_size)
    keep = true_group_of_row[layout.person_row[extra_at]] != wrong[extra_owner]
    extra_owner, extra_at = extra_owner[keep], extra_at[keep]
    missing_size = true_layout.group_size[wrong]
    missing_owner = np.repeat(np.arange(wrong.size), missing_size)
    missing_at = np.repeat(true_layout.group_person_start[wrong], missing_size) + ragged_arange(
        missing_size
    )
    keep = detected_group_of_row[true_layout.person_row[missing_at]] != partner[missing_owner]
    missing_owner, missing_at = missing_owner[keep], missing_at[keep]
    owner = np.concatenate([extra_owner, missing_owner])
    kind = np.concatenate(
        [np.zeros(extra_owner.size, np.int64), np.ones(missing_owner.size, np.int64)]
    )
    person = np.concatenate([layout.person_id[extra_at], true_layout.person_id[missing_at]])
    position = np.concatenate(
        [layout.person_position[extra_at], true_layout.person_position[missing_at]]
    ).reshape(-1, 2)
    order = np.lexsort((person, kind, owner))
    owner, kind, person, position = owner[order], kind[order], person[order], position[order]
    cells, inverse = np.unique(person * 2 + kind, return_inverse=True)
    names = [f"{('extra', 'missing')[c & 1]} {c >> 1}" for c in cells.tolist()]
    wrong_label = [names[k] for k in inverse.reshape(-1).tolist()]
    wrong_colour = np.array([_colours.EXTRA_MEMBER, _colours.MISSING_MEMBER], dtype=np.uint8)[kind]
    wrong_counts = np.bincount(true_layout.group_frame[wrong[owner]], minlength=n).astype(np.int64)

    spurious = np.flatnonzero(~matches.detected_matched & matches.evaluated[layout.group_frame])
    for kind, where, picked, colour in (
        ("missed", true_layout, missed, _colours.MISSED),
        ("spurious", layout, spurious, _colours.SPURIOUS),
    ):
        _send_cylinders(
            rec,
            f"{root}/mistakes/{kind}",
            times,
            np.bincount(where.group_frame[picked], minlength=n).astype(np.int64),
            centres=where.group_centre[picked],
            z=z + RING_HEIGHT_M,
            height=RING_HEIGHT_M,
            fill_mode=rr.components.FillMode.MajorWireframe,
            radii=np.maximum(where.group_radius[picked], MIN_CIRCLE_M) + MISTAKE_MARGIN_M,
            line_radius=2 * RING_LINE_M,
            colour=colour,
            labels=_labels(kind, where, picked),
        )
    send_rows(
        rec,
        f"{root}/mistakes/wrong_members",
        rr.Points3D.from_fields(radii=[WRONG_MEMBER_RADIUS_M]),
        times,
        rr.Points3D.columns(
            positions=at_height(position, WRONG_MEMBER_Z_M),
            labels=wrong_label,
            colors=wrong_colour.reshape(-1, 4),
        ).partition(wrong_counts),
    )


def _labels(kind: str, layout: GroupLayout, rows: np.ndarray) -> list[str]:
    """``"<kind> 1,2,3"`` for the F-formations ``rows`` of ``layout``."""
    keys = layout.group_key[rows]
    used = np.unique(keys)
    text = {k: f"{kind} " + ",".join(map(str, layout.members_table[k])) for k in used.tolist()}
    return [text[k] for k in keys.tolist()]


def _send_cylinders(
    rec: rr.RecordingStream,
    entity: str,
    times: list[rr.TimeColumn],
    counts: np.ndarray,
    *,
    centres: np.ndarray,
    z: float,
    height: float,
    fill_mode: rr.components.FillMode,
    radius: float | None = None,
    radii: np.ndarray | None = None,
    line_radius: float | None = None,
    colour: tuple[int, int, int, int] | None = None,
    show_labels: bool | None = None,
    class_ids: np.ndarray | None = None,
    labels: list[str] | None = None,
    extra: Sequence[Any] = (),
) -> None:
    """Logs a layer of upright cylinders on ``entity``: ``counts[k]`` of them at the k-th time,
    centred over ``centres`` (m, 2) at height ``z``.

    ``height``, ``fill_mode``, ``radius`` (one for all), ``line_radius``, ``colour`` and
    ``show_labels`` are static, logged once; ``radii`` (m,), ``class_ids`` and ``labels`` are
    per cylinder; ``extra`` are further time-varying columns. None leaves a field unset.
    """
    send_rows(
        rec,
        entity,
        rr.Cylinders3D.from_fields(
            lengths=[height],
            radii=None if radius is None else [radius],
            colors=None if colour is None else [colour],
            line_radii=None if line_radius is None else [line_radius],
            fill_mode=fill_mode,
            show_labels=show_labels,
        ),
        times,
        [
            *rr.Cylinders3D.columns(
                centers=at_height(centres, z),
                radii=None if radii is None else radii.astype(np.float32),
                labels=labels,
                class_ids=class_ids,
            ).partition(counts),
            *extra,
        ],
    )
