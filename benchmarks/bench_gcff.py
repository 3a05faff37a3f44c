"""GCFF speed: per-frame time for 6, 18, 50 and 200 people, beside a plain-loop baseline.

The baseline, measured in the same run on the same scenes, is the straightforward
implementation of the same algorithm: costs in Python loops over (group, person, person) as the
reference ``gc.m`` writes them, alpha-moves tried one at a time with a loop over labels. Both
must return the same labels (checked). Scenes are conversational circles of 1-5 people laid
out on a grid 3.5 m apart (seeded).

Run: ``python benchmarks/bench_gcff.py [--repeats 7] [--quick]`` (``--quick``: two scenes per
size, one of 200 people, best of 2). Targets: at most 1 ms per frame for 18 people; no slower
than the baseline at any size (issue 31), a speed-up of at least 1 everywhere.
"""

from __future__ import annotations

import math
import statistics

import numpy as np
from circles import crowd
from timing import BenchmarkParser, timed

from reform.gcff import MAX_REFITS, VISIBILITY_BASE, VISIBILITY_COSINE, energy, gcff_labels

SIZES = (6, 18, 50, 200)  # people per frame
SEED = 20150601
STRIDE_CM = 70.0  # centimetres (the reference code's setting)
MDL_CM2 = 10_000.0  # square centimetres
GRID_SPACING_M = 3.5  # metres between circle centres
TARGET_MS_18 = 1.0  # milliseconds per frame for 18 people
SCENES = 15  # scenes per size below 200 people (3 of 200)
QUICK_SCENES = 2  # scenes per size below 200 people with --quick (1 of 200)


def scene(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``n`` people (positions in metres, yaws in radians) in circles of 1-5, on a grid."""
    side = math.ceil(math.sqrt(n / 3)) + 1
    return crowd(
        rng,
        n,
        draw_size=lambda: rng.integers(1, 6),
        centre=lambda k: GRID_SPACING_M * np.array([k % side, k // side], dtype=float),
        radius_per_person_m=0.12,
        angle_sd=0.15,
        position_sd=0.05,
        yaw_sd=0.2,
    )


def loop_gcff(position_m: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """The same algorithm written plainly, with Python loops (the baseline)."""
    pos = [(float(x) * 100.0, float(y) * 100.0) for x, y in position_m]
    n = len(pos)
    pts = [
        (x + math.cos(t) * STRIDE_CM, y + math.sin(t) * STRIDE_CM)
        for (x, y), t in zip(pos, yaw.tolist(), strict=True)
    ]
    labels = list(range(n))
    for _ in range(MAX_REFITS):
        k = max(labels) + 1
        costs = [[0.0] * k for _ in range(n)]
        for g in range(k):
            members = [i for i in range(n) if labels[i] == g]
            mx = sum(pts[i][0] for i in members) / len(members)
            my = sum(pts[i][1] for i in members) / len(members)
            for i in range(n):
                costs[i][g] = (pts[i][0] - mx) ** 2 + (pts[i][1] - my) ** 2
            near = [i for i in range(n) if costs[i][g] < MDL_CM2]
            v = {i: (pos[i][0] - mx, pos[i][1] - my) for i in near}
            r = {i: math.hypot(*v[i]) for i in near}
            for j in near:
                for i in near:
                    if r[i] > r[j]:
                        cos = (v[i][0] * v[j][0] + v[i][1] * v[j][1]) / (r[i] * r[j])
                        if cos > VISIBILITY_COSINE:
                            costs[i][g] += VISIBILITY_BASE ** min(cos * r[i] / r[j], 100.0)
        unary = np.array(costs)
        current = energy(unary, labels, label_cost=MDL_CM2)
        alpha, stale = 0, 0
        new_labels = list(labels)
        while stale < k:
            d = [costs[i][alpha] - costs[i][new_labels[i]] for i in range(n)]
            moved = list(new_labels)
            for label in set(new_labels) - {alpha}:
                members = [i for i in range(n) if new_labels[i] == label]
                option_a = sum(d[i] for i in members if d[i] < 0) + MDL_CM2
                option_b = sum(d[i] for i in members)
                for i in members:
                    if option_b <= option_a or d[i] <= 0:
                        moved[i] = alpha
            candidate = energy(unary, moved, label_cost=MDL_CM2)
            if candidate <= current and moved != new_labels:
                stale = 0 if candidate < current else stale + 1
                new_labels, current = moved, candidate
            else:
                stale += 1
            alpha = (alpha + 1) % k
        renumber = {label: r for r, label in enumerate(sorted(set(new_labels)))}
        new_labels = [renumber[label] for label in new_labels]
        if new_labels == labels:
            break
        labels = new_labels
    return np.array(labels)


def per_frame_seconds(fn, scenes, repeats: int) -> float:
    """Median over scenes of the best of ``repeats`` runs, seconds per frame."""
    return statistics.median(timed(fn, repeats, args=people).best for people in scenes)


def main() -> None:
    args = BenchmarkParser(__doc__, repeats=7, quick_repeats=2).parse_args()
    rng = np.random.default_rng(SEED)

    def vectorised(position, yaw):
        return gcff_labels(position, yaw, stride=STRIDE_CM / 100.0, mdl=MDL_CM2 / 1e4)

    print(f"GCFF per-frame time, stride {STRIDE_CM:g} cm, mdl {MDL_CM2:g} cm² (medians)")
    print(f"{'people':>6}  {'reform.gcff':>12}  {'loop baseline':>14}  {'speed-up':>8}  scenes")
    slower = []
    for n in SIZES:
        count = (QUICK_SCENES if args.quick else SCENES) if n < 200 else (1 if args.quick else 3)
        scenes = [scene(n, rng) for _ in range(count)]
        for position, yaw in scenes:
            fast, slow = vectorised(position, yaw), loop_gcff(position, yaw)
            if not np.array_equal(fast, slow):
                raise SystemExit(f"{n} people: vectorised and loop labels differ")
        repeats = args.repeats
        fast = per_frame_seconds(vectorised, scenes, repeats)
        slow = per_frame_seconds(loop_gcff, scenes, 1 if n >= 200 else max(1, repeats // 2))
        print(
            f"{n:>6}  {fast * 1e3:>9.3f} ms  {slow * 1e3:>11.3f} ms  {slow / fast:>7.1f}x  {count}"
        )
        if n == 18:
            verdict = "meets" if fast * 1e3 <= TARGET_MS_18 else "MISSES"
            print(f"{'':>6}  18 people: {verdict} the target of {TARGET_MS_18:g} ms per frame")
        if fast > slow:
            slower.append(n)
    if slower:
        print(f"MISSES: slower than the loop baseline at {', '.join(map(str, slower))} people")
    else:
        print("meets: no slower than the loop baseline at any size")


if __name__ == "__main__":
    main()
