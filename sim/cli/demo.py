"""What ``reform-sim demo`` does when it runs.

Its arguments are `sim.cli._demo`."""

from __future__ import annotations

import argparse
import sys
import time

from sim.cli._common import check_output, default_datasets
from sim.experiments.demo import run_demo
from sim.experiments.demo_report import write_report
from sim.recording import rerun_in_this_shell


def run(args: argparse.Namespace) -> int:
    check_output("--out", args.out, folder=True)
    started = time.perf_counter()
    result = run_demo(
        out_dir=args.out,
        datasets=args.data if args.data is not None else default_datasets(),
        seed=args.seed,
        jobs=args.jobs,
        quick=args.quick,
        progress=(lambda _line: None) if args.quiet else None,
        progress_bars=not args.quiet,
        recordings=args.recordings,
    )
    written = write_report(result)
    seconds = time.perf_counter() - started
    out = result.out_dir
    print(f"demo finished in {seconds / 60:.1f} min; everything is in {out}/:")
    print(f"  report:     {written['markdown']}")
    print(f"  numbers:    {written['json']}")
    print(f"  model:      {result.model}")
    if args.recordings:
        print(f"  recordings: {len(result.recordings)} .rrd files in {out / 'recordings'}/")
        rerun = rerun_in_this_shell()
        for path in result.recordings:
            print(f"    {rerun} {path}")
    else:
        print("  recordings: none (--no-recordings)")
    print(f"  figures:    {len(result.figures)} PNG files")
    missing = [name for name in ("salsa", "babble") if name not in result.datasets]
    if missing:
        print(
            f"real datasets: {' and '.join(missing)} not found, so this run scored simulated "
            "data only. Add them with `reform-sim datasets fetch salsa babble` (or give "
            "--data DIR, a folder holding salsa/ and babble/) and run again for the "
            "SALSA and Babble evaluations."
        )
    sys.stdout.flush()
    return 0
