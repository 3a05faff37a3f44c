"""``reform-sim experiment temporal``: every detector's events, latency and flicker on the
default party and the real datasets, and the temporal filters' goal."""

from __future__ import annotations

import argparse

from sim.cli._common import add_jobs_argument
from sim.cli._experiment_io import add_out_argument
from sim.cli._grammar import add_quiet, add_seed, run_loading
from sim.cli._numbers import ascii_float, ascii_int
from sim.experiments.temporal import DURATION_S, EPISODES, RATE_HZ

DESCRIPTION = """\
Simulates the default party (mingle at its default options: --episodes episodes of --duration
seconds at --rate frames per second) and scores every catalogued detector that runs with its
defaults or learns on training frames, on the party and on every real dataset found (or given
with --data), per frame (P/R/F1) and in time (event recall and precision, latency, false events
per minute, identity switches; docs/guide/temporal.md), as `reform-sim benchmark --temporal`
does. Checks the temporal filters' goal on the party: false events per minute at most half the
wrapped detector's, at most 1 s added median latency, frame F1 at T = 2/3 not lower. Writes
DIR/temporal.md, DIR/temporal.json and DIR/temporal.png, and prints the Markdown.
"""

BASENAME = "temporal"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data",
        action="append",
        default=[],
        metavar="PATH|NAME",
        help="a real dataset (repeatable): a fetched or local dataset's name or its folder "
        "(default: every fetched or local dataset); --data none for the party alone",
    )
    parser.add_argument(
        "--detector",
        action="append",
        default=[],
        metavar="NAME",
        help="a catalogued detector (repeatable; default: every one that runs with its defaults "
        "or learns on training frames)",
    )
    parser.add_argument(
        "--episodes",
        type=ascii_int,
        default=EPISODES,
        metavar="N",
        help=f"party episodes ({EPISODES})",
    )
    parser.add_argument(
        "--duration",
        type=ascii_float,
        default=DURATION_S,
        metavar="S",
        help=f"seconds per party episode ({DURATION_S:g})",
    )
    parser.add_argument(
        "--rate",
        type=ascii_float,
        default=RATE_HZ,
        metavar="HZ",
        help=f"frames per second ({RATE_HZ:g})",
    )
    add_jobs_argument(parser)
    add_out_argument(parser, basename=BASENAME)
    add_seed(parser)
    add_quiet(parser)
    parser.set_defaults(handler=run_loading("sim.cli.experiment_temporal:run", "MuJoCo"))
