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


def end_helpers() -> None:
    """Stops now the helpers the interpreter stops as it exits, so that what is left after them
    is what would outlive the run: the local Ray instance, joblib's reusable loky workers, and
    the resource trackers of loky and multiprocessing (they end when this process closes their
    pipe)."""
    if "ray" in sys.modules and sys.modules["ray"].is_initialized():
        sys.modules["ray"].shutdown()
    if "joblib.externals.loky.reusable_executor" in sys.modules:
        executor = sys.modules["joblib.externals.loky.reusable_executor"]._executor
        if executor is not None:
            executor.shutdown(wait=True)
    for module in (
        "joblib.externals.loky.backend.resource_tracker",
        "multiprocessing.resource_tracker",
    ):
        tracker = getattr(sys.modules.get(module), "_resource_tracker", None)
        if tracker is not None and tracker._pid is not None:
            tracker._stop()


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
    """The descendants of this process still alive after ``grace_s`` seconds of waiting."""
    deadline = time.monotonic() + grace_s
    while (alive := descendants(reap=True)) and time.monotonic() < deadline:
        time.sleep(0.1)
    return alive


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
