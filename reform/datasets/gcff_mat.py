"""The GCFF MATLAB format (Setti et al. 2015) used by CoffeeBreak, Cocktail Party, Synth, GDet.

A GCFF folder holds:

* ``features.mat``: ``features``, a 1×T cell array of N×4 matrices ``[ID, x, y, θ]`` (one per
  frame; θ radians counter-clockwise from +x; x, y in the dataset's ground units) and
  ``timestamp``, 1×T;
* ``groundtruth.mat``: ``GTgroups``, a 1×G cell array, each a cell array of row vectors of IDs
  (one per group), and ``GTtimestamp``, 1×G, a subset of ``timestamp``;
* optionally ``settings_gc.mat``: ``stride`` (a length) and ``mdl`` (a squared length), the GCFF
  parameters tuned for the dataset.

The public sets write positions in centimetre-like units, so :func:`load_gcff` assumes
centimetres unless told otherwise (refusing a folder whose spacing says image pixels or metres)
and converts to metres. Time stamps are frame numbers or seconds in the public sets, kept as
stored; Unix times (in seconds, milliseconds, microseconds or nanoseconds, told apart by their
magnitude and spacing) are read in their unit and counted in seconds from each sequence's start.
"""

from __future__ import annotations

import math
import struct
import zlib
from collections import Counter
from os import PathLike
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from reform.datasets._isolated import IsolatedFailure, run_isolated
from reform.datasets._mat5 import read_mat5
from reform.datasets._validation import (
    ID_RULE,
    Repairs,
    TimeReading,
    check_assumed_centimetres,
    check_not_text,
    check_time_increases,
    check_time_unit,
    check_unique_ids,
    file_kind,
    make_frame,
    note_absent_members,
    read_time_unit,
    require_file,
    units_per_metre,
)
from reform.datasets.errors import (
    DataFormatError,
    damaged_found,
    file_errors_as_data_errors,
    os_error_found,
)
from reform.frame import POSITION_LIMIT_M, Dataset, Frame, Group, wrap_angle
from reform.gcff import MDL_LIMIT_M2, STRIDE_LIMIT_M
from reform.machine import available_memory
from reform.path_argument import path_argument

__all__ = [
    "FEATURES_FILE",
    "GROUNDTRUTH_FILE",
    "MAT_INFLATED_LIMIT_BYTES",
    "SETTINGS_FILE",
    "load_gcff",
    "read_settings",
    "sequence_folders",
    "units_per_metre",
]

FEATURES_FILE = "features.mat"
GROUNDTRUTH_FILE = "groundtruth.mat"
SETTINGS_FILE = "settings_gc.mat"

# GCFF files store radians, in [-pi, pi] in some sets and [0, 2pi) in others, and a little
# beyond in sets derived from tracker output (Cocktail Party's run to 6.8 rad); anything up to
# two full turns is accepted and wrapped. Beyond that the values look like degrees. Radians.
_ANGLE_LIMIT_RAD = 4.0 * math.pi
_ID_LIMIT = 2.0**53  # largest |ID| a double holds exactly
_TIMESTAMP_RTOL = 1e-9  # relative tolerance matching GTtimestamp to timestamp
# ... capped at this share of the smallest step between frames: at Unix times (1.3e9 s) the
# relative tolerance alone spans more than a second, which could attach a ground truth to a
# neighbouring frame's time.
_TIMESTAMP_STEP_SHARE = 1e-3
# Most bytes a GCFF .mat file's variables may take once inflated, bytes: the public files inflate
# to 35 kB at most (features.mat of CoffeeBreak and Synth; 2.4 times their compressed size), and
# a GCFF file of 10,000 frames of 50 people would hold 16 MB of [ID, x, y, θ]; a file claiming
# more is a compressed bomb or corrupt. Also at most a quarter of the memory available.
MAT_INFLATED_LIMIT_BYTES = 256 * 2**20
_MAT_HEADER_BYTES = 128  # a MATLAB 5 file's text header, subsystem offset, version, endianness
_MI_MATRIX = 14  # data element types of a MATLAB 5 file
_MI_COMPRESSED = 15
_INFLATE_CHUNK = 2**20  # bytes inflated at a time while counting


@file_errors_as_data_errors
def load_gcff(
    path: str | PathLike[str],
    *,
    units: str | None = None,
    metres_per_pixel: float | None = None,
    strict: bool = False,
    time_unit: str | None = None,
) -> Dataset:
    """Loads a GCFF MATLAB folder, or a folder of them (one sequence each).

    Frames carry the body only (``head_position`` and ``head_yaw`` are None): GCFF's θ is one
    orientation per person. ``time`` is the frame's ``timestamp`` as stored (its unit is the
    dataset's; often a frame index), or, for Unix times, seconds from the sequence's first
    frame (see ``time_unit``). Ground truth is canonicalised as for the other formats:
    groups of two or more as listed, everyone else a singleton; frames whose timestamp is not
    in ``GTtimestamp`` have ``groups=None``.

    The field's files carry quirks that are repaired as the field's protocol does, each counted
    in ``metadata["report"]["repairs"]`` (``strict=True`` refuses them instead):

    * ``groundtruth_members_absent``: a ground-truth member who is not in that frame's
      features (the annotators saw someone the tracker did not) stays in the ground truth
      (``Frame.listed_groups``), so that they count as a missed member exactly as the original
      evaluation code (``ff_evalgroups.m``) counts them; the detectors see only who is in the
      features.
    * ``people_dropped_nan``: a row whose x, y or θ is NaN (a pose the estimator did not find)
      is dropped from that frame; if the annotation names that person, they are an absent
      member as above.

    A folder without ``features.mat`` whose subfolders hold GCFF folders (CoffeeBreak's
    ``Seq1``, ``Seq2``; GDet's ``S1`` … ``S6``) is read as one dataset, a sequence per
    subfolder in name order, each with its own ``settings_gc.mat``.

    Args:
        path: the folder (or its ``features.mat``), or a folder of such folders.
        units: length unit of the files' positions, ``"cm"`` (as the public sets use),
            ``"m"``, or ``"px"`` (image pixels, sets derived from pose estimation; needs
            ``metres_per_pixel``). Positions are converted to metres. None reads centimetres
            and refuses a sequence whose people then stand a median of more than 3 m from their
            nearest neighbour (`reform.datasets._validation.MAX_CENTIMETRE_SPACING_M`): its
            positions are image pixels; or of less than 0.1 m
            (`reform.datasets._validation.MIN_CENTIMETRE_SPACING_M`): they are metres. A unit
            given is not checked.
        metres_per_pixel: the scale of ``units="px"``; refused with other units.
        strict: refuse the quirks listed above instead of repairing them.
        time_unit: the unit of ``timestamp``, ``"s"``, ``"ms"``, ``"us"`` or ``"ns"``. None
            keeps times below 1e8 as stored (seconds or frame numbers) and reads larger ones as
            Unix times in the unit their magnitude and spacing prove
            (`reform.datasets._validation.read_time_unit`), refusing times that fit no unit.
            Unix times count in seconds from each sequence's first frame; the unit, how it was
            known and each sequence's origin are in ``metadata["report"]["time_unit"]``.

    Returns:
        The dataset, named after the folder, a sequence per folder. ``metadata["settings_gc"]``
        holds ``stride`` and ``mdl`` as stored (file units) and converted (``stride_m``,
        ``mdl_m2``) when ``settings_gc.mat`` exists (one folder);
        ``metadata["settings_gc_by_sequence"]`` holds them per sequence (always).

    Raises:
        ValueError: ``units`` or ``time_unit`` is unknown, or ``metres_per_pixel`` is missing
            for pixels, given for another unit, or not a positive finite number.
        DataFormatError: a file is missing, unreadable or malformed, its positions' spacing
            says pixels or metres (``units`` None), or its time stamps fit no unit
            (``time_unit`` None).
    """
    path = path_argument(path, name="path", function="load_gcff")
    per_metre = units_per_metre("cm" if units is None else units, metres_per_pixel)
    check_time_unit(time_unit)
    folder = path.parent if path.is_file() else path
    if not folder.is_dir():
        raise DataFormatError(
            folder, None, None, "a GCFF folder (features.mat, groundtruth.mat)", "no such folder"
        )
    sequences = [folder] if (folder / FEATURES_FILE).exists() else sequence_folders(folder)
    if sequences and sequences[0] != folder:
        _check_only_sequences(folder, sequences)
    if not sequences:
        raise DataFormatError(
            folder,
            None,
            None,
            "a GCFF folder (features.mat, groundtruth.mat) or a folder of them",
            "no features.mat in it or in its subfolders",
        )
    repairs = Repairs(strict=strict)
    frames: list[Frame] = []
    reports: dict[str, dict[str, Any]] = {}
    settings: dict[str, dict[str, Any]] = {}
    times: dict[str, tuple[TimeReading, float | None]] = {}
    file_units = "cm" if units is None else units
    for sequence_folder in sequences:
        sequence_frames, report, times[sequence_folder.name] = _load_sequence(
            sequence_folder, per_metre=per_metre, repairs=repairs, time_unit=time_unit
        )
        if units is None:
            check_assumed_centimetres(sequence_frames, path=sequence_folder / FEATURES_FILE)
        frames.extend(sequence_frames)
        reports[sequence_folder.name] = report
        settings_path = sequence_folder / SETTINGS_FILE
        if settings_path.exists():
            settings[sequence_folder.name] = _settings(
                settings_path, units=file_units, metres_per_pixel=metres_per_pixel
            )

    totals = Counter()
    for report in reports.values():
        totals.update(report)
    report_out: dict[str, Any] = dict(totals)
    if len(reports) > 1:
        report_out["by_sequence"] = reports
    report_out.update(repairs.report())
    dropped = repairs.counts.get("people_dropped_nan", 0)
    if units is None and dropped:
        report_out["units_caution"] = (
            f"positions read in centimetres, the unit assumed when none is given, though "
            f"{dropped} poses are NaN, the mark of a set derived from pose estimation, whose "
            "positions are image pixels: give units='px' with metres_per_pixel (--units px "
            "--metres-per-pixel M) if they are pixels, units='cm' (--units cm) to say they "
            "are centimetres"
        )
    time_text = "timestamp as stored in features.mat"
    readings = {reading for reading, _ in times.values()}
    if readings != {TimeReading("s", "as stored", False)}:
        if len(readings) == 1:
            (reading,) = readings
            time_text = f"timestamp of features.mat in {reading.describe()}"
            report_out["time_unit"] = reading.report({k: o for k, (_, o) in times.items()})
        else:
            time_text = "timestamp of features.mat, read per sequence (report: time_unit)"
            report_out["time_unit"] = {k: r.report({k: o}) for k, (r, o) in times.items()}
    metadata: dict[str, Any] = {
        "format": "gcff",
        "file_units": file_units,
        "time": time_text,
        "report": report_out,
        "settings_gc_by_sequence": settings,
    }
    if units == "px":
        metadata["metres_per_pixel"] = metres_per_pixel
    if len(sequences) == 1 and settings:
        metadata["settings_gc"] = next(iter(settings.values()))
    return Dataset(
        frames=tuple(frames), name=folder.name, source=str(folder), units="m", metadata=metadata
    )


def sequence_folders(folder: Path) -> list[Path]:
    """The subfolders of ``folder`` holding a ``features.mat``, in name order."""
    try:
        children = sorted(folder.iterdir())
    except OSError as exc:
        raise DataFormatError(
            folder, None, None, "a readable folder", os_error_found(exc)
        ) from None
    found = []
    for child in children:
        try:
            if child.is_dir() and (child / FEATURES_FILE).is_file():
                found.append(child)
        except OSError as exc:  # a subfolder that cannot be looked into: named, not its file
            raise DataFormatError(
                child, None, None, "a readable folder", os_error_found(exc)
            ) from None
    return found


# Files that show a folder holds a dataset of another format (or of this one, deeper).
_OTHER_DATASET_FILES = ("features.txt", "Motion-capture-data.csv", "dataset.json")


# The files of a GCFF sequence folder besides features.mat ("settings.mat": an older method's).
_SEQUENCE_FILES = (GROUNDTRUTH_FILE, SETTINGS_FILE, "settings.mat")


def _broken_sequence(child: Path) -> str | None:
    """What keeps a subfolder that is a GCFF sequence by its ground truth (or a near name of
    its features file) from being read as one: its ``features.mat`` missing, or not a file (a
    folder, a link that leads nowhere), with what it holds instead; None when it is no
    sequence, or a whole one."""
    try:
        names = sorted(entry.name for entry in child.iterdir())
    except OSError as exc:
        return f"a folder that cannot be listed: {os_error_found(exc)}"
    near = [n for n in names if n != FEATURES_FILE and n.lower().startswith(FEATURES_FILE)]
    if not (GROUNDTRUTH_FILE in names or near or FEATURES_FILE in names):
        return None  # settings alone make no sequence (the public Poster folder ships only those)
    features = child / FEATURES_FILE
    if FEATURES_FILE in names:
        if features.is_file():
            return None
        kind = "a folder" if features.is_dir() else "a link that leads to no file"
        return f"{FEATURES_FILE} that is {kind}"
    held = ", ".join(n for n in names if n in _SEQUENCE_FILES or n in near)
    return f"{held} but no {FEATURES_FILE}"


def _check_only_sequences(folder: Path, sequences: list[Path]) -> None:
    """Refuses a folder of GCFF sequences whose other subfolders hold datasets too (a folder of
    datasets, such as the one all the public sets are fetched into): reading the GCFF ones as
    one dataset would leave the others out without a word. So is one whose other subfolder is
    a sequence that cannot be read (`_broken_sequence`): it would be left out the same way."""
    others = []
    broken: list[tuple[Path, str]] = []
    for child in sorted(folder.iterdir()):
        if child in sequences or child.name.startswith((".", "_")) or not child.is_dir():
            continue
        what = _broken_sequence(child)
        if what is not None:
            broken.append((child, what))
            continue
        try:
            holds = any((child / name).is_file() for name in _OTHER_DATASET_FILES) or bool(
                sequence_folders(child)
            )
        except (OSError, DataFormatError):
            holds = False
        if holds:
            others.append(child.name)
    if others:
        raise DataFormatError(
            folder,
            None,
            None,
            "a GCFF folder, or a folder of GCFF sequence folders only",
            f"a folder of datasets: GCFF sequences {[s.name for s in sequences]} beside "
            f"other datasets {others}",
            hint="name one dataset's folder",
        )
    if broken:
        child, what = broken[0]
        raise DataFormatError(
            child,
            None,
            None,
            f"a GCFF sequence folder like {', '.join(s.name for s in sequences)}, with its "
            f"{FEATURES_FILE}",
            what,
            hint="put its features file back, or move the folder out, to read the others",
        )


def _load_sequence(
    folder: Path, *, per_metre: float, repairs: Repairs, time_unit: str | None
) -> tuple[list[Frame], dict[str, int], tuple[TimeReading, float | None]]:
    """The frames of one GCFF folder, its report counts, and how its time stamps were read
    (with the first one in Unix seconds when they are Unix times)."""
    features_path = require_file(folder / FEATURES_FILE, what="the GCFF features file")
    groundtruth_path = require_file(folder / GROUNDTRUTH_FILE, what="the GCFF ground-truth file")

    features_mat = _loadmat(features_path)
    features = _cells(
        _variable(features_mat, "features", features_path), path=features_path, field="features"
    )
    timestamps = _vector(
        _variable(features_mat, "timestamp", features_path), path=features_path, field="timestamp"
    )
    if timestamps.size != len(features):
        raise DataFormatError(
            features_path,
            None,
            "timestamp",
            f"{len(features)} values (one per features cell)",
            f"{timestamps.size}",
        )
    order: dict[float, int] = {}
    previous: float | None = None
    for t, value in enumerate(timestamps.tolist()):
        check_time_increases(
            value,
            previous,
            path=features_path,
            where=f"frame {t + 1}",
            field="timestamp",
            previous_where=f"frame {t}",
        )
        order[value] = t
        previous = value
    reading = read_time_unit([timestamps], path=features_path, field="timestamp", stated=time_unit)
    seconds, origin = reading.seconds(timestamps)

    gt_mat = _loadmat(groundtruth_path)
    gt_cells = _cells(
        _variable(gt_mat, "GTgroups", groundtruth_path), path=groundtruth_path, field="GTgroups"
    )
    gt_times = _vector(
        _variable(gt_mat, "GTtimestamp", groundtruth_path),
        path=groundtruth_path,
        field="GTtimestamp",
    )
    if gt_times.size != len(gt_cells):
        raise DataFormatError(
            groundtruth_path,
            None,
            "GTtimestamp",
            f"{len(gt_cells)} values (one per GTgroups cell)",
            f"{gt_times.size}",
        )

    rows = [
        _frame_rows(cell, path=features_path, frame=t + 1, per_metre=per_metre, repairs=repairs)
        for t, cell in enumerate(features)
    ]

    listed_of_frame: dict[int, tuple[int, list[list[int]]]] = {}
    smallest_step = float(np.diff(timestamps).min()) if timestamps.size > 1 else math.inf
    for g, (cell, stamp) in enumerate(zip(gt_cells, gt_times.tolist(), strict=True)):
        where = f"GT frame {g + 1} (GTtimestamp {stamp:g})"
        t = _match_time(stamp, timestamps, order, smallest_step)
        if t is None:
            raise DataFormatError(
                groundtruth_path,
                where,
                "GTtimestamp",
                "a value of features.mat's timestamp",
                f"{stamp!r}",
            )
        if t in listed_of_frame:
            raise DataFormatError(
                groundtruth_path,
                where,
                "GTtimestamp",
                "one ground truth per frame",
                f"frame {t + 1} annotated twice",
            )
        listed_of_frame[t] = (g, _groups(cell, path=groundtruth_path, where=where))

    frames: list[Frame] = []
    report: Counter[str] = Counter()
    for t, (ids, position, yaw) in enumerate(rows):
        groups: tuple[Group, ...] | None = None
        listed_groups: tuple[Group, ...] | None = None
        if t in listed_of_frame:
            g, listed = listed_of_frame[t]
            groups, listed_groups = _canonical(
                listed,
                ids,
                path=groundtruth_path,
                where=f"GT frame {g + 1} (GTtimestamp {gt_times[g]:g})",
                report=report,
                repairs=repairs,
            )
        frames.append(
            make_frame(
                path=features_path,
                where=f"frame {t + 1}",
                ids=ids,
                position=position / per_metre,
                yaw=wrap_angle(yaw),
                groups=groups,
                listed_groups=listed_groups,
                time=float(seconds[t]),
                sequence=folder.name,
            )
        )
    counts = {
        "frames": len(frames),
        "annotated_frames": len(listed_of_frame),
        "groundtruth_singletons_listed": report["singletons_listed"],
        "duplicate_singletons": report["duplicate_singletons"],
        "people_in_no_group": report["people_in_no_group"],
        "groundtruth_frames_with_absent_members": report["frames_with_absent"],
    }
    return frames, counts, (reading, origin)


def _loadmat(path: Path) -> dict[str, Any]:
    kind = file_kind(path)
    if kind != "a file":
        raise DataFormatError(path, None, None, "a MATLAB .mat file", kind)
    check_not_text(path, expected="a MATLAB .mat file", name="MATLAB")
    check_inflated_size(path)
    found = _read_plain(path)
    if found is not None:
        return found
    import scipy.io  # noqa: F401 - imported here, so that no child imports it again

    try:
        # In a child process: a corrupt file can crash scipy's compiled reader.
        return run_isolated(_read_mat, str(path))
    except IsolatedFailure as exc:
        if exc.kind == "NotImplementedError":  # MATLAB v7.3 (HDF5)
            raise DataFormatError(
                path, None, None, "a MATLAB file of version 7.2 or older", exc.message
            ) from None
        # scipy raises ValueError, TypeError, OSError, MemoryError... on corrupt files
        if exc.kind == "crash":
            found = exc.message
        elif exc.kind == "PermissionError":
            found = "no permission to read it"
        else:
            found = damaged_found("MATLAB file", exc.message)
        raise DataFormatError(path, None, None, "a readable MATLAB .mat file", found) from None


def _read_plain(path: Path) -> dict[str, Any] | None:
    """The file read without scipy where it holds numeric matrices and cells only, as every
    public GCFF file does (`reform.datasets._mat5`: scipy's answer, in this process, as pure
    Python cannot crash it); None leaves the file to scipy."""
    try:
        if path.stat().st_size > MAT_INFLATED_LIMIT_BYTES:
            return None
        return read_mat5(path.read_bytes())
    except OSError:
        return None  # scipy's reader names the error


def check_inflated_size(path: str | PathLike[str], *, limit: int | None = None) -> int:
    """Bytes the variables of a MATLAB 5 file take once inflated, counted before any is read.

    Each compressed variable is inflated a chunk at a time and only counted, so that a
    compressed bomb (a few MB inflating to GB) is refused within ``limit`` bytes of work and
    memory: the variable's own declared size (its first bytes inflated) is checked first, then
    the bytes it really inflates to. Files of MATLAB 4 and 7.3 (HDF5) are left to the reader,
    which refuses them or holds no compression.

    Args:
        path: the ``.mat`` file.
        limit: most bytes allowed; by default :data:`MAT_INFLATED_LIMIT_BYTES` or a quarter of
            the memory available, whichever is less.

    Returns:
        The bytes counted (0 for a file that is not MATLAB 5).

    Raises:
        DataFormatError: the variables inflate (or claim to) beyond ``limit``, naming the
            variable's place in the file, or the file cannot be read.
    """
    path = path_argument(path, name="path", function="check_inflated_size")
    if limit is None:
        limit = min(MAT_INFLATED_LIMIT_BYTES, max(available_memory() // 4, 2**20))
    expected = (
        f"a MATLAB file whose variables inflate to at most {limit / 2**20:g} MiB "
        f"({MAT_INFLATED_LIMIT_BYTES / 2**20:g} MiB or a quarter of the memory available)"
    )
    try:
        with open(path, "rb") as handle:
            header = handle.read(_MAT_HEADER_BYTES)
            if len(header) < _MAT_HEADER_BYTES or header[126:128] not in (b"IM", b"MI"):
                return 0
            order = "<" if header[126:128] == b"IM" else ">"
            total = 0
            position = _MAT_HEADER_BYTES
            for k in range(1, 2**31):
                handle.seek(position)
                tag = handle.read(8)
                if len(tag) < 8:
                    break
                mdtype, nbytes = struct.unpack(order + "II", tag)
                if mdtype >> 16:  # a small data element: 4 bytes of data in its tag
                    position += 8
                    continue
                where = f"variable {k} (at byte {position})"
                if mdtype == _MI_COMPRESSED:
                    total = _count_inflated(
                        handle,
                        nbytes,
                        order,
                        total,
                        limit,
                        path=path,
                        where=where,
                        expected=expected,
                    )
                    position += 8 + nbytes
                else:
                    total += nbytes
                    position += 8 + nbytes + (-nbytes % 8)
                if total > limit:
                    raise DataFormatError(
                        path, where, None, expected, f"{total:,} bytes (a compressed bomb?)"
                    )
    except OSError as exc:
        found = os_error_found(exc) if exc.errno else damaged_found("MATLAB file", str(exc))
        raise DataFormatError(path, None, None, "a readable MATLAB .mat file", found) from None
    return total


def _count_inflated(
    handle: Any,
    nbytes: int,
    order: str,
    total: int,
    limit: int,
    *,
    path: Path,
    where: str,
    expected: str,
) -> int:
    """``total`` plus the bytes one compressed element of ``nbytes`` inflates to, stopped (and
    refused) as soon as the sum passes ``limit``, or as soon as the element's declared size
    does."""
    inflater = zlib.decompressobj()
    remaining = nbytes
    start = total
    declared_checked = False
    head = b""
    while remaining > 0:
        data = handle.read(min(remaining, 2**16))
        if not data:
            break  # truncated: the reader says so
        remaining -= len(data)
        try:
            while data:
                out = inflater.decompress(data, _INFLATE_CHUNK)
                data = inflater.unconsumed_tail
                total += len(out)
                if not declared_checked:
                    head += out[:8]
                    if len(head) >= 8:
                        declared_checked = True
                        inner, declared = struct.unpack(order + "II", head[:8])
                        if inner == _MI_MATRIX and start + 8 + declared > limit:
                            raise DataFormatError(
                                path,
                                where,
                                None,
                                expected,
                                f"a variable declaring {declared:,} bytes inflated "
                                f"from {nbytes:,} compressed",
                            )
                if total > limit:
                    raise DataFormatError(
                        path,
                        where,
                        None,
                        expected,
                        f"more than {limit:,} bytes inflated from {nbytes:,} compressed "
                        "(a compressed bomb?)",
                    )
                if inflater.eof:
                    return total
        except zlib.error:
            return total  # corrupt compression: the reader says so, naming it
    return total


def _read_mat(path: str) -> dict[str, Any]:
    from scipy.io import loadmat

    return loadmat(path, squeeze_me=False, struct_as_record=True)


def _variable(mat: dict[str, Any], name: str, path: Path) -> Any:
    if name not in mat:
        present = sorted(k for k in mat if not k.startswith("__"))
        raise DataFormatError(path, None, name, f"a variable {name!r}", f"variables {present}")
    return mat[name]


def _cells(value: Any, *, path: Path, field: str) -> list[Any]:
    """The elements of a 1×K (or K×1) cell array, in order."""
    array = np.asarray(value)
    if array.dtype != object:
        raise DataFormatError(
            path, None, field, "a cell array", f"a {array.dtype} array of shape {array.shape}"
        )
    if array.ndim != 2 or (array.size and 1 not in array.shape):
        raise DataFormatError(path, None, field, "a 1×K cell array", f"shape {array.shape}")
    return list(array.ravel())


def _real(dtype: np.dtype) -> bool:
    """Whether a MATLAB array of ``dtype`` holds real numbers: not cells, text, logicals or
    complex numbers (whose imaginary part a cast to float would drop without a word)."""
    return np.issubdtype(dtype, np.number) and not np.issubdtype(dtype, np.complexfloating)


def _vector(value: Any, *, path: Path, field: str) -> np.ndarray:
    array = np.asarray(value)
    if not _real(array.dtype):
        raise DataFormatError(path, None, field, "a numeric vector", f"a {array.dtype} array")
    if not _is_vector(array):
        raise DataFormatError(path, None, field, "a 1×K vector", f"shape {array.shape}")
    vector = array.astype(np.float64).ravel()
    DataFormatError.check_rows(
        ~np.isfinite(vector), path, lambda k: f"element {k + 1}", field, "a finite number", vector
    )
    return vector


def _is_vector(array: np.ndarray) -> bool:
    """Whether ``array`` is a row (1×K), a column (K×1), 1-D, a scalar, or empty."""
    return array.ndim <= 1 or (array.ndim == 2 and (array.size == 0 or 1 in array.shape))


def _frame_rows(
    cell: Any, *, path: Path, frame: int, per_metre: float, repairs: Repairs
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ids, (n, 2) positions in file units, (n,) θ) of one ``features`` cell; rows whose x, y
    or θ is NaN (a pose not found) are dropped, counted in ``repairs``."""
    where = f"frame {frame}"
    array = np.asarray(cell)
    if not (array.size == 0 and array.dtype != object or _real(array.dtype)):
        raise DataFormatError(
            path, where, "features", "an N×4 numeric matrix [ID, x, y, θ]", f"a {array.dtype} array"
        )
    if array.size == 0:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 2)), np.zeros(0)
    if array.ndim == 2 and array.shape[1] == 3:
        raise DataFormatError(
            path,
            where,
            "features",
            "an N×4 matrix [ID, x, y, θ]: a position and an orientation per person",
            f"shape {array.shape}: [ID, x, y] without the orientation θ",
        )
    if array.ndim != 2 or array.shape[1] != 4:
        raise DataFormatError(
            path, where, "features", "an N×4 matrix [ID, x, y, θ]", f"shape {array.shape}"
        )
    array = array.astype(np.float64)

    def at_row(row: int) -> str:
        return f"{where}, row {row + 1}"

    DataFormatError.check_rows(
        ~np.isfinite(array[:, 0]), path, at_row, "ID", "a finite number", array[:, 0]
    )
    unposed = np.isnan(array[:, 1:]).any(axis=1)
    if unposed.any():
        row = int(np.flatnonzero(unposed)[0])
        column = int(np.flatnonzero(np.isnan(array[row, 1:]))[0])
        repairs.note(
            "people_dropped_nan",
            path=path,
            where=f"{at_row(row)} (ID {array[row, 0]:g})",
            field=("x", "y", "θ")[column],
            expected="a number (a NaN pose: that person is dropped from the frame)",
            found="NaN",
            count=int(unposed.sum()),
        )
        array = array[~unposed]
    for column, name in enumerate(("x", "y", "θ"), start=1):
        values = array[:, column]
        DataFormatError.check_rows(
            ~np.isfinite(values), path, at_row, name, "a finite number", values
        )
    ids = array[:, 0]
    for bad, expected in (
        (np.abs(ids) > _ID_LIMIT, f"an integer with |ID| <= 2^53 ({_ID_LIMIT:g})"),
        (ids != np.round(ids), "an integer"),
        (ids < 0, f"an integer >= 0 ({ID_RULE})"),
    ):
        DataFormatError.check_rows(bad, path, at_row, "ID", expected, ids)
    ids = ids.astype(np.int64)
    check_unique_ids(ids.tolist(), path=path, where=where)
    limit = POSITION_LIMIT_M * per_metre
    far = np.argwhere(np.abs(array[:, 1:3]) > limit)
    if far.size:
        row, column = (int(v) for v in far[0])
        raise DataFormatError(
            path,
            f"{at_row(row)} (ID {ids[row]})",
            "xy"[column],
            f"a position with |value| <= {limit:g} file units ({POSITION_LIMIT_M:g} m; "
            "farther looks like a corrupt value)",
            repr(float(array[row, column + 1])),
        )
    theta = array[:, 3]
    DataFormatError.check_rows(
        np.abs(theta) > _ANGLE_LIMIT_RAD,
        path,
        lambda row: f"{at_row(row)} (ID {ids[row]})",
        "θ",
        "radians with |θ| <= 4π (values beyond look like degrees)",
        theta,
    )
    return ids, array[:, 1:3], theta


def _match_time(
    stamp: float, timestamps: np.ndarray, order: dict[float, int], smallest_step: float
) -> int | None:
    """The frame whose timestamp is ``stamp``, within a rounding (capped at a share of the
    frames' ``smallest_step``), or None."""
    if stamp in order:
        return order[stamp]
    tolerance = min(_TIMESTAMP_RTOL * (1.0 + abs(stamp)), _TIMESTAMP_STEP_SHARE * smallest_step)
    close = np.flatnonzero(np.abs(timestamps - stamp) <= tolerance)
    return int(close[0]) if close.size == 1 else None


def _groups(cell: Any, *, path: Path, where: str) -> list[list[int]]:
    """The groups of one ``GTgroups`` cell: a cell array of ID vectors (or one numeric vector)."""
    array = np.asarray(cell)
    if array.size == 0:
        return []
    members_list = list(array.ravel()) if array.dtype == object else [array]
    groups = []
    for k, members in enumerate(members_list, start=1):
        vector = np.asarray(members)
        if vector.size == 0:
            continue
        if not _real(vector.dtype):
            raise DataFormatError(
                path, where, f"group {k}", "a numeric vector of IDs", f"a {vector.dtype} array"
            )
        if not _is_vector(vector):  # a matrix's rows would be read as one merged group
            raise DataFormatError(
                path,
                where,
                f"group {k}",
                "a row or column vector of IDs (shape (1, k), (k, 1) or (k,))",
                f"shape {vector.shape}",
            )
        values = vector.astype(np.float64).ravel()
        if (
            not np.all(np.isfinite(values))
            or np.any(values != np.round(values))
            or np.any(np.abs(values) > _ID_LIMIT)
        ):
            raise DataFormatError(path, where, f"group {k}", "integer IDs", str(values.tolist()))
        if np.any(values < 0):
            raise DataFormatError(
                path, where, f"group {k}", f"IDs >= 0 ({ID_RULE})", str(values.tolist())
            )
        groups.append([int(v) for v in values])
    return groups


def _canonical(
    listed: list[list[int]],
    ids: np.ndarray,
    *,
    path: Path,
    where: str,
    report: Counter[str],
    repairs: Repairs,
) -> tuple[tuple[Group, ...], tuple[Group, ...] | None]:
    """The frame's ``groups`` (present members of the listed groups of two or more) and, when
    some listed member is absent from the features, the F-formations as listed."""
    present = set(ids.tolist())
    grouped: set[int] = set()
    groups: list[Group] = []
    fformations: list[Group] = []
    absent_total = 0
    for k, members in enumerate(listed, start=1):
        if len(set(members)) != len(members):
            raise DataFormatError(path, where, f"group {k}", "distinct members", str(members))
        # Listed alone, an absent person changes no score (singletons are not scored).
        absent = note_absent_members(
            repairs, members, present, path=path, where=where, field=f"group {k}", id_word="ID"
        )
        if len(members) >= 2:
            absent_total += len(absent)
            clash = grouped.intersection(members)
            if clash:
                raise DataFormatError(
                    path, where, f"group {k}", "disjoint groups", f"ID {min(clash)} in two groups"
                )
            grouped.update(members)
            fformations.append(tuple(members))
            kept = tuple(m for m in members if m in present)
            if kept:
                groups.append(kept)
    singletons = [m[0] for m in listed if len(m) == 1]
    report["singletons_listed"] += len(singletons)
    report["duplicate_singletons"] += sum(1 for s in singletons if s in grouped)
    report["people_in_no_group"] += len(present - grouped - set(singletons))
    if absent_total:
        report["frames_with_absent"] += 1
        return tuple(g for g in groups if len(g) >= 2), tuple(fformations)
    return tuple(groups), None


def _settings(path: Path, *, units: str, metres_per_pixel: float | None) -> dict[str, Any]:
    per_metre = units_per_metre(units, metres_per_pixel)
    read = read_settings(path, required=(), units=units, metres_per_pixel=metres_per_pixel)
    out: dict[str, Any] = {"units": units, **read}
    if "stride" in out:
        out["stride_m"] = out["stride"] / per_metre
    if "mdl" in out:
        out["mdl_m2"] = out["mdl"] / per_metre**2
    return out


class _Setting(NamedTuple):
    """What a GCFF parameter must be."""

    power: int  # of length: 1 for a length, 2 for a squared one
    limit: float  # the largest the detector takes, metres to that power
    zero: bool  # whether 0 is accepted
    kind: str  # what it is, with its lower bound
    meaning: str  # what it does


# What each GCFF parameter must be, with the detector's own bounds.
_SETTINGS_RULES = {
    "stride": _Setting(
        1,
        STRIDE_LIMIT_M,
        True,
        "a finite length >= 0",
        "the o-space centre's distance in front of each person",
    ),
    "mdl": _Setting(
        2, MDL_LIMIT_M2, False, "a finite squared length > 0", "the cost of opening a group"
    ),
}


@file_errors_as_data_errors
def read_settings(
    path: str | PathLike[str],
    *,
    required: tuple[str, ...] = ("stride", "mdl"),
    units: str = "cm",
    metres_per_pixel: float | None = None,
) -> dict[str, float]:
    """``stride`` and ``mdl`` of a GCFF ``settings_gc.mat``, as stored (file units).

    Args:
        path: the ``.mat`` file.
        required: the variables that must be present; the others are read when present.
        units: length unit of the file's values, as `load_gcff` takes it (``"cm"``, ``"m"`` or
            ``"px"`` with ``metres_per_pixel``): the detector's bounds are checked in it.
        metres_per_pixel: the scale of ``units="px"``.

    Returns:
        ``{"stride": ..., "mdl": ...}`` (the ones present), floats in the file's units.

    Raises:
        ValueError: ``units`` is unknown, or ``metres_per_pixel`` does not go with it.
        DataFormatError: the file is missing or unreadable, a required variable is missing, or
            a value is not a numeric scalar, or ``stride < 0``, or ``mdl <= 0``, or either is
            beyond what the detector takes (`reform.gcff.STRIDE_LIMIT_M`,
            `reform.gcff.MDL_LIMIT_M2`).
    """
    path = path_argument(path, name="path", function="read_settings")
    per_metre = units_per_metre(units, metres_per_pixel)
    mat = _loadmat(path)
    out: dict[str, float] = {}
    for name, rule in _SETTINGS_RULES.items():
        if name not in mat:
            if name in required:
                present = sorted(k for k in mat if not k.startswith("__"))
                raise DataFormatError(
                    path, None, name, f"a variable {name!r}", f"variables {present}"
                )
            continue
        array = np.asarray(mat[name])
        if not _real(array.dtype) or array.size != 1:
            raise DataFormatError(
                path,
                None,
                name,
                "a numeric scalar",
                f"a {array.dtype} array of shape {array.shape}",
            )
        value = float(array.ravel()[0])
        scale = per_metre**rule.power
        if not (
            math.isfinite(value)
            and (value >= 0 if rule.zero else value > 0)
            and value / scale <= rule.limit
        ):
            unit = "m" if rule.power == 1 else "m²"
            raise DataFormatError(
                path,
                None,
                name,
                f"{rule.kind} and <= {rule.limit * scale:g} file units ({rule.limit:g} {unit}, "
                f"the most GCFF takes; {rule.meaning})",
                repr(value),
            )
        out[name] = value
    return out
