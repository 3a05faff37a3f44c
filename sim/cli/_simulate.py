"""``reform-sim simulate``: one episode of a scenario, written as the project's Parquet."""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

from sim.cli._common import (
    CliError,
    add_overrides_argument,
    add_sensor_arguments,
    add_view_argument,
    check_output,
    check_recording,
    parse_overrides,
    sensor_options,
)

_DESCRIPTION = """\
Runs one episode of a registered scenario (reform-sim scenarios lists them and their options)
in the MuJoCo world and writes its frames, ground truth included, to a Parquet file in the
project's format. With --view robot the frames are what the robot's head sensor observes
(field of view, range, occlusion, noise), the ground truth restricted to the people seen.
With --save the episode is also recorded for the Rerun viewer (scene, people, robot, groups,
the scenario's events).
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "simulate",
        help="run one episode of a scenario and write its frames (Parquet)",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_arguments,
    )


def _arguments(parser: argparse.ArgumentParser) -> None:
    from sim.recording import add_recording_arguments

    parser.add_argument("--scenario", required=True, metavar="NAME", help="scenario name")
    parser.add_argument("--seed", required=True, type=int, metavar="S", help="episode seed")
    parser.add_argument("--out", required=True, metavar="FILE.parquet", help="output file")
    parser.add_argument(
        "--duration",
        type=float,
        default=None,
        metavar="SECONDS",
        help="seconds to simulate (default: the scenario's natural length)",
    )
    parser.add_argument(
        "--rate", type=float, default=None, metavar="HZ", help="frames per second (default 2)"
    )
    add_view_argument(parser)
    add_overrides_argument(parser)
    parser.add_argument(
        "--dt",
        type=float,
        default=None,
        metavar="SECONDS",
        help="control step of the world (default 0.01; up to 0.1, faster and rougher)",
    )
    add_sensor_arguments(parser)
    add_recording_arguments(parser)
    parser.set_defaults(handler=run)


def _sensor(args: argparse.Namespace):
    given = sensor_options(args)
    if given is None:
        return None
    from sim.sensor import Sensor

    return Sensor(**given)


def run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if out.suffix != ".parquet":
        raise CliError(f"--out must name a .parquet file, got {args.out}")
    check_output("--out", out)
    check_recording(args)
    from reform.datasets import write_parquet
    from sim.episode import simulate_episode
    from sim.recording import FieldOfView, record_episode, target_from_args

    target = target_from_args(args)
    options = parse_overrides(args.scenario, args.overrides)
    kwargs = {}
    if args.rate is not None:
        kwargs["rate"] = args.rate
    if args.dt is not None:
        kwargs["dt"] = args.dt
    sensor = _sensor(args)
    start = time.perf_counter()
    episode = simulate_episode(
        args.scenario,
        seed=args.seed,
        duration=args.duration,
        view=args.view,
        sensor=sensor,
        options=options,
        **kwargs,
    )
    elapsed = time.perf_counter() - start
    dataset = episode.dataset
    write_parquet(dataset, out)
    sizes = Counter(len(g) for f in dataset for g in f.groups or () if len(g) >= 2)
    by_size = ", ".join(f"{n}: {sizes[n]:,}" for n in sorted(sizes)) or "none"
    meta = dataset.metadata
    print(
        f"{out}: {len(dataset):,} frames of {args.scenario} (seed {args.seed}, "
        f"{meta['duration_s']:g} s at {meta['rate_hz']:g} Hz, view {args.view}) in "
        f"{elapsed:.1f} s; F-formations by size: {by_size}; {len(episode.events)} events"
    )
    if target is not None:
        record_episode(
            target,
            episode.truth,
            observed=dataset.frames if args.view == "robot" else None,
            events=episode.events,
            seed=args.seed,
            name=dataset.frames[0].sequence if dataset.frames else args.scenario,
            field_of_view=FieldOfView.of(sensor),
        )
        if target.save is not None:
            print(f"wrote {target.save} (open it with `rerun {target.save}`)", file=sys.stderr)
    return 0
