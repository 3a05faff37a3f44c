"""Writing a generated dataset to object storage against local disk: frames per second, the cost
of one shard, and a paper calculation of a 64-worker, one-million-episode run.

The same ``generate_dataset`` run (``mingle``, 18 people, the ground-truth view, episodes of the
scenario's natural length, 600 s at 2 Hz) is timed writing to a folder on local disk and to a
real S3-compatible server on 127.0.0.1 (moto's server mode, started here), one worker each,
medians over ``--repeats`` runs. Both must write the same shards, byte for byte (checked). The
requests the run makes to the store are counted by the server, by HTTP method.

From the store run's measured cost per shard (seconds, bytes, requests) the paper calculation
scales to 64 workers writing one million episodes: wall time if the store keeps up, the data
size (shards and the card, which lists every shard), and the requests per second the store
must take. A local server on the same 2 cores is no model of a remote one's latency: the time
per shard it gives is the client's and server's CPU cost; a remote store adds its round trips,
which many workers overlap.

Run: ``python benchmarks/bench_store.py [--episodes 4] [--repeats 3] [--quick]``
(``--quick``: two episodes cut to 30 s, one repeat).
"""

from __future__ import annotations

import json
import logging
import os
import statistics
import tempfile
from collections import Counter
from pathlib import Path

from timing import BenchmarkParser

from sim.generate import generate_dataset

SCENARIO = "mingle"
SEED = 1
EPISODES = 4
QUICK_EPISODES = 2
QUICK_DURATION_S = 30.0  # seconds per episode with --quick
BUCKET = "bench-data"
WORKERS = 64  # the paper run
PAPER_EPISODES = 1_000_000


def _server() -> tuple[object, str]:
    from moto.server import ThreadedMotoServer

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
    return server, f"http://{host}:{port}"


class _Requests(logging.Handler):
    """Counts the requests the server answers, by HTTP method (from its access log)."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.counts: Counter = Counter()

    def emit(self, record: logging.LogRecord) -> None:
        words = record.getMessage().split('"')
        if len(words) > 1 and words[1].split(" ")[0].isupper():
            self.counts[words[1].split(" ")[0]] += 1


def _counting() -> Counter:
    handler = _Requests()
    server_log = logging.getLogger("werkzeug")
    server_log.setLevel(logging.INFO)
    server_log.propagate = False  # counted, not printed
    server_log.addHandler(handler)
    return handler.counts


def main() -> int:
    parser = BenchmarkParser(__doc__, repeats=3)
    parser.add_sized("--episodes", default=EPISODES, quick=QUICK_EPISODES, help="episodes")
    args = parser.parse_args()
    episodes = args.episodes
    duration = QUICK_DURATION_S if args.quick else None
    counts = _counting()
    server, endpoint = _server()
    from reform.datasets.store import open_store

    disk_s, store_s = [], []
    try:
        with tempfile.TemporaryDirectory(prefix="bench-store-") as scratch:
            # Warm-up: the motion kernel's compiled code, the store's client, on neither clock.
            warm = dict(episodes=1, seed=SEED, duration=QUICK_DURATION_S, n_jobs=1, progress=False)
            generate_dataset(SCENARIO, out_dir=Path(scratch) / "warm", **warm)
            generate_dataset(SCENARIO, out_dir=f"s3://{BUCKET}/warm", **warm)
            for r in range(args.repeats):
                kwargs = dict(
                    episodes=episodes, seed=SEED, duration=duration, n_jobs=1, progress=False
                )
                local = Path(scratch) / f"disk{r}"
                disk = generate_dataset(SCENARIO, out_dir=local, **kwargs)
                counts.clear()
                uri = f"s3://{BUCKET}/run{r}"
                stored = generate_dataset(SCENARIO, out_dir=uri, **kwargs)
                requests = Counter(counts)
                disk_s.append(disk.seconds)
                store_s.append(stored.seconds)
                store = open_store(uri)
                for shard in disk.shards:  # the same bytes, wherever written
                    path = f"data/{shard.path}"
                    assert store.read(path) == (local / path).read_bytes(), path
                frames = disk.annotated_frames
                assert stored.annotated_frames == frames
                shard_bytes = sum(store.sizes("data").values()) / episodes
                card = json.loads(store.read("dataset.json") or b"{}")
                empty = len(json.dumps({**card, "shards": []}, indent=2))
                card_per_shard = (len(json.dumps(card, indent=2)) - empty) / episodes
    finally:
        server.stop()
    disk_fps = frames / statistics.median(disk_s)
    store_fps = frames / statistics.median(store_s)
    per_shard_s = statistics.median(store_s) / episodes
    overhead_s = (statistics.median(store_s) - statistics.median(disk_s)) / episodes
    per_shard_requests = (requests["PUT"] - 5) / episodes  # less the lock, the two cards twice
    total_requests = sum(requests.values())
    print(f"store: moto server at {endpoint}, {episodes} episodes of {SCENARIO}, one worker")
    print(f"local disk  {disk_fps:,.0f} frames/s  ({statistics.median(disk_s):.2f} s)")
    print(f"S3 server   {store_fps:,.0f} frames/s  ({statistics.median(store_s):.2f} s)")
    print(f"store / disk ratio {store_fps / disk_fps:.2f}x")
    print(
        f"per shard: {per_shard_s:.3f} s ({overhead_s * 1000:+.1f} ms against disk), "
        f"{shard_bytes / 1024:,.1f} KiB, {per_shard_requests:.1f} PUT requests, "
        f"{card_per_shard:.0f} bytes of card"
    )
    print(
        f"requests of the run: {total_requests} "
        f"({', '.join(f'{k} {v}' for k, v in sorted(requests.items()))})"
    )
    hours = PAPER_EPISODES * per_shard_s / WORKERS / 3600
    data_gb = PAPER_EPISODES * shard_bytes / 1e9
    card_gb = PAPER_EPISODES * card_per_shard / 1e9
    rate = WORKERS * per_shard_requests / per_shard_s
    print(
        f"paper: {WORKERS} workers x {PAPER_EPISODES:,} episodes: {hours:.1f} h, "
        f"{data_gb:,.1f} GB of shards + {card_gb:.2f} GB card, "
        f"{rate:,.0f} requests/s to the store ({PAPER_EPISODES * per_shard_requests:,.0f} PUTs "
        f"+ {PAPER_EPISODES / 1000:,.0f} batch deletes of the commits)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
