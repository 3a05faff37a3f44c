"""``reform-sim experiment gcff``: GCFF (paper setting, tuned) beside REFORM on SALSA and Babble."""

from __future__ import annotations

import argparse

from sim.cli._common import add_dry_run_argument, add_max_memory_argument
from sim.cli._experiment_io import add_salsa_split_arguments
from sim.cli._grammar import add_quiet, run_loading

DESCRIPTION = """\
Scores GCFF with the REFORM paper's setting (stride 0.7 m, MDL 30000 read as 30000 cm² =
3.0 m²), with the reference code's default (70 cm, 10000 cm²), and tuned by grid search on the
SALSA training split (reform.time_split), plus the majority baseline, on the SALSA test split and
on Babble, with the field's protocol. Evaluation JSON files of other detectors on the same frames
(REFORM's classifiers; dataset "salsa-test" or "babble") are added with --with-results. Writes
DIR/gcff-comparison.md and DIR/gcff-comparison.json and prints the Markdown.
"""

BASENAME = "gcff-comparison"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_salsa_split_arguments(parser, basename=BASENAME, use="used to tune (default 0.6)")
    parser.add_argument(
        "--gcff-orientation",
        choices=("body", "head"),
        default="body",
        help="orientation GCFF uses (default: body, as the paper)",
    )
    parser.add_argument(
        "--stride-grid",
        type=_floats,
        default=None,
        metavar="S1,S2,...",
        help="strides tried when tuning, metres (default: 0.4 to 1.0 by 0.1)",
    )
    parser.add_argument(
        "--mdl-grid",
        type=_floats,
        default=None,
        metavar="M1,M2,...",
        help="mdl values tried when tuning, square metres (default: 0.5 0.75 1 1.5 2 3 4)",
    )
    parser.add_argument(
        "--with-results",
        action="append",
        default=[],
        metavar="JSON",
        help="evaluation JSON (reform-sim evaluate --json, or a file holding a 'results' list) "
        "of another detector on the same frames; repeatable",
    )
    add_max_memory_argument(parser, holds="the grid search holds the scores of every setting")
    add_dry_run_argument(parser)
    add_quiet(parser, old=())
    parser.set_defaults(handler=run_loading("sim.cli.experiment_gcff:run", "scikit-learn"))


def _floats(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers, e.g. 0.5,0.7, got {text!r}"
        ) from None
    return values
