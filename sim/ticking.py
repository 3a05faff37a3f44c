"""A progress bar that keeps ticking while the work it counts has not yet finished a unit.

tqdm redraws a bar when it is updated; a first unit that takes long (worker processes starting,
a large episode) leaves it frozen, and a frozen bar looks like a hung command. `ticking` redraws
it every `TICK_S` seconds, its elapsed time moving, until the work ends.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator
from typing import Any

__all__ = ["TICK_S", "ticking"]

TICK_S = 2.0  # seconds between redraws of a bar that no unit has moved


@contextlib.contextmanager
def ticking(bar: Any, *, every: float = TICK_S) -> Iterator[Any]:
    """Redraws ``bar`` (a tqdm bar) every ``every`` seconds while the block runs; yields it.

    A disabled bar is left alone (no thread)."""
    if getattr(bar, "disable", False):
        yield bar
        return
    stop = threading.Event()

    def tick() -> None:
        while not stop.wait(every):
            bar.refresh()

    thread = threading.Thread(target=tick, name="progress-tick", daemon=True)
    thread.start()
    try:
        yield bar
    finally:
        stop.set()
        thread.join()
