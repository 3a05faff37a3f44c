"""``reform-sim experiment hri``: the paper's HRI proof of concept, re-enacted in simulation."""

from __future__ import annotations

import argparse

from sim.cli._common import add_backend_arguments
from sim.cli._experiment_io import add_io_arguments
from sim.cli._grammar import add_episodes, add_quiet, add_recordings, add_seed, run_loading
from sim.experiments.hri_views import DEFAULT_SEEDS, VIEW_NAMES

DESCRIPTION = """\
Simulates the three HRI scenes of the REFORM paper (hri-conversation: two people and the robot
converse; hri-robot-excluded: two people talk in front of the robot; hri-passing: people walk
past, no F-formation) with several seeds, and scores REFORM (weighted KNN, bagged trees, logistic
regression; trained on the SALSA training split when SALSA is found (--data), and on a
synthetic training set), GCFF (the paper's setting and the reference default) and the majority
baseline from the ground truth and from the robot's head sensor, beside the paper's HRI numbers.
Writes DIR/hri.md and DIR/hri.json; with --recordings, one Rerun recording per scene in
DIR/recordings/ (first seed, robot view, detections of REFORM and GCFF).
"""

BASENAME = "hri"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_io_arguments(parser, basename=BASENAME, names=("salsa",))
    add_episodes(
        parser,
        default=DEFAULT_SEEDS,
        help=f"episodes per scene (default {DEFAULT_SEEDS})",
        old="--seeds",
    )
    add_seed(parser)
    parser.add_argument(
        "--views",
        default=",".join(VIEW_NAMES),
        metavar="V1,V2",
        help=f"views to score (default {','.join(VIEW_NAMES)})",
    )
    add_backend_arguments(parser, jobs_help="worker processes (training, episodes)")
    add_recordings(parser, default=False, each="scene (its first episode, robot view)", folder=True)
    add_quiet(parser, old=())
    parser.set_defaults(
        handler=run_loading("sim.cli.experiment_hri:run", "MuJoCo, scikit-learn and Rerun")
    )
