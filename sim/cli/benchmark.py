"""What ``reform-sim benchmark`` does when it runs.

Its arguments are `sim.cli._benchmark`."""

from __future__ import annotations

import argparse
import dataclasses
import shlex
import sys
from pathlib import Path

from reform.detectors import builtin_names, detector_info, detector_names
from reform.splits import DEFAULT_TRAIN_FRACTION
from sim.cli._benchmark import CELLS_PER_WORKER, DEFAULT_DETECTORS, DEFAULT_OUT
from sim.cli._common import (
    CliError,
    check_backend,
    check_output,
    frame_memory_limit,
    job_count,
)
from sim.cli._detectors import make_plugin
from sim.cli._grammar import ticking_bar
from sim.experiments.benchmark import (
    dataset_spec,
    detector_spec,
    found_datasets,
    model_spec,
    one_recording_each,
    read_for_run,
    run_benchmark,
)
from sim.experiments.benchmark_report import write_report
from sim.progress import progress_bar
from sim.recording import pandas_withheld
from sim.ticking import ticking


def _jobs(args: argparse.Namespace, *, cells: int) -> int:
    """``--jobs``, or by default every core but one process per `CELLS_PER_WORKER` cells: a run
    too small to pay for worker processes runs in this one."""
    if args.jobs is not None:
        return job_count(args)
    return max(1, min(job_count(args), cells // CELLS_PER_WORKER))


def _run(args: argparse.Namespace) -> int:
    from sim.cli.benchmark_twin import refuse_unread, run_twin

    refuse_unread(args)
    if args.twin is not None:
        return run_twin(args)
    check_backend(args)
    check_output("--out", args.out, folder=True)
    limit, limit_text = frame_memory_limit(args)  # a malformed size refused before any reading
    names = args.data
    given = [
        flag
        for flag, value in (
            ("--units", args.units),
            ("--time-unit", args.time_unit),
            ("--metres-per-pixel", args.metres_per_pixel),
        )
        if value is not None
    ]
    if given and not names:
        raise CliError(f"{given[0]} says how to read the datasets given with --data; give --data")
    if args.metres_per_pixel is not None and args.units != "px":
        raise CliError("--metres-per-pixel is the scale of --units px; give --units px too")
    if not names:
        names, left_out = one_recording_each(found_datasets())
        print(*left_out, sep="\n", file=sys.stderr, end="\n" if left_out else "")
    if not names:
        raise CliError(
            "no datasets found: fetch the public ones with `reform-sim datasets fetch --all`, "
            "point $REFORM_SIM_DATASETS at a folder of datasets, or give --data PATH|NAME"
        )
    fraction = DEFAULT_TRAIN_FRACTION if args.train_fraction is None else args.train_fraction
    if not 0.0 < fraction < 1.0:
        raise CliError(f"--train-fraction must lie in (0, 1), got {fraction}")
    split = tuple(args.test_split or ("salsa",))
    datasets = [
        dataset_spec(
            name,
            test_split=split,
            train_fraction=fraction,
            units=args.units,
            metres_per_pixel=args.metres_per_pixel,
            time_unit=args.time_unit,
        )
        for name in names
    ]
    if args.frames is not None:
        datasets = [dataclasses.replace(d, split=args.frames) for d in datasets]
    unknown = [name for name in args.test_split or () if name not in {d.name for d in datasets}]
    if unknown:
        raise CliError(
            f"--test-split {unknown[0]}: expected the name of a dataset of this run "
            f"({', '.join(d.name for d in datasets)}), got {unknown[0]!r}"
        )
    named = args.detector or DEFAULT_DETECTORS
    if "all" in named:
        named = [*builtin_names(), *(n for n in named if n != "all")]
    detectors = [detector_spec(spec) for spec in dict.fromkeys(named)]
    if args.model:  # each file read, skops and scikit-learn imported: seconds
        with ticking_bar(args, "reading models", len(args.model), unit="file"):
            detectors += [model_spec(path) for path in args.model]
    detectors = [dataclasses.replace(d, deadline_s=args.detector_timeout) for d in detectors]
    _check_detectors(detectors)
    jobs = _jobs(args, cells=len(datasets) * len(detectors))
    if jobs > 1 and args.backend == "local":  # each worker may hold a frame at once
        limit, limit_text = limit // jobs, f"{limit_text} shared by {jobs} workers"
    try:
        with ticking_bar(args, "reading datasets", len(datasets), unit="dataset"):
            run = read_for_run(  # one with nothing to score, or a frame too large, is refused
                datasets,
                detectors,
                memory=(limit, limit_text),
                hint="give a larger --max-memory, fewer --jobs, or leave that detector out",
            )
    except ValueError as exc:
        if args.data:
            raise
        raise CliError(f"{exc} (a dataset found, not given: --data names those to score)") from exc

    bar = progress_bar(
        total=len(datasets) * len(detectors),
        desc="benchmark",
        unit="cell",
        file=sys.stderr,
        disable=args.quiet,
    )

    def progress(done: int, total: int, cell) -> None:  # noqa: ARG001
        f1 = "skipped" if cell.scores is None else f"F1 {100 * cell.scores.at['2/3'][2]:.1f}"
        bar.set_postfix_str(f"{cell.dataset} × {cell.detector}: {f1}", refresh=False)
        bar.update(1)

    with bar, ticking(bar):  # redrawn while a long cell (or the workers' start) keeps it still
        benchmark = run_benchmark(
            datasets,
            detectors,
            jobs=jobs,
            backend=args.backend,
            address=args.address,
            progress=progress,
            temporal=args.temporal,
            run=run,
        )
    command = _command(args)
    out = Path(args.out)
    if not args.quiet:
        files = f" and {len(datasets)} recording(s)" if args.recordings else ""
        print(f"writing the report, its plot{files} into {out}/ ...", file=sys.stderr)
    said = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    with pandas_withheld():  # pyarrow, under Rerun, would import it for nothing: see there
        written = write_report(
            benchmark, out, command=command, recordings=args.recordings, progress=said
        )
    print(written["markdown"].read_text(), end="")
    print(f"wrote {out}/: " + ", ".join(p.name for p in written.values()), file=sys.stderr)
    return 0


def _check_detectors(detectors) -> None:
    """Every plugin is made once up front, so that a bad one is named before any work (the
    current folder searched for a ``module:factory`` path, as `evaluate` and `detect` do; the
    workers inherit the search path). The catalogue's own detectors are made where they run
    only: making them here would import their libraries into a process that runs none."""

    for detector in detectors:
        if detector.spec.startswith(("reform:", "dante:")):
            continue
        if detector.spec in detector_names() and detector_info(detector.spec).source == "built-in":
            continue
        make_plugin(detector.spec, deadline_s=detector.deadline_s)


def _command(args: argparse.Namespace) -> str:
    """The command line that reruns this benchmark."""
    words = ["reform-sim", "benchmark"]
    for flag, values in (
        ("--data", args.data),
        ("--detector", args.detector),
        ("--model", args.model),
        ("--test-split", args.test_split),
        ("--frames", [args.frames] if args.frames else None),
    ):
        for value in values or ():
            words += [flag, value]
    if args.train_fraction is not None:
        words += ["--train-fraction", f"{args.train_fraction:g}"]
    for flag, value in (
        ("--units", args.units),
        ("--metres-per-pixel", args.metres_per_pixel),
        ("--time-unit", args.time_unit),
    ):
        if value is not None:
            words += [flag, f"{value:g}" if isinstance(value, float) else value]
    if args.temporal:
        words.append("--temporal")
    if args.out != DEFAULT_OUT:
        words += ["--out", args.out]
    if not args.recordings:
        words.append("--no-recordings")
    return " ".join(shlex.quote(w) for w in words)
