"""What ``reform-sim experiment sim2real`` does when it runs.

Its arguments are `sim.cli._experiment_sim2real`."""

from __future__ import annotations

import argparse
import math
import shlex
import sys
import time
from pathlib import Path

from reform.datasets import DataFormatError, detect_format, load_dataset, resolve
from reform.frame import Dataset
from sim.cli._common import CliError, backend_words, check_output, executor_from_args
from sim.cli._experiment_io import REPORT_SUFFIXES, check_report, report_stem, write_report
from sim.cli._experiment_sim2real import BASENAME, SYNTHETIC
from sim.cli._grammar import ticking_bar
from sim.experiments.benchmark import found_datasets, one_recording_each
from sim.experiments.sim2real import CLASSIFIER_NAMES, RECIPES, SALSA, sim_to_real
from sim.experiments.sim2real_report import (
    calibration_figure,
    rank_figure,
    sim2real_figure,
    to_markdown,
)

FIGURES = (".png", "-rank.png", "-calibration.png")
MODEL = "recommended.skops"


def _datasets_in(folder: Path) -> list[Path]:
    """The subfolders of ``folder`` that hold a dataset in a format read here, in name order
    (none when ``folder`` is not a folder)."""
    if not folder.is_dir():
        return []
    found = []
    for child in sorted(folder.iterdir()):
        if not child.is_dir() or child.name.startswith((".", "_")):
            continue
        try:
            detect_format(child)
        except ValueError:
            continue  # holds no dataset (a format none reads): not one of them
        found.append(child)
    return found


def load_named(entries: list[str]) -> dict[str, Dataset]:
    """``--data`` values (or every dataset found) loaded: dataset name -> dataset. A folder of
    datasets gives each dataset in it, named by its folder. A recording is scored once: a
    second packaging of it that was found, not named, is left out (said on stderr)."""
    named: dict[str, str] = {}
    chosen: set[str] = set()  # the datasets named one by one on the command line
    for value in entries or found_datasets():
        name, sep, path = value.partition("=")
        if sep and (not name or not path):
            raise CliError(f"--data {value}: expected NAME=PATH, got an empty side")
        where = path if sep else value
        named[(name if sep else Path(value).name or value).lower()] = where
    out: dict[str, Dataset] = {}
    for name, where in named.items():
        try:
            out[name] = load_dataset(resolve(where))
            chosen.update([name] if entries else [])
        except FileNotFoundError as exc:
            raise CliError(f"--data {where}: {exc}") from None
        except DataFormatError as exc:
            children = _datasets_in(Path(resolve(where)))
            if not children:  # one dataset, malformed
                raise CliError(str(exc)) from None
            for child in children:  # a folder of datasets
                try:
                    out.setdefault(child.name.lower(), load_dataset(child))
                except DataFormatError as inner:
                    raise CliError(str(inner)) from None
    kept, left_out = one_recording_each(list(out), named=chosen)
    print(*left_out, sep="\n", file=sys.stderr, end="\n" if left_out else "")
    out = {name: out[name] for name in kept}
    if SALSA not in out:
        raise CliError(
            "the experiment needs SALSA (its training split is the one real set the choice may "
            f"see), got {', '.join(out) or 'no dataset'}: fetch it with `reform-sim datasets "
            "fetch salsa` or give --data salsa=PATH"
        )
    return out


def _command(args: argparse.Namespace) -> str:
    words = ["reform-sim", "experiment", "sim2real"]
    for value in args.data:
        words += ["--data", value]
    if args.seed != 0:
        words += ["--seed", str(args.seed)]
    if args.episodes_scale != 1.0:
        words += ["--episodes-scale", f"{args.episodes_scale:g}"]
    if args.classifiers:
        words += ["--classifiers", args.classifiers]
    words += backend_words(args)
    words += ["--out", args.out]
    return shlex.join(words)


def run(args: argparse.Namespace) -> int:
    if not (math.isfinite(args.episodes_scale) and args.episodes_scale > 0):
        raise CliError(f"--episodes-scale must be a finite number > 0, got {args.episodes_scale}")
    classifiers = CLASSIFIER_NAMES
    if args.classifiers:
        classifiers = tuple(c.strip() for c in args.classifiers.split(",") if c.strip())
        unknown = [c for c in classifiers if c not in CLASSIFIER_NAMES]
        if unknown or not classifiers:
            raise CliError(
                f"--classifiers must be among {','.join(CLASSIFIER_NAMES)}, "
                f"got {args.classifiers!r}"
            )
    out = report_stem(args.out, BASENAME, suffixes=(*REPORT_SUFFIXES, *FIGURES))
    check_report(out, suffixes=(*REPORT_SUFFIXES, *FIGURES))
    synthetic = args.synthetic if args.synthetic is not None else out.parent / SYNTHETIC
    check_output("--synthetic", synthetic, folder=True)
    executor = executor_from_args(args, progress=not args.quiet)  # the Ray address probed
    real = load_named(args.data)
    recipes = tuple(r.scaled(args.episodes_scale) for r in RECIPES)
    started = time.perf_counter()

    def progress(message: str) -> None:
        if not args.quiet:
            print(
                f"[{time.perf_counter() - started:6.1f} s] {message}", file=sys.stderr, flush=True
            )

    with executor:
        result = sim_to_real(
            real,
            synthetic_root=synthetic,
            recipes=recipes,
            classifiers=classifiers,
            seed=args.seed,
            out_model=out.parent / MODEL,
            progress=progress,
            progress_bars=not args.quiet,
            executor=executor,
        )
    command = _command(args)
    names = []
    drawings = (sim2real_figure, rank_figure, calibration_figure)
    progress("drawing the figures")
    with ticking_bar(args, "figures", len(FIGURES), unit="figure"):  # seconds on busy cores
        for suffix, draw in zip(FIGURES, drawings, strict=True):
            names.append(draw(result, out.with_name(out.name + suffix)).name)
    markdown = to_markdown(result, command=command, figures=names)
    write_report(out, markdown, result.to_json(command=command))
    print(markdown, end="")
    print(
        f"wrote {out}.md, {out}.json, {', '.join(names)} and {out.parent / MODEL}",
        file=sys.stderr,
    )
    return 0
