"""``reform-sim experiment paper``: the REFORM paper's Table I and Babble table on the real data."""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import time
from pathlib import Path

from sim.cli._common import CliError
from sim.cli._experiment_gcff import _experiment_subparsers

_DESCRIPTION = """\
Trains REFORM with the paper's three classifiers on the SALSA training split (reform.time_split:
per session, the first 60 % of annotated frames by time), with hyper-parameters chosen by
time-blocked cross-validation on that part only, and scores them and the majority baseline on
the SALSA test split and on every annotated Babble frame, at T = 2/3 and T = 1, beside the
paper's published figures. Diagnostics rerun the classifiers under the paper's kind of split,
MATLAB's presets and a feature slip, to explain the differences. Writes OUT.md and OUT.json and
prints the Markdown.
"""


def register(subparsers) -> None:
    parser = _experiment_subparsers(subparsers).add_parser(
        "paper",
        help="the REFORM paper's experiment (Table I, Babble) on SALSA and Babble",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--datasets",
        metavar="DIR",
        help="folder holding salsa/ and babble/ (e.g. ../shared/datasets)",
    )
    parser.add_argument("--salsa", metavar="PATH", help="SALSA folder (default: DIR/salsa)")
    parser.add_argument("--babble", metavar="PATH", help="Babble folder (default: DIR/babble)")
    parser.add_argument(
        "--out",
        required=True,
        metavar="OUT",
        help="output path without extension: writes OUT.md and OUT.json",
    )
    parser.add_argument(
        "--train-fraction",
        type=float,
        default=0.6,
        metavar="F",
        help="share of each SALSA session's annotated frames, by time, for training (0.6)",
    )
    parser.add_argument("--folds", type=int, default=5, metavar="K", help="CV folds (5)")
    parser.add_argument("--jobs", type=int, default=None, metavar="N", help="parallel CV fits")
    parser.add_argument(
        "--no-diagnostics", action="store_true", help="skip the diagnostic reruns (faster)"
    )
    parser.set_defaults(handler=run)


def _command(args: argparse.Namespace) -> str:
    words = ["reform-sim", "experiment", "paper"]
    if args.datasets:
        words += ["--datasets", args.datasets]
    for flag, value in (("--salsa", args.salsa), ("--babble", args.babble)):
        if value:
            words += [flag, value]
    if args.train_fraction != 0.6:
        words += ["--train-fraction", f"{args.train_fraction:g}"]
    if args.folds != 5:
        words += ["--folds", str(args.folds)]
    if args.jobs is not None:
        words += ["--jobs", str(args.jobs)]
    if args.no_diagnostics:
        words.append("--no-diagnostics")
    words += ["--out", args.out]
    return shlex.join(words)


def run(args: argparse.Namespace) -> int:
    from reform.atomic import atomic_open
    from reform.datasets import load_babble, load_salsa
    from reform.experiment import paper_experiment

    if not 0.0 < args.train_fraction < 1.0:
        raise CliError(f"--train-fraction must lie in (0, 1), got {args.train_fraction}")
    if args.folds < 2:
        raise CliError(f"--folds must be at least 2, got {args.folds}")
    salsa = args.salsa or (args.datasets and str(Path(args.datasets) / "salsa"))
    babble = args.babble or (args.datasets and str(Path(args.datasets) / "babble"))
    if not salsa or not babble:
        raise CliError("give --datasets DIR (holding salsa/ and babble/) or --salsa and --babble")
    started = time.perf_counter()

    def progress(message: str) -> None:
        print(f"[{time.perf_counter() - started:6.1f} s] {message}", file=sys.stderr)

    experiment = paper_experiment(
        load_salsa(salsa),
        load_babble(babble),
        train_fraction=args.train_fraction,
        n_folds=args.folds,
        n_jobs=args.jobs,
        diagnostics=not args.no_diagnostics,
        progress=progress,
    )
    command = _command(args)
    markdown = experiment.to_markdown(command=command)
    out = Path(args.out)
    if out.suffix in (".md", ".json"):
        out = out.with_suffix("")
    with atomic_open(out.with_name(out.name + ".md")) as handle:
        handle.write(markdown)
    with atomic_open(out.with_name(out.name + ".json")) as handle:
        json.dump(experiment.to_json(command=command), handle, indent=2, allow_nan=False)
        handle.write("\n")
    print(markdown, end="")
    print(f"wrote {out}.md and {out}.json", file=sys.stderr)
    return 0
