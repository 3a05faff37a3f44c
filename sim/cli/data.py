"""What ``reform-sim data`` does when it runs.

Its arguments are `sim.cli._data`."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from reform.datasets import detect_format, resolve, write_parquet
from reform.datasets.parquet import verify_folder
from reform.datasets.summary import summarise
from sim.cli._common import check_output, data_path, load_data


def run_verify(args: argparse.Namespace) -> int:
    from sim.generate import leftovers  # MuJoCo's importers: only for this action

    path = data_path(args)
    problems = verify_folder(path)
    left = leftovers(path)
    for line in [*problems, *left]:
        print(line)
    behind = f"; {len(left)} leftover(s) of runs that did not finish, listed above" if left else ""
    if problems:
        print(
            f"{path}: {len(problems)} problem(s); the dataset is not whole{behind}",
            file=sys.stderr,
        )
        return 1
    print(f"{path}: whole (every shard its card lists is there, unaltered){behind}")
    return 0


def _load(args: argparse.Namespace):
    dataset = load_data(args)
    return args.format or detect_format(resolve(args.data)), dataset


def run_info(args: argparse.Namespace) -> int:
    format, dataset = _load(args)
    summary = summarise(dataset)
    summary["format"] = format
    summary["group_events"] = _event_counts(dataset)
    if args.json:
        json.dump(summary, sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(format_info(summary, metadata=dict(dataset.metadata)), end="")
    return 0


def run_convert(args: argparse.Namespace) -> int:
    check_output("--out", args.out, suffix=".parquet")
    _, dataset = _load(args)
    write_parquet(dataset, args.out)
    print(f"wrote {args.out}: {len(dataset)} frames", file=sys.stderr)
    return 0


def _event_counts(dataset: Any) -> dict[str, int]:
    """The dataset's group events per kind (`reform.datasets.dataset_group_events`: stored in
    generated shards, else found on the annotated frames), every kind listed."""
    from reform.datasets import dataset_group_events
    from reform.events import EVENT_KINDS

    counts = dict.fromkeys(EVENT_KINDS, 0)
    for event in dataset_group_events(dataset):
        counts[event.kind] += 1
    return counts


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
    events = summary.get("group_events")
    if events is not None:
        lines.append(
            "group events     "
            + ", ".join(f"{count} {kind}" for kind, count in events.items())
            + " (docs/guide/temporal.md)"
        )
    settings = metadata.get("settings_gc")
    if settings:
        lines.append(f"settings_gc      {json.dumps(settings)}")
    report = summary.get("report")
    if report:
        lines.append("loader report")
        for key, value in report.items():
            lines.append(f"  {key}: {json.dumps(value)}")
    return "\n".join(lines) + "\n"
