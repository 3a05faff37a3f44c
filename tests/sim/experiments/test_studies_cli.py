"""The studies' commands refuse bad input in one line, before any work: one table for
``reform-sim demo``, ``experiment hri`` and ``stress``."""

from __future__ import annotations

import shlex

import pytest
from cli_errors import cli_error

COMMANDS = {
    "demo": "demo --quick --out OUT",
    "hri": "experiment hri --out OUT",
    "stress": "stress --grid small --out OUT",
}
# (command, its bad options, a part of the one-line error), named command-option.
BAD_INPUT = [
    ("demo", "--jobs 0", "--jobs must be >= 1, got 0"),
    ("demo", "--data /nonexistent/datasets", "/nonexistent/datasets is not a folder"),
    ("hri", "--views sonar", "--views must name views among"),
    ("hri", "--episodes 0", "--episodes must be >= 1, got 0"),
    ("hri", "--data salsa=/nonexistent/salsa", "SALSA not found at /nonexistent/salsa"),
    ("stress", "--axes weather", "--axes must name axes among"),
    ("stress", "--episodes 0", "--episodes must be >= 1, got 0"),
    ("stress", "--episodes 2000000", "--episodes must be at most 1,000,000, got 2,000,000"),
    ("stress", "--axes density,density", "--axes names density twice"),
    ("stress", "--save curves.txt", "--save must be a path ending in .rrd"),
]


@pytest.mark.parametrize(
    ("command", "options", "message"),
    BAD_INPUT,
    ids=[f"{command}-{options.split()[0][2:]}" for command, options, _ in BAD_INPUT],
)
def test_bad_input_is_one_line(command, options, message, tmp_path, capsys) -> None:
    argv = shlex.split(COMMANDS[command]) + shlex.split(options)
    err = cli_error([str(tmp_path / "out") if word == "OUT" else word for word in argv], capsys)
    assert message in err
