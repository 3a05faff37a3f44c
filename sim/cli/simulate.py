"""What ``reform-sim simulate`` does when it runs.

Its arguments are `sim.cli._simulate`."""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from tqdm import tqdm

from reform.datasets import write_parquet
from sim import sizing
from sim.cli._common import (
    CliError,
    check_output,
    check_recording,
    max_memory,
    parse_overrides,
    sensor_options,
    size_error,
)
from sim.episode import estimate_episode, prepare, simulate_episode, write_episode
from sim.recording import target_from_args
from sim.sensor import Sensor
from sim.ticking import ticking

_STREAMING = (
    "record nothing (no {save}, {connect}, {serve}) to stream the frames to {out} in bounded memory"
)


def _sensor(args: argparse.Namespace):
    given = sensor_options(args)
    if given is None:
        return None

    return Sensor(**given)


def run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if out.suffix != ".parquet":
        raise CliError(f"--out must name a .parquet file, got {args.out}")
    check_output("--out", out)
    check_recording(args)
    limit = max_memory(args)

    target = target_from_args(args)
    made = prepare(
        args.scenario,
        seed=args.seed,
        options=parse_overrides(args.scenario, args.overrides, duration=args.duration),
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
        return _run_recorded(args, made, target, sensor, kwargs, out, start, estimate.frames)
    bar = tqdm(
        total=estimate.frames,
        unit="frame",
        desc=f"simulate {made.name}",
        disable=args.quiet,
        delay=1.0,  # short runs print nothing
        file=sys.stderr,
    )
    # On a terminal, redrawn while a frame takes long: the first compiles the motion kernel
    # (10 s on two busy cores in a fresh clone, whose numba cache is empty).
    moving = ticking(bar) if sys.stderr.isatty() else contextlib.nullcontext()
    with bar, moving:
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
    frames: int,
) -> int:
    """The whole episode in memory, written to --out and recorded; a bar of its ``frames``
    (estimated) moves while it is simulated in one call, and while it is recorded."""
    from sim.recording import FieldOfView, record_episode, rerun_in_this_shell  # Rerun: here only

    bar = tqdm(
        total=frames,
        unit="frame",
        desc=f"simulate {made.name}",
        disable=args.quiet,
        delay=1.0,  # short runs print nothing
        leave=False,  # the report below says what was made
        file=sys.stderr,
    )
    with bar, ticking(bar):
        episode = simulate_episode(
            made, duration=args.duration, view=args.view, sensor=sensor, **kwargs
        )
        bar.update(frames)
    dataset = episode.dataset
    write_parquet(dataset, out)
    sizes = Counter(len(g) for f in dataset for g in f.groups or () if len(g) >= 2)
    _report(out, args, len(dataset), dataset.metadata, sizes, episode.events, start)
    bar = tqdm(
        total=len(episode.truth),
        unit="frame",
        desc="recording",
        disable=args.quiet,
        delay=1.0,
        leave=False,  # the line below names the recording
        file=sys.stderr,
    )
    with bar, ticking(bar):
        record_episode(
            target,
            episode.truth,
            observed=dataset.frames if args.view == "robot" else None,
            events=episode.events,
            seed=args.seed,
            name=dataset.frames[0].sequence if dataset.frames else args.scenario,
            field_of_view=FieldOfView.of(sensor),
        )
        bar.update(len(episode.truth))
    if target.save is not None:
        rerun = rerun_in_this_shell()
        print(f"wrote {target.save} (open it with `{rerun} {target.save}`)", file=sys.stderr)
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
