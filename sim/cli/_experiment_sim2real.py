"""``reform-sim experiment sim2real``: REFORM trained on synthetic crowds, tested on real people."""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from pathlib import Path

from sim.cli._common import CliError, check_output
from sim.cli._experiment_io import (
    REPORT_SUFFIXES,
    add_dataset_arguments,
    add_out_argument,
    check_report,
    dataset_words,
    report_stem,
    salsa_and_babble,
    write_report,
)

_DESCRIPTION = """\
Trains REFORM (the paper's three classifiers) only on simulated episodes of mingle (a SALSA-like
party, with tracker noise calibrated on SALSA's training split) and word-improv (the Babble
game), and scores it on the SALSA test split (reform.time_split) and on every annotated Babble
frame, beside REFORM trained on SALSA's training split, GCFF (the paper's setting and tuned on
SALSA's training split) and the majority baseline, with block-bootstrap intervals and the
experiment's goals checked. The synthetic data are generated once under --synthetic and reused.
Writes OUT/sim2real.md, OUT/sim2real.json and OUT/sim2real.png (or OUT.md, OUT.json, OUT.png
when OUT is not a folder) and prints the Markdown.
"""

DEFAULT_SYNTHETIC = "runs/sim2real"
BASENAME = "sim2real"


def register(experiments: argparse._SubParsersAction) -> None:
    experiments.add_parser(
        "sim2real",
        help="REFORM trained on synthetic crowds only, tested on SALSA and Babble",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_arguments,
    )


def _arguments(parser: argparse.ArgumentParser) -> None:
    add_dataset_arguments(parser)
    add_out_argument(
        parser, help="a folder (writes sim2real.md/.json/.png in it) or a path without extension"
    )
    parser.add_argument(
        "--synthetic",
        default=DEFAULT_SYNTHETIC,
        metavar="DIR",
        help=f"folder of the generated synthetic data, reused when present ({DEFAULT_SYNTHETIC})",
    )
    parser.add_argument("--seed", type=int, default=0, metavar="S", help="master seed (0)")
    parser.add_argument(
        "--episodes-scale",
        type=float,
        default=1.0,
        metavar="X",
        help="multiply every source's episodes by X (at least 1 each; 1 = the documented run)",
    )
    parser.add_argument(
        "--classifiers",
        default=None,
        metavar="A,B",
        help="REFORM classifiers (default: weighted-knn,bagged-trees,logistic-regression)",
    )
    parser.add_argument("--jobs", type=int, default=None, metavar="N", help="worker processes")
    parser.add_argument(
        "--no-diagnostics", action="store_true", help="skip the per-source diagnostic rows"
    )
    parser.add_argument(
        "--no-randomised",
        action="store_true",
        help="leave the randomised mode (mingle-randomised) out of the diagnostics",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")
    parser.set_defaults(handler=run)


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
    words += ["--out", args.out]
    return shlex.join(words)


def _outputs(out: str) -> Path:
    """The output path without extension."""
    path = Path(out)
    if out.endswith(("/", "\\")) or path.is_dir():
        return path / BASENAME
    return report_stem(out, suffixes=(*REPORT_SUFFIXES, ".png"))


def run(args: argparse.Namespace) -> int:
    import dataclasses

    from reform.datasets import load_babble, load_salsa, resolve
    from sim.experiments.sim2real import (
        CLASSIFIER_NAMES,
        DEFAULT_SOURCES,
        RANDOMISED_SOURCES,
        sim_to_real,
    )
    from sim.experiments.sim2real_report import sim2real_figure, to_markdown

    salsa, babble = salsa_and_babble(args)
    if not args.episodes_scale > 0:
        raise CliError(f"--episodes-scale must be > 0, got {args.episodes_scale}")
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
    out = _outputs(args.out)
    check_report(out, suffixes=(*REPORT_SUFFIXES, ".png"))
    check_output("--synthetic", args.synthetic, folder=True)
    sources = tuple(
        dataclasses.replace(s, episodes=max(1, round(s.episodes * args.episodes_scale)))
        for s in DEFAULT_SOURCES
    )
    started = time.perf_counter()

    def progress(message: str) -> None:
        print(f"[{time.perf_counter() - started:6.1f} s] {message}", file=sys.stderr, flush=True)

    result = sim_to_real(
        load_salsa(resolve(salsa)),
        load_babble(resolve(babble)),
        synthetic_root=args.synthetic,
        sources=sources,
        seed=args.seed,
        classifiers=classifiers,
        n_jobs=args.jobs,
        diagnostics=not args.no_diagnostics,
        randomised=() if args.no_randomised else RANDOMISED_SOURCES,
        progress=progress,
        progress_bars=not args.no_progress,
    )
    command = _command(args)
    figure = sim2real_figure(result, out.with_name(out.name + ".png"))
    markdown = to_markdown(result, command=command, figure=figure.name)
    write_report(out, markdown, result.to_json(command=command))
    print(markdown, end="")
    print(f"wrote {out}.md, {out}.json and {out}.png", file=sys.stderr)
    return 0
