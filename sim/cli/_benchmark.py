"""``reform-sim benchmark``: every detector on every dataset, one table as the field reports it."""

from __future__ import annotations

import argparse
import shlex
import sys

from sim.cli._common import (
    CliError,
    add_backend_arguments,
    add_train_fraction_argument,
    check_backend,
    check_output,
)

DEFAULT_OUT = "benchmark-output"
DEFAULT_DETECTORS = ("gcff", "gcff-own", "majority")

_DESCRIPTION = """\
Runs every detector given on every dataset given (default: every dataset found, fetched with
`reform-sim datasets fetch` or in $REFORM_SIM_DATASETS, else ../shared/datasets) and scores
them with the field's protocol: per dataset precision, recall and F1 at T = 2/3 and T = 1, and
the mean over datasets, with the original papers' published figures beside ours where they
exist. Writes OUT/benchmark.md, OUT/benchmark.json, OUT/benchmark.png and one Rerun recording
per dataset (OUT/recordings/<dataset>.rrd: its scenes, the ground truth, every detector's
groups and mistakes).

Detectors (--detector, repeatable): gcff (GCFF with one setting for every dataset, the REFORM
paper's 0.7 m / 30,000 cm²), gcff-own (GCFF with each dataset's own shipped settings_gc.mat,
per sequence; datasets that ship none are skipped), majority, any registered or installed
detector's name, or package.module:factory. REFORM models: --model FILE (repeatable), written
by `reform-sim train`. Default: gcff, gcff-own, majority, plus every --model.

Honest evaluation: datasets named by --test-split (default: salsa) are scored on the test part
of reform.time_split only, the frames `reform-sim train --frames train` leaves out.
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "benchmark",
        help="every detector on every dataset: P/R/F1 at T = 2/3 and 1, and the mean",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_arguments,
    )


def _arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data",
        action="append",
        metavar="PATH|NAME",
        help="a dataset (repeatable): a path, or a fetched or local dataset's name "
        "(default: every dataset found)",
    )
    parser.add_argument(
        "--detector",
        action="append",
        metavar="SPEC",
        help="a detector (repeatable): gcff, gcff-own, majority, a plugin's name or "
        f"package.module:factory (default: {', '.join(DEFAULT_DETECTORS)})",
    )
    parser.add_argument(
        "--model",
        action="append",
        metavar="MODEL",
        help="a REFORM model file written by `reform-sim train` (repeatable)",
    )
    parser.add_argument(
        "--test-split",
        action="append",
        metavar="NAME",
        help="score this dataset on its test split only (repeatable; default: salsa)",
    )
    add_train_fraction_argument(
        parser, help="the training share of the split of --test-split datasets (0.6)", default=None
    )
    parser.add_argument(
        "--out", default=DEFAULT_OUT, metavar="DIR", help=f"output folder (./{DEFAULT_OUT})"
    )
    parser.add_argument(
        "--no-recordings", action="store_true", help="do not write the per-dataset .rrd files"
    )
    add_backend_arguments(parser, jobs_default="1")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(handler=_run)


def _found_datasets() -> list[str]:
    """Every dataset name on this machine: the fetched public ones, then the local folders."""
    from reform.datasets import is_fetched, local_datasets_dir, registry

    names = [entry.name for entry in registry() if is_fetched(entry.name)]
    local = local_datasets_dir()
    if local is not None and local.is_dir():
        from reform.datasets import detect_format

        for child in sorted(local.iterdir()):
            if child.is_dir() and child.name not in names:
                try:
                    detect_format(child)
                except ValueError:
                    continue
                names.append(child.name)
    return names


def _run(args: argparse.Namespace) -> int:
    from reform.splits import DEFAULT_TRAIN_FRACTION
    from sim.experiments.benchmark import dataset_spec, detector_spec, model_spec, run_benchmark
    from sim.experiments.benchmark_report import write_report

    check_backend(args)
    check_output("--out", args.out, folder=True)
    names = args.data or _found_datasets()
    if not names:
        raise CliError(
            "no datasets found: fetch the public ones with `reform-sim datasets fetch --all`, "
            "point $REFORM_SIM_DATASETS at a folder of datasets, or give --data PATH|NAME"
        )
    fraction = DEFAULT_TRAIN_FRACTION if args.train_fraction is None else args.train_fraction
    if not 0.0 < fraction < 1.0:
        raise CliError(f"--train-fraction must lie in (0, 1), got {fraction}")
    split = tuple(args.test_split or ("salsa",))
    datasets = [dataset_spec(name, test_split=split, train_fraction=fraction) for name in names]
    detectors = [detector_spec(spec) for spec in (args.detector or DEFAULT_DETECTORS)]
    detectors += [model_spec(path) for path in args.model or ()]
    _check_detectors(detectors)

    bar = None
    if not args.no_progress:
        from tqdm import tqdm

        bar = tqdm(
            total=len(datasets) * len(detectors), desc="benchmark", unit="cell", file=sys.stderr
        )

    def progress(done: int, total: int, cell) -> None:  # noqa: ARG001
        if bar is not None:
            f1 = "skipped" if cell.scores is None else f"F1 {100 * cell.scores.at['2/3'][2]:.1f}"
            bar.set_postfix_str(f"{cell.dataset} × {cell.detector}: {f1}", refresh=False)
            bar.update(1)

    try:
        benchmark = run_benchmark(
            datasets,
            detectors,
            jobs=args.jobs or 1,
            backend=args.backend,
            address=args.address,
            progress=progress,
        )
    finally:
        if bar is not None:
            bar.close()
    command = _command(args)
    written = write_report(benchmark, args.out, command=command, recordings=not args.no_recordings)
    print(written["markdown"].read_text(), end="")
    print(f"wrote {args.out}/: " + ", ".join(p.name for p in written.values()), file=sys.stderr)
    return 0


def _check_detectors(detectors) -> None:
    """Every plugin is made once up front, so that a bad one is named before any work."""
    from reform.detectors import make_detector

    for detector in detectors:
        if detector.spec in ("gcff", "gcff-own") or detector.spec.startswith("reform:"):
            continue
        make_detector(detector.spec)


def _command(args: argparse.Namespace) -> str:
    """The command line that reruns this benchmark."""
    words = ["reform-sim", "benchmark"]
    for flag, values in (
        ("--data", args.data),
        ("--detector", args.detector),
        ("--model", args.model),
        ("--test-split", args.test_split),
    ):
        for value in values or ():
            words += [flag, value]
    if args.train_fraction is not None:
        words += ["--train-fraction", f"{args.train_fraction:g}"]
    if args.out != DEFAULT_OUT:
        words += ["--out", args.out]
    if args.no_recordings:
        words.append("--no-recordings")
    return " ".join(shlex.quote(w) for w in words)
