"""The tables the reports share (sim.experiments.tables): percentages and the command block."""

from __future__ import annotations

import math

from sim.experiments.tables import command_block, percent


def test_percent_and_command_block() -> None:
    assert percent(0.8125) == "81.2" and percent(1.0) == "100.0"
    for missing in (None, math.nan, math.inf):
        assert percent(missing) == "-"
        assert percent(missing, missing="—") == "—"
    assert command_block("reform-sim stress") == [
        "Produced by:",
        "",
        "```sh",
        "reform-sim stress",
        "```",
        "",
    ]
