"""What ``reform-sim experiment hri`` does when it runs.

Its arguments are `sim.cli._experiment_hri`."""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time

from reform.datasets import load_salsa, resolve
from sim.cli._common import CliError, backend_words, check_output, executor_from_args
from sim.cli._experiment_hri import BASENAME
from sim.cli._experiment_io import experiment_command, named_datasets, report_target, write_report
from sim.cli._grammar import stage_lines
from sim.experiments.hri import VIEWS, hri_detectors, hri_experiment, record_scenes
from sim.experiments.hri_report import to_markdown
from sim.experiments.hri_views import DEFAULT_SEEDS, VIEW_NAMES
from sim.sizing import check_episodes


def _command(args: argparse.Namespace) -> str:
    words = []
    if args.episodes != DEFAULT_SEEDS:
        words += ["--episodes", str(args.episodes)]
    if args.seed != 0:
        words += ["--seed", str(args.seed)]
    if args.views != ",".join(VIEW_NAMES):
        words += ["--views", args.views]
    words += backend_words(args)
    if args.recordings:
        words.append("--recordings")
    return experiment_command("hri", args, words)


def run(args: argparse.Namespace) -> int:
    if args.episodes < 1:
        raise CliError(f"--episodes must be >= 1, got {args.episodes}")
    check_episodes(args.episodes, what="the HRI experiment", flag="--episodes")
    views = [v.strip() for v in args.views.split(",") if v.strip()]
    unknown = [v for v in views if v not in VIEWS]
    if unknown or not views:
        raise CliError(f"--views must name views among {','.join(VIEWS)}, got {args.views!r}")
    out = report_target(args.out, BASENAME)
    executor = executor_from_args(args, progress=not args.quiet)  # the Ray address probed
    recordings = None
    if args.recordings:
        recordings = (
            args.recordings if isinstance(args.recordings, str) else out.parent / "recordings"
        )
        check_output("--recordings", recordings, folder=True)
    salsa_path = named_datasets(args, ("salsa",))["salsa"]
    salsa = None
    try:
        salsa_path = str(resolve(salsa_path))
    except FileNotFoundError:
        if args.data:
            raise CliError(
                f"SALSA not found at {salsa_path} (give --data salsa=PATH, or fetch it: "
                "reform-sim datasets fetch salsa)"
            ) from None
        print("SALSA not found: the SALSA-trained REFORM rows are left out", file=sys.stderr)
    else:
        print(f"loading SALSA from {salsa_path}", file=sys.stderr)
        salsa = load_salsa(salsa_path).frames

    start = time.perf_counter()
    # On a terminal the time so far moves under the stage lines while a stage works (training,
    # simulating, scoring a view: 10 to 20 s each on two cores).
    with stage_lines(args, "experiment hri", stamp=False) as progress, executor:
        detectors, training = hri_detectors(
            salsa=salsa, seed=args.seed, progress=progress, executor=executor
        )
        trained = time.perf_counter() - start
        experiment = hri_experiment(
            seed=args.seed,
            seeds=args.episodes,
            views=views,
            detectors=detectors,
            training=training,
            progress=progress,
            executor=executor,
        )
    timings = {"training": trained, **experiment.timings}
    timings["total"] = time.perf_counter() - start
    experiment = dataclasses.replace(experiment, timings=timings)
    command = _command(args)
    write_report(
        out, to_markdown(experiment, command=command), experiment.to_json(command=command), indent=1
    )
    print(f"wrote {out}.md and {out}.json")
    if recordings is not None:
        for path in record_scenes(detectors, recordings, seed=args.seed):
            print(f"wrote recording {path}")
    return 0
