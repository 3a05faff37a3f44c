"""``reform-sim data verify`` reports what killed runs left in the folder it checks: the temporary
file of a writer killed mid-write and a lock no run holds, never one that a live process holds.
Each writer and lock holder is a real process; the killed ones are killed with SIGKILL."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from cli_errors import run_cli
from quiet_generate import generate_quietly

pytestmark = [
    pytest.mark.faults,
    pytest.mark.skipif(os.name != "posix", reason="kills processes with SIGKILL"),
]

WAIT_S = 60.0  # seconds a child has to get to its write or its lock (the machine is shared)
# A child that starts an atomic write of ARGV[1] (or takes the lock of folder ARGV[1]), says so on
# stdout, and waits to be killed.
WRITER = (
    "import sys, time\n"
    "from reform.atomic import atomic_path\n"
    "with atomic_path(sys.argv[1]) as tmp:\n"
    "    tmp.write_bytes(b'half a shard' * 1000)\n"
    "    print(tmp.name, flush=True)\n"
    "    time.sleep(600)\n"
)
LOCKER = (
    "import sys, time\n"
    "from pathlib import Path\n"
    "from sim.generate import _folder_lock\n"
    "with _folder_lock(Path(sys.argv[1])):\n"
    "    print('locked', flush=True)\n"
    "    time.sleep(600)\n"
)


def _started(code: str, argument: Path) -> tuple[subprocess.Popen, str]:
    """A child running ``code`` on ``argument``, once it has said what it did."""
    child = subprocess.Popen(
        [sys.executable, "-c", code, str(argument)], stdout=subprocess.PIPE, text=True
    )
    said = child.stdout.readline().strip()
    assert said, "the child ended before it got to its write or its lock"
    return child, said


def _killed(code: str, argument: Path) -> str:
    child, said = _started(code, argument)
    child.send_signal(signal.SIGKILL)
    child.wait(timeout=WAIT_S)
    child.stdout.close()
    return said


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("leftovers") / "ds"
    generate_quietly("hri-conversation", out, episodes=1, seed=1, duration=2.0)
    return out


def test_data_verify_reports_what_killed_runs_left_and_nothing_live(dataset, capsys):
    shard = next(dataset.rglob("part.parquet"))
    temporary = shard.parent / _killed(WRITER, shard)
    _killed(LOCKER, dataset)
    live, live_name = _started(WRITER, dataset / "README.md")  # a run writing now: not a leftover
    try:
        status, out, err = run_cli(["data", "verify", "--data", dataset], capsys)
    finally:
        live.kill()
        live.wait(timeout=WAIT_S)
        live.stdout.close()
    assert status == 0, err
    pid = int(re.search(r"\.(\d+)@", temporary.name).group(1))
    assert out.splitlines() == [
        f"{temporary}: a leftover temporary file (11.7 KiB) of a killed run (process {pid} of this "
        f"machine, gone); the next write into {shard.parent} removes it",
        f"{dataset / '.generate.lock'}: a lock left by a run that did not finish (no run holds "
        "it); the next generate run in this folder takes it over",
        f"{dataset}: whole (every shard its card lists is there, unaltered); 2 leftover(s) of "
        "runs that did not finish, listed above",
    ]
    assert live_name not in out
    assert temporary.exists()  # reported, never removed by verify


def test_a_lock_a_live_run_holds_is_not_a_leftover(tmp_path, capsys):
    out = tmp_path / "ds"
    generate_quietly("hri-conversation", out, episodes=1, seed=1, duration=2.0)
    holder, _ = _started(LOCKER, out)
    try:
        status, printed, _ = run_cli(["data", "verify", "--data", out], capsys)
    finally:
        holder.kill()
        holder.wait(timeout=WAIT_S)
        holder.stdout.close()
    assert status == 0
    assert printed == f"{out}: whole (every shard its card lists is there, unaltered)\n"
