"""``benchmarks/documented_commands.py`` measures what its table says: a command's exit, its longest
silence (start and exit included, a bar's redraw a line), a refusal the page shows passed and
one it does not failed, a command over its time stopped and never passed.

Its ``--quick`` run (the README's commands: minutes) is too long for the tests; these run a few
shell lines of a second or two through the same function."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REFUSAL = "reform-sim data: error: broken/features.mat: frame 1, row 2: field 'ID': expected"


@pytest.fixture
def script(documented_commands):
    return documented_commands


def _run(script, command: str, tmp_path: Path, *, timeout: float = 30.0):
    return script.run_command(
        command, cwd=tmp_path, env={"PATH": os.environ["PATH"]}, timeout=timeout
    )


def test_the_longest_silence_counts_redraws_and_the_wait_for_the_exit(script, tmp_path):
    # 0.3 s to a redraw, 0.3 s to the next line, then 1.2 s silent before the exit.
    outcome = _run(script, "sleep 0.3; printf 'bar\\r'; sleep 0.3; echo done; sleep 1.2", tmp_path)
    assert (outcome.exit, outcome.last_line) == (0, "done")
    assert 1.1 <= outcome.silence <= 2.5 and outcome.seconds >= outcome.silence
    assert outcome.quiet_after == "done"  # the line the silence followed
    assert script.verdict(outcome, None) == ("passed", True)


def test_the_line_before_the_longest_silence_is_named(script, tmp_path):
    outcome = _run(script, "echo one; echo two; sleep 1.5; echo three; sleep 0.2", tmp_path)
    assert outcome.quiet_after == "two" and outcome.silence >= 1.4
    outcome = _run(script, "sleep 1.5; echo only", tmp_path)
    assert outcome.quiet_after == ""  # silent from the start


def test_a_refusal_passes_only_where_the_page_shows_one(script, tmp_path):
    outcome = _run(
        script, 'echo "reform-sim data: error: x/: no such folder" >&2; exit 2', tmp_path
    )
    assert outcome.exit == 2
    assert script.verdict(outcome, REFUSAL) == ("refused as the page shows", True)
    assert script.verdict(outcome, None) == (
        "failed: reform-sim data: error: x/: no such folder",
        False,
    )
    other = REFUSAL.replace("reform-sim data", "reform-sim stress")
    assert not script.verdict(outcome, other)[1]


def test_a_command_over_its_time_is_stopped_and_timed_out(script, tmp_path):
    outcome = _run(script, "echo started; sleep 60", tmp_path, timeout=1.0)
    assert outcome.exit is None and 1.0 <= outcome.seconds < 10.0
    assert script.verdict(outcome, None) == ("timed out", False)
