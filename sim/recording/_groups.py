"""Conversational groups on the floor: ground truth and each detector as its own entity tree.

``world/groups/<name>`` (``truth``, ``reform``, ``gcff``, ...), each toggleable on its own:

* ``members``: a disc under every person, coloured by their group (grey when alone), with the
  person id and the index of their group in the partition as extra components;
* ``centres``: each F-formation's o-space centre (the mean of its members' positions, as in
  Characterisation), labelled by its group;
* ``circles``: a circle around each centre whose radius is the group's Tightness.

Groups are coloured through an annotation context (one class per group track): a group keeps its
colour from frame to frame while it keeps a majority of its members, and a detected group that
matches a true group (T = 2/3, ``reform.metrics``) takes that group's colour.

For detectors, on annotated frames, mistakes are drawn under ``world/groups/<name>/mistakes``:
``missed`` (true F-formations no detected group matches, red circles), ``spurious`` (detected
F-formations that match no true group, magenta circles) and ``wrong_members`` (in a matched pair,
people the detected group added, ``extra``, or left out, ``missing``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import rerun as rr

from reform import T_TWO_THIRDS, Evaluation, Frame, Group, evaluate
from sim.recording import _colours
from sim.recording._columns import at_height, circle_points, line_strips_column
from sim.recording._timeline import Clock

__all__ = [
    "GROUPS_ROOT",
    "TRUTH",
    "GroupLayout",
    "LoggedGroups",
    "evaluate_detector",
    "frame_key",
    "group_tracks",
    "log_groups",
]

GROUPS_ROOT = "world/groups"
TRUTH = "truth"
MEMBER_RADIUS_M = 0.28  # metres: the disc under a person
CENTRE_RADIUS_M = 0.06  # metres
CIRCLE_POINTS = 48
CIRCLE_RADIUS_M = 0.012  # metres, line thickness
MIN_CIRCLE_M = 0.15  # metres: smallest circle drawn
MISTAKE_MARGIN_M = 0.25  # metres: mistake circles ring the group's circle
WRONG_MEMBER_Z_M = 0.35  # metres
WRONG_MEMBER_RADIUS_M = 0.12  # metres
TRUTH_Z_M = 0.01  # metres: height of the truth tree's drawings
DETECTOR_Z_M = 0.03  # metres: first detector's height; each next one is DETECTOR_STEP_M higher
DETECTOR_STEP_M = 0.02  # metres


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
        counts = np.zeros(len(frames), dtype=np.int64)
        p_frame: list[int] = []
        p_id: list[int] = []
        p_group: list[int] = []
        p_pos: list[np.ndarray] = []
        p_ff: list[int] = []
        g_frame: list[int] = []
        g_members: list[Group] = []
        for f, (frame, partition) in enumerate(zip(frames, partitions, strict=True)):
            if partition is None:
                continue
            row_of = {pid: k for k, pid in enumerate(frame.ids.tolist())}
            order: list[int] = []
            for gi, group in enumerate(partition):
                members = tuple(int(m) for m in group)
                if not members:
                    raise ValueError(f"{_where(what, f, frame)}: group {gi} is empty")
                ff = len(g_frame) if len(members) >= 2 else -1
                if ff >= 0:
                    g_frame.append(f)
                    g_members.append(members)
                for m in members:
                    k = row_of.pop(m, None)
                    if k is None:
                        problem = "appears twice" if m in frame.ids else "is not in the frame"
                        raise ValueError(
                            f"{_where(what, f, frame)}: person {m} (group {gi}) {problem}; "
                            f"expected a full partition of ids {frame.ids.tolist()}"
                        )
                    order.append(k)
                    p_group.append(gi)
                    p_ff.append(ff)
            if row_of:
                raise ValueError(
                    f"{_where(what, f, frame)}: person {next(iter(row_of))} is in no group; "
                    "expected a full partition of the frame's ids, singletons included"
                )
            counts[f] = len(order)
            p_frame.extend([f] * len(order))
            p_id.extend(frame.ids[order].tolist())
            p_pos.append(frame.position[order])
        person_position = np.concatenate(p_pos) if p_pos else np.zeros((0, 2))
        group_of_person = np.asarray(p_ff, dtype=np.int64)
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
            person_frame=np.asarray(p_frame, dtype=np.int64),
            person_id=np.asarray(p_id, dtype=np.int64),
            person_group=np.asarray(p_group, dtype=np.int64),
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


def frame_key(frame: Frame) -> tuple[str, int]:
    """(sequence, time in microseconds): how frames of different streams are matched."""
    return (frame.sequence, round(frame.time * 1_000_000))


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
    height_m: float | None = None,
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
        height_m: height of the drawings; default: truth lowest, detectors above.

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
    z = (TRUTH_Z_M if is_truth else DETECTOR_Z_M) if height_m is None else height_m
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
        rr.Points3D.from_fields(radii=[MEMBER_RADIUS_M], show_labels=False),
        static=True,
    )
    rec.send_columns(
        f"{root}/members",
        indexes=times,
        columns=[
            *rr.Points3D.columns(
                positions=at_height(layout.person_position, z),
                class_ids=person_class.astype(np.uint16),
            ).partition(layout.counts),
            *rr.AnyValues.columns(
                person_id=layout.person_id, group_index=layout.person_group
            ).partition(layout.counts),
        ],
        strict=True,
    )
    group_counts = layout.group_counts
    rec.log(f"{root}/centres", rr.Points3D.from_fields(radii=[CENTRE_RADIUS_M]), static=True)
    rec.send_columns(
        f"{root}/centres",
        indexes=times,
        columns=rr.Points3D.columns(
            positions=at_height(layout.group_centre, z + 0.005), class_ids=tracks.astype(np.uint16)
        ).partition(group_counts),
        strict=True,
    )
    circle_radius = np.maximum(layout.group_radius, MIN_CIRCLE_M)
    rec.log(
        f"{root}/circles",
        rr.LineStrips3D.from_fields(radii=[CIRCLE_RADIUS_M], show_labels=False),
        static=True,
    )
    rec.send_columns(
        f"{root}/circles",
        indexes=times,
        columns=[
            line_strips_column(
                circle_points(
                    layout.group_centre, circle_radius, z=z + 0.005, n_points=CIRCLE_POINTS
                ),
                np.full(len(layout.group_members), CIRCLE_POINTS),
                group_counts,
            ),
            *rr.LineStrips3D.columns(class_ids=tracks.astype(np.uint16)).partition(group_counts),
        ],
        strict=True,
    )
    if not is_truth and evaluation is not None:
        _log_mistakes(rec, root, frames, layout, truth_by_frame, detected_matched, times, z=z)
    return LoggedGroups(
        layout=layout,
        tracks=tracks,
        frame_keys=tuple(frame_key(f) for f in frames),
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
    fixed: dict[int, int] = {}
    for r in np.flatnonzero(detected_matched).tolist():
        f = int(layout.group_frame[r])
        members = frozenset(layout.group_members[r])
        for true_group, matched in truth_by_frame.get(f, []):
            if matched and 3 * len(members & set(true_group)) >= 2 * max(
                len(members), len(true_group)
            ):
                key = (*frame_key(frames[f]), frozenset(true_group))
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
        detected = [
            frozenset(layout.group_members[r]) for r in range(det_start[f], det_start[f + 1])
        ]
        for true_group, matched in truth:
            members = frame.position[[frame.index_of(m) for m in true_group]]
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
                wrong_position.append(frame.position[frame.index_of(person)])
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
        rr.LineStrips3D.from_fields(radii=[CIRCLE_RADIUS_M * 2], colors=[colour]),
        static=True,
    )
    rec.send_columns(
        entity,
        indexes=times,
        columns=[
            line_strips_column(
                circle_points(centres, rings, z=z + 0.01, n_points=CIRCLE_POINTS),
                np.full(centres.shape[0], CIRCLE_POINTS),
                counts,
            ),
            *rr.LineStrips3D.columns(labels=labels).partition(counts),
        ],
        strict=True,
    )
