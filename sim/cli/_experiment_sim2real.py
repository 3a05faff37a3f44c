"""``reform-sim experiment sim2real``: REFORM trained on synthetic crowds, tested on real people."""

from __future__ import annotations

import argparse

from sim.cli._common import add_backend_arguments, run_with
from sim.cli._experiment_io import (
    add_dataset_arguments,
    add_out_argument,
)
from sim.cli._grammar import add_quiet, add_seed

DESCRIPTION = """\
Trains REFORM (the paper's three classifiers) only on simulated episodes of mingle (a SALSA-like
party, with tracker noise calibrated on SALSA's training split) and word-improv (the Babble
game), and scores it on the SALSA test split (reform.time_split) and on every annotated Babble
frame, beside REFORM trained on SALSA's training split, GCFF (the paper's setting and tuned on
SALSA's training split) and the majority baseline, with block-bootstrap intervals and the
experiment's goals checked. The synthetic data are generated once under --synthetic and reused.
Writes DIR/sim2real.md, DIR/sim2real.json and DIR/sim2real.png and prints the Markdown.
"""

BASENAME = "sim2real"

DEFAULT_SYNTHETIC = "runs/sim2real"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_dataset_arguments(parser)
    add_out_argument(parser, basename=BASENAME)
    parser.add_argument(
        "--synthetic",
        default=DEFAULT_SYNTHETIC,
        metavar="DIR",
        help=f"folder of the generated synthetic data, reused when present ({DEFAULT_SYNTHETIC})",
    )
    add_seed(parser)
    parser.add_argument(
        "--episodes-scale",
        type=float,
        default=1.0,
        metavar="X",
        help="multiply every source's episodes by X (at least 1 each; 1 = the documented run)",
    )
    parser.add_argument(
        "--classifiers",
        default=None,
        metavar="A,B",
        help="REFORM classifiers (default: weighted-knn,bagged-trees,logistic-regression)",
    )
    add_backend_arguments(
        parser, jobs_default="every core", jobs_help="worker processes (generation, training)"
    )
    parser.add_argument(
        "--no-diagnostics", action="store_true", help="skip the per-source diagnostic rows"
    )
    parser.add_argument(
        "--no-randomised",
        action="store_true",
        help="leave the randomised mode (mingle-randomised) out of the diagnostics",
    )
    add_quiet(parser)
    parser.set_defaults(handler=run_with("sim.cli.experiment_sim2real:run"))
