"""SALSA (Alameda-Pineda et al., TPAMI 2016) in the DANTE text format.

A DANTE folder holds two files:

* ``features.txt``: one line per instant, ``<t> ID_a x y body head ID_b x y body head ...``
  (tokens separated by single spaces). ``x``, ``y`` are metres; ``body`` and ``head`` are
  absolute orientations in radians, counter-clockwise from +x, *unwrapped* (SALSA's reach
  -65 rad). Blocks of a missing person are padded with the token ``fake`` and skipped.
* ``group_names.txt``: one line per annotated instant, ``<t> < ID_a ID_b > < ID_c > ...``, the
  time string identical to the matching ``features.txt`` line.

The time restarts when a new session begins: every decrease of ``t`` opens a new sequence
(``session1``, ``session2``, ...); within a session ``t`` increases (a repeated ``t`` is an
error). SALSA's session-2 time strings carry a +2e-5 offset, so a frame's
``time`` is ``round(float(t), 1)`` and ground-truth lines are matched to feature lines by their
exact time string, in file order.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

import numpy as np

from reform.datasets._validation import (
    UNWRAPPED_ANGLE_LIMIT_RAD,
    check_angle,
    check_coordinate,
    check_time_increases,
    check_unique_ids,
    make_frame,
    parse_float,
    require_file,
)
from reform.datasets.errors import DataFormatError
from reform.frame import Dataset, Frame, Group, wrap_angle

__all__ = ["FEATURES_FILE", "GROUPS_FILE", "load_salsa"]

FEATURES_FILE = "features.txt"
GROUPS_FILE = "group_names.txt"

_BLOCK = 5  # tokens per person: ID, x, y, body, head
_FAKE = "fake"
_ID_PATTERN = re.compile(r"ID_(\d+)")
_TIME_DECIMALS = 1  # SALSA is sampled every 3 s at t = 0.2 + 3k


@dataclass(frozen=True)
class _Row:
    line: int
    time_string: str
    sequence: str
    time: float
    ids: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    head_yaw: np.ndarray


def load_salsa(
    path: str | PathLike[str], *, groups_path: str | PathLike[str] | None = None
) -> Dataset:
    """Loads a dataset in the DANTE text format (SALSA).

    Frames carry body and head: ``yaw`` is column 4 (body), ``head_yaw`` column 5 (head), both
    wrapped to [-pi, pi). SALSA records no separate head position, so ``head_position`` equals
    the body position.

    Ground truth is canonicalised: the groups of two or more people are kept as listed (group
    order and member order of the file); every other person is a singleton and is not stored
    in ``Frame.groups``. People listed in no group and one-person groups naming someone who is
    already in a larger group are irregularities of the annotation; they are counted in
    ``metadata["report"]`` (``missing_from_groundtruth``, ``duplicate_singletons``). Feature
    lines without a ground-truth line become frames with ``groups=None``.

    Args:
        path: a folder holding ``features.txt`` and ``group_names.txt``, or the path of the
            features file itself.
        groups_path: the ground-truth file when ``path`` is a features file (default: the
            ``group_names.txt`` beside it).

    Returns:
        The dataset, named ``"salsa"``, positions in metres, one sequence per session.

    Raises:
        DataFormatError: a file is missing, empty or malformed (the message names the file,
            line, field, what was expected and what was found).
    """
    path = Path(path)
    if path.is_dir():
        features_path = path / FEATURES_FILE
        groups_file = path / GROUPS_FILE if groups_path is None else Path(groups_path)
    else:
        features_path = path
        groups_file = path.parent / GROUPS_FILE if groups_path is None else Path(groups_path)
    require_file(features_path, what="a DANTE features file")
    require_file(groups_file, what="a DANTE group file")

    rows, fake_blocks = _read_features(features_path)
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
    missing = duplicates = 0
    missing_lines = set()
    for index, row in enumerate(rows):
        groups: tuple[Group, ...] | None = None
        if index in groups_of_row:
            gt_line, listed = groups_of_row[index]
            groups, n_missing, n_duplicates = _canonical_groups(
                listed, row.ids, path=groups_file, where=f"line {gt_line} (t={row.time_string})"
            )
            missing += n_missing
            duplicates += n_duplicates
            if n_missing:
                missing_lines.add(gt_line)
        frames.append(
            make_frame(
                path=features_path,
                where=f"line {row.line}",
                ids=row.ids,
                position=row.position,
                yaw=row.yaw,
                head_position=row.position,
                head_yaw=row.head_yaw,
                groups=groups,
                time=row.time,
                sequence=row.sequence,
            )
        )

    per_sequence = Counter(f.sequence for f in frames)
    annotated = Counter(f.sequence for f in frames if f.groups is not None)
    report = {
        "feature_lines": len(rows),
        "groundtruth_lines": len(gt_lines),
        "frames_per_sequence": dict(per_sequence),
        "annotated_per_sequence": {s: annotated.get(s, 0) for s in per_sequence},
        "unannotated_feature_lines": [r.line for i, r in enumerate(rows) if i not in groups_of_row],
        "fake_blocks_skipped": fake_blocks,
        "missing_from_groundtruth": missing,
        "groundtruth_lines_with_missing": len(missing_lines),
        "duplicate_singletons": duplicates,
    }
    return Dataset(
        frames=tuple(frames),
        name="salsa",
        source=str(path),
        units="m",
        metadata={
            "format": "salsa",
            "features_file": str(features_path),
            "groups_file": str(groups_file),
            "head_position": "equal to the body position (the format has none)",
            "report": report,
        },
    )


def _parse_id(token: str, *, path: Path, where: str) -> int:
    match = _ID_PATTERN.fullmatch(token)
    if match is None:
        raise DataFormatError(path, where, "ID", "a token ID_<number>", repr(token))
    return int(match.group(1))


def _read_features(path: Path) -> tuple[list[_Row], int]:
    rows: list[_Row] = []
    fake_blocks = 0
    session = 1
    previous_time: float | None = None
    with open(path, encoding="ascii", errors="replace") as handle:
        for line_number, line in enumerate(handle, start=1):
            text = line.rstrip("\n").rstrip("\r")
            where = f"line {line_number}"
            if not text.strip():
                raise DataFormatError(
                    path, where, None, "<t> followed by blocks of 5 tokens", "an empty line"
                )
            tokens = text.split()
            n_blocks, extra = divmod(len(tokens) - 1, _BLOCK)
            if extra:
                raise DataFormatError(
                    path,
                    where,
                    "tokens",
                    f"1 time token + a multiple of {_BLOCK} (ID x y body head per person)",
                    f"{len(tokens)} tokens (truncated line?)",
                )
            time_value = parse_float(tokens[0], path=path, where=where, field="t")
            time = round(time_value, _TIME_DECIMALS)
            if previous_time is not None and time_value < previous_time:
                session += 1  # the time restarts: a new session
            elif rows:
                check_time_increases(
                    time,
                    rows[-1].time,
                    path=path,
                    where=where,
                    field="t",
                    previous_where=f"line {rows[-1].line}, t = {rows[-1].time_string}",
                    found=repr(tokens[0]) + (f" (t = {time!r})" if str(time) != tokens[0] else ""),
                )
            previous_time = time_value

            ids: list[int] = []
            values: list[tuple[float, float, float, float]] = []
            for b in range(n_blocks):
                block = tokens[1 + b * _BLOCK : 1 + (b + 1) * _BLOCK]
                if block[1] == _FAKE:
                    if any(t != _FAKE for t in block[1:]):
                        raise DataFormatError(
                            path,
                            where,
                            f"block {b + 1}",
                            "a person block or 5 'fake' tokens",
                            " ".join(block),
                        )
                    fake_blocks += 1
                    continue
                person = _parse_id(block[0], path=path, where=where)
                person_where = f"{where}, person {person}"
                x = parse_float(block[1], path=path, where=person_where, field="x")
                y = parse_float(block[2], path=path, where=person_where, field="y")
                check_coordinate(x, path=path, where=person_where, field="x")
                check_coordinate(y, path=path, where=person_where, field="y")
                body = parse_float(block[3], path=path, where=person_where, field="body")
                head = parse_float(block[4], path=path, where=person_where, field="head")
                for name, angle in (("body", body), ("head", head)):
                    check_angle(
                        angle,
                        limit=UNWRAPPED_ANGLE_LIMIT_RAD,
                        path=path,
                        where=person_where,
                        field=name,
                    )
                ids.append(person)
                values.append((x, y, body, head))
            check_unique_ids(ids, path=path, where=where)
            array = np.array(values, dtype=np.float64).reshape(-1, 4)
            rows.append(
                _Row(
                    line=line_number,
                    time_string=tokens[0],
                    sequence=f"session{session}",
                    time=time,
                    ids=np.array(ids, dtype=np.int64),
                    position=array[:, :2],
                    yaw=wrap_angle(array[:, 2]),
                    head_yaw=wrap_angle(array[:, 3]),
                )
            )
    if not rows:
        raise DataFormatError(path, None, None, "at least one feature line", "none")
    return rows, fake_blocks


def _read_groups(path: Path) -> list[tuple[int, str, list[list[int]]]]:
    out: list[tuple[int, str, list[list[int]]]] = []
    with open(path, encoding="ascii", errors="replace") as handle:
        for line_number, line in enumerate(handle, start=1):
            text = line.rstrip("\n").rstrip("\r")
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
                raise DataFormatError(
                    path, where, "groups", "at least one group '< ID ... >'", "none"
                )
            out.append((line_number, tokens[0], groups))
    if not out:
        raise DataFormatError(path, None, None, "at least one ground-truth line", "none")
    return out


def _canonical_groups(
    listed: list[list[int]], ids: np.ndarray, *, path: Path, where: str
) -> tuple[tuple[Group, ...], int, int]:
    """Groups of two or more as listed; counts people missing and duplicate singletons."""
    present = set(ids.tolist())
    grouped: set[int] = set()
    groups: list[Group] = []
    for g, members in enumerate(listed, start=1):
        for person in members:
            if person not in present:
                raise DataFormatError(
                    path,
                    where,
                    f"group {g}",
                    f"members present in the frame (ids {sorted(present)})",
                    f"ID {person}",
                )
        if len(set(members)) != len(members):
            raise DataFormatError(
                path, where, f"group {g}", "distinct members", " ".join(map(str, members))
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
            groups.append(tuple(members))
    singletons = [m[0] for m in listed if len(m) == 1]
    duplicates = sum(1 for s in singletons if s in grouped)
    named = grouped | set(singletons)
    missing = len(present - named)
    return tuple(groups), missing, duplicates
