"""``reform-sim experiment hri``: the paper's HRI proof of concept, re-enacted in simulation."""

from __future__ import annotations

import argparse

from sim.cli._common import add_backend_arguments, run_with
from sim.cli._experiment_io import (
    add_dataset_arguments,
    add_out_argument,
)
from sim.experiments.hri_views import DEFAULT_SEEDS, VIEW_NAMES

DESCRIPTION = """\
Simulates the three HRI scenes of the REFORM paper (hri-conversation: two people and the robot
converse; hri-robot-excluded: two people talk in front of the robot; hri-passing: people walk
past, no F-formation) with several seeds, and scores REFORM (weighted KNN, bagged trees, logistic
regression; trained on the SALSA training split when --salsa or --datasets is given, and on a
synthetic training set), GCFF (the paper's setting and the reference default) and the majority
baseline from the ground truth and from the robot's head sensor, beside the paper's HRI numbers.
Writes OUT.md and OUT.json; with --recordings DIR, one Rerun recording per scene (first seed,
robot view, detections of REFORM and GCFF).
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_dataset_arguments(parser, babble=False)
    add_out_argument(parser)
    parser.add_argument(
        "--seeds",
        type=int,
        default=DEFAULT_SEEDS,
        metavar="K",
        help=f"episodes per scene (default {DEFAULT_SEEDS})",
    )
    parser.add_argument("--seed", type=int, default=0, help="master seed (default 0)")
    parser.add_argument(
        "--views",
        default=",".join(VIEW_NAMES),
        metavar="V1,V2",
        help=f"views to score (default {','.join(VIEW_NAMES)})",
    )
    add_backend_arguments(
        parser, jobs_default="every core", jobs_help="worker processes (training, episodes)"
    )
    parser.add_argument(
        "--recordings",
        default=None,
        metavar="DIR",
        help="write DIR/<scene>.rrd: the first episode of each scene from the robot's view",
    )
    parser.set_defaults(handler=run_with("sim.cli.experiment_hri:run"))
