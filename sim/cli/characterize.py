"""What ``reform-sim characterize`` does when it runs.

Its arguments are `sim.cli._characterize`."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path
from typing import Any

from reform.calibration import MIN_GROUPS, TIGHTNESS_TOLERANCE_M, characterise_dataset, compare
from reform.datasets import detect_format, load_dataset, resolve
from reform.datasets.store import is_uri
from sim.cli._characterize import BASENAME
from sim.cli._common import CliError, read_text, refuse_given_twice
from sim.cli._grammar import report_outputs, write_outputs
from sim.experiments.characterisation_report import (
    characterisation_summary,
    format_calibration,
    format_characterisation,
)

# Version of the JSON written by ``characterize --json``.
CHARACTERISATION_SCHEMA_VERSION = 1


def _command(args: argparse.Namespace) -> str:
    """The command line that reproduces this run, options in a fixed order."""
    words = ["reform-sim", "characterize", "--data", *args.data]
    if args.format:
        words += ["--format", args.format]
    if args.units:
        words += ["--units", args.units]
    if args.compare_to:
        words += ["--compare-to", *args.compare_to]
    if args.by_sequence:
        words.append("--by-sequence")
    if args.min_groups is not None:
        words += ["--min-groups", str(args.min_groups)]
    if args.tolerance is not None:
        words += ["--tolerance", f"{args.tolerance:g}"]
    if args.check:
        words.append("--check")
    for flag, value in (
        ("--json", args.old_json),
        ("--markdown", args.old_markdown),
        ("--out", args.out),
        ("--notes", args.notes),
    ):
        if value:
            words += [flag, value]
    return shlex.join(words)


def _same_path(a: str, b: str) -> bool:
    return Path(a).resolve() == Path(b).resolve()


def run(args: argparse.Namespace) -> int:
    min_groups = MIN_GROUPS if args.min_groups is None else args.min_groups
    tolerance = TIGHTNESS_TOLERANCE_M if args.tolerance is None else args.tolerance
    if min_groups < 1:
        raise CliError(f"--min-groups must be >= 1, got {min_groups}")
    if not tolerance > 0.0:
        raise CliError(f"--tolerance must be a positive number of metres, got {tolerance:g}")
    outputs = report_outputs(args, BASENAME)
    notes = None
    if args.notes:
        if "markdown" not in outputs:
            raise CliError("--notes is appended to the Markdown report: give --out DIR too")
        notes = read_text("--notes", args.notes, expected="UTF-8 Markdown text")

    locations = [resolve(path) for path in args.data]
    refuse_given_twice(
        "--data",
        [
            (p, at if is_uri(at) else Path(at).resolve())
            for p, at in zip(args.data, locations, strict=True)
        ],
    )
    datasets: list[dict[str, Any]] = []
    for path, location in zip(args.data, locations, strict=True):
        if not args.quiet:
            print(f"characterising {path}", file=sys.stderr)
        format = args.format or detect_format(location)
        dataset = load_dataset(location, format=format, units=args.units)
        measured = characterise_dataset(dataset)
        if measured.frames == 0:
            raise CliError(f"{path}: the dataset has no annotated frames, nothing to characterise")
        entry = characterisation_summary(measured, min_groups=min_groups)
        entry.update(path=path, source=dataset.source, format=format)
        if args.by_sequence and len(dataset.sequences()) > 1:
            entry["sequences"] = {}
            for sequence in dataset.sequences():
                part = characterise_dataset(
                    [f for f in dataset if f.sequence == sequence],
                    name=f"{dataset.name}/{sequence}",
                )
                if part.frames:
                    entry["sequences"][sequence] = characterisation_summary(
                        part, min_groups=min_groups, tukey=False, paper_name=dataset.name
                    )
        datasets.append({"measured": measured, "summary": entry})

    comparisons: list[dict[str, Any]] = []
    for ref_path in args.compare_to:
        reference = load_dataset(resolve(ref_path))
        measured_ref = characterise_dataset(reference)
        if measured_ref.frames == 0:
            raise CliError(f"{ref_path}: the reference has no annotated frames")
        for path, item in zip(args.data, datasets, strict=True):
            if _same_path(path, ref_path):
                continue
            result = compare(item["measured"], measured_ref).to_json(
                tol_m=tolerance, min_groups=min_groups
            )
            result.update(candidate_source=path, reference_source=ref_path)
            comparisons.append(result)

    command = _command(args)
    summaries = [item["summary"] for item in datasets]
    print(_report(summaries, comparisons, command=command, style="text"), end="")
    document = {
        "schema_version": CHARACTERISATION_SCHEMA_VERSION,
        "command": command,
        "min_groups": min_groups,
        "tolerance_m": tolerance,
        "datasets": summaries,
        "comparisons": comparisons,
    }

    def markdown() -> str:
        text = _report(summaries, comparisons, command=command, style="markdown")
        if notes:
            text += "\n## Discussion\n\n" + notes.strip() + "\n"
        return text

    write_outputs(outputs, document=document, markdown=markdown)
    if args.check and any(not c["within_tolerance"] for c in comparisons):
        print(
            "reform-sim characterize: the mean Tightness misses the tolerance (see above)",
            file=sys.stderr,
        )
        return 1
    return 0


def _report(
    summaries: list[dict[str, Any]],
    comparisons: list[dict[str, Any]],
    *,
    command: str,
    style: str,
) -> str:
    parts = []
    if style == "markdown":
        parts += [
            "# Characterisation of F-formations",
            "",
            "Generated by:",
            "",
            "```",
            command,
            "```",
            "",
        ]
    for summary in summaries:
        parts.append(
            format_characterisation(summary, style=style, sequences=summary.get("sequences"))
        )
    for comparison in comparisons:
        parts.append(format_calibration(comparison, style=style))
    return "\n".join(parts)
