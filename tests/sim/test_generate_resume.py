"""A resume checks what it keeps: every shard already in the folder is checked against the size
and sha256 recorded when it was written (its commit file, or the card); a damaged one (one float
changed, the file the same size, its footer intact) is named on stderr and made again, and the
card is written from the records alone, so that it never vouches for a damaged file."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest
from damaged_shard import one_float_changed
from killed_run import CLI, RUN_TIMEOUT_S, kill_when
from quiet_generate import generate_quietly

from reform.datasets import read_parquet
from reform.datasets.parquet import verify_folder
from sim.cli import main
from sim.generate import CARD_JSON, CARD_MARKDOWN, shard_path

pytestmark = pytest.mark.faults  # the fault suite: pytest -m faults

REPO_ROOT = Path(__file__).resolve().parents[2]
SCENARIO = "hri-conversation"  # two people and the robot: a cheap scene
EPISODES = 3
SEED = 5
DURATION_S = 5.0  # seconds per episode: 10 frames at 2 Hz
KILL_EPISODES = 30  # a run long enough to be killed mid-way
ARGS = ["--scenario", SCENARIO, "--seed", str(SEED), "--duration", "5", "--jobs", "1", "--quiet"]


def generate(out: Path, episodes: int = EPISODES):
    return generate_quietly(SCENARIO, out, episodes=episodes, seed=SEED, duration=DURATION_S)


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    """The dataset made in one uninterrupted run."""
    out = tmp_path_factory.mktemp("resume") / "reference"
    generate(out)
    return out


@pytest.fixture
def folder(reference, tmp_path) -> Path:
    copy = tmp_path / "ds"
    shutil.copytree(reference, copy)
    return copy


def damage(path: Path) -> None:
    """One float of the shard changed; the same size, the footer intact."""
    before = path.read_bytes()
    path.write_bytes(one_float_changed(before))
    assert path.stat().st_size == len(before)


def damaged_lines(err: str) -> list[str]:
    return [line for line in err.splitlines() if "is damaged" in line]


def test_data_verify_names_a_shard_with_one_float_changed(folder, capsys):
    shard = shard_path(folder, SCENARIO, 1)
    damage(shard)
    assert len(read_parquet(shard)) == DURATION_S * 2  # it still reads, alone
    assert main(["data", "verify", "--data", str(folder)]) == 1
    (line,) = capsys.readouterr().out.splitlines()
    assert "episode=1/part.parquet" in line and "field 'sha256'" in line and "(altered)" in line


def test_a_run_over_a_complete_folder_makes_a_damaged_shard_again(folder, reference, capsys):
    shard = shard_path(folder, SCENARIO, 1)
    damage(shard)
    report = generate(folder)
    assert report.generated == (1,) and report.skipped == (0, 2)
    (line,) = damaged_lines(capsys.readouterr().err)
    assert line.startswith(f"reform-sim generate: {shard} is damaged (sha256 ")
    assert line.endswith("recorded when it was written); it is made again")
    assert shard.read_bytes() == shard_path(reference, SCENARIO, 1).read_bytes()
    # The card is the one first written, not one vouching for the damaged file.
    assert (folder / CARD_JSON).read_bytes() == (reference / CARD_JSON).read_bytes()
    assert (folder / CARD_MARKDOWN).read_bytes() == (reference / CARD_MARKDOWN).read_bytes()
    assert verify_folder(folder) == []
    assert not (folder / "_commits").exists()
    # Once made again, the next run finds nothing to do and says nothing.
    assert generate(folder).generated == ()
    assert damaged_lines(capsys.readouterr().err) == []


def test_extending_checks_the_shards_it_keeps(reference, tmp_path, capsys):
    out = tmp_path / "ds"
    generate(out, episodes=2)
    damage(shard_path(out, SCENARIO, 0))
    report = generate(out)
    assert report.generated == (0, 2) and report.skipped == (1,)
    (line,) = damaged_lines(capsys.readouterr().err)
    assert str(shard_path(out, SCENARIO, 0)) in line
    for k in range(EPISODES):
        assert shard_path(out, SCENARIO, k).read_bytes() == (
            shard_path(reference, SCENARIO, k).read_bytes()
        )
    assert (out / CARD_JSON).read_bytes() == (reference / CARD_JSON).read_bytes()


def test_a_killed_run_resumed_checks_each_shard_against_its_commit(tmp_path):
    out = tmp_path / "ds"
    command = [*CLI, "generate", *ARGS, "--episodes", str(KILL_EPISODES), "--out", str(out)]
    process = subprocess.Popen(
        command,
        cwd=REPO_ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    commits = out / "_commits"
    kill_when(process, lambda: len(list(commits.glob("*.json"))) >= 3, poll_s=0.005)
    written = sorted(
        int(p.parent.name[8:]) for p in out.glob("data/scenario=*/episode=*/*.parquet")
    )
    assert 3 <= len(written) < KILL_EPISODES, "the run was not killed mid-way"
    for k in written:  # a shard in place always has its checksum recorded
        entry = json.loads((commits / f"episode={k}.json").read_text())
        assert entry["bytes"] == shard_path(out, SCENARIO, k).stat().st_size
    damage(shard_path(out, SCENARIO, 0))
    (commits / "episode=1.json").unlink()  # a shard whose checksum was never recorded

    resumed = subprocess.run(
        command, cwd=REPO_ROOT, capture_output=True, timeout=RUN_TIMEOUT_S, text=True
    )
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    (line,) = damaged_lines(resumed.stderr)
    assert str(shard_path(out, SCENARIO, 0)) in line
    assert (
        f"1 shard(s) with no checksum record to check them against (the first: "
        f"{shard_path(out, SCENARIO, 1)}; the card does not list it and its file under _commits/"
    ) in resumed.stderr
    kept = len(written) - 2
    assert f"({KILL_EPISODES - kept} generated, {kept} already there)" in resumed.stdout
    assert verify_folder(out) == []
    reference = tmp_path / "reference"
    generate(reference, episodes=2)
    for k in (0, 1):
        assert shard_path(out, SCENARIO, k).read_bytes() == (
            shard_path(reference, SCENARIO, k).read_bytes()
        )
    assert not commits.exists() and not list(out.rglob("*.tmp"))
