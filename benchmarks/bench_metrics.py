"""Speed of reform.evaluate on every annotated SALSA frame, against a loop-by-loop baseline.

The baseline transcribes GCFF's ff_evalgroups.m literally in Python (sets, a scan of the detected
groups for every true group, float division) plus a double loop over pairs; it is run in the same
process on the same predictions, and the two must agree (checked). The predictions are the
original GCFF code's on SALSA when its reference output is found beside the datasets, else the
truth with its groups shifted by one. Prints medians and their ratio.

    python benchmarks/bench_metrics.py [--datasets ../shared/datasets] [--repeats 7] [--quick]

``--quick``: the first 100 annotated frames, one repeat.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from timing import BenchmarkParser, datasets_folder, median_seconds

from reform import T_ONE, T_TWO_THIRDS, evaluate
from reform.datasets import load_salsa

REFERENCE = "reference/gcff-reference/salsa-body-stride70cm-mdl10000.txt"
QUICK_FRAMES = 100  # annotated frames of a --quick run


def loop_baseline(frames, predictions, threshold):
    """Frame-mean P, R and pairwise accuracy, one Python loop per rule."""
    precisions, recalls, correct, total = [], [], 0, 0
    for frame, prediction in zip(frames, predictions, strict=True):
        ids = frame.ids.tolist()
        true_of = {m: g for g, group in enumerate(frame.partition()) for m in group}
        pred_of = {m: g for g, group in enumerate(prediction) for m in group}
        for a in range(len(ids)):
            for b in range(a + 1, len(ids)):
                same_true = true_of[ids[a]] == true_of[ids[b]]
                same_pred = pred_of[ids[a]] == pred_of[ids[b]]
                correct += same_true == same_pred
                total += 1
        truth = [set(g) for g in frame.partition() if len(g) > 1]
        detected = [set(g) for g in prediction if len(g) > 1]
        if not truth and not detected:
            p, r = 1.0, 1.0
        elif not detected:
            p, r = 1.0, 0.0
        elif not truth:
            p, r = 0.0, 1.0
        else:
            tp = 0
            for g in truth:
                for d in detected:
                    if len(g & d) / max(len(g), len(d)) >= threshold:
                        tp += 1
                        break
            p, r = tp / len(detected), tp / len(truth)
        precisions.append(p)
        recalls.append(r)
    return float(np.mean(precisions)), float(np.mean(recalls)), correct / total


def read_partitions(path: Path):
    out = []
    for line in path.read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        groups: dict[str, list[int]] = {}
        for pair in line.split()[2:]:
            person, label = pair.split(":")
            groups.setdefault(label, []).append(int(person))
        out.append(tuple(map(tuple, groups.values())))
    return out


def main() -> None:
    parser = BenchmarkParser(__doc__, repeats=7)
    parser.add_datasets_argument()
    args = parser.parse_args()
    datasets = datasets_folder(args.datasets, "salsa")
    frames = load_salsa(datasets / "salsa").annotated()
    reference = datasets.parent / REFERENCE
    predictions = read_partitions(reference) if reference.is_file() else None
    if predictions is None:  # fall back to a deterministic synthetic detector: shifted truth
        predictions = [f.partition()[1:] + f.partition()[:1] for f in frames]
    if args.quick:
        frames, predictions = frames[:QUICK_FRAMES], predictions[:QUICK_FRAMES]

    ev = evaluate(frames, predictions)
    for t in (T_TWO_THIRDS, T_ONE):
        p, r, acc = loop_baseline(frames, predictions, float(t))
        found = (ev.at(t).precision, ev.at(t).recall, ev.pairwise_accuracy)
        if not np.allclose((p, r, acc), found, rtol=0.0, atol=1e-12):
            raise SystemExit(
                f"T={t}: evaluate gives P, R, pairwise accuracy {found}, the loop {(p, r, acc)}"
            )

    fast = median_seconds(
        lambda: evaluate(frames, predictions).to_json(detector="d", dataset="s"), args.repeats
    )
    slow = median_seconds(
        lambda: [loop_baseline(frames, predictions, float(t)) for t in (T_TWO_THIRDS, T_ONE)],
        args.repeats,
    )
    print(
        f"evaluate, {len(frames)} SALSA frames, T=2/3 and T=1 + JSON: {fast * 1e3:.1f} ms "
        f"(median of {args.repeats}); loop baseline {slow * 1e3:.1f} ms; "
        f"ratio {slow / fast:.1f}x faster"
    )


if __name__ == "__main__":
    main()
