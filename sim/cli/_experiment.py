"""``reform-sim experiment``: the documented experiments, one subcommand each."""

from __future__ import annotations

import argparse

from sim.cli import (
    _experiment_gcff,
    _experiment_hri,
    _experiment_paper,
    _experiment_sim2real,
)

# Each module exposes ``register(experiments)``, adding its experiment as the commands do theirs;
# the order is the order of ``reform-sim experiment --help``.
_EXPERIMENTS = (_experiment_gcff, _experiment_paper, _experiment_hri, _experiment_sim2real)


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "experiment",
        help="run a documented experiment and write its results (Markdown + JSON)",
        arguments=_experiments,
    )


def _experiments(parser: argparse.ArgumentParser) -> None:
    experiments = parser.add_subparsers(dest="experiment", metavar="EXPERIMENT", required=True)
    for module in _EXPERIMENTS:
        module.register(experiments)
