"""``reform-sim experiment paper``: the REFORM paper's Table I and Babble table on the real data."""

from __future__ import annotations

import argparse

from sim.cli._common import add_jobs_argument
from sim.cli._experiment_io import add_salsa_split_arguments
from sim.cli._grammar import add_quiet, run_loading
from sim.cli._numbers import ascii_int

DESCRIPTION = """\
Trains REFORM with the paper's three classifiers on the SALSA training split (reform.time_split:
per session, the first 60 % of annotated frames by time), with hyper-parameters chosen by
time-blocked cross-validation on that part only, and scores them and the majority baseline on
the SALSA test split and on every annotated Babble frame, at T = 2/3 and T = 1, beside the
paper's published figures. Diagnostics rerun the classifiers under the paper's kind of split,
MATLAB's presets and a feature slip, to explain the differences. Writes DIR/paper-experiment.md
and DIR/paper-experiment.json and prints the Markdown.
"""

BASENAME = "paper-experiment"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_salsa_split_arguments(parser, basename=BASENAME, use="for training (0.6)")
    parser.add_argument("--folds", type=ascii_int, default=5, metavar="K", help="CV folds (5)")
    add_jobs_argument(parser, does="processes fitting the cross-validation folds")
    parser.add_argument(
        "--no-diagnostics", action="store_true", help="skip the diagnostic reruns (faster)"
    )
    add_quiet(parser, old=())
    parser.set_defaults(handler=run_loading("sim.cli.experiment_paper:run", "scikit-learn"))
