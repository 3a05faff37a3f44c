"""Crowds: REFORM and GCFF on one frame of 200 to 2,000 people, time and peak memory.

The frames are concourse-like crowds (seeded): conversational groups of 2-6 standing in
circles facing their centre, and walkers crossing the hall in random directions, at a density
of `DENSITY_PER_M2` people per square metre; groups keep a clear gap between them, walkers go
anywhere, close by the groups too.

REFORM (Bagged Trees, trained on the SALSA training split when the shared datasets are found,
else on synthetic circles; see ``bench_reform.training_frames``) is ``Reform.predict`` on one
frame. Its baseline, measured in the same run on the same frames, classifies every pair (the
pair features of :func:`reform.batch_pair_features`, the compiled classifier of
:func:`reform.fast.compile_classifier`) and reconstructs from them: what a crowd costs when no
pair is skipped. Both must give the same partition on every frame (checked); at sizes up to
`WHOLE_MATRIX_PEOPLE` the whole-matrix reference, :func:`reform.greedy_reconstruction`, is timed
and checked too, on the first frame (it grows as n^3.8: minutes at 2,000 people). Times are
medians over the frames of a size (wall clock); peak memory is traced by ``tracemalloc`` on the
first frame of a size.

GCFF (``Gcff()``, the reference code's settings) is timed on the same frames, median of a
size's frames (at most `GCFF_FRAMES`).

REFORM changes method with the frame's size (beyond ``reform.detector.LARGE_FRAME_PEOPLE`` = 256
people), so its growth exponent from 200 people spans the small frames' path and the crowds';
GCFF takes its crowd path from 65 people on, at every size here.

Run: ``python benchmarks/bench_crowd.py [--quick] [--sizes 200 500 1000 2000]``
(``--quick``: 200 and 400 people, two frames each, models trained on 100 frames). Targets
(issue 31): REFORM at most 50 ms at 1,000 people and 250 ms at 2,000, peak memory under 500
MB; GCFF at most 1 s at 2,000.
"""

from __future__ import annotations

import math
import time
import tracemalloc

import numpy as np
from bench_reform import training_frames
from circles import circle, wrap_yaws
from timing import BenchmarkParser, timed_each

from reform import (
    Frame,
    Gcff,
    Reform,
    batch_pair_features,
    greedy_reconstruction,
    pair_indices,
    partition_from_labels,
    relation_matrix,
)
from reform.fast import compile_classifier
from reform.reconstruction import graph_greedy_labels

SEED = 20261205
SIZES = (200, 500, 1000, 2000)  # people per frame
QUICK_SIZES = (200, 400)
FRAMES = 7  # frames per size (5 of 2,000 people)
QUICK_FRAMES = 2
WHOLE_MATRIX_PEOPLE = 500  # sizes up to this also timed with the whole-matrix reference (the
# smallest size only, with --quick)
GCFF_FRAMES = 3  # frames per size timed with GCFF
DENSITY_PER_M2 = 0.5  # people per square metre of the hall (a busy concourse)
WALKER_SHARE = 0.4  # share of the people walking through, not in a group
GROUP_GAP_M = 1.0  # metres: at least this between the circles of two groups
TARGETS_MS = {1000: 50.0, 2000: 250.0}  # REFORM, milliseconds per frame
TARGET_PEAK_MB = 500.0  # REFORM, megabytes
TARGET_GCFF_2000_S = 1.0  # seconds per frame


def crowd_frame(n: int, rng: np.random.Generator) -> Frame:
    """``n`` people in a square hall: groups of 2-6 in circles, walkers anywhere."""
    side = math.sqrt(n / DENSITY_PER_M2)
    walkers = int(round(WALKER_SHARE * n))
    position, yaw = [], []
    centres: list[np.ndarray] = []
    radii: list[float] = []
    standing = n - walkers
    while standing > 0:
        size = int(min(rng.integers(2, 7), standing))
        radius = 0.45 + 0.1 * size
        for _ in range(1000):  # a free spot; else the group stands where it lands
            centre = rng.uniform(radius, side - radius, 2)
            if all(
                np.hypot(*(centre - c)) >= radius + r + GROUP_GAP_M
                for c, r in zip(centres, radii, strict=True)
            ):
                break
        members, facing = circle(
            rng,
            centre=centre,
            size=size,
            radius=radius,
            angle_sd=0.2,
            position_sd=0.08,
            yaw_sd=0.3,
        )
        centres.append(centre)
        radii.append(radius)
        position += members
        yaw += facing
        standing -= size
    position = np.concatenate([np.asarray(position), rng.uniform(0, side, (walkers, 2))])
    yaw = np.concatenate([wrap_yaws(yaw), rng.uniform(-math.pi, math.pi, walkers)])
    order = rng.permutation(n)  # groups' members are not neighbours in row order
    return Frame(ids=np.arange(1, n + 1), position=position[order], yaw=yaw[order])


def every_pair(model: Reform, compiled, frame: Frame) -> tuple[tuple[int, ...], ...]:
    """The baseline: every pair's features and label, then reconstruction."""
    n = frame.n_people
    x = batch_pair_features(frame.position[None], frame.yaw[None], features=model.features_)[0]
    together = compiled.predict(x)
    i, j = pair_indices(n)
    labels = graph_greedy_labels(n, i[together], j[together], variant=model.reconstruction)
    return _ids(partition_from_labels(labels, range(n)), frame)


def whole_matrix(model: Reform, compiled, frame: Frame) -> tuple[tuple[int, ...], ...]:
    """Every pair's label, then the whole-matrix reference reconstruction."""
    n = frame.n_people
    x = batch_pair_features(frame.position[None], frame.yaw[None], features=model.features_)[0]
    rows = greedy_reconstruction(relation_matrix(compiled.predict(x), n))
    return _ids(rows, frame)


def _ids(rows, frame: Frame) -> tuple[tuple[int, ...], ...]:
    return tuple(sorted((tuple(int(frame.ids[r]) for r in g) for g in rows), key=min))


def peak_mb(call) -> float:
    """Megabytes allocated at the peak of ``call()``, traced."""
    tracemalloc.start()
    try:
        call()
        return tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()


def growth(sizes: list[int], values: list[float]) -> float:
    """The exponent k of ``value ~ n^k`` between the smallest and the largest size."""
    return math.log(values[-1] / values[0]) / math.log(sizes[-1] / sizes[0])


def main() -> None:
    parser = BenchmarkParser(__doc__)
    parser.add_sized(
        "--sizes", default=SIZES, quick=QUICK_SIZES, help="people per frame", nargs="+"
    )
    args = parser.parse_args()
    sizes = sorted(args.sizes)
    train, source = training_frames(args.quick)
    model = Reform().fit(train).compile()  # a long run's pace from the first frame
    compiled = compile_classifier(model.classifier_, threshold=model.threshold)
    print(
        f"Crowds of {', '.join(map(str, sizes))} people (seed {SEED}); REFORM trained on {source}."
    )
    print(
        f"{'people':>6} {'REFORM ms':>10} {'every pair ms':>14} {'ratio':>7} {'peak MB':>8} "
        f"{'every pair MB':>14} {'whole matrix ms':>16} {'GCFF ms':>9}  groups"
    )
    times, peaks, gcff_times, differ = [], [], [], []
    for n in sizes:
        count = QUICK_FRAMES if args.quick else (5 if n >= 2000 else FRAMES)
        seeds = np.random.SeedSequence(SEED, spawn_key=(n,)).spawn(count)
        frames = [crowd_frame(n, np.random.default_rng(s)) for s in seeds]
        model.predict(frames[:1])  # warm-up
        ours = timed_each(lambda f: model.predict([f])[0], frames)
        predicted = [model.predict([f])[0] for f in frames]
        base = timed_each(lambda f: every_pair(model, compiled, f), frames)
        expected = [every_pair(model, compiled, f) for f in frames]
        same = predicted == expected
        whole = "-"
        if n <= WHOLE_MATRIX_PEOPLE and (n == sizes[0] or not args.quick):
            reference = timed_each(lambda f: whole_matrix(model, compiled, f), frames[:1])
            same = same and reference.result == predicted[0]
            whole = f"{1e3 * reference.median:.1f}"
        peak = peak_mb(lambda f=frames[0]: model.predict([f]))
        base_peak = peak_mb(lambda f=frames[0]: every_pair(model, compiled, f))
        gcff = timed_each(lambda f: Gcff().predict([f]), frames[:GCFF_FRAMES])
        times.append(ours.median)
        peaks.append(peak)
        gcff_times.append(gcff.median)
        if not same:
            differ.append(n)
        print(
            f"{n:>6} {1e3 * ours.median:>10.1f} {1e3 * base.median:>14.1f} "
            f"{base.median / ours.median:>6.1f}x {peak:>8.1f} {base_peak:>14.1f} {whole:>16} "
            f"{1e3 * gcff.median:>9.1f}  {'same' if same else 'DIFFERENT'}"
        )
    print(
        f"growth from {sizes[0]} to {sizes[-1]} people: REFORM time n^{growth(sizes, times):.2f}, "
        f"memory n^{growth(sizes, peaks):.2f}; GCFF time n^{growth(sizes, gcff_times):.2f}"
    )
    verdicts = []
    for n, limit in TARGETS_MS.items():
        if n in sizes:
            ms = 1e3 * times[sizes.index(n)]
            verdicts.append(f"{n:,} people {ms:.1f} ms (<= {limit:g}: {_met(ms <= limit)})")
    verdicts.append(
        f"peak {max(peaks):.1f} MB (< {TARGET_PEAK_MB:g}: {_met(max(peaks) < TARGET_PEAK_MB)})"
    )
    if 2000 in sizes:
        seconds = gcff_times[sizes.index(2000)]
        verdicts.append(
            f"GCFF at 2,000 {seconds:.2f} s (<= {TARGET_GCFF_2000_S:g}: "
            f"{_met(seconds <= TARGET_GCFF_2000_S)})"
        )
    print(f"Targets: {'; '.join(verdicts)}")
    if differ:
        raise SystemExit(f"REFORM's groups differ from the baseline's at {differ} people")


def _met(ok: bool) -> str:
    return "met" if ok else "MISSED"


if __name__ == "__main__":
    start = time.perf_counter()
    main()
    print(f"({time.perf_counter() - start:.0f} s)")
