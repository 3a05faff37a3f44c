"""What ``reform-sim calibrate`` does when it runs.

Its arguments are `sim.cli._calibrate`."""

from __future__ import annotations

import argparse
import json
import math
import shlex
import sys
from pathlib import Path

from reform.atomic import atomic_open
from reform.datasets import fetch, is_fetched, load_babble, load_salsa
from sim.cli._common import (
    DEFAULT_DATASETS,
    CliError,
    check_backend,
    check_output,
    default_datasets,
    executor_from_args,
)
from sim.experiments.calibration import DEFAULT_SEEDS, calibrate_scenarios
from sim.experiments.calibration_report import to_markdown
from sim.sizing import check_episodes


def _command(args: argparse.Namespace) -> str:
    words = ["reform-sim", "calibrate", "--out", args.out]
    if args.datasets is not None:
        words += ["--datasets", args.datasets]
    if args.seeds is not None:
        words += ["--seeds", str(args.seeds)]
    if args.check:
        words.append("--check")
    if args.jobs is not None:
        words += ["--jobs", str(args.jobs)]
    if args.backend != "local":
        words += ["--backend", args.backend]
    if args.address is not None:
        words += ["--address", args.address]
    return shlex.join(words)


def run(args: argparse.Namespace) -> int:
    seeds = DEFAULT_SEEDS if args.seeds is None else args.seeds
    if seeds < 1:
        raise CliError(f"--seeds must be >= 1, got {seeds}")
    check_episodes(seeds, what="the calibration", flag="--seeds")
    check_backend(args)
    given = args.datasets or default_datasets()
    folders = {}
    for name in ("salsa", "babble"):
        if given is not None:
            folders[name] = Path(given) / name
            if not folders[name].is_dir():
                raise CliError(f"--datasets {given}: no {name}/ folder in it")
        elif is_fetched(name):
            folders[name] = fetch(name)
        else:
            raise CliError(
                f"{name} not found: give --datasets DIR (holding salsa/ and babble/; default "
                f"{DEFAULT_DATASETS}) or fetch it with `reform-sim datasets fetch {name}`"
            )
    check_output("--out", args.out, folder=True)
    out = Path(args.out)
    salsa, babble = load_salsa(folders["salsa"]), load_babble(folders["babble"])
    with executor_from_args(args, progress=not args.no_progress) as executor:
        report = calibrate_scenarios(
            salsa, babble, seeds=seeds, command=_command(args), executor=executor
        )
    out.mkdir(parents=True, exist_ok=True)
    markdown = out / "calibration.md"
    with atomic_open(markdown) as handle:
        handle.write(to_markdown(report))
    with atomic_open(out / "calibration.json") as handle:
        json.dump(report.to_json(), handle, indent=2, allow_nan=False)
        handle.write("\n")
    for cal in report.calibrations:
        checked = cal.comparison.reference_sizes()
        gaps = [abs(d) for s, d in cal.comparison.tightness_difference().items() if s in checked]
        worst = max((g for g in gaps if math.isfinite(g)), default=math.nan)
        ks = ", ".join(f"{k.statistic:.3f}" for k in cal.comparison.ks)
        print(
            f"{cal.scenario} vs {cal.reference}: largest Tightness difference {worst:.3f} m; "
            f"KS D (distance in/out, effort in/out) {ks}"
        )
    failures = report.failures()
    print(f"wrote {markdown} and {out / 'calibration.json'}", file=sys.stderr)
    if failures:
        for line in failures:
            print(f"missed: {line}", file=sys.stderr)
        if args.check:
            return 1
    return 0
