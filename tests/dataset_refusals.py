"""A dataset refused alike by every reader of it: the same one DataFormatError from each."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import pytest

from reform import DataFormatError


def assert_refused_by_each(
    readers: Iterable[Callable[[Path], Any]], path: Path, message: str
) -> None:
    """Each of ``readers`` (called with ``path`` alone) raises a DataFormatError matching the
    regular expression ``message``."""
    for read in readers:
        with pytest.raises(DataFormatError, match=message):
            read(path)
