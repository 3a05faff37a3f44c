"""``reform-sim experiment``: the documented experiments, one subcommand each."""

from __future__ import annotations

import argparse

from sim.cli._common import Command, add_commands

DESCRIPTION = "Runs a documented experiment and writes its results (Markdown + JSON)."

# The experiments, in the order of ``reform-sim experiment --help``.
EXPERIMENTS = (
    Command(
        "gcff",
        "GCFF (paper setting, tuned on SALSA train) beside REFORM, SALSA test and Babble",
        "sim.cli._experiment_gcff",
    ),
    Command(
        "paper",
        "the REFORM paper's experiment (Table I, Babble) on SALSA and Babble",
        "sim.cli._experiment_paper",
    ),
    Command(
        "hri",
        "the paper's HRI proof of concept re-enacted: REFORM and GCFF on the HRI scenes",
        "sim.cli._experiment_hri",
    ),
    Command(
        "sim2real",
        "REFORM trained on synthetic crowds only, tested on SALSA and Babble",
        "sim.cli._experiment_sim2real",
    ),
    Command(
        "twins",
        "venue twins of every real dataset: tuning on them, predicting each detector's F1",
        "sim.cli._experiment_twins",
    ),
    Command(
        "temporal",
        "groups in time: every detector's events, latency and flicker, and the temporal filters",
        "sim.cli._experiment_temporal",
    ),
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    experiments = parser.add_subparsers(dest="experiment", metavar="EXPERIMENT", required=True)
    add_commands(experiments, EXPERIMENTS)
