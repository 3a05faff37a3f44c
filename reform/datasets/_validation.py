"""Checks every loader shares: numbers, angles, files, and frame construction.

Each check raises :class:`~reform.datasets.errors.DataFormatError` naming the file, where in it
(line, frame, row), the field, what was expected and what was found.
"""

from __future__ import annotations

import math
import os
import re
from collections import defaultdict
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from reform.atomic import file_kind
from reform.datasets.errors import DataFormatError, os_error_found
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
ID_MAX = 2**63 - 1  # person ids are int64

# Units of the files' positions per metre (positions are divided by it); "px" has its own scale.
UNITS_PER_M = {"cm": 100.0, "m": 1.0}

# The widest median spacing (distance from a person to their nearest neighbour, the median over
# a dataset's people and frames) a file read in its format's usual unit may have, metres. The
# field's datasets space people 0.2 to 2 m apart; DANTE's CoffeeBreak text files, which hold
# centimetres where the DANTE format holds metres, read as metres put them 60 m and more apart.
MAX_SPACING_M = 20.0

# The widest median spacing a GCFF folder read in centimetres, the unit assumed rather than
# given, may have, metres. The field's sets space people a median of 0.63 m (SALSA) to 1.0 m
# (Babble) from their nearest neighbour, 0.72 m (Synth) and 0.80 m (CoffeeBreak) among the GCFF
# ones, and conversation keeps people within Hall's social distance (3.6 m at most); a folder
# whose people stand a median of more than 3 m apart read as centimetres holds another unit,
# in the field's GCFF packagings image pixels (sets derived from pose estimation).
MAX_CENTIMETRE_SPACING_M = 3.0

# The narrowest median spacing a GCFF folder read in centimetres, the unit assumed rather than
# given, may have, metres. Bodies keep people's centres some 0.3 m apart at the closest. The
# field's sets have medians of 0.60 m (SALSA's first session) and more: 0.72 m (Synth), 0.73 m
# (Cocktail Party, on frames of DANTE's copy in metres), 0.79 m and 0.83 m (CoffeeBreak's two
# sequences), six times this bound or more; no single frame of theirs comes below 0.21 m
# (Babble's narrowest), so even a sequence of one frame clears it; and the strides shipped
# beside them (CoffeeBreak 50 and 20 units, Synth 30) put each o-space centre tens of
# centimetres in front of its people. Read as centimetres, a folder in metres puts its people a
# hundred times closer (0.006 to 0.01 m for those sets): under this bound for any scene whose
# people stand a median of 10 m apart or less, three times the widest conversation allows
# (MAX_CENTIMETRE_SPACING_M).
MIN_CENTIMETRE_SPACING_M = 0.1

# Longest line a text loader reads, characters: a SALSA line of 18 people is 1.3 kB, so this
# holds about 14,000 people; a longer line is a corrupt file (a missing newline, binary data),
# refused before it is split into tokens (a 50 MB line split took 1 GB).
MAX_LINE_CHARS = 1_000_000


# How the field's text files write a number: decimal digits with an optional point and exponent
# (Python's repr, C's %e and %g: '-1.72', '1.767008e+02', '.5'), or a spelling of NaN or infinity
# (refused as not finite, or a person dropped where a loader reads NaN as one). float() takes
# more: digits grouped by '_' ('1_2.5' is 12.5) and non-ASCII digits, which no file writes.
NUMBER = re.compile(
    r"[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:e[+-]?\d+)?|inf|infinity|nan)", re.IGNORECASE | re.ASCII
)


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
            path, None, None, "a readable text file", os_error_found(exc)
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


# How a Git LFS pointer starts: the small text file a clone without Git LFS holds in place of
# each file the repository keeps in LFS.
GIT_LFS_POINTER = b"version https://git-lfs.github.com/spec/"
# Bytes looked at to tell a text file where a binary one is expected. The binary formats read
# hold bytes no text holds well before: a Parquet file right after its 4-byte 'PAR1', a MATLAB
# file by byte 128 (version and byte order follow the 116 bytes of a version 5 header's text;
# version 4 starts with binary integers).
_TEXT_HEAD_BYTES = 512
# The first bytes of a compressed file, by compression: a file compressed whole in place of
# the format's own (the format's reader says only that it cannot parse it).
_COMPRESSED = (
    (b"\x1f\x8b", "gzip"),
    (b"PK\x03\x04", "zip"),
    (b"BZh", "bzip2"),
    (b"\xfd7zXZ\x00", "xz"),
    (b"\x28\xb5\x2f\xfd", "zstd"),
)
_MAT_HEADER_BYTES = 128  # a MATLAB 5 file's header: text, then version and endianness


def check_not_text(
    path: str | Path, *, expected: str, name: str, content: bytes | None = None
) -> None:
    """Refuses a text file where a binary file of the format ``name`` is expected: a Git LFS
    pointer (the file itself was never fetched) or other text, such as a web page saved in its
    place. Anything else, and a file that cannot be opened, is left to the format's reader.

    Args:
        path: the file (or, with ``content``, its name for the message).
        expected: what the file should be (``"a Parquet file"``).
        name: the format's name (``"Parquet"``).
        content: the file's bytes when they are already read (from a store).
    """
    if content is None:
        try:
            with open(path, "rb") as handle:
                head = handle.read(_TEXT_HEAD_BYTES)
        except OSError:
            return
    else:
        head = content[:_TEXT_HEAD_BYTES]
    for magic, compression in _COMPRESSED:
        if head.startswith(magic):
            raise DataFormatError(
                path,
                None,
                None,
                expected,
                f"a {compression}-compressed file",
                hint="decompress it first",
            )
    if name == "MATLAB" and head.startswith(b"MATLAB") and len(head) < _MAT_HEADER_BYTES:
        raise DataFormatError(
            path,
            None,
            None,
            expected,
            f"a MATLAB file cut short inside its {_MAT_HEADER_BYTES}-byte header ({len(head)} "
            "bytes in all)",
        )
    if head.startswith(GIT_LFS_POINTER):
        raise DataFormatError(
            path,
            None,
            None,
            expected,
            "a Git LFS pointer, not the file",
            hint="fetch it with `git lfs pull`",
        )
    text = _text(head)
    if text:
        raise DataFormatError(
            path, None, None, expected, f"text starting with {text[:20]!r}, not a {name} file"
        )


def _text(head: bytes) -> str | None:
    """``head`` decoded, if it is the start of a UTF-8 text with no control character but
    whitespace (a character cut at its end aside); else None."""
    try:
        text = head.decode("utf-8")
    except UnicodeDecodeError as exc:
        if exc.reason != "unexpected end of data":
            return None
        text = head[: exc.start].decode("utf-8")
    if any((ord(c) < 32 and c not in "\t\n\r\f") or c == "\x7f" for c in text):
        return None
    return text


def parse_float(token: str, *, path: Path, where: str, field: str) -> float:
    """A finite float from a text token written as :data:`NUMBER` says (blanks around it
    allowed). A spelling of NaN or infinity is refused as not finite."""
    text = token.strip()
    if NUMBER.fullmatch(text) is None:
        raise DataFormatError(path, where, field, "a number", repr(token))
    value = float(text)
    if not math.isfinite(value):
        raise DataFormatError(path, where, field, "a finite number", repr(token))
    return value


def parse_whole(
    token: str, *, path: Path, where: str, field: str, what: str, limit: int = ID_MAX
) -> int:
    """A whole number >= 0 from a text token of ASCII digits (blanks around it allowed), at most
    ``limit`` (by default `ID_MAX`: an id fits an int64); ``what`` it is, for the message
    (``"a participant number"``). Its digits are counted before they are read: Python reads
    no more than 4,300 of them."""
    text = token.strip()
    if not (text.isascii() and text.isdigit()):
        raise DataFormatError(path, where, field, what, repr(token))
    digits = text.lstrip("0") or "0"
    if len(digits) > len(str(limit)) or int(digits) > limit:
        raise DataFormatError(
            path, where, field, f"{what} <= {limit}", f"{text} ({len(digits):,} digits)"
        )
    return int(digits)


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


def check_assumed_metres(
    frames: Sequence[Frame], *, path: Path, hint: str | None = None
) -> None:
    """Refuses frames read in metres, the unit assumed rather than given, whose people stand
    farther apart than any dataset of the field (:data:`MAX_SPACING_M`): the file holds another
    unit, and every distance a detector saw would be wrong. A unit given on purpose is not
    checked. ``hint``: what to do, for a format whose unit cannot be given."""
    spacing = median_spacing(frames)
    if spacing is None or spacing <= MAX_SPACING_M:
        return
    raise DataFormatError(
        path,
        None,
        "positions",
        f"metres, people a median of at most {MAX_SPACING_M:g} m from their nearest neighbour",
        f"a median of {spacing:.3g} (centimetres, read as metres?)",
        hint=hint
        or "give units='cm' (--units cm) if the file holds centimetres, units='m' if it holds "
        "metres",
    )


# --- units of the files' time stamps --------------------------------------------------------

# Units a file's time stamps may be stated in (time_unit=, --time-unit), seconds per unit.
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
_TIME_UNIT_WORDS = {"s": "seconds", "ms": "milliseconds", "us": "microseconds", "ns": "nanoseconds"}

# Largest |time| read as stored, in seconds (or a GCFF set's frame numbers): over three years.
# The field's recordings last minutes to hours, so larger values are Unix times or another unit.
STORED_TIME_LIMIT = 1e8

# Unix times a recording of the field can carry: 1990-01-01 to 2100-01-01, seconds. In seconds,
# milliseconds, microseconds and nanoseconds these windows lie a factor 1000 apart and never
# overlap, so the magnitude of a file's times names their unit.
UNIX_TIME_RANGE_S = (631_152_000.0, 4_102_444_800.0)

# The median step between frames a unit must make plausible, seconds: motion capture at 1 kHz
# to one frame an hour (the field's sets: 100 Hz for Babble, a frame each 3 s for SALSA, 5 s for
# Cocktail Party). A step outside says the magnitude's unit is not the file's.
FRAME_STEP_RANGE_S = (1e-3, 3600.0)


@dataclass(frozen=True)
class TimeReading:
    """How a file's time stamps are read: their unit, how it was known, and whether they are
    Unix times (then counted from each sequence's first frame, the origin kept in the report).

    Attributes:
        unit: one of :data:`TIME_UNITS`.
        how: ``"as stored"`` (seconds, or frame numbers, kept as the file writes them),
            ``"stated"`` (given by the caller) or ``"inferred"`` (from their magnitude and
            spacing).
        unix: the times are Unix times: each sequence's times count from its first frame.
    """

    unit: str
    how: str
    unix: bool

    def seconds(self, times: np.ndarray) -> tuple[np.ndarray, float | None]:
        """(n,) one sequence's times in seconds (from its first when Unix times), and that
        first time in Unix seconds (None when not Unix times)."""
        times = np.asarray(times, dtype=np.float64)
        per_unit = TIME_UNITS[self.unit]
        if not self.unix or times.size == 0:
            return (times if self.unit == "s" else times * per_unit), None
        return (times - times[0]) * per_unit, float(times[0]) * per_unit

    def describe(self) -> str:
        """The reading in words, for a dataset's metadata."""
        if self.how == "as stored":
            return "as stored (seconds)"
        word = ("Unix " if self.unix else "") + _TIME_UNIT_WORDS[self.unit]
        how = "stated" if self.how == "stated" else "inferred from their magnitude and spacing"
        start = ", counted in seconds from each sequence's first frame" if self.unix else ""
        return f"{word} ({how}){start}"

    def report(self, origins: dict[str, float | None]) -> dict[str, Any]:
        """The load report's entry: unit, how it was known, and each sequence's first time in
        Unix seconds (``origin_unix_s``, when Unix times)."""
        out: dict[str, Any] = {"unit": self.unit, "how": self.how, "read": self.describe()}
        if self.unix:
            out["origin_unix_s"] = dict(origins)
        return out


def check_time_unit(time_unit: str | None) -> None:
    """Raises ValueError unless ``time_unit`` is None or one of :data:`TIME_UNITS`."""
    if time_unit is not None and time_unit not in TIME_UNITS:
        raise ValueError(f"time_unit must be one of {tuple(TIME_UNITS)}, got {time_unit!r}")


def read_time_unit(
    sequences: Sequence[np.ndarray], *, path: Path, field: str, stated: str | None = None
) -> TimeReading:
    """The unit of a file's time stamps: ``stated``, else as their magnitude and spacing prove.

    Times below :data:`STORED_TIME_LIMIT` are kept as stored (seconds, or frame numbers), as the
    field's public sets write them. Larger times are Unix times in the one unit of
    :data:`TIME_UNITS` whose window of dates (:data:`UNIX_TIME_RANGE_S`) holds them all, if
    that unit puts frames a plausible step apart (:data:`FRAME_STEP_RANGE_S`): values near
    1.7e15 a step of 1e5 apart are Unix microseconds (0.1 s steps). A stated unit is trusted;
    its times are Unix times when they fall in the window of dates.

    Args:
        sequences: each sequence's times as stored (increasing), the file's unit.
        path: the file, for the message.
        field: the field holding the times (``"timestamp"``, ``"t"``).
        stated: the unit the caller gives (``time_unit=``, ``--time-unit``), or None.

    Raises:
        DataFormatError: no unit fits (Unix-sized times outside every window or with
            implausible steps, or small times whose frames lie hours apart), naming the file,
            the field, what was expected and found, and the option that states the unit.
    """
    check_time_unit(stated)
    times = [np.asarray(s, dtype=np.float64) for s in sequences if len(s)]
    if not times:
        return TimeReading(stated or "s", "stated" if stated else "as stored", False)
    low = min(float(t.min()) for t in times)
    high = max(float(t.max()) for t in times)
    steps = np.concatenate([np.diff(t) for t in times])
    step = float(np.median(steps)) if steps.size else None
    if stated is not None:
        per_unit = TIME_UNITS[stated]
        unix = UNIX_TIME_RANGE_S[0] <= low * per_unit and high * per_unit <= UNIX_TIME_RANGE_S[1]
        return TimeReading(stated, "stated", unix)
    largest = max(abs(low), abs(high))
    if largest < STORED_TIME_LIMIT:
        if step is None or step <= FRAME_STEP_RANGE_S[1]:
            return TimeReading("s", "as stored", False)
    else:
        for unit, per_unit in TIME_UNITS.items():
            first, last = (bound / per_unit for bound in UNIX_TIME_RANGE_S)
            if first <= low and high <= last:
                if step is None or (
                    FRAME_STEP_RANGE_S[0] <= step * per_unit <= FRAME_STEP_RANGE_S[1]
                ):
                    return TimeReading(unit, "inferred", True)
                break
    found = f"values {low:.10g} to {high:.10g}"
    if step is not None:
        found += f", a median step of {step:.4g} between frames"
    raise DataFormatError(
        path,
        None,
        field,
        f"times in seconds (|t| < {STORED_TIME_LIMIT:g}, frames at most "
        f"{FRAME_STEP_RANGE_S[1]:g} s apart) or Unix times in s, ms, us or ns (dates 1990 to "
        f"2100, frames {FRAME_STEP_RANGE_S[0]:g} s to {FRAME_STEP_RANGE_S[1]:g} s apart)",
        found,
        hint="give their unit with time_unit= (--time-unit): s, ms, us or ns",
    )


def check_assumed_centimetres(frames: Sequence[Frame], *, path: Path) -> None:
    """Refuses frames read in centimetres, the unit assumed rather than given, whose people
    stand farther apart than conversation allows (:data:`MAX_CENTIMETRE_SPACING_M`): the file
    holds image pixels (or another unit); or closer than bodies allow
    (:data:`MIN_CENTIMETRE_SPACING_M`): the file holds metres. Either way every distance a
    detector saw would be wrong. A unit given on purpose is not checked."""
    spacing = median_spacing(frames)
    if spacing is None or MIN_CENTIMETRE_SPACING_M <= spacing <= MAX_CENTIMETRE_SPACING_M:
        return
    if spacing > MAX_CENTIMETRE_SPACING_M:
        side, limit, unit = "at most", MAX_CENTIMETRE_SPACING_M, "image pixels"
        option = (
            "units='px' with metres_per_pixel (--units px --metres-per-pixel M) if the file "
            "holds pixels"
        )
    else:
        side, limit, unit = "at least", MIN_CENTIMETRE_SPACING_M, "metres"
        option = "units='m' (--units m) if the file holds metres"
    raise DataFormatError(
        path,
        None,
        "positions",
        f"centimetres, people a median of {side} {limit * 100:g} units ({limit:g} m) from their "
        "nearest neighbour",
        f"a median of {spacing * 100:.4g} units ({spacing:.3g} m in centimetres: {unit}?)",
        hint=f"give {option}, units='cm' (--units cm) if it holds centimetres",
    )
