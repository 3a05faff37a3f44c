"""A generated folder as other tools read it: shards under data/ (hive-partitioned), a card with
Hugging Face front matter, and folders of the first layout (shards right under the folder)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import yaml

from reform.datasets import read_parquet
from reform.datasets.parquet import COLUMNS
from sim.generate import (
    CARD_JSON,
    CARD_MARKDOWN,
    DATA_DIR,
    folder_layout,
    generate_dataset,
    read_card,
    shard_path,
)

SCENARIO = "hri-conversation"  # two people and the robot: a cheap scene
EPISODES = 3
SEED = 5
DURATION_S = 4.0  # seconds per episode: 8 frames at 2 Hz


def generate(out_dir: Path, episodes: int = EPISODES):
    return generate_dataset(
        SCENARIO,
        episodes=episodes,
        seed=SEED,
        out_dir=out_dir,
        duration=DURATION_S,
        n_jobs=1,
        progress=False,
    )


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("layout") / "ds"
    generate(out)
    return out


def test_the_folder_is_laid_out_as_a_hub_dataset(folder):
    top = sorted(p.name for p in folder.iterdir() if not p.name.startswith("."))
    assert top == [CARD_MARKDOWN, DATA_DIR, CARD_JSON]
    shards = sorted(p.relative_to(folder / DATA_DIR).as_posix() for p in folder.rglob("*.parquet"))
    assert shards == [f"scenario={SCENARIO}/episode={k}/part.parquet" for k in range(EPISODES)]
    # Nothing in data/ but the shards: what every tool below reads.
    assert all(p.is_dir() or p.suffix == ".parquet" for p in (folder / DATA_DIR).rglob("*"))
    card = read_card(folder)
    assert [s["path"] for s in card["shards"]] == [f"{DATA_DIR}/{s}" for s in shards]


def test_the_card_has_hugging_face_front_matter(folder):
    text = (folder / CARD_MARKDOWN).read_text()
    assert text.startswith("---\n")
    header, body = text[4:].split("\n---\n", 1)
    meta = yaml.safe_load(header)
    assert meta["license"] == "mit"
    assert meta["pretty_name"] == f"reform-sim synthetic dataset: {SCENARIO}"
    assert meta["task_categories"] == ["robotics"]
    assert "f-formation" in meta["tags"]
    rows = read_card(folder)["totals"]["rows"]
    assert rows < 1000 and meta["size_categories"] == ["n<1K"]
    (config,) = meta["configs"]
    assert config["config_name"] == "default"
    (files,) = config["data_files"]
    assert files["split"] == "train"
    # The pattern names exactly the shards.
    assert sorted(folder.glob(files["path"])) == sorted(folder.rglob("*.parquet"))
    assert body.lstrip().startswith(f"# Synthetic dataset: {SCENARIO}")


def _check_table(columns: list[str], scenario: list, episode: list, n_rows: int, folder: Path):
    assert set(COLUMNS) <= set(columns)
    assert {"scenario", "episode"} <= set(columns)
    assert set(scenario) == {SCENARIO}
    assert sorted({int(e) for e in episode}) == list(range(EPISODES))
    assert n_rows == sum(_rows(folder, k) for k in range(EPISODES))


def _rows(folder: Path, episode: int) -> int:
    import pyarrow.parquet as pq

    return pq.ParquetFile(shard_path(folder, SCENARIO, episode)).metadata.num_rows


def test_pandas_reads_the_shards(folder):
    pandas = pytest.importorskip("pandas")
    table = pandas.read_parquet(folder / DATA_DIR)
    _check_table(
        list(table.columns), list(table["scenario"]), list(table["episode"]), len(table), folder
    )
    # The hive column agrees with the rows' own sequence column.
    for k in range(EPISODES):
        assert set(table[table["episode"] == k]["sequence"]) == {f"{SCENARIO}-{k}"}


def test_pyarrow_dataset_reads_the_shards(folder):
    import pyarrow as pa
    import pyarrow.dataset as ds

    dataset = ds.dataset(folder / DATA_DIR, partitioning="hive")
    assert dataset.schema.field("scenario").type == pa.string()
    assert pa.types.is_integer(dataset.schema.field("episode").type)
    table = dataset.to_table()
    _check_table(
        table.column_names,
        table["scenario"].to_pylist(),
        table["episode"].to_pylist(),
        table.num_rows,
        folder,
    )
    one = dataset.to_table(filter=ds.field("episode") == 1)
    assert set(one["sequence"].to_pylist()) == {f"{SCENARIO}-1"}


def test_polars_reads_the_shards(folder):
    polars = pytest.importorskip("polars")
    frame = polars.scan_parquet(
        str(folder / DATA_DIR / "**" / "*.parquet"), hive_partitioning=True
    ).collect()
    _check_table(
        frame.columns, frame["scenario"].to_list(), frame["episode"].to_list(), frame.height, folder
    )


def test_duckdb_reads_the_shards(folder):
    duckdb = pytest.importorskip("duckdb")
    pattern = (folder / DATA_DIR).as_posix() + "/**/*.parquet"
    relation = duckdb.sql(f"SELECT * FROM read_parquet('{pattern}', hive_partitioning = true)")
    rows = relation.fetchall()
    columns = relation.columns
    scenario = [r[columns.index("scenario")] for r in rows]
    episode = [r[columns.index("episode")] for r in rows]
    _check_table(columns, scenario, episode, len(rows), folder)
    counts = duckdb.sql(
        f"SELECT episode, count(DISTINCT sequence) FROM read_parquet('{pattern}', "
        "hive_partitioning = true) GROUP BY episode ORDER BY episode"
    ).fetchall()
    assert counts == [(k, 1) for k in range(EPISODES)]


def _first_layout(new: Path, old: Path) -> None:
    """``new`` as the first layout wrote it: shards right under the folder, the card listing
    them there."""
    shutil.copytree(new, old)
    (old / DATA_DIR / f"scenario={SCENARIO}").rename(old / f"scenario={SCENARIO}")
    (old / DATA_DIR).rmdir()
    card = json.loads((old / CARD_JSON).read_text())
    card["layout"] = card["layout"].removeprefix(f"{DATA_DIR}/")
    for shard in card["shards"]:
        shard["path"] = shard["path"].removeprefix(f"{DATA_DIR}/")
    (old / CARD_JSON).write_text(json.dumps(card, indent=2) + "\n")


def test_a_folder_of_the_first_layout_reads_and_extends_in_its_layout(folder, tmp_path):
    old = tmp_path / "old"
    _first_layout(folder, old)
    assert folder_layout(old) == ""
    assert read_parquet(old).frames == read_parquet(folder).frames
    report = generate(old, episodes=EPISODES + 1)
    assert report.generated == (EPISODES,) and report.skipped == tuple(range(EPISODES))
    assert not (old / DATA_DIR).exists()  # never two layouts in one folder
    added = old / f"scenario={SCENARIO}" / f"episode={EPISODES}" / "part.parquet"
    assert shard_path(old, SCENARIO, EPISODES) == added
    # The same shard, byte for byte, as a new-layout run writes.
    longer = tmp_path / "longer"
    generate(longer, episodes=EPISODES + 1)
    assert added.read_bytes() == shard_path(longer, SCENARIO, EPISODES).read_bytes()
    card = read_card(old)
    assert card["shards"][-1]["path"] == added.relative_to(old).as_posix()
    assert 'path: "scenario=*/episode=*/*.parquet"' in (old / CARD_MARKDOWN).read_text()
    assert len(read_parquet(old).sequences()) == EPISODES + 1


def test_an_unfinished_folder_of_the_first_layout_continues_in_it(folder, tmp_path):
    old = tmp_path / "old"
    _first_layout(folder, old)
    card = json.loads((old / CARD_JSON).read_text())  # killed before its first shard
    card.update(complete=False, shards=[])
    (old / CARD_JSON).write_text(json.dumps(card))
    shutil.rmtree(old / f"scenario={SCENARIO}")
    assert folder_layout(old) == ""
    generate(old)
    assert not (old / DATA_DIR).exists()
    assert len(list(old.glob("scenario=*/episode=*/part.parquet"))) == EPISODES


def test_a_folder_holding_both_layouts_is_refused(folder, tmp_path):
    mixed = tmp_path / "mixed"
    shutil.copytree(folder, mixed)
    shutil.copytree(mixed / DATA_DIR / f"scenario={SCENARIO}", mixed / f"scenario={SCENARIO}")
    before = sorted(p.as_posix() for p in mixed.rglob("*"))
    with pytest.raises(ValueError, match=r"holds shards in two layouts \(scenario=hri-conv"):
        generate(mixed)
    assert sorted(p.as_posix() for p in mixed.rglob("*")) == before
