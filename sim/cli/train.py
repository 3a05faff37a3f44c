"""What ``reform-sim train`` does when it runs.

Its arguments are `sim.cli._train`."""

from __future__ import annotations

import argparse
import sys

from reform import Reform
from reform.classifiers import make_classifier
from reform.features import check_features
from reform.persistence import save_model
from reform.tuning import classifier_params, tune
from sim.cli._common import (
    CliError,
    check_frames,
    check_output,
    load_data,
    select_frames,
)
from sim.cli._grammar import show_progress


def run(args: argparse.Namespace) -> int:
    check_output("--out", args.out)
    check_frames(args)
    if args.threshold is not None and not 0.0 < args.threshold < 1.0:
        raise CliError(f"--threshold must be a probability in (0, 1), got {args.threshold}")
    features = check_features([name.strip() for name in args.features.split(",") if name.strip()])
    dataset = load_data(args)
    frames = select_frames(args, dataset.frames, doing="train on")
    params = {}
    if args.tune:
        if not args.quiet:
            print(
                f"cross-validating {args.classifier} on {len(frames)} frames ...", file=sys.stderr
            )
        tuning = tune(args.classifier, frames, features=features, n_jobs=args.jobs)
        params = classifier_params(args.classifier, tuning.best_params)
        for candidate, score in zip(tuning.candidates, tuning.mean_score, strict=True):
            if args.quiet:
                break
            print(f"  {candidate}: CV pairwise accuracy {100 * score:.2f} %", file=sys.stderr)
    if show_progress(args):
        print(f"fitting {args.classifier} on {len(frames):,} frames ...", file=sys.stderr)
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
