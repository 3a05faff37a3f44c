"""REFORM speed: per-frame latency and batch throughput for 7, 18 and 50 people, each classifier.

Baseline, measured in the same run on the same frames: the naive use of scikit-learn — per
frame, the pair features, one ``predict`` of the plain fitted classifier, and the reference
Greedy Reconstruction (:func:`reform.greedy_reconstruction`). REFORM's ``predict`` uses the
compiled classifier of :mod:`reform.fast`; both must give identical partitions (checked on every
baseline frame) and identical pair labels (``Reform.predict_pairs`` against
:func:`reform.fast.sklearn_pair_labels`, checked on the batch's pairs).

The models are the three ready-made classifiers with their default parameters, trained on the
SALSA training split (``reform.time_split``) when the shared datasets are found
(``$REFORM_SIM_DATASETS`` or ``../shared/datasets``), else on synthetic circles. The timed frames
are synthetic: circles of 2-5 people facing their centre and loners, on a grid 3 m apart, at
SALSA-like density (seeded).

Throughput is wall-clock frames per second of ``predict`` on a batch of distinct frames (median
of three runs); frames per CPU-second are printed beside it, as the machine may be shared. Where
a batch's time goes is measured with the public pieces ``predict`` is made of (stacking the
frames' arrays, :func:`reform.batch_pair_features`, the compiled classifier of
:func:`reform.fast.compile_classifier`, :func:`reform.batch_greedy_labels`), chunk by chunk,
beside ``predict`` itself on the same chunks: the rest (building the partitions, checking the
frames) is the difference.

Last, the options beyond the paper (``features="relative"``, ``reconstruction="correlation"``,
``calibration="sigmoid"``) are timed on batches of 18 and 30 people as a ratio to the defaults on
the same frames: correlation clustering asks the classifier for probabilities (scikit-learn's
``predict_proba``, not the compiled table) and clusters each frame in Python, calibration runs
one classifier per fold.

Run: ``python benchmarks/bench_reform.py [--quick]`` (``--quick``: models trained on 100 frames,
a few frames per size, batches of 200 frames, one batch run, 20,000 pairs checked). Targets
(Bagged Trees, 18 people): median single-frame detection at most 0.5 ms, batch at least 50,000
frames/s, identical predictions.
"""

from __future__ import annotations

import functools
import math
import statistics
import time
from pathlib import Path

import numpy as np
from circles import crowd
from timing import BenchmarkParser, default_datasets, median_seconds, timed_each

import reform
from reform import (
    Frame,
    Reform,
    batch_greedy_labels,
    batch_pair_features,
    frame_pair_features,
    greedy_reconstruction,
    relation_matrix,
    time_split,
)
from reform.classifiers import BAGGED_TREES, CLASSIFIERS, make_classifier
from reform.fast import compile_classifier, sklearn_pair_labels

SIZES = (7, 18, 50)  # people per frame
SEED = 20201025
GRID_SPACING_M = 3.0  # metres between circle centres
TARGET_SINGLE_MS = 0.5  # milliseconds, Bagged Trees, 18 people
TARGET_BATCH_FPS = 50_000  # frames per second, Bagged Trees, 18 people
BATCH_SECONDS = 1.0  # aim for batches that take about this long
QUICK_TRAINING_FRAMES = 100  # training frames with --quick (evenly spaced)
QUICK_BATCH_FRAMES = 200  # frames of a batch with --quick
STAGE_CHUNK_PAIRS = 1 << 18  # pairs per chunk when timing the stages of a batch
CHECKED_FRAMES = 2_000  # frames of the batch whose pair labels are checked (at most)
CHECKED_PAIRS = 300_000  # pairs of the batch whose labels are checked (at most)
QUICK_CHECKED_PAIRS = 20_000  # pairs checked with --quick (at most)


def scene(rng: np.random.Generator, n: int) -> Frame:
    """``n`` people in circles of 2-5 facing their centre, and some loners."""
    side = math.ceil(math.sqrt(n / 2.5)) + 1
    cells = rng.permutation(side * side)

    def centre(k: int) -> np.ndarray:
        """Circle ``k`` in a shuffled grid cell, jittered; a second round of cells shifted."""
        cell = cells[k % cells.size]
        at = GRID_SPACING_M * np.array([cell % side, cell // side], dtype=float)
        return at + (rng.normal(0.0, 0.3, 2) + ((k + 1) // cells.size) * 0.9)

    position, yaw = crowd(
        rng,
        n,
        draw_size=lambda: rng.choice([1, 2, 2, 3, 3, 4, 5]),
        centre=centre,
        radius_per_person_m=0.1,
        angle_sd=0.2,
        position_sd=0.08,
        yaw_sd=0.35,
    )
    return Frame(ids=np.arange(1, n + 1), position=position, yaw=yaw)


def training_frames(quick: bool) -> tuple[tuple[Frame, ...], str]:
    """SALSA's training split when found, else synthetic circles; with ``quick``, 100 frames."""
    root = Path(default_datasets())
    if (root / "salsa").is_dir():
        salsa = reform.load_dataset(root / "salsa")
        train, _ = time_split(salsa.annotated())
        if quick:
            train = train[:: max(1, len(train) // QUICK_TRAINING_FRAMES)][:QUICK_TRAINING_FRAMES]
            return train, f"{len(train)} frames of the SALSA training split"
        return train, f"SALSA training split ({len(train)} frames)"
    rng = np.random.default_rng(SEED)
    frames = []
    count = QUICK_TRAINING_FRAMES if quick else 600
    for t in range(count):
        frame = scene(rng, 18)
        truth = _circles_truth(frame)
        frames.append(frame.replace(groups=truth, time=float(t), sequence="synthetic"))
    return tuple(frames), f"synthetic circles ({count} frames; shared datasets not found)"


def _circles_truth(frame: Frame) -> tuple[tuple[int, ...], ...]:
    """Ground truth of a synthetic scene: people within 1.2 m and facing inward together."""
    features = frame_pair_features(frame)
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
    k_naive = 5 if quick else 40
    k_single = 20 if quick else 300
    frames = [scene(rng, n) for _ in range(max(k_naive, k_single))]
    model.compile().predict(frames[:3])  # warm-up: the compiled classifier, as a long run's

    naive_out = [naive_predict(model, f) for f in frames[:k_naive]]
    naive_s = timed_each(lambda f: naive_predict(model, f), frames[:k_naive]).median
    single_s = timed_each(lambda f: model.predict([f]), frames[:k_single]).median
    fast_out = model.predict(frames[:k_naive])
    identical_frames = sum(a == b for a, b in zip(naive_out, fast_out, strict=True))

    batch_size = int(min(60_000, max(300, BATCH_SECONDS / max(single_s / 4, 1e-7))))
    if quick:
        batch_size = QUICK_BATCH_FRAMES
    batch = distinct_frames(n, batch_size)
    runs, cpu = [], []
    for _ in range(1 if quick else 3):
        start, start_cpu = time.perf_counter(), time.process_time()
        model.predict(batch)
        runs.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    batch_fps = batch_size / statistics.median(runs)
    checked = QUICK_CHECKED_PAIRS if quick else CHECKED_PAIRS
    pool = batch[: min(CHECKED_FRAMES, max(1, checked // (n * (n - 1) // 2)))]

    # Pair labels of REFORM's predict_pairs against scikit-learn's on the batch's pairs.
    position = np.stack([f.position for f in pool])
    yaw = np.stack([f.yaw for f in pool])
    x = batch_pair_features(position, yaw, features=model.features_)
    x = x.reshape(-1, x.shape[-1])
    fast_pairs = np.concatenate(model.predict_pairs(pool))
    sklearn_pairs = sklearn_pair_labels(model.classifier_, x, threshold=model.threshold)
    agreement = float(np.mean(fast_pairs == sklearn_pairs))
    compiled = compile_classifier(model.classifier_, threshold=model.threshold)
    return {
        "n": n,
        "naive_ms": naive_s * 1e3,
        "single_ms": single_s * 1e3,
        "naive_fps": 1.0 / naive_s,
        "batch_fps": batch_fps,
        "batch_cpu_fps": batch_size / statistics.median(cpu),
        "batch_frames": batch_size,
        "identical": f"{identical_frames}/{k_naive}",
        "identical_frames": identical_frames,
        "frames_checked": k_naive,
        "agreement": agreement,
        "pairs_checked": x.shape[0],
        "kind": compiled.kind,
    }


def stages(model: Reform, n: int, n_frames: int) -> dict[str, float]:
    """Where a batch's time goes, chunk by chunk: stacking the frames' arrays, features,
    classification, reconstruction (each timed with the public function ``predict`` calls),
    and the rest of ``predict`` on the same chunk (building the partitions, checks)."""
    frames = distinct_frames(n, n_frames)
    compiled = compile_classifier(model.classifier_, threshold=model.threshold)
    step = max(1, STAGE_CHUNK_PAIRS // (n * (n - 1) // 2))
    out = dict.fromkeys(("stack", "features", "classify", "reconstruct", "the rest"), 0.0)
    for start in range(0, n_frames, step):
        chunk = frames[start : start + step]
        count = len(chunk)
        t0 = time.perf_counter()
        position = np.concatenate([f.position for f in chunk]).reshape(count, n, 2)
        yaw = np.concatenate([f.yaw for f in chunk]).reshape(count, n)
        t1 = time.perf_counter()
        x = batch_pair_features(position, yaw, features=model.features_)
        t2 = time.perf_counter()
        labels = compiled.predict(x.reshape(-1, x.shape[-1])).reshape(count, -1)
        t3 = time.perf_counter()
        batch_greedy_labels(labels, n, variant=model.reconstruction)
        t4 = time.perf_counter()
        model.predict(chunk)
        t5 = time.perf_counter()
        parts = (t1 - t0, t2 - t1, t3 - t2, t4 - t3, max(0.0, (t5 - t4) - (t4 - t0)))
        for key, seconds in zip(out, parts, strict=True):
            out[key] += seconds
    return out


OPTION_SETS = (  # Reform's options beyond the paper, timed against the defaults
    {"features": "relative"},
    {"reconstruction": "correlation"},
    {"calibration": "sigmoid"},
)
OPTION_SIZES = (18, 30)  # people per frame
OPTION_FRAMES = 2_000  # frames predicted per option (200 with --quick)


def options_ratios(train: tuple[Frame, ...], quick: bool) -> list[str]:
    """Batch predict time of each option set over the defaults' on the same frames, Bagged
    Trees, median of three runs each (a ratio: both measured in this process, now)."""
    count = 200 if quick else OPTION_FRAMES
    default = Reform().fit(train).compile()  # each model compiled, as a long run's
    lines = []
    for n in OPTION_SIZES:
        frames = distinct_frames(n, count)
        base = median_seconds(functools.partial(default.predict, frames), 3)
        for options in OPTION_SETS:
            model = Reform(**options).fit(train).compile()
            seconds = median_seconds(functools.partial(model.predict, frames), 3)
            words = ", ".join(f"{k}={v!r}" for k, v in options.items())
            lines.append(
                f"{words:<28} {n:>3} people: {1e3 * seconds / count:7.3f} ms/frame, "
                f"{seconds / base:6.1f}x the defaults' {1e3 * base / count:.3f} ms/frame"
            )
    return lines


def main() -> None:
    args = BenchmarkParser(__doc__).parse_args()

    train, source = training_frames(args.quick)
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
    differ = []  # "classifier with n people" wherever predictions differ from the baseline
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
            if r["identical_frames"] != r["frames_checked"] or r["agreement"] != 1.0:
                differ.append(f"{name} with {n} people")
    print()
    n_frames = 1_000 if args.quick else 50_000
    parts = stages(models[BAGGED_TREES], 18, n_frames)
    total = sum(parts.values())
    shares = ", ".join(f"{k} {1e3 * v:.0f} ms ({100 * v / total:.0f}%)" for k, v in parts.items())
    print(f"Bagged Trees, 18 people, {n_frames:,} frames, by stage: {shares}")
    print("\nOptions beyond the paper (Bagged Trees, batch predict, against the defaults):")
    for line in options_ratios(train, args.quick):
        print(f"  {line}")
    assert summary is not None
    single_ok = summary["single_ms"] <= TARGET_SINGLE_MS
    batch_ok = summary["batch_fps"] >= TARGET_BATCH_FPS
    same = summary["identical_frames"] == summary["frames_checked"]
    exact = summary["agreement"] == 1.0
    print(
        f"Targets, Bagged Trees, 18 people: single frame {summary['single_ms']:.3f} ms "
        f"(<= {TARGET_SINGLE_MS} ms: {'met' if single_ok else 'MISSED'}), "
        f"batch {summary['batch_fps']:,.0f} frames/s "
        f"(>= {TARGET_BATCH_FPS:,}: {'met' if batch_ok else 'MISSED'}; "
        f"{summary['batch_cpu_fps']:,.0f} frames per CPU-second), "
        f"predictions identical: {'yes' if same and exact else 'NO'}"
    )
    if differ:
        raise SystemExit(f"REFORM's predictions differ from the baseline's: {', '.join(differ)}")


if __name__ == "__main__":
    main()
