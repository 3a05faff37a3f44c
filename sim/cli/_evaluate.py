"""``reform-sim evaluate``: score a detector on a dataset's annotated frames, print the table."""

from __future__ import annotations

import argparse

from sim.cli._common import run_with
from sim.cli._detection import add_detection_arguments
from sim.cli._grammar import add_frames, add_report_out, add_temporal_arguments
from sim.recording import add_recording_arguments

DESCRIPTION = """\
Runs a detector on every annotated frame of a dataset and scores it with the field's protocol
(GCFF's ff_evalgroups): pairwise accuracy; precision, recall and F1 at T = 2/3 and T = 1
(singletons dropped, means of the per-frame P and R, F1 of the means); micro-averaged P/R/F1;
recall and precision by group size. Prints the table; --out DIR saves it (DIR/evaluation.json,
DIR/evaluation.md). --frames test scores the SALSA test split that `reform-sim train --frames
train` leaves out.

--temporal also scores the detector in time (docs/guide/temporal.md): the group events of its
answers (forms, dissolves, joins, leaves, merges, splits) against the ground truth's, matched
within --tolerance seconds: recall and precision per kind, latency (median, 95th percentile),
false events per minute and group identity switches, with intervals over sequences.
"""

BASENAME = "evaluation"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_detection_arguments(parser)
    add_frames(parser, scored="to score")
    add_report_out(parser, basename=BASENAME, holds="the scores, docs/json-schema.md")
    parser.add_argument(
        "--per-frame",
        action="store_true",
        help="include every frame's scores in the JSON (for time-series plots)",
    )
    add_temporal_arguments(parser)
    add_recording_arguments(parser)
    parser.set_defaults(handler=run_with("sim.cli.evaluate:run"))
