"""``reform-sim demo``: the whole toolkit on an embedded default, in a few minutes."""

from __future__ import annotations

import argparse
import sys
import time

from sim.cli._common import CliError, check_output, default_datasets

_DESCRIPTION = """\
Simulates every registered scenario briefly, generates a synthetic training set (mingle and
word-improv), trains REFORM on it, scores REFORM and GCFF on held-back synthetic episodes and,
when found under --datasets, on the SALSA test split and Babble, runs the stress tests on the
small grid and re-enacts the paper's HRI experiment. Writes Rerun recordings (.rrd), the model
(model.skops), plots and a Markdown report into --out, and says where they are.
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "demo",
        help="the whole toolkit on an embedded default: simulate, train, evaluate, record, report",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_arguments,
    )


def _arguments(parser: argparse.ArgumentParser) -> None:
    from sim.experiments.demo_files import DEFAULT_OUT

    parser.add_argument(
        "--datasets",
        metavar="DIR",
        default=None,
        help="folder holding salsa/ and/or babble/ (default: $REFORM_SIM_DATASETS, else "
        "../shared/datasets when it exists, else synthetic data only)",
    )
    parser.add_argument(
        "--out", default=DEFAULT_OUT, metavar="DIR", help=f"output folder ({DEFAULT_OUT})"
    )
    parser.add_argument("--seed", type=int, default=0, metavar="S", help="master seed (0)")
    parser.add_argument(
        "--jobs", type=int, default=None, metavar="N", help="worker processes (every core)"
    )
    parser.add_argument(
        "--quick", action="store_true", help="tiny budgets: a smoke run in well under a minute"
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from sim.experiments.demo import run_demo
    from sim.experiments.demo_report import write_report

    if args.seed < 0:
        raise CliError(f"--seed must be >= 0, got {args.seed}")
    check_output("--out", args.out, folder=True)
    started = time.perf_counter()
    result = run_demo(
        out_dir=args.out,
        datasets=args.datasets if args.datasets is not None else default_datasets(),
        seed=args.seed,
        jobs=args.jobs,
        quick=args.quick,
        progress_bars=not args.no_progress,
    )
    written = write_report(result)
    seconds = time.perf_counter() - started
    out = result.out_dir
    print(f"demo finished in {seconds / 60:.1f} min; everything is in {out}/:")
    print(f"  report:     {written['markdown']}")
    print(f"  numbers:    {written['json']}")
    print(f"  model:      {result.model}")
    print(f"  recordings: {len(result.recordings)} .rrd files in {out / 'recordings'}/")
    for path in result.recordings:
        print(f"    rerun {path}")
    print(f"  figures:    {len(result.figures)} PNG files")
    missing = [name for name in ("salsa", "babble") if name not in result.datasets]
    if missing:
        print(
            f"real datasets: {' and '.join(missing)} not found, so this run scored simulated "
            "data only. Add them with `reform-sim datasets fetch salsa babble` (or give "
            "--datasets DIR, a folder holding salsa/ and babble/) and run again for the "
            "SALSA and Babble evaluations."
        )
    sys.stdout.flush()
    return 0
