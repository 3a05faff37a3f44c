"""``reform-sim train``: fit REFORM on a dataset's annotated frames and save it as a skops file."""

from __future__ import annotations

import argparse
import sys

from sim.cli._common import (
    TRAIN_FRACTION,
    CliError,
    add_data_arguments,
    add_train_fraction_argument,
    check_output,
    check_train_fraction,
    load_data,
)

FRAME_CHOICES = ("all", "train", "test")

_DESCRIPTION = """\
Deconstructs the annotated frames of a dataset into pairs (Distance, Effort Angle), fits one of
the paper's pair classifiers, and saves the fitted REFORM model with skops (never pickle),
together with its features, classifier, training summary and the package version. Use the model
with `reform-sim detect --model` and `reform-sim evaluate --model`.

--frames train|test picks the training or test part of reform.time_split (per sequence, the
first --train-fraction of annotated frames by time train); --tune chooses the classifier's
hyper-parameters by time-blocked cross-validation on the frames used for training.
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "train",
        help="train REFORM on a dataset's annotated frames and save it (skops)",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_arguments,
    )


def _arguments(parser: argparse.ArgumentParser) -> None:
    from reform.classifiers import CLASSIFIERS
    from reform.features import DEFAULT_FEATURES, FEATURES
    from reform.reconstruction import RECONSTRUCTIONS

    add_data_arguments(parser)
    parser.add_argument(
        "--classifier",
        choices=tuple(CLASSIFIERS),
        default="bagged-trees",
        help="pair classifier (default: bagged-trees)",
    )
    parser.add_argument(
        "--frames",
        choices=FRAME_CHOICES,
        default="all",
        help="annotated frames to train on: all, or the train/test part of reform.time_split",
    )
    add_train_fraction_argument(
        parser,
        help="with --frames train|test: share of each sequence's annotated frames, by time, in "
        "the train part (0.6)",
        default=None,  # not given: it needs --frames train|test
    )
    parser.add_argument(
        "--tune",
        action="store_true",
        help="choose hyper-parameters by time-blocked cross-validation on the training frames",
    )
    parser.add_argument("--jobs", type=int, default=None, metavar="N", help="parallel CV fits")
    parser.add_argument(
        "--features",
        default=",".join(DEFAULT_FEATURES),
        metavar="F1,F2",
        help=f"pair features, comma-separated, from {', '.join(FEATURES)} "
        f"(default: {','.join(DEFAULT_FEATURES)})",
    )
    parser.add_argument(
        "--reconstruction",
        choices=RECONSTRUCTIONS,
        default="union",
        help="Greedy Reconstruction variant (default: union, the paper's)",
    )
    parser.add_argument(
        "--threshold",
        type=float,
        default=None,
        metavar="P",
        help="together when the classifier's probability is at least P (default: its decision)",
    )
    parser.add_argument(
        "--out", required=True, metavar="MODEL", help="model file to write (.skops)"
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from reform import Reform, time_split
    from reform.classifiers import make_classifier
    from reform.features import check_features
    from reform.persistence import save_model
    from reform.tuning import classifier_params, tune

    check_output("--out", args.out)
    if args.train_fraction is None:
        args.train_fraction = TRAIN_FRACTION
    else:
        check_train_fraction(args)
        if args.frames == "all":
            raise CliError(
                f"--train-fraction {args.train_fraction:g} splits the frames for --frames "
                "train|test; with --frames all every annotated frame trains"
            )
    if args.threshold is not None and not 0.0 < args.threshold < 1.0:
        raise CliError(f"--threshold must be a probability in (0, 1), got {args.threshold}")
    features = check_features([name.strip() for name in args.features.split(",") if name.strip()])
    dataset = load_data(args)
    frames = dataset.annotated()
    if not frames:
        raise CliError(f"{args.data}: the dataset has no annotated frames to train on")
    if args.frames != "all":
        train, test = time_split(frames, args.train_fraction)
        frames = train if args.frames == "train" else test
        if not frames:
            raise CliError(f"{args.data}: the {args.frames} part of the split holds no frames")
    params = {}
    if args.tune:
        print(f"cross-validating {args.classifier} on {len(frames)} frames ...", file=sys.stderr)
        tuning = tune(args.classifier, frames, features=features, n_jobs=args.jobs)
        params = classifier_params(args.classifier, tuning.best_params)
        for candidate, score in zip(tuning.candidates, tuning.mean_score, strict=True):
            print(f"  {candidate}: CV pairwise accuracy {100 * score:.2f} %", file=sys.stderr)
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
