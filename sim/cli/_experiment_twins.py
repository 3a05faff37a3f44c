"""``reform-sim experiment twins``: venue twins against every real dataset found."""

from __future__ import annotations

import argparse

from sim.cli._common import run_with
from sim.cli._experiment_io import add_out_argument
from sim.cli._grammar import add_quiet, add_seed

DESCRIPTION = """\
For every real dataset found: fits its label-free venue twin (`reform-sim twin`), generates the
twin's data (under --twins, default DIR/twins, reused), and measures, on the second half of
each recording, (1) tuning: GCFF, the proximity baseline and REFORM with one setting for every
dataset, tuned on the twin, and tuned on the first half's labels (the ceiling); (2) prediction:
every catalogued detector's F1 on the twin against its real F1 (Pearson r, Spearman, Kendall's
tau, mean absolute error, mean maximum rank violation, with bootstrap intervals), beside the
real ceiling (the first half predicting the second); (3) leave one out. The whole experiment
runs --repeats times, with master seeds S, S+1, ...: the tables are seed S's, the goals the mean
over the seeds, with their range. Writes DIR/twins.md, DIR/twins.json and DIR/twins.png, and
prints the Markdown.
"""

BASENAME = "twins"
TWINS = "twins"  # the twins' folder in --out, when --twins is not given
REPEATS = 3  # master seeds the experiment runs with, by default
MAX_REPEATS = 20  # most seeds one run takes (each about 4 minutes on two cores)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data",
        action="append",
        default=[],
        metavar="PATH|NAME",
        help="a real dataset (repeatable): NAME=PATH, a fetched or local dataset's name or its "
        "folder (default: every fetched or local dataset)",
    )
    add_out_argument(parser, basename=BASENAME)
    parser.add_argument(
        "--twins",
        default=None,
        metavar="DIR",
        help=f"folder of the twins and their generated data, reused when present (default: "
        f"OUT/{TWINS})",
    )
    add_seed(parser)
    parser.add_argument(
        "--repeats",
        type=int,
        default=REPEATS,
        metavar="N",
        help=f"run the whole experiment with N master seeds, S to S+N-1 (1-{MAX_REPEATS}; "
        f"default {REPEATS}); the twins of seed S+k are under --twins/seed-(S+k)",
    )
    add_quiet(parser)
    parser.set_defaults(handler=run_with("sim.cli.experiment_twins:run"))
