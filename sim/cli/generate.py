"""What ``reform-sim generate`` does when it runs.

Its arguments are `sim.cli._generate`."""

from __future__ import annotations

import argparse
import sys

from reform.annotation import AnnotationModel, parse_annotation
from reform.datasets.store import is_uri
from sim.cli._common import (
    CliError,
    check_backend,
    check_output,
    max_memory,
    parse_overrides,
    sensor_options,
    size_error,
)
from sim.generate import RANDOM_ANNOTATION, FolderRefused, generate_dataset
from sim.sizing import RequestTooLarge
from sim.world import steps_per_frame, whole_step_rates


def _annotation(items: list[str]) -> AnnotationModel | str | None:
    """``--annotation``: settings, or ``random`` alone."""
    if RANDOM_ANNOTATION in items:
        if len(items) > 1:
            raise CliError(
                f"--annotation {RANDOM_ANNOTATION} draws every setting; it takes no other "
                f"--annotation, got {items}"
            )
        return RANDOM_ANNOTATION
    return parse_annotation(items) if items else None


def _twin_arguments(args: argparse.Namespace) -> None:
    """``--twin``: the twin's scenario, options, annotation, rate and episodes in place of the
    flags, which it refuses beside it; without it, --scenario and --episodes are required."""
    if args.twin is None:
        for flag, value in (("--scenario", args.scenario), ("--episodes", args.episodes)):
            if value is None:
                raise CliError(f"{flag} is required (or give --twin TWIN.json)")
        return
    given = [
        flag
        for flag, value in (
            ("--scenario", args.scenario),
            ("--annotation", args.annotation),
            ("--rate", args.rate),
            ("--duration", args.duration),
            ("--set", args.overrides),
        )
        if value
    ]
    if given:
        raise CliError(
            f"--twin fixes the scenario, its options, annotation and rate; got {given[0]}"
        )
    from sim.twins import read_twin
    from sim.twins.data import twin_options

    twin = read_twin(args.twin)
    args.scenario = twin.scenario
    args.episodes = twin.episodes if args.episodes is None else args.episodes
    args.rate = twin.rate_hz
    args.twin_model = twin
    args.twin_options, grown = twin_options(twin, seed=args.seed, episodes=args.episodes)
    if grown:
        print(f"{args.twin}: {grown}", file=sys.stderr)


def _check_rate(args: argparse.Namespace) -> None:
    """``--rate``: frames on the world's control steps (a twin's rate_hz is checked when read)."""
    if args.rate is None or not args.rate > 0.0:  # not a rate at all: refused as before
        return
    try:
        steps_per_frame(args.rate)
    except ValueError:
        raise CliError(
            f"--rate {args.rate:g}: expected {whole_step_rates()}, found {args.rate:g}"
        ) from None


def _set_keys(items: list[str]) -> set[str]:
    """The option names given by ``--set`` (checked by `parse_overrides`)."""
    return {item.partition("=")[0].strip() for item in items}


def _run(args: argparse.Namespace) -> int:
    _twin_arguments(args)
    _check_rate(args)
    twin = getattr(args, "twin_model", None)
    annotation = _annotation(args.annotation)
    if twin is not None and not twin.annotation.identity:
        annotation = twin.annotation
    check_backend(args)
    if not is_uri(args.out):  # a store is checked when opened, before any work
        check_output("--out", args.out, folder=True)
    limit = max_memory(args)
    try:
        report = generate_dataset(
            args.scenario,
            episodes=args.episodes,
            seed=args.seed,
            out_dir=args.out,
            options=(
                args.twin_options
                if twin is not None
                else parse_overrides(args.scenario, args.overrides, duration=args.duration)
            ),
            view=args.view,
            sensor=sensor_options(args),
            **({} if args.rate is None else {"rate": args.rate}),
            duration=args.duration,
            annotation=annotation,
            backend=args.backend,
            address=args.address,
            n_jobs=args.jobs,
            save_recordings=args.recordings,
            progress=not args.quiet,
            max_memory=limit,
        )
    except FolderRefused as exc:  # named as the command names it
        raise CliError(exc.message("--out")) from None
    except RequestTooLarge as exc:  # sized before any work: named by the flags
        flags = {"out_dir": "--out", "n_jobs": "--jobs"}
        if twin is None and "duration" in _set_keys(args.overrides):
            flags["duration"] = "--set duration"
        raise size_error(exc, flags) from None
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
