"""Ctrl-C reaches ``reform-sim`` alone, not the worker processes it starts.

A terminal sends SIGINT to every process of the foreground job: worker processes (joblib's,
Ray's) would each print a KeyboardInterrupt traceback, some while still importing. While a
command runs, SIGINT is blocked in the main thread, so that every thread and process started
from it inherits the blocked signal, and is delivered to a parked thread instead, whose Python
handler raises KeyboardInterrupt in the main thread as usual. The command then stops its workers
as on any error (joblib terminates them) and ``main`` reports the interruption in one line.
(joblib's own resource tracker is started with SIGINT blocked for the same reason.)

A Python handler runs when the main thread next executes Python code: a main thread waiting in
a system call (a detector's ``time.sleep``, a socket, a lock) would wait on. So the signal's
arrival is also written to a wake-up socket (`signal.set_wakeup_fd`), and a thread reading it
sends the main thread SIGUSR1, whose handler does nothing: the call is interrupted, and Python
runs the pending SIGINT handler on its way back.

SIGTERM (``kill PID``, a job scheduler, a container stopping) stops a command the same way: it
raises `Stopped`, a KeyboardInterrupt, in the main thread (:func:`sigterm_stops`), so that the
workers are terminated with the command rather than left computing without it. A second SIGTERM
ends the process at once, as SIGTERM does by default (its workers end with it).

Once a command is stopping, an exception in loky's pool-manager thread is not printed
(:func:`quiet_pool_manager`): terminating joblib's workers races with that thread's own
bookkeeping (a KeyError from its table of pending work, joblib/loky#663), and the stop is
already said in one line. Every other thread's exceptions print as before.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from collections.abc import Iterator
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import socket

__all__ = ["Stopped", "quiet_pool_manager", "sigint_to_main_only", "sigterm_stops"]

_parked: threading.Thread | None = None
_TRACKER_FILTER = "ignore:resource_tracker:UserWarning"  # loky's tracker's leftover warnings
POOL_MANAGER_THREAD = "ExecutorManagerThread"  # loky's name for its pool's manager thread
WAKER_JOIN_S = 5.0  # seconds: at most this long for the wake-up thread to stop at the end (it
# stops at once unless the machine is too busy to run it)


def _park() -> None:
    """Starts, once, a daemon thread that waits forever with SIGINT unblocked."""
    global _parked
    if _parked is None:
        _parked = threading.Thread(
            target=threading.Event().wait, name="reform-sim-sigint", daemon=True
        )
        _parked.start()


class Stopped(KeyboardInterrupt):
    """A command stopped by a signal other than Ctrl-C's (SIGTERM), raised in the main thread.

    Attributes:
        signal: the signal that stopped it.
    """

    def __init__(self, signum: int) -> None:
        self.signal = signal.Signals(signum)
        super().__init__(self.signal.name)


# The signal the latest sigterm_stops raised as Stopped (cleared as each one begins): read after
# it ends, by the command's report of the stop.
_STOPPED: list[int] = []


def quiet_pool_manager() -> None:
    """From now on, this process does not print an exception raised in a thread named
    `POOL_MANAGER_THREAD` (see the module notes); other threads' print as before."""
    previous = threading.excepthook
    if getattr(previous, "quiets_pool_manager", False):
        return

    def hook(args: threading.ExceptHookArgs) -> None:
        if args.thread is None or args.thread.name != POOL_MANAGER_THREAD:
            previous(args)

    hook.quiets_pool_manager = True  # type: ignore[attr-defined]
    threading.excepthook = hook


def _raise_stopped(signum: int, _frame: object) -> None:
    signal.signal(signum, signal.SIG_DFL)  # a second one ends the process at once
    quiet_pool_manager()
    _STOPPED.append(signum)
    raise Stopped(signum)


def as_stopped(exc: KeyboardInterrupt) -> KeyboardInterrupt:
    """``exc``, or the `Stopped` it stands for: code the signal's exception passed through (Ray's
    wait, which checks for signals itself) may have raised a plain KeyboardInterrupt in its
    place."""
    if isinstance(exc, Stopped) or not _STOPPED:
        return exc
    return Stopped(_STOPPED[-1])


@contextlib.contextmanager
def sigterm_stops() -> Iterator[None]:
    """Within: SIGTERM raises `Stopped` in this (the main) thread. A no-op outside the main
    thread, where there is no SIGTERM, and when SIGTERM has a disposition of the caller's (a
    handler, or ignored) rather than the default."""
    main = threading.current_thread() is threading.main_thread()
    if main:  # a command in another thread leaves the main thread's record alone
        _STOPPED.clear()
    if (
        not hasattr(signal, "SIGTERM")
        or not main
        or signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL
    ):
        yield
        return
    signal.signal(signal.SIGTERM, _raise_stopped)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


@contextlib.contextmanager
def sigint_to_main_only() -> Iterator[None]:
    """Within: Ctrl-C raises KeyboardInterrupt in this (the main) thread, and the processes
    started here do not see it. A no-op outside the main thread, where signal masks cannot be
    set (not POSIX), and when SIGINT has a handler of the caller's (not Python's default)."""
    if (
        not hasattr(signal, "pthread_sigmask")
        or threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    ):
        yield
        return
    _park()
    # An interrupted pool of loky workers leaves semaphores its resource tracker (a process of
    # its own) cleans up at exit, saying so in a warning on stderr: the interruption is already
    # said in one line. Worker processes inherit the filter through the environment.
    filters = os.environ.get("PYTHONWARNINGS", "")
    if _TRACKER_FILTER not in filters.split(","):
        os.environ["PYTHONWARNINGS"] = ",".join(f for f in (filters, _TRACKER_FILTER) if f)
    # multiprocessing's resource tracker, started on the first use of worker processes, unblocks
    # SIGINT in the thread that starts it (instead of restoring the mask; Python 3.11). Started
    # here, before the block (11 ms, one small process), it leaves the mask alone later.
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()
    with _wake_main_on_sigint():
        previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            yield
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, previous)


@contextlib.contextmanager
def _wake_main_on_sigint() -> Iterator[None]:
    """Within: a SIGINT interrupts the main thread's blocking call (see the module notes). Left
    out when SIGUSR1 or the wake-up fd is someone else's already."""
    if not hasattr(signal, "SIGUSR1") or signal.getsignal(signal.SIGUSR1) not in (
        signal.SIG_DFL,
        None,
    ):
        yield
        return
    theirs = signal.set_wakeup_fd(-1)
    if theirs != -1:  # an event loop's: leave it be
        signal.set_wakeup_fd(theirs)
        yield
        return
    import socket  # here: ``reform-sim --help`` exits before any command runs, without it

    reader, writer = socket.socketpair()
    writer.setblocking(False)
    signal.signal(signal.SIGUSR1, _nothing)
    signal.set_wakeup_fd(writer.fileno(), warn_on_full_buffer=False)
    main = threading.main_thread().ident
    waker = threading.Thread(target=_wake, args=(reader, main), name="reform-sim-wake", daemon=True)
    waker.start()
    try:
        yield
    finally:
        signal.set_wakeup_fd(-1)
        writer.close()  # the waker reads what is left, then the end of the stream, and stops
        waker.join(timeout=WAKER_JOIN_S)
        # Only then is SIGUSR1's default (which ends the process) put back: a waker scheduled
        # late on a busy machine may still be about to send it for the signal that stopped the
        # command. One that has not caught up by now keeps its handler, which does nothing.
        if not waker.is_alive():
            signal.signal(signal.SIGUSR1, signal.SIG_DFL)
        reader.close()


def _nothing(_signum: int, _frame: object) -> None:
    """SIGUSR1's handler: its arrival is all that is needed."""


def _wake(reader: socket.socket, main: int | None) -> None:
    """Sends the main thread SIGUSR1 whenever the wake-up socket says SIGINT (or SIGTERM)
    arrived."""
    while True:
        try:
            data = reader.recv(64)
        except OSError:
            return
        if not data:
            return
        if any(s in data for s in (signal.SIGINT, signal.SIGTERM)):
            quiet_pool_manager()
            if main is not None:
                signal.pthread_kill(main, signal.SIGUSR1)
