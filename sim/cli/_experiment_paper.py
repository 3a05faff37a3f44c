"""``reform-sim experiment paper``: the REFORM paper's Table I and Babble table on the real data."""

from __future__ import annotations

import argparse
import shlex
import sys
import time

from sim.cli._common import (
    TRAIN_FRACTION,
    CliError,
    add_train_fraction_argument,
    check_train_fraction,
)
from sim.cli._experiment_io import (
    add_dataset_arguments,
    add_out_argument,
    check_report,
    dataset_words,
    publish,
    report_stem,
    salsa_and_babble,
)

_DESCRIPTION = """\
Trains REFORM with the paper's three classifiers on the SALSA training split (reform.time_split:
per session, the first 60 % of annotated frames by time), with hyper-parameters chosen by
time-blocked cross-validation on that part only, and scores them and the majority baseline on
the SALSA test split and on every annotated Babble frame, at T = 2/3 and T = 1, beside the
paper's published figures. Diagnostics rerun the classifiers under the paper's kind of split,
MATLAB's presets and a feature slip, to explain the differences. Writes OUT.md and OUT.json and
prints the Markdown.
"""


def register(experiments: argparse._SubParsersAction) -> None:
    experiments.add_parser(
        "paper",
        help="the REFORM paper's experiment (Table I, Babble) on SALSA and Babble",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_arguments,
    )


def _arguments(parser: argparse.ArgumentParser) -> None:
    add_dataset_arguments(parser)
    add_out_argument(parser)
    add_train_fraction_argument(
        parser,
        help="share of each SALSA session's annotated frames, by time, for training (0.6)",
    )
    parser.add_argument("--folds", type=int, default=5, metavar="K", help="CV folds (5)")
    parser.add_argument("--jobs", type=int, default=None, metavar="N", help="parallel CV fits")
    parser.add_argument(
        "--no-diagnostics", action="store_true", help="skip the diagnostic reruns (faster)"
    )
    parser.set_defaults(handler=run)


def _command(args: argparse.Namespace) -> str:
    words = ["reform-sim", "experiment", "paper", *dataset_words(args)]
    if args.train_fraction != TRAIN_FRACTION:
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
    from reform.datasets import load_babble, load_salsa, resolve
    from sim.experiments.paper import paper_experiment
    from sim.experiments.paper_report import to_markdown

    check_train_fraction(args)
    if args.folds < 2:
        raise CliError(f"--folds must be at least 2, got {args.folds}")
    salsa, babble = salsa_and_babble(args)
    check_report(report_stem(args.out))
    started = time.perf_counter()

    def progress(message: str) -> None:
        print(f"[{time.perf_counter() - started:6.1f} s] {message}", file=sys.stderr)

    experiment = paper_experiment(
        load_salsa(resolve(salsa)),
        load_babble(resolve(babble)),
        train_fraction=args.train_fraction,
        n_folds=args.folds,
        n_jobs=args.jobs,
        diagnostics=not args.no_diagnostics,
        progress=progress,
    )
    command = _command(args)
    publish(
        to_markdown(experiment, command=command), experiment.to_json(command=command), out=args.out
    )
    return 0
