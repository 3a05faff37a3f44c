"""``reform-sim calibrate``: the scenarios beside SALSA and Babble (docs/results/calibration)."""

from __future__ import annotations

import argparse

from sim.cli._common import DEFAULT_DATASETS, add_backend_arguments, run_with

DESCRIPTION = """\
Simulates word-improv and mingle with default options and compares them with Babble and SALSA:
Tightness and Symmetry by group size (target: within 0.1 m), Kolmogorov-Smirnov statistics of
the pair features against bounds from the real data; also the randomised mode's coverage and the
HRI scenes. Writes calibration.md and calibration.json into --out.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", required=True, metavar="DIR", help="folder for the report")
    parser.add_argument(
        "--datasets",
        default=None,
        metavar="DIR",
        help="folder holding salsa/ and babble/ (default: $REFORM_SIM_DATASETS, else "
        f"{DEFAULT_DATASETS})",
    )
    parser.add_argument(
        "--seeds", type=int, default=None, metavar="N", help="episodes per scenario (default 8)"
    )
    parser.add_argument(
        "--check", action="store_true", help="exit with status 1 when a target is missed"
    )
    add_backend_arguments(parser, jobs_default="every core", jobs_help="episodes at once")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(handler=run_with("sim.cli.calibrate:run"))
