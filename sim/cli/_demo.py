"""``reform-sim demo``: the whole toolkit on an embedded default, in a few minutes."""

from __future__ import annotations

import argparse

from sim.cli._common import add_jobs_argument
from sim.cli._grammar import (
    add_out,
    add_quiet,
    add_recordings,
    add_seed,
    rename,
    run_loading,
    setter,
)
from sim.experiments.demo_files import DEFAULT_OUT

DESCRIPTION = """\
Simulates every registered scenario briefly, generates a synthetic training set (mingle and
word-improv), trains REFORM on it, scores REFORM and GCFF on held-back synthetic episodes and,
when found (--data), on the SALSA test split and Babble, runs the stress tests on the
small grid and re-enacts the paper's HRI experiment. Writes Rerun recordings (.rrd), the model
(model.skops), plots and a Markdown report into --out, and says where they are.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data",
        metavar="DIR",
        default=None,
        help="folder holding salsa/ and/or babble/ (default: $REFORM_SIM_DATASETS, else "
        "../shared/datasets when it exists, else the fetched ones, else synthetic data only)",
    )
    rename(parser, "--datasets", "--data", setter("data"), metavar="DIR")
    add_out(
        parser,
        folder=True,
        default=DEFAULT_OUT,
        help="folder for the report, the model, the plots and the recordings",
    )
    add_seed(parser)
    add_jobs_argument(parser)
    parser.add_argument(
        "--quick", action="store_true", help="tiny budgets: a smoke run in well under a minute"
    )
    add_recordings(
        parser, default=True, each="scenario, evaluation and HRI scene, and the stress curves"
    )
    add_quiet(parser)
    parser.set_defaults(handler=run_loading("sim.cli.demo:run", "MuJoCo, scikit-learn and Rerun"))
