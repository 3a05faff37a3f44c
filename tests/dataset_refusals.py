"""A dataset refused by its readers: the same one DataFormatError from each."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import pytest

from reform import DataFormatError


def assert_refused(read: Callable[[Path], Any], path: Path, message: str) -> None:
    """``read(path)`` raises a DataFormatError matching the regular expression ``message``."""
    with pytest.raises(DataFormatError, match=message):
        read(path)


def assert_refused_by_each(
    readers: Iterable[Callable[[Path], Any]], path: Path, message: str
) -> None:
    """Each of ``readers`` (called with ``path`` alone) raises a DataFormatError matching the
    regular expression ``message``."""
    for read in readers:
        assert_refused(read, path, message)
