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
colour from frame to frame while it keeps a majority of its members, and a detected group that
matches a true group (T = 2/3, ``reform.metrics``) takes that group's colour.

For detectors, on annotated frames, mistakes are drawn under ``world/groups/<name>/mistakes``:
``missed`` (true F-formations no detected group matches, red rings), ``spurious`` (detected
F-formations that match no true group, magenta rings) and ``wrong_members`` (in a matched pair,
people the detected group added, ``extra``, or left out, ``missing``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import rerun as rr

from reform import T_TWO_THIRDS, Evaluation, Frame, Group, evaluate
from sim.recording import _colours
from sim.recording._columns import at_height, value_columns
from sim.recording._timeline import Clock, frame_keys

__all__ = [
    "GROUPS_ROOT",
    "TRUTH",
    "GroupLayout",
    "LoggedGroups",
    "evaluate_detector",
    "group_tracks",
    "log_groups",
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


@dataclass(frozen=True, eq=False)
class GroupLayout:
    """The groups of a run, flattened: one row per person, one row per F-formation.

    Attributes:
        counts: (n_frames,) people per frame with a partition (0 where none).
        person_frame, person_id, person_group: (n_people_rows,) frame index, person id and index
            of the person's group in that frame's partition.
        person_position: (n_people_rows, 2) metres.
        group_frame: (n_fformations,) frame index of each F-formation (two or more people).
        group_members: the members of each F-formation, tuples of ids.
        group_centre: (n_fformations, 2) metres, mean of the members' positions.
        group_radius: (n_fformations,) metres, the group's Tightness.
        group_of_person: (n_people_rows,) row of the person's F-formation, -1 when alone.
    """

    counts: np.ndarray
    person_frame: np.ndarray
    person_id: np.ndarray
    person_group: np.ndarray
    person_position: np.ndarray
    group_frame: np.ndarray
    group_members: tuple[Group, ...]
    group_centre: np.ndarray
    group_radius: np.ndarray
    group_of_person: np.ndarray

    @classmethod
    def of(
        cls, frames: Sequence[Frame], partitions: Sequence[Sequence[Group] | None], *, what: str
    ) -> GroupLayout:
        """Lays out ``partitions[i]`` (a full partition of ``frames[i]``'s ids, or None)."""
        if len(partitions) != len(frames):
            raise ValueError(
                f"{what} must hold one partition per frame: expected {len(frames)}, "
                f"found {len(partitions)}"
            )
        m_frame: list[int] = []  # one entry per member, in partition order
        m_id: list[int] = []
        m_group: list[int] = []
        m_ff: list[int] = []
        g_frame: list[int] = []
        g_members: list[Group] = []
        has_partition = np.zeros(len(frames), dtype=bool)
        for f, partition in enumerate(partitions):
            if partition is None:
                continue
            has_partition[f] = True
            for gi, group in enumerate(partition):
                members = tuple(map(int, group))
                size = len(members)
                if not size:
                    raise ValueError(f"{_where(what, f, frames[f])}: group {gi} is empty")
                ff = -1
                if size >= 2:
                    ff = len(g_frame)
                    g_frame.append(f)
                    g_members.append(members)
                m_id.extend(members)
                m_frame.extend([f] * size)
                m_group.extend([gi] * size)
                m_ff.extend([ff] * size)
        person_frame = np.asarray(m_frame, dtype=np.int64)
        person_id = np.asarray(m_id, dtype=np.int64)
        rows, flat_position = _locate(frames, person_frame, person_id)
        _check_partitions(frames, partitions, what, has_partition, person_frame, person_id, rows)
        counts = np.bincount(person_frame, minlength=len(frames)).astype(np.int64)
        person_position = flat_position[rows]
        group_of_person = np.asarray(m_ff, dtype=np.int64)
        n_groups = len(g_frame)
        member = group_of_person >= 0
        size = np.bincount(group_of_person[member], minlength=n_groups).astype(np.float64)
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
                    / size
                )
            distance = np.linalg.norm(
                person_position[member] - centre[group_of_person[member]], axis=1
            )
            radius = (
                np.bincount(group_of_person[member], weights=distance, minlength=n_groups) / size
            )
        return cls(
            counts=counts,
            person_frame=person_frame,
            person_id=person_id,
            person_group=np.asarray(m_group, dtype=np.int64),
            person_position=person_position,
            group_frame=np.asarray(g_frame, dtype=np.int64),
            group_members=tuple(g_members),
            group_centre=centre,
            group_radius=radius,
            group_of_person=group_of_person,
        )

    @property
    def group_counts(self) -> np.ndarray:
        """(n_frames,) F-formations per frame."""
        return np.bincount(self.group_frame, minlength=self.counts.size).astype(np.int64)


@dataclass(frozen=True, eq=False)
class LoggedGroups:
    """What :func:`log_groups` drew.

    Attributes:
        layout: the groups, flattened.
        tracks: (n_fformations,) each F-formation's track (its colour class).
        frame_keys: (sequence, time in microseconds) of each frame.
        rows: (n_frames,) each frame's row on the run's clock.
        evaluation: for a detector's tree on frames with ground truth, its evaluation.
    """

    layout: GroupLayout
    tracks: np.ndarray
    frame_keys: tuple[tuple[str, int], ...]
    rows: np.ndarray
    evaluation: Evaluation | None = None

    def track_map(self) -> dict[tuple[str, int, frozenset[int]], int]:
        """(sequence, time in microseconds, members) -> track."""
        return {
            (*self.frame_keys[f], frozenset(m)): int(t)
            for f, m, t in zip(
                self.layout.group_frame.tolist(),
                self.layout.group_members,
                self.tracks.tolist(),
                strict=True,
            )
        }


def _locate(
    frames: Sequence[Frame], member_frame: np.ndarray, member_id: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Row of each (frame, person id) in the frames' concatenated arrays (-1 when absent), and
    those concatenated positions."""
    if not frames:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 2))
    counts = np.fromiter((f.n_people for f in frames), dtype=np.int64, count=len(frames))
    flat_id = np.concatenate([f.ids for f in frames])
    flat_position = (
        np.concatenate([f.position for f in frames]) if counts.sum() else np.zeros((0, 2))
    )
    flat_frame = np.repeat(np.arange(len(frames)), counts)
    known = np.unique(flat_id)
    rank = np.searchsorted(known, member_id)
    found = (rank < known.size) & (known[np.minimum(rank, max(known.size - 1, 0))] == member_id)
    table = flat_frame * known.size + np.searchsorted(known, flat_id)
    order = np.argsort(table, kind="stable")
    wanted = member_frame * known.size + rank
    at = np.minimum(np.searchsorted(table[order], wanted), max(table.size - 1, 0))
    found &= table.size > 0
    found[found] &= table[order][at[found]] == wanted[found]
    rows = np.where(found, order[at] if table.size else -1, -1)
    return rows.astype(np.int64), flat_position


def _check_partitions(
    frames: Sequence[Frame],
    partitions: Sequence[Sequence[Group] | None],
    what: str,
    has_partition: np.ndarray,
    member_frame: np.ndarray,
    member_id: np.ndarray,
    rows: np.ndarray,
) -> None:
    """Raises for the first frame whose partition names a stranger, someone twice, or misses
    someone."""
    counts = np.fromiter((f.n_people for f in frames), dtype=np.int64, count=len(frames))
    expected = np.where(has_partition, counts, 0)
    covered = np.bincount(rows[rows >= 0], minlength=int(counts.sum()))
    per_frame = np.bincount(member_frame, minlength=len(frames))
    strangers = member_frame[rows < 0]
    twice = np.zeros(len(frames), dtype=bool)
    np.logical_or.at(twice, np.repeat(np.arange(len(frames)), counts), covered > 1)
    bad = np.zeros(len(frames), dtype=bool)
    bad[strangers] = True
    bad |= twice | (per_frame != expected)
    if not np.any(bad):
        return
    f = int(np.flatnonzero(bad)[0])
    frame = frames[f]
    seen: set[int] = set()
    for gi, group in enumerate(partitions[f]):
        for m in (int(x) for x in group):
            if m not in set(frame.ids.tolist()) or m in seen:
                problem = "appears twice" if m in seen else "is not in the frame"
                raise ValueError(
                    f"{_where(what, f, frame)}: person {m} (group {gi}) {problem}; "
                    f"expected a full partition of ids {frame.ids.tolist()}"
                )
            seen.add(m)
    missing = next(i for i in frame.ids.tolist() if i not in seen)
    raise ValueError(
        f"{_where(what, f, frame)}: person {missing} is in no group; "
        "expected a full partition of the frame's ids, singletons included"
    )


def _where(what: str, index: int, frame: Frame) -> str:
    seq = f"sequence {frame.sequence!r}, " if frame.sequence else ""
    return f"{what}[{index}] ({seq}time {frame.time:g} s)"


def group_tracks(
    layout: GroupLayout,
    frames: Sequence[Frame],
    *,
    fixed: dict[int, int] | None = None,
    first_track: int = 1,
) -> np.ndarray:
    """(n_fformations,) track id of each F-formation: stable while a group keeps a majority.

    An F-formation continues the track of a group of the previous frame (same sequence) when
    each holds more than half of the larger one (``2·|A∩B| > max(|A|, |B|)``, so the match is
    unique); otherwise it starts a new track. ``fixed`` imposes tracks on some F-formations
    (row -> track), e.g. a detected group takes the track of the true group it matches.
    """
    fixed = fixed or {}
    tracks = np.zeros(len(layout.group_members), dtype=np.int64)
    next_track = max([first_track, *(t + 1 for t in fixed.values())])
    previous: list[tuple[frozenset[int], int]] = []
    previous_sequence: str | None = None
    starts = np.searchsorted(layout.group_frame, np.arange(len(frames) + 1))
    for f, frame in enumerate(frames):
        rows = range(int(starts[f]), int(starts[f + 1]))
        if frame.sequence != previous_sequence:
            previous, previous_sequence = [], frame.sequence
        if not rows and layout.counts[f] == 0:
            continue  # no partition here: keep the tracks alive across the gap
        used = {fixed[r] for r in rows if r in fixed}
        current: list[tuple[frozenset[int], int]] = []
        for r in rows:
            members = frozenset(layout.group_members[r])
            track = fixed.get(r)
            if track is None:
                for old, old_track in previous:
                    if old_track not in used and 2 * len(members & old) > max(
                        len(members), len(old)
                    ):
                        track = old_track
                        break
            if track is None:
                track = next_track
                next_track += 1
            used.add(track)
            tracks[r] = track
            current.append((members, track))
        previous = current
    return tracks


def evaluate_detector(
    frames: Sequence[Frame], partitions: Sequence[Sequence[Group]]
) -> Evaluation | None:
    """``reform.evaluate`` at T = 2/3 (and 1), or None when no frame carries ground truth."""
    if not any(f.groups is not None for f in frames):
        return None
    return evaluate(frames, partitions)


def _matches(
    evaluation: Evaluation, frames: Sequence[Frame], layout: GroupLayout
) -> tuple[dict[int, tuple[Group, bool]], np.ndarray]:
    """Which groups matched at T = 2/3, read from the evaluation's records.

    Returns:
        frame index -> [(true F-formation, matched)] for the annotated frames, and
        (n_fformations,) bool: each detected F-formation of ``layout`` matched a true group.
    """
    k = evaluation.thresholds.index(T_TWO_THIRDS)
    detected_matched = np.zeros(len(layout.group_members), dtype=bool)
    truth: dict[int, list[tuple[Group, bool]]] = {}
    det_rows = np.searchsorted(layout.group_frame, np.arange(len(frames) + 1))
    true_start = np.searchsorted(evaluation.true_frame, np.arange(evaluation.n_frames + 1))
    det_start = np.searchsorted(evaluation.detected_frame, np.arange(evaluation.n_frames + 1))
    for r, f in enumerate(evaluation.frame_index.tolist()):
        true_groups = frames[f].fformations()
        flags = evaluation.true_matched[k, true_start[r] : true_start[r + 1]]
        det_flags = evaluation.detected_matched[k, det_start[r] : det_start[r + 1]]
        rows = np.arange(det_rows[f], det_rows[f + 1])
        if len(true_groups) != flags.size or rows.size != det_flags.size:
            raise ValueError(
                f"evaluation does not belong to these frames and partitions (frame {f}: "
                f"{len(true_groups)} true and {rows.size} detected F-formations, evaluation has "
                f"{flags.size} and {det_flags.size})"
            )
        truth[f] = [(g, bool(m)) for g, m in zip(true_groups, flags.tolist(), strict=True)]
        detected_matched[rows] = det_flags
    return truth, detected_matched


def log_groups(
    rec: rr.RecordingStream,
    frames: Sequence[Frame],
    partitions: Sequence[Sequence[Group] | None] | None = None,
    *,
    name: str = TRUTH,
    clock: Clock | None = None,
    evaluation: Evaluation | None = None,
    truth: LoggedGroups | None = None,
    layer: int | None = None,
) -> LoggedGroups:
    """Logs one entity tree of groups, ``world/groups/<name>``, for a finished run.

    Args:
        rec: the recording stream.
        frames: the frames the groups belong to (positions are drawn from them), in time order.
        partitions: one full partition per frame (None where unknown); default: the frames'
            ground truth (None for frames without).
        name: the tree's name, ``"truth"`` or a detector's (``"reform"``, ``"gcff"``).
        clock: the run's clock; default: ``Clock.from_frames(frames)``.
        evaluation: ``reform.evaluate(frames, partitions)``, for the mistakes and the colours
            of matched groups; computed here when None and the frames carry ground truth.
        truth: the truth tree's :func:`log_groups` result, so that detected groups that
            match a true group share its colour.
        layer: stacking order of the tree: 0 (truth, default for it) is drawn lowest with the
            largest discs, each next layer higher with smaller discs (default for detectors: 1;
            give the k-th detector k + 1).

    Returns:
        What was drawn (pass the truth tree's as ``truth`` to the detectors' calls).

    Raises:
        ValueError: if a partition is not a full partition of its frame's ids (naming the
            frame and the person) or a frame matches no frame of ``clock``.
    """
    frames = tuple(frames)
    clock = Clock.from_frames(frames) if clock is None else clock
    rows = clock.rows_of(frames)
    is_truth = partitions is None
    if is_truth:
        partitions = [f.partition() if f.groups is not None else None for f in frames]
    layout = GroupLayout.of(frames, partitions, what=f"{name} partitions")
    layer = (0 if is_truth else 1) if layer is None else int(layer)
    if layer < 0:
        raise ValueError(f"layer must be >= 0, got {layer}")
    z = TRUTH_Z_M + layer * LAYER_STEP_M
    disc = max(MEMBER_RADIUS_M - layer * MEMBER_RADIUS_STEP_M, MIN_MEMBER_RADIUS_M)
    root = f"{GROUPS_ROOT}/{name}"

    fixed: dict[int, int] = {}
    truth_by_frame: dict[int, list[tuple[Group, bool]]] = {}
    detected_matched = np.zeros(len(layout.group_members), dtype=bool)
    if not is_truth:
        if evaluation is None:
            evaluation = evaluate_detector(frames, partitions)
        if evaluation is not None:
            truth_by_frame, detected_matched = _matches(evaluation, frames, layout)
            if truth is not None:
                fixed = _inherit_tracks(layout, truth, frames, truth_by_frame, detected_matched)
    first = 1 if truth is None else int(truth.tracks.max(initial=0)) + 1
    tracks = group_tracks(layout, frames, fixed=fixed, first_track=first)

    n_tracks = int(tracks.max(initial=0))
    label = "group" if is_truth else f"{name} group"
    rec.log(
        root,
        rr.AnnotationContext(
            [rr.AnnotationInfo(id=0, label="alone", color=_colours.SINGLETON)]
            + [
                rr.AnnotationInfo(id=t, label=f"{label} {t}", color=_colours.group_colour(t))
                for t in range(1, n_tracks + 1)
            ]
        ),
        static=True,
    )
    times = clock.columns(rows)
    person_class = np.append(tracks, 0)[layout.group_of_person]  # -1 (alone) picks the 0
    rec.log(
        f"{root}/members",
        rr.Cylinders3D.from_fields(
            lengths=[DISC_HEIGHT_M],
            radii=[disc],
            fill_mode=rr.components.FillMode.Solid,
            show_labels=False,
        ),
        static=True,
    )
    rec.send_columns(
        f"{root}/members",
        indexes=times,
        columns=[
            *rr.Cylinders3D.columns(
                centers=at_height(layout.person_position, z),
                class_ids=person_class.astype(np.uint16),
            ).partition(layout.counts),
            *value_columns(
                layout.counts, person_id=layout.person_id, group_index=layout.person_group
            ),
        ],
        strict=True,
    )
    group_counts = layout.group_counts
    rec.log(
        f"{root}/centres",
        rr.Points3D.from_fields(radii=[CENTRE_RADIUS_M], show_labels=False),
        static=True,
    )
    rec.send_columns(
        f"{root}/centres",
        indexes=times,
        columns=rr.Points3D.columns(
            positions=at_height(layout.group_centre, z + 0.005), class_ids=tracks.astype(np.uint16)
        ).partition(group_counts),
        strict=True,
    )
    rec.log(
        f"{root}/circles",
        rr.Cylinders3D.from_fields(
            lengths=[RING_HEIGHT_M],
            line_radii=[RING_LINE_M],
            fill_mode=rr.components.FillMode.MajorWireframe,
            show_labels=False,
        ),
        static=True,
    )
    rec.send_columns(
        f"{root}/circles",
        indexes=times,
        columns=rr.Cylinders3D.columns(
            centers=at_height(layout.group_centre, z + RING_HEIGHT_M / 2),
            radii=np.maximum(layout.group_radius, MIN_CIRCLE_M).astype(np.float32),
            class_ids=tracks.astype(np.uint16),
        ).partition(group_counts),
        strict=True,
    )
    if not is_truth and evaluation is not None:
        _log_mistakes(rec, root, frames, layout, truth_by_frame, detected_matched, times, z=z)
    return LoggedGroups(
        layout=layout,
        tracks=tracks,
        frame_keys=frame_keys(frames),
        rows=rows,
        evaluation=evaluation,
    )


def _inherit_tracks(
    layout: GroupLayout,
    truth: LoggedGroups,
    frames: Sequence[Frame],
    truth_by_frame: dict[int, list[tuple[Group, bool]]],
    detected_matched: np.ndarray,
) -> dict[int, int]:
    """Detected F-formation row -> track of the true F-formation it matches (T = 2/3)."""
    track_of = truth.track_map()
    keys = frame_keys(frames)
    fixed: dict[int, int] = {}
    for r in np.flatnonzero(detected_matched).tolist():
        f = int(layout.group_frame[r])
        members = frozenset(layout.group_members[r])
        for true_group, matched in truth_by_frame.get(f, []):
            if matched and 3 * len(members & set(true_group)) >= 2 * max(
                len(members), len(true_group)
            ):
                key = (*keys[f], frozenset(true_group))
                if key in track_of:
                    fixed[r] = track_of[key]
                break
    return fixed


def _log_mistakes(
    rec: rr.RecordingStream,
    root: str,
    frames: Sequence[Frame],
    layout: GroupLayout,
    truth_by_frame: dict[int, list[tuple[Group, bool]]],
    detected_matched: np.ndarray,
    times: list[rr.TimeColumn],
    *,
    z: float,
) -> None:
    n = len(frames)
    missed_centre: list[np.ndarray] = []
    missed_radius: list[float] = []
    missed_label: list[str] = []
    missed_counts = np.zeros(n, dtype=np.int64)
    wrong_position: list[np.ndarray] = []
    wrong_label: list[str] = []
    wrong_colour: list[tuple[int, int, int, int]] = []
    wrong_counts = np.zeros(n, dtype=np.int64)
    det_start = np.searchsorted(layout.group_frame, np.arange(n + 1))
    for f, truth in truth_by_frame.items():
        frame = frames[f]
        row_of = {pid: k for k, pid in enumerate(frame.ids.tolist())}
        detected = [
            frozenset(layout.group_members[r]) for r in range(det_start[f], det_start[f + 1])
        ]
        for true_group, matched in truth:
            if matched and frozenset(true_group) in detected:
                continue  # found exactly: nothing to show
            members = frame.position[[row_of[m] for m in true_group]]
            centre = members.mean(axis=0)
            if not matched:
                missed_centre.append(centre)
                missed_radius.append(float(np.linalg.norm(members - centre, axis=1).mean()))
                missed_label.append("missed " + ",".join(str(m) for m in true_group))
                missed_counts[f] += 1
                continue
            true_set = set(true_group)
            partner = max(detected, key=lambda d: len(d & true_set))
            for person, kind, colour in [
                *((p, "extra", _colours.EXTRA_MEMBER) for p in sorted(partner - true_set)),
                *((p, "missing", _colours.MISSING_MEMBER) for p in sorted(true_set - partner)),
            ]:
                wrong_position.append(frame.position[row_of[person]])
                wrong_label.append(f"{kind} {person}")
                wrong_colour.append(colour)
                wrong_counts[f] += 1
    spurious = np.flatnonzero(~detected_matched & np.isin(layout.group_frame, list(truth_by_frame)))
    spurious_counts = np.bincount(layout.group_frame[spurious], minlength=n).astype(np.int64)

    _log_rings(
        rec,
        f"{root}/mistakes/missed",
        centres=np.array(missed_centre).reshape(-1, 2),
        radii=np.array(missed_radius),
        labels=missed_label,
        counts=missed_counts,
        colour=_colours.MISSED,
        times=times,
        z=z,
    )
    _log_rings(
        rec,
        f"{root}/mistakes/spurious",
        centres=layout.group_centre[spurious],
        radii=layout.group_radius[spurious],
        labels=[
            "spurious " + ",".join(str(m) for m in layout.group_members[r])
            for r in spurious.tolist()
        ],
        counts=spurious_counts,
        colour=_colours.SPURIOUS,
        times=times,
        z=z,
    )
    entity = f"{root}/mistakes/wrong_members"
    rec.log(entity, rr.Points3D.from_fields(radii=[WRONG_MEMBER_RADIUS_M]), static=True)
    rec.send_columns(
        entity,
        indexes=times,
        columns=rr.Points3D.columns(
            positions=at_height(np.array(wrong_position).reshape(-1, 2), WRONG_MEMBER_Z_M),
            labels=wrong_label,
            colors=np.array(wrong_colour, dtype=np.uint8).reshape(-1, 4),
        ).partition(wrong_counts),
        strict=True,
    )


def _log_rings(
    rec: rr.RecordingStream,
    entity: str,
    *,
    centres: np.ndarray,
    radii: np.ndarray,
    labels: list[str],
    counts: np.ndarray,
    colour: tuple[int, int, int, int],
    times: list[rr.TimeColumn],
    z: float,
) -> None:
    rings = np.maximum(radii, MIN_CIRCLE_M) + MISTAKE_MARGIN_M
    rec.log(
        entity,
        rr.Cylinders3D.from_fields(
            lengths=[RING_HEIGHT_M],
            line_radii=[2 * RING_LINE_M],
            colors=[colour],
            fill_mode=rr.components.FillMode.MajorWireframe,
        ),
        static=True,
    )
    rec.send_columns(
        entity,
        indexes=times,
        columns=rr.Cylinders3D.columns(
            centers=at_height(centres, z + RING_HEIGHT_M),
            radii=rings.astype(np.float32),
            labels=labels,
        ).partition(counts),
        strict=True,
    )
