"""What ``reform-sim experiment paper`` does when it runs.

Its arguments are `sim.cli._experiment_paper`."""

from __future__ import annotations

import argparse

from reform.datasets import load_babble, load_salsa
from sim.cli._common import (
    TRAIN_FRACTION,
    CliError,
    check_train_fraction,
    job_count,
)
from sim.cli._experiment_io import (
    dataset_locations,
    experiment_command,
    named_datasets,
    publish,
    report_target,
)
from sim.cli._experiment_paper import BASENAME
from sim.cli._grammar import stage_lines
from sim.experiments.paper import paper_experiment
from sim.experiments.paper_report import to_markdown


def _command(args: argparse.Namespace) -> str:
    words = []
    if args.train_fraction != TRAIN_FRACTION:
        words += ["--train-fraction", f"{args.train_fraction:g}"]
    if args.folds != 5:
        words += ["--folds", str(args.folds)]
    if args.jobs is not None:
        words += ["--jobs", str(args.jobs)]
    if args.no_diagnostics:
        words.append("--no-diagnostics")
    return experiment_command("paper", args, words)


def run(args: argparse.Namespace) -> int:
    check_train_fraction(args)
    if args.folds < 2:
        raise CliError(f"--folds must be at least 2, got {args.folds}")
    data = named_datasets(args)
    stem = report_target(args.out, BASENAME)
    where = dataset_locations(data)

    with stage_lines(args, "experiment paper") as progress:
        experiment = paper_experiment(
            load_salsa(where["salsa"]),
            load_babble(where["babble"]),
            train_fraction=args.train_fraction,
            n_folds=args.folds,
            n_jobs=job_count(args),
            diagnostics=not args.no_diagnostics,
            progress=progress,
        )
    command = _command(args)
    publish(
        to_markdown(experiment, command=command), experiment.to_json(command=command), stem=stem
    )
    return 0
