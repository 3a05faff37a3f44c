"""Peak memory of one call, traced by ``tracemalloc``: for tests that a refusal or a bounded
read allocates little."""

from __future__ import annotations

import tracemalloc
from collections.abc import Callable
from typing import TypeVar

import pytest

T = TypeVar("T")
E = TypeVar("E", bound=BaseException)


def traced_peak(call: Callable[[], T]) -> tuple[T, int]:
    """What ``call()`` returns and the bytes Python allocated at the peak while it ran."""
    tracemalloc.start()
    try:
        result = call()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return result, peak


def raised_peak(call: Callable[[], object], expected: type[E]) -> tuple[E, int]:
    """The ``expected`` exception ``call()`` raises and the bytes allocated at the peak."""

    def catch() -> E:
        with pytest.raises(expected) as info:
            call()
        return info.value

    return traced_peak(catch)
