"""Start-up time of the ``reform-sim`` command, beside every subcommand's parser built at once.

Measured in the same run, each a fresh interpreter (wall time, median of ``--repeats``):

* **python**: ``python -c pass``, the floor under any command;
* **--help**: ``reform-sim --help``: the parser with each subcommand's name and help line only;
* **data info --help**, **evaluate --help**: one subcommand's arguments added (evaluate's pull
  in the Rerun flags of `sim.recording`, which import neither rerun nor reform's modules);
* **train --help**, **stress --help**: subcommands whose arguments list reform's classifiers
  (`reform.classifiers`, which imports scikit-learn) and the stress tests' grids
  (`sim.experiments.stress_grid`, which imports neither scikit-learn nor MuJoCo);
* **experiment hri --help**: its views and default size come from `sim.experiments.hri_views`
  (light too);
* **import reform**: the package alone, its public names loaded on first use;
* **every parser** (the baseline): gymnasium imported and every subcommand's arguments added, as
  building the parser did before subcommands were added on use.

The ratio every parser / --help is the median of the ratios of runs made one after the other,
so that a change of load on the machine hits both alike.

Run: ``python benchmarks/bench_cli_startup.py [--repeats 7] [--quick]`` (``--quick``: one run
per case, the file cache not warmed first).
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time
from pathlib import Path

from timing import BenchmarkParser

ROOT = Path(__file__).resolve().parents[1]
COMMAND = [sys.executable, "-c", "import sys; from sim.cli import main; sys.exit(main())"]
EVERY_PARSER = (
    "import argparse, gymnasium\n"
    "from sim.cli import build_parser\n"
    "def build(parser):\n"
    "    for action in parser._actions:\n"
    "        if isinstance(action, argparse._SubParsersAction):\n"
    "            for child in action.choices.values():\n"
    "                child.format_help()\n"
    "                build(child)\n"
    "build(build_parser())\n"
)
CASES = {
    "python": [sys.executable, "-c", "pass"],
    "--help": [*COMMAND, "--help"],
    "data info --help": [*COMMAND, "data", "info", "--help"],
    "evaluate --help": [*COMMAND, "evaluate", "--help"],
    "train --help": [*COMMAND, "train", "--help"],
    "stress --help": [*COMMAND, "stress", "--help"],
    "experiment hri --help": [*COMMAND, "experiment", "hri", "--help"],
    "import reform": [sys.executable, "-c", "import reform"],
    "every parser": [sys.executable, "-c", EVERY_PARSER],
}


def _seconds(argv: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(argv, cwd=ROOT, stdout=subprocess.DEVNULL, check=True)
    return time.perf_counter() - start


def main() -> None:
    args = BenchmarkParser(__doc__, repeats=7).parse_args()
    repeats = args.repeats
    if not args.quick:
        for argv in CASES.values():  # warm the file cache
            _seconds(argv)
    times: dict[str, list[float]] = {name: [] for name in CASES}
    for _ in range(repeats):
        for name, argv in CASES.items():
            times[name].append(_seconds(argv))
    for name, values in times.items():
        print(f"{name:<22} median {statistics.median(values):6.3f} s  best {min(values):6.3f} s")
    ratios = [e / h for e, h in zip(times["every parser"], times["--help"], strict=True)]
    print(f"every parser / --help: {statistics.median(ratios):.1f}x")


if __name__ == "__main__":
    main()
