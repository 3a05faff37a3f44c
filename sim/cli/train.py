"""What ``reform-sim train`` does when it runs.

Its arguments are `sim.cli._train`."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

from reform import Reform
from reform.classifiers import make_classifier
from reform.features import DEFAULT_FEATURES, FEATURES, check_features
from reform.persistence import save_model
from reform.tuning import classifier_params, tune
from sim.cli._common import (
    CliError,
    check_frames,
    check_output,
    job_count,
    load_data,
    select_frames,
)
from sim.cli._grammar import show_progress, stage_lines, ticking_bar
from sim.cli._train import TRAINED
from sim.progress import progress_bar
from sim.ticking import ticking

# REFORM's own options: (flag, attribute); refused with --detector dante.
_REFORM_OPTIONS = (
    ("--classifier", "classifier"),
    ("--tune", "tune"),
    ("--jobs", "jobs"),
    ("--features", "features"),
    ("--reconstruction", "reconstruction"),
    ("--threshold", "threshold"),
)


def run(args: argparse.Namespace) -> int:
    check_output("--out", args.out, suffix=TRAINED[args.detector])
    check_frames(args)
    if args.every < 1:
        raise CliError(f"--every keeps every K-th frame: K must be 1 or more, got {args.every}")
    if args.validation is not None and not 0.0 < args.validation < 1.0:
        raise CliError(
            f"--validation is the share of training frames held out: in (0, 1), got "
            f"{args.validation:g}"
        )
    if args.detector == "dante":
        return _run_dante(args)
    if args.validation is not None:
        raise CliError(
            "--validation stops DANTE's training early; REFORM's classifiers train once "
            "(--tune cross-validates them)"
        )
    if args.option:
        raise CliError(
            f"--option {args.option[0]} is for --detector dante; REFORM takes --classifier, "
            "--features, --reconstruction, --threshold and --tune"
        )
    args.classifier = args.classifier or "bagged-trees"
    if args.features is not None and not args.features.strip(", "):
        raise CliError(f"--features must name features among {', '.join(FEATURES)}, got ''")
    args.features = args.features or ",".join(DEFAULT_FEATURES)
    args.reconstruction = args.reconstruction or "union"
    if args.threshold is not None and not 0.0 < args.threshold < 1.0:
        raise CliError(f"--threshold must be a probability in (0, 1), got {args.threshold}")
    features = check_features([name.strip() for name in args.features.split(",") if name.strip()])
    dataset = load_data(args)
    frames = _every(args, select_frames(args, dataset.frames, doing="train on"))
    params = {}
    if args.tune:
        if not args.quiet:
            print(
                f"cross-validating {args.classifier} on {len(frames)} frames ...", file=sys.stderr
            )
        with ticking_bar(args, "cross-validating", len(frames)):
            tuning = tune(args.classifier, frames, features=features, n_jobs=job_count(args))
        params = classifier_params(args.classifier, tuning.best_params)
        for candidate, score in zip(tuning.candidates, tuning.mean_score, strict=True):
            if args.quiet:
                break
            print(f"  {candidate}: CV pairwise accuracy {100 * score:.2f} %", file=sys.stderr)
    if show_progress(args):
        print(f"fitting {args.classifier} on {len(frames):,} frames ...", file=sys.stderr)
    with ticking_bar(args, f"fitting {args.classifier}", len(frames)):
        model = Reform(
            make_classifier(args.classifier, **params),
            features=features,
            reconstruction=args.reconstruction,
            threshold=args.threshold,
        ).fit(frames)
        path = save_model(model, args.out)
    summary = model.training_summary_
    print(
        f"trained REFORM ({args.classifier}{', ' + str(params) if params else ''}) on "
        f"{summary['frames']:,} frames of {dataset.name} ({summary['pairs']:,} pairs, "
        f"{summary['together_pairs']:,} together); features {', '.join(model.features_)}; "
        f"wrote {path}"
    )
    return 0


def _run_dante(args: argparse.Namespace) -> int:
    """Trains DANTE with its catalogued options (``--option NAME=VALUE``) and saves it."""
    given = [flag for flag, dest in _REFORM_OPTIONS if getattr(args, dest) not in (None, False)]
    if given:
        what = "is an option" if len(given) == 1 else "are options"
        raise CliError(
            f"{', '.join(given)} {what} of --detector reform, not of --detector dante "
            "(DANTE's: --option NAME=VALUE)"
        )
    from reform.detectors import DetectorError, detector_info

    info = detector_info("dante")
    options = {}
    for text in args.option:
        name, sep, value = text.partition("=")
        name = name.strip()
        if not sep or not name:
            raise CliError(f"--option expects NAME=VALUE, got {text!r}")
        if name == "model":
            raise CliError("--option model= names a trained model; train writes one to --out")
        try:
            options[name] = info.option(name).parse("dante", value.strip())
        except DetectorError as exc:
            raise CliError(str(exc)) from None
    from reform.dante import INSTALL, Dante, torch_available

    with stage_lines(args, "loading PyTorch", stamp=False):  # 2 to 5 s on two busy cores
        available = torch_available()
    if not available:
        raise CliError(f"--detector dante needs PyTorch, which is not installed: {INSTALL}")
    dataset = load_data(args)
    frames = select_frames(args, dataset.frames, doing="train on")
    validation = None
    if args.validation is not None:
        from reform import time_split

        frames, validation = time_split(frames, 1.0 - args.validation)
        validation = _every(args, validation)
        if not frames or not validation:
            raise CliError(
                f"{args.data}: --validation {args.validation:g} leaves "
                f"{len(frames)} training and {len(validation)} validation frames; both need some"
            )
    elif "patience" in options:
        raise CliError("--option patience= stops training early on --validation F frames")
    frames = _every(args, frames)
    model = Dante(**options)
    if not args.quiet:
        held = f", stopping on {len(validation):,} validation frames" if validation else ""
        print(
            f"training DANTE on {len(frames):,} frames of {dataset.name} (at most "
            f"{model.epochs} epochs{held}) ...",
            file=sys.stderr,
        )

    bar = progress_bar(
        total=model.epochs, desc="epochs", unit="epoch", file=sys.stderr, disable=args.quiet
    )

    def progress(epoch: int, epochs: int, loss: float, validation_loss: float | None) -> None:
        held = "" if validation_loss is None else f", validation loss {validation_loss:.4f}"
        bar.write(f"  epoch {epoch}/{epochs}: loss {loss:.4f}{held}", file=sys.stderr)
        bar.update(1)

    try:
        # Redrawn while an epoch runs: one on SALSA takes a minute or more on two cores.
        with bar, ticking(bar):
            model.fit(frames, validation=validation, progress=None if args.quiet else progress)
    except ValueError as exc:
        raise CliError(f"{args.data}: {' '.join(str(exc).split())}") from None
    path = model.save(args.out)
    summary = model.training_summary_
    print(
        f"trained DANTE on {summary['frames']:,} frames of {dataset.name} "
        f"({summary['ordered_pairs']:,} ordered pairs, {summary['together_pairs']:,} together; "
        f"{summary['epochs_run']} epochs, final loss {summary['final_loss']:.4f}); wrote {path}"
    )
    return 0


def _every(args: argparse.Namespace, frames: Sequence[Any]) -> list[Any]:
    """Every ``--every``-th of ``frames``, counted per sequence in time order (input order kept)."""
    if args.every == 1:
        return list(frames)
    rank: dict[tuple[str, float], int] = {}
    for sequence in dict.fromkeys(frame.sequence for frame in frames):
        times = sorted(frame.time for frame in frames if frame.sequence == sequence)
        rank.update(((sequence, time), index) for index, time in enumerate(times))
    return [frame for frame in frames if rank[frame.sequence, frame.time] % args.every == 0]
