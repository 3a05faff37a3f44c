"""Atomic file writes: a temporary file beside the target, then a rename.

A reader never sees a half-written file, and an interrupted write leaves the old file (or none).
A target that cannot be written (an existing folder, a path under a file, a folder that cannot be
created) raises `OutputPathError` naming the path before anything is written;
:func:`check_file_path` and :func:`check_folder_path` say so up front, before a long run.

A process killed while it writes leaves its temporary file behind (a killed ``simulate --save``
leaves tens of megabytes). Temporary names carry their writer's process id and machine,
``.NAME.PID@HOST.RANDOM.tmp`` (HOST: six hex digits of a hash of the host name and the process-id
namespace), and the first write of a process into a folder removes the temporaries of that naming
whose writer, on this machine, is no longer alive (:func:`remove_stale_temporaries`); nothing else
is ever removed: not another machine's or container's, not a live process's, not a file named
otherwise.

A write that fills the disk (no space left on the device, or the user's quota spent) raises
`DiskFull`, an OSError naming the path, the bytes written before it stopped, the space left
there and, where the writer says, the space needed; its temporary file is removed.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import os
import re
import shutil
import socket
import stat
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO

__all__ = [
    "DiskFull",
    "OutputPathError",
    "atomic_open",
    "atomic_path",
    "check_file_path",
    "check_folder_path",
    "Temporary",
    "file_kind",
    "find_temporaries",
    "is_disk_full",
    "remove_stale_temporaries",
    "temporary_folder",
]

_DEFAULT_FILE_MODE = 0o666
# A temporary of this module's: ".NAME.PID@HOST.RANDOM.tmp" (RANDOM: tempfile's 8 characters).
_TEMPORARY = re.compile(r"\..+\.(?P<pid>[0-9]+)@(?P<host>[0-9a-f]{6})\.[a-z0-9_]{8}\.tmp")
_cleaned: set[str] = set()  # folders this process has cleaned of stale temporaries


def _host() -> str:
    """Where process ids mean the same as this process's: six hex digits of a hash of the host
    name and, on Linux, of the process-id namespace (two containers sharing a folder on one
    machine number their processes apart)."""
    try:
        namespace = os.stat("/proc/self/ns/pid").st_ino
    except OSError:
        namespace = 0
    return hashlib.sha256(f"{socket.gethostname()}:{namespace}".encode()).hexdigest()[:6]


def _temporary_prefix(target: Path) -> str:
    return f".{target.name}.{os.getpid()}@{_host()}."


def _alive(pid: int) -> bool:
    """Whether process ``pid`` of this machine may be alive (when unsure: yes)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (OSError, OverflowError):  # another user's (EPERM), or no such id at all
        return True
    return True


@dataclass(frozen=True)
class Temporary:
    """A temporary file or folder of this module's naming found in a folder.

    Attributes:
        path: where it is.
        pid: its writer's process id.
        state: ``"stale"`` (its writer, of this machine, is gone: a killed run's), ``"live"``
            (its writer may still be writing it) or ``"elsewhere"`` (written on another machine
            or container, whose processes cannot be asked).
    """

    path: Path
    pid: int
    state: str


def find_temporaries(folder: str | os.PathLike[str]) -> list[Temporary]:
    """The temporaries of this module's naming in ``folder`` (not its subfolders), each with
    whether its writer is gone; nothing is removed. Empty where processes cannot be asked
    whether they live without signalling them (not POSIX)."""
    if os.name != "posix":
        return []
    try:
        names = sorted(os.listdir(folder))
    except OSError:
        return []
    host, found = _host(), []
    for name in names:
        match = _TEMPORARY.fullmatch(name)
        if match is None:
            continue
        pid = int(match["pid"])
        if match["host"] != host:
            state = "elsewhere"
        elif pid <= 0 or _alive(pid):
            state = "live"
        else:
            state = "stale"
        found.append(Temporary(Path(folder, name), pid, state))
    return found


def remove_stale_temporaries(folder: str | os.PathLike[str]) -> list[Path]:
    """Removes the temporaries of killed writers from ``folder`` (not its subfolders).

    A temporary file or folder is removed when it is named as this module names them
    (``.NAME.PID@HOST.RANDOM.tmp``), was made where process ids mean what they mean here (this
    machine, this container), and its writer's process is gone.
    Anything else is left alone. A no-op where processes cannot be asked whether they live
    without signalling them (not POSIX).

    Returns:
        The paths removed.
    """
    removed = []
    for temporary in find_temporaries(folder):
        if temporary.state != "stale":
            continue
        path = temporary.path
        try:
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path)
            else:
                path.unlink()
        except FileNotFoundError:  # removed meanwhile, by another process cleaning up
            continue
        except OSError:
            continue  # left for a later run: a clean-up never fails a write
        removed.append(path)
    return removed


def _clean_once(folder: Path) -> None:
    """:func:`remove_stale_temporaries` on ``folder``, the first time this process writes there."""
    key = os.path.abspath(folder)
    if key not in _cleaned:
        _cleaned.add(key)
        remove_stale_temporaries(folder)


@contextlib.contextmanager
def temporary_folder(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yields a new hidden folder beside ``path``, named as this module names temporaries (so
    that a killed writer's is removed by a later write there), and removes it at the end.

    For writers that make files of their own names: write there, then `os.replace` the result
    onto ``path``. Missing folders are created.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    _clean_once(target.parent)
    scratch = Path(
        tempfile.mkdtemp(prefix=_temporary_prefix(target), suffix=".tmp", dir=target.parent)
    )
    try:
        yield scratch
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


class OutputPathError(ValueError):
    """An output path that cannot be written, e.g.::

        out/report.json: expected a file path, found an existing folder
        notes.txt/out.json: expected a folder at notes.txt, found a file

    Attributes:
        path: the output path.
        problem: what is wrong with it (the message after ``path: ``).
    """

    def __init__(self, path: str | os.PathLike[str], problem: str) -> None:
        self.path = Path(path)
        self.problem = problem
        super().__init__(f"{os.fspath(path)}: {problem}")


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _nearest_existing(path: Path, target: str | os.PathLike[str]) -> Path:
    """The nearest ancestor of ``path`` (itself included) that exists; it must be a folder."""
    for folder in (path, *path.parents):
        if folder.is_dir():
            return folder
        if folder.is_symlink() and not folder.exists():
            found = f"a link to nothing ({folder.readlink()})"
            raise OutputPathError(target, f"expected a folder at {folder}, found {found}")
        if folder.exists():
            if folder.is_dir():  # made meanwhile, by another process writing beside us
                return folder
            raise OutputPathError(target, f"expected a folder at {folder}, found a file")
    return Path(".")  # pragma: no cover - a relative path's parents end at "."


def _check_writable(folder: Path, existing: Path, target: str | os.PathLike[str]) -> None:
    """Creates and removes a temporary file in ``existing``, the nearest existing ancestor of
    ``folder``: the one way to know that a write there will succeed (root passes ``os.access``
    on read-only and virtual file systems)."""
    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as exc:
        if folder == existing:
            problem = f"cannot write in folder {folder} ({exc.strerror or exc})"
        else:
            problem = (
                f"folder {folder} cannot be created: cannot write in {existing} "
                f"({exc.strerror or exc})"
            )
        raise OutputPathError(target, problem) from exc


def file_kind(path: Path) -> str:
    """What is at ``path``, for a message: ``"no such file"``, ``"a folder"``, ``"a FIFO (named
    pipe)"``, ``"a socket"``, ``"a character device"``, ``"a symbolic link loop"``, ..."""
    try:
        mode = path.stat().st_mode
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "a symbolic link loop"
        if exc.errno in (errno.ENOENT, errno.ENOTDIR):
            return "a dangling symbolic link" if path.is_symlink() else "no such file"
        return f"a path that cannot be read ({exc.strerror})"
    for test, kind in (
        (stat.S_ISREG, "a file"),
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
    ):
        if test(mode):
            return kind
    return "not a regular file"


def _check_file_kinds(path: str | os.PathLike[str]) -> tuple[Path, Path]:
    """The checks that need no write (not a folder, not under a file): the target and the
    nearest existing ancestor of its folder."""
    target = Path(path)
    if os.fspath(path).endswith(("/", os.sep)) or target.is_dir():
        found = "an existing folder" if target.is_dir() else "a folder path ending in /"
        raise OutputPathError(path, f"expected a file path, found {found}")
    kind = file_kind(target)
    if kind not in ("a file", "no such file", "a dangling symbolic link"):
        # Replacing a FIFO or a device by a file of results is never what was meant.
        raise OutputPathError(path, f"expected a file path, found {kind}")
    return target, _nearest_existing(target.parent, path)


def check_file_path(path: str | os.PathLike[str]) -> Path:
    """Checks that a file can be written at ``path`` (by `atomic_path`), without writing it.

    Missing folders are not created; a temporary file is created and removed in the nearest
    existing one to learn that they can be.

    Returns:
        ``path`` as a `Path`.

    Raises:
        OutputPathError: ``path`` is an existing folder, one of its folders is a file, or its
            folder cannot be created or written in.
    """
    target, existing = _check_file_kinds(path)
    _check_writable(target.parent, existing, path)
    return target


def check_folder_path(path: str | os.PathLike[str]) -> Path:
    """Checks that ``path`` is a folder, or can be created as one, and written in.

    Returns:
        ``path`` as a `Path`.

    Raises:
        OutputPathError: ``path`` is an existing file, one of its parents is a file, or it cannot
            be created or written in.
    """
    target = Path(path)
    if target.exists() and not target.is_dir():
        raise OutputPathError(path, "expected a folder path, found an existing file")
    _check_writable(target, _nearest_existing(target, path), path)
    return target


_FULL_ERRNOS = (errno.ENOSPC, errno.EDQUOT)  # what a full disk (or a spent quota) raises


class DiskFull(OSError):
    """A write that found the disk full: one line naming the path, what was written, the space
    left and the space needed (``errno`` is ENOSPC)."""

    def __init__(self, path: Path, *, written: int, needed: float | None = None) -> None:
        free = _free_bytes(path.parent)  # the unfinished file removed
        left = "" if free is None else f"; {_size(free)} free there without it"
        need = (
            f"about {_size(needed)} needed"
            if needed is not None and needed > written
            else f"more than {_size(written)} needed"
        )
        self.message = (
            f"{path}: the disk is full (no space left on the device after {_size(written)} of it "
            f"were written{left}, {need}); free some space there or write elsewhere"
        )
        super().__init__(errno.ENOSPC, self.message)
        self.path = path

    def __str__(self) -> str:
        return self.message


def _free_bytes(folder: Path) -> int | None:
    try:
        return shutil.disk_usage(folder).free
    except OSError:
        return None


def _size(n: float) -> str:
    """Bytes as ``"61 kB"``, ``"1.4 MB"`` (decimal units, as ``df -H``)."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{int(n)} bytes"


def is_disk_full(exc: BaseException) -> bool:
    """Whether ``exc`` says the disk is full (ENOSPC, EDQUOT), as an OSError or in the words
    of a library that wraps it."""
    if isinstance(exc, OSError) and exc.errno in _FULL_ERRNOS:
        return True
    return any(os.strerror(code) in str(exc) for code in _FULL_ERRNOS)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], *, needed: float | None = None) -> Iterator[Path]:
    """Yields a temporary path in the target's folder; renames it onto ``path`` on success.

    Use it with writers that take a path (``pyarrow.parquet.write_table``, ``skops.io.dump``).
    Missing folders are created. On an exception the temporary file is removed and ``path`` is
    left untouched; a killed writer's is removed by the next write into that folder (see the
    module notes).

    Args:
        path: the file to write.
        needed: the bytes the file is expected to take, if known, for the message of a full disk.

    Raises:
        OutputPathError: ``path`` is an existing folder, one of its folders is a file, or its
            folder cannot be created or written in (raised before the caller writes anything).
        DiskFull: the writer found the disk full.
    """
    target, _ = _check_file_kinds(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputPathError(
            path, f"folder {target.parent} cannot be created ({exc.strerror or exc})"
        ) from exc
    _clean_once(target.parent)
    try:
        fd, tmp_name = tempfile.mkstemp(
            prefix=_temporary_prefix(target), suffix=".tmp", dir=target.parent
        )
    except OSError as exc:
        raise OutputPathError(
            path, f"cannot write in folder {target.parent} ({exc.strerror or exc})"
        ) from exc
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        # mkstemp creates the file owner-only; give the result the permissions of a plain open().
        os.chmod(tmp, _DEFAULT_FILE_MODE & ~_current_umask())
        os.replace(tmp, target)
    except Exception as exc:
        try:
            written = tmp.stat().st_size
        except OSError:
            written = 0
        tmp.unlink(missing_ok=True)
        if is_disk_full(exc):
            raise DiskFull(target, written=written, needed=needed) from exc
        raise
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike[str], mode: str = "w", **kwargs) -> Iterator[IO]:
    """``open`` for writing, atomically: the file appears complete or not at all.

    Raises:
        OutputPathError: as `atomic_path`.
    """
    if not mode.startswith("w"):
        raise ValueError(f"atomic_open writes only, mode must start with 'w', got {mode!r}")
    with atomic_path(path) as tmp, open(tmp, mode, **kwargs) as handle:
        yield handle
        handle.flush()
        os.fsync(handle.fileno())
