"""The project's own dataset format: Parquet, long layout (one row per frame × person).

Every column is documented in :data:`COLUMNS` (and in the README). A frame with nobody in it is
one row whose ``person_id`` is null, so empty frames survive the round trip. The dataset's
name, source, units and metadata, the format version and the version of the code that wrote
the file are JSON in the schema metadata under the key ``reform_sim``.

The round trip is exact: ``read_parquet(p) `` gives frames equal to the ones written (float64
values bit for bit, ``None`` heads distinct from unobserved NaN heads, group order and member
order preserved). The metadata comes back as JSON gives it (lists for tuples, string keys).

`write_parquet` writes the same file from a `reform.FrameBlock` (arrays over a fixed roster: who
is present at each instant, poses, groups) without a `Frame` per instant: the fast path of
dataset generation.

A folder of Parquet files (for instance hive-partitioned shards
``DIR/scenario=.../episode=.../part.parquet``) reads as one dataset: the files in natural sorted
order of their relative paths, their frames concatenated.

pyarrow is imported only inside these functions.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Mapping
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from reform import __version__
from reform.atomic import atomic_path
from reform.datasets import _walk
from reform.datasets._validation import ID_RULE, check_time_increases, file_kind, make_frame
from reform.datasets._walk import find_files
from reform.datasets.errors import DataFormatError, file_errors_as_data_errors
from reform.frame import KINDS, POSITION_LIMIT_M, Dataset, Frame, Group
from reform.frame_block import FrameBlock
from reform.machine import available_memory
from reform.path_argument import path_argument

__all__ = [
    "CARD_JSON",
    "verify_folder",
    "CODECS",
    "COLUMNS",
    "FORMAT_VERSION",
    "METADATA_KEY",
    "read_parquet",
    "write_parquet",
]

FORMAT_VERSION = 1
METADATA_KEY = b"reform_sim"
_YAW_LIMIT_RAD = math.pi + 2e-3  # wrapped radians plus rounding; larger values look like degrees
# Parquet codecs a file may be written with (``"none"``: uncompressed).
CODECS = ("none", "snappy", "gzip", "brotli", "lz4", "zstd")
# The card of a folder written by ``reform-sim generate`` (sim.generate.CARD_JSON).
CARD_JSON = "dataset.json"  # the card of a folder written by reform-sim generate
CARD_VERSION = 1  # the newest card format this reader knows (sim.generate.CARD_VERSION)
READ_BYTES_PER_ROW = 320  # bytes of memory per row while a file is read (measured: peak)

# name -> (arrow type name, nullable, unit, description). The README's column table is this.
COLUMNS: dict[str, tuple[str, bool, str, str]] = {
    "sequence": ("string", False, "", "recording (session, episode) the frame belongs to"),
    "frame": ("int64", False, "", "frame index in the file, 0, 1, 2, ... in recording order"),
    "time": (
        "float64",
        False,
        "s",
        "time stamp of the frame, seconds from the start of its sequence",
    ),
    "annotated": ("bool", False, "", "the frame carries ground-truth groups"),
    "has_head": ("bool", False, "", "the frame carries head pose columns (else they are null)"),
    "person_id": (
        "int64",
        True,
        "",
        "person id, unique within the frame; null on the one row of a frame with nobody",
    ),
    "kind": ("string", True, "", "'human' or 'robot'; null on an empty frame's row"),
    "x": ("float64", True, "m", "body (torso) position, ground plane"),
    "y": ("float64", True, "m", "body (torso) position, ground plane"),
    "yaw": ("float64", True, "rad", "body yaw, counter-clockwise from +x, in [-pi, pi]"),
    "head_x": (
        "float64",
        True,
        "m",
        "head position; NaN = head not observed; null when has_head is false",
    ),
    "head_y": (
        "float64",
        True,
        "m",
        "head position; NaN = head not observed; null when has_head is false",
    ),
    "head_yaw": (
        "float64",
        True,
        "rad",
        "head yaw in [-pi, pi]; NaN = not observed; null when has_head is false",
    ),
    "group": (
        "int32",
        True,
        "",
        "index of the person's ground-truth group in the frame (0, 1, ...); null = in no group",
    ),
    "group_member": (
        "int32",
        True,
        "",
        "position of the person inside that group (keeps the member order)",
    ),
}


def _pyarrow():
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError as exc:  # pragma: no cover - pyarrow is a dependency of the project
        raise ImportError("reading and writing Parquet needs pyarrow: pip install pyarrow") from exc
    return pa, pq


def _arrow_type(pa, type_name: str):
    return {
        "string": pa.string(),
        "int64": pa.int64(),
        "int32": pa.int32(),
        "float64": pa.float64(),
        "bool": pa.bool_(),
    }[type_name]


def write_parquet(
    dataset: Dataset | FrameBlock,
    path: str | PathLike[str],
    *,
    name: str | None = None,
    source: str = "",
    metadata: Mapping[str, Any] | None = None,
    compression: str = "zstd",
) -> Path:
    """Writes ``dataset`` to one Parquet file, atomically (temporary file, then rename).

    Args:
        dataset: the frames and provenance (a `Dataset`), or one sequence as a `FrameBlock`,
            written without a `Frame` per instant: the same file, byte for byte, as the
            `Dataset` of ``block.frames()``.
        path: the file to write (parent folders are created).
        name: the dataset's name, in the header of a `FrameBlock` (a `Dataset` carries its
            own; giving it with one is an error).
        source: where the data come from, in the header of a `FrameBlock` (as ``name``).
        metadata: the provenance, in the header of a `FrameBlock` (as ``name``); must be
            JSON-serialisable.
        compression: Parquet codec (``"zstd"``, ``"snappy"``, ``"none"`` ...).

    Returns:
        The path written.

    Raises:
        ValueError: the metadata is not JSON-serialisable, ``compression`` is not one of
            :data:`CODECS`, or the header is missing or given twice: before anything is written.
    """
    if not isinstance(dataset, (Dataset, FrameBlock)):
        raise TypeError(
            f"write_parquet: dataset must be a reform.Dataset or a FrameBlock, got "
            f"{type(dataset).__name__}"
        )
    path = path_argument(path, name="path", function="write_parquet")
    _check_compression(compression)
    _check_ids_written(dataset)
    if isinstance(dataset, FrameBlock):
        if name is None:
            raise ValueError("write_parquet of a FrameBlock needs name=, the dataset's name")
        header_json = _header_json(name, source, "m", metadata or {})
        return _write_table(_block_columns(dataset), header_json, Path(path), compression)
    if name is not None or source or metadata is not None:
        raise ValueError("write_parquet of a Dataset takes its name, source and metadata from it")
    listed = {
        str(k): [list(g) for g in frame.listed_groups]
        for k, frame in enumerate(dataset.frames)
        if frame.listed_groups is not None
    }
    header_json = _header_json(
        dataset.name, dataset.source, dataset.units, dataset.metadata, listed_groups=listed
    )
    return _write_table(_columns(dataset.frames), header_json, Path(path), compression)


def _check_compression(compression: Any) -> None:
    """Raises unless ``compression`` names a codec of :data:`CODECS` this pyarrow can write."""
    if not isinstance(compression, str) or compression.lower() not in CODECS:
        raise ValueError(f"compression must be one of {CODECS}, got {compression!r}")
    pa, _ = _pyarrow()
    if compression.lower() != "none" and not pa.Codec.is_available(compression.lower()):
        available = tuple(c for c in CODECS if c == "none" or pa.Codec.is_available(c))
        raise ValueError(
            f"compression {compression!r} is not built into this pyarrow; available: {available}"
        )


def _block_columns(block: FrameBlock) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The long table's columns (as :func:`_columns` makes them) from a block's arrays."""
    time, ids, present, n_frames, n = (
        block.time,
        block.ids,
        block.present,
        len(block),
        block.ids.size,
    )
    has_head = block.head_position is not None

    # Row order: frame by frame, the people present in roster order; an empty frame gets one
    # row in an extra column n (its person columns null).
    empty_frame = ~present.any(axis=1)
    slots = np.concatenate([present, empty_frame[:, None]], axis=1)
    t_of, a_of = np.nonzero(slots)
    n_rows = t_of.size
    empty = a_of == n
    a_safe = np.where(empty, 0, a_of)
    row_of = np.full(slots.shape, -1, dtype=np.int64)
    row_of[t_of, a_of] = np.arange(n_rows)

    person_id = np.where(empty, 0, ids[a_safe] if n else 0)
    kind = np.empty(n_rows, dtype=object)
    if n:
        kind[:] = np.array(block.kinds, dtype=object)[a_safe]
    kind[empty] = None
    body = np.zeros((n_rows, 3))
    head = np.zeros((n_rows, 3))
    if n:
        body[:, :2] = block.position[t_of, a_safe]
        body[:, 2] = block.yaw[t_of, a_safe]
        if has_head:
            head[:, :2] = block.head_position[t_of, a_safe]
            head[:, 2] = block.head_yaw[t_of, a_safe]
    body[empty] = 0.0
    head[empty] = 0.0

    group = np.full(n_rows, -1, dtype=np.int32)
    member = np.full(n_rows, -1, dtype=np.int32)
    annotated_frame = np.zeros(n_frames, dtype=bool)
    index_of = {int(i): a for a, i in enumerate(ids.tolist())}
    for t, frame_groups in enumerate(block.present_groups()):
        if frame_groups is None:
            continue
        annotated_frame[t] = True
        rows = row_of[t]
        for g, members in enumerate(frame_groups):
            for m, person in enumerate(members):
                group[rows[index_of[int(person)]]] = g
                member[rows[index_of[int(person)]]] = m

    counts = np.bincount(t_of, minlength=n_frames)
    has_head_rows = np.full(n_rows, has_head)
    no_head = empty | ~has_head_rows
    no_group = group < 0
    nothing = np.zeros(n_rows, dtype=bool)
    return {
        "sequence": (np.full(n_rows, block.sequence, dtype=object), nothing),
        "frame": (t_of.astype(np.int64), nothing),
        "time": (np.repeat(time, counts), nothing),
        "annotated": (np.repeat(annotated_frame, counts), nothing),
        "has_head": (has_head_rows, nothing),
        "person_id": (person_id.astype(np.int64), empty),
        "kind": (kind, empty),
        "x": (body[:, 0], empty),
        "y": (body[:, 1], empty),
        "yaw": (body[:, 2], empty),
        "head_x": (head[:, 0], no_head),
        "head_y": (head[:, 1], no_head),
        "head_yaw": (head[:, 2], no_head),
        "group": (group, no_group),
        "group_member": (member, no_group),
    }


def _header_json(
    name: str,
    source: str,
    units: str,
    metadata: Any,
    *,
    listed_groups: Mapping[str, list[list[int]]] | None = None,
) -> str:
    header = {
        "format_version": FORMAT_VERSION,
        "generator_version": f"reform-sim {__version__}",
        "name": name,
        "source": source,
        "units": units,
        "metadata": dict(metadata),
    }
    if listed_groups:
        # Frame.listed_groups (ground truth naming people absent from the frame), by frame.
        header["listed_groups"] = dict(listed_groups)
    try:
        return json.dumps(header, allow_nan=False, sort_keys=False)
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"dataset.metadata must be JSON-serialisable (finite numbers), got an error: {exc}"
        ) from exc


def _write_table(
    columns: dict[str, tuple[np.ndarray, np.ndarray]],
    header_json: str,
    target: Path,
    compression: str,
) -> Path:
    """Writes the long table's columns (values, null masks) with the header, atomically."""
    pa, pq = _pyarrow()
    fields = []
    arrays = []
    for name, (type_name, nullable, unit, description) in COLUMNS.items():
        values, mask = columns[name]
        arrow_type = _arrow_type(pa, type_name)
        arrays.append(pa.array(values, type=arrow_type, mask=mask if nullable else None))
        meta = {b"description": description.encode()}
        if unit:
            meta[b"unit"] = unit.encode()
        fields.append(pa.field(name, arrow_type, nullable=nullable, metadata=meta))
    schema = pa.schema(fields, metadata={METADATA_KEY: header_json.encode()})
    table = pa.Table.from_arrays(arrays, schema=schema)
    with atomic_path(target) as tmp:
        pq.write_table(table, tmp, compression=compression)
    return target


def _columns(frames: tuple[Frame, ...]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Column values and null masks (True = null) of the long table."""
    counts = np.array([max(f.n_people, 1) for f in frames], dtype=np.int64)
    n_rows = int(counts.sum())
    frame_index = np.repeat(np.arange(len(frames), dtype=np.int64), counts)
    sequence = np.repeat(np.array([f.sequence for f in frames], dtype=object), counts)
    time = np.repeat(np.array([f.time for f in frames], dtype=np.float64), counts)
    annotated = np.repeat(np.array([f.groups is not None for f in frames], dtype=bool), counts)
    has_head = np.repeat(
        np.array([f.head_position is not None for f in frames], dtype=bool), counts
    )

    person_id = np.zeros(n_rows, dtype=np.int64)
    kind = np.empty(n_rows, dtype=object)
    body = np.zeros((n_rows, 3))
    head = np.zeros((n_rows, 3))
    group = np.full(n_rows, -1, dtype=np.int32)
    member = np.full(n_rows, -1, dtype=np.int32)
    empty = np.zeros(n_rows, dtype=bool)
    start = 0
    for frame, count in zip(frames, counts.tolist(), strict=True):
        n = frame.n_people
        rows = slice(start, start + count)
        if n == 0:
            empty[start] = True
            kind[start] = None
        else:
            person_id[rows] = frame.ids
            kind[rows] = frame.kinds
            body[rows, :2] = frame.position
            body[rows, 2] = frame.yaw
            if frame.head_position is not None:
                head[rows, :2] = frame.head_position
                head[rows, 2] = frame.head_yaw
            if frame.groups:
                row_of = {int(i): start + r for r, i in enumerate(frame.ids.tolist())}
                for g, members in enumerate(frame.groups):
                    for m, person in enumerate(members):
                        group[row_of[person]] = g
                        member[row_of[person]] = m
        start += count
    no_head = empty | ~has_head
    no_group = group < 0
    nothing = np.zeros(n_rows, dtype=bool)
    return {
        "sequence": (sequence, nothing),
        "frame": (frame_index, nothing),
        "time": (time, nothing),
        "annotated": (annotated, nothing),
        "has_head": (has_head, nothing),
        "person_id": (person_id, empty),
        "kind": (kind, empty),
        "x": (body[:, 0], empty),
        "y": (body[:, 1], empty),
        "yaw": (body[:, 2], empty),
        "head_x": (head[:, 0], no_head),
        "head_y": (head[:, 1], no_head),
        "head_yaw": (head[:, 2], no_head),
        "group": (group, no_group),
        "group_member": (member, no_group),
    }


@file_errors_as_data_errors
def read_parquet(path: str | PathLike[str], *, allow_incomplete: bool = False) -> Dataset:
    """Reads a Parquet file written by :func:`write_parquet`, or a folder of them.

    A folder's files (``**/*.parquet``, hidden files and temporary files skipped) are read in
    natural sorted order of their relative paths (``episode=2`` before ``episode=10``) and their
    frames concatenated. The dataset's name is the files' common name (else the folder's); its
    metadata holds one entry per file under ``"shards"``. A sequence name may not occur in two
    files (it would merge two recordings).

    A file's rows come grouped by frame (a frame's rows together, frames ``0, 1, 2, ...`` in
    order), and within each sequence the frames' times increase, as :func:`write_parquet`
    writes them; anything else is refused rather than reordered.

    Args:
        path: a ``.parquet`` file or a folder of them, on this machine or in a store
            (``s3://bucket/prefix``, any fsspec URI; `reform.datasets.store`).
        allow_incomplete: read a folder of ``reform-sim generate`` whose card
            (``dataset.json``) says the run has not finished, with the episodes written so far.
            By default such a folder is refused.

    Raises:
        DataFormatError: a file is missing, empty, not written by this project, of a newer
            format version, or malformed (the message names the file, frame, field), or the
            folder is an unfinished generated dataset.
        reform.datasets.store.StoreError: a store that cannot be used (no credentials, not
            reachable, no such bucket), in one line.
    """
    from reform.datasets.store import is_uri

    if is_uri(path):
        from reform.datasets.store_dataset import read_store

        return read_store(str(path), allow_incomplete=allow_incomplete)
    path = path_argument(path, name="path", function="read_parquet")
    if not path.exists():
        raise DataFormatError(
            path, None, None, "a Parquet file or a folder of them", "no such file or folder"
        )
    if not path.is_dir():
        kind = file_kind(path)
        if kind != "a file":
            raise DataFormatError(path, None, None, "a Parquet file or a folder of them", kind)
        frames, header = _read_file(path)
        return Dataset(
            frames=tuple(frames),
            name=str(header.get("name", path.stem)),
            source=str(header.get("source", "")),
            units="m",
            metadata=header.get("metadata", {}),
        )
    return _read_folder(_LocalFolder(path), allow_incomplete=allow_incomplete)


class _LocalFolder:
    """A dataset folder on this machine, as `_read_folder` and `_check_shards` see it: files by
    relative path."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.name = folder.name

    def where(self, relative: str = "") -> Path:
        """What messages name: the file's path."""
        return self.folder / relative if relative else self.folder

    def card(self) -> dict[str, Any] | None:
        return _read_card(self.folder)

    def parquet_files(self, what: str = "a Parquet file or a folder of them") -> list[str]:
        """Every ``.parquet`` file, hidden files and folders (``.``, ``_``) skipped; the search
        bounded (`reform.datasets._walk.find_files`: more entries than a dataset holds, ``what``
        the folder was expected to be, is one error)."""
        found = find_files(self.folder, ".parquet", what=what, max_entries=_entries_of(self.card()))
        return [p.relative_to(self.folder).as_posix() for p in found]

    def size(self, relative: str) -> int | str:
        """The file's size, or what is there instead (``"no such file"``...)."""
        shard = self.folder / relative
        try:
            return shard.stat().st_size if shard.is_file() else file_kind(shard)
        except OSError as exc:
            return f"{type(exc).__name__}: {exc}"

    def sha256(self, relative: str) -> str:
        return _sha256(self.folder / relative)

    def read(self, relative: str) -> tuple[list[Frame], dict[str, Any]]:
        return _read_file(self.folder / relative)

    def committed(self, card: Mapping[str, Any]) -> tuple[list[str], list[DataFormatError]]:
        """The shards of an unfinished run that a reader may take: every one there (a shard is
        renamed into place whole)."""
        return self.parquet_files(), []


def _read_folder(source: Any, *, allow_incomplete: bool) -> Dataset:
    """A folder of Parquet files (`_LocalFolder`, or `reform.datasets.store` one) as one dataset."""
    files = source.parquet_files()
    card = source.card()
    problems: list[DataFormatError] = []
    if card is not None:
        if not allow_incomplete:
            _check_complete(source, card, len(files))
        files, problems = _check_shards(source, card, files, allow_incomplete=allow_incomplete)
    if not files and not problems:
        raise DataFormatError(source.where(), None, None, "a folder holding .parquet files", "none")
    files.sort(key=lambda p: _natural_key(Path(p)))
    frames: list[Frame] = []
    shards = []
    names = []
    sequence_file: dict[str, str] = {}
    for relative in files:
        try:
            shard_frames, header = source.read(relative)
        except DataFormatError as exc:
            if not allow_incomplete:
                raise
            problems.append(exc)
            continue
        for sequence in dict.fromkeys(f.sequence for f in shard_frames):
            if sequence in sequence_file:
                raise DataFormatError(
                    source.where(relative),
                    None,
                    "sequence",
                    f"sequence names not used by another file ({sequence_file[sequence]})",
                    repr(sequence),
                )
            sequence_file[sequence] = relative
        frames.extend(shard_frames)
        names.append(header.get("name", ""))
        shards.append(
            {
                "path": relative,
                "name": header.get("name", ""),
                "source": header.get("source", ""),
                "frames": len(shard_frames),
                "metadata": header.get("metadata", {}),
            }
        )
    name = names[0] if names and len(set(names)) == 1 and names[0] else source.name
    metadata: dict[str, Any] = {"shards": shards}
    if problems:
        # Read on purpose (allow_incomplete): what is missing is said, never left out silently.
        metadata["incomplete"] = [str(p) for p in problems]
    return Dataset(
        frames=tuple(frames),
        name=name,
        source=str(source.where()),
        units="m",
        metadata=metadata,
    )


def _entries_of(card: Mapping[str, Any] | None) -> int | None:
    """Entries a search of a folder may look at: the walk's own bound (None), and for a
    generated dataset a few more per episode its card lists (a folder, a shard, a recording)."""
    listed = card.get("shards") if card is not None else None
    if not isinstance(listed, list):
        return None
    return _walk.MAX_ENTRIES + 8 * len(listed)


def _read_card(folder: Path) -> dict[str, Any] | None:
    """The card of a ``reform-sim generate`` folder (``dataset.json``), or None without one."""
    card_path = folder / CARD_JSON
    if not card_path.is_file():
        if card_path.exists() or card_path.is_symlink():
            raise DataFormatError(
                card_path,
                None,
                None,
                "a reform-sim dataset card (a JSON file)",
                file_kind(card_path),
            )
        return None
    try:
        text = card_path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise DataFormatError(
            card_path,
            None,
            None,
            "a reform-sim dataset card (JSON)",
            f"{type(exc).__name__}: {exc}",
        ) from exc
    return _json_object(text, card_path, field=None, expected="a reform-sim dataset card (JSON)")


def _json_object(
    text: str | bytes, path: Path, *, field: str | None, expected: str
) -> dict[str, Any]:
    """``text`` as a JSON object; one `DataFormatError` naming ``path`` for anything else
    (malformed, nested too deep to read, not an object)."""
    try:
        value = json.loads(text)
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise DataFormatError(path, None, field, expected, f"{type(exc).__name__}: {exc}") from exc
    except RecursionError:
        raise DataFormatError(path, None, field, expected, "JSON nested too deep to read") from None
    if not isinstance(value, dict):
        raise DataFormatError(path, None, field, expected, f"a JSON {type(value).__name__}")
    return value


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _check_shards(
    source: Any, card: Mapping[str, Any], files: list[str], *, allow_incomplete: bool
) -> tuple[list[str], list[DataFormatError]]:
    """The card's shards, each checked: listed files that are missing, unreadable, or whose
    size or sha256 differs from the card's, and Parquet files the card does not list.

    Returns:
        The files to read and, with ``allow_incomplete``, the problems found (else the first
        problem is raised).
    """
    card_path = source.where(CARD_JSON)
    listed = card.get("shards")
    complete = card.get("complete")
    if not isinstance(complete, bool):
        raise DataFormatError(card_path, None, "complete", "true or false", repr(complete))
    if not complete:
        return source.committed(card)
    if not isinstance(listed, list):
        raise DataFormatError(
            card_path, None, "shards", "the list of the dataset's shards", type(listed).__name__
        )
    version = card.get("card_version", CARD_VERSION)
    if (
        isinstance(version, bool)
        or not isinstance(version, int)
        or not 1 <= version <= CARD_VERSION
    ):
        raise DataFormatError(
            card_path, None, "card_version", f"an integer from 1 to {CARD_VERSION}", repr(version)
        )
    episodes = card.get("episodes")
    if episodes is not None and (
        isinstance(episodes, bool) or not isinstance(episodes, int) or episodes != len(listed)
    ):
        raise DataFormatError(
            card_path,
            None,
            "episodes",
            f"the number of shards the card lists ({len(listed)})",
            repr(episodes),
        )
    problems: list[DataFormatError] = []
    keep: list[str] = []
    names: set[str] = set()
    for k, entry in enumerate(listed):
        if not isinstance(entry, dict) or not isinstance(entry.get("path"), str):
            raise DataFormatError(
                card_path, f"shards[{k}]", "path", "a shard's relative path", repr(entry)
            )
        relative = entry["path"]
        if Path(relative).is_absolute() or ".." in Path(relative).parts:
            raise DataFormatError(
                card_path,
                f"shards[{k}]",
                "path",
                "a path inside the dataset's folder",
                repr(relative),
            )
        for key, kind in (("bytes", int), ("sha256", str)):
            if key in entry and (not isinstance(entry[key], kind) or isinstance(entry[key], bool)):
                raise DataFormatError(
                    card_path,
                    f"shards[{k}]",
                    key,
                    "a size in bytes" if kind is int else "a sha256 hex digest",
                    repr(entry[key]),
                )
        if relative in names:
            raise DataFormatError(
                card_path, f"shards[{k}]", "path", "each shard listed once", repr(relative)
            )
        names.add(relative)
        shard = source.where(relative)
        where = f"shard {relative} (shards[{k}] of {CARD_JSON})"
        size = source.size(relative)
        if isinstance(size, str):
            problems.append(DataFormatError(shard, None, None, f"the {where}", size))
            continue
        expected_size = entry.get("bytes")
        if isinstance(expected_size, int) and size != expected_size:
            problems.append(
                DataFormatError(
                    shard, None, "bytes", f"{expected_size} bytes ({where})", f"{size} bytes"
                )
            )
            continue
        expected_digest = entry.get("sha256")
        if isinstance(expected_digest, str):
            try:
                digest = source.sha256(relative)
            except OSError as exc:
                problems.append(DataFormatError(shard, None, None, f"a readable {where}", f"{exc}"))
                continue
            if digest != expected_digest:
                problems.append(
                    DataFormatError(
                        shard, None, "sha256", f"{expected_digest} ({where})", f"{digest} (altered)"
                    )
                )
                continue
        keep.append(relative)
    strays = [r for r in sorted(files) if r not in names]
    for relative in strays:
        problems.append(
            DataFormatError(
                source.where(relative),
                None,
                None,
                f"only the shards {CARD_JSON} lists ({len(listed)})",
                "a Parquet file it does not list (from another dataset?)",
            )
        )
    if problems and not allow_incomplete:
        first = problems[0]
        more = f"; {len(problems) - 1} more problem(s)" if len(problems) > 1 else ""
        raise DataFormatError(
            first.path,
            first.where,
            first.field,
            first.expected,
            first.found,
            hint=f"the dataset is not whole{more}; `reform-sim data verify {source.where()}` "
            "lists every problem, allow_incomplete=True (--allow-incomplete) reads the shards "
            "that are",
        )
    return keep, problems


def _check_complete(source: Any, card: Mapping[str, Any], n_files: int) -> None:
    """Refuses a ``reform-sim generate`` folder whose card says the run has not finished."""
    card_path = source.where(CARD_JSON)
    if not isinstance(card, dict) or card.get("complete", True) is not False:
        return
    command = str(card.get("command", "")).replace("--out DIR", f"--out {source.where()}")
    raise DataFormatError(
        card_path,
        None,
        "complete",
        "true (every episode of the run written)",
        f"false: incomplete dataset ({n_files} of {card.get('episodes', '?')} episodes written)",
        hint="run the same reform-sim generate command again to finish it"
        + (f" ({command})" if command else "")
        + ", or pass allow_incomplete=True (--allow-incomplete on the command line) to read the "
        "episodes written so far",
    )


def _natural_key(relative: Path) -> tuple:
    return tuple(
        tuple((0, int(t), "") if t.isdigit() else (1, 0, t) for t in re.split(r"(\d+)", part) if t)
        for part in relative.parts
    )


def _check_rows_fit(path: Path | str, pq: Any, source: Any = None) -> None:
    """Refuses, before reading it, a file whose rows cannot fit the memory available (a few MB
    of Parquet can claim a hundred million rows)."""
    try:
        rows = pq.ParquetFile(path if source is None else source).metadata.num_rows
    except Exception:  # noqa: BLE001 - a corrupt footer is named by read_table below
        return
    need = rows * READ_BYTES_PER_ROW
    available = available_memory()
    if available and need > available:
        raise DataFormatError(
            path,
            None,
            None,
            f"a file whose rows fit the {available / 2**30:.1f} GiB of memory available",
            f"{rows:,} rows needing about {need / 2**30:.1f} GiB to read",
        )


def _read_file(
    path: Path | str, content: bytes | None = None
) -> tuple[list[Frame], dict[str, Any]]:
    """The frames and header of the file at ``path``, or of its contents ``content`` (read from a
    store; ``path`` is then its URI, for messages)."""
    pa, pq = _pyarrow()
    if (len(content) if content is not None else Path(path).stat().st_size) == 0:
        raise DataFormatError(path, None, None, "a Parquet file", "an empty file")
    source = None if content is None else pa.BufferReader(content)
    _check_rows_fit(path, pq, source)
    try:
        table = pq.read_table(path if source is None else source, partitioning=None)
    except Exception as exc:  # pyarrow raises ArrowInvalid, OSError... on corrupt files
        raise DataFormatError(
            path, None, None, "a readable Parquet file", f"{type(exc).__name__}: {exc}"
        ) from exc
    raw = (table.schema.metadata or {}).get(METADATA_KEY)
    if raw is None:
        raise DataFormatError(
            path,
            None,
            "schema metadata",
            f"a {METADATA_KEY.decode()!r} entry (a file written by reform-sim)",
            "none",
        )
    header = _json_object(raw, path, field="schema metadata", expected="a JSON object")
    for key, kind in (("name", str), ("source", str), ("metadata", dict)):
        if key in header and not isinstance(header[key], kind):
            raise DataFormatError(
                path,
                None,
                key,
                f"a JSON {'object' if kind is dict else 'string'}",
                type(header[key]).__name__,
            )
    version = header.get("format_version")
    if not isinstance(version, int) or version > FORMAT_VERSION or version < 1:
        raise DataFormatError(
            path, None, "format_version", f"an integer from 1 to {FORMAT_VERSION}", repr(version)
        )
    if header.get("units", "m") != "m":
        raise DataFormatError(path, None, "units", "'m'", repr(header.get("units")))

    data: dict[str, np.ndarray] = {}
    null: dict[str, np.ndarray] = {}
    for name, (type_name, nullable, _, _) in COLUMNS.items():
        if name not in table.column_names:
            raise DataFormatError(
                path, None, name, f"a column {name!r}", f"columns {table.column_names}"
            )
        column = table.column(name)
        expected = _arrow_type(pa, type_name)
        if column.type != expected and not (
            type_name == "string" and column.type == pa.large_string()
        ):
            raise DataFormatError(path, None, name, f"type {expected}", f"{column.type}")
        mask = column.is_null().to_numpy(zero_copy_only=False)
        if not nullable and mask.any():
            row = int(np.flatnonzero(mask)[0])
            raise DataFormatError(path, f"row {row}", name, "a value", "null")
        null[name] = mask
        if type_name == "string":
            data[name] = np.array(column.to_pylist(), dtype=object)
        else:
            filled = column.fill_null(False if type_name == "bool" else 0) if mask.any() else column
            data[name] = filled.to_numpy()
    frames = _frames(path, data, null)
    return _with_listed_groups(path, frames, header.get("listed_groups")), header


def _with_listed_groups(path: Path, frames: list[Frame], listed: Any) -> list[Frame]:
    """``frames`` with the header's ``listed_groups`` (frame index -> groups) set."""
    if listed is None:
        return frames
    if not isinstance(listed, dict):
        raise DataFormatError(
            path, None, "listed_groups", "an object: frame index -> groups", type(listed).__name__
        )
    frames = list(frames)
    for key, groups in listed.items():
        if not (isinstance(key, str) and key.isdigit() and int(key) < len(frames)):
            raise DataFormatError(
                path, None, "listed_groups", f"frame indices below {len(frames)}", repr(key)
            )
        k = int(key)
        negative = _negative_member(groups)
        if negative is not None:
            raise DataFormatError(
                path, f"frame {k}", "listed_groups", f"ids >= 0 ({ID_RULE})", repr(negative)
            )
        try:
            frames[k] = frames[k].replace(listed_groups=groups)
        except (TypeError, ValueError) as exc:
            raise DataFormatError(
                path, f"frame {k}", "listed_groups", "groups agreeing with the frame", str(exc)
            ) from None
    return frames


def _negative_member(groups: Any) -> Any:
    """The first negative integer member of a list of groups (None when there is none; other
    malformations are the frame's to refuse)."""
    if not isinstance(groups, list):
        return None
    for group in groups:
        if isinstance(group, list):
            for member in group:
                if isinstance(member, int) and not isinstance(member, bool) and member < 0:
                    return member
    return None


def _check_ids_written(dataset: Dataset | FrameBlock) -> None:
    """Refuses a negative person id before anything is written: no reader would take it."""
    if isinstance(dataset, FrameBlock):
        if dataset.ids.size and int(dataset.ids.min()) < 0:
            raise ValueError(
                f"person ids must be >= 0 ({ID_RULE}), got {int(dataset.ids.min())} in the block"
            )
        return
    for k, frame in enumerate(dataset.frames):
        low = [int(frame.ids.min())] if frame.ids.size else []
        low += [m for g in frame.listed_groups or () for m in g if m < 0]
        if low and min(low) < 0:
            raise ValueError(f"person ids must be >= 0 ({ID_RULE}), got {min(low)} in frame {k}")


def _frames(path: Path, data: dict[str, np.ndarray], null: dict[str, np.ndarray]) -> list[Frame]:
    n_rows = data["frame"].size
    if n_rows == 0:
        return []
    index = data["frame"]
    _check_frame_runs(path, index)
    starts = np.concatenate([[0], np.flatnonzero(np.diff(index)) + 1])
    ends = np.concatenate([starts[1:], [n_rows]])

    for name in ("x", "y", "yaw", "head_x", "head_y", "head_yaw"):
        values = data[name]
        bad = ~null[name] & np.isinf(values)
        if name in ("x", "y", "yaw"):
            bad |= ~null[name] & np.isnan(values)
        if name in ("yaw", "head_yaw"):
            bad |= ~null[name] & (np.abs(values) > _YAW_LIMIT_RAD)
        else:
            bad |= ~null[name] & (np.abs(values) > POSITION_LIMIT_M)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            where = f"frame {int(index[row])} (row {row})"
            value = float(values[row])
            if not math.isfinite(value):
                expected = "a finite number" + (" or NaN" if name.startswith("head") else "")
            elif name.endswith("yaw"):
                expected = "radians in [-pi, pi] (larger values look like degrees)"
            else:
                expected = (
                    f"metres with |value| <= {POSITION_LIMIT_M:g} (farther looks like a corrupt "
                    "value)"
                )
            raise DataFormatError(path, where, name, expected, repr(value))
    if np.any(np.isnan(data["time"])) or np.any(np.isinf(data["time"])):
        row = int(np.flatnonzero(~np.isfinite(data["time"]))[0])
        raise DataFormatError(
            path,
            f"frame {int(index[row])} (row {row})",
            "time",
            "a finite number",
            repr(float(data["time"][row])),
        )
    _check_unique_ids(path, index, data["person_id"], null["person_id"])
    negative = np.flatnonzero(~null["person_id"] & (data["person_id"] < 0))
    if negative.size:
        row = int(negative[0])
        raise DataFormatError(
            path,
            f"frame {int(index[row])} (row {row})",
            "person_id",
            f"an id >= 0 ({ID_RULE})",
            str(int(data["person_id"][row])),
        )
    _check_heads(path, index, data, null)

    frames = []
    last_time: dict[str, tuple[int, float]] = {}  # sequence -> (frame, time) of its last frame
    for k, (a, b) in enumerate(zip(starts.tolist(), ends.tolist(), strict=True)):
        where = f"frame {k} (rows {a}..{b - 1})"
        for name in ("sequence", "time", "annotated", "has_head"):
            column = data[name][a:b]
            if np.any(column != column[0]):
                raise DataFormatError(
                    path,
                    where,
                    name,
                    "one value for all rows of the frame",
                    str(sorted(set(column.tolist()))),
                )
        sequence, time = str(data["sequence"][a]), float(data["time"][a])
        previous = last_time.get(sequence)
        check_time_increases(
            time,
            None if previous is None else previous[1],
            path=path,
            where=f"frame {k} (row {a})",
            field="time",
            previous_where=None if previous is None else f"frame {previous[0]}",
        )
        last_time[sequence] = (k, time)
        empty = null["person_id"][a:b]
        if empty.any():
            if b - a != 1:
                raise DataFormatError(
                    path, where, "person_id", "a value on every row of a frame with people", "null"
                )
            frames.append(
                make_frame(
                    path=path,
                    where=where,
                    ids=np.zeros(0, dtype=np.int64),
                    position=np.zeros((0, 2)),
                    yaw=np.zeros(0),
                    kinds=(),
                    head_position=np.zeros((0, 2)) if data["has_head"][a] else None,
                    head_yaw=np.zeros(0) if data["has_head"][a] else None,
                    groups=() if data["annotated"][a] else None,
                    time=time,
                    sequence=sequence,
                )
            )
            continue
        for name in ("kind", "x", "y", "yaw"):
            if null[name][a:b].any():
                raise DataFormatError(
                    path, where, name, "a value on every row of a frame with people", "null"
                )
        kinds = tuple(data["kind"][a:b].tolist())
        unknown = sorted({k for k in kinds if k not in KINDS})
        if unknown:
            raise DataFormatError(path, where, "kind", f"one of {KINDS}", str(unknown))
        head_position = head_yaw = None
        if data["has_head"][a]:
            for name in ("head_x", "head_y", "head_yaw"):
                if null[name][a:b].any():
                    raise DataFormatError(
                        path, where, name, "a number or NaN (has_head is true)", "null"
                    )
            head_position = np.column_stack([data["head_x"][a:b], data["head_y"][a:b]])
            head_yaw = data["head_yaw"][a:b]
        else:
            for name in ("head_x", "head_y", "head_yaw"):
                if not null[name][a:b].all():
                    raise DataFormatError(path, where, name, "null (has_head is false)", "a value")
        ids = data["person_id"][a:b]
        groups = _groups(
            path,
            where,
            ids,
            data["group"][a:b],
            data["group_member"][a:b],
            null["group"][a:b],
            null["group_member"][a:b],
            annotated=bool(data["annotated"][a]),
        )
        frames.append(
            make_frame(
                path=path,
                where=where,
                ids=ids,
                position=np.column_stack([data["x"][a:b], data["y"][a:b]]),
                yaw=data["yaw"][a:b],
                kinds=kinds,
                head_position=head_position,
                head_yaw=head_yaw,
                groups=groups,
                time=time,
                sequence=sequence,
            )
        )
    return frames


def _check_frame_runs(path: Path, index: np.ndarray) -> None:
    """Refuses rows not grouped by frame: each frame's rows together, frames 0, 1, 2, ..."""
    rule = "rows grouped by frame, frames 0, 1, 2, ... in order"
    if index[0] != 0:
        raise DataFormatError(path, "row 0", "frame", f"frame 0 ({rule})", str(int(index[0])))
    step = np.diff(index)
    bad = np.flatnonzero((step != 0) & (step != 1))
    if bad.size:
        row = int(bad[0]) + 1
        previous = int(index[row - 1])
        raise DataFormatError(
            path,
            f"row {row}",
            "frame",
            f"frame {previous} or {previous + 1} ({rule})",
            str(int(index[row])),
        )


def _check_unique_ids(
    path: Path, index: np.ndarray, person_id: np.ndarray, empty: np.ndarray
) -> None:
    """Refuses a person id listed twice in one frame, naming the second row."""
    rows = np.flatnonzero(~empty)
    if rows.size < 2:
        return
    ordered = rows[np.lexsort((rows, person_id[rows], index[rows]))]
    same = (index[ordered[1:]] == index[ordered[:-1]]) & (
        person_id[ordered[1:]] == person_id[ordered[:-1]]
    )
    if not same.any():
        return
    pairs = np.flatnonzero(same)
    k = pairs[np.argmin(ordered[1:][pairs])]  # the duplicate met first in the file
    first, row = int(ordered[k]), int(ordered[k + 1])
    raise DataFormatError(
        path,
        f"frame {int(index[row])} (row {row})",
        "person_id",
        "ids unique within the frame",
        f"{int(person_id[row])}, already on row {first}",
    )


def _check_heads(
    path: Path, index: np.ndarray, data: dict[str, np.ndarray], null: dict[str, np.ndarray]
) -> None:
    """Refuses a head observed in part: head_x, head_y, head_yaw are all numbers or all NaN."""
    names = ("head_x", "head_y", "head_yaw")
    valued = ~(null["head_x"] | null["head_y"] | null["head_yaw"])
    missing = np.column_stack([np.isnan(data[n]) for n in names])
    partial = valued & missing.any(axis=1) & ~missing.all(axis=1)
    if not partial.any():
        return
    row = int(np.flatnonzero(partial)[0])
    odd_nan = missing[row].sum() == 1  # one NaN among numbers, else one number among NaNs
    column = int(np.flatnonzero(missing[row] if odd_nan else ~missing[row])[0])
    others = " and ".join(n for c, n in enumerate(names) if c != column)
    raise DataFormatError(
        path,
        f"frame {int(index[row])} (row {row})",
        names[column],
        f"{'a number' if odd_nan else 'NaN'}, as {others} (a head is observed in full or not "
        "at all)",
        repr(float(data[names[column]][row])),
    )


def _groups(
    path: Path,
    where: str,
    ids: np.ndarray,
    group: np.ndarray,
    member: np.ndarray,
    group_null: np.ndarray,
    member_null: np.ndarray,
    *,
    annotated: bool,
) -> tuple[Group, ...] | None:
    if np.any(group_null != member_null):
        raise DataFormatError(
            path, where, "group_member", "null exactly where group is null", "a mismatch"
        )
    listed = ~group_null
    if not annotated:
        if listed.any():
            raise DataFormatError(
                path,
                where,
                "group",
                "null (the frame is not annotated)",
                f"{int(group[listed][0])}",
            )
        return None
    if not listed.any():
        return ()
    g, m, person = group[listed], member[listed], ids[listed]
    n_groups = int(g.max()) + 1
    # Each group holds someone: more groups than people listed is malformed (and a huge index
    # must not build a huge range).
    if g.min() < 0 or n_groups > g.size or set(g.tolist()) != set(range(n_groups)):
        raise DataFormatError(
            path,
            where,
            "group",
            f"indices 0..{n_groups - 1}, each used",
            str(sorted(set(g.tolist()))),
        )
    out = []
    for k in range(n_groups):
        in_group = g == k
        positions = m[in_group]
        if sorted(positions.tolist()) != list(range(int(in_group.sum()))):
            raise DataFormatError(
                path,
                where,
                "group_member",
                f"positions 0..{int(in_group.sum()) - 1} in group {k}",
                str(sorted(positions.tolist())),
            )
        out.append(tuple(int(p) for p in person[in_group][np.argsort(positions)]))
    return tuple(out)


@file_errors_as_data_errors
def verify_folder(path: str | PathLike[str]) -> list[str]:
    """Every problem of a ``reform-sim generate`` folder, one line each (empty when whole).

    Checks what :func:`read_parquet` checks, without stopping at the first problem: the card
    says the run finished; each shard it lists is there, of its size and sha256; no Parquet
    file is there that it does not list; every shard reads.

    Args:
        path: the folder, or its URI in a store (``s3://bucket/prefix``,
            `reform.datasets.store`).

    Raises:
        DataFormatError: ``path`` is not a folder with a card (``dataset.json``).
        reform.datasets.store.StoreError: a store that cannot be used (one line).
    """
    from reform.datasets.store import is_uri

    if not is_uri(path):
        path_argument(path, name="path", function="verify_folder")
    source = _source(path)
    card = source.card() if source is not None else None
    if card is None:
        raise DataFormatError(
            source.where() if source is not None else Path(path),
            None,
            None,
            f"a reform-sim generate folder (with {CARD_JSON})",
            "none",
        )
    problems: list[str] = []
    files = source.parquet_files(what="a reform-sim generate folder")
    try:
        _check_complete(source, card, len(files))
    except DataFormatError as exc:
        problems.append(str(exc))
    keep, found = _check_shards(source, card, files, allow_incomplete=True)
    problems += [str(p) for p in found]
    for relative in sorted(keep, key=lambda p: _natural_key(Path(p))):
        try:
            source.read(relative)
        except DataFormatError as exc:
            problems.append(str(exc))
    return problems


def _source(path: str | PathLike[str]) -> Any:
    """The folder at ``path`` (a `_LocalFolder`, or a store's for a URI); None when none."""
    from reform.datasets.store import is_uri

    if is_uri(path):
        from reform.datasets.store_dataset import StoreFolder

        return StoreFolder.open(str(path))
    folder = Path(path)
    return _LocalFolder(folder) if folder.is_dir() else None
