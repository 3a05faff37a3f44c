"""What ``reform-sim calibrate`` does when it runs.

Its arguments are `sim.cli._calibrate`."""

from __future__ import annotations

import argparse
import math
import shlex
import sys
import time
from pathlib import Path

from reform.datasets import load_babble, load_salsa, resolve
from sim.cli._calibrate import BASENAME
from sim.cli._common import CliError, check_output
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
    return shlex.join(words)


def run(args: argparse.Namespace) -> int:
    seeds = DEFAULT_SEEDS if args.episodes is None else args.episodes
    if seeds < 1:
        raise CliError(f"--episodes must be >= 1, got {seeds}")
    check_episodes(seeds, what="the calibration", flag="--episodes")
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
    started = time.perf_counter()

    def progress(line: str) -> None:
        if not args.quiet:
            print(f"[{time.perf_counter() - started:6.1f} s] {line}", file=sys.stderr, flush=True)

    report = calibrate_scenarios(
        load_salsa(folders["salsa"]),
        load_babble(folders["babble"]),
        seeds=seeds,
        command=_command(args),
        progress=progress,
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
