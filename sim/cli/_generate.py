"""``reform-sim generate``: a synthetic dataset of seeded episodes, as hive-partitioned Parquet."""

from __future__ import annotations

import argparse
import sys

from sim.cli._common import (
    add_backend_arguments,
    add_max_memory_argument,
    add_overrides_argument,
    add_sensor_arguments,
    add_view_argument,
    check_backend,
    check_output,
    max_memory,
    parse_overrides,
    sensor_options,
    size_error,
)


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "generate",
        help="generate a synthetic dataset: many seeded episodes as Parquet shards",
        description=(
            "Simulates EPISODES episodes of a scenario and writes them as hive-partitioned "
            "Parquet (DIR/scenario=NAME/episode=K/part.parquet) with a dataset card "
            "(DIR/dataset.json, DIR/README.md). Same seed, same data; finished shards are "
            "skipped, so an interrupted run resumes and a larger --episodes extends. The run is "
            "sized first (memory, disk, time; sim.sizing) and refused in one line when it cannot "
            "fit this machine."
        ),
        arguments=_arguments,
    )


def _arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scenario", required=True, metavar="NAME", help="scenario name")
    parser.add_argument("--episodes", required=True, type=int, metavar="N", help="episodes")
    parser.add_argument("--seed", required=True, type=int, metavar="S", help="master seed")
    parser.add_argument("--out", required=True, metavar="DIR", help="dataset folder")
    add_overrides_argument(parser)
    parser.add_argument(
        "--duration", type=float, default=None, metavar="SECONDS", help="episode length"
    )
    parser.add_argument(
        "--rate", type=float, default=None, metavar="HZ", help="output (annotation) rate (2 Hz)"
    )
    add_view_argument(parser)
    add_sensor_arguments(parser)
    add_backend_arguments(parser, jobs_default="all cores")
    parser.add_argument(
        "--save-recordings",
        action="store_true",
        help="also write one Rerun .rrd per episode (DIR/recordings/episode=K.rrd)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_max_memory_argument(
        parser, holds="each worker holds the episode it writes (episodes do not stream)"
    )
    parser.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    from sim.generate import generate_dataset
    from sim.sizing import RequestTooLarge

    check_backend(args)
    check_output("--out", args.out, folder=True)
    limit = max_memory(args)
    try:
        report = generate_dataset(
            args.scenario,
            episodes=args.episodes,
            seed=args.seed,
            out_dir=args.out,
            options=parse_overrides(args.scenario, args.overrides),
            view=args.view,
            sensor=sensor_options(args),
            **({} if args.rate is None else {"rate": args.rate}),
            duration=args.duration,
            backend=args.backend,
            address=args.address,
            n_jobs=args.jobs,
            save_recordings=args.save_recordings,
            progress=not args.no_progress,
            max_memory=limit,
        )
    except RequestTooLarge as exc:  # sized before any work: named by the flags
        raise size_error(exc, {"out_dir": "--out", "n_jobs": "--jobs"}) from None
    made = report.generated_annotated_frames
    speed = made / report.seconds if report.seconds > 0 else 0.0
    print(
        f"{report.out_dir}: {report.episodes} episodes of {args.scenario} "
        f"({len(report.generated)} generated, {len(report.skipped)} already there), "
        f"{report.frames:,} frames ({report.annotated_frames:,} annotated); "
        f"this run: {made:,} annotated frames in {report.seconds:.1f} s ({speed:,.0f}/s) "
        f"on {report.n_jobs} {'CPUs (Ray)' if report.backend == 'ray' else 'processes'}; "
        f"card: {report.card}"
    )
    sys.stdout.flush()
    return 0
