"""REFORM's options beyond the paper, compared on SALSA's training split by time-blocked CV.

Every choice these options make (the feature set, the edge weight of correlation clustering)
was made with this study, which reads **only SALSA's training split** (``reform.time_split``,
first 60 % of each session): SALSA's test split, Babble, CoffeeBreak and Synth stay unseen. The
training split is cut into stretches of time (:func:`reform.time_blocks`, 5 per session) and
each stretch is predicted by a model fitted on the others (``GroupKFold``), so no fold is tested
on the neighbours of frames it trained on.

Each held-out stretch is predicted as it is and with every position multiplied by 0.6 and by
1.6, as if it came from a dataset measured at another scale (the field's datasets differ about
twofold in group radius, and video-estimated positions carry a per-dataset scale error).

Per option set it reports: the classifier's pair accuracy and pair F1 (its own labels, before
reconstruction), the pairwise accuracy of the predicted partitions and their group F1 at
T = 2/3 and T = 1 (:func:`reform.evaluate`), and the log loss of the pair probabilities (what
calibration is for). Beside the options, the edge weight of correlation clustering is compared:
the log-odds ``logit(p)`` (chosen) and the plain ``p - 0.5``.

Run: ``python -m sim.experiments.reform_options [--step N] [--quick] [--datasets DIR]
[--json FILE]`` (``--step N``: every Nth training frame, neighbouring frames being
near-duplicates; ``--quick``: every 4th, the unscaled folds only).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from sklearn.metrics import f1_score, log_loss
from sklearn.model_selection import GroupKFold

from reform import Frame, Reform, evaluate, load_dataset, pair_indices, time_blocks, time_split
from reform.metrics import pair_labels
from reform.reconstruction import correlation_clustering, pair_weights

__all__ = ["OPTION_SETS", "SCALES", "compare_options", "main"]

N_FOLDS = 5  # stretches of time per session, one fold each
SCALES = (1.0, 0.6, 1.6)  # factors on the held-out positions
# The option sets compared (keyword arguments of reform.Reform); the first is the paper's.
OPTION_SETS: tuple[dict[str, Any], ...] = (
    {},
    {"features": "relative"},
    {"reconstruction": "correlation"},
    {"features": "relative", "reconstruction": "correlation"},
    {"calibration": "isotonic"},
    {"reconstruction": "correlation", "calibration": "isotonic"},
    {"features": "relative", "reconstruction": "correlation", "calibration": "isotonic"},
)


def label(options: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v}" for k, v in options.items()) or "paper (defaults)"


def compare_options(
    frames: Sequence[Frame],
    *,
    option_sets: Sequence[dict[str, Any]] = OPTION_SETS,
    scales: Sequence[float] = SCALES,
) -> list[dict[str, Any]]:
    """Scores of each option set on ``frames`` (annotated training frames) by time-blocked CV."""
    frames = tuple(frames)
    blocks = time_blocks(frames, N_FOLDS)
    folds = list(GroupKFold(N_FOLDS).split(np.zeros(len(frames)), groups=blocks))
    rows = []
    for options in option_sets:
        rows += _score(frames, folds, options, scales)
        for row in rows[-len(scales) :]:
            print(_line(row), file=sys.stderr, flush=True)
    return rows


def _scaled(frame: Frame, factor: float) -> Frame:
    if factor == 1.0:
        return frame
    head = None if frame.head_position is None else frame.head_position * factor
    return frame.replace(position=frame.position * factor, head_position=head)


def _score(
    frames: tuple[Frame, ...], folds: list, options: dict[str, Any], scales: Sequence[float]
) -> list[dict[str, Any]]:
    """One row per scale: each fold's model, fitted once, predicts its stretch at every scale."""
    parts: dict[float, dict[str, list]] = {s: {} for s in scales}
    for train, test in folds:
        model = Reform(**options).fit([frames[k] for k in train])
        for scale in scales:
            held = [_scaled(frames[k], scale) for k in test]
            part = parts[scale]
            probabilities = model.predict_pair_proba(held)
            part.setdefault("held", []).extend(held)
            part.setdefault("predicted", []).extend(model.predict(held))
            part.setdefault("y", []).extend(pair_labels(f) for f in held)
            part.setdefault("labels", []).extend(model.predict_pairs(held))
            part.setdefault("proba", []).extend(probabilities)
            if options.get("reconstruction") == "correlation":
                for frame, p in zip(held, probabilities, strict=True):
                    part.setdefault("logit", []).append(_cluster(frame, pair_weights(p)))
                    part.setdefault("linear", []).append(_cluster(frame, p - 0.5))
    return [_row(options, scale, parts[scale]) for scale in scales]


def _row(options: dict[str, Any], scale: float, part: dict[str, list]) -> dict[str, Any]:
    y = np.concatenate(part["y"])
    hard = np.concatenate(part["labels"])
    p = np.concatenate(part["proba"])
    held = part["held"]
    scores = evaluate(held, part["predicted"])
    row = {
        "options": label(options),
        "scale": scale,
        "frames": len(held),
        "pairs": int(y.size),
        "pair_accuracy": float(np.mean(hard == y)),
        "pair_f1": float(f1_score(y, hard)),
        "log_loss": float(log_loss(y, np.clip(p, 1e-6, 1 - 1e-6), labels=[0, 1])),
        "partition_pairwise_accuracy": float(scores.pairwise_accuracy),
        "f1_two_thirds": float(scores.at("2/3").f1),
        "f1_one": float(scores.at("1").f1),
    }
    if "logit" in part:
        row["f1_two_thirds_logit_weight"] = float(evaluate(held, part["logit"]).at("2/3").f1)
        row["f1_two_thirds_linear_weight"] = float(evaluate(held, part["linear"]).at("2/3").f1)
    return row


def _cluster(frame: Frame, weights: np.ndarray) -> tuple[tuple[int, ...], ...]:
    """Correlation clustering of one frame's pair weights (frame row order) -> its partition."""
    n = frame.n_people
    if n < 2:
        return tuple((int(k),) for k in frame.ids)
    i, j = pair_indices(n)
    order = np.argsort(frame.ids, kind="stable")  # Reform clusters people in id order
    rank = np.empty(n, dtype=np.intp)
    rank[order] = np.arange(n)
    matrix = np.zeros((n, n))
    matrix[rank[i], rank[j]] = weights
    matrix[rank[j], rank[i]] = weights
    labels = correlation_clustering(matrix)
    groups: dict[int, list[int]] = {}
    for row, person in enumerate(frame.ids[order].tolist()):
        groups.setdefault(int(labels[row]), []).append(int(person))
    return tuple(tuple(g) for g in groups.values())


def _line(row: dict[str, Any]) -> str:
    weights = (
        f" (edge weight logit {row['f1_two_thirds_logit_weight']:.4f}, "
        f"p-0.5 {row['f1_two_thirds_linear_weight']:.4f})"
        if "f1_two_thirds_logit_weight" in row
        else ""
    )
    return (
        f"{row['options']:<72} x{row['scale']:<4g} pair acc {row['pair_accuracy']:.4f} "
        f"pair F1 {row['pair_f1']:.4f} log loss {row['log_loss']:.4f} "
        f"F1@2/3 {row['f1_two_thirds']:.4f} F1@1 {row['f1_one']:.4f}{weights}"
    )


def markdown(rows: Sequence[dict[str, Any]]) -> str:
    """The rows as a Markdown table."""
    lines = [
        "| options | scale | pair accuracy | pair F1 | log loss | F1 @ 2/3 | F1 @ 1 |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['options']} | ×{r['scale']:g} | {r['pair_accuracy']:.3f} | {r['pair_f1']:.3f} "
            f"| {r['log_loss']:.3f} | {r['f1_two_thirds']:.3f} | {r['f1_one']:.3f} |"
        )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="every 4th frame, no rescaling")
    parser.add_argument(
        "--datasets",
        type=Path,
        default=Path(os.environ.get("REFORM_SIM_DATASETS", "../shared/datasets")),
        help="folder holding salsa/ (default: $REFORM_SIM_DATASETS)",
    )
    parser.add_argument("--json", type=Path, help="also write the rows to this JSON file")
    parser.add_argument(
        "--step", type=int, default=1, help="use every Nth training frame (default: all)"
    )
    args = parser.parse_args(argv)
    salsa = args.datasets / "salsa"
    if not salsa.is_dir():
        parser.exit(2, f"error: --datasets: no salsa/ folder in {args.datasets}\n")
    train, _ = time_split(load_dataset(salsa).annotated())  # the test split is never read
    if args.step < 1:
        parser.exit(2, f"error: --step must be a whole number >= 1, got {args.step}\n")
    train = train[:: 4 if args.quick else args.step]
    rows = compare_options(train, scales=(1.0,) if args.quick else SCALES)
    print(markdown(rows))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
