"""A venue twin of SALSA fitted and its dataset generated, beside the time to load SALSA.

Issue 28's speed figure: a twin fitted (`sim.twins.fit_twin`: pilot parties, scale, room,
annotation; the pilot parties on ``--jobs`` processes) and its labelled dataset generated
(`sim.twins.generate_twin`, on as many) in under a minute for a dataset the size of SALSA
(1,145 frames of 18 people).
Measured in the same run: loading SALSA (`reform.datasets.load_dataset`, the baseline), fitting
its twin, generating the twin's dataset into a fresh folder; each a wall-clock median over
``--repeats`` runs, with its ratio to the load.

Run: ``python benchmarks/bench_twin.py [--datasets DIR] [--jobs 2] [--repeats 3] [--quick]``
(``--quick``: one repeat, the twin's data cut to one episode).
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from timing import BenchmarkParser, datasets_folder, default_datasets, timed

from reform.datasets import load_dataset
from sim.twins import fit_twin, generate_twin

TARGET_S = 60.0  # seconds: issue 28's bound on fitting and generating together


def main() -> int:
    parser = BenchmarkParser(__doc__, repeats=3, quick_repeats=1)
    parser.add_argument("--datasets", default=default_datasets(), help="the datasets' folder")
    parser.add_argument("--jobs", type=int, default=2, help="processes of the fit and generation")
    args = parser.parse_args()
    root = datasets_folder(Path(args.datasets), "salsa")
    load = timed(lambda: load_dataset(root / "salsa"), args.repeats)
    frames = list(load.result)
    fit = timed(lambda: fit_twin(frames, name="salsa", n_jobs=args.jobs), args.repeats)
    twin = fit.result
    episodes = 1 if args.quick else twin.episodes

    def generate():
        folder = Path(tempfile.mkdtemp(prefix="bench-twin-"))
        try:
            return generate_twin(twin, folder / "data", episodes=episodes, n_jobs=args.jobs)
        finally:
            shutil.rmtree(folder, ignore_errors=True)

    made = timed(generate, args.repeats)
    frames_made = made.result.annotated_frames
    total = fit.median + made.median
    print(f"SALSA: {len(frames):,} frames; twin: {episodes} episodes, {frames_made:,} frames")
    print(f"{'step':<28}{'median s':>10}{'x load':>10}")
    print(f"{'load SALSA (baseline)':<28}{load.median:>10.2f}{1.0:>10.1f}")
    print(f"{'fit the twin':<28}{fit.median:>10.2f}{fit.median / load.median:>10.1f}")
    print(f"{'generate its dataset':<28}{made.median:>10.2f}{made.median / load.median:>10.1f}")
    verdict = "met" if total < TARGET_S else "NOT met"
    print(f"twin fitted and generated: {total:.1f} s (goal < {TARGET_S:g} s: {verdict})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
