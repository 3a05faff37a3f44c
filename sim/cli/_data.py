"""``reform-sim data``: inspect a dataset (``info``) or convert it to the project's Parquet."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from sim.cli._common import add_data_arguments, check_output, load_data

_INFO_DESCRIPTION = """\
Loads a dataset (SALSA / DANTE text, Babble, a GCFF MATLAB folder, or the project's Parquet)
and prints what it holds: frames, sequences, people, annotated frames, the group-size
histogram over the annotated frames (singletons included), units, and the loader's report
(irregularities it found and how it handled them).
"""

_CONVERT_DESCRIPTION = """\
Loads a dataset in any supported format and writes it in the project's Parquet format
(positions in metres, every column documented in the README).
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "data",
        help="inspect or convert a dataset",
        description="Inspect a dataset (info) or convert it to Parquet (convert).",
        arguments=_actions,
    )


def _actions(parser: argparse.ArgumentParser) -> None:
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    actions.add_parser(
        "info",
        help="print frames, people, annotation, group sizes, units and the loader's report",
        description=_INFO_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_info_arguments,
    )
    actions.add_parser(
        "verify",
        help="check that a generated dataset folder is whole: every shard there, unaltered",
        description="Checks a `reform-sim generate` folder against its card (dataset.json): the "
        "run finished, every shard it lists is there with its size and sha256, no other Parquet "
        "file is there, every shard reads. Prints each problem on a line; exit status 1 when "
        "there is one.",
        arguments=_verify_arguments,
    )
    actions.add_parser(
        "convert",
        help="write a dataset in the project's Parquet format",
        description=_CONVERT_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_convert_arguments,
    )


def _info_arguments(parser: argparse.ArgumentParser) -> None:
    add_data_arguments(parser, flag="path")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.set_defaults(handler=run_info)


def _verify_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("path", metavar="DIR", help="a folder written by reform-sim generate")
    parser.set_defaults(handler=run_verify)


def run_verify(args: argparse.Namespace) -> int:
    from reform.datasets.parquet import verify_folder

    problems = verify_folder(args.path)
    for problem in problems:
        print(problem)
    if problems:
        print(f"{args.path}: {len(problems)} problem(s); the dataset is not whole", file=sys.stderr)
        return 1
    print(f"{args.path}: whole (every shard its card lists is there, unaltered)")
    return 0


def _convert_arguments(parser: argparse.ArgumentParser) -> None:
    add_data_arguments(parser, flag="path")
    parser.add_argument("--out", required=True, metavar="OUT", help="the .parquet file to write")
    parser.set_defaults(handler=run_convert)


def _load(args: argparse.Namespace):
    from reform.datasets import detect_format, resolve

    dataset = load_data(args, attribute="path")
    return args.format or detect_format(resolve(args.path)), dataset


def run_info(args: argparse.Namespace) -> int:
    from reform.datasets.summary import summarise

    format, dataset = _load(args)
    summary = summarise(dataset)
    summary["format"] = format
    if args.json:
        json.dump(summary, sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(format_info(summary, metadata=dict(dataset.metadata)), end="")
    return 0


def run_convert(args: argparse.Namespace) -> int:
    from reform.datasets import write_parquet

    check_output("--out", args.out)
    _, dataset = _load(args)
    write_parquet(dataset, args.out)
    print(f"wrote {args.out}: {len(dataset)} frames", file=sys.stderr)
    return 0


def format_info(summary: dict[str, Any], *, metadata: dict[str, Any]) -> str:
    """The summary as aligned text."""
    lines = [
        f"dataset          {summary['name']} (format {summary['format']})",
        f"source           {summary['source']}",
    ]
    file_units = metadata.get("file_units")
    units = summary["units"] + (f" (file in {file_units}, converted)" if file_units else "")
    lines.append(f"units            {units}")
    lines.append(f"frames           {summary['frames']}")
    lines.append(f"annotated frames {summary['annotated_frames']}")
    people = summary["people"]
    lines.append(
        f"people           {people['distinct_ids']} distinct ids; per frame "
        f"min {people['min']}, median {people['median']:g}, max {people['max']}"
    )
    if summary["robots"]:
        lines.append(f"robots           in {summary['robots']} frames")
    heads = summary["heads"]
    lines.append(
        f"heads            {heads['observed']} observed, {heads['not_observed']} not observed, "
        f"{heads['no_head_data']} without head data (person-frames)"
    )
    lines.append("sequences")
    for name, entry in summary["sequences"].items():
        lines.append(
            f"  {name}: {entry['frames']} frames, {entry['annotated_frames']} annotated, "
            f"{entry['duration_s']:g} s"
        )
    sizes = summary["group_sizes"]
    lines.append("group sizes (annotated frames, singletons included)")
    if sizes:
        width = max(len(str(v)) for v in [*sizes.values(), *sizes.keys(), "size"])
        lines.append("  size   " + " ".join(k.rjust(width) for k in sizes))
        lines.append("  groups " + " ".join(str(v).rjust(width) for v in sizes.values()))
    else:
        lines.append("  (no annotated frames)")
    lines.append(f"F-formations     {summary['fformations']} (groups of 2 or more)")
    settings = metadata.get("settings_gc")
    if settings:
        lines.append(f"settings_gc      {json.dumps(settings)}")
    report = summary.get("report")
    if report:
        lines.append("loader report")
        for key, value in report.items():
            lines.append(f"  {key}: {json.dumps(value)}")
    return "\n".join(lines) + "\n"
