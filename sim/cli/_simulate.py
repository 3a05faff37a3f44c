"""``reform-sim simulate``: one episode of a scenario, written as the project's Parquet."""

from __future__ import annotations

import argparse

from sim.cli._common import (
    add_max_memory_argument,
    add_overrides_argument,
    add_sensor_arguments,
    add_view_argument,
)
from sim.cli._grammar import add_quiet, add_seed, run_loading
from sim.cli._numbers import ascii_float
from sim.recording import add_recording_arguments

DESCRIPTION = """\
Runs one episode of a registered scenario (reform-sim scenarios lists them and their options)
in the MuJoCo world and writes its frames, ground truth included, to a Parquet file in the
project's format. With --view robot the frames are what the robot's head sensor observes
(field of view, range, occlusion, noise), the ground truth restricted to the people seen.
With --save the episode is also recorded for the Rerun viewer (scene, people, robot, groups,
the scenario's events).

The run is sized before it starts (memory, disk, time; sim.sizing) and refused, in one line,
when it cannot fit this machine. Without a recording the frames stream to --out as they are
made, in bounded memory, with progress on stderr; a recording (--save, --connect, --serve)
needs the whole episode in memory, up to --max-memory.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scenario", required=True, metavar="NAME", help="scenario name")
    add_seed(parser, help="episode seed")
    parser.add_argument("--out", required=True, metavar="FILE.parquet", help="output file")
    parser.add_argument(
        "--duration",
        type=ascii_float,
        default=None,
        metavar="SECONDS",
        help="seconds to simulate (default: the scenario's natural length)",
    )
    parser.add_argument(
        "--rate", type=ascii_float, default=None, metavar="HZ", help="frames per second (default 2)"
    )
    add_view_argument(parser)
    add_overrides_argument(parser)
    parser.add_argument(
        "--dt",
        type=ascii_float,
        default=None,
        metavar="SECONDS",
        help="control step of the world (default 0.01; up to 0.1, faster and rougher)",
    )
    add_sensor_arguments(parser)
    add_recording_arguments(parser)
    add_max_memory_argument(
        parser,
        holds="a recording holds the whole episode, the frames otherwise stream to --out",
    )
    add_quiet(parser)
    parser.set_defaults(handler=run_loading("sim.cli.simulate:run", "MuJoCo"))
