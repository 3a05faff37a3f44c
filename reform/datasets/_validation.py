"""Checks every loader shares: numbers, angles, files, and frame construction.

Each check raises :class:`~reform.datasets.errors.DataFormatError` naming the file, where in it
(line, frame, row), the field, what was expected and what was found.
"""

from __future__ import annotations

import math
import os
from collections import defaultdict
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from reform.atomic import file_kind
from reform.datasets.errors import DataFormatError
from reform.features import frame_scale
from reform.frame import POSITION_LIMIT_M, Frame

# Largest |angle| accepted from a file that stores wrapped radians (GCFF, Babble): pi plus the
# rounding of values written with three decimals (Babble's -3.142). Radians.
WRAPPED_ANGLE_LIMIT_RAD = math.pi + 2e-3

# Largest |angle| accepted from a file that stores unwrapped radians (SALSA/DANTE). SALSA's
# annotations drift up to 65.3 rad (about ten turns); angles in degrees reach 90-360 in every
# realistic scene, so a value beyond this bound means degrees, not a long drift. Radians.
UNWRAPPED_ANGLE_LIMIT_RAD = 100.0

# Person ids are integers >= 0 in every format of the field: DANTE's ID_<digits> and Babble's
# participant numbers cannot be negative, the public GCFF sets number people from 1, and
# generated datasets from 0 (the robot). A negative id is refused with this reason.
ID_RULE = "person ids are never negative"

# Units of the files' positions per metre (positions are divided by it); "px" has its own scale.
UNITS_PER_M = {"cm": 100.0, "m": 1.0}

# The widest median spacing (distance from a person to their nearest neighbour, the median over
# a dataset's people and frames) a file read in its format's usual unit may have, metres. The
# field's datasets space people 0.2 to 2 m apart; DANTE's CoffeeBreak text files, which hold
# centimetres where the DANTE format holds metres, read as metres put them 60 m and more apart.
MAX_SPACING_M = 20.0

# Longest line a text loader reads, characters: a SALSA line of 18 people is 1.3 kB, so this
# holds about 14,000 people; a longer line is a corrupt file (a missing newline, binary data),
# refused before it is split into tokens (a 50 MB line split took 1 GB).
MAX_LINE_CHARS = 1_000_000


def read_lines(path: Path) -> Iterator[tuple[int, str]]:
    """The lines of a text file (line number from 1, the line without its newline), read one
    at a time as ASCII (other bytes become U+FFFD and are refused where they stand).

    Raises:
        DataFormatError: a line longer than :data:`MAX_LINE_CHARS`, naming it; or the file
            cannot be read.
    """
    try:
        with open(path, encoding="ascii", errors="replace", newline=None) as handle:
            for number in range(1, 2**62):
                line = handle.readline(MAX_LINE_CHARS + 1)
                if not line:
                    return
                if len(line) > MAX_LINE_CHARS:
                    raise DataFormatError(
                        path,
                        f"line {number}",
                        None,
                        f"a line of at most {MAX_LINE_CHARS:,} characters (a longer one is a "
                        "corrupt file: a missing newline, binary data)",
                        "a longer line",
                    )
                yield number, line.rstrip("\n")
    except OSError as exc:
        raise DataFormatError(
            path, None, None, "a readable text file", f"{type(exc).__name__}: {exc.strerror}"
        ) from None


def require_file(path: Path, *, what: str) -> Path:
    """``path`` if it is an existing, non-empty, readable regular file.

    Raises:
        DataFormatError: if it is missing, a folder, a FIFO, a socket, a device, a link loop,
            unreadable, or empty.
    """
    kind = file_kind(path)
    if kind in ("no such file", "a dangling symbolic link"):
        raise DataFormatError(path, None, None, f"{what} (an existing file)", kind)
    if kind != "a file":
        raise DataFormatError(path, None, None, f"{what} (a file)", kind)
    if not os.access(path, os.R_OK):
        raise DataFormatError(path, None, None, f"{what} (a readable file)", "permission denied")
    if path.stat().st_size == 0:
        raise DataFormatError(path, None, None, f"{what} (a non-empty file)", "an empty file")
    return path


def parse_float(token: str, *, path: Path, where: str, field: str) -> float:
    """A finite float from a text token."""
    try:
        value = float(token)
    except ValueError:
        raise DataFormatError(path, where, field, "a number", repr(token)) from None
    if not math.isfinite(value):
        raise DataFormatError(path, where, field, "a finite number", repr(token))
    return value


def check_finite(value: float, *, path: Path, where: str, field: str) -> float:
    """``value`` if it is finite."""
    if not math.isfinite(value):
        raise DataFormatError(path, where, field, "a finite number", repr(value))
    return value


def check_coordinate(
    value: float, *, path: Path, where: str, field: str, per_metre: float = 1.0
) -> float:
    """``value`` (a position coordinate in file units) if finite and a plausible distance.

    Args:
        value: the coordinate as stored.
        per_metre: file units per metre (100 for centimetres); the bound is
            :data:`reform.frame.POSITION_LIMIT_M` metres.
    """
    check_finite(value, path=path, where=where, field=field)
    limit = POSITION_LIMIT_M * per_metre
    if abs(value) > limit:
        unit = "m" if per_metre == 1.0 else "file units"
        raise DataFormatError(
            path,
            where,
            field,
            f"a position with |value| <= {limit:g} {unit} (farther looks like a corrupt value)",
            repr(value),
        )
    return value


def check_time_increases(
    time: float,
    previous: float | None,
    *,
    path: Path,
    where: str,
    field: str,
    previous_where: str | None,
    found: str | None = None,
) -> float:
    """``time`` if it is later than ``previous`` (the sequence's last time; None at its start).

    Args:
        previous_where: where ``previous`` was read (``"line 3"``), for the message.
        found: the value as the file writes it, for the message (default ``repr(time)``).
    """
    if previous is not None and not time > previous:
        raise DataFormatError(
            path,
            where,
            field,
            f"a time > {previous!r} (that of the sequence's previous frame, {previous_where}): "
            "time increases within a sequence",
            repr(time) if found is None else found,
        )
    return time


def check_angle(value: float, *, limit: float, path: Path, where: str, field: str) -> float:
    """``value`` if it is finite and within ``[-limit, limit]`` radians."""
    check_finite(value, path=path, where=where, field=field)
    if abs(value) > limit:
        raise DataFormatError(
            path,
            where,
            field,
            f"an angle in radians with |value| <= {limit:.4g} (larger values look like degrees)",
            repr(value),
        )
    return value


def check_unique_ids(ids: Iterable[int], *, path: Path, where: str, field: str = "ID") -> None:
    """Raises when an id occurs twice."""
    seen: set[int] = set()
    for person in ids:
        if person in seen:
            raise DataFormatError(
                path, where, field, "ids unique within the frame", f"id {person} twice"
            )
        seen.add(person)


def make_frame(*, path: Path, where: str, **fields: Any) -> Frame:
    """``Frame(**fields)``, with a validation error re-raised as a DataFormatError."""
    try:
        return Frame(**fields)
    except ValueError as exc:
        raise DataFormatError(path, where, "frame", "a valid frame", str(exc)) from exc


class Repairs:
    """The load report's count of every repair a loader makes to a file's ordinary quirks.

    Real annotation files carry quirks their authors lived with (a ground-truth member the
    tracker lost, a person whose pose is NaN). A loader repairs them as the field's protocol
    does and counts each kind here; with ``strict`` it refuses the first one instead, naming
    the file, where, the field, what was expected and what was found.
    """

    def __init__(self, *, strict: bool = False) -> None:
        self.strict = strict
        self.counts: dict[str, int] = {}
        self.first: dict[str, str] = {}

    def note(
        self,
        kind: str,
        *,
        path: Path,
        where: str | None,
        field: str | None,
        expected: str,
        found: str,
        count: int = 1,
    ) -> None:
        """Counts ``count`` repairs of ``kind``; raises instead when strict."""
        error = DataFormatError(
            path, where, field, expected, found, hint="refused by --strict (strict=True)"
        )
        if self.strict:
            raise error
        self.counts[kind] = self.counts.get(kind, 0) + count
        self.first.setdefault(kind, str(error).removesuffix("; refused by --strict (strict=True)"))

    def report(self) -> dict[str, Any]:
        """``{"repairs": {kind: count}, "first_repair": {kind: message}}`` (empty when none)."""
        return {"repairs": dict(self.counts), "first_repair": dict(self.first)}


def note_absent_members(
    repairs: Repairs,
    members: Iterable[int],
    present: set[int],
    *,
    path: Path,
    where: str,
    field: str,
    id_word: str = "ID",
) -> list[int]:
    """The listed ``members`` absent from the frame's features, each counted as the repair
    ``groundtruth_members_absent`` (they stay in the ground truth and count as missed)."""
    absent = [m for m in members if m not in present]
    if absent:
        repairs.note(
            "groundtruth_members_absent",
            path=path,
            where=where,
            field=field,
            expected=f"members present in the frame's features ({id_word}s {sorted(present)}); "
            "an absent member stays in the ground truth and counts as missed",
            found=f"ID {absent[0]}",
            count=len(absent),
        )
    return absent


def units_per_metre(units: str, metres_per_pixel: float | None) -> float:
    """File units per metre of ``units`` (``"px"`` with its ``metres_per_pixel``).

    Raises:
        ValueError: an unknown unit, pixels without a scale, a scale for another unit, or a
            scale that is not a positive finite number.
    """
    if units not in (*UNITS_PER_M, "px"):
        raise ValueError(f"units must be one of {(*UNITS_PER_M, 'px')}, got {units!r}")
    if units != "px":
        if metres_per_pixel is not None:
            raise ValueError(
                f"metres_per_pixel is the scale of units='px', got it with units={units!r}"
            )
        return UNITS_PER_M[units]
    if metres_per_pixel is None:
        raise ValueError(
            "units='px' needs metres_per_pixel (--metres-per-pixel M): pixel positions are "
            "never read as metres"
        )
    if (
        isinstance(metres_per_pixel, bool)
        or not isinstance(metres_per_pixel, (int, float))
        or not math.isfinite(metres_per_pixel)
        or metres_per_pixel <= 0
    ):
        raise ValueError(f"metres_per_pixel must be a positive number, got {metres_per_pixel!r}")
    return 1.0 / float(metres_per_pixel)


def median_spacing(frames: Sequence[Frame]) -> float | None:
    """The median, over frames of 2 people or more, of each frame's scale (the median distance
    from a person to their nearest neighbour, `reform.features.frame_scale`), in the frames'
    unit; None without such a frame."""
    by_size: dict[int, list[np.ndarray]] = defaultdict(list)
    for frame in frames:
        if frame.n_people >= 2:
            by_size[frame.n_people].append(frame.position)
    if not by_size:
        return None
    scales = [np.atleast_1d(frame_scale(np.stack(group))) for group in by_size.values()]
    return float(np.median(np.concatenate(scales)))


def check_assumed_metres(frames: Sequence[Frame], *, path: Path) -> None:
    """Refuses frames read in metres, the unit assumed rather than given, whose people stand
    farther apart than any dataset of the field (:data:`MAX_SPACING_M`): the file holds another
    unit, and every distance a detector saw would be wrong. A unit given on purpose is not
    checked."""
    spacing = median_spacing(frames)
    if spacing is None or spacing <= MAX_SPACING_M:
        return
    raise DataFormatError(
        path,
        None,
        "positions",
        f"metres, people a median of at most {MAX_SPACING_M:g} m from their nearest neighbour",
        f"a median of {spacing:.3g} (centimetres, read as metres?)",
        hint="give units='cm' (--units cm) if the file holds centimetres, units='m' if it "
        "holds metres",
    )
