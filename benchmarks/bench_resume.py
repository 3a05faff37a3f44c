"""What a resume's checks cost: every shard a resumed ``generate`` keeps is read and checked
against the size and sha256 recorded when it was written; this times those checks beside the
generation of the shards they check, in the same run.

The same ``generate_dataset`` run (``mingle``, 18 people, the ground-truth view, episodes of the
scenario's natural length, 600 s at 2 Hz, one worker) is made into a folder on local disk and
into a real S3-compatible server on 127.0.0.1 (moto's server mode, started here), then run again
over each finished dataset: nothing is left to simulate (checked), every shard is checked
(`GenerationReport.check_seconds`, medians over ``--repeats`` runs). Printed for each: the
generation's time, the whole resumed run's and its checks', and checks / generation against the
target (issue 32: at most 10 %).

Run: ``python benchmarks/bench_resume.py [--episodes 4] [--repeats 3] [--quick]`` (``--quick``:
two episodes cut to 30 s, one repeat).
"""

from __future__ import annotations

import logging
import os
import statistics
import tempfile
from pathlib import Path

from timing import BenchmarkParser

from sim.generate import generate_dataset

SCENARIO = "mingle"
PEOPLE = 18
SEED = 1
EPISODES = 4
QUICK_EPISODES = 2
QUICK_DURATION_S = 30.0  # seconds per episode with --quick
BUCKET = "bench-resume"
TARGET = 0.10  # checks on resume / generation of the shards they check, at most


def _server() -> object:
    """A real S3-compatible server on 127.0.0.1; the environment pointed at it."""
    from moto.server import ThreadedMotoServer

    logging.getLogger("werkzeug").disabled = True  # the server's access log, not printed
    server = ThreadedMotoServer(ip_address="127.0.0.1", port=0, verbose=False)
    server.start()
    host, port = server.get_host_and_port()
    os.environ.update(
        AWS_ACCESS_KEY_ID="bench",
        AWS_SECRET_ACCESS_KEY="bench",
        AWS_ENDPOINT_URL=f"http://{host}:{port}",
        AWS_DEFAULT_REGION="us-east-1",
        AWS_EC2_METADATA_DISABLED="true",
    )
    import boto3

    boto3.client("s3").create_bucket(Bucket=BUCKET)
    return server


def measure(out: str | Path, *, episodes: int, duration: float | None, repeats: int) -> dict:
    """Generation of ``episodes`` episodes into ``out``, then ``repeats`` runs over it."""
    kwargs = dict(
        episodes=episodes,
        seed=SEED,
        options={"people": PEOPLE},
        duration=duration,
        n_jobs=1,
        progress=False,
    )
    made = generate_dataset(SCENARIO, out_dir=out, **kwargs)
    assert made.generated == tuple(range(episodes)), made.generated
    resumes = [generate_dataset(SCENARIO, out_dir=out, **kwargs) for _ in range(repeats)]
    for resumed in resumes:  # every shard kept, checked, the same data
        assert resumed.generated == () and resumed.skipped == made.generated
        assert resumed.shards == made.shards
    return {
        "generate": made.seconds,
        "resume": statistics.median(r.seconds for r in resumes),
        "checks": statistics.median(r.check_seconds for r in resumes),
        "frames": made.annotated_frames,
    }


def main() -> int:
    parser = BenchmarkParser(__doc__, repeats=3)
    parser.add_sized("--episodes", default=EPISODES, quick=QUICK_EPISODES, help="episodes")
    args = parser.parse_args()
    duration = QUICK_DURATION_S if args.quick else None
    server = _server()
    try:
        with tempfile.TemporaryDirectory(prefix="bench-resume-") as scratch:
            # Warm-up: the motion kernel's compiled code, the store's client, on neither clock.
            warm = dict(episodes=1, seed=SEED, duration=QUICK_DURATION_S, n_jobs=1, progress=False)
            generate_dataset(SCENARIO, out_dir=Path(scratch) / "warm", **warm)
            generate_dataset(SCENARIO, out_dir=f"s3://{BUCKET}/warm", **warm)
            sized = dict(episodes=args.episodes, duration=duration, repeats=args.repeats)
            results = {
                "local disk": measure(Path(scratch) / "disk", **sized),
                "S3 server": measure(f"s3://{BUCKET}/resume", **sized),
            }
    finally:
        server.stop()
    first = next(iter(results.values()))
    length = "natural length" if duration is None else f"{duration:g} s"
    print(
        f"{SCENARIO}: {PEOPLE} people, {args.episodes} episodes ({length}, "
        f"{first['frames']:,} annotated frames), one worker; resumed runs: median of "
        f"{args.repeats}"
    )
    print(f"{'where':<11} {'generate':>10} {'resume':>10} {'checks':>10}  checks / generate")
    worst = 0.0
    for where, r in results.items():
        ratio = r["checks"] / r["generate"]
        worst = max(worst, ratio)
        print(
            f"{where:<11} {r['generate']:>8.2f} s {r['resume']:>8.2f} s {r['checks']:>8.3f} s  "
            f"{ratio:.2%}"
        )
    verdict = "met" if worst <= TARGET else "NOT met"
    print(f"target: checks on resume <= {TARGET:.0%} of the generation: {verdict} ({worst:.2%})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
