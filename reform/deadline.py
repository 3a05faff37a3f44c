"""Deadlines on someone else's code: a call that must return within so many seconds.

A detector is code from elsewhere (a plugin, an installed package): importing it, calling its
factory and its ``predict`` may never return. :func:`within` runs such a call under a deadline
and raises :class:`DeadlineExpired` when it passes, carrying the Python frames the call was
running then (so that a caller can say which of its data the call held).

In the main thread the call runs where it is (its ``sys.exit``, ``os._exit`` and Ctrl-C behave as
they would without a deadline) and a timer signal (``SIGALRM``) raises `DeadlineExpired` inside
it at the deadline, which stops it. Elsewhere (another thread, a platform without the signal) it
runs in a daemon thread of its own, abandoned at the deadline. Neither can stop a call stuck in
compiled code that never releases the interpreter. A call made while another's deadline runs
(one within another) keeps the outer deadline.

Durations are read by :func:`duration`: seconds (``30``, ``1.5``) or with a unit (``90s``, ``2m``,
``500ms``); every deadline a user gives is read by it and refused in the words of
:data:`DURATION_FORM`.
"""

from __future__ import annotations

import re
import signal
import sys
import threading
from collections.abc import Callable
from types import FrameType
from typing import Any, TypeVar

__all__ = ["DURATION_FORM", "DeadlineExpired", "duration", "in_thread", "within"]

DURATION_FORM = "a duration above zero (seconds, or with a unit: 90s, 2m, 500ms)"
_DURATION = re.compile(r"^\s*(\d+(?:\.\d*)?|\.\d+)\s*(ms|s|m|min)?\s*$")
_UNIT_S = {None: 1.0, "s": 1.0, "ms": 1e-3, "m": 60.0, "min": 60.0}
_STACK_DEPTH = 64  # Python frames kept of a call stopped at its deadline, innermost first

T = TypeVar("T")


def duration(text: str) -> float | None:
    """``text`` as seconds (``"30"``, ``"1.5"``, ``"90s"``, ``"2m"``, ``"500ms"``, spaces
    allowed), or None when it is not a duration above zero."""
    match = _DURATION.match(text) if isinstance(text, str) else None
    seconds = float(match.group(1)) * _UNIT_S[match.group(2)] if match else 0.0
    return seconds if seconds > 0.0 else None


class DeadlineExpired(BaseException):
    """A call did not return within its deadline.

    A BaseException, as KeyboardInterrupt is: raised inside someone's code, it must not be
    swallowed by that code's ``except Exception``.

    Attributes:
        seconds: the deadline.
        stack: the Python frames the call was running when it passed, innermost first.
    """

    def __init__(self, seconds: float, stack: list[FrameType]) -> None:
        super().__init__(f"did not return within {seconds:g} s")
        self.seconds = seconds
        self.stack = stack


def _stack(frame: FrameType | None) -> list[FrameType]:
    out = []
    while frame is not None and len(out) < _STACK_DEPTH:
        out.append(frame)
        frame = frame.f_back
    return out


def within(seconds: float, call: Callable[..., T], *args: Any, **kwargs: Any) -> T:
    """``call(*args, **kwargs)``, stopped when it has not returned within ``seconds``.

    Raises:
        DeadlineExpired: it did not return in time (see the module notes).
        ValueError: ``seconds`` not above zero.
        Whatever ``call`` raises.
    """
    if not seconds > 0.0:
        raise ValueError(f"seconds must be above zero, got {seconds!r}")
    main = threading.current_thread() is threading.main_thread()
    if not main or not hasattr(signal, "setitimer"):
        return in_thread(seconds, call, *args, **kwargs)
    if signal.getitimer(signal.ITIMER_REAL)[0] > 0.0:  # inside another deadline: it holds
        return call(*args, **kwargs)

    def expire(signum: int, frame: FrameType | None) -> None:  # noqa: ARG001 - signal's API
        raise DeadlineExpired(seconds, _stack(frame))

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        return call(*args, **kwargs)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def in_thread(
    seconds: float,
    call: Callable[..., T],
    /,
    *args: Any,
    thread_name: str = "deadline",
    **kwargs: Any,
) -> T:
    """``call(*args, **kwargs)`` in a daemon thread (``thread_name``), abandoned (left running,
    never keeping the process) when it has not returned within ``seconds``.

    Raises:
        DeadlineExpired: it did not return in time (its stack: the thread's frames then).
        Whatever ``call`` raises.
    """
    outcome: dict[str, Any] = {}

    def run() -> None:
        try:
            outcome["value"] = call(*args, **kwargs)
        except BaseException as exc:  # noqa: BLE001 - raised again in the caller
            outcome["error"] = exc

    thread = threading.Thread(target=run, name=thread_name, daemon=True)
    thread.start()
    thread.join(seconds)
    if thread.is_alive():
        running = sys._current_frames().get(thread.ident)
        raise DeadlineExpired(seconds, _stack(running))
    if "error" in outcome:
        raise outcome["error"]
    return outcome.get("value")
