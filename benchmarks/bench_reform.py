"""REFORM speed: per-frame latency and batch throughput for 7, 18 and 50 people, each classifier.

Baseline, measured in the same run on the same frames: the naive use of scikit-learn — per
frame, the pair features, one ``predict`` of the plain fitted classifier, and the reference
Greedy Reconstruction (:func:`reform.greedy_reconstruction`). REFORM's ``predict`` uses the
compiled classifier of :mod:`reform.fast`; both must give identical partitions (checked on every
baseline frame) and identical pair labels (checked on the batch's pairs).

The models are the three ready-made classifiers with their default parameters, trained on the
SALSA training split (``reform.time_split``) when the shared datasets are found
(``$REFORM_SIM_DATASETS`` or ``../shared/datasets``), else on synthetic circles. The timed frames
are synthetic: circles of 2-5 people facing their centre and loners, on a grid 3 m apart, at
SALSA-like density (seeded).

Throughput is wall-clock frames per second of ``predict`` on a batch of distinct frames (median
of three runs); frames per CPU-second are printed beside it, as the machine may be shared.

Run: ``python benchmarks/bench_reform.py [--quick]``. Targets (Bagged Trees, 18 people): median
single-frame detection at most 0.5 ms, batch at least 50,000 frames/s, identical predictions.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from pathlib import Path

import numpy as np
from circles import circle, wrap_yaws
from timing import default_datasets, timed_each

import reform
from reform import Frame, Reform, greedy_reconstruction, relation_matrix, time_split
from reform.classifiers import BAGGED_TREES, CLASSIFIERS, make_classifier
from reform.fast import sklearn_pair_labels
from reform.features import batch_pair_features, frame_pair_features
from reform.reconstruction import batch_greedy_labels

SIZES = (7, 18, 50)  # people per frame
SEED = 20201025
GRID_SPACING_M = 3.0  # metres between circle centres
TARGET_SINGLE_MS = 0.5  # milliseconds, Bagged Trees, 18 people
TARGET_BATCH_FPS = 50_000  # frames per second, Bagged Trees, 18 people
BATCH_SECONDS = 1.0  # aim for batches that take about this long


def scene(rng: np.random.Generator, n: int) -> Frame:
    """``n`` people in circles of 2-5 facing their centre, and some loners."""
    position, yaw = [], []
    side = math.ceil(math.sqrt(n / 2.5)) + 1
    cells = rng.permutation(side * side)
    k = 0
    while len(position) < n:
        size = int(min(rng.choice([1, 2, 2, 3, 3, 4, 5]), n - len(position)))
        cell = cells[k % cells.size]
        k += 1
        centre = GRID_SPACING_M * np.array([cell % side, cell // side], dtype=float)
        centre += rng.normal(0.0, 0.3, 2) + (k // cells.size) * 0.9
        members, facing = circle(
            rng,
            centre=centre,
            size=size,
            radius=0.45 + 0.1 * size,
            angle_sd=0.2,
            position_sd=0.08,
            yaw_sd=0.35,
        )
        position += members
        yaw += facing
    return Frame(ids=np.arange(1, n + 1), position=np.asarray(position), yaw=wrap_yaws(yaw))


def training_frames() -> tuple[tuple[Frame, ...], str]:
    root = Path(default_datasets())
    if (root / "salsa").is_dir():
        salsa = reform.load_dataset(root / "salsa")
        train, _ = time_split(salsa.annotated())
        return train, f"SALSA training split ({len(train)} frames)"
    rng = np.random.default_rng(SEED)
    frames = []
    for t in range(600):
        frame = scene(rng, 18)
        truth = _circles_truth(frame)
        frames.append(frame.replace(groups=truth, time=float(t), sequence="synthetic"))
    return tuple(frames), "synthetic circles (600 frames; shared datasets not found)"


def _circles_truth(frame: Frame) -> tuple[tuple[int, ...], ...]:
    """Ground truth of a synthetic scene: people within 1.2 m and facing inward together."""
    from reform.features import pair_indices

    features = frame_pair_features(frame)
    i, j = pair_indices(frame.n_people)
    together = (features[:, 0] < 1.3) & (features[:, 1] < 2.2)
    rows = greedy_reconstruction(relation_matrix(together, frame.n_people))
    return tuple(tuple(int(frame.ids[r]) for r in g) for g in rows if len(g) > 1)


_FRAMES: dict[int, list[Frame]] = {}


def distinct_frames(n: int, count: int) -> list[Frame]:
    """``count`` different scenes of ``n`` people (made once per size, then reused)."""
    frames = _FRAMES.setdefault(n, [])
    rng = np.random.default_rng(SEED + 1000 * n + len(frames))
    while len(frames) < count:
        frames.append(scene(rng, n).replace(time=float(len(frames))))
    return frames[:count]


def naive_predict(model: Reform, frame: Frame):
    """The baseline: features, one scikit-learn predict, reference reconstruction."""
    labels = model.classifier_.predict(frame_pair_features(frame, features=model.features_))
    rows = greedy_reconstruction(relation_matrix(labels == 1, frame.n_people))
    return tuple(tuple(int(frame.ids[r]) for r in group) for group in rows)


def bench(model: Reform, n: int, quick: bool) -> dict:
    rng = np.random.default_rng(SEED + n)
    k_naive = 15 if quick else 40
    k_single = 100 if quick else 300
    frames = [scene(rng, n) for _ in range(max(k_naive, k_single))]
    model.predict(frames[:3])  # warm-up (the compiled classifier is built at fit)

    naive_out = [naive_predict(model, f) for f in frames[:k_naive]]
    naive_s = timed_each(lambda f: naive_predict(model, f), frames[:k_naive]).median
    single_s = timed_each(lambda f: model.predict([f]), frames[:k_single]).median
    fast_out = model.predict(frames[:k_naive])
    identical_frames = sum(a == b for a, b in zip(naive_out, fast_out, strict=True))

    batch_size = int(min(60_000, max(300, BATCH_SECONDS / max(single_s / 4, 1e-7))))
    if quick:
        batch_size = min(batch_size, 10_000)
    batch = distinct_frames(n, batch_size)
    runs, cpu = [], []
    for _ in range(1 if quick else 3):
        start, start_cpu = time.perf_counter(), time.process_time()
        model.predict(batch)
        runs.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    batch_fps = batch_size / statistics.median(runs)
    pool = batch[:2000]

    # Pair labels of the compiled classifier against scikit-learn's on the batch's pairs.
    position = np.stack([f.position for f in pool])
    yaw = np.stack([f.yaw for f in pool])
    x = batch_pair_features(position, yaw).reshape(-1, 2)[:300_000]
    compiled = model._pair_classifier()
    agreement = float(np.mean(compiled.predict(x) == sklearn_pair_labels(model.classifier_, x)))
    return {
        "n": n,
        "naive_ms": naive_s * 1e3,
        "single_ms": single_s * 1e3,
        "naive_fps": 1.0 / naive_s,
        "batch_fps": batch_fps,
        "batch_cpu_fps": batch_size / statistics.median(cpu),
        "batch_frames": batch_size,
        "identical": f"{identical_frames}/{k_naive}",
        "agreement": agreement,
        "pairs_checked": x.shape[0],
        "kind": compiled.kind,
    }


def stages(model: Reform, n: int, n_frames: int) -> dict[str, float]:
    """Where a batch's time goes, chunk by chunk as ``predict`` does: stacking the frames'
    arrays, features, classification, reconstruction, building the partitions."""
    from reform.detector import CHUNK_PAIRS, _partitions

    frames = distinct_frames(n, n_frames)
    compiled = model._pair_classifier()
    step = max(1, CHUNK_PAIRS // (n * (n - 1) // 2))
    out = dict.fromkeys(("stack", "features", "classify", "reconstruct", "partitions"), 0.0)
    for start in range(0, n_frames, step):
        chunk = frames[start : start + step]
        count = len(chunk)
        t0 = time.perf_counter()
        position = np.concatenate([f.position for f in chunk]).reshape(count, n, 2)
        yaw = np.concatenate([f.yaw for f in chunk]).reshape(count, n)
        ids = np.concatenate([f.ids for f in chunk]).reshape(count, n)
        t1 = time.perf_counter()
        x = batch_pair_features(position, yaw)
        t2 = time.perf_counter()
        labels = compiled.predict(x.reshape(-1, 2)).reshape(count, -1)
        t3 = time.perf_counter()
        groups = batch_greedy_labels(labels, n)
        t4 = time.perf_counter()
        _partitions(groups, ids)
        t5 = time.perf_counter()
        for key, seconds in zip(out, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4), strict=True):
            out[key] += seconds
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer frames, one batch run")
    args = parser.parse_args()

    train, source = training_frames()
    print(f"REFORM speed. Models trained on {source}; timed frames synthetic (seed {SEED}).")
    print("Baseline: per frame, features + one scikit-learn predict + reference reconstruction.\n")
    header = (
        f"{'classifier':<20} {'people':>6} {'naive ms':>9} {'REFORM ms':>9} {'x':>6} "
        f"{'naive fr/s':>10} {'batch fr/s':>11} {'x':>7} {'(CPU fr/s)':>11}  identical  "
        "pair agreement  compiled"
    )
    print(header)
    print("-" * len(header))
    summary = None
    models = {}
    for name in CLASSIFIERS:
        models[name] = Reform(make_classifier(name)).fit(train)
        for n in SIZES:
            r = bench(models[name], n, args.quick)
            print(
                f"{name:<20} {n:>6} {r['naive_ms']:>9.3f} {r['single_ms']:>9.3f} "
                f"{r['naive_ms'] / r['single_ms']:>6.1f} {r['naive_fps']:>10,.0f} "
                f"{r['batch_fps']:>11,.0f} {r['batch_fps'] / r['naive_fps']:>7.0f} "
                f"{r['batch_cpu_fps']:>11,.0f}  "
                f"{r['identical']:>9}  {100 * r['agreement']:>13.3f}%  {r['kind']}"
            )
            if name == BAGGED_TREES and n == 18:
                summary = r
    print()
    n_frames = 10_000 if args.quick else 50_000
    parts = stages(models[BAGGED_TREES], 18, n_frames)
    total = sum(parts.values())
    shares = ", ".join(f"{k} {1e3 * v:.0f} ms ({100 * v / total:.0f}%)" for k, v in parts.items())
    print(f"Bagged Trees, 18 people, {n_frames:,} frames, by stage: {shares}")
    assert summary is not None
    single_ok = summary["single_ms"] <= TARGET_SINGLE_MS
    batch_ok = summary["batch_fps"] >= TARGET_BATCH_FPS
    same = summary["identical"].split("/")[0] == summary["identical"].split("/")[1]
    exact = summary["agreement"] == 1.0
    print(
        f"Targets, Bagged Trees, 18 people: single frame {summary['single_ms']:.3f} ms "
        f"(<= {TARGET_SINGLE_MS} ms: {'met' if single_ok else 'MISSED'}), "
        f"batch {summary['batch_fps']:,.0f} frames/s "
        f"(>= {TARGET_BATCH_FPS:,}: {'met' if batch_ok else 'MISSED'}; "
        f"{summary['batch_cpu_fps']:,.0f} frames per CPU-second), "
        f"predictions identical: {'yes' if same and exact else 'NO'}"
    )


if __name__ == "__main__":
    main()
