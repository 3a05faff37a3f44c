"""A generated dataset folder is whole or refused: its card lists every shard with its size and
sha256, and a missing, truncated, altered or foreign shard is named, never silently dropped."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from cli_errors import cli_error

from reform.datasets import DataFormatError, read_parquet
from reform.datasets.parquet import verify_folder
from sim.cli import main
from sim.generate import CARD_JSON, generate_dataset

pytestmark = pytest.mark.faults  # the fault suite: pytest -m faults

EPISODES = 3


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("whole") / "ds"
    generate_dataset(
        "hri-conversation",
        episodes=EPISODES,
        seed=5,
        out_dir=out,
        duration=5.0,
        n_jobs=1,
        progress=False,
    )
    return out


@pytest.fixture
def folder(reference, tmp_path) -> Path:
    copy = tmp_path / "ds"
    shutil.copytree(reference, copy)
    return copy


def _shards(folder: Path) -> list[dict]:
    return json.loads((folder / CARD_JSON).read_text())["shards"]


def test_the_card_lists_every_shard_with_its_size_and_checksum(reference):
    shards = _shards(reference)
    assert len(shards) == EPISODES
    for shard in shards:
        path = reference / shard["path"]
        assert shard["bytes"] == path.stat().st_size
        assert len(shard["sha256"]) == 64
    assert verify_folder(reference) == []
    assert len({f.sequence for f in read_parquet(reference)}) == EPISODES


def _delete(folder: Path, shard: str) -> None:
    (folder / shard).unlink()


def _truncate(folder: Path, shard: str) -> None:
    path = folder / shard
    path.write_bytes(path.read_bytes()[:-100])


def _alter(folder: Path, shard: str) -> None:
    path = folder / shard
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        (_delete, r"expected the shard .*, found no such file"),
        (_truncate, r"field 'bytes': expected \d+ bytes .*found \d+ bytes"),
        (_alter, r"field 'sha256': expected [0-9a-f]{64} .*\(altered\)"),
    ],
    ids=["missing", "truncated", "altered"],
)
def test_a_damaged_shard_is_named_unless_asked_for_what_is_there(folder, damage, message):
    shard = _shards(folder)[1]["path"]
    damage(folder, shard)
    with pytest.raises(DataFormatError, match=message) as caught:
        read_parquet(folder)
    assert shard in str(caught.value) and "data verify" in str(caught.value)
    partial = read_parquet(folder, allow_incomplete=True)
    assert len({f.sequence for f in partial}) == EPISODES - 1
    (problem,) = partial.metadata["incomplete"]
    assert shard in problem
    (reported,) = verify_folder(folder)
    assert shard in reported


def test_a_parquet_file_the_card_does_not_list_is_refused(folder):
    first = _shards(folder)[0]["path"]
    stray = folder / "data" / "scenario=hri-conversation" / "episode=99" / "part.parquet"
    stray.parent.mkdir()
    shutil.copy(folder / first, stray)
    with pytest.raises(DataFormatError, match=r"episode=99/part.parquet: expected only the shards"):
        read_parquet(folder)


def test_data_verify_and_the_commands_say_what_is_left_out(folder, capsys):
    assert main(["data", "verify", "--data", str(folder)]) == 0
    assert "whole" in capsys.readouterr().out
    shard = _shards(folder)[2]["path"]
    _delete(folder, shard)
    assert main(["data", "verify", "--data", str(folder)]) == 1
    captured = capsys.readouterr()
    assert shard in captured.out and "1 problem(s)" in captured.err
    assert main(["data", "info", "--data", str(folder)]) == 2
    assert "the dataset is not whole" in capsys.readouterr().err
    assert main(["data", "info", "--data", str(folder), "--allow-incomplete"]) == 0
    err = capsys.readouterr().err
    assert "1 shard(s) left out (--allow-incomplete)" in err and shard in err


@pytest.mark.parametrize(
    ("where", "field", "by", "shards_give"),
    [
        ("", "episodes", 1, "the number of shards the card lists"),
        ("totals", "shards", 1, "the number of its shards"),
        ("totals", "frames", -1, "the frames its 3 shards hold"),
        ("totals", "rows", 5, "the rows its 3 shards hold"),
        ("shards[1]", "frames", 2, "the frames of shard {path}"),
        ("shards[0]", "annotated_frames", 1, "the annotated frames of shard {path}"),
    ],
    ids=["episodes", "shards", "frames", "rows", "shard-frames", "shard-annotated-frames"],
)
def test_data_verify_refuses_a_card_whose_counts_are_not_its_shards(
    folder, where, field, by, shards_give, capsys
):
    card_path = folder / CARD_JSON
    card = json.loads(card_path.read_text())
    if where.startswith("shards"):
        part = card["shards"][int(where[len("shards[") : -1])]
    else:
        part = card[where] if where else card
    true = part[field]  # the generated card's: what its shards give
    part[field] += by
    card_path.write_text(json.dumps(card))
    at = f"{where}: " if where else ""
    assert cli_error(["data", "verify", "--data", folder], capsys) == (
        f"reform-sim data: error: {card_path}: {at}field {field!r}: expected "
        f"{shards_give.format(path=part.get('path'))} ({true}), found {true + by}"
    )


def test_data_verify_refuses_a_card_that_says_of_a_shard_what_it_does_not_hold(folder, capsys):
    """Two shards swapped with their sizes and hashes: each is unaltered, but not the episode
    the card says; a group size the shards do not hold, in the totals."""
    card_path = folder / CARD_JSON
    card = json.loads(card_path.read_text())
    first, second = card["shards"][0], card["shards"][1]
    for key in ("bytes", "sha256"):
        first[key], second[key] = second[key], first[key]
    a, b = folder / first["path"], folder / second["path"]
    shard_a, shard_b = a.read_bytes(), b.read_bytes()
    a.write_bytes(shard_b)
    b.write_bytes(shard_a)
    card_path.write_text(json.dumps(card))
    assert cli_error(["data", "verify", "--data", folder], capsys) == (
        f"reform-sim data: error: {card_path}: shards[0]: field 'sequence': expected the "
        f"sequence of shard {first['path']} ({second['sequence']!r}), found {first['sequence']!r}"
    )
    a.write_bytes(shard_a)
    b.write_bytes(shard_b)
    for key in ("bytes", "sha256"):
        first[key], second[key] = second[key], first[key]
    card["totals"]["group_sizes"]["99"] = 1
    card_path.write_text(json.dumps(card))
    assert "totals: field 'group_sizes': expected the group sizes its 3 shards hold" in (
        cli_error(["data", "verify", "--data", folder], capsys)
    )
