"""Which loader reads a path: format detection and the one entry point, :func:`load_dataset`."""

from __future__ import annotations

from os import PathLike
from pathlib import Path

from reform.datasets._walk import find_files
from reform.datasets.errors import DataFormatError, file_errors_as_data_errors
from reform.frame import Dataset
from reform.path_argument import path_argument

__all__ = [
    "FORMATS",
    "FORMAT_ALIASES",
    "FORMAT_FILES",
    "LENGTH_UNITS",
    "detect_format",
    "load_dataset",
]

# Other names of the formats: "dante" is the DANTE text format that SALSA's packaging uses.
FORMAT_ALIASES = {"dante": "salsa"}
# Length units a GCFF folder or a DANTE text file may be written in (the other formats are
# always metres); "px" (image pixels) needs its scale, metres_per_pixel.
LENGTH_UNITS = ("cm", "m", "px")
# Formats whose files have one fixed length unit.
_FIXED_UNITS = {"babble": "m", "parquet": "m"}

# How deep detection looks for shards (DIR/scenario=.../episode=.../part.parquet is 2 levels).
_PARQUET_DEPTH = 4

# What each format's files are, as detection finds them.
FORMAT_FILES = {
    "salsa": "a folder with the DANTE text files features.txt and group_names.txt",
    "babble": "a folder with Motion-capture-data.csv",
    "gcff": "a folder with features.mat, or a folder of such folders",
    "parquet": f"a .parquet file or a folder of them, at most {_PARQUET_DEPTH} levels down",
}
FORMATS = tuple(FORMAT_FILES)
_DESCRIPTION = ", ".join(
    f"{name}{''.join(f', alias {a}' for a, of in FORMAT_ALIASES.items() if of == name)} ({files})"
    for name, files in FORMAT_FILES.items()
)


def _holds_parquet(folder: Path) -> bool:
    """True if ``folder`` holds a .parquet file at most :data:`_PARQUET_DEPTH` levels down
    (looking at :data:`~reform.datasets._walk.MAX_ENTRIES` entries at most)."""
    return bool(find_files(folder, ".parquet", max_depth=_PARQUET_DEPTH, first=True, strict=False))


def _folder_formats(folder: Path) -> dict[str, str]:
    """Every format whose files ``folder`` holds: ``format -> the files that show it``."""
    from reform.datasets.dante import DANTE_FILES_FOLDER

    found = {}
    for prefix in ("", f"{DANTE_FILES_FOLDER}/"):  # DANTE's repository: <dataset>/DS_utils/
        if (folder / f"{prefix}features.txt").is_file() and (
            folder / f"{prefix}group_names.txt"
        ).is_file():
            found["salsa"] = f"{prefix}features.txt, {prefix}group_names.txt"
            break
    if (folder / "Motion-capture-data.csv").is_file():
        found["babble"] = "Motion-capture-data.csv"
    if (folder / "features.mat").is_file():
        found["gcff"] = "features.mat"
    else:
        from reform.datasets.gcff_mat import sequence_folders

        sequences = sequence_folders(folder)
        if sequences:
            found["gcff"] = ", ".join(f"{s.name}/features.mat" for s in sequences)
    try:
        if _holds_parquet(folder):
            found["parquet"] = ".parquet files"
    except DataFormatError:
        if not found:
            raise  # too large a folder to tell, and nothing else found: said as such
    return found


def _someone_seen(dataset: Dataset, path: Path) -> Dataset:
    """``dataset``, a recording of the field's, unless nobody is in any of its frames (every
    pose untracked, NaN or padding): nothing a detector could be scored on, the mark of a
    damaged file rather than of a scene."""
    if dataset.frames and not any(frame.n_people for frame in dataset.frames):
        raise DataFormatError(
            path,
            None,
            "people",
            "someone in at least one frame",
            f"nobody in any of its {len(dataset.frames):,} frames (every pose untracked, NaN or "
            "padding)",
        )
    return dataset


@file_errors_as_data_errors
def detect_format(path: str | PathLike[str]) -> str:
    """The format of a dataset path: one of :data:`FORMATS`.

    A folder holding the files of two formats (SALSA's and Babble's, say) is ambiguous: it is
    refused, and the caller names the format (``format=``, ``--format`` on the command line).

    Raises:
        DataFormatError: the path does not exist, matches no format (the message lists them),
            or is a folder matching several.
    """
    from reform.datasets.store import is_uri

    if is_uri(path):  # in a store: the project's Parquet is the one format written there
        return "parquet"
    path = path_argument(path, name="path", function="detect_format")
    if not path.exists():
        raise DataFormatError(
            path, None, None, "an existing dataset file or folder", "no such file or folder"
        )
    if path.is_dir():
        found = _folder_formats(path)
        if len(found) == 1:
            return next(iter(found))
        if len(found) > 1:
            raise DataFormatError(
                path,
                None,
                None,
                "the files of one dataset format",
                "; ".join(f"{name} ({files})" for name, files in found.items()),
                hint="name the format to read: format='"
                + "' or format='".join(found)
                + "' (--format on the command line)",
            )
    else:
        if path.suffix == ".parquet":
            return "parquet"
        if path.name == "features.txt":
            return "salsa"
        if path.name == "Motion-capture-data.csv":
            return "babble"
        if path.name == "features.mat":
            return "gcff"
    if path.is_dir():
        odd = _known_names_unreadable(path)
        if odd:
            raise DataFormatError(
                path,
                None,
                None,
                f"a dataset in one of the formats: {_DESCRIPTION}",
                f"none of them: {odd}",
            )
    raise DataFormatError(
        path, None, None, f"a dataset in one of the formats: {_DESCRIPTION}", "none of them"
    )


# The files by which detection knows a format, for saying what stands in their place.
_KNOWN_FILES = ("features.txt", "group_names.txt", "Motion-capture-data.csv", "features.mat")


def _known_names_unreadable(folder: Path) -> str:
    """The format files ``folder`` names but holds no file as (a folder, a link loop, a FIFO),
    each with what it is: ``features.mat is a folder``; empty when there are none."""
    from reform.atomic import file_kind

    odd = []
    for name in _KNOWN_FILES:
        entry = folder / name
        if entry.is_symlink() or entry.exists():
            kind = file_kind(entry)
            if kind != "a file":
                odd.append(f"{name} is {kind}")
    return ", ".join(odd)


@file_errors_as_data_errors
def load_dataset(
    path: str | PathLike[str],
    *,
    format: str | None = None,
    units: str | None = None,
    metres_per_pixel: float | None = None,
    strict: bool = False,
    allow_incomplete: bool = False,
    time_unit: str | None = None,
) -> Dataset:
    """Loads a dataset in any supported format; positions come back in metres.

    Args:
        path: a dataset file or folder; or a Parquet file or folder in a store, by its URI
            (``s3://bucket/prefix``; `reform.datasets.store`).
        format: one of :data:`FORMATS` (or an alias, ``"dante"``); detected from ``path`` when
            None.
        units: length unit of the file's positions, ``"cm"``, ``"m"`` or ``"px"``. GCFF
            folders (default ``"cm"``, as the public GCFF datasets use, checked: a folder whose
            people then stand a median of more than 3 m apart holds image pixels and is
            refused; ``"px"`` for sets derived from pose estimation, with
            ``metres_per_pixel``) and DANTE text files
            (default ``"m"``, the format's unit, checked: a file whose people then stand
            farther apart than in any dataset of the field is refused, as DANTE's own
            CoffeeBreak files in centimetres are) have a choice; Babble and Parquet are always
            metres, and giving another unit for them is an error.
        metres_per_pixel: the scale of ``units="px"``.
        strict: refuse the quirks a loader otherwise repairs and counts in
            ``metadata["report"]["repairs"]`` (ground-truth members absent from the features,
            NaN poses, ...), naming file, frame, field, expected and found.
        allow_incomplete: Parquet only: read an unfinished ``reform-sim generate`` folder
            (see :func:`~reform.datasets.parquet.read_parquet`).
        time_unit: GCFF and DANTE only: the unit of the files' time stamps, ``"s"``, ``"ms"``,
            ``"us"`` or ``"ns"``; by default times below 1e8 are kept as stored and larger ones
            read as Unix times in the unit their magnitude and spacing prove, counted from
            each sequence's start (`reform.datasets._validation.read_time_unit`). Babble and
            Parquet times are always seconds, and giving a unit for them is an error.

    Raises:
        DataFormatError: the path is missing, matches no format, or a file is malformed.
        ValueError: unknown ``format`` or ``units``, units that contradict the format, or
            pixels without their scale.
    """
    from reform.datasets.store import is_uri

    if is_uri(path):
        if format not in (None, "parquet"):
            raise ValueError(
                f"format: a dataset in a store ({path}) is read as parquet, got format={format!r}"
            )
        if units not in (None, "m"):
            raise ValueError(f"units: the parquet format stores positions in 'm', got {units!r}")
        if time_unit is not None:
            raise ValueError(f"time_unit: the parquet format stores seconds, got {time_unit!r}")
        from reform.datasets.parquet import read_parquet

        return read_parquet(path, allow_incomplete=allow_incomplete)
    path = path_argument(path, name="path", function="load_dataset")
    if format is None:
        format = detect_format(path)
    format = FORMAT_ALIASES.get(format, format)
    if format not in FORMATS:
        known = (*FORMATS, *FORMAT_ALIASES)
        raise ValueError(f"format must be one of {known}, got {format!r}")
    if units is not None and units not in LENGTH_UNITS:
        raise ValueError(f"units must be one of {LENGTH_UNITS}, got {units!r}")
    fixed = _FIXED_UNITS.get(format)
    if fixed is not None and units is not None and units != fixed:
        raise ValueError(
            f"units: the {format} format stores positions in {fixed!r}, got units={units!r}"
        )
    if metres_per_pixel is not None and units != "px":
        raise ValueError(
            f"metres_per_pixel is the scale of units='px', got it with units={units!r}"
        )
    if time_unit is not None and format in _FIXED_UNITS:
        raise ValueError(f"time_unit: the {format} format stores seconds, got {time_unit!r}")
    if not path.exists():
        raise DataFormatError(
            path, None, None, f"an existing {format} file or folder", "no such file or folder"
        )

    if format == "parquet":
        from reform.datasets.parquet import read_parquet

        return read_parquet(path, allow_incomplete=allow_incomplete)
    if format == "salsa":
        from reform.datasets.dante import load_dante

        dataset = load_dante(
            path,
            strict=strict,
            units=units,
            metres_per_pixel=metres_per_pixel,
            time_unit=time_unit,
        )
    elif format == "babble":
        from reform.datasets.babble import load_babble

        dataset = load_babble(path)
    else:
        from reform.datasets.gcff_mat import load_gcff

        dataset = load_gcff(
            path,
            units=units,
            metres_per_pixel=metres_per_pixel,
            strict=strict,
            time_unit=time_unit,
        )
    return _someone_seen(dataset, path)  # a recording of the field's
