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


def test_the_runs_own_resource_tracker_ends_with_it_and_any_other_process_is_counted() -> None:
    from joblib import Parallel, delayed

    assert Parallel(n_jobs=2, backend="loky")(delayed(abs)(k) for k in (-1, -2)) == [1, 2]
    leftover_processes.end_helpers()  # the workers stop; loky's tracker is left to end with us
    own = leftover_processes.own_trackers()
    commands = {p.pid: p.command for p in leftover_processes.descendants()}
    assert any("loky.backend.resource_tracker" in commands.get(pid, "") for pid in own)
    other = subprocess.Popen(["sleep", "300"])
    try:
        left = {p.pid for p in leftover_processes.left_running(grace_s=0.5)}
        assert other.pid in left and not left & own  # sleep is counted, the tracker is not
    finally:
        other.kill()
        other.wait()
