"""The field's detectors' speed: per-frame time at 6, 18 and 200 people, beside GCFF's.

Times ``predict`` of each catalogued field detector (proximity, dominant-sets, gtcg, hvff,
hvff-multiscale) with its stated settings on one frame, and GCFF (``gcff``, the field's
reference detector, measured in the same run on the same scenes) as the baseline: the ratio is
the detector's time over GCFF's. Scenes are conversational circles of 1-5 people on a grid
3.5 m apart (seeded), as ``bench_gcff``'s. Every answer is checked to be a partition of its
frame, and to be the same groups when the people are listed in reverse order.

Run: ``python benchmarks/bench_field_detectors.py [--repeats 5] [--quick]`` (``--quick``: one
scene per size, one timed run).
"""

from __future__ import annotations

import math
import statistics

import numpy as np
from circles import crowd
from timing import BenchmarkParser, timed

from reform import Frame, make_detector, run_detector

DETECTORS = ("proximity", "dominant-sets", "gtcg", "hvff", "hvff-multiscale")
BASELINE = "gcff"
SIZES = (6, 18, 200)  # people per frame
SEED = 20110829
GRID_SPACING_M = 3.5  # metres between circle centres
SCENES = 5  # scenes per size (2 of 200 people)
QUICK_SCENES = 1  # scenes per size with --quick


def scene(n: int, rng: np.random.Generator) -> Frame:
    """``n`` people in circles of 1-5 on a grid, as one frame."""
    side = math.ceil(math.sqrt(n / 3)) + 1
    position, yaw = crowd(
        rng,
        n,
        draw_size=lambda: rng.integers(1, 6),
        centre=lambda k: GRID_SPACING_M * np.array([k % side, k // side], dtype=float),
        radius_per_person_m=0.12,
        angle_sd=0.15,
        position_sd=0.05,
        yaw_sd=0.2,
    )
    return Frame(ids=np.arange(1, n + 1), position=position, yaw=yaw)


def groups(partition) -> set[frozenset[int]]:
    return {frozenset(int(m) for m in g) for g in partition}


def per_frame_seconds(name: str, scenes: list[Frame], repeats: int) -> float:
    """Median over scenes of the median of ``repeats`` timed predictions of one frame."""
    detector = make_detector(name)
    for frame in scenes:  # checked once, outside the timing: a partition, and order-free
        (answer,) = run_detector(name, detector, [frame])
        order = np.arange(frame.n_people)[::-1]
        reverse = Frame(ids=frame.ids[order], position=frame.position[order], yaw=frame.yaw[order])
        (again,) = run_detector(name, detector, [reverse])
        if groups(answer) != groups(again):
            raise SystemExit(f"{name}: other groups for the people listed in reverse order")
    return statistics.median(
        timed(detector.predict, repeats, args=([frame],)).median for frame in scenes
    )


def main() -> None:
    args = BenchmarkParser(__doc__, repeats=5, quick_repeats=1).parse_args()
    rng = np.random.default_rng(SEED)
    print(f"Per-frame time of the field's detectors (median over scenes), beside {BASELINE}")
    print(f"{'detector':>16}  {'people':>6}  {'time':>12}  {BASELINE:>12}  {'ratio':>8}")
    for n in SIZES:
        count = QUICK_SCENES if args.quick else (SCENES if n < 200 else 2)
        scenes = [scene(n, rng) for _ in range(count)]
        baseline = per_frame_seconds(BASELINE, scenes, args.repeats)
        for name in DETECTORS:
            seconds = per_frame_seconds(name, scenes, args.repeats)
            print(
                f"{name:>16}  {n:>6}  {seconds * 1e3:>9.3f} ms  {baseline * 1e3:>9.3f} ms  "
                f"{seconds / baseline:>7.2f}x"
            )


if __name__ == "__main__":
    main()
