"""``reform-sim simulate`` streaming its frames to --out keeps its bar moving on a terminal while a
frame takes long (the first compiles the motion kernel: 10 s in a fresh clone on two busy cores);
a log gets the bar as before, drawn when a frame is done."""

from __future__ import annotations

import io
import re
import sys
import time

import pytest

import sim.cli.simulate
from sim.cli import main

ARGV = ["simulate", "--scenario", "hri-conversation", "--duration", "2", "--out", "a.parquet"]


class _Terminal(io.StringIO):
    """A stderr that is a terminal."""

    def isatty(self) -> bool:
        return True


@pytest.fixture
def slow_first_frame(tmp_path, monkeypatch):
    """``write_episode`` taking 2.5 s before its first frame, as a cold kernel does."""
    write_episode = sim.cli.simulate.write_episode

    def slow(*args, **kwargs):
        time.sleep(2.5)
        return write_episode(*args, **kwargs)

    monkeypatch.setattr(sim.cli.simulate, "write_episode", slow)
    monkeypatch.chdir(tmp_path)


def test_a_terminal_sees_the_bar_move_before_the_first_frame(slow_first_frame, monkeypatch):
    monkeypatch.setattr(sys, "stderr", _Terminal())
    assert main(ARGV) == 0
    err = sys.stderr.getvalue()
    assert re.search(r"simulate hri-conversation: +0%\|[^\r]*\| 0/\d+ \[00:0[2-9]<", err), err


def test_a_log_gets_no_redraw_before_the_first_frame(slow_first_frame, monkeypatch):
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    assert main(ARGV) == 0
    assert not re.search(r"\| 0/\d+ \[", sys.stderr.getvalue()), sys.stderr.getvalue()
