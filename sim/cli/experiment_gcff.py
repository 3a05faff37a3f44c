"""What ``reform-sim experiment gcff`` does when it runs.

Its arguments are `sim.cli._experiment_gcff`."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from reform import Dataset
from reform.datasets import load_babble, load_salsa
from reform.gcff import MDL_GRID_M2, STRIDE_GRID_M
from reform.json_values import JsonError, parse_json
from sim import sizing
from sim.cli._common import (
    CliError,
    check_train_fraction,
    max_memory,
    read_text,
    size_error,
)
from sim.cli._experiment_gcff import BASENAME
from sim.cli._experiment_io import (
    dataset_locations,
    experiment_command,
    named_datasets,
    publish,
    report_target,
)
from sim.cli._grammar import ticking_bar
from sim.experiments.gcff import GCFF_ROWS, gcff_comparison
from sim.experiments.gcff_report import to_markdown


def _command(args: argparse.Namespace) -> str:
    words = ["--train-fraction", f"{args.train_fraction:g}"]
    for flag, grid in (("--stride-grid", args.stride_grid), ("--mdl-grid", args.mdl_grid)):
        if grid is not None:
            words += [flag, ",".join(f"{v:g}" for v in grid)]
    if args.gcff_orientation != "body":
        words += ["--gcff-orientation", args.gcff_orientation]
    for path in args.with_results:
        words += ["--with-results", path]
    return experiment_command("gcff", args, words)


def _read_results(path: str) -> list[dict[str, Any]]:
    text = read_text("--with-results", path, expected="JSON text")
    try:
        data = parse_json(text)
    except JsonError as exc:
        raise CliError(f"--with-results {path}: expected JSON results, found {exc}") from None
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


def _check_size(args: argparse.Namespace, salsa: Dataset, babble: Dataset) -> None:
    """Refuses, before the grid search, one that cannot fit this machine (its settings' scores
    in memory, a week of segmenting), and states its estimate once."""
    strides = STRIDE_GRID_M if args.stride_grid is None else args.stride_grid
    mdls = MDL_GRID_M2 if args.mdl_grid is None else args.mdl_grid
    annotated = sum(1 for frame in salsa.frames if frame.groups is not None)
    tuning = round(args.train_fraction * annotated)
    scored = GCFF_ROWS * (annotated - tuning + len(babble.annotated()))
    estimate = sizing.gcff_tuning_estimate(
        settings=len(strides) * len(mdls), tuning_frames=tuning, scored_frames=scored
    )
    what = (
        f"the GCFF comparison ({len(strides)} strides x {len(mdls)} mdl values tuned on "
        f"{tuning} SALSA frames)"
    )
    try:
        sizing.check(
            estimate,
            what=what,
            shrink="shorter {stride_grid} or {mdl_grid}",
            memory_limit=max_memory(args),
            out=args.out,
        )
    except sizing.RequestTooLarge as exc:
        raise size_error(exc) from None
    print(sizing.describe(estimate, what), file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    check_train_fraction(args)
    data = named_datasets(args)
    stem = report_target(args.out, BASENAME)
    extra = [result for path in args.with_results for result in _read_results(path)]
    grids = {
        name: value
        for name, value in (("stride_grid", args.stride_grid), ("mdl_grid", args.mdl_grid))
        if value is not None
    }
    where = dataset_locations(data)
    if not args.quiet and sys.stderr.isatty():  # a refusal after it is one line in a pipe
        print("reading SALSA and Babble ...", file=sys.stderr, flush=True)
    salsa, babble = load_salsa(where["salsa"]), load_babble(where["babble"])
    _check_size(args, salsa, babble)
    if args.dry_run:
        return 0
    if not args.quiet:
        print("tuning GCFF on the SALSA training split (a grid of settings) ...", file=sys.stderr)
    # The grid tuned and every row scored in one call: about a minute on two cores.
    strides, mdls = grids.get("stride_grid", STRIDE_GRID_M), grids.get("mdl_grid", MDL_GRID_M2)
    with ticking_bar(args, "tuning GCFF", len(strides) * len(mdls), unit="setting"):
        comparison = gcff_comparison(
            salsa,
            babble,
            train_fraction=args.train_fraction,
            orientation=args.gcff_orientation,
            **grids,
        )
    if extra:
        comparison = comparison.with_results(extra)
    command = _command(args)
    publish(
        to_markdown(comparison, command=command), comparison.to_json(command=command), stem=stem
    )
    return 0
