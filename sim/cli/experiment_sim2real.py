"""What ``reform-sim experiment sim2real`` does when it runs.

Its arguments are `sim.cli._experiment_sim2real`."""

from __future__ import annotations

import argparse
import dataclasses
import math
import shlex
import sys
import time

from reform.datasets import load_babble, load_salsa, resolve
from sim.cli._common import CliError, check_output, executor_from_args
from sim.cli._experiment_io import (
    REPORT_SUFFIXES,
    check_report,
    dataset_words,
    named_datasets,
    report_stem,
    write_report,
)
from sim.cli._experiment_sim2real import BASENAME
from sim.experiments.sim2real import (
    CLASSIFIER_NAMES,
    DEFAULT_SOURCES,
    RANDOMISED_SOURCES,
    sim_to_real,
)
from sim.experiments.sim2real_report import sim2real_figure, to_markdown


def _command(args: argparse.Namespace) -> str:
    words = ["reform-sim", "experiment", "sim2real", *dataset_words(args)]
    if args.seed != 0:
        words += ["--seed", str(args.seed)]
    if args.episodes_scale != 1.0:
        words += ["--episodes-scale", f"{args.episodes_scale:g}"]
    if args.classifiers:
        words += ["--classifiers", args.classifiers]
    if args.no_diagnostics:
        words.append("--no-diagnostics")
    if args.no_randomised:
        words.append("--no-randomised")
    if args.backend != "local":
        words += ["--backend", args.backend]
    if args.address is not None:
        words += ["--address", args.address]
    words += ["--out", args.out]
    return shlex.join(words)


def run(args: argparse.Namespace) -> int:
    if not (math.isfinite(args.episodes_scale) and args.episodes_scale > 0):
        raise CliError(f"--episodes-scale must be a finite number > 0, got {args.episodes_scale}")
    if args.seed < 0:
        raise CliError(f"--seed must be >= 0, got {args.seed}")
    classifiers = CLASSIFIER_NAMES
    if args.classifiers:
        classifiers = tuple(c.strip() for c in args.classifiers.split(",") if c.strip())
        unknown = [c for c in classifiers if c not in CLASSIFIER_NAMES]
        if unknown or not classifiers:
            raise CliError(
                f"--classifiers must be among {','.join(CLASSIFIER_NAMES)}, "
                f"got {args.classifiers!r}"
            )
    data = named_datasets(args)
    out = report_stem(args.out, BASENAME, suffixes=(*REPORT_SUFFIXES, ".png"))
    check_report(out, suffixes=(*REPORT_SUFFIXES, ".png"))
    check_output("--synthetic", args.synthetic, folder=True)
    executor = executor_from_args(args, progress=not args.quiet)  # the Ray address probed
    sources = tuple(
        dataclasses.replace(s, episodes=max(1, round(s.episodes * args.episodes_scale)))
        for s in DEFAULT_SOURCES
    )
    started = time.perf_counter()

    def progress(message: str) -> None:
        if not args.quiet:
            print(
                f"[{time.perf_counter() - started:6.1f} s] {message}", file=sys.stderr, flush=True
            )

    with executor:
        result = sim_to_real(
            load_salsa(resolve(data["salsa"])),
            load_babble(resolve(data["babble"])),
            synthetic_root=args.synthetic,
            sources=sources,
            seed=args.seed,
            classifiers=classifiers,
            diagnostics=not args.no_diagnostics,
            randomised=() if args.no_randomised else RANDOMISED_SOURCES,
            progress=progress,
            progress_bars=not args.quiet,
            executor=executor,
        )
    command = _command(args)
    figure = sim2real_figure(result, out.with_name(out.name + ".png"))
    markdown = to_markdown(result, command=command, figure=figure.name)
    write_report(out, markdown, result.to_json(command=command))
    print(markdown, end="")
    print(f"wrote {out}.md, {out}.json and {out}.png", file=sys.stderr)
    return 0
