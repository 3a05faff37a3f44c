"""The session check of `conftest.no_process_left_running`: it sees what a run left behind."""

from __future__ import annotations

import subprocess
import time

import leftover_processes
import pytest

pytestmark = pytest.mark.skipif(
    not leftover_processes.supported(), reason="lists processes through Linux /proc"
)


def test_an_orphan_of_a_stopped_wrapper_is_still_seen_and_stopped() -> None:
    # A wrapper that starts a long-lived program and exits, as a launcher script does: the
    # program outlives its parent and would be nobody's child but init's.
    assert leftover_processes.adopt_orphans()
    subprocess.run(["sh", "-c", "sleep 300 >/dev/null 2>&1 &"], check=True)
    time.sleep(0.2)
    left = [p for p in leftover_processes.descendants() if p.command == "sleep 300"]
    assert len(left) == 1 and "pid " in str(left[0])
    leftover_processes.stop(left, grace_s=5.0)
    assert not [p for p in leftover_processes.descendants() if p.command == "sleep 300"]


def test_a_finished_child_is_not_counted() -> None:
    subprocess.run(["sleep", "0"], check=True)
    assert not [p for p in leftover_processes.descendants() if p.command == "sleep 0"]
