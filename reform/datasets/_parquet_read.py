"""Reading the project's Parquet format: its columns and version, one file, a folder of shards.

`reform.datasets.parquet` (the public `read_parquet`, `write_parquet`, `verify_folder`) and
`reform.datasets.store_dataset` (a folder in object storage) both build on this module; it
imports neither. A folder is read through a folder object (`_LocalFolder` here,
`reform.datasets.store_dataset.StoreFolder` for a store) that lists, sizes and reads shards by
relative path.

A file's rules are checked on whole columns and its frames made without a check each
(`reform.Frame._trusted_frames`), their arrays views of the columns read; a file that breaks a
rule only a frame can name (a frame's rows disagreeing on its time, a gap in its group indices)
is read again frame by frame, each frame checked and made on its own, so that the refusal names
the file, the frame and its rows, and the field.

pyarrow is imported only inside these functions.
"""

from __future__ import annotations

import functools
import hashlib
import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from reform.datasets import _walk
from reform.datasets._validation import (
    ID_RULE,
    check_not_text,
    check_time_increases,
    file_kind,
    make_frame,
)
from reform.datasets._walk import find_files
from reform.datasets.errors import DataFormatError, damaged_found, os_error_found
from reform.frame import KINDS, POSITION_LIMIT_M, Dataset, Frame, Group
from reform.json_values import JsonError, parse_json
from reform.machine import available_memory

FORMAT_VERSION = 1
METADATA_KEY = b"reform_sim"
_YAW_LIMIT_RAD = math.pi + 2e-3  # wrapped radians plus rounding; larger values look like degrees
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
            return os_error_found(exc)

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
    except OSError as exc:
        raise DataFormatError(
            card_path, None, None, "a reform-sim dataset card (JSON)", os_error_found(exc)
        ) from None
    except UnicodeDecodeError:
        raise DataFormatError(
            card_path, None, None, "a reform-sim dataset card (JSON)", "bytes that are not UTF-8"
        ) from None
    return _json_object(text, card_path, field=None, expected="a reform-sim dataset card (JSON)")


def _json_object(
    text: str | bytes, path: Path, *, field: str | None, expected: str
) -> dict[str, Any]:
    """``text`` as a JSON object; one `DataFormatError` naming ``path`` for anything else
    (malformed, nested too deep to read, not an object)."""
    try:
        value = parse_json(text)
    except JsonError as exc:
        raise DataFormatError(path, None, field, expected, str(exc)) from None
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


def _check_rows_fit(path: Path | str, pq: Any, source: Any = None) -> Any:
    """Refuses, before reading it, a file whose rows cannot fit the memory available (a few MB
    of Parquet can claim a hundred million rows). Returns the file's schema as pyarrow reads
    it, or None when its footer cannot be read (read_table names that)."""
    try:
        file = pq.ParquetFile(path if source is None else source)
        rows = file.metadata.num_rows
    except Exception:  # noqa: BLE001 - a corrupt footer is named by read_table below
        return None
    try:
        schema = file.schema_arrow
    except Exception:  # noqa: BLE001 - named by read_table below, as a corrupt footer is
        schema = None
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
    return schema


def _as_codes(pa: Any, schema: Any) -> list[str]:
    """The format's string columns that ``schema`` (a file's) holds as plain text: read as
    codes into their distinct texts (``read_dictionary``), which pyarrow does faster than
    reading the texts to encode them again (`_dictionary`). A column stored with another type
    is read as stored, to be refused by its type."""
    if schema is None:
        return []
    out = []
    for name, (type_name, _, _, _) in COLUMNS.items():
        index = schema.get_field_index(name)  # -1: absent, or more than one column so named
        if type_name == "string" and index >= 0:
            if schema.field(index).type in (pa.string(), pa.large_string()):
                out.append(name)
    return out


def _read_file(
    path: Path | str, content: bytes | None = None
) -> tuple[list[Frame], dict[str, Any]]:
    """The frames and header of the file at ``path``, or of its contents ``content`` (read from a
    store; ``path`` is then its URI, for messages)."""
    pa, pq = _pyarrow()
    if (len(content) if content is not None else Path(path).stat().st_size) == 0:
        raise DataFormatError(path, None, None, "a Parquet file", "an empty file")
    check_not_text(path, expected="a Parquet file", name="Parquet", content=content)
    source = None if content is None else pa.BufferReader(content)
    as_codes = _as_codes(pa, _check_rows_fit(path, pq, source))
    try:
        table = pq.read_table(
            path if source is None else source,
            partitioning=None,
            read_dictionary=as_codes or None,
            page_checksum_verification=True,  # pages written with a CRC (every file since)
        )
    except Exception as exc:  # pyarrow raises ArrowInvalid, OSError... on corrupt files
        found = (
            os_error_found(exc)
            if isinstance(exc, OSError) and exc.errno
            else damaged_found("Parquet file", str(exc))
        )
        raise DataFormatError(path, None, None, "a readable Parquet file", found) from exc
    try:
        columns = table.column_names
    except UnicodeDecodeError as exc:  # a column name's bytes are not UTF-8
        raise DataFormatError(
            path, None, "column names", "UTF-8 text", f"bytes that are not ({exc.reason})"
        ) from None
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
    extra = [name for name in columns if name not in COLUMNS]
    if extra:  # read, it would be dropped without a word
        raise DataFormatError(
            path,
            None,
            extra[0],
            f"only the columns of format version {version} ({', '.join(COLUMNS)})",
            "a column of another name",
        )

    data: dict[str, np.ndarray] = {}
    null: dict[str, np.ndarray] = {}
    texts: dict[str, list[str]] = {}
    for name, (type_name, nullable, _, _) in COLUMNS.items():
        if name not in columns:
            raise DataFormatError(path, None, name, f"a column {name!r}", f"columns {columns}")
        column = table.column(name)
        expected = _arrow_type(pa, type_name)
        coded = name in as_codes and pa.types.is_dictionary(column.type)
        found = column.type.value_type if coded else column.type
        if found != expected and not (type_name == "string" and found == pa.large_string()):
            raise DataFormatError(path, None, name, f"type {expected}", f"{found}")
        if column.null_count:
            mask = column.is_null().to_numpy(zero_copy_only=False)
        else:
            mask = np.zeros(len(column), dtype=bool)
        if not nullable:
            DataFormatError.check_rows(
                mask, path, lambda row: f"row {row}", name, "a value", show=lambda _: "null"
            )
        null[name] = mask
        if type_name == "string":
            data[name], texts[name] = (
                _codes(column, path, name) if coded else _dictionary(column)
            )
        else:
            filled = column.fill_null(False if type_name == "bool" else 0) if mask.any() else column
            data[name] = filled.to_numpy()
    frames = _frames(path, data, null, texts)
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


def _dictionary(column: Any) -> tuple[np.ndarray, list[str]]:
    """A string column as codes into its distinct texts, in order of first appearance: row
    ``r`` holds ``texts[codes[r]]``, and a null row the code ``len(texts)``."""
    encoded = column.combine_chunks().dictionary_encode()
    texts = encoded.dictionary.to_pylist()
    return encoded.indices.fill_null(len(texts)).to_numpy(), texts


def _codes(column: Any, path: Path, name: str) -> tuple[np.ndarray, list[str]]:
    """`_dictionary` of a string column read as codes (`_as_codes`): its dictionaries made one,
    in order of first appearance (each chunk's own order, as a file's writer made it, and the
    texts of later chunks after those of earlier ones); encoded again by `_dictionary` where a
    file's dictionary lists one text twice, so that one text always has one code. A code
    outside its dictionary (a damaged file) is a DataFormatError naming its row."""
    encoded = column.combine_chunks()
    texts = encoded.dictionary.to_pylist()
    codes = encoded.indices.fill_null(0).to_numpy()
    null = encoded.indices.is_null().to_numpy(zero_copy_only=False)
    DataFormatError.check_rows(
        ~null & ((codes < 0) | (codes >= len(texts))),
        path,
        lambda row: f"row {row}",
        name,
        f"a code of one of its column's {len(texts)} texts (a damaged file?)",
        codes,
        lambda value: f"code {int(value)}",
    )
    if len(set(texts)) < len(texts):
        return _dictionary(column.cast(column.type.value_type))
    return encoded.indices.fill_null(len(texts)).to_numpy(), texts


def _objects(codes: np.ndarray, texts: list[str]) -> np.ndarray:
    """The string column of ``codes`` into ``texts`` as an object array, None where null."""
    return np.array([*texts, None], dtype=object)[codes]


def _frames(
    path: Path,
    data: dict[str, np.ndarray],
    null: dict[str, np.ndarray],
    texts: dict[str, list[str]],
) -> list[Frame]:
    """The frames of a file's columns (string columns as codes into ``texts``), each rule of
    the format checked: on whole columns first; then, when a frame breaks a rule that
    `_frames_from_columns` checks only as a whole, by `_frames_one_by_one`, which names it."""
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
            where = _frame_row(index, row)
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
    at_row = functools.partial(_frame_row, index)
    times, person_id = data["time"], data["person_id"]
    DataFormatError.check_rows(~np.isfinite(times), path, at_row, "time", "a finite number", times)
    _check_unique_ids(path, index, person_id, null["person_id"])
    negative = ~null["person_id"] & (person_id < 0)
    rule = f"an id >= 0 ({ID_RULE})"
    DataFormatError.check_rows(
        negative, path, at_row, "person_id", rule, person_id, lambda value: str(int(value))
    )
    _check_heads(path, index, data, null)

    frames = _frames_from_columns(data, null, texts, starts, ends)
    if frames is not None:
        return frames
    objects = {name: _objects(data[name], words) for name, words in texts.items()}
    return _frames_one_by_one(path, data | objects, null, starts, ends)


def _frames_one_by_one(
    path: Path,
    data: dict[str, np.ndarray],
    null: dict[str, np.ndarray],
    starts: np.ndarray,
    ends: np.ndarray,
) -> list[Frame]:
    """The frames of a file's columns (string columns as object arrays), whose whole-column
    rules hold, built and checked one at a time: the first frame to break a rule is named
    (which frame, rows, field), as `_frames_from_columns` cannot."""
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


def _frames_from_columns(
    data: dict[str, np.ndarray],
    null: dict[str, np.ndarray],
    texts: dict[str, list[str]],
    starts: np.ndarray,
    ends: np.ndarray,
) -> list[Frame] | None:
    """The frames of a file's columns, every rule `_frames_one_by_one` checks frame by frame
    checked at once on whole columns; None when a frame breaks one (the caller then reads the
    file frame by frame, to name it). Same frames as `_frames_one_by_one`, value for value.

    ``data`` and ``null``: each column (string ones as codes into ``texts``) and its nulls,
    whose whole-column rules hold (`_frames`: rows grouped by frame, poses finite and in range,
    heads whole, ids unique within a frame and >= 0, times finite). ``starts``, ``ends``: each
    frame's first row and one past its last.
    """
    index = data["frame"]
    n_frames = starts.size
    counts = ends - starts
    # One value a frame: its sequence, time, whether annotated, whether with heads.
    for name in ("sequence", "time", "annotated", "has_head"):
        if np.any(data[name] != data[name][starts][index]):
            return None
    sequence_code, times = data["sequence"][starts], data["time"][starts]
    # Times increase within each sequence (frames of different sequences may interleave).
    order = np.argsort(sequence_code, kind="stable")
    same = sequence_code[order][1:] == sequence_code[order][:-1]
    if np.any(same & ~(times[order][1:] > times[order][:-1])):
        return None
    # A frame with nobody is one row whose person_id is null; its other columns are not read.
    empty = null["person_id"][starts]
    if np.any(np.bincount(index, weights=null["person_id"], minlength=n_frames) > empty):
        return None
    if np.any(empty & (counts != 1)):
        return None
    people = ~null["person_id"]  # the rows of frames with people
    heads = data["has_head"]
    if any(np.any(people & null[name]) for name in ("kind", "x", "y", "yaw")):
        return None
    known_kind = np.array([word in KINDS for word in texts["kind"]] + [False])
    if not np.all(known_kind[data["kind"][people]]):
        return None
    for name in ("head_x", "head_y", "head_yaw"):
        if np.any(people & (null[name] == heads)):  # null exactly where the frame has no heads
            return None
    frame_groups = _frame_groups(data, null, starts, counts, people)
    if frame_groups is None:
        return None

    # Each frame's arrays are views of the columns (a frame with nobody: of none of its rows).
    n_people = np.where(empty, 0, counts)
    ids = _pieces(data["person_id"], starts, n_people)
    position = _pieces(np.column_stack([data["x"], data["y"]]), starts, n_people)
    yaw = _pieces(data["yaw"], starts, n_people)
    has_head = heads[starts]
    head_position = head_yaw = [None] * n_frames
    if has_head.any():
        head_position = _pieces(np.column_stack([data["head_x"], data["head_y"]]), starts, n_people)
        head_yaw = _pieces(data["head_yaw"], starts, n_people)
        if not has_head.all():
            where = has_head.tolist()
            head_position = [v if h else None for v, h in zip(head_position, where, strict=True)]
            head_yaw = [v if h else None for v, h in zip(head_yaw, where, strict=True)]
    kinds = _kinds(data["kind"][people], texts["kind"], n_people)
    sequences = _objects(sequence_code, texts["sequence"]).tolist()
    return Frame._trusted_frames(
        ids, position, yaw, kinds, head_position, head_yaw, frame_groups, times.tolist(), sequences
    )


def _frame_groups(
    data: dict[str, np.ndarray],
    null: dict[str, np.ndarray],
    starts: np.ndarray,
    counts: np.ndarray,
    people: np.ndarray,
) -> list[tuple[Group, ...] | None] | None:
    """Each frame's groups (None where not annotated) from the columns ``group`` and
    ``group_member`` of the rows of frames with people (``people``); None when a frame's
    breaks a rule of `_groups`. ``starts``, ``counts``: each frame's first row and rows."""
    index, annotated = data["frame"], data["annotated"]
    in_group = people & ~null["group"]
    if np.any(people & (null["group"] != null["group_member"])) or np.any(in_group & ~annotated):
        return None
    # The groups, checked and put in order without sorting: a group's slot is its frame's
    # first row plus its index, a member's place the group's first place plus its position.
    rows = np.flatnonzero(in_group)
    frame_of = index[rows]
    group = data["group"][rows].astype(np.int64)
    member = data["group_member"][rows].astype(np.int64)
    n_listed = counts[frame_of]
    if np.any((group < 0) | (group >= n_listed) | (member < 0) | (member >= n_listed)):
        return None
    slot = starts[frame_of] + group
    size = np.bincount(slot, minlength=index.size)
    if np.any(size[slot[group > 0] - 1] == 0):  # a frame's groups 0, 1, 2, ... each used
        return None
    if np.any(member >= size[slot]):
        return None
    offset = np.cumsum(size) - size
    place = offset[slot] + member
    taken = np.zeros(rows.size, dtype=bool)
    taken[place] = True
    if not taken.all():  # two members at one place in a group
        return None
    in_order = np.empty(rows.size, dtype=np.int64)
    in_order[place] = data["person_id"][rows]
    used = np.flatnonzero(size)
    bounds = [*offset[used].tolist(), rows.size]
    members = in_order.tolist()
    group_starts = np.searchsorted(index[used], np.arange(starts.size + 1)).tolist()
    # A frame whose groups are those of the frame before (most frames of a recording) shares
    # them: same number of people in groups, same people at each place, same group breaks.
    n_frames = starts.size
    noted = annotated[starts]
    listed = np.bincount(frame_of, minlength=n_frames)
    frame_of_place = np.repeat(np.arange(n_frames), listed)
    group_of_place = np.empty(rows.size, dtype=np.int64)
    group_of_place[place] = group
    again = np.zeros(n_frames, dtype=bool)
    again[1:] = noted[1:] & noted[:-1] & (listed[1:] == listed[:-1])
    back = np.arange(rows.size)
    back = np.where(again[frame_of_place], back - np.repeat([0, *listed[:-1]], listed), back)
    differ = (in_order != in_order[back]) | (group_of_place != group_of_place[back])
    again &= np.bincount(frame_of_place, weights=differ, minlength=n_frames) == 0
    out: list[tuple[Group, ...] | None] = []
    for a, b, note, same in zip(
        group_starts[:-1], group_starts[1:], noted.tolist(), again.tolist(), strict=True
    ):
        if same:
            out.append(out[-1])
        elif note:
            out.append(tuple([tuple(members[bounds[j] : bounds[j + 1]]) for j in range(a, b)]))
        else:
            out.append(None)
    return out


def _kinds(codes: np.ndarray, words: list[str], n_people: np.ndarray) -> list[tuple[str, ...]]:
    """Each frame's kinds, from the kind ``codes`` into ``words`` of the rows of frames with
    people (a frame with nobody: no row, no kind). Frames of one kind throughout (SALSA's
    humans) share one tuple per size."""
    sizes = n_people.tolist()
    if codes.size and np.all(codes == codes[0]):
        by_size = {n: (words[codes[0]],) * n for n in set(sizes)}
        return [by_size[n] for n in sizes]
    kind_of_row = _objects(codes, words).tolist()
    firsts = np.cumsum(n_people) - n_people  # each frame's first row among the rows with people
    return [tuple(kind_of_row[a : a + n]) for a, n in zip(firsts.tolist(), sizes, strict=True)]


def _pieces(values: np.ndarray, starts: np.ndarray, sizes: np.ndarray) -> list[np.ndarray]:
    """``values[starts[k] : starts[k] + sizes[k]]`` for each k, read-only views of ``values``
    (an array this reading made, which nothing else holds: as private as copies). A run of
    consecutive frames of one size is cut as one block reshaped, frame by row (iterating over
    its rows is many times faster than slicing each frame)."""
    values.flags.writeable = False
    change = np.flatnonzero(sizes[1:] != sizes[:-1]) + 1
    out: list[np.ndarray] = []
    for first, last in zip([0, *change.tolist()], [*change.tolist(), sizes.size], strict=True):
        start, size = int(starts[first]), int(sizes[first])
        if last - first == 1:
            out.append(values[start : start + size])
            continue
        block = values[start : start + (last - first) * size]
        out.extend(block.reshape(last - first, size, *values.shape[1:]))
    return out


def _frame_row(index: np.ndarray, row: int) -> str:
    """Where row ``row`` (0-based) is in a file whose frame of each row is ``index``."""
    return f"frame {int(index[row])} (row {row})"


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
    if rows.size < 2 or _unique_by_count(index[rows], person_id[rows]):
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
        _frame_row(index, row),
        "person_id",
        "ids unique within the frame",
        f"{int(person_id[row])}, already on row {first}",
    )


def _unique_by_count(frame: np.ndarray, ids: np.ndarray) -> bool:
    """True when no id occurs twice in one frame, found by counting each (frame, id) pair;
    False when one does, or when ids spread too wide to count in memory proportional to the
    rows (the caller then sorts)."""
    low, high = int(ids.min()), int(ids.max())
    span = high - low + 1
    n_pairs = (int(frame.max()) + 1) * span
    if n_pairs > 4 * frame.size + 1024:
        return False
    return int(np.bincount(frame * span + (ids - low), minlength=1).max()) <= 1


def _check_heads(
    path: Path, index: np.ndarray, data: dict[str, np.ndarray], null: dict[str, np.ndarray]
) -> None:
    """Refuses a head observed in part: head_x, head_y, head_yaw are all numbers or all NaN."""
    names = ("head_x", "head_y", "head_yaw")
    valued = ~(null["head_x"] | null["head_y"] | null["head_yaw"])
    nan_x, nan_y, nan_yaw = (np.isnan(data[n]) for n in names)
    if not np.any(valued & ((nan_x != nan_y) | (nan_x != nan_yaw))):
        return
    missing = np.column_stack([nan_x, nan_y, nan_yaw])
    partial = valued & missing.any(axis=1) & ~missing.all(axis=1)
    if not partial.any():
        return
    row = int(np.flatnonzero(partial)[0])
    odd_nan = missing[row].sum() == 1  # one NaN among numbers, else one number among NaNs
    column = int(np.flatnonzero(missing[row] if odd_nan else ~missing[row])[0])
    others = " and ".join(n for c, n in enumerate(names) if c != column)
    raise DataFormatError(
        path,
        _frame_row(index, row),
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
