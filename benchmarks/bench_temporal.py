"""Speed of reform.temporal.evaluate_events on a 35-minute, 7-person sequence at 10 Hz, beside the
frame metrics (reform.evaluate) on the same frames and predictions.

The truth moves one person every 2 to 6 seconds (to another group, or alone); the "detection" is
the truth seen late (each change 0 to 1.5 s after it happens) with flicker (now and then one
person alone for 0.1 to 0.3 s), drawn from a seeded generator. Both scorers run on the same
21,000 frames; the goal is the temporal metrics in under a second. Checked first: the truth
scored against itself gives recall 1, precision 1, latency 0, no false events and no switches.
Prints the medians and their ratio.

    python benchmarks/bench_temporal.py [--repeats 5] [--quick]

``--quick``: 2 minutes (1,200 frames), one repeat.
"""

from __future__ import annotations

import numpy as np
from timing import BenchmarkParser, median_seconds

from reform import Frame, evaluate
from reform.temporal import evaluate_events

SEED = 30
PEOPLE = 7
RATE_HZ = 10.0  # frames per second
CHANGE_EVERY_S = (2.0, 6.0)  # seconds between two changes of the truth, uniform
LATE_S = (0.0, 1.5)  # seconds the detection lags a change, uniform
FLICKER_PER_S = 0.04  # flickers per second: one person detached for a moment
FLICKER_FRAMES = (1, 3)  # how long a flicker lasts, frames
TOLERANCE_S = 1.0  # matching window, seconds
GOAL_S = 1.0  # seconds for the temporal metrics over the full sequence


def partition(labels: np.ndarray) -> tuple[tuple[int, ...], ...]:
    """The full partition (singletons included) of people 0..n-1 given one label each."""
    groups: dict[int, list[int]] = {}
    for person, label in enumerate(labels.tolist()):
        groups.setdefault(label, []).append(person)
    return tuple(tuple(g) for g in groups.values())


def scene(minutes: float, rng: np.random.Generator) -> tuple[list[Frame], list]:
    """True frames and the noisy detection's partitions, one per frame."""
    n = int(round(minutes * 60.0 * RATE_HZ))
    truth = np.zeros((n, PEOPLE), dtype=np.int64)
    labels = np.array([0, 0, 0, 1, 1, 2, 3])
    detected = truth.copy()
    lag_until = -1
    stale = labels.copy()
    next_change = int(rng.uniform(*CHANGE_EVERY_S) * RATE_HZ)
    for k in range(n):
        if k == next_change:
            stale = labels.copy()
            person = int(rng.integers(PEOPLE))
            labels = labels.copy()
            labels[person] = int(rng.integers(PEOPLE + 1))  # a label of nobody: alone
            lag_until = k + int(rng.uniform(*LATE_S) * RATE_HZ)
            next_change = k + int(rng.uniform(*CHANGE_EVERY_S) * RATE_HZ)
        truth[k] = labels
        detected[k] = stale if k < lag_until else labels
    flickers = np.flatnonzero(rng.random(n) < FLICKER_PER_S / RATE_HZ)
    for k in flickers.tolist():
        length = int(rng.integers(FLICKER_FRAMES[0], FLICKER_FRAMES[1] + 1))
        detected[k : k + length, int(rng.integers(PEOPLE))] = PEOPLE + 10  # alone
    ids = np.arange(PEOPLE)
    position = np.c_[np.arange(PEOPLE, dtype=float), np.zeros(PEOPLE)]
    frames = [
        Frame(
            ids=ids,
            position=position,
            yaw=np.zeros(PEOPLE),
            groups=partition(truth[k]),
            time=k / RATE_HZ,
            sequence="party",
        )
        for k in range(n)
    ]
    return frames, [partition(detected[k]) for k in range(n)]


def main() -> None:
    parser = BenchmarkParser(__doc__, repeats=5)
    parser.add_sized("--minutes", default=35.0, quick=2.0, type=float, help="sequence length")
    args = parser.parse_args()
    frames, predictions = scene(args.minutes, np.random.default_rng(SEED))

    perfect = evaluate_events(frames, [f.partition() for f in frames], tolerance_s=TOLERANCE_S)
    found = (
        perfect.recall,
        perfect.precision,
        perfect.latency_median_s,
        perfect.false_events_per_minute,
        perfect.identity_switches,
    )
    if found != (1.0, 1.0, 0.0, 0.0, 0):
        raise SystemExit(f"the truth against itself scores {found}, expected (1, 1, 0, 0, 0)")

    temporal = median_seconds(
        lambda: evaluate_events(frames, predictions, tolerance_s=TOLERANCE_S).to_json(),
        args.repeats,
    )
    framewise = median_seconds(
        lambda: evaluate(frames, predictions).to_json(detector="noisy", dataset="party"),
        args.repeats,
    )
    result = evaluate_events(frames, predictions, tolerance_s=TOLERANCE_S)
    print(
        f"sequence: {len(frames):,} frames ({args.minutes:g} min, {PEOPLE} people, "
        f"{RATE_HZ:g} Hz), {len(result.true_events)} true events, "
        f"{len(result.detected_events)} detected; recall {result.recall:.2f}, precision "
        f"{result.precision:.2f}, median latency {result.latency_median_s:.2f} s, "
        f"{result.false_events_per_minute:.1f} false events/min, "
        f"{result.identity_switches} identity switches"
    )
    print(
        f"evaluate_events +JSON {temporal * 1e3:8.1f} ms   evaluate (frame P/R/F1) +JSON "
        f"{framewise * 1e3:8.1f} ms   ratio {temporal / framewise:.2f}x (median of {args.repeats})"
    )
    verdict = "met" if temporal < GOAL_S else "NOT met"
    print(f"goal: temporal metrics under {GOAL_S:g} s: {verdict} ({temporal:.3f} s)")


if __name__ == "__main__":
    main()
