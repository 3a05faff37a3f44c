"""``reform-sim detect``: run a detector on a dataset and write its groups, frame by frame."""

from __future__ import annotations

import argparse

from sim.cli._common import run_with
from sim.cli._detection import add_detection_arguments
from sim.recording import add_recording_arguments

DESCRIPTION = """\
Runs a detector on the frames of a dataset and writes, per frame, its sequence, time stamp and
the detected F-formations (groups of two or more person ids; everyone in no group is alone).
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_detection_arguments(parser)
    parser.add_argument("--out", required=True, metavar="OUT", help="JSON file to write")
    parser.add_argument(
        "--annotated-only",
        action="store_true",
        help="only the frames that carry ground truth (default: every frame)",
    )
    add_recording_arguments(parser)
    parser.set_defaults(handler=run_with("sim.cli.detect:run"))
