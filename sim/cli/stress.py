"""What ``reform-sim stress`` does when it runs.

Its arguments are `sim.cli._stress`."""

from __future__ import annotations

import argparse
import dataclasses
import os
import shlex
import sys
from collections.abc import Callable

from reform.detectors import builtin_names
from sim import sizing
from sim.cli._common import (
    CliError,
    backend_words,
    check_output,
    check_recording,
    executor_from_args,
    max_memory,
    size_error,
)
from sim.cli._detectors import make_plugin
from sim.cli._grammar import stage_lines
from sim.experiments.stress import AXES, DETECTOR_LABELS, GRIDS, run_stress
from sim.experiments.stress_grid import (
    BASE_PEOPLE,
    CROWD_MIN_PEOPLE,
    MAX_STRESS_EPISODES,
    StressGrid,
)
from sim.experiments.stress_report import write_report
from sim.recording import target_from_args
from sim.sizing import check_episodes


def _command(args: argparse.Namespace) -> str:
    words = ["reform-sim", "stress", "--grid", args.grid]
    if args.episodes is not None:
        words += ["--episodes", str(args.episodes)]
    if args.seed != 0:
        words += ["--seed", str(args.seed)]
    if args.axes is not None:
        words += ["--axes", args.axes]
    words += backend_words(args)
    for name in args.detectors or ():
        words += ["--detector", name]
    if args.temporal:
        words.append("--temporal")
    if args.detector_timeout is not None:
        words += ["--detector-timeout", f"{args.detector_timeout:g}"]
    words += ["--out", args.out]
    if args.save is not None:
        words += ["--save", args.save]
    return shlex.join(words)


def _check_size(grid: StressGrid, axes: list[str] | None, args: argparse.Namespace) -> None:
    """Refuses, before any work, a stress test that cannot fit this machine (memory, disk at
    --out, a week), and states its estimate once."""
    names = list(AXES) if axes is None else axes
    workers = args.jobs or os.cpu_count() or 1

    def estimate_with(crowds: tuple[int, ...]) -> sizing.Estimate:
        """The run's estimate, the crowd axis's levels being ``crowds``."""
        scene_agents = []
        for name in names:
            if AXES[name].kind != "scene":
                continue
            for level in crowds if name == "crowd" else grid.levels(name):
                if name in ("groups", "crowd"):
                    scene_agents.append((int(level), False))
                elif name == "sensor":
                    scene_agents.append((BASE_PEOPLE + 1, level != "truth"))
                else:
                    scene_agents.append((BASE_PEOPLE, False))
        return sizing.stress_estimate(
            seeds=grid.seeds,
            frames=max(1, round(grid.duration_s * grid.rate_hz)),
            rate_hz=grid.rate_hz,
            base_people=BASE_PEOPLE,
            perturb_levels=sum(len(grid.levels(a)) for a in names if AXES[a].kind == "perturb"),
            scene_agents=scene_agents,
            train_frames=round(grid.train_episodes * grid.train_duration_s * grid.train_rate_hz),
            workers=workers,
        )

    estimate = estimate_with(grid.crowd_people)
    if "crowd" in names:
        _check_crowd(grid, estimate_with, args, workers)
    try:
        sizing.check(
            estimate,
            what="the stress test",
            shrink="fewer {episodes}, fewer {axes} or the small {grid}",
            memory_limit=max_memory(args),
            alternative="fewer workers ({jobs})" if (args.jobs or 2) > 1 else "",
            out=args.out,
        )
    except sizing.RequestTooLarge as exc:
        raise size_error(exc) from None
    print(sizing.describe(estimate, "the stress test"), file=sys.stderr, flush=True)


def _check_crowd(
    grid: StressGrid,
    estimate_with: Callable[[tuple[int, ...]], sizing.Estimate],
    args: argparse.Namespace,
    workers: int,
) -> None:
    """Refuses, before any work, a crowd axis whose largest crowd this machine cannot hold (or
    --max-memory), naming the crowd asked and the largest that fits. A run that cannot hold
    even the smallest crowd is left to the whole run's check, which names every way to shrink
    it."""
    limit = max_memory(args)
    limit_text = f"--max-memory {sizing.format_size(limit)}" if limit is not None else ""
    if limit is None:
        limit = sizing.available_memory()
        limit_text = f"the {sizing.format_size(limit)} of memory this machine has available"

    def fits(people: int) -> bool:
        return estimate_with(tuple(min(p, people) for p in grid.crowd_people)).memory <= limit

    asked = max(grid.crowd_people)
    if fits(asked) or not fits(CROWD_MIN_PEOPLE):
        return
    low, high = CROWD_MIN_PEOPLE, asked  # fits(low), not fits(high)
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (middle, high) if fits(middle) else (low, middle)
    raise CliError(
        f"the crowd axis of --grid {args.grid} asks for a concourse of {asked:,} people, more "
        f"than {limit_text} holds with {workers} worker{'s' * (workers != 1)}: at most {low:,} "
        "people fit; leave crowd out of --axes, run the small --grid, give fewer --jobs or a "
        "larger --max-memory"
    )


def run(args: argparse.Namespace) -> int:
    grid = GRIDS[args.grid]
    if args.episodes is not None:
        if args.episodes < 1:
            raise CliError(f"--episodes must be >= 1, got {args.episodes}")
        check_episodes(args.episodes, what="the stress test", flag="--episodes")
        try:
            grid = dataclasses.replace(grid, seeds=args.episodes)
        except ValueError:  # past the grid's own bound on its test episodes
            raise CliError(
                f"--episodes must be at most {MAX_STRESS_EPISODES:,}, got {args.episodes:,}"
            ) from None
    axes = None
    if args.axes is not None:
        axes = [a.strip() for a in args.axes.split(",") if a.strip()]
        unknown = [a for a in axes if a not in AXES]
        if unknown or not axes:
            raise CliError(f"--axes must name axes among {','.join(AXES)}, got {args.axes!r}")
        twice = next((a for k, a in enumerate(axes) if a in axes[:k]), None)
        if twice is not None:
            raise CliError(f"--axes names {twice} twice, got {args.axes!r}; name each axis once")
    check_output("--out", args.out, folder=True)
    check_recording(args)
    plugins = {}
    named = list(args.detectors or ())
    if "all" in named:  # the catalogue, beside the detectors stress always runs
        every = [n for n in builtin_names(needs=("", "training")) if n not in DETECTOR_LABELS]
        named = [*every, *(n for n in named if n != "all" and n not in every)]
    for name in named:
        if name in DETECTOR_LABELS:
            raise CliError(
                f"--detector {name}: stress always runs {DETECTOR_LABELS[name]} (trained on its "
                "synthetic training set); --detector adds detectors of your own"
            )
        if name in plugins:
            raise CliError(f"--detector {name} is given twice")
        plugins[name] = make_plugin(name, deadline_s=args.detector_timeout)
    executor = executor_from_args(args)  # a Ray address is probed here, before the estimate
    _check_size(grid, axes, args)  # the last check: its estimate is said once all have passed
    if args.dry_run:
        return 0

    # On a terminal the time so far moves under the stage lines while a stage works (the
    # default grid's training set: a minute on two cores) and while the plots are drawn.
    with stage_lines(args, "stress", stamp=False) as progress:
        with executor:
            results = run_stress(
                grid,
                seed=args.seed,
                axes=axes,
                plugins=plugins,
                progress=progress,
                executor=executor,
                temporal=args.temporal,
                detector_timeout=args.detector_timeout,
            )
        if results.grid_name == "custom":
            results = dataclasses.replace(
                results, grid_name=f"{args.grid} (--episodes {args.episodes})"
            )
        written = write_report(
            results, args.out, command=_command(args), save=target_from_args(args)
        )
    print(
        f"stress tests done in {results.timings['total']:.0f} s "
        f"({results.environment.get('cpu_s', 0):.0f} CPU s on {results.jobs} "
        f"{'Ray CPU(s)' if args.backend == 'ray' else 'worker(s)'})",
        file=sys.stderr,
    )
    for key, path in written.items():
        print(f"wrote {key}: {path}")
    return 0
