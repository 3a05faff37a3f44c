"""``reform-sim experiment gcff``: GCFF (paper setting, tuned) beside REFORM on SALSA and Babble."""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from typing import Any

from sim.cli._common import (
    CliError,
    add_train_fraction_argument,
    check_train_fraction,
    read_text,
)
from sim.cli._experiment_io import add_out_argument, check_report, publish, report_stem

_DESCRIPTION = """\
Scores GCFF with the REFORM paper's setting (stride 0.7 m, MDL 30000 read as 30000 cm² =
3.0 m²), with the reference code's default (70 cm, 10000 cm²), and tuned by grid search on the
SALSA training split (reform.time_split), plus the majority baseline, on the SALSA test split and
on Babble, with the field's protocol. Evaluation JSON files of other detectors on the same frames
(REFORM's classifiers; dataset "salsa-test" or "babble") are added with --with-results. Writes
OUT.md and OUT.json and prints the Markdown.
"""


def register(experiments: argparse._SubParsersAction) -> None:
    experiments.add_parser(
        "gcff",
        help="GCFF (paper setting, tuned on SALSA train) beside REFORM, SALSA test and Babble",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_arguments,
    )


def _arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--salsa", required=True, metavar="PATH|NAME", help="SALSA (DANTE folder or dataset name)"
    )
    parser.add_argument(
        "--babble", required=True, metavar="PATH|NAME", help="Babble (folder or dataset name)"
    )
    add_out_argument(parser)
    add_train_fraction_argument(
        parser,
        help="share of each SALSA session's annotated frames, by time, used to tune (default 0.6)",
    )
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
    parser.set_defaults(handler=run)


def _floats(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers, e.g. 0.5,0.7, got {text!r}"
        ) from None
    return values


def _command(args: argparse.Namespace) -> str:
    words = [
        "reform-sim",
        "experiment",
        "gcff",
        "--salsa",
        args.salsa,
        "--babble",
        args.babble,
        "--train-fraction",
        f"{args.train_fraction:g}",
    ]
    for flag, grid in (("--stride-grid", args.stride_grid), ("--mdl-grid", args.mdl_grid)):
        if grid is not None:
            words += [flag, ",".join(f"{v:g}" for v in grid)]
    if args.gcff_orientation != "body":
        words += ["--gcff-orientation", args.gcff_orientation]
    for path in args.with_results:
        words += ["--with-results", path]
    words += ["--out", args.out]
    return shlex.join(words)


def _read_results(path: str) -> list[dict[str, Any]]:
    text = read_text("--with-results", path, expected="JSON text")
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CliError(f"--with-results {path}: not JSON ({exc})") from None
    if isinstance(data, dict) and "results" in data:
        data = data["results"]
    results = data if isinstance(data, list) else [data]
    for i, result in enumerate(results):
        if not isinstance(result, dict) or result.get("kind") != "reform-sim/evaluation":
            raise CliError(
                f"--with-results {path}: entry {i} must be an evaluation "
                "(kind 'reform-sim/evaluation'), got "
                f"{result.get('kind') if isinstance(result, dict) else type(result).__name__}"
            )
    return results


def run(args: argparse.Namespace) -> int:
    from reform.datasets import load_babble, load_salsa, resolve
    from sim.experiments.gcff import gcff_comparison
    from sim.experiments.gcff_report import to_markdown

    check_train_fraction(args)
    check_report(report_stem(args.out))
    extra = [result for path in args.with_results for result in _read_results(path)]
    print("tuning GCFF on the SALSA training split (a grid of settings) ...", file=sys.stderr)
    grids = {
        name: value
        for name, value in (("stride_grid", args.stride_grid), ("mdl_grid", args.mdl_grid))
        if value is not None
    }
    comparison = gcff_comparison(
        load_salsa(resolve(args.salsa)),
        load_babble(resolve(args.babble)),
        train_fraction=args.train_fraction,
        orientation=args.gcff_orientation,
        **grids,
    )
    if extra:
        comparison = comparison.with_results(extra)
    command = _command(args)
    publish(
        to_markdown(comparison, command=command), comparison.to_json(command=command), out=args.out
    )
    return 0
