"""``reform-sim experiment twins``: venue twins against every real dataset found."""

from __future__ import annotations

import argparse

from sim.cli._common import run_with
from sim.cli._experiment_io import add_out_argument
from sim.cli._grammar import add_quiet, add_seed
from sim.cli._numbers import ascii_int

DESCRIPTION = """\
For every real dataset found: fits its label-free venue twin (`reform-sim twin`), generates the
twin's data (under --twins, default DIR/twins, reused), and measures, on the second half of
each recording, (1) tuning: GCFF, the proximity baseline and REFORM with one setting for every
dataset, tuned on the twin, and tuned on the first half's labels (the ceiling); (2) prediction:
every catalogued detector's F1 on the twin against its real F1 (Pearson r, Spearman, Kendall's
tau, mean absolute error, mean maximum rank violation, with bootstrap intervals), beside the
real ceiling (the first half predicting the second); (3) leave one out. A place is predicted
by --twins-per-place twins fitted with consecutive master seeds (the mean of their predictions,
as `reform-sim benchmark --twin A --twin B --twin C` gives), and the whole experiment runs
--repeats times, with seeds S, S+1, ...: the tables are seed S's twin's, the goals the mean over
the repeats, with their range. Writes DIR/twins.md, DIR/twins.json and DIR/twins.png, and
prints the Markdown.
"""

BASENAME = "twins"
TWINS = "twins"  # the twins' folder in --out, when --twins is not given
REPEATS = 3  # times the experiment runs, by default
MAX_REPEATS = 20  # most repeats one run takes
PER_PLACE = 3  # twins predicting each place, by default
MAX_SEEDS = 30  # most master seeds one run takes: repeats x twins per place (each ~5 minutes)


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
        type=ascii_int,
        default=REPEATS,
        metavar="N",
        help=f"run the whole experiment N times (1-{MAX_REPEATS}; default {REPEATS}), with "
        "master seeds S, S+1, ...; the twins of seed S+k are under --twins/seed-(S+k)",
    )
    parser.add_argument(
        "--twins-per-place",
        type=ascii_int,
        default=PER_PLACE,
        metavar="K",
        help=f"twins fitted to each place with consecutive seeds, their predictions averaged "
        f"(default {PER_PLACE}; repeats x K at most {MAX_SEEDS} seeds)",
    )
    add_quiet(parser)
    parser.set_defaults(handler=run_with("sim.cli.experiment_twins:run"))
