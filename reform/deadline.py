"""Deadlines on someone else's code: a call that must return within so many seconds.

A detector is code from elsewhere (a plugin, an installed package): importing it, calling its
factory and its ``predict`` may never return. :func:`within` runs such a call under a deadline
and raises :class:`DeadlineExpired` when it passes, carrying the Python frames the call was
running then (so that a caller can say which of its data the call held).

In the main thread the call runs where it is (its ``sys.exit``, ``os._exit`` and Ctrl-C behave as
they would without a deadline) and a timer signal (``SIGALRM``) raises `DeadlineExpired` inside
it at the deadline, which stops it. Elsewhere (another thread, a platform without the signal) it
runs in a daemon thread of its own, abandoned at the deadline. A call made while another's
deadline runs (one within another) keeps the outer deadline.

Neither can stop a call stuck in compiled code that never returns to the interpreter (a
deadlock, an endless loop in C holding the interpreter's lock): the signal's handler never
runs. For that, a command may turn on :func:`hard_stops`: a main-thread deadline given a
``stuck`` line also arms a watcher process, which, when the call has still not returned
:data:`STUCK_GRACE_S` seconds after its deadline, writes that line on stderr and ends this
process (SIGKILL, the one signal that needs no cooperation from it). The watcher is started
once, the first time it is needed, costs two short pipe writes per call, and ends when this
process does.

Durations are read by :func:`duration`: seconds (``30``, ``1.5``) or with a unit (``90s``, ``2m``,
``500ms``); every deadline a user gives is read by it and refused in the words of
:data:`DURATION_FORM`.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import re
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from types import FrameType
from typing import Any, TypeVar

__all__ = [
    "DURATION_FORM",
    "STUCK_GRACE_S",
    "DeadlineExpired",
    "duration",
    "hard_stopping",
    "hard_stops",
    "in_thread",
    "within",
]

MAX_DEADLINE_S = 30 * 86400.0  # seconds: the longest deadline (past it, a system timer overflows)
DURATION_FORM = (
    "a duration above zero and at most 30 days (seconds, or with a unit: 90s, 2m, 500ms)"
)
# ASCII digits only: ``\d`` would take other scripts' digits ('٣') for 3.
_DURATION = re.compile(r"^\s*([0-9]+(?:\.[0-9]*)?|\.[0-9]+)\s*(ms|s|m|min)?\s*$")
_UNIT_S = {None: 1.0, "s": 1.0, "ms": 1e-3, "m": 60.0, "min": 60.0}
_STACK_DEPTH = 64  # Python frames kept of a call stopped at its deadline, innermost first
# Seconds past its deadline a call may go on holding the interpreter before hard_stops ends the
# process: room for a busy machine to run the deadline's own handler, which stops it cleanly.
STUCK_GRACE_S = 5.0

T = TypeVar("T")


def duration(text: str) -> float | None:
    """``text`` as seconds (``"30"``, ``"1.5"``, ``"90s"``, ``"2m"``, ``"500ms"``, spaces
    allowed), or None when it is not a duration above zero and at most `MAX_DEADLINE_S`."""
    match = _DURATION.match(text) if isinstance(text, str) else None
    seconds = float(match.group(1)) * _UNIT_S[match.group(2)] if match else 0.0
    return seconds if 0.0 < seconds <= MAX_DEADLINE_S else None


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


def within(
    seconds: float, call: Callable[..., T], /, *args: Any, stuck: str | None = None, **kwargs: Any
) -> T:
    """``call(*args, **kwargs)``, stopped when it has not returned within ``seconds``.

    Args:
        stuck: under :func:`hard_stops`, the line said before the process is ended when the
            call has not returned :data:`STUCK_GRACE_S` seconds after its deadline (it holds
            the interpreter in compiled code); None: no such backstop.

    Raises:
        DeadlineExpired: it did not return in time (see the module notes).
        ValueError: ``seconds`` not above zero.
        Whatever ``call`` raises.
    """
    if not 0.0 < seconds <= MAX_DEADLINE_S:
        raise ValueError(
            f"seconds must be above zero and at most {MAX_DEADLINE_S:g} (30 days), got {seconds!r}"
        )
    main = threading.current_thread() is threading.main_thread()
    if not main or not hasattr(signal, "setitimer"):
        return in_thread(seconds, call, *args, **kwargs)
    if signal.getitimer(signal.ITIMER_REAL)[0] > 0.0:  # inside another deadline: it holds
        return call(*args, **kwargs)

    def expire(signum: int, frame: FrameType | None) -> None:  # noqa: ARG001 - signal's API
        raise DeadlineExpired(seconds, _stack(frame))

    previous = signal.signal(signal.SIGALRM, expire)
    watched = stuck is not None and _WATCH.arm(seconds + STUCK_GRACE_S, stuck)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        return call(*args, **kwargs)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)
        if watched:
            _WATCH.clear()


@contextlib.contextmanager
def hard_stops(prefix: str, *, to: str | None = None) -> Iterator[None]:
    """Within: a call :func:`within` stops with a ``stuck`` line is ended, process and all,
    when it holds the interpreter past its deadline (see the module notes); the line is written
    after ``prefix`` (``"reform-sim detect: error: "``) on stderr, or appended to the file
    ``to`` (a worker's note, which the process that started it reads)."""
    before = _WATCH.prefix, _WATCH.to
    _WATCH.prefix, _WATCH.to = prefix, to
    try:
        yield
    finally:
        _WATCH.prefix, _WATCH.to = before


def hard_stopping() -> str | None:
    """The prefix of the :func:`hard_stops` this process is within, or None."""
    return _WATCH.prefix


# The watcher: reads "arm<TAB>WHEN<TAB>FILE<TAB>LINE" and "clear" on its stdin; at an armed
# moment (the monotonic clock, shared by every process of the machine) it writes LINE on its
# stderr (this process's), or appends it to FILE when one is given, and kills PARENT; at the end
# of its stdin (this process gone) it ends.
_WATCHER = """\
import os, select, signal, sys, time
signal.signal(signal.SIGINT, signal.SIG_IGN)
parent, pending, armed = int(sys.argv[1]), b"", None
while True:
    wait = None if armed is None else max(0.0, armed[0] - time.monotonic())
    if not select.select([0], [], [], wait)[0]:
        out = os.open(armed[1], os.O_WRONLY | os.O_APPEND) if armed[1] else 2
        os.write(out, armed[2] + b"\\n")
        os.kill(parent, signal.SIGKILL)
        break
    chunk = os.read(0, 65536)
    if not chunk:
        break
    *lines, pending = (pending + chunk).split(b"\\n")
    for line in lines:
        word, *rest = line.split(b"\\t", 3)
        if word == b"arm":
            armed = (float(rest[0]), rest[1], rest[2])
        elif word == b"clear":
            armed = None
"""


class _Watch:
    """This process's watcher (started at the first `arm` under `hard_stops`)."""

    def __init__(self) -> None:
        self.prefix: str | None = None
        self.to: str | None = None
        self._process: Any = None  # a subprocess.Popen
        self._owner = 0

    def arm(self, seconds: float, line: str) -> bool:
        """Arms the watcher to say ``line`` and end this process in ``seconds``; False (nothing
        armed) outside `hard_stops` or when no watcher can be started."""
        if self.prefix is None:
            return False
        text = " ".join(f"{self.prefix}{line}".split())
        at = time.monotonic() + seconds
        to = self.to or ""
        return self._send(f"arm\t{at:.3f}\t{to}\t{text}\n".encode(errors="replace"))

    def clear(self) -> None:
        self._send(b"clear\n")

    def _send(self, data: bytes) -> bool:
        process = self._started()
        if process is None or process.stdin is None:
            return False
        try:
            process.stdin.write(data)
            process.stdin.flush()
        except OSError:  # the watcher is gone: calls go unwatched, as without hard_stops
            return False
        return True

    def _started(self) -> Any:
        if self._process is not None and self._owner == os.getpid():
            return self._process
        import subprocess  # here: a process that arms no watcher never imports it

        try:  # -I -S: no user site, no site packages: a bare interpreter starts in milliseconds
            self._process = subprocess.Popen(
                [sys.executable, "-I", "-S", "-c", _WATCHER, str(os.getpid())],
                stdin=subprocess.PIPE,
                stdout=subprocess.DEVNULL,
                close_fds=True,
            )
        except OSError:
            self._process = None
            return None
        self._owner = os.getpid()
        atexit.register(self._stop)
        return self._process

    def _stop(self) -> None:
        process, self._process = self._process, None
        if process is None or self._owner != os.getpid():
            return
        with contextlib.suppress(OSError):
            if process.stdin is not None:
                process.stdin.close()  # its end of input: it ends
        with contextlib.suppress(Exception):  # subprocess.TimeoutExpired: left to end alone
            process.wait(timeout=5.0)


_WATCH = _Watch()


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
