"""``reform-sim data``: inspect a dataset (``info``) or convert it to the project's Parquet."""

from __future__ import annotations

import argparse

from sim.cli._common import Action, add_actions, add_data_argument, add_data_arguments, run_with

_INFO_DESCRIPTION = """\
Loads a dataset (SALSA / DANTE text, Babble, a GCFF MATLAB folder, or the project's Parquet)
and prints what it holds: frames, sequences, people, annotated frames, the group-size
histogram over the annotated frames (singletons included), units, and the loader's report
(irregularities it found and how it handled them).
"""

_CONVERT_DESCRIPTION = """\
Loads a dataset in any supported format and writes it in the project's Parquet format
(positions in metres, every column documented in docs/reference/formats.md).
"""


DESCRIPTION = """\
Inspect a dataset (info) or convert it to Parquet (convert).
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_actions(parser, ACTIONS)


def _info_arguments(parser: argparse.ArgumentParser) -> None:
    add_data_arguments(parser, old_positional=True)
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.set_defaults(handler=run_with("sim.cli.data:run_info"))


def _verify_arguments(parser: argparse.ArgumentParser) -> None:
    add_data_argument(parser, old_positional=True, metavar="DIR|URI")
    parser.set_defaults(handler=run_with("sim.cli.data:run_verify"))


def _convert_arguments(parser: argparse.ArgumentParser) -> None:
    add_data_arguments(parser, old_positional=True)
    parser.add_argument(
        "--out", required=True, metavar="FILE.parquet", help="the .parquet file to write"
    )
    parser.set_defaults(handler=run_with("sim.cli.data:run_convert"))


ACTIONS = (
    Action(
        "info",
        "print frames, people, annotation, group sizes, units and the loader's report",
        _INFO_DESCRIPTION,
        _info_arguments,
    ),
    Action(
        "verify",
        "check that a generated dataset folder is whole: every shard there, unaltered",
        "Checks a `reform-sim generate` folder against its card (dataset.json): the run finished, "
        "every shard it lists is there with its size and sha256, no other Parquet file is there, "
        "every shard reads. Prints each problem on a line; exit status 1 when there is one. A "
        "card that says of its shards what they do not hold (their counts of frames, annotated "
        "frames and rows, group sizes, sequence, episode) is refused in one line (exit status 2).",
        _verify_arguments,
        as_written=False,
    ),
    Action(
        "convert",
        "write a dataset in the project's Parquet format",
        _CONVERT_DESCRIPTION,
        _convert_arguments,
    ),
)
