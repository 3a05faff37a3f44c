"""Long work is never silent, and what it says it will take is what it takes: a real
``reform-sim generate`` (worker processes, episodes), its stderr read as it comes, every piece
stamped with its time (a bar redraws with ``\\r``), checked for its longest silence and for its
estimate against the time the work then took.

The one figure the command's own start-up governs (imports before the first line) is held to a
looser bound here; `test_cli_startup.py` is about it."""

from __future__ import annotations

import io
import os
import re
import subprocess
import sys
import time
from pathlib import Path

from quiet_generate import generate_quietly

from sim.cli import main

SILENCE_S = 5.0  # seconds: the longest a running command may say nothing
START_S = 15.0  # seconds: the longest before its first line (imports, checks; a shared machine)
RATIO = 3.0  # an estimate is within this factor of the time measured
_UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0, "days": 86400.0}
# A detector that predicts its frames in one call, for 2.5 s (GTCG on SALSA: about a minute).
SLOW_PLUGIN = (
    "import time\n\n\nclass Slow:\n    def predict(self, frames):\n        time.sleep(2.5)\n"
    "        return [[(int(i),) for i in frame.ids] for frame in frames]\n\n\n"
    "def make():\n    return Slow()\n"
)
# Small, but large enough to start two worker processes and give each episodes.
GENERATE = ["generate", "--scenario", "mingle", "--episodes", "4", "--duration", "10"]


def _stamped(argv: list[str], cwd: Path) -> tuple[list[tuple[float, str]], float, int]:
    """The pieces of ``reform-sim argv``'s stderr with the seconds since its start at which each
    came, the seconds it ran and its exit status."""
    started = time.monotonic()
    process = subprocess.Popen(
        [sys.executable, "-m", "sim.cli", *argv],
        cwd=cwd,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        env=dict(os.environ, COLUMNS="120"),
    )
    pieces = []
    while chunk := os.read(process.stderr.fileno(), 65536):
        now = time.monotonic() - started
        text = chunk.decode(errors="replace")
        pieces += [(now, piece) for piece in re.split(r"[\r\n]", text) if piece.strip()]
    status = process.wait(timeout=120)
    return pieces, time.monotonic() - started, status


def _estimate_s(line: str) -> float:
    """The seconds an estimate line states (``about 3.2 s``, ``about 12 min``)."""
    value, unit = re.search(r"about ([\d.e+]+) (s|min|h|days)\b", line).groups()
    return float(value) * _UNITS[unit]


def test_generate_is_never_silent_and_its_estimate_holds(tmp_path):
    pieces, ran, status = _stamped([*GENERATE, "--jobs", "2", "--out", "g"], tmp_path)
    assert status == 0, pieces[-3:]
    times = [t for t, _ in pieces]
    gaps = [later - earlier for earlier, later in zip(times, [*times[1:], ran], strict=True)]
    print(f"first line at {times[0]:.1f} s, longest silence after it {max(gaps):.1f} s")
    assert times[0] <= START_S, pieces[:2]
    assert max(gaps) <= SILENCE_S, [(round(t, 1), p[:60]) for t, p in pieces]
    (said, line), *_ = [(t, p) for t, p in pieces if " about " in p]
    done = max(t for t, p in pieces if "4/4" in p)  # the bar full: every episode written
    estimate = _estimate_s(line)
    ratio = (done - said) / estimate
    print(f"estimated {estimate:.1f} s, took {done - said:.1f} s: ratio {ratio:.2f}")
    assert 1 / RATIO <= ratio <= RATIO, (line, done - said)


def test_no_estimate_when_nothing_is_left_to_do(tmp_path, capsys):
    argv = [*GENERATE[:4], "2", "--duration", "4", "--jobs", "1", "--out", str(tmp_path / "g")]
    assert main(argv) == 0
    assert " about " in capsys.readouterr().err  # the first run says what it will take
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert " about " not in err and "2/2" in err, err


class _Terminal(io.StringIO):
    """A stderr that is a terminal: short commands show their progress only on one."""

    def isatty(self) -> bool:
        return True


def test_a_detector_predicting_in_one_call_keeps_its_bar_moving(tmp_path, monkeypatch):
    (tmp_path / "slow.py").write_text(SLOW_PLUGIN)
    generate_quietly("hri-conversation", tmp_path / "ds", episodes=1, seed=1, duration=2.0)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "stderr", _Terminal())
    assert main(["evaluate", "--detector", "slow:make", "--data", "ds"]) == 0
    err = sys.stderr.getvalue()
    # Redrawn, its time moving, while predict had not yet returned a frame.
    assert re.search(r"running slow:make: +0%\|[^\r]*\| 0/\d+ \[00:0[2-9]<", err), err
    assert re.search(r"[\r\n]slow:make: \d+ frames in [\d.]+ s\n", err), err  # the bar cleared


def test_simulate_with_a_recording_keeps_its_bar_moving(tmp_path, monkeypatch):
    import sim.cli.simulate
    from sim.episode import simulate_episode

    def slow(*args, **kwargs):  # the episode in memory, as a long one takes seconds
        time.sleep(2.5)
        return simulate_episode(*args, **kwargs)

    monkeypatch.setattr(sim.cli.simulate, "simulate_episode", slow)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "stderr", _Terminal())
    argv = ["simulate", "--scenario", "hri-conversation", "--duration", "2", "--out", "a.parquet"]
    assert main([*argv, "--save", "a.rrd"]) == 0
    err = sys.stderr.getvalue()
    # Redrawn, its time moving, while the episode had not yet been simulated.
    assert re.search(r"simulate hri-conversation: +0%\|[^\r]*\| 0/\d+ \[00:0[2-9]<", err), err
    assert "wrote a.rrd" in err


def test_stage_lines_keep_the_time_moving_under_them(monkeypatch):
    from argparse import Namespace

    from sim.cli._grammar import stage_lines

    monkeypatch.setattr(sys, "stderr", _Terminal())
    with stage_lines(Namespace(quiet=False), "experiment x") as progress:
        progress("tuning")
        time.sleep(2.5)  # a stage that works without a word
    err = sys.stderr.getvalue()
    assert re.search(r"\[ +0\.\d s\] tuning\n", err), err
    assert "experiment x: 00:02 so far" in err, err
    monkeypatch.setattr(sys, "stderr", io.StringIO())  # a log: the lines alone
    with stage_lines(Namespace(quiet=False), "experiment x") as progress:
        progress("tuning")
    assert re.fullmatch(r"\[ +0\.\d s\] tuning\n", sys.stderr.getvalue())
