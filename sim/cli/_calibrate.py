"""``reform-sim calibrate``: the scenarios beside SALSA and Babble (docs/results/calibration)."""

from __future__ import annotations

import argparse

from sim.cli._common import add_backend_arguments
from sim.cli._experiment_io import add_dataset_arguments
from sim.cli._grammar import add_episodes, add_out, add_quiet, run_loading

DESCRIPTION = """\
Simulates word-improv and mingle with default options and compares them with Babble and SALSA:
Tightness and Symmetry by group size (target: within 0.1 m), Kolmogorov-Smirnov statistics of
the pair features against bounds from the real data; also the randomised mode's coverage and the
HRI scenes. Writes calibration.md and calibration.json into --out.
"""

BASENAME = "calibration"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_out(parser, folder=True, help=f"folder for {BASENAME}.md and {BASENAME}.json (created)")
    add_dataset_arguments(parser)
    add_episodes(parser, help="episodes per scenario (default 8)", old="--seeds")
    parser.add_argument(
        "--check", action="store_true", help="exit with status 1 when a target is missed"
    )
    add_backend_arguments(parser, jobs_help="episodes at once")
    add_quiet(parser, old=())
    parser.set_defaults(handler=run_loading("sim.cli.calibrate:run", "MuJoCo"))
