"""Dataset generation speed: annotated frames per second end to end, serial and on every core.

The SALSA-like case of issue 6: ``mingle`` with 18 people, 2 Hz annotations, episodes of the
scenario's natural length (600 s, 1,200 frames). Measured in the same run:

* **stages** of one episode, serially, per annotated frame: making the scenario (its whole
  script is drawn), the poses (``sim.episode.episode_blocks``: the script sampled at 10 Hz, the
  motion kernel and MuJoCo's kinematics at 100 Hz, the ground-truth rule; the floor a dataset
  stands on), the Frames (``simulate_episode``: the same plus one validated `reform.Frame` per
  annotated instant), and the Parquet shard (``write_parquet``);
* **end to end**: ``generate_dataset`` (simulation, shards written atomically, the card) with one
  process, then with ``--jobs`` processes (joblib/loky, the pool warmed up first; the cold start
  is printed too), medians over ``--repeats`` runs; the ratio parallel / serial, the ratio
  serial / poses floor, and the time one million annotated frames would take.

Target (issue 6): one million annotated 18-person frames in <= 10 minutes on the 2-core machine.

Run: ``python benchmarks/bench_generate.py [--episodes 8] [--repeats 3] [--jobs 2] [--quick]``.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import scenarios
from reform.datasets import write_parquet
from sim.episode import episode_blocks, simulate_episode
from sim.generate import episode_seed, generate_dataset

SCENARIO = "mingle"
PEOPLE = 18
RATE_HZ = 2.0  # Hz, SALSA's annotation rate
SEED = 20200915
MILLION = 1_000_000  # annotated frames
TARGET_MINUTES = 10.0


def stages(episodes: int) -> dict[str, float]:
    """Seconds per annotated frame of each stage, medians over ``episodes`` episodes."""
    times: dict[str, list[float]] = {"scenario": [], "poses": [], "frames": [], "parquet": []}
    with tempfile.TemporaryDirectory() as scratch:
        for k in range(episodes):
            seed = episode_seed(SEED, k)
            start = time.perf_counter()
            made = scenarios.make(SCENARIO, seed=seed, people=PEOPLE)
            made_s = time.perf_counter() - start
            start = time.perf_counter()
            count = sum(len(b) for b in episode_blocks(made, rate=RATE_HZ))
            poses_s = time.perf_counter() - start
            start = time.perf_counter()
            episode = simulate_episode(made, rate=RATE_HZ)
            frames_s = time.perf_counter() - start
            start = time.perf_counter()
            write_parquet(episode.dataset, Path(scratch) / f"{k}.parquet")
            parquet_s = time.perf_counter() - start
            assert len(episode.dataset) == count
            times["scenario"].append(made_s / count)
            times["poses"].append(poses_s / count)
            times["frames"].append((frames_s - poses_s) / count)
            times["parquet"].append(parquet_s / count)
    return {name: statistics.median(values) for name, values in times.items()}


def end_to_end(episodes: int, n_jobs: int) -> tuple[float, int]:
    """(seconds, annotated frames) of one ``generate_dataset`` run into a fresh folder."""
    scratch = Path(tempfile.mkdtemp(prefix="bench-generate-"))
    try:
        report = generate_dataset(
            SCENARIO,
            episodes=episodes,
            seed=SEED,
            out_dir=scratch / "data",
            options={"people": PEOPLE},
            rate=RATE_HZ,
            n_jobs=n_jobs,
            progress=False,
        )
        return report.seconds, report.annotated_frames
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=8, help="episodes per timed run")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--jobs", type=int, default=2, help="processes of the parallel runs")
    parser.add_argument("--quick", action="store_true", help="4 episodes, 1 repeat")
    args = parser.parse_args()
    episodes = 4 if args.quick else args.episodes
    repeats = 1 if args.quick else args.repeats

    start = time.perf_counter()
    end_to_end(1, 1)  # the motion kernel compiled or loaded from numba's cache
    print(f"warm-up (motion kernel, imports) {time.perf_counter() - start:.2f} s")
    made = scenarios.make(SCENARIO, seed=SEED, people=PEOPLE)
    print(
        f"{SCENARIO}: {PEOPLE} people, {made.duration:g} s episodes at {RATE_HZ:g} Hz "
        f"({round(made.duration * RATE_HZ)} annotated frames each), {episodes} episodes per "
        f"run, median of {repeats}"
    )

    per_frame = stages(min(episodes, 4))
    total = sum(per_frame.values())
    print("\none episode, serially, per annotated frame:")
    for name, seconds in per_frame.items():
        print(f"  {name:<9} {seconds * 1e6:8.0f} us  {seconds / total:6.1%}")
    print(f"  {'total':<9} {total * 1e6:8.0f} us  ({1 / total:,.0f} frames/s)")

    start = time.perf_counter()
    cold_s, cold_frames = end_to_end(episodes, args.jobs)
    print(
        f"\ncold start of {args.jobs} workers included: {cold_frames / cold_s:,.0f} frames/s "
        f"({time.perf_counter() - start:.1f} s)"
    )
    serial = [end_to_end(episodes, 1) for _ in range(repeats)]
    parallel = [end_to_end(episodes, args.jobs) for _ in range(repeats)]
    frames = serial[0][1]
    serial_rate = frames / statistics.median(s for s, _ in serial)
    parallel_rate = frames / statistics.median(s for s, _ in parallel)
    floor_rate = 1.0 / per_frame["poses"]
    print("\nend to end (generate_dataset: simulate, write shards, card):")
    print(f"{'run':<22} {'frames/s':>10} {'ratio':>7}")
    print(f"{'poses floor (serial)':<22} {floor_rate:>10,.0f} {1.0:>7.2f}")
    print(f"{'serial':<22} {serial_rate:>10,.0f} {serial_rate / floor_rate:>7.2f}")
    print(
        f"{f'{args.jobs} processes':<22} {parallel_rate:>10,.0f} "
        f"{parallel_rate / floor_rate:>7.2f}  ({parallel_rate / serial_rate:.2f}x serial)"
    )
    minutes_serial = MILLION / serial_rate / 60.0
    minutes = MILLION / parallel_rate / 60.0
    verdict = "meets" if minutes <= TARGET_MINUTES else "misses"
    print(
        f"\none million annotated frames: {minutes:.1f} min with {args.jobs} processes "
        f"({minutes_serial:.1f} min serially); target <= {TARGET_MINUTES:g} min: {verdict} it"
    )


if __name__ == "__main__":
    main()
