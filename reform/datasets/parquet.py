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

The columns and the reading of a file or a folder live in `reform.datasets._parquet_read`,
which `reform.datasets.store_dataset` (a folder in object storage) shares.

pyarrow is imported only inside these functions.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from reform import __version__
from reform.atomic import atomic_path
from reform.datasets._parquet_read import (
    CARD_JSON,
    COLUMNS,
    FORMAT_VERSION,
    METADATA_KEY,
    _arrow_type,
    _check_complete,
    _check_shards,
    _LocalFolder,
    _natural_key,
    _pyarrow,
    _read_file,
    _read_folder,
)
from reform.datasets._validation import ID_RULE, file_kind
from reform.datasets.errors import DataFormatError, file_errors_as_data_errors
from reform.datasets.store import is_uri
from reform.datasets.store_dataset import StoreFolder, read_store
from reform.frame import Dataset, Frame
from reform.frame_block import FrameBlock
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

# Parquet codecs a file may be written with (``"none"``: uncompressed).
CODECS = ("none", "snappy", "gzip", "brotli", "lz4", "zstd")

# The columns written with a dictionary: those whose values repeat (names, ids, kinds, frame
# numbers, flags, groups). The float columns (time and poses) are written plain: a dictionary of
# 20,000 measurements that hardly repeat doubles the time to write them and adds a fifth to the
# file. Readers need nothing of this: a file with every column in a dictionary (pyarrow's default,
# which files written earlier have) reads as it did.
_DICTIONARY_COLUMNS = tuple(name for name, spec in COLUMNS.items() if spec[0] != "float64")


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


def _block_columns(block: FrameBlock) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The long table's columns (as :func:`_columns` makes them) from a block's arrays.

    Whole arrays at once: each row's values taken from the block's arrays by one flat index
    (instant x roster slot), the groups laid out once per run of instants that share them
    (`FrameBlock.present_groups` gives one object for such a run), not person by person."""
    time, ids, present, n_frames, n = (
        block.time,
        block.ids,
        block.present,
        len(block),
        block.ids.size,
    )
    has_head = block.head_position is not None

    # Row order: frame by frame, the people present in roster order; an empty frame gets one
    # row in an extra slot n (its person columns null).
    empty_frame = ~present.any(axis=1)
    slots = np.concatenate([present, empty_frame[:, None]], axis=1)
    t_of, a_of = np.nonzero(slots)
    n_rows = t_of.size
    empty = a_of == n
    a_safe = np.where(empty, 0, a_of)
    flat = t_of * n + a_safe  # the row's place in a (T, n) array

    out = _PersonRows(n_rows, kinds=False)
    out.empty[:] = empty
    if n:
        out.person_id[:] = ids.take(a_safe)
        out.person_id[empty] = 0
        out.body[:, :2] = block.position.reshape(-1, 2).take(flat, axis=0)
        out.body[:, 2] = block.yaw.reshape(-1).take(flat)
        if has_head:
            out.head[:, :2] = block.head_position.reshape(-1, 2).take(flat, axis=0)
            out.head[:, 2] = block.head_yaw.reshape(-1).take(flat)
    out.body[empty] = 0.0
    out.head[empty] = 0.0

    # Each instant's group and place in it by roster slot (-1: in none; slot n: the empty
    # frame's row), set once per run of instants with the same groups.
    group_of = np.full((n_frames, n + 1), -1, dtype=np.int32)
    member_of = np.full((n_frames, n + 1), -1, dtype=np.int32)
    annotated_frame = np.zeros(n_frames, dtype=bool)
    index_of = {int(i): a for a, i in enumerate(ids.tolist())}
    laid_out: dict[int, tuple[list[int], list[int], list[int]]] = {}
    runs = []  # (first instant, end, groups)
    for t, frame_groups in enumerate(block.present_groups()):
        if frame_groups is None:
            continue
        if runs and runs[-1][2] is frame_groups and runs[-1][1] == t:
            runs[-1][1] = t + 1
        else:
            runs.append([t, t + 1, frame_groups])
    for start, end, frame_groups in runs:
        annotated_frame[start:end] = True
        layout = laid_out.get(id(frame_groups))
        if layout is None:
            layout = ([], [], [])
            for g, members in enumerate(frame_groups):
                for m, person in enumerate(members):
                    layout[0].append(index_of[int(person)])
                    layout[1].append(g)
                    layout[2].append(m)
            laid_out[id(frame_groups)] = layout
        if layout[0]:
            group_of[start:end, layout[0]] = layout[1]
            member_of[start:end, layout[0]] = layout[2]
    slot = t_of * (n + 1) + a_of  # the row's place in a (T, n + 1) array
    out.group[:] = group_of.reshape(-1).take(slot)
    out.member[:] = member_of.reshape(-1).take(slot)

    # The string columns as Arrow arrays straight away: each row's kind taken from the roster's
    # (null for an empty frame's row), the one sequence name repeated.
    pa, _ = _pyarrow()
    out.kind = pa.array([*block.kinds, None], type=pa.string()).take(a_of)
    counts = np.bincount(t_of, minlength=n_frames)
    return out.columns(
        sequence=pa.repeat(pa.scalar(block.sequence, type=pa.string()), n_rows),
        frame=t_of.astype(np.int64),
        time=np.repeat(time, counts),
        annotated=np.repeat(annotated_frame, counts),
        has_head=np.full(n_rows, has_head),
    )


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
        if isinstance(values, pa.Array):  # made as Arrow already, its nulls included
            arrays.append(values)
        else:
            arrays.append(pa.array(values, type=arrow_type, mask=mask if nullable else None))
        meta = {b"description": description.encode()}
        if unit:
            meta[b"unit"] = unit.encode()
        fields.append(pa.field(name, arrow_type, nullable=nullable, metadata=meta))
    schema = pa.schema(fields, metadata={METADATA_KEY: header_json.encode()})
    table = pa.Table.from_arrays(arrays, schema=schema)
    with atomic_path(target) as tmp:
        pq.write_table(
            table,
            tmp,
            compression=compression,
            use_dictionary=_DICTIONARY_COLUMNS,
            write_page_checksum=True,  # each page's CRC: a changed byte is found when read
        )
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

    out = _PersonRows(n_rows)
    start = 0
    for frame, count in zip(frames, counts.tolist(), strict=True):
        n = frame.n_people
        rows = slice(start, start + count)
        if n == 0:
            out.empty[start] = True
            out.kind[start] = None
        else:
            out.person_id[rows] = frame.ids
            out.kind[rows] = frame.kinds
            out.body[rows, :2] = frame.position
            out.body[rows, 2] = frame.yaw
            if frame.head_position is not None:
                out.head[rows, :2] = frame.head_position
                out.head[rows, 2] = frame.head_yaw
            if frame.groups:
                row_of = {int(i): start + r for r, i in enumerate(frame.ids.tolist())}
                for g, members in enumerate(frame.groups):
                    for m, person in enumerate(members):
                        out.group[row_of[person]] = g
                        out.member[row_of[person]] = m
        start += count
    return out.columns(
        sequence=sequence, frame=frame_index, time=time, annotated=annotated, has_head=has_head
    )


class _PersonRows:
    """The long table's per-person arrays, one entry a row, while a writer fills them: ids,
    kinds, ``body`` and ``head`` poses ((n_rows, 3): x, y, yaw), the group and the place in it
    (-1: in none), and ``empty``: the one row of a frame with nobody (person columns null).
    ``kinds=False``: the writer sets ``kind`` itself, as an Arrow string array."""

    def __init__(self, n_rows: int, *, kinds: bool = True) -> None:
        self.person_id = np.zeros(n_rows, dtype=np.int64)
        self.kind: Any = np.empty(n_rows, dtype=object) if kinds else None
        # Column-major: each of x, y, yaw one contiguous column, as Arrow takes it.
        self.body = np.zeros((n_rows, 3), order="F")
        self.head = np.zeros((n_rows, 3), order="F")
        self.group = np.full(n_rows, -1, dtype=np.int32)
        self.member = np.full(n_rows, -1, dtype=np.int32)
        self.empty = np.zeros(n_rows, dtype=bool)

    def columns(
        self,
        *,
        sequence: np.ndarray,
        frame: np.ndarray,
        time: np.ndarray,
        annotated: np.ndarray,
        has_head: np.ndarray,
    ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Every column of the long table, values and null masks (True = null), given the
        frame-level ones (one entry a row). A value that is an Arrow array already carries
        its nulls (`_write_table` takes it as it is)."""
        empty = self.empty
        no_head = empty | ~has_head
        no_group = self.group < 0
        nothing = np.zeros(empty.size, dtype=bool)
        return {
            "sequence": (sequence, nothing),
            "frame": (frame, nothing),
            "time": (time, nothing),
            "annotated": (annotated, nothing),
            "has_head": (has_head, nothing),
            "person_id": (self.person_id, empty),
            "kind": (self.kind, empty),
            "x": (self.body[:, 0], empty),
            "y": (self.body[:, 1], empty),
            "yaw": (self.body[:, 2], empty),
            "head_x": (self.head[:, 0], no_head),
            "head_y": (self.head[:, 1], no_head),
            "head_yaw": (self.head[:, 2], no_head),
            "group": (self.group, no_group),
            "group_member": (self.member, no_group),
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
    if is_uri(path):
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


@file_errors_as_data_errors
def verify_folder(path: str | PathLike[str]) -> list[str]:
    """Every problem of a ``reform-sim generate`` folder, one line each (empty when whole).

    Checks what :func:`read_parquet` checks, without stopping at the first problem: the card
    says the run finished; each shard it lists is there, of its size and sha256; no Parquet
    file is there that it does not list; every shard reads. Then that the card's counts are
    its shards' (`_check_counts`).

    Args:
        path: the folder, or its URI in a store (``s3://bucket/prefix``,
            `reform.datasets.store`).

    Raises:
        DataFormatError: ``path`` is not a folder with a card (``dataset.json``), or a count
            of its card is not what its shards give.
        reform.datasets.store.StoreError: a store that cannot be used (one line).
    """
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
    counted: dict[str, dict[str, Any]] = {}
    for relative in sorted(keep, key=lambda p: _natural_key(Path(p))):
        try:
            frames, _ = source.read(relative)
        except DataFormatError as exc:
            problems.append(str(exc))
            continue
        counted[relative] = {field: hold(frames) for field, hold in _HELD.items()}
    if card.get("complete") is True:  # an unfinished run's card is refused as such above
        _check_counts(source.where(CARD_JSON), card, counted, every=not problems)
    return problems


def _group_sizes(frames: list[Frame]) -> dict[str, int]:
    """Size -> groups of that size over the annotated frames, everyone counted (people alone
    are groups of one), as a card keeps them."""
    from reform.datasets.summary import summarise

    return summarise(Dataset(frames=tuple(frames), name="shard"))["group_sizes"]


# What a card says of each shard (and, in its totals, of them all: the counts and the group
# sizes summed), as the shard's frames give it.
_COUNTS = {
    "frames": len,
    "annotated_frames": lambda frames: sum(frame.groups is not None for frame in frames),
    "rows": lambda frames: sum(frame.n_people for frame in frames),
}
_HELD = {
    **_COUNTS,
    "sequence": lambda frames: ", ".join(dict.fromkeys(frame.sequence for frame in frames)),
    "group_sizes": _group_sizes,
}


def _check_counts(
    card_path: Path | str,
    card: Mapping[str, Any],
    counted: Mapping[str, Mapping[str, Any]],
    *,
    every: bool,
) -> None:
    """Refuses a card that says of its shards what they do not hold: each shard's `_HELD` that
    ``counted`` holds (shard path -> values), its episode against its path's
    (``episode=N``), and, when ``every`` shard was counted, its totals of them."""
    for k, entry in enumerate(card["shards"]):
        held = counted.get(entry["path"])
        if held is None:
            continue
        named = re.search(r"(?:^|/)episode=(\d+)/", entry["path"])
        found = {**held, **({"episode": int(named.group(1))} if named else {})}
        for field, value in found.items():
            if field in entry and entry[field] != value:
                what = field.replace("_", " ")
                raise DataFormatError(
                    card_path,
                    f"shards[{k}]",
                    field,
                    f"the {what} of shard {entry['path']} ({value!r})",
                    repr(entry[field]),
                )
    totals = card.get("totals")
    if not every or not isinstance(totals, dict):
        return
    sizes: dict[str, int] = {}
    for held in counted.values():
        for size, count in held["group_sizes"].items():
            sizes[size] = sizes.get(size, 0) + count
    given = {"shards": (len(counted), "the number of its shards")} | {
        field: (
            sum(held[field] for held in counted.values()),
            f"the {field.replace('_', ' ')} its {len(counted)} shards hold",
        )
        for field in _COUNTS
    }
    given["group_sizes"] = (
        dict(sorted(sizes.items(), key=lambda item: int(item[0]))),
        f"the group sizes its {len(counted)} shards hold",
    )
    for field, (value, what) in given.items():
        if field in totals and totals[field] != value:
            raise DataFormatError(
                card_path, "totals", field, f"{what} ({value!r})", repr(totals[field])
            )


def _source(path: str | PathLike[str]) -> Any:
    """The folder at ``path`` (a `_LocalFolder`, or a store's for a URI); None when none."""
    if is_uri(path):
        return StoreFolder.open(str(path))
    folder = Path(path)
    return _LocalFolder(folder) if folder.is_dir() else None
