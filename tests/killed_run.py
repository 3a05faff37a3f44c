"""A ``reform-sim`` run in a child process of its own, killed mid-way: for resume tests."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable

CLI = [sys.executable, "-c", "import sys; from sim.cli import main; sys.exit(main())"]
RUN_TIMEOUT_S = 300.0  # seconds, generous: the machine is shared


def kill_when(process: subprocess.Popen, ready: Callable[[], bool], *, poll_s: float) -> None:
    """Waits until ``ready()`` holds (checked every ``poll_s`` seconds), the run ends or
    `RUN_TIMEOUT_S` pass, then kills the run's whole process group (started with
    ``start_new_session=True``) and asserts that SIGKILL ended it."""
    deadline = time.monotonic() + RUN_TIMEOUT_S
    try:
        while not ready() and process.poll() is None and time.monotonic() < deadline:
            time.sleep(poll_s)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)
        process.wait(timeout=RUN_TIMEOUT_S)
    assert process.returncode == -signal.SIGKILL, process.stderr.read().decode()[-2000:]
