"""``reform-sim scenarios``: the registered scenarios, what they are and their typed options."""

from __future__ import annotations

import argparse

from sim.cli._common import run_with

DESCRIPTION = """\
Lists the registered scenarios with a line on each and their options (name, type, default,
meaning). Set options with `reform-sim simulate --set KEY=VALUE`.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("names", nargs="*", metavar="NAME", help="only these scenarios")
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")
    parser.set_defaults(handler=run_with("sim.cli.scenarios:run"))
