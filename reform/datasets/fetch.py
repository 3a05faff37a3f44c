"""The field's public datasets: their registry, fetching them into a local cache, and finding them.

The registry (``public-datasets.json``, shipped with the package) pins every file of every public
F-formation dataset: its GitHub repository, commit and path, its size and its sha256. Nothing of
the data itself is shipped: :func:`fetch` downloads it, at the pinned commit, from
``https://raw.githubusercontent.com/<repo>/<commit>/<path>`` or from a mirror laid out the same
way, verifies each file's size and sha256, and keeps it in the cache (:func:`cache_dir`).

A fetched dataset's folder is laid out to be read by `reform.datasets.load_dataset`: the folders
its files share in the repository are dropped (CoffeeBreak's
``data/octave/CoffeeBreak/Seq1/features.mat`` is ``<cache>/coffeebreak/Seq1/features.mat``).
Each file is downloaded to a temporary name and moved into place once verified; the folder is
marked complete by a manifest (:data:`MANIFEST`), written atomically after the last file. A
failed fetch leaves no manifest and no unverified file under a final name.

:func:`resolve` turns what a user typed (a path, a fetched dataset's name, or the name of a folder
among the real datasets beside a clone) into a path.

pooch (download and checksum) and platformdirs (the user data folder) are imported only inside
the functions that use them, so that ``import reform.datasets`` stays light.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
import posixpath
import re
import shutil
import socket
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from importlib import resources
from os import PathLike
from pathlib import Path, PurePosixPath
from typing import Any
from urllib.parse import quote, unquote, urlsplit

from reform.atomic import atomic_open, check_folder_path, file_kind, temporary_folder
from reform.datasets.errors import DataFormatError
from reform.json_values import JsonError, parse_json
from reform.path_argument import path_argument

__all__ = [
    "DATA_VARIABLE",
    "DEFAULT_MIRROR",
    "MANIFEST",
    "DatasetFile",
    "FetchError",
    "PublicDataset",
    "cache_dir",
    "download_deadline",
    "fetch",
    "is_fetched",
    "local_datasets_dir",
    "one_per_recording",
    "registry",
    "resolve",
]

APP_NAME = "reform-sim"  # the platform user data folder's name
DATA_VARIABLE = "REFORM_SIM_DATA"  # environment variable naming the cache folder
DATASETS_VARIABLE = "REFORM_SIM_DATASETS"  # environment variable naming the real datasets' folder
DEFAULT_DATASETS = "../shared/datasets"  # the real datasets beside a clone
DEFAULT_MIRROR = "https://raw.githubusercontent.com"  # files at <mirror>/<repo>/<commit>/<path>
MANIFEST = ".reform-sim-fetched.json"  # written last, in a dataset's folder: the fetch is complete
MANIFEST_VERSION = 1
DOWNLOAD_TIMEOUT_S = 60.0  # seconds without an answer before a download fails
MIN_DOWNLOAD_RATE = 10_000  # bytes/s: a file must arrive within DOWNLOAD_TIMEOUT_S + bytes / this
REGISTRY_FILE = "public-datasets.json"

# A file:// URL's path as a local path (urllib.request's url2pathname, without importing
# urllib.request and http.client).
if os.name == "nt":  # pragma: no cover - exercised on Windows only
    from nturl2path import url2pathname
else:
    url2pathname = unquote

_SHA256 = re.compile(r"[0-9a-f]{64}")
_COMMIT = re.compile(r"[0-9a-f]{40}")
_NAME = re.compile(r"[a-z0-9][a-z0-9-]*")
_REPO = re.compile(r"[A-Za-z0-9_.-]+/[A-Za-z0-9_.-]+")

# Files whose sha256 this process has verified: (path, sha256) -> the file's stat signature then.
# A file whose signature has not changed since is only checked for its size.
_VERIFIED: dict[tuple[str, str], tuple[int, int, int, int]] = {}


class FetchError(DataFormatError):
    """A dataset file that could not be fetched or did not verify, in one line, e.g.::

        data/octave/Synth/features.mat: dataset 'synth' from https://raw.github…/features.mat:
        expected sha256 31a0…, found sha256 9c4e…

    Attributes:
        dataset: the dataset's registry name.
        file: the file's path in its repository.
        url: where it was fetched from.
        expected, found: what the file should have been, and what came.
    """

    def __init__(
        self,
        dataset: str,
        file: str,
        url: str,
        expected: str,
        found: str,
        hint: str | None = None,
    ) -> None:
        self.dataset = dataset
        self.file = file
        self.url = url
        super().__init__(file, f"dataset {dataset!r} from {url}", None, expected, found, hint=hint)

    def __reduce__(self) -> tuple:
        fields = (self.dataset, self.file, self.url, self.expected, self.found, self.hint)
        return type(self), fields


class _Invalid(ValueError):
    """A registry value that is not what it should be (made a `DataFormatError` naming the
    registry file by :func:`registry`)."""

    def __init__(self, field: str, expected: str, found: str) -> None:
        self.field = field
        self.expected = expected
        self.found = found
        super().__init__(f"{field}: expected {expected}, found {found}")


def _require(condition: bool, field: str, expected: str, found: Any) -> None:
    if not condition:
        raise _Invalid(field, expected, repr(found))


def _text(value: Any, field: str) -> None:
    _require(isinstance(value, str) and bool(value.strip()), field, "a non-empty string", value)


@dataclasses.dataclass(frozen=True)
class DatasetFile:
    """One file of a public dataset, pinned.

    Attributes:
        path: the file's path in the repository (POSIX, relative).
        commit: the commit it is taken at (40 hex digits).
        bytes: its size, in bytes (> 0).
        sha256: its SHA-256, 64 lowercase hex digits.
    """

    path: str
    commit: str
    bytes: int
    sha256: str

    def __post_init__(self) -> None:
        _text(self.path, "path")
        parts = PurePosixPath(self.path).parts
        _require(
            not self.path.startswith("/")
            and "\\" not in self.path
            and all(part not in ("", ".", "..") for part in parts)
            and "/".join(parts) == self.path,
            "path",
            "a relative POSIX path without '.', '..' or empty parts",
            self.path,
        )
        _require(
            isinstance(self.commit, str) and _COMMIT.fullmatch(self.commit) is not None,
            "commit",
            "40 lowercase hex digits",
            self.commit,
        )
        _require(type(self.bytes) is int and self.bytes > 0, "bytes", "an integer > 0", self.bytes)
        _require(
            isinstance(self.sha256, str) and _SHA256.fullmatch(self.sha256) is not None,
            "sha256",
            "64 lowercase hex digits",
            self.sha256,
        )


@dataclasses.dataclass(frozen=True)
class PublicDataset:
    """A public F-formation dataset, as the registry pins it.

    Attributes:
        name: the name it is fetched by (``coffeebreak``): lowercase letters, digits, dashes.
        title: a human title.
        format: the registry's name for its file format (``gcff-mat``, ``dante-txt``,
            ``babble-csv``).
        units: the length unit of its positions (``cm``, ``m``).
        repo: the GitHub repository holding it, ``owner/name``.
        citation: the paper to cite.
        notes: what to know about it.
        licence: the licence note, when the registry gives one (a ``licence`` entry, else the
            clause of ``notes`` that mentions a licence), else None.
        files: its files, in the registry's order.
        recording: the name of the entry holding the same recording packaged otherwise (the
            Cocktail Party in DANTE's text files is ``cocktail-party`` recorded once), or None
            when this entry is a recording of its own. A mean over datasets counts a recording
            once (:func:`one_per_recording`).
    """

    name: str
    title: str
    format: str
    units: str
    repo: str
    citation: str
    notes: str
    licence: str | None
    files: tuple[DatasetFile, ...]
    recording: str | None = None

    def __post_init__(self) -> None:
        _require(
            isinstance(self.name, str) and _NAME.fullmatch(self.name) is not None,
            "name",
            "lowercase letters, digits and dashes",
            self.name,
        )
        for field in ("title", "format", "units", "citation"):
            _text(getattr(self, field), field)
        _require(isinstance(self.notes, str), "notes", "a string", self.notes)
        _require(
            self.licence is None or (isinstance(self.licence, str) and bool(self.licence)),
            "licence",
            "a non-empty string or None",
            self.licence,
        )
        _require(
            isinstance(self.repo, str) and _REPO.fullmatch(self.repo) is not None,
            "repo",
            "a GitHub repository, owner/name",
            self.repo,
        )
        _require(
            isinstance(self.files, tuple)
            and bool(self.files)
            and all(isinstance(f, DatasetFile) for f in self.files),
            "files",
            "a non-empty tuple of DatasetFile",
            self.files,
        )
        paths = [f.path for f in self.files]
        duplicates = sorted({p for p in paths if paths.count(p) > 1})
        _require(not duplicates, "files", "each path once", duplicates)
        _require(MANIFEST not in self.local_names, "files", f"no file named {MANIFEST}", paths)
        _require(
            self.recording is None
            or (isinstance(self.recording, str) and _NAME.fullmatch(self.recording) is not None),
            "recording",
            "the name of another dataset of the registry, or absent",
            self.recording,
        )
        _require(self.recording != self.name, "recording", "another dataset's name", self.name)

    @property
    def bytes(self) -> int:
        """The size of all its files, in bytes."""
        return sum(f.bytes for f in self.files)

    @property
    def local_names(self) -> tuple[str, ...]:
        """Each file's path inside the dataset's local folder: its repository path less the
        folders every file of the dataset shares (one per file, in order)."""
        parents = [PurePosixPath(f.path).parent for f in self.files]
        common = PurePosixPath(posixpath.commonpath([p.as_posix() for p in parents]))
        if common == PurePosixPath("."):
            return tuple(f.path for f in self.files)
        return tuple(PurePosixPath(f.path).relative_to(common).as_posix() for f in self.files)


def _licence_note(entry: dict[str, Any]) -> str | None:
    if "licence" in entry:
        return entry["licence"]
    notes = entry.get("notes")
    if not isinstance(notes, str):
        return None
    clauses = [c.strip() for c in notes.split(";") if re.search(r"licen[cs]e", c, re.IGNORECASE)]
    return "; ".join(clauses) or None


def _parse_entry(entry: Any) -> PublicDataset:
    _require(isinstance(entry, dict), "entry", "a JSON object", type(entry).__name__)
    for key in ("name", "title", "format", "units", "repo", "files", "citation"):
        _require(key in entry, key, "the key to be present", None)
    files = entry["files"]
    _require(isinstance(files, list) and bool(files), "files", "a non-empty list", files)
    parsed = []
    for k, item in enumerate(files):
        _require(isinstance(item, dict), f"files[{k}]", "a JSON object", item)
        commit = item.get("commit", entry.get("commit"))
        _require(commit is not None, f"files[{k}].commit", "a commit (or the dataset's)", None)
        for key in ("path", "bytes", "sha256"):
            _require(key in item, f"files[{k}].{key}", "the key to be present", None)
        try:
            parsed.append(DatasetFile(item["path"], commit, item["bytes"], item["sha256"]))
        except _Invalid as exc:
            raise _Invalid(f"files[{k}].{exc.field}", exc.expected, exc.found) from None
    return PublicDataset(
        name=entry["name"],
        title=entry["title"],
        format=entry["format"],
        units=entry["units"],
        repo=entry["repo"],
        citation=entry["citation"],
        notes=entry.get("notes", ""),
        licence=_licence_note(entry),
        files=tuple(parsed),
        recording=entry.get("recording"),
    )


def _packaged_registry() -> Path:
    return Path(str(resources.files("reform.datasets").joinpath(REGISTRY_FILE)))


def registry(path: str | PathLike[str] | None = None) -> tuple[PublicDataset, ...]:
    """The public datasets, from the packaged registry or another registry file.

    Args:
        path: a registry JSON file laid out as the packaged one (``{"datasets": [...]}``);
            None for the one shipped with the package.

    Returns:
        One `PublicDataset` per entry, in the file's order.

    Raises:
        DataFormatError: the file cannot be read, is not JSON, or an entry is malformed (the
            message names the file, the entry and the field).
    """
    return _read_registry(path)


def _read_registry(path: str | PathLike[str] | None) -> tuple[PublicDataset, ...]:
    """:func:`registry`, under a name the functions taking a ``registry=`` argument can call."""
    source = (
        _packaged_registry()
        if path is None
        else path_argument(path, name="registry", function="registry")
    )
    kind = file_kind(source)
    if kind != "a file":
        raise DataFormatError(source, None, None, "a registry file (JSON)", kind)
    try:
        text = source.read_text(encoding="utf-8")
    except OSError as exc:
        raise DataFormatError(
            source, None, None, "a readable registry file", exc.strerror or str(exc)
        ) from None
    try:
        document = parse_json(text)
    except JsonError as exc:
        raise DataFormatError(source, None, None, "a registry file (JSON)", str(exc)) from None
    if not isinstance(document, dict) or not isinstance(document.get("datasets"), list):
        raise DataFormatError(
            source, None, "datasets", "an object with a list of datasets", _kind(document)
        )
    entries: list[PublicDataset] = []
    for k, entry in enumerate(document["datasets"]):
        label = entry.get("name") if isinstance(entry, dict) else None
        where = f"dataset {k}" + (f" ({label!r})" if isinstance(label, str) else "")
        try:
            entries.append(_parse_entry(entry))
        except _Invalid as exc:
            raise DataFormatError(source, where, exc.field, exc.expected, exc.found) from None
    names = [e.name for e in entries]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise DataFormatError(source, None, "name", "each dataset name once", ", ".join(twice))
    own = {e.name for e in entries if e.recording is None}
    for k, entry in enumerate(entries):
        if entry.recording is not None and entry.recording not in own:
            raise DataFormatError(
                source,
                f"dataset {k} ({entry.name!r})",
                "recording",
                f"the name of a dataset of the registry that is a recording of its own "
                f"({', '.join(sorted(own))})",
                repr(entry.recording),
            )
    return tuple(entries)


def one_per_recording(
    names: Sequence[str], registry_path: str | PathLike[str] | None = None
) -> tuple[list[str], dict[str, str]]:
    """``names`` with each recording once: a dataset the registry marks as another packaging of
    a recording (:attr:`PublicDataset.recording`) is left out when that recording is among
    ``names`` too.

    Returns:
        The names kept, in order, and each name left out -> the name it repeats.
    """
    same = {e.name: e.recording for e in _read_registry(registry_path) if e.recording}
    present = set(names)
    kept = [n for n in names if same.get(n) not in present]
    return kept, {n: same[n] for n in names if same.get(n) in present}


def _kind(value: Any) -> str:
    if isinstance(value, dict):
        return "an object without a 'datasets' list"
    return f"a JSON {type(value).__name__}"


def _find(name: str, registry_path: str | PathLike[str] | None) -> PublicDataset:
    entries = _read_registry(registry_path)
    for entry in entries:
        if entry.name == name:
            return entry
    known = ", ".join(e.name for e in entries)
    raise ValueError(f"unknown dataset {name!r}; the public datasets are: {known}")


def cache_dir() -> Path:
    """The folder fetched datasets are kept in: ``$REFORM_SIM_DATA`` when set, else the
    platform's user data folder for ``reform-sim`` (``~/.local/share/reform-sim`` on Linux)."""
    named = os.environ.get(DATA_VARIABLE)
    if named:
        return Path(named)
    try:
        import platformdirs
    except ImportError as exc:  # pragma: no cover - platformdirs is a dependency of the project
        raise ImportError("the dataset cache needs platformdirs: pip install platformdirs") from exc
    return Path(platformdirs.user_data_dir(APP_NAME, appauthor=False))


def local_datasets_dir() -> Path | None:
    """The real datasets' folder when none is given: ``$REFORM_SIM_DATASETS`` when set, else
    ``../shared/datasets`` (from the working folder) when that folder exists, else None."""
    named = os.environ.get(DATASETS_VARIABLE)
    if named:
        return Path(named)
    return Path(DEFAULT_DATASETS) if Path(DEFAULT_DATASETS).is_dir() else None


def _folder(dataset: PublicDataset, cache: str | PathLike[str] | None) -> Path:
    return (cache_dir() if cache is None else Path(cache)) / dataset.name


def _manifest(dataset: PublicDataset) -> dict[str, Any]:
    """What the manifest of a complete copy of ``dataset`` holds (its source aside)."""
    return {
        "format_version": MANIFEST_VERSION,
        "name": dataset.name,
        "repo": dataset.repo,
        "files": [
            {
                "name": local,
                "path": f.path,
                "commit": f.commit,
                "bytes": f.bytes,
                "sha256": f.sha256,
            }
            for local, f in zip(dataset.local_names, dataset.files, strict=True)
        ],
    }


def _signature(stat: os.stat_result) -> tuple[int, int, int, int]:
    return (stat.st_size, stat.st_mtime_ns, stat.st_ctime_ns, stat.st_ino)


def _sha256(path: Path) -> str:
    with open(path, "rb") as handle:
        return hashlib.file_digest(handle, "sha256").hexdigest()


def _verified(path: Path, file: DatasetFile) -> bool:
    """Whether ``path`` holds ``file``: its size always, its sha256 the first time this
    process looks at it (and whenever it has changed since)."""
    try:
        stat = path.stat()
    except OSError:
        return False
    if not path.is_file() or stat.st_size != file.bytes:
        return False
    key = (str(path.resolve()), file.sha256)
    if _VERIFIED.get(key) == _signature(stat):
        return True
    try:
        if _sha256(path) != file.sha256:
            return False
    except OSError:
        return False
    _VERIFIED[key] = _signature(stat)
    return True


def _complete(dataset: PublicDataset, folder: Path) -> bool:
    """Whether ``folder`` holds a complete, verified copy of ``dataset``."""
    try:
        manifest = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return False
    if not isinstance(manifest, dict):
        return False
    expected = _manifest(dataset)
    if any(manifest.get(key) != value for key, value in expected.items()):
        return False
    return all(
        _verified(folder / local, f)
        for local, f in zip(dataset.local_names, dataset.files, strict=True)
    )


def _damaged(dataset: PublicDataset, folder: Path) -> str | None:
    """What differs in a copy of ``dataset`` fetched into ``folder`` whole (its manifest is
    there) and changed since: the first file missing or not as fetched; None otherwise."""
    if not (folder / MANIFEST).is_file():
        return None
    for local, file in zip(dataset.local_names, dataset.files, strict=True):
        path = folder / local
        if not path.is_file():
            return f"{path}: expected the fetched file ({file.bytes:,} bytes), found none"
        size = path.stat().st_size
        if size != file.bytes:
            return f"{path}: expected {file.bytes:,} bytes as fetched, found {size:,}"
        if not _verified(path, file):
            return f"{path}: expected sha256 {file.sha256} as fetched, found another"
    return None


def is_fetched(
    name: str,
    cache: str | PathLike[str] | None = None,
    *,
    registry: str | PathLike[str] | None = None,
) -> bool:
    """Whether the public dataset ``name`` is complete and verified in the cache.

    Args:
        name: a registry name (``reform-sim datasets list``).
        cache: the cache folder; None for :func:`cache_dir`.
        registry: another registry file; None for the packaged one.

    Raises:
        ValueError: ``name`` is not in the registry (the message lists the names).
    """
    dataset = _find(name, registry)
    return _complete(dataset, _folder(dataset, cache))


def _mirror_base(mirror: str | PathLike[str] | None) -> str:
    """The URL the ``<repo>/<commit>/<path>`` of each file is appended to."""
    if mirror is None:
        return DEFAULT_MIRROR
    text = os.fspath(mirror)
    scheme = urlsplit(text).scheme.lower()
    if scheme in ("http", "https", "file"):
        return text.rstrip("/")
    if len(scheme) > 1:  # a drive letter ("C:\\mirror") is a path, not a scheme
        raise ValueError(
            f"mirror: expected an http://, https:// or file:// URL or a folder, got {text!r}"
        )
    folder = Path(text)
    if not folder.is_dir():
        found = "a file" if folder.exists() else "no such folder"
        raise ValueError(f"mirror: expected a folder, got {text!r} ({found})")
    return folder.resolve().as_uri()


def _chain(exc: BaseException) -> Iterator[BaseException]:
    """``exc`` and the errors it wraps: requests and urllib3 keep them in ``args`` and
    ``reason`` as well as in ``__cause__`` and ``__context__``."""
    seen: set[int] = set()
    queue: list[Any] = [exc]
    while queue:
        error = queue.pop(0)
        if not isinstance(error, BaseException) or id(error) in seen:
            continue
        seen.add(id(error))
        yield error
        queue.extend([*error.args, getattr(error, "reason", None)])
        queue.extend([error.__cause__, error.__context__])


def _reason(exc: BaseException) -> str:
    """The operating system's words for a network failure (``Connection refused``), found in
    the errors ``exc`` wraps; else its first line."""
    for error in _chain(exc):
        if isinstance(error, OSError) and error.strerror:
            return error.strerror
        if isinstance(error, TimeoutError):
            return "timed out"
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _bytes_read(exc: BaseException) -> int | None:
    """How many bytes of the body came before the connection closed, when ``exc`` wraps an
    ``http.client.IncompleteRead`` (urllib3's holds a count, the standard library's the bytes)."""
    for error in _chain(exc):
        partial = getattr(error, "partial", None)
        if partial is not None and hasattr(error, "expected"):
            return partial if isinstance(partial, int) else len(partial)
    return None


class _Problem(Exception):
    """Why one download failed: what was expected and what was found."""

    def __init__(self, expected: str, found: str, hint: str | None = None) -> None:
        self.expected = expected
        self.found = found
        self.hint = hint
        super().__init__(f"expected {expected}, found {found}")


def _copy_file(url: str, output_file: str, pooch: Any) -> None:
    """A pooch downloader for ``file://`` mirrors: copies the file the URL names."""
    del pooch
    source = Path(url2pathname(urlsplit(url).path))
    if not source.is_file():
        found = "a folder" if source.is_dir() else "no such file"
        raise _Problem("a file at that path", found)
    try:
        shutil.copyfile(source, output_file)
    except OSError as exc:
        raise _Problem("a readable file", exc.strerror or str(exc)) from None


class _SizeCap:
    """What pooch takes for a progress bar, which stops a download once it is larger than the
    registry's size for the file (`TooLarge`): a mirror that never stops sending must not fill
    the disk. Passes the progress on to ``bar`` (a tqdm bar), if any."""

    def __init__(self, file: DatasetFile, bar: Any = None) -> None:
        self.file = file
        self.bar = bar
        self.path: str | None = None  # the file being written (set by `_checked`)

    @property
    def total(self) -> int:
        return self.file.bytes

    @total.setter
    def total(self, announced: int) -> None:  # the server's Content-Length
        if announced > self.file.bytes:
            raise _Problem(
                f"{self.file.bytes} bytes",
                f"{announced} bytes announced by the server: too large, not the file the "
                "registry names (nothing kept)",
            )

    def update(self, n: int) -> None:
        if self.path is not None and os.path.getsize(self.path) > self.file.bytes:
            raise _Problem(
                f"{self.file.bytes} bytes",
                f"more than {self.file.bytes} bytes, cut off there: too large, the download did "
                "not end at the registry's size (nothing kept)",
            )
        if self.bar is not None:
            self.bar.update(n)

    def reset(self) -> None:
        if self.bar is not None:
            self.bar.reset()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _checked(
    downloader: Callable[..., Any], file: DatasetFile, cap: _SizeCap | None = None
) -> Callable[..., None]:
    """``downloader``, its failures made `_Problem`s and its output's size checked, so that a
    truncated file is named as one before pooch checks the sha256 (``cap``: told the file
    being written, to cut it at the registry's size)."""

    def download(url: str, output_file: str, pooch: Any) -> None:
        if cap is not None:
            cap.path = str(output_file)
        try:
            downloader(url, output_file, pooch)
        except OSError as exc:  # requests' errors are OSErrors
            response = getattr(exc, "response", None)
            if response is not None:
                raise _Problem(
                    "HTTP 200 with the file", f"HTTP {response.status_code} {response.reason}"
                ) from None
            written = _bytes_read(exc)
            if written is None and os.path.exists(output_file):
                written = os.path.getsize(output_file) or None
            if written is not None:
                raise _Problem(
                    f"{file.bytes} bytes", f"{written} bytes, then the download broke off"
                ) from None
            host = urlsplit(url).netloc or url
            raise _Problem(
                f"an answer from {host}",
                _reason(exc),
                hint="no network here? fetch from a copy with --mirror URL (http://, file:// or "
                "a folder laid out as <mirror>/<repo>/<commit>/<path>)",
            ) from None
        size = os.path.getsize(output_file)
        if size != file.bytes:
            raise _Problem(f"{file.bytes} bytes", f"{size} bytes")

    return download


def download_deadline(size: int) -> float:
    """Seconds a file of ``size`` bytes may take to arrive whole: `DOWNLOAD_TIMEOUT_S` plus its
    size at `MIN_DOWNLOAD_RATE`. A mirror that trickles (a byte every few seconds, each in time
    for the read timeout) is cut off then, instead of holding the fetch for ever."""
    return DOWNLOAD_TIMEOUT_S + size / MIN_DOWNLOAD_RATE


class _Deadline:
    """Shuts a download's connection once ``seconds`` have passed: the read that waits on it
    fails at once. Its `capture` is a requests response hook (it learns the connection)."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self.expired = False
        self._response: Any = None
        self._timer = threading.Timer(seconds, self._expire)
        self._timer.daemon = True

    def capture(self, response: Any, *args: Any, **kwargs: Any) -> Any:
        self._response = response
        return response

    def _expire(self) -> None:
        self.expired = True
        response = self._response
        if response is None:  # no answer yet: the read timeout ends the wait
            return
        try:
            response.raw._fp.fp.raw._sock.shutdown(socket.SHUT_RDWR)
        except (AttributeError, OSError):
            with contextlib.suppress(Exception):
                response.raw.close()

    def __enter__(self) -> _Deadline:
        self._timer.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._timer.cancel()


@contextlib.contextmanager
def _quiet(pooch: Any) -> Iterator[None]:
    """pooch logs every download to stderr at level INFO: only its warnings, here."""
    logger = pooch.get_logger()
    level = logger.level
    logger.setLevel("WARNING")
    try:
        yield
    finally:
        logger.setLevel(level)


def _pooch() -> Any:
    try:
        import pooch
    except ImportError as exc:  # pragma: no cover - pooch is a dependency of the project
        raise ImportError("fetching datasets needs pooch: pip install pooch") from exc
    return pooch


def _download(
    dataset: PublicDataset,
    file: DatasetFile,
    url: str,
    target: Path,
    *,
    label: str,
    progress: bool,
) -> None:
    """Downloads ``url`` to ``target`` through pooch (a temporary file, moved into place once
    its size and sha256 match), or raises `FetchError`. ``label`` names the progress bar."""
    pooch = _pooch()
    bar = None
    cap = None
    deadline = _Deadline(download_deadline(file.bytes))
    if urlsplit(url).scheme == "file":
        inner: Callable[..., Any] = _copy_file
    else:
        if progress:
            from tqdm import tqdm

            # A finished or failed bar is cleared (leave=False): the caller reports the outcome.
            bar = tqdm(
                desc=label,
                total=file.bytes,  # pooch sets the server's length; a bar needs one to be true
                unit="B",
                unit_scale=True,
                file=sys.stderr,
                leave=False,
            )
        cap = _SizeCap(file, bar)
        inner = pooch.HTTPDownloader(
            progressbar=cap,
            timeout=DOWNLOAD_TIMEOUT_S,
            hooks={"response": deadline.capture},
        )
    try:
        # pooch's temporary file goes in a folder of ours, named for this process: one that a
        # killed or hung fetch leaves is removed by the next fetch into that folder.
        with _quiet(pooch), deadline, temporary_folder(target) as scratch:
            pooch.retrieve(
                url,
                known_hash=f"sha256:{file.sha256}",
                fname=target.name,
                path=scratch,
                downloader=_checked(inner, file, cap),
            )
            os.replace(scratch / target.name, target)
    except _Problem as exc:
        if deadline.expired:
            raise FetchError(
                dataset.name,
                file.path,
                url,
                f"{file.bytes} bytes within {deadline.seconds:g} s",
                f"{exc.found.split(', then')[0]} when cut off: too slow a mirror (try another "
                "--mirror)",
            ) from None
        raise FetchError(
            dataset.name, file.path, url, exc.expected, exc.found, hint=exc.hint
        ) from None
    except ValueError as exc:  # pooch: the sha256 does not match
        got = re.search(r"got ([0-9a-fA-F]{64})", str(exc))
        found = f"sha256 {got.group(1).lower()}" if got else str(exc)
        raise FetchError(dataset.name, file.path, url, f"sha256 {file.sha256}", found) from None
    finally:
        if bar is not None:
            bar.close()
    # pooch's temporary file is owner-only: give the file the permissions of a plain open().
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(target, 0o666 & ~umask)
    _VERIFIED[(str(target.resolve()), file.sha256)] = _signature(target.stat())


def fetch(
    name: str,
    *,
    mirror: str | PathLike[str] | None = None,
    cache: str | PathLike[str] | None = None,
    progress: bool = False,
    registry: str | PathLike[str] | None = None,
) -> Path:
    """Downloads the public dataset ``name`` into the cache, verified, and returns its folder.

    Every file is taken at the commit the registry pins, checked for its size and sha256, and
    kept; a dataset already complete and verified in the cache is not downloaded again. The
    folder returned loads with `reform.datasets.load_dataset`.

    Args:
        name: a registry name (``reform-sim datasets list``), e.g. ``"coffeebreak"``.
        mirror: where to download from instead of GitHub: an ``http://``, ``https://`` or
            ``file://`` URL, or a folder, laid out as ``<mirror>/<repo>/<commit>/<path>``.
        cache: the cache folder; None for :func:`cache_dir`.
        progress: show a progress bar per downloaded file on stderr.
        registry: another registry file; None for the packaged one.

    Returns:
        The dataset's folder, ``<cache>/<name>``.

    Raises:
        ValueError: ``name`` is not in the registry (the message lists the names), or
            ``mirror`` is neither a URL of those kinds nor a folder.
        FetchError: a file could not be downloaded (HTTP error, unreachable host, missing from
            the mirror) or does not match its size or sha256. Files verified before it stay;
            the dataset is not marked complete.
        OutputPathError: the cache folder cannot be written.
    """
    dataset = _find(name, registry)
    base = _mirror_base(mirror)
    folder = _folder(dataset, cache)
    if _complete(dataset, folder):
        return folder
    check_folder_path(folder)
    # From here on the folder changes: no manifest may vouch for it until every file verifies.
    (folder / MANIFEST).unlink(missing_ok=True)
    try:
        for local, file in zip(dataset.local_names, dataset.files, strict=True):
            target = folder / local
            if _verified(target, file):
                continue
            if target.is_file() or target.is_symlink():
                target.unlink()  # a damaged or stale copy: never left under its final name
            url = f"{base}/{dataset.repo}/{file.commit}/{quote(file.path)}"
            _download(
                dataset, file, url, target, label=f"{dataset.name} {local}", progress=progress
            )
    except BaseException:
        _remove_empty_folders(folder)  # what verified stays; no empty shell of the dataset
        raise
    document = {**_manifest(dataset), "source": base}
    with atomic_open(folder / MANIFEST, "w", encoding="utf-8") as handle:
        json.dump(document, handle, indent=1)
        handle.write("\n")
    return folder


def _remove_empty_folders(folder: Path) -> None:
    """Removes ``folder`` and the folders below it that hold nothing, deepest first."""
    if not folder.is_dir():
        return
    below = sorted((p for p in folder.rglob("*") if p.is_dir()), key=lambda p: -len(p.parts))
    for path in [*below, folder]:
        with contextlib.suppress(OSError):  # not empty (or not ours to remove): kept
            path.rmdir()


def resolve(
    name_or_path: str | PathLike[str],
    *,
    cache: str | PathLike[str] | None = None,
    registry: str | PathLike[str] | None = None,
) -> Path:
    """The dataset path a user means by ``name_or_path``.

    In order: a store's URI (``s3://bucket/prefix``), as given; an existing file or folder, as
    given; the cached folder of a fetched public
    dataset of that name; a folder of that name among the real datasets
    (:func:`local_datasets_dir`).

    Args:
        name_or_path: a path, or a dataset name (``salsa``).
        cache: the cache folder; None for :func:`cache_dir`.
        registry: another registry file; None for the packaged one.

    Raises:
        FileNotFoundError: a public dataset that is neither fetched nor in the real datasets'
            folder (the message says the three ways to give it: its folder's path,
            ``$REFORM_SIM_DATASETS``, or fetching it), or neither a path nor a dataset name (the
            message lists the names).
    """
    from reform.datasets.store import is_uri

    if is_uri(name_or_path):  # a store's URI, as given (a Path would fold its "//")
        return name_or_path  # type: ignore[return-value]
    path = path_argument(name_or_path, name="name_or_path", function="resolve")
    if path.exists():
        return path
    text = os.fspath(name_or_path)
    entries = {e.name: e for e in _read_registry(registry)}
    dataset = entries.get(text)
    if dataset is not None and _complete(dataset, _folder(dataset, cache)):
        return _folder(dataset, cache)
    local = local_datasets_dir()
    if local is not None and text and path.name == text and (local / text).is_dir():
        return local / text
    if dataset is not None:
        damage = _damaged(dataset, _folder(dataset, cache))
        if damage is not None:
            raise FileNotFoundError(
                f"dataset {text!r} in the cache has changed since it was fetched: {damage}; "
                f"fetch it again: `reform-sim datasets fetch {text}`"
            )
        where = cache_dir() if cache is None else Path(cache)
        looked = f"{DATASETS_VARIABLE} is not set" if local is None else f"no {text}/ in {local}"
        raise FileNotFoundError(
            f"dataset {text!r} is not fetched (cache {where}) and {looked}; give the path of "
            f"the folder that holds it, or set {DATASETS_VARIABLE} to the folder holding "
            f"{text}/, or fetch it once online: `reform-sim datasets fetch {text}` "
            "(--mirror URL fetches from a copy)"
        )
    if path.is_symlink():  # a link that leads nowhere: said, not taken for a name
        from reform.atomic import file_kind

        raise FileNotFoundError(
            f"{text}: expected a dataset file or folder, found {file_kind(path)}"
        )
    raise FileNotFoundError(
        f"{text}: no such file or folder, nor a dataset name; the public datasets are: "
        + ", ".join(entries)
    )
