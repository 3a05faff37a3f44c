"""Deadlines on a detector's code: a plugin whose module import, factory or ``predict`` never
returns ends ``detect``, ``evaluate`` and ``benchmark`` with one line naming the detector, what it
was doing (the frame and the data, for ``predict``) and the deadline, within that deadline plus
10 s; a deadline that is not a duration above zero is one line before any work. The plugins are
``module:factory`` paths in the current folder; ``detect`` runs in a process of its own."""

from __future__ import annotations

import importlib
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from cli_errors import cli_error, run_cli
from killed_run import CLI
from quiet_generate import generate_quietly

from reform.deadline import STUCK_GRACE_S, DeadlineExpired, duration, within
from sim.cli import main

pytestmark = pytest.mark.faults  # the fault suite: pytest -m faults

DEADLINE_S = 0.5  # seconds: the deadline the tests give (4 frames: 2 s to predict them)
SLACK_S = 10.0  # seconds a command may take beyond its deadline (start-up included)
HINT = "give it longer with --detector-timeout DURATION"
PLUGINS = {
    # busy in Python while its module is imported
    "stuck_at_import": "while True:\n    pass\n\n\ndef make():\n    return None\n",
    "stuck_in_factory": "import time\n\n\ndef make():\n    time.sleep(3600)\n",
    # answers two frames, then waits for ever on the third
    "stuck_in_predict": (
        "import time\n\n\nclass Stuck:\n    def predict(self, frames):\n        out = []\n"
        "        for k, frame in enumerate(frames):\n            if k == 2:\n"
        "                while True:\n                    time.sleep(1)\n"
        "            out.append([(int(i),) for i in frame.ids])\n        return out\n\n\n"
        "def make():\n    return Stuck()\n"
    ),
}
# Waits for ever in compiled code, holding the interpreter: a mutex locked twice by one thread
# (a deadlock no signal interrupts), through ctypes.PyDLL, which keeps the interpreter's lock.
STUCK_IN_C = (
    "import ctypes\n\n\nclass Stuck:\n    def predict(self, frames):\n"
    "        libc = ctypes.PyDLL(None)\n        mutex = ctypes.create_string_buffer(64)\n"
    "        libc.pthread_mutex_lock(mutex)\n        libc.pthread_mutex_lock(mutex)\n\n\n"
    "def make():\n    return Stuck()\n"
)
CONSOLE = [
    sys.executable,
    "-c",
    "import sys; from sim.cli import console_main; sys.exit(console_main())",
]
# What each line says after "reform-sim COMMAND: error: " (a regular expression).
MESSAGES = {
    "stuck_at_import": (
        r"detector 'stuck_at_import:make': the detector did not finish within 0.5 s \(import of "
        r"module 'stuck_at_import'\); "
    ),
    "stuck_in_factory": (
        r"detector 'stuck_in_factory:make': the detector did not finish within 0.5 s \(build: its "
        r"factory stuck_in_factory:make\); "
    ),
    "stuck_in_predict": (
        r"stuck_in_predict:make: the detector did not finish within 2 s \(predict on frame 2 "
        r"\(hri-conversation-0 t=\S+ s\) of ds, 4 frames in one call\); "
    ),
}


@pytest.fixture(scope="module")
def lab(tmp_path_factory) -> Path:
    """A folder holding the plugins and a tiny generated dataset (``ds``, 4 frames)."""
    root = tmp_path_factory.mktemp("detector-deadline")
    for module, source in {**PLUGINS, "stuck_in_c": STUCK_IN_C}.items():
        (root / f"{module}.py").write_text(source)
    generate_quietly("hri-conversation", root / "ds", episodes=1, seed=1, duration=2.0)
    return root


@pytest.mark.parametrize("plugin", list(PLUGINS))
def test_a_detector_that_never_returns_ends_detect_within_its_deadline(lab, plugin):
    started = time.monotonic()
    run = subprocess.run(
        [*CLI, "detect", "--detector", f"{plugin}:make", "--data", "ds", "--out", "out.json"]
        + ["--detector-timeout", f"{DEADLINE_S:g}s"],
        cwd=lab,
        capture_output=True,
        text=True,
        timeout=DEADLINE_S * 4 + SLACK_S + 30,  # a hang fails the test, not the suite
    )
    seconds = time.monotonic() - started
    assert run.returncode == 2
    pattern = f"reform-sim detect: error: {MESSAGES[plugin]}{re.escape(HINT)}\n"
    assert re.fullmatch(pattern, run.stderr), run.stderr
    assert seconds < 4 * DEADLINE_S + SLACK_S
    assert not (lab / "out.json").exists()


@pytest.mark.parametrize(
    ("command", "status"),
    [
        (["detect", "--out", "out.json"], -signal.SIGKILL),  # in the command's own process
        # in a worker process, the other detector in the other worker
        (["benchmark", "--detector", "majority", "--jobs", "2", "--out", "out", "--quiet"], 2),
    ],
    ids=["detect", "benchmark-workers"],
)
def test_a_detector_stuck_in_compiled_code_is_ended_with_its_process_in_one_line(
    lab, command, status
):
    """No signal handler runs while compiled code holds the interpreter: the deadline's watcher
    process ends the process STUCK_GRACE_S after the deadline, and the command says one line."""
    started = time.monotonic()
    run = subprocess.run(
        [*CONSOLE, *command, "--detector", "stuck_in_c:make", "--data", "ds"]
        + ["--detector-timeout", f"{DEADLINE_S:g}s"],
        cwd=lab,
        capture_output=True,
        text=True,
        timeout=DEADLINE_S * 4 + STUCK_GRACE_S + SLACK_S + 30,
    )
    seconds = time.monotonic() - started
    assert run.returncode == status, (run.returncode, run.stderr)
    pattern = (
        rf"reform-sim {command[0]}: error: stuck_in_c:make: predict on 4 frame\(s\) of ds did not "
        rf"finish within 2 s and had not returned to Python {STUCK_GRACE_S:g} s later \(stuck in "
        r"compiled code, where it cannot be stopped\): the process was ended; "
        + re.escape(HINT)
        + "\n"
    )
    assert re.fullmatch(pattern, run.stderr), run.stderr
    assert 4 * DEADLINE_S + STUCK_GRACE_S - 1 < seconds < 4 * DEADLINE_S + STUCK_GRACE_S + SLACK_S
    assert not (lab / "out.json").exists() and not (lab / "out").exists()


def test_predict_past_its_deadline_ends_benchmark_in_one_line(lab, capsys, monkeypatch):
    """In the benchmark's own process (``evaluate`` runs a detector as ``detect`` does)."""
    command = "benchmark"
    monkeypatch.chdir(lab)
    monkeypatch.syspath_prepend(str(lab))
    importlib.import_module(f"sim.cli.{command}")  # its imports are not the deadline's time
    extra = ["--out", lab / "bench", "--quiet", "--no-recordings"]
    started = time.monotonic()
    line = cli_error(
        [command, "--detector", "stuck_in_predict:make", "--data", "ds", *extra]
        + ["--detector-timeout", f"{DEADLINE_S:g}s"],
        capsys,
    )
    assert time.monotonic() - started < 4 * DEADLINE_S + SLACK_S
    assert re.fullmatch(
        f"reform-sim {command}: error: {MESSAGES['stuck_in_predict']}{re.escape(HINT)}", line
    ), line


def test_predict_past_its_deadline_ends_stress_in_one_line(lab, capsys, monkeypatch):
    """In a worker of the stress tests (one dropout level, one short episode of 20 frames)."""
    monkeypatch.chdir(lab)
    monkeypatch.syspath_prepend(str(lab))
    started = time.monotonic()
    status, _, err = run_cli(
        ["stress", "--grid", "small", "--episodes", "1", "--axes", "dropout", "--jobs", "1"]
        + ["--detector", "stuck_in_predict:make", "--detector-timeout", "0.1", "--out", "st"]
        + ["--quiet"],
        capsys,
    )
    assert time.monotonic() - started < 20 * 0.1 + SLACK_S + 20.0  # its episode simulated first
    assert status == 2
    estimate, line = err.strip().splitlines()  # the stated estimate, then the error
    assert estimate.startswith("the stress test: about "), estimate
    assert re.fullmatch(
        r"reform-sim stress: error: stuck_in_predict:make: the detector did not finish within "
        r"2 s \(predict .*\); " + re.escape(HINT),
        line,
    ), line


@pytest.mark.parametrize("command", ["detect", "evaluate", "benchmark", "stress"])
@pytest.mark.parametrize("value", ["0", "-2", "0s", "soon", "2 hours", "1" + "0" * 30, "\u0663"])
def test_a_deadline_that_is_not_a_duration_above_zero_is_one_line_before_any_work(
    command, value, capsys, tmp_path
):
    data = [] if command == "stress" else ["--data", str(tmp_path / "none")]
    with pytest.raises(SystemExit) as exit_info:
        main([command, "--detector", "majority", *data, f"--detector-timeout={value}"])
    assert exit_info.value.code == 2
    line = capsys.readouterr().err
    assert line.count("\n") == 1
    assert line.startswith(
        f"reform-sim {command}: error: argument --detector-timeout: expected a duration above "
        f"zero and at most 30 days (seconds, or with a unit: 90s, 2m, 500ms), got {value!r}"
    )


@pytest.mark.parametrize(
    ("text", "seconds"),
    [("30", 30.0), ("1.5", 1.5), ("90s", 90.0), ("2m", 120.0), ("500ms", 0.5), (" 3 s ", 3.0)],
)
def test_durations(text, seconds):
    assert duration(text) == seconds


def _held_forever(where: list[str]) -> None:
    what = "the call held this"  # noqa: F841 - what the expired deadline's stack shows
    where.append(threading.current_thread().name)
    time.sleep(3600)


@pytest.mark.parametrize("in_main_thread", [True, False], ids=["main-thread", "other-thread"])
def test_within_stops_a_call_at_its_deadline_and_shows_what_it_held(in_main_thread):
    caught: list[BaseException] = []
    where: list[str] = []

    def call() -> None:
        try:
            within(0.2, _held_forever, where)
        except DeadlineExpired as exc:
            caught.append(exc)

    if in_main_thread:
        call()
    else:
        thread = threading.Thread(target=call, name="caller")
        thread.start()
        thread.join(10)
    (expired,) = caught
    assert expired.seconds == 0.2
    assert any(f.f_locals.get("what") == "the call held this" for f in expired.stack)
    assert (where[0] == "MainThread") is in_main_thread
    assert within(0.2, sum, [1, 2]) == 3  # a call in time returns its value
