"""Speed of the calibration measurements on SALSA, each against a plain per-item loop.

Baselines, run in the same process and checked to give the same numbers:
``characterise`` (vectorised over the groups of each size) against a loop calling the
one-group ``tightness`` and ``symmetry`` per F-formation; ``pair_feature_samples`` (vectorised
over frames with the same number of people) against a loop of ``frame_pair_features`` and
``pair_labels`` per frame. Prints medians and ratios (baseline / vectorised).

    python benchmarks/bench_characterisation.py [--datasets ../shared/datasets] [--repeats 5]
        [--quick]

``--quick``: the first 60 annotated frames, one repeat.
"""

from __future__ import annotations

import numpy as np
from timing import BenchmarkParser, datasets_folder, median_seconds

from reform.calibration import PAIR_FEATURES, pair_feature_samples
from reform.characterisation import characterise, symmetry, tightness
from reform.datasets import load_salsa
from reform.features import frame_pair_features
from reform.metrics import pair_labels

QUICK_FRAMES = 60  # annotated frames of a --quick run


def loop_characterise(frames) -> tuple[np.ndarray, np.ndarray]:
    tight, sym = [], []
    for frame in frames:
        for group in frame.fformations():
            members = frame.position[[frame.index_of(m) for m in group]]
            tight.append(tightness(members))
            sym.append(symmetry(members))
    return np.asarray(tight), np.asarray(sym)


def loop_pairs(frames) -> tuple[np.ndarray, np.ndarray]:
    features = [frame_pair_features(f, features=PAIR_FEATURES) for f in frames]
    labels = [pair_labels(f) for f in frames]
    return np.concatenate(features), np.concatenate(labels)


def main() -> None:
    parser = BenchmarkParser(__doc__, repeats=5)
    parser.add_datasets_argument()
    args = parser.parse_args()
    frames = load_salsa(datasets_folder(args.datasets, "salsa") / "salsa").annotated()
    if args.quick:
        frames = frames[:QUICK_FRAMES]

    shapes = characterise(frames)
    tight, sym = loop_characterise(frames)
    np.testing.assert_allclose(shapes.tightness, tight, rtol=1e-12)
    np.testing.assert_allclose(shapes.symmetry, sym, rtol=1e-9, atol=1e-9)
    samples = pair_feature_samples(frames)
    features, labels = loop_pairs(frames)
    np.testing.assert_allclose(samples.distance, features[:, 0], rtol=1e-12)
    np.testing.assert_allclose(samples.effort_angle, features[:, 1], rtol=1e-12)
    np.testing.assert_array_equal(samples.label, labels)

    print(
        f"SALSA: {len(frames)} annotated frames, {shapes.size.size} F-formations, "
        f"{samples.label.size} pairs; medians of {args.repeats}"
    )
    for name, fast, slow in (
        ("characterise", lambda: characterise(frames), lambda: loop_characterise(frames)),
        ("pair_feature_samples", lambda: pair_feature_samples(frames), lambda: loop_pairs(frames)),
    ):
        t_fast = median_seconds(fast, args.repeats)
        t_slow = median_seconds(slow, args.repeats)
        print(
            f"{name:22s} {1e3 * t_fast:8.1f} ms   per-item loop {1e3 * t_slow:8.1f} ms   "
            f"ratio {t_slow / t_fast:5.1f}x"
        )


if __name__ == "__main__":
    main()
