"""The demo's stages keep a line with their time moving under them on a terminal while they work
without a bar of their own (the stress test's episodes and plots: 4 to 15 s on two busy cores);
a log gets the stage lines alone, as before."""

from __future__ import annotations

import io
import re
import sys
import time

from sim.experiments.demo import _say, _Stages


class _Terminal(io.StringIO):
    """A stderr that is a terminal."""

    def isatty(self) -> bool:
        return True


def _two_stages(*, working: bool) -> None:
    stages = _Stages(2, _say, show=True)
    try:
        stages.begin("stress", "stress tests", working=working)
        time.sleep(2.5)  # a stage that works without a word
        stages.begin("report", "writing the report")
    finally:
        stages.end()


def test_a_stage_keeps_its_time_moving_on_a_terminal(monkeypatch):
    monkeypatch.setattr(sys, "stderr", _Terminal())
    _two_stages(working=True)
    err = sys.stderr.getvalue()
    assert re.search(r"\[1/2\] stress tests  \(at 0 s\)\n", err), err
    assert "[1/2] stress: 00:02 so far" in err, err
    assert re.search(r"\[2/2\] writing the report  \(at \d s\)\n", err), err


def test_a_stage_printing_past_the_bars_draws_no_time(monkeypatch):
    monkeypatch.setattr(sys, "stderr", _Terminal())
    _two_stages(working=False)
    assert "[1/2] stress:" not in sys.stderr.getvalue()


def test_a_log_gets_the_stage_lines_alone(monkeypatch):
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    _two_stages(working=True)
    assert re.fullmatch(
        r"\[1/2\] stress tests  \(at 0 s\)\n\[2/2\] writing the report  \(at \d s\)\n",
        sys.stderr.getvalue(),
    )
