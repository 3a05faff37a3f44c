"""Babble (Hedayati et al., IROS 2020): Vicon motion capture of a word game, 7 participants.

A Babble folder holds two files:

* ``Motion-capture-data.csv``: a header line, then one line per frame *N* (line *N* + 1). Each
  line holds blocks of 10 comma-separated fields, one per participant, and a trailing comma:
  ``Name, HeadX, HeadY, HeadRotation, TorsoX, TorsoY, TorsoRotation, Hieght, FrameNum, Time``.
  Positions are metres, rotations radians in (-pi, pi], counter-clockwise from +x. An all-zero
  ``(x, y, rotation)`` triple means "not tracked". The header names fewer blocks than the
  lines hold, so fields are read by position.
* ``annotated-frames.csv``: ``N,{[id id ...] [id ...]}`` per annotated frame; ``{[]}`` means no
  F-formation. Participants named in no group are singletons.

How the loader handles the recording's quirks (each case is counted in
``metadata["report"]``, never silent):

* **Time.** ``Time`` is a wall clock with 1 s resolution, so a frame's ``time`` is taken from the
  Vicon frame counter instead: ``(FrameNum - FrameNum of frame 1) / 100`` seconds (Vicon runs at
  100 Hz). Its largest gap to the wall clock is reported (``max_clock_gap_s``; about 1 s). Each
  step of the counter agrees with the clock's within :data:`CLOCK_STEP_TOLERANCE_S`: a FrameNum
  jump, or a ``Time`` going back other than the 12-hour clock's wrap (12:59:59 to 1:00:00), is
  refused.
* **Untracked torso.** The participant is absent from that frame (not in ``ids``), except when
  the annotation names them as a group member: then their tracked head stands in for the body
  (position and yaw) in that frame (``torso_from_head``). A member with neither torso nor a
  trustworthy head is not in the frame but stays in its ground truth (``Frame.listed_groups``),
  counted as a missed member as the field's protocol counts it (``members_dropped``).
* **Untracked head.** The participant's head is NaN (``heads_untracked``).
* **Misplaced heads.** A head more than :data:`HEAD_TORSO_MAX_M` from its own torso and within
  that distance of another participant's torso is that participant's head (participants 3 and 4
  wore each other's head markers): it is moved to its owner when the owner's own head is missing
  or misplaced too (``heads_swapped_back`` counts full exchanges, ``heads_moved`` one-way moves),
  otherwise dropped (``heads_dropped_duplicate``). A far head near nobody's torso is dropped
  (``heads_dropped_far``). A dropped head is NaN; detectors fall back to the body.
"""

from __future__ import annotations

import re
from collections import Counter
from os import PathLike
from pathlib import Path

import numpy as np

from reform.datasets._validation import (
    WRAPPED_ANGLE_LIMIT_RAD,
    check_angle,
    check_assumed_metres,
    check_coordinate,
    check_unique_ids,
    make_frame,
    parse_float,
    parse_whole,
    read_lines,
    require_file,
)
from reform.datasets.errors import DataFormatError, file_errors_as_data_errors
from reform.frame import Dataset, Frame, Group
from reform.path_argument import path_argument

__all__ = [
    "ANNOTATIONS_FILE",
    "CLOCK_STEP_TOLERANCE_S",
    "HEAD_TORSO_MAX_M",
    "MOTION_FILE",
    "VICON_RATE_HZ",
    "load_babble",
]

MOTION_FILE = "Motion-capture-data.csv"
ANNOTATIONS_FILE = "annotated-frames.csv"

VICON_RATE_HZ = 100.0  # Vicon frame counter rate, ticks per second
HEAD_TORSO_MAX_M = 0.5  # metres; a tracked head farther than this from its torso is misplaced
_BLOCK = 10  # fields per participant
_FIELDS = (
    "Name",
    "HeadX",
    "HeadY",
    "HeadRotation",
    "TorsoX",
    "TorsoY",
    "TorsoRotation",
    "Hieght",
    "FrameNum",
    "Time",
)
_ANNOTATION = re.compile(r"^\s*(\d+)\s*,\s*\{(.*)\}\s*$")
_GROUP = re.compile(r"\[([^\[\]]*)\]")
_CLOCK = re.compile(r"^(\d{1,2}):(\d{2}):(\d{2})$")
_HALF_DAY_S = 12 * 3600  # the wall clock is 12-hour without AM/PM
# How far a line's FrameNum step (at VICON_RATE_HZ) and its Time step may differ, seconds. Time's
# 1 s resolution alone puts them up to 1 s apart; in Babble they differ by at most 0.66 s. A
# FrameNum jump or a Time going back that is no wrap of the clock differs by more.
CLOCK_STEP_TOLERANCE_S = 2.0


@file_errors_as_data_errors
def load_babble(path: str | PathLike[str], *, annotated_only: bool = False) -> Dataset:
    """Loads the Babble motion capture joined with its annotated frames.

    Every line of the CSV is a frame (sequence ``"babble"``); only the annotated frames carry
    ground truth (``Frame.groups`` holds their groups of two or more). The torso is the body,
    the head is the head. See the module docstring for the handling of untracked and misplaced
    markers; the counts are in ``metadata["report"]`` and the frame number *N* of every frame
    in ``metadata["frame_numbers"]``.

    Args:
        path: a folder holding ``Motion-capture-data.csv`` and ``annotated-frames.csv``, or the
            path of the motion-capture CSV (the annotations are read beside it).
        annotated_only: keep only the annotated frames (99 in Babble).

    Returns:
        The dataset, named ``"babble"``, positions in metres.

    Raises:
        DataFormatError: a file is missing, empty or malformed (the message names the file,
            line or frame, field, what was expected and what was found).
    """
    path = path_argument(path, name="path", function="load_babble")
    folder = path if path.is_dir() else path.parent
    motion_path = folder / MOTION_FILE if path.is_dir() else path
    annotations_path = folder / ANNOTATIONS_FILE
    require_file(motion_path, what="a Babble motion-capture CSV")
    require_file(annotations_path, what="a Babble annotation CSV")

    ids, values, frame_counter, clock = _read_motion(motion_path)
    annotations, duplicates = _read_annotations(
        annotations_path, n_frames=len(values), known=set(ids)
    )

    n_frames = len(values)
    times = (frame_counter - frame_counter[0]) / VICON_RATE_HZ
    clock_gap = float(np.max(np.abs(times - (clock - clock[0])))) if n_frames else 0.0

    report: Counter[str] = Counter()
    swaps: Counter[str] = Counter()
    torso_from_head: list[list[int]] = []
    members_dropped: list[list[int]] = []
    frames: list[Frame] = []
    frame_numbers: list[int] = []
    for index in range(n_frames):
        number = index + 1
        groups_listed = annotations.get(number)
        if annotated_only and groups_listed is None:
            continue
        where = f"line {number + 1} (frame {number})"
        head, torso = values[index, :, 0:3], values[index, :, 3:6]
        head_tracked = ~np.all(head == 0.0, axis=1)
        torso_tracked = ~np.all(torso == 0.0, axis=1)
        report["heads_untracked"] += int(np.sum(torso_tracked & ~head_tracked))
        head_out, head_ok = _place_heads(head, head_tracked, torso, torso_tracked, report, swaps)

        body = torso.copy()
        present = torso_tracked.copy()
        groups: tuple[Group, ...] | None = None
        listed_groups: tuple[Group, ...] | None = None
        if groups_listed is not None:
            kept_groups: list[Group] = []
            absent = False
            for group in groups_listed:
                kept: list[int] = []
                for person in group:
                    i = ids.index(person)
                    if not torso_tracked[i]:
                        if head_tracked[i] and not _near_other_torso(
                            head[i], i, torso, torso_tracked
                        ):
                            body[i] = head[i]
                            head_out[i] = head[i]
                            head_ok[i] = True
                            present[i] = True
                            torso_from_head.append([number, person])
                        else:
                            members_dropped.append([number, person])
                            absent = True
                            continue
                    kept.append(person)
                if len(kept) >= 2:
                    kept_groups.append(tuple(kept))
            groups = tuple(kept_groups)
            if absent:  # they stay in the ground truth, missed as the field's protocol counts
                listed_groups = tuple(tuple(g) for g in groups_listed if len(g) >= 2)
        report["heads_without_torso_ignored"] += int(np.sum(head_tracked & ~present))

        rows = np.flatnonzero(present)
        head_position = np.where(head_ok[rows, None], head_out[rows, :2], np.nan)
        head_yaw = np.where(head_ok[rows], head_out[rows, 2], np.nan)
        frames.append(
            make_frame(
                path=motion_path,
                where=where,
                ids=np.asarray(ids, dtype=np.int64)[rows],
                position=body[rows, :2],
                yaw=body[rows, 2],
                head_position=head_position,
                head_yaw=head_yaw,
                groups=groups,
                listed_groups=listed_groups,
                time=float(times[index]),
                sequence="babble",
            )
        )
        frame_numbers.append(number)

    summary = {
        "rows": n_frames,
        "frames": len(frames),
        "annotated_frames": len(annotations),
        "annotation_lines_duplicated": duplicates,
        "max_clock_gap_s": round(clock_gap, 3),
        "heads_untracked": report["heads_untracked"],
        "heads_swapped_back": report["heads_swapped_back"],
        "heads_moved": report["heads_moved"],
        "heads_dropped_duplicate": report["heads_dropped_duplicate"],
        "heads_dropped_far": report["heads_dropped_far"],
        "misplaced_heads_by_owner": dict(sorted(swaps.items())),
        "heads_without_torso_ignored": report["heads_without_torso_ignored"],
        "torso_from_head": torso_from_head,
        "members_dropped": members_dropped,
    }
    check_assumed_metres(
        frames, path=motion_path, hint="the format holds metres: convert the positions to metres"
    )
    return Dataset(
        frames=tuple(frames),
        name="babble",
        source=str(folder),
        units="m",
        metadata={
            "format": "babble",
            "motion_file": str(motion_path),
            "annotations_file": str(annotations_path),
            "time": f"(FrameNum - first FrameNum) / {VICON_RATE_HZ:g} Hz, seconds",
            "frame_numbers": frame_numbers,
            "report": summary,
        },
    )


def _near_other_torso(head: np.ndarray, i: int, torso: np.ndarray, tracked: np.ndarray) -> bool:
    distance = np.hypot(*(torso[:, :2] - head[:2]).T)
    others = tracked.copy()
    others[i] = False
    return bool(np.any(others & (distance < HEAD_TORSO_MAX_M)))


def _place_heads(
    head: np.ndarray,
    head_tracked: np.ndarray,
    torso: np.ndarray,
    torso_tracked: np.ndarray,
    report: Counter[str],
    swaps: Counter[str],
) -> tuple[np.ndarray, np.ndarray]:
    """Heads assigned to their owners: ((n, 3) head triples, (n,) bool which are valid)."""
    n = head.shape[0]
    out = head.copy()
    ok = head_tracked & torso_tracked
    own_distance = np.hypot(*(head[:, :2] - torso[:, :2]).T)
    misplaced = ok & (own_distance > HEAD_TORSO_MAX_M)
    if not np.any(misplaced):
        return out, ok
    ok = ok & ~misplaced
    owners: dict[int, int] = {}
    for i in np.flatnonzero(misplaced):
        distance = np.hypot(*(torso[:, :2] - head[i, :2]).T)
        distance[i] = np.inf
        distance[~torso_tracked] = np.inf
        j = int(np.argmin(distance))
        if distance[j] < HEAD_TORSO_MAX_M:
            owners[int(i)] = j
        else:
            report["heads_dropped_far"] += 1
    filled = np.zeros(n, dtype=bool)
    moved: set[tuple[int, int]] = set()
    for i, j in owners.items():
        if ok[j] or filled[j]:
            report["heads_dropped_duplicate"] += 1
            continue
        out[j] = head[i]
        filled[j] = True
        moved.add((i, j))
        swaps[f"{i + 1}->{j + 1}"] += 1
    for i, j in moved:
        if (j, i) in moved:
            report["heads_swapped_back"] += int(i < j)
        else:
            report["heads_moved"] += 1
    return out, ok | filled


def _clock_seconds(text: str, *, path: Path, where: str) -> float:
    match = _CLOCK.match(text.strip())
    if match is None:
        raise DataFormatError(path, where, "Time", "a time like H:MM:SS", repr(text))
    hours, minutes, seconds = (int(g) for g in match.groups())
    return float(hours * 3600 + minutes * 60 + seconds)


def _read_motion(path: Path) -> tuple[list[int], np.ndarray, np.ndarray, np.ndarray]:
    """(participant ids, (T, n, 6) head xyθ + torso xyθ, (T,) FrameNum, (T,) clock seconds)."""
    lines = [line.rstrip("\r") for _, line in read_lines(path)]
    if not lines or not lines[0].strip():
        raise DataFormatError(
            path, "line 1", "header", "a header line starting with 'Name1'", "an empty line"
        )
    if not lines[0].lstrip().startswith("Name"):
        raise DataFormatError(
            path, "line 1", "header", "a header line starting with 'Name1'", repr(lines[0][:40])
        )
    if len(lines) < 2:
        raise DataFormatError(path, None, None, "at least one data line after the header", "none")

    ids: list[int] | None = None
    values: list[list[float]] = []
    counters: list[float] = []
    clock_texts: list[str] = []
    for line_number, line in enumerate(lines[1:], start=2):
        where = f"line {line_number} (frame {line_number - 1})"
        fields = line.split(",")
        if fields and fields[-1].strip() == "":
            fields = fields[:-1]
        n_blocks, extra = divmod(len(fields), _BLOCK)
        expected_blocks = len(ids) if ids is not None else n_blocks
        if extra or n_blocks == 0 or n_blocks != expected_blocks:
            raise DataFormatError(
                path,
                where,
                "fields",
                f"{expected_blocks * _BLOCK or 'a multiple of 10'} comma-separated fields "
                f"({_BLOCK} per participant) and a trailing comma",
                f"{len(fields)} fields (truncated line?)",
            )
        row_ids: list[int] = []
        row: list[float] = []
        counter = clock_text = first = None
        for b in range(n_blocks):
            block = fields[b * _BLOCK : (b + 1) * _BLOCK]
            person = parse_whole(
                block[0],
                path=path,
                where=where,
                field=f"Name (block {b + 1})",
                what="a participant number",
            )
            row_ids.append(person)
            person_where = f"{where}, participant {person}"
            triple_values = []
            for k in range(1, 7):
                value = parse_float(block[k], path=path, where=person_where, field=_FIELDS[k])
                if k in (1, 2, 4, 5):
                    check_coordinate(value, path=path, where=person_where, field=_FIELDS[k])
                if k in (3, 6):
                    check_angle(
                        value,
                        limit=WRAPPED_ANGLE_LIMIT_RAD,
                        path=path,
                        where=person_where,
                        field=_FIELDS[k],
                    )
                triple_values.append(value)
            row.extend(triple_values)
            parse_float(block[7], path=path, where=person_where, field=_FIELDS[7])  # read by none
            block_counter = parse_float(block[8], path=path, where=person_where, field="FrameNum")
            if not block_counter.is_integer():
                raise DataFormatError(
                    path, person_where, "FrameNum", "an integer Vicon frame number", repr(block[8])
                )
            block_clock = block[9].strip()
            _clock_seconds(block_clock, path=path, where=person_where)
            if counter is None:
                counter, clock_text, first = block_counter, block_clock, person
            elif block_counter != counter:
                raise DataFormatError(
                    path,
                    person_where,
                    "FrameNum",
                    f"the line's FrameNum, {counter:.0f} (participant {first})",
                    repr(block[8].strip()),
                )
            elif block_clock != clock_text:
                raise DataFormatError(
                    path,
                    person_where,
                    "Time",
                    f"the line's Time, {clock_text} (participant {first})",
                    repr(block_clock),
                )
        check_unique_ids(row_ids, path=path, where=where, field="Name")
        if ids is None:
            ids = row_ids
        elif row_ids != ids:
            raise DataFormatError(
                path, where, "Name", f"participants {ids} in this order", str(row_ids)
            )
        if counters and counter <= counters[-1]:
            raise DataFormatError(
                path,
                where,
                "FrameNum",
                f"a Vicon frame number above {counters[-1]:.0f} (line {line_number - 1}): "
                "time increases",
                f"{counter:.0f}",
            )
        values.append(row)
        counters.append(counter)
        clock_texts.append(clock_text)
    assert ids is not None
    array = np.array(values, dtype=np.float64).reshape(len(values), len(ids), 6)
    return ids, array, np.array(counters), _wall_clock(path, counters, clock_texts)


def _wall_clock(path: Path, counters: list[float], texts: list[str]) -> np.ndarray:
    """(T,) each line's Time in seconds, counted on across the clock's wraps (a 12-hour clock's
    12:59:59 to 1:00:00), each step checked against FrameNum's.

    Args:
        counters: (T,) each line's FrameNum (increasing).
        texts: (T,) each line's Time, ``H:MM:SS``.

    Raises:
        DataFormatError: a step of FrameNum and the same step of Time more than
            :data:`CLOCK_STEP_TOLERANCE_S` apart: a Time going back that is no wrap, or a
            FrameNum jump Time does not make, naming the line and both steps.
    """
    clocks: list[float] = []
    offset = 0.0
    for k, text in enumerate(texts):
        line = k + 2
        where = f"line {line} (frame {k + 1})"
        clock = _clock_seconds(text, path=path, where=where) + offset
        if not clocks:
            clocks.append(clock)
            continue
        back = clock < clocks[-1]
        while clock < clocks[-1]:  # the clock wrapped: 12 h on (twice for a 24-hour clock)
            offset += _HALF_DAY_S
            clock += _HALF_DAY_S
        frames_s = (counters[k] - counters[k - 1]) / VICON_RATE_HZ
        clock_s = clock - clocks[-1]
        if abs(frames_s - clock_s) <= CLOCK_STEP_TOLERANCE_S:
            clocks.append(clock)
            continue
        if back:
            raise DataFormatError(
                path,
                where,
                "Time",
                f"a Time from {texts[k - 1]} (line {line - 1}) on, {frames_s:.2f} s later as "
                f"FrameNum steps (within {CLOCK_STEP_TOLERANCE_S:g} s), or the 12-hour clock's "
                "wrap from 12:59:59 to 1:00:00",
                repr(text),
            )
        raise DataFormatError(
            path,
            where,
            "FrameNum",
            f"a step that agrees with Time's within {CLOCK_STEP_TOLERANCE_S:g} s at "
            f"{VICON_RATE_HZ:g} Hz (Time goes from {texts[k - 1]} on line {line - 1} to "
            f"{text}: {clock_s:g} s)",
            f"{counters[k]:.0f} after {counters[k - 1]:.0f} (line {line - 1}): {frames_s:.2f} s",
        )
    return np.array(clocks)


def _read_annotations(
    path: Path, *, n_frames: int, known: set[int]
) -> tuple[dict[int, tuple[Group, ...]], int]:
    """{frame number: groups of two or more}, and the number of identical duplicate lines."""
    annotations: dict[int, tuple[Group, ...]] = {}
    first_line: dict[int, int] = {}
    duplicates = 0
    for line_number, line in read_lines(path):
        where = f"line {line_number}"
        match = _ANNOTATION.match(line)
        if match is None:
            raise DataFormatError(path, where, None, "N,{[id id ...] ...}", repr(line.rstrip("\n")))
        number = parse_whole(
            match.group(1), path=path, where=where, field="frame", what="a frame number"
        )
        where = f"line {line_number} (frame {number})"
        if not 1 <= number <= n_frames:
            raise DataFormatError(
                path,
                where,
                "frame",
                f"a frame number in 1..{n_frames} of the motion capture",
                str(number),
            )
        body = match.group(2)
        if _GROUP.sub("", body).strip(" ,"):
            raise DataFormatError(path, where, "groups", "groups written [id id ...]", repr(body))
        groups: list[Group] = []
        seen: set[int] = set()
        for g, text in enumerate(_GROUP.findall(body), start=1):
            members = []
            for token in text.replace(",", " ").split():
                person = parse_whole(
                    token, path=path, where=where, field=f"group {g}", what="a participant number"
                )
                if person not in known:
                    raise DataFormatError(
                        path,
                        where,
                        f"group {g}",
                        f"members present in the motion capture (participants {sorted(known)})",
                        f"participant {person}",
                    )
                if person in seen:
                    raise DataFormatError(
                        path,
                        where,
                        f"group {g}",
                        "each participant in one group once",
                        f"participant {person} twice",
                    )
                seen.add(person)
                members.append(person)
            if len(members) >= 2:
                groups.append(tuple(members))
        canonical = tuple(groups)
        if number in annotations:
            if annotations[number] != canonical:
                raise DataFormatError(
                    path,
                    where,
                    "groups",
                    f"the groups of line {first_line[number]}, {annotations[number]}",
                    str(canonical),
                )
            duplicates += 1
            continue
        annotations[number] = canonical
        first_line[number] = line_number
    if not annotations:
        raise DataFormatError(path, None, None, "at least one annotated frame", "none")
    return annotations, duplicates
