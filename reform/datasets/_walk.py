"""Looking for a dataset's files inside a folder, within bounds.

A folder named by mistake (``/``, a home folder) must not be walked whole: the walk looks at
most :data:`MAX_ENTRIES` entries, never follows a symbolic link to a folder, and passes over
hidden folders and those starting with ``_`` (Spark's ``_temporary``, a run's ``.partial``).
"""

from __future__ import annotations

import os
from collections import deque
from pathlib import Path

from reform.datasets.errors import DataFormatError, os_error_found

__all__ = ["MAX_ENTRIES", "find_files"]

MAX_ENTRIES = 100_000  # entries (files and folders) a search looks at before it gives up: a
# generated dataset of 10,000 episodes holds about 20,000


def _skipped(name: str) -> bool:
    return name.startswith((".", "_"))


def find_files(
    folder: Path,
    suffix: str,
    *,
    max_depth: int | None = None,
    first: bool = False,
    strict: bool = True,
    what: str = "a dataset folder",
    max_entries: int | None = None,
) -> list[Path]:
    """The files named ``*suffix`` in ``folder`` and its subfolders (breadth first).

    Args:
        folder: where to look.
        suffix: the files' ending (``".parquet"``).
        max_depth: subfolder levels to look into (0: ``folder`` alone); None for all.
        first: stop at the first file found.
        strict: a subfolder that cannot be read is an error (a reader must not skip shards
            silently); otherwise it is passed over (detection).
        what: what the folder was expected to be, for the error.
        max_entries: entries to look at, at most; :data:`MAX_ENTRIES` by default.

    Raises:
        DataFormatError: more than :data:`MAX_ENTRIES` entries, or (``strict``) a subfolder
            that cannot be read.
    """
    limit = MAX_ENTRIES if max_entries is None else max_entries
    found: list[Path] = []
    seen = 0
    queue: deque[tuple[Path, int]] = deque([(folder, 0)])
    unreadable: DataFormatError | None = None
    while queue:
        current, depth = queue.popleft()
        try:
            with os.scandir(current) as entries:
                children = sorted(entries, key=lambda e: e.name)
        except OSError as exc:
            error = DataFormatError(
                current, None, None, "a readable folder", os_error_found(exc)
            )
            if current == folder:
                raise error from None
            if strict and unreadable is None:
                unreadable = error  # said once the walk is over (a walk too large says so first)
            continue
        for entry in children:
            seen += 1
            if seen > limit:
                levels = "" if max_depth is None else f" at most {max_depth} levels down"
                raise DataFormatError(
                    folder,
                    None,
                    None,
                    f"{what} (a search for *{suffix} files{levels} looks at "
                    f"{limit:,} entries at most)",
                    f"more than {limit:,} entries",
                    hint="name the dataset's own folder, or a file",
                )
            if _skipped(entry.name):
                continue
            try:
                is_dir = entry.is_dir(follow_symlinks=False)
                is_file = not is_dir and entry.name.endswith(suffix) and entry.is_file()
            except OSError:
                is_dir = is_file = False
            if is_file:
                found.append(Path(entry.path))
                if first:
                    return found
            elif is_dir and (max_depth is None or depth < max_depth):
                queue.append((Path(entry.path), depth + 1))
    if unreadable is not None:
        raise unreadable
    return found
