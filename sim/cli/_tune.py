"""``reform-sim tune``: a detector's settings chosen on a venue twin's generated data."""

from __future__ import annotations

import argparse

from sim.cli._common import add_jobs_argument, run_with
from sim.cli._grammar import add_quiet

DESCRIPTION = """\
Chooses a detector's settings for the place a venue twin (`reform-sim twin`) describes, on the
twin's labelled synthetic data (generated first into --twin-data, default twin-data/ beside
twin.json, and reused): every setting of the grids the detector declares (GCFF: stride x mdl)
scored by F1 at T = 2/3, the best kept (GCFF: the cheapest group, mdl, among the settings within
2 points of the best, since a twin cannot see the merges a costlier group makes; the file names
the rule); REFORM is trained on the twin (each of the paper's
classifiers trained on half the episodes and scored on the others, the best trained on all).
Writes a settings file (JSON, reform.settings: the detector, its options, the grid's scores)
that `detect` and `evaluate` take with --settings FILE.json or, for REFORM, a model file (.skops)
that `detect`, `evaluate` and `benchmark` take with --model.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--twin", required=True, metavar="TWIN.json", help="a twin written by `reform-sim twin`"
    )
    parser.add_argument(
        "--detector",
        required=True,
        metavar="NAME",
        help="a catalogued detector (gcff, reform, ...)",
    )
    parser.add_argument(
        "--out",
        metavar="FILE",
        help="settings file (default: tuned-NAME.json beside twin.json; for REFORM a model file, "
        "tuned-reform.skops)",
    )
    parser.add_argument(
        "--twin-data",
        metavar="DIR",
        help="the twin's generated dataset (default: twin-data/ beside twin.json; made if absent)",
    )
    add_jobs_argument(parser, does="processes generating the twin's data and scoring the settings")
    add_quiet(parser)
    parser.set_defaults(handler=run_with("sim.cli.tune:_run"))
