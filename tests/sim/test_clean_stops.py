"""A command stopped by SIGTERM, or killed outright, leaves no worker process running: real
``reform-sim`` commands with two local workers, real signals to the command's process alone (as
``kill PID`` sends them), and the processes below it listed before and looked for after."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import psutil
import pytest

ROOT = Path(__file__).resolve().parents[2]
START = (
    "import sys; from sim.cli import console_main; sys.argv[0] = 'reform-sim'; "
    "sys.exit(console_main())"
)
WAIT_S = 120.0  # at most this long for the command to get going (the machine is shared)
GONE_S = 5.0  # its workers must be gone this soon after it ended

pytestmark = [
    pytest.mark.faults,
    pytest.mark.skipif(os.name != "posix", reason="sends POSIX signals"),
]


def _below(process: psutil.Process) -> list[psutil.Process]:
    """The live (not zombie) processes below ``process``."""
    found = []
    for child in process.children(recursive=True):
        with contextlib.suppress(psutil.Error):
            if child.status() != psutil.STATUS_ZOMBIE:
                found.append(child)
    return found


def _alive(processes: list[psutil.Process]) -> list[str]:
    """Those of ``processes`` still running (same process, not a reused id), as text."""
    left = []
    for process in processes:
        with contextlib.suppress(psutil.Error):
            if process.is_running() and process.status() != psutil.STATUS_ZOMBIE:
                left.append(f"{process.pid}: {' '.join(process.cmdline())[:120]}")
    return left


def _stop(
    argv: list[str],
    tmp_path: Path,
    sig: signal.Signals,
    *,
    started: Callable[[], bool],
    start: str = START,
) -> tuple[int, str, list[str]]:
    """Runs ``reform-sim argv``, waits until ``started()`` holds and two workers run below it,
    sends ``sig`` to the command's process alone, and waits for it to end.

    Returns:
        Its exit status, its whole stderr, and the processes that were below it and still run
        `GONE_S` seconds after it ended (each as ``pid: command line``).
    """
    log = tmp_path / "stderr.txt"
    with log.open("w") as err:
        process = subprocess.Popen(
            [sys.executable, "-c", start, *argv],
            cwd=ROOT,
            stdout=subprocess.DEVNULL,
            stderr=err,
            start_new_session=True,
        )
    command = psutil.Process(process.pid)
    below: list[psutil.Process] = []
    try:
        deadline = time.monotonic() + WAIT_S
        while process.poll() is None:
            below = _below(command)
            workers = [p for p in below if "LokyProcess" in " ".join(p.cmdline())]
            if len(workers) == 2 and started():
                break
            assert time.monotonic() < deadline, log.read_text()
            time.sleep(0.05)
        assert process.poll() is None, f"the command ended before {sig.name}: {log.read_text()}"
        os.kill(process.pid, sig)
        status = process.wait(timeout=WAIT_S)
        deadline = time.monotonic() + GONE_S
        while _alive(below) and time.monotonic() < deadline:
            time.sleep(0.1)
        return status, log.read_text(), _alive(below)
    finally:
        for leftover in [command, *below]:
            with contextlib.suppress(psutil.Error):
                leftover.kill()
        process.wait()


def _generate(out: Path) -> list[str]:
    argv = ["generate", "--scenario", "mingle", "--episodes", "400", "--seed", "0"]
    return [*argv, "--duration", "20", "--jobs", "2", "--quiet", "--out", str(out)]


def test_sigterm_stops_generate_and_its_workers_and_says_how_to_resume(tmp_path):
    out = tmp_path / "synthetic"
    status, err, left = _stop(
        _generate(out), tmp_path, signal.SIGTERM, started=lambda: any(out.rglob("part.parquet"))
    )
    assert left == []
    assert err.strip().splitlines() == [
        "reform-sim generate: stopped by SIGTERM; run the same command again to resume"
    ]
    assert status == 128 + signal.SIGTERM
    shards = sorted(out.rglob("part.parquet"))
    time.sleep(1.0)  # nothing goes on writing once the command has ended
    assert sorted(out.rglob("part.parquet")) == shards


def test_workers_end_when_generate_is_killed_outright(tmp_path):
    out = tmp_path / "synthetic"
    status, _, left = _stop(
        _generate(out), tmp_path, signal.SIGKILL, started=lambda: any(out.rglob("part.parquet"))
    )
    assert status == -signal.SIGKILL
    assert left == []


def test_sigterm_stops_stress_and_its_workers(tmp_path):
    argv = ["stress", "--grid", "small", "--jobs", "2", "--out", str(tmp_path / "s")]
    log = tmp_path / "stderr.txt"
    status, err, left = _stop(
        argv, tmp_path, signal.SIGTERM, started=lambda: "training REFORM" in log.read_text()
    )
    assert left == []
    assert "Traceback" not in err, err
    # Both at once, with the whole stderr: a stop that went otherwise shows how (its status).
    last = err.strip().splitlines()[-1]
    assert (status, last) == (128 + signal.SIGTERM, "reform-sim stress: stopped by SIGTERM"), err


def test_a_killed_simulates_recording_is_removed_by_the_next_run_there(tmp_path):
    """``simulate --save`` killed while it writes its recording leaves a hidden temporary file
    (tens of megabytes on a long episode); the next run writing in that folder removes it."""
    argv = ["simulate", "--scenario", "mingle", "--seed", "0", "--duration", "3600"]
    process = subprocess.Popen(
        [sys.executable, "-c", START, *argv, "--out", "long.parquet", "--save", "long.rrd"],
        cwd=tmp_path,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )

    def writing() -> bool:
        return any(p.stat().st_size > 0 for p in tmp_path.glob(".long.rrd.*.tmp"))

    try:
        deadline = time.monotonic() + WAIT_S
        while not writing():
            assert process.poll() is None, "simulate ended before it was killed"
            assert time.monotonic() < deadline, "simulate did not start its recording"
            time.sleep(0.05)
    finally:
        process.kill()
        process.wait()
    assert [p.name for p in tmp_path.glob(".*.tmp")] != []  # left behind
    argv = ["simulate", "--scenario", "mingle", "--seed", "0", "--duration", "5"]
    subprocess.run(
        [sys.executable, "-c", START, *argv, "--out", "short.parquet", "--save", "short.rrd"],
        cwd=tmp_path,
        check=True,
        capture_output=True,
        timeout=WAIT_S,
    )
    left = sorted(p.name for p in tmp_path.iterdir())
    assert {"short.parquet", "short.rrd"} <= set(left)
    assert [name for name in left if name.startswith(".")] == []


def test_sigterm_stops_benchmark_and_its_workers(tmp_path):
    """Two workers each in a detector's predict that would sleep ten minutes."""
    from quiet_generate import generate_quietly

    (tmp_path / "sleepy.py").write_text(
        "import time\n\n\nclass Sleepy:\n    def predict(self, frames):\n"
        "        time.sleep(600)\n\n\ndef make():\n    return Sleepy()\n"
    )
    for k in (1, 2):
        generate_quietly("hri-conversation", tmp_path / f"ds{k}", episodes=1, seed=k, duration=5.0)
    argv = ["benchmark", "--data", str(tmp_path / "ds1"), "--data", str(tmp_path / "ds2")]
    argv += ["--detector", "sleepy:make", "--jobs", "2", "--quiet", "--out", str(tmp_path / "b")]
    start = f"import sys; sys.path.insert(0, {str(tmp_path)!r}); " + START
    status, err, left = _stop(argv, tmp_path, signal.SIGTERM, started=lambda: True, start=start)
    assert left == []
    assert err.strip().splitlines() == ["reform-sim benchmark: stopped by SIGTERM"]
    assert status == 128 + signal.SIGTERM
