"""``reform-sim experiment sim2real``: one detector trained on simulation alone, scored on every
real dataset it never saw."""

from __future__ import annotations

import argparse

from sim.cli._common import add_backend_arguments
from sim.cli._experiment_io import add_out_argument
from sim.cli._grammar import add_quiet, add_seed, run_loading
from sim.cli._numbers import ascii_float

DESCRIPTION = """\
Trains REFORM only on generated data: every candidate (recipes of synthetic data x the paper's
classifiers x REFORM's options) is fitted on its recipe and the recommended one is chosen on
SALSA's training split and simulated validation episodes only. Scores it on every real dataset
found (SALSA's test split, every annotated frame of the others) beside REFORM trained on SALSA's
training split, GCFF with one setting and with each dataset's own settings, and REFORM trained on
the other real datasets (leave one dataset out); reports the rank agreement (Kendall's tau)
between the simulated party and the real datasets, the goals, and plots. The synthetic data are
generated once under --synthetic (default: DIR/synthetic) and reused; nothing is written
outside DIR unless --synthetic names another folder. Writes DIR/sim2real.md, DIR/sim2real.json,
DIR/sim2real.png, DIR/sim2real-rank.png, DIR/sim2real-calibration.png and
DIR/recommended.skops, and prints the Markdown.
"""

BASENAME = "sim2real"

SYNTHETIC = "synthetic"  # the synthetic data's folder in --out, when --synthetic is not given


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data",
        action="append",
        default=[],
        metavar="PATH|NAME",
        help="a real dataset (repeatable): NAME=PATH, a fetched or local dataset's name, its "
        "folder, or a folder of datasets; SALSA is required (default: every fetched or local "
        "dataset)",
    )
    add_out_argument(parser, basename=BASENAME)
    parser.add_argument(
        "--synthetic",
        default=None,
        metavar="DIR",
        help=f"folder of the generated synthetic data, reused when present (default: "
        f"OUT/{SYNTHETIC})",
    )
    add_seed(parser)
    parser.add_argument(
        "--episodes-scale",
        type=ascii_float,
        default=1.0,
        metavar="X",
        help="multiply every source's episodes by X (at least 1 each; 1 = the documented run)",
    )
    parser.add_argument(
        "--classifiers",
        default=None,
        metavar="A,B",
        help="REFORM classifiers compared (default: logistic-regression,weighted-knn,bagged-trees)",
    )
    add_backend_arguments(parser, jobs_help="worker processes (generation, training)")
    add_quiet(parser)
    parser.set_defaults(
        handler=run_loading("sim.cli.experiment_sim2real:run", "MuJoCo and scikit-learn")
    )
