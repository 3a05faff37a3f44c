"""A report's files on disk: its Markdown page and its JSON document, each written atomically.

One way for every study and command that writes them: a reader never finds half a file, the JSON
is strict (no NaN or infinity) and ends with a newline.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from reform.atomic import atomic_open

__all__ = ["write_json", "write_markdown"]


def write_markdown(path: str | os.PathLike[str], text: str) -> Path:
    """Writes ``text`` to ``path`` (atomically; missing folders are created). Returns the path."""
    with atomic_open(path) as handle:
        handle.write(text)
    return Path(path)


def write_json(path: str | os.PathLike[str], document: Any, *, indent: int) -> Path:
    """Writes ``document`` as strict JSON (``indent`` spaces a level, a final newline) to
    ``path`` (atomically; missing folders are created). Returns the path.

    Raises:
        ValueError: ``document`` holds NaN or an infinity (strict JSON has neither).
    """
    with atomic_open(path) as handle:
        json.dump(document, handle, indent=indent, allow_nan=False)
        handle.write("\n")
    return Path(path)
