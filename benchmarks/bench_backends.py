"""Local processes against Ray: wall time of `stress` and `generate` on each backend, same
arguments, and the ratio.

A Ray instance is started in this process on this machine's cores (its start is timed apart),
then each command's library call runs on the local backend (``jobs`` = every core, joblib's
loky) and on Ray (both through `sim.executor.Executor`: stress is given one, generate is asked
for ``backend="ray"``), each backend's workers warmed up first (a smaller run of the same work),
medians over ``--repeats`` runs. The outputs must be the same on both backends (checked:
stress's curves and training summary as JSON; every generated shard and the card, byte for
byte).

The ratio ray / local is the cost of Ray's scheduling, serialisation and object store on one
machine, where it brings no extra cores; on a cluster the same run spreads over every node's
CPUs. On a machine shared with other work the wall times carry its load (printed).

Run: ``python benchmarks/bench_backends.py [--repeats 2] [--quick]`` (``--quick``: stress on
one axis with one test episode, generate two 30-second episodes, one repeat, no warm-up).
"""

from __future__ import annotations

import dataclasses
import filecmp
import os
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from timing import BenchmarkParser

from sim.executor import Executor, cpu_count
from sim.experiments.stress import GRIDS, run_stress
from sim.generate import generate_dataset

SCENARIO = "mingle"  # generate's scenario, at its default 18 people
SEED = 1
STRESS_AXES = ("position-noise", "dropout", "density", "sensor")  # perturbations, scenes
EPISODES = 16  # generate: episodes per run
DURATION_S = 600.0  # generate: seconds per episode (the scenario's natural length)
QUICK_EPISODES = 2
QUICK_DURATION_S = 30.0
QUICK_AXES = ("dropout",)


def _stress_key(results) -> dict:
    data = results.to_json()
    return {k: data[k] for k in ("grid", "detectors", "training", "axes")}


def bench_stress(
    executor: Executor, grid, axes, repeats: int, *, warm: bool
) -> tuple[list[float], dict]:
    """Wall seconds of each `run_stress`, and its results (JSON) for the equality check."""
    seconds, key = [], None
    if warm:  # workers up, code compiled
        run_stress(dataclasses.replace(grid, seeds=1), seed=SEED, axes=axes[:1], executor=executor)
    for _ in range(repeats):
        start = time.perf_counter()
        results = run_stress(grid, seed=SEED, axes=axes, executor=executor)
        seconds.append(time.perf_counter() - start)
        key = _stress_key(results)
    return seconds, key


def bench_generate(
    backend: str, root: Path, episodes: int, duration: float, repeats: int, *, warm: bool
) -> tuple[list[float], Path]:
    """Wall seconds of each `generate_dataset` into a fresh folder; the last folder."""
    options = {"n_jobs": cpu_count()} if backend == "local" else {}
    if warm:  # workers up, code compiled; another seed, another folder
        generate_dataset(
            SCENARIO,
            episodes=1,
            seed=SEED + 1,
            out_dir=root / f"warm-{backend}",
            duration=duration,
            backend=backend,
            progress=False,
            **options,
        )
    seconds, out = [], root
    for k in range(repeats):
        out = root / f"{backend}-{k}"
        start = time.perf_counter()
        generate_dataset(
            SCENARIO,
            episodes=episodes,
            seed=SEED,
            out_dir=out,
            duration=duration,
            backend=backend,
            progress=False,
            **options,
        )
        seconds.append(time.perf_counter() - start)
    return seconds, out


def same_files(a: Path, b: Path) -> bool:
    """Whether two generated folders hold the same visible files (shards, cards), byte for
    byte."""

    def visible(folder: Path) -> list[Path]:
        return sorted(
            p.relative_to(folder)
            for p in folder.rglob("*")
            if p.is_file() and not any(s.startswith(".") for s in p.relative_to(folder).parts)
        )

    files = visible(a)
    return (
        bool(files)
        and files == visible(b)
        and all(filecmp.cmp(a / f, b / f, shallow=False) for f in files)
    )


def line(what: str, local: list[float], ray: list[float], workers: int) -> str:
    lo, ra = statistics.median(local), statistics.median(ray)
    return (
        f"{what:<58} local {workers} processes {lo:7.1f} s   ray {ra:7.1f} s   "
        f"ray / local: {ra / lo:.2f}x"
    )


def main() -> None:
    parser = BenchmarkParser(__doc__, repeats=2, quick_repeats=1)
    args = parser.parse_args()
    import ray

    workers = cpu_count()
    load = " ".join(f"{v:.2f}" for v in os.getloadavg())
    print(f"machine: {workers} cores, load average {load}")
    start = time.perf_counter()
    ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    print(f"ray.init (a local instance, {workers} CPUs): {time.perf_counter() - start:.1f} s")
    try:
        axes = QUICK_AXES if args.quick else STRESS_AXES
        grid = GRIDS["small"]
        if args.quick:
            grid = dataclasses.replace(grid, seeds=1)
        warm = not args.quick
        local_s, local_key = bench_stress(Executor("local"), grid, axes, args.repeats, warm=warm)
        with Executor("ray") as executor:
            ray_s, ray_key = bench_stress(executor, grid, axes, args.repeats, warm=warm)
        if ray_key != local_key:
            raise SystemExit("stress: the Ray backend's results differ from the local ones")
        what = f"stress (grid small, {grid.seeds} seeds, {','.join(axes)})"
        print(line(what, local_s, ray_s, workers))

        episodes = QUICK_EPISODES if args.quick else EPISODES
        duration = QUICK_DURATION_S if args.quick else DURATION_S
        scratch = Path(tempfile.mkdtemp(prefix="bench-backends-"))
        try:
            local_g, local_out = bench_generate(
                "local", scratch, episodes, duration, args.repeats, warm=warm
            )
            ray_g, ray_out = bench_generate(
                "ray", scratch, episodes, duration, args.repeats, warm=warm
            )
            if not same_files(local_out, ray_out):
                raise SystemExit("generate: the Ray backend's dataset differs from the local one")
        finally:
            shutil.rmtree(scratch, ignore_errors=True)
        what = f"generate ({SCENARIO}, {episodes} episodes of {duration:g} s)"
        print(line(what, local_g, ray_g, workers))
    finally:
        ray.shutdown()


if __name__ == "__main__":
    main()
