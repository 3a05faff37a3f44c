"""Ctrl-C: one line, exit status 130, no traceback (from ``reform-sim`` or its workers)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from sim.cli import _resumes, build_parser
from sim.cli._interrupt import POOL_MANAGER_THREAD, quiet_pool_manager

ROOT = Path(__file__).resolve().parents[3]
START = (
    "import sys; from sim.cli import console_main; sys.argv[0] = 'reform-sim'; "
    "sys.exit(console_main())"
)
WAIT_S = 60.0  # at most this long for the command to get going, and to stop

pytestmark = [
    pytest.mark.faults,
    pytest.mark.skipif(os.name != "posix", reason="sends SIGINT to a process group"),
]


@pytest.fixture(autouse=True)
def ctrl_c_as_a_terminal_sends_it():
    """SIGINT not ignored, as in a terminal. A suite started in the background by a shell
    without job control (``make test &``, some CI runners) inherits SIGINT ignored, and so
    would the command under test: Ctrl-C would then never reach it."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def _interrupt(
    argv: list[str], tmp_path: Path, *, started: Callable[[str], bool], start: str = START
) -> tuple[int, str]:
    """Runs ``reform-sim argv`` in its own process group, waits until ``started(stderr so far)``
    holds, and sends SIGINT to the whole group, as Ctrl-C in a terminal does.

    Returns:
        The exit status and the whole stderr.
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
    try:
        deadline = time.monotonic() + WAIT_S
        while process.poll() is None and not started(log.read_text()):
            assert time.monotonic() < deadline, log.read_text()
            time.sleep(0.05)
        assert process.poll() is None, f"the command ended before Ctrl-C: {log.read_text()}"
        os.killpg(process.pid, signal.SIGINT)
        status = process.wait(timeout=WAIT_S)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    return status, log.read_text()


def test_generate_interrupted_says_run_again_to_resume(tmp_path):
    out = tmp_path / "synthetic"
    argv = ["generate", "--scenario", "mingle", "--episodes", "400", "--seed", "0"]
    argv += ["--duration", "20", "--jobs", "2", "--quiet", "--out", str(out)]
    status, err = _interrupt(argv, tmp_path, started=lambda _: any(out.rglob("part.parquet")))
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert err.strip().splitlines() == [
        "reform-sim generate: interrupted; run the same command again to resume"
    ]
    assert status == 130


def test_stress_interrupted_in_one_line(tmp_path):
    argv = ["stress", "--grid", "small", "--jobs", "2", "--out", str(tmp_path / "s")]
    status, err = _interrupt(argv, tmp_path, started=lambda err: "training REFORM" in err)
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert err.strip().splitlines()[-1] == "reform-sim stress: interrupted"
    assert status == 130


def test_main_called_from_python_lets_ctrl_c_reach_its_caller(tmp_path):
    """A script calling `sim.cli.main` stops on Ctrl-C like on any call: KeyboardInterrupt."""
    out = tmp_path / "synthetic"
    script = (
        "import sys\nfrom sim.cli import main\n"
        "try:\n    main(sys.argv[1:])\n"
        "except KeyboardInterrupt:\n"
        "    print('KeyboardInterrupt reached the caller', file=sys.stderr)\n"
        "    sys.exit(7)\n"
        "print('the script went on', file=sys.stderr)\n"
    )
    argv = ["generate", "--scenario", "mingle", "--episodes", "400", "--seed", "0"]
    argv += ["--duration", "20", "--jobs", "2", "--quiet", "--out", str(out)]
    started = lambda _: any(out.rglob("part.parquet"))  # noqa: E731
    status, err = _interrupt(argv, tmp_path, started=started, start=script)
    assert err.strip().splitlines()[-1] == "KeyboardInterrupt reached the caller", err
    assert status == 7


def test_which_commands_say_they_resume():
    parser = build_parser()
    argv = {
        "generate": ["--scenario", "m", "--episodes", "1", "--seed", "0", "--out", "x"],
        "demo": [],
        "stress": [],
        "simulate": ["--scenario", "m", "--seed", "0", "--out", "x.parquet"],
    }
    said = {name: _resumes(parser.parse_args([name, *words])) for name, words in argv.items()}
    assert said == {"generate": True, "demo": True, "stress": False, "simulate": False}
    sim2real = parser.parse_args(["experiment", "sim2real", "--out", "x"])
    paper = parser.parse_args(["experiment", "paper", "--out", "x"])
    assert (_resumes(sim2real), _resumes(paper)) == (True, False)


def test_a_detector_waiting_in_a_system_call_is_interrupted(tmp_path, shared_datasets):
    """Ctrl-C while a researcher's detector sleeps (or waits on a socket, a lock): the main
    thread is woken, and the command stops in one line."""
    (tmp_path / "sleepy.py").write_text(
        "import sys, time\n\n"
        "class Sleepy:\n"
        "    def predict(self, frames):\n"
        "        print('asleep', file=sys.stderr, flush=True)\n"
        "        time.sleep(3600)\n"
    )
    start = f"import sys; sys.path.insert(0, {str(tmp_path)!r}); " + START
    argv = ["evaluate", "--detector", "sleepy:Sleepy", "--data", str(shared_datasets / "synth")]
    status, err = _interrupt(argv, tmp_path, started=lambda e: "asleep" in e, start=start)
    assert "Traceback" not in err, err
    assert err.strip().splitlines()[-1] == "reform-sim evaluate: interrupted"
    assert status == 130


def test_a_waker_scheduled_late_does_not_end_the_process():
    """The thread that wakes the main thread on a signal may run late on a busy machine, after
    the command has already stopped: its SIGUSR1 must not then find SIGUSR1's default (which
    ends the process without a word) in place."""
    code = (
        "import signal, sys, time\n"
        "import sim.cli._interrupt as interrupt\n"
        "wake = interrupt._wake\n"
        "def late(reader, main):\n"
        "    time.sleep(0.3)  # scheduled late\n"
        "    wake(reader, main)\n"
        "interrupt._wake = late\n"
        "try:\n"
        "    with interrupt.sigterm_stops(), interrupt.sigint_to_main_only():\n"
        "        signal.raise_signal(signal.SIGTERM)\n"
        "        time.sleep(5.0)\n"
        "except interrupt.Stopped:\n"
        "    time.sleep(0.5)\n"
        "    print('stopped', signal.getsignal(signal.SIGUSR1) is signal.SIG_DFL)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=WAIT_S
    )
    assert (done.returncode, done.stdout, done.stderr) == (0, "stopped True\n", "")


def _printed_by_thread(name: str, capsys) -> str:
    def fail() -> None:
        raise KeyError(7)

    thread = threading.Thread(target=fail, name=name)
    thread.start()
    thread.join()
    return capsys.readouterr().err


def test_once_stopping_the_pool_managers_exception_is_not_printed(monkeypatch, capsys):
    monkeypatch.setattr(threading, "excepthook", threading.__excepthook__)
    assert "KeyError: 7" in _printed_by_thread(POOL_MANAGER_THREAD, capsys)  # before a stop
    quiet_pool_manager()
    quiet_pool_manager()  # a second stop: one filter
    assert _printed_by_thread(POOL_MANAGER_THREAD, capsys) == ""
    assert "KeyError: 7" in _printed_by_thread("reform-sim-other", capsys)
