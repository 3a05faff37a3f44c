"""The tables the reports share (sim.experiments.tables): percentages, the command block and a
page's Markdown table."""

from __future__ import annotations

import math

from sim.experiments.tables import command_block, markdown_table, percent


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


def test_markdown_table_is_the_table_then_a_blank_line() -> None:
    lines = [
        "## Scores",
        "",
        *markdown_table(["detector", "F1"], [["gcff", "81.2"], ["reform", "9.0"]]),
    ]
    assert "\n".join(lines) == (
        "## Scores\n"
        "\n"
        "| detector |   F1 |\n"
        "|:---------|-----:|\n"
        "| gcff     | 81.2 |\n"
        "| reform   |  9.0 |\n"
    )
