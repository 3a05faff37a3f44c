"""Progress bars on stderr: tqdm's when one is shown, and nothing to import when none is.

tqdm costs a command about 30 ms of CPU to import (with `importlib.metadata` and
`multiprocessing`), which a ``--quiet`` run, or a map with no bar, has no use for.
"""

from __future__ import annotations

import sys
from typing import Any

__all__ = ["elapsed_line", "progress_bar"]

ELAPSED_FORMAT = "{desc}: {elapsed} so far"  # a line counting no unit, only the time


class _NoBar:
    """What a disabled tqdm bar answers, without tqdm."""

    disable = True

    def __init__(self, total: int | None = None) -> None:
        self.total = total
        self.n = 0

    def update(self, n: int = 1) -> None:
        self.n += n

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:  # noqa: ARG002
        return None

    def refresh(self) -> None:
        return None

    def close(self) -> None:
        return None

    def __enter__(self) -> _NoBar:
        return self

    def __exit__(self, *exc: object) -> None:
        return None


def progress_bar(*, disable: bool = False, **options: Any) -> Any:
    """``tqdm(**options)``, or when ``disable`` a bar that draws nothing (tqdm not imported).

    Args:
        disable: draw nothing.
        options: tqdm's (``total``, ``desc``, ``unit``, ``file``, ...).
    """
    if disable:
        return _NoBar(options.get("total"))
    from tqdm import tqdm  # noqa: PLC0415 (only a bar that is shown needs it)

    return tqdm(**options)


def elapsed_line(desc: str, *, disable: bool = False) -> Any:
    """A line ``desc: 00:12 so far`` on stderr, cleared when closed, for work that counts no
    unit; `sim.ticking.ticking` keeps its time moving. Drawn at once, so that the work is never
    silent from its start.

    Args:
        desc: what is being done.
        disable: draw nothing (tqdm not imported).
    """
    return progress_bar(
        desc=desc, bar_format=ELAPSED_FORMAT, file=sys.stderr, leave=False, disable=disable
    )
