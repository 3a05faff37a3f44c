"""What every benchmark script shares: timing a call over repeats, and where the datasets are.

A plain module beside the scripts: ``python benchmarks/bench_x.py`` puts ``benchmarks/`` first
on ``sys.path``, so each script imports it as ``from timing import ...``.
"""

from __future__ import annotations

import os
import statistics
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

DATASETS_VARIABLE = "REFORM_SIM_DATASETS"  # environment variable naming the datasets folder
REPO = Path(__file__).resolve().parents[1]  # the repository's root


@dataclass(frozen=True)
class Timing:
    """Seconds of each timed call, and what the last call returned.

    Attributes:
        seconds: Duration of each call in order, seconds; shape (calls,).
        result: Return value of the last call (None when nothing was called).
    """

    seconds: tuple[float, ...]
    result: Any

    @property
    def median(self) -> float:
        """Median seconds of the calls."""
        return statistics.median(self.seconds)

    @property
    def first(self) -> float:
        """Seconds of the first call."""
        return self.seconds[0]

    @property
    def best(self) -> float:
        """Seconds of the fastest call."""
        return min(self.seconds)


def timed(
    function: Callable[..., Any],
    repeats: int,
    *,
    args: tuple[Any, ...] = (),
    clock: Callable[[], float] = time.perf_counter,
) -> Timing:
    """Call ``function(*args)`` ``repeats`` times, timing each call alone.

    Args:
        function: What to time.
        repeats: Number of calls, at least 1.
        args: Positional arguments of every call.
        clock: Seconds counter read around each call: ``time.perf_counter`` (wall clock) or
            ``time.process_time`` (CPU seconds of this process).

    Returns:
        The seconds of each call and the last call's result.
    """
    if repeats < 1:
        raise ValueError(f"repeats: expected an integer >= 1, found {repeats!r}")
    seconds, result = [], None
    for _ in range(repeats):
        start = clock()
        result = function(*args)
        seconds.append(clock() - start)
    return Timing(seconds=tuple(seconds), result=result)


def timed_each(
    function: Callable[[Any], Any],
    items: Iterable[Any],
    *,
    clock: Callable[[], float] = time.perf_counter,
) -> Timing:
    """Call ``function(item)`` once per item, timing each call alone.

    Args:
        function: What to time; takes one item.
        items: The argument of each call, at least one.
        clock: Seconds counter read around each call (see :func:`timed`).

    Returns:
        The seconds of each call (in the order of ``items``) and the last call's result.
    """
    seconds, result = [], None
    for item in items:
        start = clock()
        result = function(item)
        seconds.append(clock() - start)
    if not seconds:
        raise ValueError("items: expected at least one item, found none")
    return Timing(seconds=tuple(seconds), result=result)


def median_seconds(
    function: Callable[[], Any],
    repeats: int,
    *,
    clock: Callable[[], float] = time.perf_counter,
) -> float:
    """Median seconds of ``repeats`` calls of ``function()`` (see :func:`timed`)."""
    return timed(function, repeats, clock=clock).median


def default_datasets() -> str:
    """The ``--datasets`` default: ``$REFORM_SIM_DATASETS``, else ``shared/datasets`` beside
    the repository (``../shared/datasets`` from its root)."""
    configured = os.environ.get(DATASETS_VARIABLE)
    return configured if configured else str(REPO.parent / "shared" / "datasets")
