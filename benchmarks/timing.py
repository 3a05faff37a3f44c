"""What every benchmark script shares: its command line, timing a call over repeats, and where
the datasets are.

Every script's command line starts from :class:`BenchmarkParser`: ``--quick`` (a smoke run
that ``tests/benchmarks/test_benchmarks.py`` runs: tiny sizes, one or two repeats, every
equality check of the full run, no timing threshold) and, where the script repeats its
timings, ``--repeats``.

A plain module beside the scripts: ``python benchmarks/bench_x.py`` puts ``benchmarks/`` first
on ``sys.path``, so each script imports it as ``from timing import ...``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

DATASETS_VARIABLE = "REFORM_SIM_DATASETS"  # environment variable naming the datasets folder
REPO = Path(__file__).resolve().parents[1]  # the repository's root
DATASETS_MISSING = 3  # exit status of a script whose datasets are not found (tests skip on it)
QUICK_HELP = (
    "smoke run: tiny sizes and one or two repeats, every equality check still made; the "
    "figures mean little"
)


class BenchmarkParser(argparse.ArgumentParser):
    """A benchmark's command line: ``--quick``, and ``--repeats`` when it repeats its timings.

    ``--repeats`` defaults to ``repeats``, or to ``quick_repeats`` with ``--quick``; given
    explicitly it wins over both. A script's own sizes that ``--quick`` shrinks are declared
    the same way, with :meth:`add_sized`.

    Args:
        doc: The script's docstring; its first paragraph is the description.
        repeats: Default number of timed runs per measure; None: the script takes no
            ``--repeats``.
        quick_repeats: Timed runs per measure with ``--quick``, 1 or 2.
    """

    def __init__(self, doc: str, *, repeats: int | None = None, quick_repeats: int = 1) -> None:
        super().__init__(description=doc.split("\n\n")[0])
        self._sizes: dict[str, tuple[Any, Any]] = {}  # dest -> (default, default with --quick)
        self.add_argument("--quick", action="store_true", help=QUICK_HELP)
        if repeats is not None:
            self.add_sized(
                "--repeats", default=repeats, quick=quick_repeats, help="timed runs per measure"
            )

    def add_sized(
        self,
        option: str,
        *,
        default: Any,
        quick: Any,
        help: str,  # noqa: A002
        type: Callable[[str], Any] | None = None,  # noqa: A002
        nargs: str | None = None,
    ) -> None:
        """Adds ``option``, a size of the run: ``default``, or ``quick`` with ``--quick``; given
        explicitly it wins over both.

        Args:
            option: The flag, e.g. ``"--episodes"``.
            default: Its value in a full run (a number, or a tuple of numbers with ``nargs``).
            quick: Its value with ``--quick``.
            help: What it is; its two defaults are added.
            type: Converts each word; None: an integer >= 1.
            nargs: As argparse's (``"+"`` for several values), None for one value.
        """
        action = self.add_argument(
            option,
            type=_at_least_one if type is None else type,
            nargs=nargs,
            default=None,
            help=f"{help} (default {_shown(default)}; {_shown(quick)} with --quick)",
        )
        self._sizes[action.dest] = (default, quick)

    def add_datasets_argument(self) -> None:
        """Adds ``--datasets DIR``: the real datasets' folder (see :func:`datasets_folder`)."""
        self.add_argument(
            "--datasets",
            type=Path,
            default=Path(default_datasets()),
            help=f"folder holding salsa/ and babble/ (default ${DATASETS_VARIABLE}, else "
            "../shared/datasets)",
        )

    def parse_args(
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> argparse.Namespace:
        """Parses the command line; fills each size not given from ``--quick``."""
        parsed = super().parse_args(args, namespace)
        for dest, (default, quick) in self._sizes.items():
            if getattr(parsed, dest) is None:
                setattr(parsed, dest, quick if parsed.quick else default)
        return parsed


def _shown(value: Any) -> str:
    """A default as the help prints it: ``2`` and ``0.5``; a tuple as ``2 10``."""
    if isinstance(value, tuple):
        return " ".join(_shown(v) for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def _at_least_one(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text}")
    return value


def datasets_folder(folder: Path, *names: str) -> Path:
    """``folder`` when it holds every dataset of ``names`` (``"salsa"``, ``"babble"``).

    Otherwise prints which is missing and how to point at them, and exits with status
    :data:`DATASETS_MISSING`.
    """
    missing = [name for name in names if not (folder / name).is_dir()]
    if missing:
        print(
            f"datasets not found: {', '.join(missing)} in {folder} (pass --datasets DIR or set "
            f"{DATASETS_VARIABLE} to the folder holding them)",
            file=sys.stderr,
        )
        raise SystemExit(DATASETS_MISSING)
    return folder


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
