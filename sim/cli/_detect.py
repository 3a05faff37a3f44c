"""``reform-sim detect``: run a detector on a dataset and write its groups, frame by frame."""

from __future__ import annotations

import argparse

from sim.cli._common import run_with
from sim.cli._detection import add_detection_arguments
from sim.cli._grammar import add_frames, rename, setter
from sim.recording import add_recording_arguments

DESCRIPTION = """\
Runs a detector on the frames of a dataset and writes, per frame, its sequence, time stamp and
the detected F-formations (groups of two or more person ids; everyone in no group is alone).
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_detection_arguments(parser)
    add_frames(parser, default=None, scored="to run on")
    rename(parser, "--annotated-only", "--frames all", setter("frames", "all"), nargs=0)
    parser.add_argument("--out", required=True, metavar="FILE.json", help="JSON file to write")
    add_recording_arguments(parser)
    parser.set_defaults(handler=run_with("sim.cli.detect:run"))
