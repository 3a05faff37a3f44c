"""Where a stress-test point spends its time: one test episode of the SALSA-like party.

For one simulated episode (mingle, 18 guests, 600 s at 0.5 Hz = 300 frames) this times, as
medians over repeats: simulating it, perturbing it (position and yaw noise and dropouts,
``reform.perturb``), predicting with each detector, scoring (``reform.evaluate``) and the
two-stage bootstrap (1000 resamples, ``reform.bootstrap``). The baseline, measured in the same
run, is ``reform.evaluate`` on the same frames: every figure is printed as a ratio to it, so the
table reads the same on a busy or an idle machine. Also prints the CPU seconds of the small grid
end to end (``run_stress("small", jobs=1)``).

    python benchmarks/bench_stress.py [--repeats 5] [--quick]

``--quick``: the detectors trained on one minute, a one-minute test episode, one repeat, and a
tiny grid (two levels per axis, one 20 s episode per point) instead of the small one.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
from timing import BenchmarkParser, median_seconds

from reform import evaluate
from reform.bootstrap import bootstrap_weights, frame_intervals
from reform.perturb import Perturbation
from sim.episode import simulate_episode
from sim.experiments.stress import DETECTORS, GRIDS, run_stress, train_detectors, training_frames

EPISODE_S = 600.0  # seconds of the timed test episode
TRAINING_S = 300.0  # seconds of the training episode
QUICK_EPISODE_S = 60.0  # seconds of the timed test episode with --quick
QUICK_TRAINING_S = 60.0  # seconds of the training episode with --quick
# Two levels per axis, one short episode per point: every axis's code path in a few seconds.
QUICK_GRID = dataclasses.replace(
    GRIDS["small"],
    position_noise_m=(0.0, 0.5),
    orientation_noise_deg=(0.0, 60.0),
    dropout=(0.0, 0.5),
    people=(6, 12),
    seeds=1,
    duration_s=20.0,
    train_duration_s=40.0,
    resamples=50,
    gcff_tuning_frames=20,
)


def _median(function, repeats: int) -> float:
    """Median CPU seconds of ``repeats`` calls."""
    return median_seconds(function, repeats, clock=time.process_time)


def main() -> None:
    args = BenchmarkParser(__doc__, repeats=5).parse_args()
    episode_s = QUICK_EPISODE_S if args.quick else EPISODE_S
    training_s = QUICK_TRAINING_S if args.quick else TRAINING_S
    grid_name, grid = ("quick", QUICK_GRID) if args.quick else ("small", GRIDS["small"])

    print("training the detectors on a small synthetic set ...", flush=True)
    detectors = train_detectors(
        training_frames(seed=0, episodes=1, duration=training_s, rate=0.5, jobs=1),
        grid=QUICK_GRID if args.quick else None,
        jobs=1,
    )

    def simulate():
        return simulate_episode("mingle", seed=11, duration=episode_s, rate=0.5).dataset.frames

    frames = simulate()
    perturbation = Perturbation(position_noise=0.2, yaw_noise=0.3, dropout=0.2)
    predictions = detectors["bagged-trees"].predict(frames)
    evaluation = evaluate(frames, predictions)
    weights = bootstrap_weights(evaluation.sequence, rng=np.random.default_rng(0))
    scores = evaluation.at("2/3")

    rows = [
        ("reform.evaluate (baseline)", _median(lambda: evaluate(frames, predictions), args.repeats))
    ]
    rows.append(("simulate the episode", _median(simulate, args.repeats)))
    rows.append(
        (
            "perturb every frame",
            _median(lambda: perturbation.apply_all(frames, np.random.default_rng(0)), args.repeats),
        )
    )
    for name in DETECTORS:
        rows.append(
            (f"predict: {name}", _median(lambda d=detectors[name]: d.predict(frames), args.repeats))
        )
    rows.append(
        (
            "bootstrap weights (1000 resamples)",
            _median(
                lambda: bootstrap_weights(evaluation.sequence, rng=np.random.default_rng(0)),
                args.repeats,
            ),
        )
    )
    rows.append(
        (
            "bootstrap intervals of one detector",
            _median(
                lambda: frame_intervals(
                    scores.frame_precision, scores.frame_recall, weights=weights, sequences=1
                ),
                args.repeats,
            ),
        )
    )
    baseline = rows[0][1]
    print(
        f"\none episode: {len(frames)} frames of {frames[0].n_people} people; "
        f"CPU seconds, median of {args.repeats}"
    )
    width = max(len(name) for name, _ in rows)
    for name, seconds in rows:
        print(f"  {name:<{width}}  {seconds:8.4f} s  {seconds / baseline:8.1f} x baseline")

    start = time.perf_counter()
    cpu = time.process_time()
    results = run_stress(grid, seed=0, jobs=1)
    scored = sum(p.frames for a in results.axes for p in a.points)
    print(
        f"\nrun_stress({grid_name!r}, jobs=1): {time.perf_counter() - start:.1f} s wall, "
        f"{time.process_time() - cpu:.1f} s CPU, {scored} frames scored per detector"
    )


if __name__ == "__main__":
    main()
