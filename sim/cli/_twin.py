"""``reform-sim twin``: fit a venue twin to a recording's frames, without their groups."""

from __future__ import annotations

import argparse

from sim.cli._common import add_data_arguments, add_jobs_argument, run_with
from sim.cli._grammar import add_out, add_quiet, add_seed

DEFAULT_OUT = "twin"

DESCRIPTION = """\
Reads a recording of a place (positions, orientations, times, who is present; never its groups)
and fits a venue twin: a party scenario and its options (people, room and crowding, spacing)
and an annotation model (orientation coding, head or body, scale, tracker jitter measured on
people standing still, dropouts, rate). Writes OUT/twin.json (every fitted value, the statistic
that fixed it, the real figure and the twin's) and OUT/twin.png (the twin against the recording).
Use it with `reform-sim generate --twin`, `reform-sim tune --twin` and
`reform-sim benchmark --twin`. --use-labels also fits the group structure (share alone, largest
group, o-space radii) from the annotated frames: a separate mode, recorded in twin.json.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_data_arguments(parser)
    add_out(parser, folder=True, default=DEFAULT_OUT, help="folder for twin.json and twin.png")
    add_seed(parser, help="master seed of the pilot parties and of the twin's data")
    parser.add_argument(
        "--use-labels",
        action="store_true",
        help="also fit the group structure from the annotated frames (twin.json says so)",
    )
    parser.add_argument("--no-plots", action="store_true", help="write twin.json only")
    add_jobs_argument(parser, does="processes the pilot parties run on")
    add_quiet(parser, old=())
    parser.set_defaults(handler=run_with("sim.cli.twin:_run"))
