"""The ``reform-sim`` command: thin subcommands that parse, call one library function, report.

Importing this package imports neither argparse nor any subcommand: the command table is here,
the parser and the run in `sim.cli._main` (its public names, `main` and `build_parser`, loaded
on first use). ``reform-sim --help`` is answered from the help argparse formatted the last time
for the same code, Python, terminal and language (`sim.cli._help_cache`), and ``--version``
without a parser, so that both answer as fast as Python starts.
"""

from __future__ import annotations

import sys

from reform._lazy import lazy_exports
from sim.cli._command import Command

# The subcommands, in the order of ``reform-sim --help``: each a name, its help line and the
# module of its arguments (`sim.cli._NAME`; what it does is `sim.cli.NAME`).
COMMANDS = (
    Command(
        "demo",
        "the whole toolkit on an embedded default: simulate, train, evaluate, record, report",
        "sim.cli._demo",
    ),
    Command("data", "inspect or convert a dataset", "sim.cli._data"),
    Command("datasets", "list or fetch the field's public datasets", "sim.cli._datasets"),
    Command(
        "evaluate",
        "score a detector on a dataset (pairwise accuracy, P/R/F1 at T=2/3 and T=1)",
        "sim.cli._evaluate",
    ),
    Command(
        "detect",
        "run a detector and write the detected groups of every frame as JSON",
        "sim.cli._detect",
    ),
    Command(
        "benchmark",
        "every detector on every dataset: P/R/F1 at T = 2/3 and 1, and the mean",
        "sim.cli._benchmark",
    ),
    Command(
        "experiment",
        "run a documented experiment and write its results (Markdown + JSON)",
        "sim.cli._experiment",
    ),
    Command(
        "train",
        "train REFORM on a dataset's annotated frames and save it (skops)",
        "sim.cli._train",
    ),
    Command(
        "characterize",
        "Tightness and Symmetry by group size, ANOVA, Tukey's HSD; compare with real data",
        "sim.cli._characterize",
        aliases=("characterise",),
    ),
    Command("scenarios", "list the registered scenarios and their options", "sim.cli._scenarios"),
    Command(
        "simulate",
        "run one episode of a scenario and write its frames (Parquet)",
        "sim.cli._simulate",
    ),
    Command(
        "generate",
        "generate a synthetic dataset: many seeded episodes as Parquet shards",
        "sim.cli._generate",
    ),
    Command(
        "twin",
        "fit a venue twin to a recording's frames (no labels): scenario and annotation model",
        "sim.cli._twin",
    ),
    Command(
        "tune",
        "choose a detector's settings on a venue twin's data; write a settings or model file",
        "sim.cli._tune",
    ),
    Command(
        "calibrate",
        "simulate the scenarios and set them beside SALSA and Babble",
        "sim.cli._calibrate",
    ),
    Command(
        "stress",
        "stress tests: F1 of REFORM and GCFF against noise, dropouts, crowds, the sensor",
        "sim.cli._stress",
    ),
    Command(
        "policy",
        "scripted baseline of the Gymnasium joining task: success rate",
        "sim.cli._policy",
    ),
)


_EXPORTS = {
    name: "sim.cli._main"
    for name in ("INTERRUPTED", "RERUN_LOG", "build_parser", "main", "_resumes")
}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)


def console_main() -> int:
    """The ``reform-sim`` console command: `main`, with Ctrl-C reported in one line (exit
    status 130) rather than as a traceback, and SIGTERM likewise (status 143)."""
    argv = sys.argv[1:]
    if argv in (["-h"], ["--help"], ["--version"]):
        from sim.cli._help_cache import answer

        return answer(argv[0])
    from sim.cli._main import console_main as run

    return run()
