"""``reform-sim simulate``: one episode of a scenario, written as the project's Parquet."""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from sim.cli._common import (
    CliError,
    add_max_memory_argument,
    add_overrides_argument,
    add_sensor_arguments,
    add_view_argument,
    check_output,
    check_recording,
    max_memory,
    parse_overrides,
    sensor_options,
    size_error,
)

# How sizing's messages name the simulation's parameters here.
_STREAMING = (
    "record nothing (no {save}, {connect}, {serve}) to stream the frames to {out} in bounded memory"
)

_DESCRIPTION = """\
Runs one episode of a registered scenario (reform-sim scenarios lists them and their options)
in the MuJoCo world and writes its frames, ground truth included, to a Parquet file in the
project's format. With --view robot the frames are what the robot's head sensor observes
(field of view, range, occlusion, noise), the ground truth restricted to the people seen.
With --save the episode is also recorded for the Rerun viewer (scene, people, robot, groups,
the scenario's events).

The run is sized before it starts (memory, disk, time; sim.sizing) and refused, in one line,
when it cannot fit this machine. Without a recording the frames stream to --out as they are
made, in bounded memory, with progress on stderr; a recording (--save, --connect, --serve)
needs the whole episode in memory, up to --max-memory.
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
    add_max_memory_argument(
        parser,
        holds="a recording holds the whole episode, the frames otherwise stream to --out",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
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
    limit = max_memory(args)
    from tqdm import tqdm

    from sim import sizing
    from sim.episode import estimate_episode, prepare, write_episode
    from sim.recording import target_from_args

    target = target_from_args(args)
    made = prepare(
        args.scenario, seed=args.seed, options=parse_overrides(args.scenario, args.overrides)
    )
    kwargs: dict[str, float] = {}
    if args.rate is not None:
        kwargs["rate"] = args.rate
    if args.dt is not None:
        kwargs["dt"] = args.dt
    sensor = _sensor(args)
    recording = target is not None
    estimate = estimate_episode(
        made,
        duration=args.duration,
        view=args.view,
        streamed=not recording,
        recording=recording,
        **kwargs,
    )
    try:
        sizing.check(
            estimate,
            shrink="a shorter {duration}, a lower {rate} or a larger {dt}",
            memory_limit=limit,
            alternative=_STREAMING if recording else "",
            out=out,
        )
    except sizing.RequestTooLarge as exc:
        raise size_error(exc) from None
    start = time.perf_counter()
    if recording:
        return _run_recorded(args, made, target, sensor, kwargs, out, start)
    with tqdm(
        total=estimate.frames,
        unit="frame",
        desc=f"simulate {made.name}",
        disable=args.no_progress,
        delay=1.0,  # short runs print nothing
        file=sys.stderr,
    ) as bar:
        written = write_episode(
            made,
            out,
            duration=args.duration,
            view=args.view,
            sensor=sensor,
            progress=bar.update,
            **kwargs,
        )
    _report(out, args, written.frames, written.metadata, written.group_sizes, written.events, start)
    return 0


def _run_recorded(
    args: argparse.Namespace,
    made: Any,
    target: Any,
    sensor: Any,
    kwargs: dict[str, float],
    out: Path,
    start: float,
) -> int:
    """The whole episode in memory, written to --out and recorded."""
    from reform.datasets import write_parquet
    from sim.episode import simulate_episode
    from sim.recording import FieldOfView, record_episode

    episode = simulate_episode(
        made, duration=args.duration, view=args.view, sensor=sensor, **kwargs
    )
    dataset = episode.dataset
    write_parquet(dataset, out)
    sizes = Counter(len(g) for f in dataset for g in f.groups or () if len(g) >= 2)
    _report(out, args, len(dataset), dataset.metadata, sizes, episode.events, start)
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


def _report(
    out: Path,
    args: argparse.Namespace,
    frames: int,
    meta: Mapping[str, Any],
    sizes: Mapping[int, int],
    events: Sequence[object],
    start: float,
) -> None:
    """The run's one line on stdout: frames, parameters, time, F-formations, events."""
    by_size = ", ".join(f"{n}: {sizes[n]:,}" for n in sorted(sizes)) or "none"
    print(
        f"{out}: {frames:,} frames of {args.scenario} (seed {args.seed}, "
        f"{meta['duration_s']:g} s at {meta['rate_hz']:g} Hz, view {args.view}) in "
        f"{time.perf_counter() - start:.1f} s; F-formations by size: {by_size}; "
        f"{len(events)} events"
    )
