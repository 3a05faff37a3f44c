"""``reform-sim characterize``: Tightness and Symmetry by group size, tests, calibration."""

from __future__ import annotations

import argparse

from sim.cli._common import FORMATS
from sim.cli._grammar import add_quiet, add_report_out, run_loading
from sim.cli._numbers import ascii_float, ascii_int

DESCRIPTION = """\
Measures the ground-truth F-formations of one or more datasets (real or synthetic): Tightness
(mean distance of the members to the group's centre, m) and Symmetry (deviation of the angular
gaps between adjacent members from 360/N, degrees) by group size, with a one-way ANOVA and
Tukey's HSD across sizes, and the Distance / Effort Angle distributions of in-group and
out-of-group pairs. SALSA and Babble are printed beside the paper's published means.

With --compare-to, each dataset is also set beside each reference: mean Tightness and
Symmetry differences by size, two-sample Kolmogorov-Smirnov tests of the pair features, and
whether the mean Tightness lies within --tolerance of the reference's for every size the
reference holds at least --min-groups times (--check: exit status 1 when not).
--out DIR writes characterisation.json and characterisation.md there.
"""

BASENAME = "characterisation"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data",
        required=True,
        action="extend",
        nargs="+",
        metavar="PATH|NAME",
        help="dataset file(s) or folder(s), or dataset names (fetched or local); repeatable",
    )
    parser.add_argument(
        "--format",
        choices=FORMATS,
        default=None,
        help="format of the --data datasets (default: detected from each path)",
    )
    parser.add_argument(
        "--units",
        choices=("cm", "m"),
        default=None,
        help="length unit of the --data files' positions (GCFF folders: default cm)",
    )
    parser.add_argument(
        "--compare-to",
        nargs="+",
        default=[],
        metavar="PATH|NAME",
        help="reference dataset(s) to set each --data dataset beside (format detected)",
    )
    parser.add_argument(
        "--by-sequence",
        action="store_true",
        help="also characterise every sequence (session, episode) on its own",
    )
    parser.add_argument(
        "--min-groups",
        type=ascii_int,
        default=None,
        metavar="N",
        help="fewest F-formations of a size for it to be tested and checked (default 5)",
    )
    parser.add_argument(
        "--tolerance",
        type=ascii_float,
        default=None,
        metavar="M",
        help="calibration tolerance on mean Tightness by size, metres (default 0.1)",
    )
    parser.add_argument(
        "--check",
        action="store_true",
        help="exit with status 1 when a comparison misses the tolerance",
    )
    add_report_out(parser, basename=BASENAME, holds="every number")
    parser.add_argument(
        "--notes",
        metavar="FILE.md",
        help="Markdown file appended to the Markdown report as its discussion",
    )
    add_quiet(parser, old=())
    parser.set_defaults(handler=run_loading("sim.cli.characterize:run", "SciPy"))
