"""The studies' commands refuse bad input in one line, before any work: one table for
``reform-sim demo``, ``experiment hri`` and ``stress``."""

from __future__ import annotations

import pytest
from cli_errors import cli_error

DEMO = ["demo", "--quick", "--out", "OUT"]
HRI = ["experiment", "hri", "--out", "OUT"]
STRESS = ["stress", "--grid", "small", "--out", "OUT"]


@pytest.mark.parametrize(
    ("command", "argv", "message"),
    [
        pytest.param(DEMO, ["--seed", "-1"], "--seed must be >= 0, got -1", id="demo-seed"),
        pytest.param(DEMO, ["--jobs", "0"], "--jobs must be >= 1, got 0", id="demo-jobs"),
        pytest.param(
            DEMO,
            ["--data", "/nonexistent/datasets"],
            "/nonexistent/datasets is not a folder",
            id="demo-data",
        ),
        pytest.param(HRI, ["--views", "sonar"], "--views must name views among", id="hri-views"),
        pytest.param(HRI, ["--episodes", "0"], "--episodes must be >= 1, got 0", id="hri-episodes"),
        pytest.param(
            HRI,
            ["--data", "salsa=/nonexistent/salsa"],
            "SALSA not found at /nonexistent/salsa",
            id="hri-data",
        ),
        pytest.param(
            STRESS, ["--axes", "weather"], "--axes must name axes among", id="stress-axes"
        ),
        pytest.param(
            STRESS, ["--episodes", "0"], "--episodes must be >= 1, got 0", id="stress-episodes"
        ),
        pytest.param(
            STRESS,
            ["--save", "curves.txt"],
            "--save must be a path ending in .rrd",
            id="stress-save",
        ),
    ],
)
def test_bad_input_is_one_line(command, argv, message, tmp_path, capsys) -> None:
    out = str(tmp_path / "out")
    err = cli_error([out if word == "OUT" else word for word in command] + argv, capsys)
    assert message in err
