"""The DANTE text format (Swofford et al. 2020): SALSA, Cocktail Party, CoffeeBreak and others.

A DANTE folder holds two files:

* ``features.txt``: one line per instant, ``<t> ID_a <fields> ID_b <fields> ...`` (tokens
  separated by spaces). Two layouts exist, detected from the file (and reported): **5 fields per
  person**, ``ID x y body head`` (SALSA's packaging), and **4**, ``ID x y θ`` (the other
  datasets). The token count alone is ambiguous (21 = 1 + 5×4 = 1 + 4×5), so the layout is the
  stride between the person tokens. ``x``, ``y`` are metres; angles are radians,
  counter-clockwise from +x, possibly *unwrapped* (SALSA's reach -65 rad). Person tokens are
  ``"ID_00" + str(n)`` (person 10 is ``ID_0010``). Blocks of a missing person are padded with the
  token ``fake`` (one per slot) and skipped. A person whose x, y or an angle is NaN is dropped
  from that frame (counted in the report).
* ``group_names.txt``: one line per annotated instant, ``<t> < ID_a ID_b > < ID_c > ...``, the
  time string identical to the matching ``features.txt`` line.

The time restarts when a new session begins: a decrease of ``t`` back to the start of the
session before (SALSA's second session starts at 0.20002 after 1932.2, its first at 0.2), or
earlier, opens a new sequence (``session1``, ``session2``, ...); within a session ``t``
increases (a repeated ``t`` is an error). A time going back anywhere else, or after a session of
a single line, is lines out of order and is refused. Ground-truth lines are matched to feature
lines by their exact time string, in file order. SALSA's session-2 time strings carry a +2e-5
offset, so when every time of a file lies within 1e-4 s of a multiple of 0.1 s, a frame's
``time`` is ``round(float(t), 1)``; otherwise (files sampled faster than 10 Hz) it is
``float(t)``. Unix times (Cocktail Party's, in seconds; or in milliseconds, microseconds,
nanoseconds, told apart by their magnitude and spacing) are read in their unit and counted in
seconds from each session's first line.

A file of 3 fields per person (``ID x y``: positions without an orientation) is refused as such.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from reform.datasets._validation import (
    ID_MAX,
    UNWRAPPED_ANGLE_LIMIT_RAD,
    Repairs,
    check_angle,
    check_assumed_metres,
    check_coordinate,
    check_time_increases,
    check_time_unit,
    check_unique_ids,
    make_frame,
    note_absent_members,
    parse_float,
    read_lines,
    read_time_unit,
    require_file,
    units_per_metre,
)
from reform.datasets.errors import DataFormatError, file_errors_as_data_errors
from reform.frame import Dataset, Frame, Group, wrap_angle
from reform.path_argument import path_argument

__all__ = ["FEATURES_FILE", "FIELDS_PER_PERSON", "GROUPS_FILE", "load_dante", "load_salsa"]

FEATURES_FILE = "features.txt"
GROUPS_FILE = "group_names.txt"
# DANTE's repository keeps each dataset's two files in ``datasets/<dataset>/DS_utils/``: a folder
# of this name is named after the one holding it.
DANTE_FILES_FOLDER = "DS_utils"

# Tokens per person block of each layout, and what its fields are.
FIELDS_PER_PERSON = {5: "ID x y body head", 4: "ID x y θ"}
_FAKE = "fake"
_POSITION_ONLY = 3  # fields per person of a file of positions without orientation: ID x y
_ID_PATTERN = re.compile(r"ID_(\d+)")
_TIME_DECIMALS = 1  # SALSA is sampled every 3 s at t = 0.2 + 3k
_TIME_GRID_TOLERANCE_S = 1e-4  # SALSA's session-2 offset is 2e-5 s
# How far after the start of the session before a time going back may land and still start a
# new session: half a frame step (the median of the file's steps forward). SALSA's session 2
# starts 2e-5 s after its session 1, whose step is 3 s; two lines swapped go back to a time at
# least one step after their session's start.
_RESTART_SLACK = 0.5
_NAN_TOKENS = frozenset({"nan", "NaN", "NAN", "-nan", "-NaN"})


@dataclass(frozen=True)
class _Row:
    line: int
    time_string: str
    sequence: str
    time: float
    ids: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    head_yaw: np.ndarray | None


@file_errors_as_data_errors
def load_dante(
    path: str | PathLike[str],
    *,
    groups_path: str | PathLike[str] | None = None,
    strict: bool = False,
    name: str | None = None,
    units: str | None = None,
    metres_per_pixel: float | None = None,
    time_unit: str | None = None,
) -> Dataset:
    """Loads a dataset in the DANTE text format (SALSA, Cocktail Party, ...).

    With 5 fields per person, ``yaw`` is the body (field 4) and ``head_yaw`` the head (field
    5), both wrapped to [-pi, pi); the format has no head position, so ``head_position`` equals
    the body position. With 4 fields, θ is the one orientation and the frames carry no head.
    ``metadata["fields_per_person"]`` says which layout the file has.

    Ground truth is canonicalised: the groups of two or more people are kept as listed (group
    order and member order of the file); every other person is a singleton and is not stored
    in ``Frame.groups``. The field's quirks are repaired and counted in
    ``metadata["report"]["repairs"]`` (``strict=True`` refuses them instead, naming file, line,
    field, expected and found):

    * ``people_missing_from_groundtruth``: people of the frame listed in no group (the file
      should be a full partition) are singletons;
    * ``duplicate_singletons``: a one-person group naming someone already in a larger group is
      dropped;
    * ``groundtruth_members_absent``: a member of a group who is not in that line's features
      stays in the ground truth (``Frame.listed_groups``), so they count as missed as the
      field's evaluation code counts them; detectors see only who is in the features;
    * ``people_dropped_nan``: a person whose x, y or an angle is NaN is dropped from the frame.

    Feature lines without a ground-truth line become frames with ``groups=None``.

    Args:
        path: a folder holding ``features.txt`` and ``group_names.txt`` (or a dataset's folder
            of DANTE's repository, holding them in ``DS_utils/``), or the path of the features
            file itself.
        groups_path: the ground-truth file when ``path`` is a features file (default: the
            ``group_names.txt`` beside it).
        strict: refuse the quirks above instead of repairing them.
        name: the dataset's name (default: the folder's name).
        units: the length unit of the file's positions, ``"m"``, ``"cm"`` or ``"px"`` (with
            ``metres_per_pixel``). None reads metres, the format's unit, and refuses a file
            whose people then stand farther apart than in any dataset of the field
            (`reform.datasets._validation.MAX_SPACING_M`): DANTE's own CoffeeBreak files hold
            centimetres. A unit given is not checked.
        metres_per_pixel: the scale of ``units="px"``; refused with other units.
        time_unit: the unit of the times ``t``, ``"s"``, ``"ms"``, ``"us"`` or ``"ns"``. None
            keeps times below 1e8 as stored (seconds) and reads larger ones as Unix times in
            the unit their magnitude and spacing prove
            (`reform.datasets._validation.read_time_unit`), refusing times that fit no unit.
            Unix times count in seconds from each session's first line; the unit, how it was
            known and each session's origin are in ``metadata["report"]["time_unit"]``.

    Returns:
        The dataset, positions in metres, one sequence per session.

    Raises:
        DataFormatError: a file is missing, empty or malformed (the message names the file,
            line, field, what was expected and what was found).
    """
    function = "load_salsa" if name == "salsa" else "load_dante"
    per_metre = units_per_metre("m" if units is None else units, metres_per_pixel)
    check_time_unit(time_unit)
    path = path_argument(path, name="path", function=function)
    if groups_path is not None:
        groups_path = path_argument(groups_path, name="groups_path", function=function)
    if path.is_dir():
        if not (path / FEATURES_FILE).exists() and (path / DANTE_FILES_FOLDER).is_dir():
            path = path / DANTE_FILES_FOLDER  # a dataset's folder in DANTE's repository layout
        features_path = path / FEATURES_FILE
        groups_file = path / GROUPS_FILE if groups_path is None else groups_path
    else:
        features_path = path
        groups_file = path.parent / GROUPS_FILE if groups_path is None else groups_path
    require_file(features_path, what="a DANTE features file")
    require_file(groups_file, what="a DANTE group file")
    repairs = Repairs(strict=strict)

    rows, fake_blocks, width, rounded, time_report = _read_features(
        features_path, repairs=repairs, per_metre=per_metre, time_unit=time_unit
    )
    gt_lines = _read_groups(groups_file)

    # Match ground-truth lines to feature lines by their exact time string, in file order.
    groups_of_row: dict[int, tuple[int, list[list[int]]]] = {}
    cursor = 0
    for gt_line, time_string, listed in gt_lines:
        while cursor < len(rows) and rows[cursor].time_string != time_string:
            cursor += 1
        if cursor == len(rows):
            raise DataFormatError(
                groups_file,
                f"line {gt_line}",
                "time",
                f"a time string of {features_path.name} (in file order)",
                repr(time_string),
            )
        groups_of_row[cursor] = (gt_line, listed)
        cursor += 1

    frames: list[Frame] = []
    missing_lines = set()
    absent_lines = set()
    for index, row in enumerate(rows):
        groups: tuple[Group, ...] | None = None
        listed_groups: tuple[Group, ...] | None = None
        if index in groups_of_row:
            gt_line, listed = groups_of_row[index]
            groups, listed_groups, n_missing = _canonical_groups(
                listed,
                row.ids,
                path=groups_file,
                where=f"line {gt_line} (t={row.time_string})",
                repairs=repairs,
            )
            if n_missing:
                missing_lines.add(gt_line)
            if listed_groups is not None:
                absent_lines.add(gt_line)
        heads = {}
        if row.head_yaw is not None:
            heads = {"head_position": row.position, "head_yaw": row.head_yaw}
        frames.append(
            make_frame(
                path=features_path,
                where=f"line {row.line}",
                ids=row.ids,
                position=row.position,
                yaw=row.yaw,
                groups=groups,
                listed_groups=listed_groups,
                time=row.time,
                sequence=row.sequence,
                **heads,
            )
        )

    per_sequence = Counter(f.sequence for f in frames)
    annotated = Counter(f.sequence for f in frames if f.groups is not None)
    cut_short = _groundtruth_cut_short(rows, groups_of_row, groups_file, features_path)
    counts = repairs.counts
    report = {
        "fields_per_person": width,
        "feature_lines": len(rows),
        "groundtruth_lines": len(gt_lines),
        "frames_per_sequence": dict(per_sequence),
        "annotated_per_sequence": {s: annotated.get(s, 0) for s in per_sequence},
        "unannotated_feature_lines": [r.line for i, r in enumerate(rows) if i not in groups_of_row],
        "fake_blocks_skipped": fake_blocks,
        "missing_from_groundtruth": counts.get("people_missing_from_groundtruth", 0),
        "groundtruth_lines_with_missing": len(missing_lines),
        "duplicate_singletons": counts.get("duplicate_singletons", 0),
        "groundtruth_lines_with_absent_members": len(absent_lines),
        "time": "round(float(t), 1)" if rounded else "float(t)",
        **repairs.report(),
    }
    if cut_short is not None:
        report["groundtruth_caution"] = cut_short
    if time_report is not None:
        report["time"] = f"float(t) in {time_report['read']}" + (
            ", rounded to 0.1 s" if rounded else ""
        )
        report["time_unit"] = time_report
    folder = features_path.parent
    metadata = {
        "format": "salsa",
        "fields_per_person": width,
        "fields": FIELDS_PER_PERSON[width],
        "features_file": str(features_path),
        "groups_file": str(groups_file),
        "report": report,
    }
    if width == 5:
        metadata["head_position"] = "equal to the body position (the format has none)"
    if units is None:
        check_assumed_metres(frames, path=features_path)
    else:
        metadata["file_units"] = units
    return Dataset(
        frames=tuple(frames),
        name=_dataset_name(folder) if name is None else name,
        source=str(path),
        units="m",
        metadata=metadata,
    )


def _groundtruth_cut_short(
    rows: list[Any], groups_of_row: dict[int, Any], groups_file: Path, features_path: Path
) -> str | None:
    """What a group file that stops before the features leaves without ground truth: the
    feature lines of a session past its last annotated one, when more of them than the
    session's usual step between annotated lines (SALSA leaves one, its last), and every line
    of a session with none while another has some; None when the ends agree."""
    if not groups_of_row:
        return None
    by_session: dict[str, list[int]] = {}
    for index, row in enumerate(rows):
        by_session.setdefault(row.sequence, []).append(index)
    left = []
    for session, indices in by_session.items():
        annotated = [i for i in indices if i in groups_of_row]
        if not annotated:
            left.append((session, len(indices), f"all of {session}"))
            continue
        step = int(np.median(np.diff(annotated))) if len(annotated) > 1 else 1
        trailing = indices[-1] - annotated[-1]
        if trailing > max(step, 1):
            first = rows[annotated[-1] + 1].line
            left.append((session, trailing, f"{session} from line {first} on"))
    if not left:
        return None
    lines = sum(n for _, n, _ in left)
    return (
        f"{groups_file.name} gives no ground truth to {lines:,} lines at the end of "
        f"{features_path.name} ({', '.join(where for _, _, where in left)}): read as frames "
        "without groups; is it cut short?"
    )


def _dataset_name(folder: Path) -> str:
    """The name of the dataset whose files are in ``folder``: the folder's own, or for DANTE's
    ``DS_utils`` its parent's (``datasets/cocktail_party/DS_utils`` is ``cocktail_party``)."""
    parent = folder.resolve().parent.name
    return parent if folder.name == DANTE_FILES_FOLDER and parent else folder.name


@file_errors_as_data_errors
def load_salsa(
    path: str | PathLike[str],
    *,
    groups_path: str | PathLike[str] | None = None,
    strict: bool = False,
) -> Dataset:
    """SALSA in its DANTE packaging: :func:`load_dante` named ``"salsa"``."""
    return load_dante(path, groups_path=groups_path, strict=strict, name="salsa")


def _parse_id(token: str, *, path: Path, where: str) -> int:
    match = _ID_PATTERN.fullmatch(token)
    if match is None:
        raise DataFormatError(path, where, "ID", "a token ID_<number>", repr(token))
    digits = match.group(1).lstrip("0") or "0"
    if len(digits) > len(str(ID_MAX)) or int(digits) > ID_MAX:
        raise DataFormatError(
            path, where, "ID", f"a token ID_<number> with a number <= {ID_MAX}", repr(token)
        )
    return int(digits)


def _is_person_token(token: str) -> bool:
    return token == _FAKE or _ID_PATTERN.fullmatch(token) is not None


def _blocks_fit(tokens: list[str], width: int) -> bool:
    """Whether a line's token count and the tokens inside its blocks (no ID among them) agree
    with ``width`` fields per person, whatever the tokens that start the blocks."""
    if (len(tokens) - 1) % width:
        return False
    inside = (i for i in range(1, len(tokens)) if (i - 1) % width)
    return not any(_ID_PATTERN.fullmatch(tokens[i]) for i in inside)


def _widths_of(tokens: list[str], widths: Iterable[int] = FIELDS_PER_PERSON) -> set[int]:
    """The layouts (fields per person) among ``widths`` a line's tokens agree with."""
    return {
        width
        for width in widths
        if _blocks_fit(tokens, width) and all(map(_is_person_token, tokens[1::width]))
    }


def _layout(path: Path, lines: list[tuple[int, list[str]]]) -> int:
    """Fields per person of the file: the one layout its lines agree with."""
    expected = "1 time token + blocks of 4 (ID x y θ) or 5 (ID x y body head) tokens per person"
    candidates = set(FIELDS_PER_PERSON)
    for line_number, tokens in lines:
        fits = _widths_of(tokens)
        if not fits and len(tokens) > 1 and not _is_person_token(tokens[1]):
            raise DataFormatError(
                path,
                f"line {line_number}",
                "ID",
                "a token ID_<number> (or 'fake') after the time",
                repr(tokens[1]),
            )
        if not fits:
            for width in FIELDS_PER_PERSON:
                if _blocks_fit(tokens, width):  # a layout but for a token starting a block
                    bad = next(t for t in tokens[1::width] if not _is_person_token(t))
                    _parse_id(bad, path=path, where=f"line {line_number}")  # refused as an ID
            _check_orientation(path, lines)
            raise DataFormatError(
                path,
                f"line {line_number}",
                "tokens",
                expected,
                f"{len(tokens)} tokens that fit neither (truncated line?)",
            )
        candidates &= fits
        if not candidates:
            raise DataFormatError(
                path,
                f"line {line_number}",
                "tokens",
                "the same layout on every line",
                f"{sorted(fits)} fields per person where earlier lines have another",
            )
        if len(candidates) == 1:
            return candidates.pop()
    raise DataFormatError(
        path, None, "tokens", expected, "no line with a person telling the layout apart"
    )


def _check_orientation(path: Path, lines: list[tuple[int, list[str]]]) -> None:
    """Refuses a file whose every line holds :data:`_POSITION_ONLY` fields per person (``ID x
    y``): positions without an orientation, which every detector of the field needs."""
    if all(_widths_of(tokens, (_POSITION_ONLY,)) for _, tokens in lines):
        raise DataFormatError(
            path,
            None,
            "orientation",
            "an orientation for every person (4 fields per person, ID x y θ, or 5, ID x y body "
            "head): the detectors need where each person faces",
            f"{_POSITION_ONLY} fields per person on every line (ID x y): positions without an "
            "orientation",
        )


def _read_lines(path: Path) -> list[tuple[int, list[str]]]:
    lines = []
    for line_number, line in read_lines(path):
        tokens = line.split()
        if not tokens:
            raise DataFormatError(
                path,
                f"line {line_number}",
                None,
                "<t> followed by a block of tokens per person",
                "an empty line",
            )
        lines.append((line_number, tokens))
    if not lines:
        raise DataFormatError(path, None, None, "at least one feature line", "none")
    return lines


def _number(token: str, *, path: Path, where: str, field: str, nan: list[str]) -> float:
    """A finite float; a NaN token is noted in ``nan`` (the person is dropped) and read as 0."""
    if token in _NAN_TOKENS:
        nan.append(field)
        return 0.0
    return parse_float(token, path=path, where=where, field=field)


def _read_features(
    path: Path, *, repairs: Repairs, per_metre: float = 1.0, time_unit: str | None = None
) -> tuple[list[_Row], int, int, bool, dict[str, Any] | None]:
    """The rows (positions in metres: the file's divided by ``per_metre``; times in seconds),
    the ``fake`` blocks skipped, the fields per person, whether times are rounded to 0.1 s, and
    the load report's ``time_unit`` entry (None when times are kept as stored)."""
    lines = _read_lines(path)
    width = _layout(path, lines)
    stored = [
        parse_float(tokens[0], path=path, where=f"line {n}", field="t") for n, tokens in lines
    ]
    sessions = _sessions(stored, lines, path=path)
    times, time_report = _seconds(stored, sessions, path=path, time_unit=time_unit)
    rounded = all(abs(t - round(t, _TIME_DECIMALS)) <= _TIME_GRID_TOLERANCE_S for t in times)
    angle_fields = ("body", "head") if width == 5 else ("θ",)
    rows: list[_Row] = []
    fake_blocks = 0
    for k, ((line_number, tokens), time_value) in enumerate(zip(lines, times, strict=True)):
        where = f"line {line_number}"
        n_blocks, extra = divmod(len(tokens) - 1, width)
        if extra:
            raise DataFormatError(
                path,
                where,
                "tokens",
                f"1 time token + a multiple of {width} ({FIELDS_PER_PERSON[width]} per person, "
                "the file's layout)",
                f"{len(tokens)} tokens (truncated line?)",
            )
        time = round(time_value, _TIME_DECIMALS) if rounded else time_value
        if k and sessions[k] == sessions[k - 1]:
            check_time_increases(
                time,
                rows[-1].time,
                path=path,
                where=where,
                field="t",
                previous_where=f"line {rows[-1].line}, t = {rows[-1].time_string}",
                found=repr(tokens[0]) + (f" (t = {time!r})" if str(time) != tokens[0] else ""),
            )

        ids: list[int] = []
        values: list[tuple[float, ...]] = []
        for b in range(n_blocks):
            block = tokens[1 + b * width : 1 + (b + 1) * width]
            if block[0] == _FAKE or block[1] == _FAKE:
                if any(t != _FAKE for t in block[1:]):
                    raise DataFormatError(
                        path,
                        where,
                        f"block {b + 1}",
                        f"a person block or {width} 'fake' tokens",
                        " ".join(block),
                    )
                fake_blocks += 1
                continue
            person = _parse_id(block[0], path=path, where=where)
            person_where = f"{where}, person {person}"
            nan: list[str] = []
            x = _number(block[1], path=path, where=person_where, field="x", nan=nan)
            y = _number(block[2], path=path, where=person_where, field="y", nan=nan)
            check_coordinate(x, path=path, where=person_where, field="x", per_metre=per_metre)
            check_coordinate(y, path=path, where=person_where, field="y", per_metre=per_metre)
            angles = [
                _number(token, path=path, where=person_where, field=field, nan=nan)
                for token, field in zip(block[3:], angle_fields, strict=True)
            ]
            for field, angle in zip(angle_fields, angles, strict=True):
                check_angle(
                    angle,
                    limit=UNWRAPPED_ANGLE_LIMIT_RAD,
                    path=path,
                    where=person_where,
                    field=field,
                )
            if nan:
                repairs.note(
                    "people_dropped_nan",
                    path=path,
                    where=person_where,
                    field=nan[0],
                    expected="a number (a NaN pose: that person is dropped from the frame)",
                    found="NaN",
                )
                continue
            ids.append(person)
            values.append((x, y, *angles))
        check_unique_ids(ids, path=path, where=where)
        array = np.array(values, dtype=np.float64).reshape(-1, 2 + len(angle_fields))
        rows.append(
            _Row(
                line=line_number,
                time_string=tokens[0],
                sequence=f"session{sessions[k]}",
                time=time,
                ids=np.array(ids, dtype=np.int64),
                position=array[:, :2] / per_metre,
                yaw=wrap_angle(array[:, 2]),
                head_yaw=wrap_angle(array[:, 3]) if width == 5 else None,
            )
        )
    return rows, fake_blocks, width, rounded, time_report


def _sessions(stored: list[float], lines: list[tuple[int, list[str]]], *, path: Path) -> list[int]:
    """Each line's session, from 1: a new one begins where the stored time goes back to at most
    :data:`_RESTART_SLACK` frame steps (the file's median) after the start of the session before,
    or earlier.

    Raises:
        DataFormatError: a time going back elsewhere (two lines swapped), or after a session of
            one line (lines in reverse order), naming the line, the time before and after.
    """
    steps = np.diff(np.array(stored))
    steps = steps[steps > 0]
    slack = _RESTART_SLACK * float(np.median(steps)) if steps.size else 0.0
    sessions: list[int] = []
    number = 1
    start = 0  # the index in ``lines`` of the session's first line
    for k, value in enumerate(stored):
        if k and value < stored[k - 1]:
            (line_number, tokens), (before, before_tokens) = lines[k], lines[k - 1]
            later = f"a time later than line {before}'s t = {before_tokens[0]}"
            if k - start < 2:
                raise DataFormatError(
                    path,
                    f"line {line_number}",
                    "t",
                    f"{later} (a time going back starts a new session only after one of two "
                    f"lines or more; line {before}'s would hold one)",
                    repr(tokens[0]),
                )
            if value > stored[start] + slack:
                first, first_tokens = lines[start]
                raise DataFormatError(
                    path,
                    f"line {line_number}",
                    "t",
                    f"{later}, or, starting a new session, one at most half a frame step "
                    f"({slack:.6g}) after the start of the session before (line {first}'s t = "
                    f"{first_tokens[0]})",
                    repr(tokens[0]),
                )
            number += 1
            start = k
        sessions.append(number)
    return sessions


def _seconds(
    stored: list[float], sessions: list[int], *, path: Path, time_unit: str | None
) -> tuple[list[float], dict[str, Any] | None]:
    """Each line's time in seconds (Unix times from their session's first line; ``sessions``:
    each line's session, from :func:`_sessions`) and the report's ``time_unit`` entry (None when
    the times are kept as stored)."""
    by_session: dict[int, list[float]] = {}
    for session, value in zip(sessions, stored, strict=True):
        by_session.setdefault(session, []).append(value)
    reading = read_time_unit(
        [np.array(s) for s in by_session.values()], path=path, field="t", stated=time_unit
    )
    if reading.how == "as stored":
        return stored, None
    seconds: list[float] = []
    origins: dict[str, float | None] = {}
    for number, values in by_session.items():
        converted, origins[f"session{number}"] = reading.seconds(np.array(values))
        seconds.extend(converted.tolist())
    return seconds, reading.report(origins)


def _read_groups(path: Path) -> list[tuple[int, str, list[list[int]]]]:
    out: list[tuple[int, str, list[list[int]]]] = []
    for line_number, line in read_lines(path):
        text = line.rstrip("\r")
        where = f"line {line_number}"
        tokens = text.split()
        if not tokens:
            raise DataFormatError(path, where, None, "<t> < ID ... > ...", "an empty line")
        parse_float(tokens[0], path=path, where=where, field="t")
        groups: list[list[int]] = []
        current: list[int] | None = None
        for position, token in enumerate(tokens[1:], start=2):
            if token == "<":
                if current is not None:
                    raise DataFormatError(
                        path, where, f"token {position}", "'>' closing the group", "'<'"
                    )
                current = []
            elif token == ">":
                if not current:
                    raise DataFormatError(
                        path,
                        where,
                        f"token {position}",
                        "'<' then at least one ID before '>'",
                        "'>'",
                    )
                groups.append(current)
                current = None
            else:
                if current is None:
                    raise DataFormatError(
                        path, where, f"token {position}", "'<' opening a group", repr(token)
                    )
                current.append(_parse_id(token, path=path, where=where))
        if current is not None:
            raise DataFormatError(
                path, where, "groups", "'>' closing the last group", "end of line (truncated?)"
            )
        if not groups:
            raise DataFormatError(path, where, "groups", "at least one group '< ID ... >'", "none")
        out.append((line_number, tokens[0], groups))
    if not out:
        raise DataFormatError(path, None, None, "at least one ground-truth line", "none")
    return out


def _canonical_groups(
    listed: list[list[int]], ids: np.ndarray, *, path: Path, where: str, repairs: Repairs
) -> tuple[tuple[Group, ...], tuple[Group, ...] | None, int]:
    """The frame's ``groups`` (present members of the listed groups of two or more), the
    F-formations as listed when some member is absent from the features (else None), and the
    number of people listed in no group."""
    present = set(ids.tolist())
    grouped: set[int] = set()
    fformations: list[Group] = []
    absent_in_groups = 0
    for g, members in enumerate(listed, start=1):
        if len(set(members)) != len(members):
            raise DataFormatError(
                path, where, f"group {g}", "distinct members", " ".join(map(str, members))
            )
        # Listed alone, an absent person changes no score (singletons are not scored).
        absent = note_absent_members(
            repairs, members, present, path=path, where=where, field=f"group {g}", id_word="id"
        )
        if len(members) >= 2:
            clash = grouped.intersection(members)
            if clash:
                raise DataFormatError(
                    path,
                    where,
                    f"group {g}",
                    "disjoint groups",
                    f"ID {min(clash)} in two groups of 2 or more",
                )
            grouped.update(members)
            fformations.append(tuple(members))
            absent_in_groups += len(absent)
    singletons = [m[0] for m in listed if len(m) == 1]
    duplicates = [s for s in singletons if s in grouped]
    if duplicates:
        repairs.note(
            "duplicate_singletons",
            path=path,
            where=where,
            field="groups",
            expected="each person in one group (a one-person group naming someone already in "
            "a larger group is dropped)",
            found=f"ID {duplicates[0]} alone and in a group",
            count=len(duplicates),
        )
    missing = sorted(present - grouped - set(singletons))
    if missing:
        repairs.note(
            "people_missing_from_groundtruth",
            path=path,
            where=where,
            field="groups",
            expected="a full partition of the frame's people (someone listed in no group is alone)",
            found=f"ID {missing[0]} in no group",
            count=len(missing),
        )
    groups = tuple(
        kept
        for kept in (tuple(m for m in group if m in present) for group in fformations)
        if len(kept) >= 2
    )
    return groups, (tuple(fformations) if absent_in_groups else None), len(missing)
