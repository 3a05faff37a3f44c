"""The field's detectors' speed: per-frame time at 6, 18 and 200 people (crowds of 200 to 2,000
with --crowd), beside GCFF's.

Times ``predict`` of each catalogued field detector (proximity, dominant-sets, gtcg, hvff,
hvff-multiscale) with its stated settings on one frame, and GCFF (``gcff``, the field's
reference detector, measured in the same run on the same scenes) as the baseline: the ratio is
the detector's time over GCFF's. Scenes are conversational circles of 1-5 people on a grid
3.5 m apart (seeded), as ``bench_gcff``'s. Every answer is checked to be a partition of its
frame, and to be the same groups when the people are listed in reverse order.

Run: ``python benchmarks/bench_field_detectors.py [--repeats 5] [--quick]`` (``--quick``: one
scene per size, one timed run).

Crowds: ``python benchmarks/bench_field_detectors.py --crowd [--sizes 200 500 1000 2000]``
(``--quick``: 200 and 400 people) times each detector and GCFF on one frame of each size (the
same scenes, seeded per size): one timed run, the median of three where it took under
`QUICK_RUN_S`. Its groups are checked: a partition; the same groups for the people in reverse
order, where the run took under `REVERSE_CHECK_S`; for HVFF and multi-scale HVFF, the
part-by-part reading gives the dense whole-frame accumulator's groups, up to
`WHOLE_FRAME_CHECK_PEOPLE` people. Then each one's growth exponent: the slope of log time on
log people, fitted over every size. Dominant sets and GTCG keep their whole-frame method on
crowds (their modules say why): minutes at 2,000 people.
"""

from __future__ import annotations

import math
import statistics

import numpy as np
from circles import crowd
from timing import BenchmarkParser, timed

import reform.hough
from reform import Frame, make_detector, run_detector

DETECTORS = ("proximity", "dominant-sets", "gtcg", "hvff", "hvff-multiscale")
BASELINE = "gcff"
SIZES = (6, 18, 200)  # people per frame
SEED = 20110829
GRID_SPACING_M = 3.5  # metres between circle centres
SCENES = 5  # scenes per size (2 of 200 people)
QUICK_SCENES = 1  # scenes per size with --quick
CROWD_SIZES = (200, 500, 1000, 2000)  # people per frame with --crowd
QUICK_CROWD_SIZES = (200, 400)
QUICK_RUN_S = 1.0  # seconds: a crowd run shorter than this is timed three times (median)
REVERSE_CHECK_S = 10.0  # seconds: a crowd run slower than this is not run again reversed
WHOLE_FRAME_CHECK_PEOPLE = 500  # HVFF's crowd reading checked against the dense one up to here
HOUGH = ("hvff", "hvff-multiscale")


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


def reverse(frame: Frame) -> Frame:
    """``frame`` with its people listed in reverse order."""
    order = np.arange(frame.n_people)[::-1]
    return Frame(ids=frame.ids[order], position=frame.position[order], yaw=frame.yaw[order])


def per_frame_seconds(name: str, scenes: list[Frame], repeats: int) -> float:
    """Median over scenes of the median of ``repeats`` timed predictions of one frame."""
    detector = make_detector(name)
    for frame in scenes:  # checked once, outside the timing: a partition, and order-free
        (answer,) = run_detector(name, detector, [frame])
        (again,) = run_detector(name, detector, [reverse(frame)])
        if groups(answer) != groups(again):
            raise SystemExit(f"{name}: other groups for the people listed in reverse order")
    return statistics.median(
        timed(detector.predict, repeats, args=([frame],)).median for frame in scenes
    )


def hough_reading(name: str, frame: Frame, *, crowd_people: int) -> tuple:
    """HVFF's (or multi-scale HVFF's) groups with ``reform.hough.CROWD_PEOPLE`` set to
    ``crowd_people`` (``frame.n_people``: the dense accumulator; 0: the part-by-part reading)."""
    limit = reform.hough.CROWD_PEOPLE
    reform.hough.CROWD_PEOPLE = crowd_people
    try:
        return make_detector(name).predict([frame])[0]
    finally:
        reform.hough.CROWD_PEOPLE = limit


def crowd_seconds(name: str, frame: Frame) -> float:
    """Seconds of one timed prediction of ``frame``, whose groups are then checked (see the
    module docstring)."""
    detector = make_detector(name)
    timing = timed(detector.predict, 1, args=([frame],))
    if timing.median < QUICK_RUN_S:  # a short run is noisy: the median of three
        timing = timed(detector.predict, 3, args=([frame],))
    (answer,) = timing.result
    members = sorted(int(m) for g in answer for m in g)
    if members != sorted(frame.ids.tolist()):
        raise SystemExit(f"{name}: not a partition of the {frame.n_people} people")
    if timing.median < REVERSE_CHECK_S:
        (again,) = run_detector(name, detector, [reverse(frame)])
        if groups(answer) != groups(again):
            raise SystemExit(f"{name}: other groups for the people listed in reverse order")
    if name in HOUGH and frame.n_people <= WHOLE_FRAME_CHECK_PEOPLE:
        dense = hough_reading(name, frame, crowd_people=frame.n_people)
        if dense != hough_reading(name, frame, crowd_people=0):
            raise SystemExit(f"{name}: the crowd reading differs from the dense one")
    return timing.median


def growth(sizes: list[int], seconds: list[float]) -> float:
    """The exponent k of ``seconds ~ people^k``: least squares on log-log, every size."""
    return float(np.polyfit(np.log(sizes), np.log(seconds), 1)[0])


def run_crowd(sizes: list[int]) -> None:
    """The ``--crowd`` run: each detector's per-frame time beside GCFF's, and its growth."""
    print(f"Per-frame time on crowds (one frame a size, seed {SEED}), beside {BASELINE}")
    print(f"{'detector':>16}  {'people':>6}  {'time':>12}  {BASELINE:>12}  {'ratio':>8}")
    times: dict[str, list[float]] = {name: [] for name in (BASELINE, *DETECTORS)}
    for n in sizes:
        frame = scene(n, np.random.default_rng(np.random.SeedSequence(SEED, spawn_key=(n,))))
        baseline = crowd_seconds(BASELINE, frame)
        times[BASELINE].append(baseline)
        for name in DETECTORS:
            seconds = crowd_seconds(name, frame)
            times[name].append(seconds)
            print(
                f"{name:>16}  {n:>6}  {seconds * 1e3:>9.1f} ms  {baseline * 1e3:>9.1f} ms  "
                f"{seconds / baseline:>7.2f}x",
                flush=True,
            )
    print(f"Growth exponent of the time from {sizes[0]} to {sizes[-1]} people (log-log fit):")
    for name, seconds in times.items():
        print(f"{name:>16}  n^{growth(sizes, seconds):.2f}")


def main() -> None:
    parser = BenchmarkParser(__doc__, repeats=5, quick_repeats=1)
    parser.add_argument(
        "--crowd", action="store_true", help="time crowds (--sizes) instead of 6, 18 and 200"
    )
    parser.add_sized(
        "--sizes",
        default=CROWD_SIZES,
        quick=QUICK_CROWD_SIZES,
        help="people per frame with --crowd",
        nargs="+",
    )
    args = parser.parse_args()
    if args.crowd:
        if len(set(args.sizes)) < 2:
            parser.error(f"--sizes needs two sizes or more to fit a growth, got {args.sizes}")
        run_crowd(sorted(set(args.sizes)))
        return
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
