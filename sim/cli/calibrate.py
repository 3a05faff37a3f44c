"""What ``reform-sim calibrate`` does when it runs.

Its arguments are `sim.cli._calibrate`."""

from __future__ import annotations

import argparse
import math
import shlex
import sys
from pathlib import Path

from reform.datasets import load_babble, load_salsa, resolve
from sim.cli._calibrate import BASENAME
from sim.cli._common import CliError, backend_words, check_output, executor_from_args
from sim.cli._experiment_io import dataset_words, named_datasets, write_report
from sim.experiments.calibration import DEFAULT_SEEDS, calibrate_scenarios
from sim.experiments.calibration_report import to_markdown
from sim.sizing import check_episodes


def _command(args: argparse.Namespace) -> str:
    words = ["reform-sim", "calibrate", "--out", args.out, *dataset_words(args)]
    if args.episodes is not None:
        words += ["--episodes", str(args.episodes)]
    if args.check:
        words.append("--check")
    words += backend_words(args)
    return shlex.join(words)


def run(args: argparse.Namespace) -> int:
    seeds = DEFAULT_SEEDS if args.episodes is None else args.episodes
    if seeds < 1:
        raise CliError(f"--episodes must be >= 1, got {seeds}")
    check_episodes(seeds, what="the calibration", flag="--episodes")
    executor = executor_from_args(args, progress=not args.quiet)  # the Ray address probed
    folders = {}
    for name, given in named_datasets(args).items():
        try:
            folders[name] = resolve(given)
        except FileNotFoundError as exc:
            raise CliError(
                f"{name} not found ({exc}): give --data DIR (holding salsa/ and babble/) or "
                f"--data {name}=PATH, or fetch it with `reform-sim datasets fetch {name}`"
            ) from None
    check_output("--out", args.out, folder=True)
    stem = Path(args.out) / BASENAME
    salsa, babble = load_salsa(folders["salsa"]), load_babble(folders["babble"])
    with executor:
        report = calibrate_scenarios(
            salsa, babble, seeds=seeds, command=_command(args), executor=executor
        )
    write_report(stem, to_markdown(report), report.to_json())
    markdown = stem.with_suffix(".md")
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
    print(f"wrote {markdown} and {stem.with_suffix('.json')}", file=sys.stderr)
    if failures:
        for line in failures:
            print(f"missed: {line}", file=sys.stderr)
        if args.check:
            return 1
    return 0
