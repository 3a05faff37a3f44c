"""Speed of the dataset loaders, each against the bare parsing floor of its file.

Baselines, run in the same process: SALSA and Babble - read the file and convert every numeric
token with ``float()`` (no validation, no frames); Parquet - ``pyarrow.parquet.read_table`` of the
same file (raw columnar read, no frames), and ``write_table`` of that table for writing; the
frames read back must equal SALSA's (checked). Each loader and its baseline run one after the
other, ``--repeats`` times; prints the medians and the median of the ratios loader / baseline
of each such pair, so that a change of load on the machine hits both alike.

    python benchmarks/bench_loaders.py [--datasets ../shared/datasets] [--repeats 5] [--quick]

``--quick``: one run of each.
"""

from __future__ import annotations

import statistics
import tempfile
from pathlib import Path

import pyarrow.parquet as pq
from timing import BenchmarkParser, datasets_folder, median_seconds

from reform.datasets import load_babble, load_salsa, read_parquet, write_parquet


def parse_floor_salsa(folder: Path) -> int:
    n = 0
    for line in (folder / "features.txt").read_text().splitlines():
        tokens = line.split(" ")
        n += len([float(t) for i, t in enumerate(tokens) if i == 0 or (i - 1) % 5])
    for line in (folder / "group_names.txt").read_text().splitlines():
        n += len(line.split(" "))
    return n


def parse_floor_babble(folder: Path) -> int:
    n = 0
    for line in (folder / "Motion-capture-data.csv").read_text().splitlines()[1:]:
        fields = line.split(",")[:-1]
        n += len([float(f) for i, f in enumerate(fields) if i % 10 not in (0, 9)])
    return n + len((folder / "annotated-frames.csv").read_text().splitlines())


def main() -> None:
    parser = BenchmarkParser(__doc__, repeats=5)
    parser.add_datasets_argument()
    args = parser.parse_args()
    root = datasets_folder(args.datasets, "salsa", "babble")

    salsa = load_salsa(root / "salsa")
    with tempfile.TemporaryDirectory() as tmp:
        parquet = write_parquet(salsa, Path(tmp) / "salsa.parquet")
        if read_parquet(parquet).frames != salsa.frames:
            raise SystemExit("read_parquet: the frames read back differ from SALSA's")
        table = pq.read_table(parquet)
        rows = [
            (
                "SALSA load_salsa",
                lambda: load_salsa(root / "salsa"),
                lambda: parse_floor_salsa(root / "salsa"),
            ),
            (
                "Babble load_babble",
                lambda: load_babble(root / "babble"),
                lambda: parse_floor_babble(root / "babble"),
            ),
            ("SALSA read_parquet", lambda: read_parquet(parquet), lambda: pq.read_table(parquet)),
            (
                "SALSA write_parquet",
                lambda: write_parquet(salsa, parquet),
                lambda: pq.write_table(table, parquet),
            ),
        ]
        print(f"{'task':<22} {'median s':>9} {'baseline s':>11} {'ratio':>7}")
        for name, loader, baseline in rows:
            loader(), baseline()  # warmed: the file cached, the code paths loaded
            pairs = [
                (median_seconds(loader, 1), median_seconds(baseline, 1))
                for _ in range(args.repeats)
            ]
            measured = statistics.median(m for m, _ in pairs)
            floor = statistics.median(f for _, f in pairs)
            ratio = statistics.median(m / f for m, f in pairs)
            print(f"{name:<22} {measured:9.3f} {floor:11.3f} {ratio:6.1f}x")


if __name__ == "__main__":
    main()
