"""DANTE's speed: per-frame time at 6, 18 and 200 people, beside GCFF's.

Times ``predict`` of a DANTE (the catalogue's architecture, trained for a few epochs on
circle scenes first: the weights do not change the network's cost, but trained affinities give
the clustering its real work) on one frame, and GCFF (``gcff``, the field's reference detector,
measured in the same run on the same scenes) as the baseline: the ratio is DANTE's time over
GCFF's. DANTE scores every ordered pair against everyone else, so its cost grows with the cube
of the people. Scenes are conversational circles of 1-5 people on a grid 3.5 m apart (seeded).
Every answer is checked to be a partition of its frame, and the same groups when the people are
listed in reverse order. Torch runs on one thread, as DANTE does while predicting.

Run: ``python benchmarks/bench_dante.py [--repeats 3] [--quick]`` (``--quick``: one scene per
size, one timed run, one training epoch, 50 people for 200). Needs the extra reform-sim[dante].
"""

from __future__ import annotations

import math
import statistics

import numpy as np
from circles import crowd
from timing import BenchmarkParser, timed

from reform import Frame, make_detector, run_detector
from reform.dante import Dante

BASELINE = "gcff"
SIZES = (6, 18, 200)  # people per frame
QUICK_SIZES = (6, 18, 50)  # people per frame with --quick (200 takes a minute on a busy machine)
SEED = 20200714
GRID_SPACING_M = 3.5  # metres between circle centres
SCENES = 3  # scenes per size below 200 people (1 of 200)
TRAINING_FRAMES = 40  # circle scenes of 6 to 18 people the model is trained on
EPOCHS = 5  # training epochs (1 with --quick)


def scene(n: int, rng: np.random.Generator) -> Frame:
    """``n`` people in circles of 1-5 on a grid, as one frame (ground truth: the circles)."""
    side = math.ceil(math.sqrt(n / 3)) + 1
    sizes: list[int] = []

    def draw() -> int:
        sizes.append(int(rng.integers(1, 6)))
        return sizes[-1]

    position, yaw = crowd(
        rng,
        n,
        draw_size=draw,
        centre=lambda k: GRID_SPACING_M * np.array([k % side, k // side], dtype=float),
        radius_per_person_m=0.12,
        angle_sd=0.15,
        position_sd=0.05,
        yaw_sd=0.2,
    )
    bounds = np.minimum(np.cumsum([0, *sizes]), n)  # the last circle is cut to who is left
    ids = np.arange(1, n + 1)
    groups = tuple(
        tuple(int(i) for i in ids[a:b]) for a, b in zip(bounds[:-1], bounds[1:], strict=True)
    )
    return Frame(ids=ids, position=position, yaw=yaw, groups=tuple(g for g in groups if len(g) > 1))


def groups(partition) -> set[frozenset[int]]:
    return {frozenset(int(m) for m in g) for g in partition}


def per_frame_seconds(name: str, detector, scenes: list[Frame], repeats: int) -> float:
    """Median over scenes of the median of ``repeats`` timed predictions of one frame."""
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
    parser = BenchmarkParser(__doc__, repeats=3, quick_repeats=1)
    parser.add_sized(
        "--sizes", default=SIZES, quick=QUICK_SIZES, nargs="+", help="people per frame"
    )
    args = parser.parse_args()
    rng = np.random.default_rng(SEED)
    training = [scene(int(rng.integers(6, 19)), rng) for _ in range(TRAINING_FRAMES)]
    dante = Dante(
        epochs=1 if args.quick else EPOCHS, learning_rate=1e-3, batch_size=512, random_state=0
    ).fit(training[:8] if args.quick else training)
    gcff = make_detector(BASELINE)
    print(f"Per-frame time of DANTE (median over scenes), beside {BASELINE}")
    print(f"{'people':>6}  {'dante':>12}  {BASELINE:>12}  {'ratio':>9}")
    for n in args.sizes:
        count = 1 if args.quick or n >= 200 else SCENES
        scenes = [scene(n, rng) for _ in range(count)]
        seconds = per_frame_seconds("dante", dante, scenes, args.repeats)
        baseline = per_frame_seconds(BASELINE, gcff, scenes, args.repeats)
        print(
            f"{n:>6}  {seconds * 1e3:>9.2f} ms  {baseline * 1e3:>9.3f} ms  "
            f"{seconds / baseline:>8.1f}x"
        )


if __name__ == "__main__":
    main()
