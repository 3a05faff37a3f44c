"""What ``reform-sim experiment temporal`` does when it runs.

Its arguments are `sim.cli._experiment_temporal`."""

from __future__ import annotations

import argparse
import shlex
import sys

from sim.cli._common import CliError, job_count
from sim.cli._experiment_io import REPORT_SUFFIXES, check_report, report_stem, write_report
from sim.cli._experiment_temporal import BASENAME
from sim.cli._grammar import stage_lines
from sim.experiments.temporal import DURATION_S, EPISODES, RATE_HZ

FIGURE = ".png"


def _real(entries: list[str]) -> list:
    """The real datasets: ``--data`` values (``none``: no real dataset), or every one found,
    each recording once, checked readable before any work."""
    from reform.datasets import DataFormatError, load_dataset, resolve
    from sim.experiments.benchmark import dataset_spec, found_datasets, one_recording_each

    if entries == ["none"]:
        return []
    if "none" in entries:
        raise CliError("--data none runs the party alone; give it alone, got " + " ".join(entries))
    names = entries or found_datasets()
    kept, left_out = one_recording_each(list(names), named=set(names) if entries else ())
    print(*left_out, sep="\n", file=sys.stderr, end="\n" if left_out else "")
    specs = []
    for name in kept:
        try:
            load_dataset(resolve(name))
        except (FileNotFoundError, DataFormatError) as exc:
            raise CliError(f"--data {name}: {' '.join(str(exc).split())}") from None
        specs.append(dataset_spec(name))
    return specs


def _command(args: argparse.Namespace) -> str:
    words = ["reform-sim", "experiment", "temporal"]
    for value in args.data:
        words += ["--data", value]
    for value in args.detector:
        words += ["--detector", value]
    for flag, value, default in (
        ("--episodes", args.episodes, EPISODES),
        ("--duration", args.duration, DURATION_S),
        ("--rate", args.rate, RATE_HZ),
        ("--seed", args.seed, 0),
    ):
        if value != default:
            words += [flag, f"{value:g}"]
    words += ["--out", args.out]
    return shlex.join(words)


def run(args: argparse.Namespace) -> int:
    from reform.detectors import DetectorError, detector_info
    from sim.experiments.temporal import run_temporal
    from sim.experiments.temporal_report import figure, to_json, to_markdown

    for flag, value, low in (
        ("--episodes", args.episodes, 1),
        ("--duration", args.duration, 1.0),
        ("--rate", args.rate, 0.1),
    ):
        if value < low:
            raise CliError(f"{flag} must be at least {low:g}, got {value:g}")
    for name in args.detector:
        try:
            detector_info(name)
        except DetectorError as exc:
            raise CliError(f"--detector {name}: {exc}") from None
    out = report_stem(args.out, BASENAME, suffixes=(*REPORT_SUFFIXES, FIGURE))
    check_report(out, suffixes=(*REPORT_SUFFIXES, FIGURE))
    real = _real(args.data)
    with stage_lines(args, "experiment temporal") as progress:
        result = run_temporal(
            real,
            seed=args.seed,
            episodes=args.episodes,
            duration=args.duration,
            rate=args.rate,
            detectors=args.detector or None,
            jobs=job_count(args),
            progress=progress,
        )
    command = _command(args)
    picture = figure(result, out.with_name(out.name + FIGURE)).name
    markdown = to_markdown(result, command=command, figure=picture)
    write_report(out, markdown, to_json(result, command=command))
    print(markdown, end="")
    return 0
