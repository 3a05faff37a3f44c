"""DANTE's fold protocol on a dataset: the spread of its scores over the paper's five folds.

Each fold (`reform.dante.fold_splits`: test one contiguous fifth of the annotated frames in
time order, validation half a fold on each side, training the rest) trains a DANTE on its
training frames, stopping early on its validation frames (``--patience``), and scores the test
frames with the field's protocol (F1 of the frame-mean precision and recall, T = 2/3 and T = 1).
Prints one line per fold, then the mean and the range over folds.

Run: ``python benchmarks/dante_folds.py --data coffeebreak [--epochs 600] [--learning-rate
1e-4] [--train-every 1] [--quick]``. The paper's settings are the defaults; on a CPU they take
hours on SALSA, so the figures on the method page say which settings printed them.
``--train-every K`` trains on every K-th training frame and ``--validate-every K`` stops early on
every K-th validation frame (SALSA's frames, 3 s apart, repeat each other); every test frame is
scored.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

from timing import BenchmarkParser, default_datasets

from reform import evaluate
from reform.dante import (
    BATCH_SIZE,
    EPOCHS,
    LEARNING_RATE,
    ORIENTATIONS,
    PATIENCE,
    Dante,
    fold_splits,
)
from reform.datasets import load_dataset


def main() -> int:
    parser = BenchmarkParser(__doc__)
    parser.add_argument(
        "--data", default="coffeebreak", help="a dataset folder or a name under --datasets"
    )
    parser.add_argument("--datasets", type=Path, default=Path(default_datasets()))
    parser.add_argument("--folds", type=int, default=5, help="k of the fold protocol (5)")
    parser.add_sized("--epochs", default=EPOCHS, quick=2, help="most epochs per fold")
    parser.add_argument("--learning-rate", type=float, default=LEARNING_RATE)
    parser.add_argument("--batch-size", type=int, default=BATCH_SIZE)
    parser.add_argument("--patience", type=int, default=PATIENCE)
    parser.add_argument("--orientation", choices=ORIENTATIONS, default="body")
    parser.add_argument("--train-every", type=int, default=1, metavar="K")
    parser.add_argument("--validate-every", type=int, default=1, metavar="K")
    parser.add_argument("--random-state", type=int, default=0)
    args = parser.parse_args()

    path = Path(args.data)
    if not path.exists():
        path = args.datasets / args.data
    dataset = load_dataset(path)
    frames = [frame for frame in dataset.frames if frame.groups is not None]
    if args.quick:
        frames = frames[:: max(1, len(frames) // 20)][:20]
    print(
        f"DANTE folds on {dataset.name}: {len(frames)} annotated frames, k={args.folds}, "
        f"epochs<={args.epochs}, lr {args.learning_rate:g}, batch {args.batch_size}, patience "
        f"{args.patience}, orientation {args.orientation}, training on every "
        f"{args.train_every} frame(s), validating on every {args.validate_every}"
    )
    rows = []
    for fold, (train, validation, test) in enumerate(fold_splits(frames, args.folds)):
        start = time.perf_counter()

        def progress(epoch: int, epochs: int, loss: float, val: float | None, fold=fold) -> None:
            print(
                f"  fold {fold} epoch {epoch}/{epochs} loss {loss:.4f} validation {val:.4f}",
                file=sys.stderr,
            )

        model = Dante(
            epochs=args.epochs,
            learning_rate=args.learning_rate,
            batch_size=args.batch_size,
            patience=args.patience,
            orientation=args.orientation,
            random_state=args.random_state,
        ).fit(
            [frames[k] for k in train[:: args.train_every]],
            validation=[frames[k] for k in validation[:: args.validate_every]],
            progress=progress,
        )
        tested = [frames[k] for k in test]
        scores = evaluate(tested, model.predict(tested))
        two_thirds, one = scores.at("2/3"), scores.at("1")
        rows.append((two_thirds.f1, one.f1))
        print(
            f"fold {fold}: train {len(train[:: args.train_every])} validation {len(validation)} "
            f"test {len(test)} frames, {model.training_summary_['epochs_run']} epochs: "
            f"T=2/3 P {two_thirds.precision:.3f} R {two_thirds.recall:.3f} F1 {two_thirds.f1:.3f}"
            f"  T=1 P {one.precision:.3f} R {one.recall:.3f} F1 {one.f1:.3f}"
            f"  ({time.perf_counter() - start:.0f} s)",
            flush=True,
        )
    for label, column in (("T=2/3", 0), ("T=1", 1)):
        values = [row[column] for row in rows]
        print(
            f"{label}: F1 mean {statistics.mean(values):.3f} over {len(values)} folds, range "
            f"{min(values):.3f} to {max(values):.3f} "
            f"({100 * (max(values) - min(values)):.1f} points)"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
