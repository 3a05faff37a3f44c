"""What ``reform-sim experiment twins`` does when it runs.

Its arguments are `sim.cli._experiment_twins`."""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from pathlib import Path

from sim.cli._common import CliError, check_output, refuse_given_twice
from sim.cli._experiment_io import REPORT_SUFFIXES, check_report, report_stem, write_report
from sim.cli._experiment_twins import (
    BASENAME,
    MAX_REPEATS,
    MAX_SEEDS,
    PER_PLACE,
    REPEATS,
    TWINS,
)

FIGURE = ".png"


def _load(entries: list[str]) -> dict:
    """``--data`` values (or every dataset found), each recording once: name -> dataset."""
    from reform.datasets import DataFormatError, load_dataset, resolve
    from reform.datasets.store import is_uri
    from sim.experiments.benchmark import found_datasets, one_recording_each
    from sim.twins import TwinInputError, check_frames_for_twin

    named: dict[str, str] = {}
    given = []
    for value in entries or found_datasets():
        name, sep, path = value.partition("=")
        if sep and (not name or not path):
            raise CliError(f"--data {value}: expected NAME=PATH, got an empty side")
        name = (name if sep else Path(value).name or value).lower()
        given.append((value, name))
        named[name] = path if sep else value
    refuse_given_twice("--data", given)
    typed = {name: value for value, name in given}  # as given on the command line
    kept, left_out = one_recording_each(list(named), named=set(named) if entries else ())
    print(*left_out, sep="\n", file=sys.stderr, end="\n" if left_out else "")
    where = {}
    for name in kept:
        try:
            where[name] = resolve(named[name])
        except FileNotFoundError as exc:
            raise CliError(f"--data {named[name]}: {exc}") from None
    refuse_given_twice(  # two names for one recording: it would count twice
        "--data",
        [
            (typed[name], at if is_uri(at) else Path(at).resolve())
            for name, at in where.items()
        ],
    )
    out = {}
    for name in kept:
        try:
            out[name] = load_dataset(where[name])
            check_frames_for_twin(list(out[name]), where=f"--data {named[name]}")
        except (FileNotFoundError, DataFormatError) as exc:
            raise CliError(f"--data {named[name]}: {exc}") from None
        except TwinInputError as exc:
            raise CliError(str(exc)) from None
        annotated = len(out[name].annotated())
        if annotated < 2:  # the first half tunes and the second is scored
            raise CliError(
                f"--data {named[name]}: field groups: expected two or more annotated frames to "
                f"score (a first half and a second), found {annotated}"
            )
    if len(out) < 2:
        raise CliError(
            f"the experiment compares datasets: expected two or more, found {len(out)} "
            "(fetch them with `reform-sim datasets fetch --all` or give --data)"
        )
    return out


def _command(args: argparse.Namespace) -> str:
    words = ["reform-sim", "experiment", "twins"]
    for value in args.data:
        words += ["--data", value]
    if args.twins is not None:
        words += ["--twins", args.twins]
    if args.seed != 0:
        words += ["--seed", str(args.seed)]
    if args.repeats != REPEATS:
        words += ["--repeats", str(args.repeats)]
    if args.twins_per_place != PER_PLACE:
        words += ["--twins-per-place", str(args.twins_per_place)]
    words += ["--out", args.out]
    return shlex.join(words)


def run(args: argparse.Namespace) -> int:
    import dataclasses

    from sim.experiments.twins import across_seeds, run_twins
    from sim.experiments.twins_report import scatter_figure, to_markdown

    if not 1 <= args.repeats <= MAX_REPEATS:
        raise CliError(f"--repeats: expected 1 to {MAX_REPEATS}, found {args.repeats}")
    per_place = args.twins_per_place
    if not 1 <= per_place or args.repeats * per_place > MAX_SEEDS:
        raise CliError(
            f"--twins-per-place: expected 1 to {MAX_SEEDS // args.repeats} with --repeats "
            f"{args.repeats} (at most {MAX_SEEDS} seeds), found {per_place}"
        )
    out = report_stem(args.out, BASENAME, suffixes=(*REPORT_SUFFIXES, FIGURE))
    check_report(out, suffixes=(*REPORT_SUFFIXES, FIGURE))
    twins = args.twins if args.twins is not None else out.parent / TWINS
    check_output("--twins", twins, folder=True)
    real = _load(args.data)
    started = time.perf_counter()

    def progress(message: str) -> None:
        if not args.quiet:
            print(
                f"[{time.perf_counter() - started:6.1f} s] {message}", file=sys.stderr, flush=True
            )

    seeds = [args.seed + k for k in range(args.repeats * per_place)]
    results = []
    for seed in seeds:
        say = progress if len(seeds) == 1 else lambda m, seed=seed: progress(f"seed {seed}: {m}")
        root = Path(twins) if seed == args.seed else Path(twins) / f"seed-{seed}"
        results.append(run_twins(real, root=root, seed=seed, progress=say))
    result = results[0]
    if len(results) > 1:
        result = dataclasses.replace(
            result,
            seeds=across_seeds(results, per_place=per_place),
            seconds=time.perf_counter() - started,
        )
    command = _command(args)
    figure = scatter_figure(result, out.with_name(out.name + FIGURE)).name
    markdown = to_markdown(result, command=command, figure=figure)
    write_report(out, markdown, result.to_json(command=command))
    print(markdown, end="")
    print(f"wrote {out}.md, {out}.json and {figure}", file=sys.stderr)
    return 0
