"""The processes a test run started and left running (Linux).

The test process is made a child subreaper (``prctl(PR_SET_CHILD_SUBREAPER)``): a process it
started that outlives its parent (the binary behind a wrapper script that was stopped, a
detached viewer, a daemon) is handed to the test process rather than to ``init``, so every
process the run started stays among its descendants and can be listed when the run ends.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path

PR_SET_CHILD_SUBREAPER = 36  # <linux/prctl.h>
PROC = Path("/proc")
GRACE_S = 10.0  # seconds a process shutting down is given to exit before it counts as left


@dataclass(frozen=True)
class Process:
    """A running process: its id, its parent's and its command line."""

    pid: int
    ppid: int
    command: str

    def __str__(self) -> str:
        return f"pid {self.pid}: {self.command}"


def supported() -> bool:
    """Whether this machine lets the check see every process the run started (Linux)."""
    return sys.platform.startswith("linux") and PROC.is_dir()


def adopt_orphans() -> bool:
    """Makes this process the subreaper of everything it starts; False where it cannot be."""
    if not supported():
        return False
    libc = ctypes.CDLL(None, use_errno=True)
    return libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0


_TRACKERS = ("joblib.externals.loky.backend.resource_tracker", "multiprocessing.resource_tracker")


def end_helpers() -> None:
    """Stops now the helpers the interpreter stops as it exits, so that what is left after them
    is what would outlive the run: the local Ray instance and joblib's reusable loky workers.

    The resource trackers of loky and multiprocessing are left to end with this process
    (`own_trackers`): stopping one early loses its record, and the clean-ups joblib registers
    for exit then start a fresh tracker that knows none of the names they release (each a
    ``KeyError`` traceback at the end of the run, and a tracker started again while the check
    waits)."""
    if "ray" in sys.modules and sys.modules["ray"].is_initialized():
        sys.modules["ray"].shutdown()
    if "joblib.externals.loky.reusable_executor" in sys.modules:
        executor = sys.modules["joblib.externals.loky.reusable_executor"]._executor
        if executor is not None:
            executor.shutdown(wait=True)


def own_trackers() -> set[int]:
    """The process ids of the resource trackers this process started (loky's and
    multiprocessing's). Each reads a pipe whose writing end this process holds and ends when
    that pipe closes, so it ends with this process: it is not left running. (A child that
    inherited the pipe and outlives this process would keep it alive, and is counted itself;
    a tracker of another process, orphaned here, is counted.)"""
    pids = set()
    for module in _TRACKERS:
        tracker = getattr(sys.modules.get(module), "_resource_tracker", None)
        if tracker is not None and getattr(tracker, "_pid", None) is not None:
            pids.add(int(tracker._pid))
    return pids


def _read(pid: int) -> tuple[int, str, str] | None:
    """(parent id, state, command line) of ``pid``; None once it is gone."""
    try:
        stat = (PROC / str(pid) / "stat").read_text()
        raw = (PROC / str(pid) / "cmdline").read_bytes()
    except (FileNotFoundError, ProcessLookupError, PermissionError):
        return None
    # "pid (comm) state ppid ...": comm may hold spaces and parentheses.
    state, ppid = stat[stat.rindex(")") + 2 :].split()[:2]
    command = " ".join(raw.decode(errors="replace").split("\0")).strip() or stat.split()[1]
    return int(ppid), state, command


def _reap(pid: int) -> None:
    with contextlib.suppress(ChildProcessError):
        os.waitpid(pid, os.WNOHANG)


def descendants(root: int | None = None, *, reap: bool = False) -> list[Process]:
    """Every live process below ``root`` (this process by default); with ``reap``, this
    process's exited children are reaped (only once no test waits for them: a child reaped
    here would read as exit status 0 to its `subprocess.Popen`)."""
    root = os.getpid() if root is None else root
    table = {}
    for entry in PROC.iterdir():
        if entry.name.isdigit() and (info := _read(int(entry.name))) is not None:
            table[int(entry.name)] = info
    children: dict[int, list[int]] = {}
    for pid, (ppid, _, _) in table.items():
        children.setdefault(ppid, []).append(pid)
    found, todo = [], list(children.get(root, []))
    while todo:
        pid = todo.pop()
        ppid, state, command = table[pid]
        if state == "Z":
            if reap and ppid == os.getpid():
                _reap(pid)
            continue
        found.append(Process(pid, ppid, command))
        todo.extend(children.get(pid, []))
    return sorted(found, key=lambda p: p.pid)


def left_running(*, grace_s: float = GRACE_S) -> list[Process]:
    """The descendants of this process still alive after ``grace_s`` seconds of waiting, but
    for its own resource trackers (`own_trackers`), which end with it."""
    deadline = time.monotonic() + grace_s
    while True:
        own = own_trackers()
        alive = [p for p in descendants(reap=True) if p.pid not in own]
        if not alive or time.monotonic() >= deadline:
            return alive
        time.sleep(0.1)


def stop(processes: list[Process], *, grace_s: float = GRACE_S) -> None:
    """Sends each process SIGTERM, then SIGKILL to those still alive after ``grace_s``."""
    for sig, wait_s in ((signal.SIGTERM, grace_s), (signal.SIGKILL, 0.0)):
        for process in processes:
            with contextlib.suppress(ProcessLookupError):
                os.kill(process.pid, sig)
        live = {p.pid for p in processes}
        deadline = time.monotonic() + wait_s
        while (live & {p.pid for p in descendants()}) and time.monotonic() < deadline:
            time.sleep(0.1)
        processes = [p for p in processes if p.pid in live & {q.pid for q in descendants()}]
        if not processes:
            return
