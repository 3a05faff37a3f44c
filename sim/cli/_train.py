"""``reform-sim train``: fit REFORM (a skops file) or DANTE (a safetensors file) on a dataset's
annotated frames and save it."""

from __future__ import annotations

import argparse

from reform.classifiers import CLASSIFIERS
from reform.features import DEFAULT_FEATURES, FEATURES
from reform.reconstruction import RECONSTRUCTIONS
from sim.cli._common import add_data_arguments, add_jobs_argument
from sim.cli._grammar import add_frames, add_quiet, run_loading
from sim.cli._numbers import ascii_float, ascii_int

DESCRIPTION = """\
Deconstructs the annotated frames of a dataset into pairs (Distance, Effort Angle), fits one of
the paper's pair classifiers, and saves the fitted REFORM model with skops (never pickle),
together with its features, classifier, training summary and the package version. Use the model
with `reform-sim detect --model` and `reform-sim evaluate --model`.

--frames train|test picks the training or test part of reform.time_split (per sequence, the
first --train-fraction of annotated frames by time train); --tune chooses the classifier's
hyper-parameters by time-blocked cross-validation on the frames used for training.

--detector dante trains DANTE (Swofford et al. 2020; the extra reform-sim[dante]) instead: its
deep affinity network on every ordered pair of the frames and their mirror images, one line per
epoch on stderr; its options (--option NAME=VALUE: epochs, learning_rate, batch_size, patience,
orientation, random_state) are the catalogue's. --validation F holds out the last F of each
sequence's training frames, by time, and stops once their loss has not improved for `patience`
epochs (the paper's early stopping). --out names the model file (.safetensors), for
`reform-sim detect|evaluate|benchmark --detector dante` with the option model=FILE.

--every K keeps every K-th of the frames chosen (and of the validation frames): a slow
recording's consecutive frames repeat each other, and K cuts the training time K-fold.
"""

# The detectors `train` fits, and the ending of the model file each one's writer writes.
TRAINED = {"reform": ".skops", "dante": ".safetensors"}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_data_arguments(parser)
    parser.add_argument(
        "--detector",
        choices=tuple(TRAINED),
        default="reform",
        help="what to train: reform (default) or dante (needs reform-sim[dante])",
    )
    parser.add_argument(
        "--option",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="dante: one of its catalogued options (repeatable), e.g. epochs=50",
    )
    parser.add_argument(
        "--classifier",
        choices=tuple(CLASSIFIERS),
        default=None,
        help="pair classifier (default: bagged-trees)",
    )
    add_frames(parser, scored="to train on")
    parser.add_argument(
        "--every",
        type=ascii_int,
        default=1,
        metavar="K",
        help="train on every K-th of those frames, in time order per sequence (default: 1, all)",
    )
    parser.add_argument(
        "--validation",
        type=ascii_float,
        default=None,
        metavar="F",
        help="dante: the last F of each sequence's training frames stop training early "
        "(--option patience=N) instead of training",
    )
    parser.add_argument(
        "--tune",
        action="store_true",
        help="choose hyper-parameters by time-blocked cross-validation on the training frames",
    )
    add_jobs_argument(parser, does="with --tune: processes fitting the cross-validation folds")
    parser.add_argument(
        "--features",
        default=None,
        metavar="F1,F2",
        help=f"pair features, comma-separated, from {', '.join(FEATURES)} "
        f"(default: {','.join(DEFAULT_FEATURES)})",
    )
    parser.add_argument(
        "--reconstruction",
        choices=RECONSTRUCTIONS,
        default=None,
        help="Greedy Reconstruction variant (default: union, the paper's)",
    )
    parser.add_argument(
        "--threshold",
        type=ascii_float,
        default=None,
        metavar="P",
        help="together when the classifier's probability is at least P (default: its decision)",
    )
    parser.add_argument(
        "--out",
        required=True,
        metavar="FILE",
        help="model file to write ("
        + ", ".join(f"{suffix} for {name}" for name, suffix in TRAINED.items())
        + ")",
    )
    add_quiet(parser, old=())
    parser.set_defaults(handler=run_loading("sim.cli.train:run", "scikit-learn"))
