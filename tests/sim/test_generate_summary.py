"""A truth-view dataset's counts (the card's totals, each shard's summary) are those of the
frames its shards hold, the shards do not depend on which process made episode 0's scenario
(the one that checked it, or a worker), and a run leaves Python's cycle collector as it found
it."""

from __future__ import annotations

import gc
from collections import Counter
from pathlib import Path

import pytest
from quiet_generate import generate_quietly

from reform.datasets import read_parquet
from sim.generate import read_card, shard_path

SCENARIO = "mingle"
# People walking past come and go: the people present change while the groups do not.
OPTIONS = {"people": 10, "passers_by": 2, "event_rate": 4.0}
EPISODES = 2
SEED = 5
DURATION_S = 60.0  # 120 frames at 2 Hz


@pytest.fixture(scope="module")
def serial(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("summary") / "data"
    generate_quietly(
        SCENARIO, out, episodes=EPISODES, seed=SEED, duration=DURATION_S, options=OPTIONS
    )
    return out


def test_totals_are_those_of_the_frames(serial):
    card = read_card(serial)
    sizes: Counter[int] = Counter()
    frames = annotated = rows = 0
    for k in range(EPISODES):
        shard = read_parquet(shard_path(serial, SCENARIO, k))
        episode = shard.metadata["episode"]
        assert episode["frames"] == len(shard)
        assert episode["annotated_frames"] == len(shard.annotated())
        assert episode["rows"] == sum(f.n_people for f in shard)
        mine: Counter[int] = Counter()
        for frame in shard.annotated():
            mine.update(len(g) for g in frame.partition())
        assert episode["group_sizes"] == {str(n): c for n, c in sorted(mine.items())}
        sizes += mine
        frames += len(shard)
        annotated += len(shard.annotated())
        rows += episode["rows"]
    totals = card["totals"]
    assert (totals["frames"], totals["annotated_frames"], totals["rows"]) == (
        frames,
        annotated,
        rows,
    )
    assert totals["group_sizes"] == {str(n): c for n, c in sorted(sizes.items())}
    assert sizes[1] > 0 and max(sizes) >= 2  # people alone, and groups


def test_episode_zero_made_by_a_worker_gives_the_same_shards(serial, tmp_path):
    out = tmp_path / "data"
    generate_quietly(
        SCENARIO,
        out,
        episodes=EPISODES,
        seed=SEED,
        duration=DURATION_S,
        options=OPTIONS,
        n_jobs=2,
    )
    for k in range(EPISODES):
        assert (
            shard_path(out, SCENARIO, k).read_bytes()
            == shard_path(serial, SCENARIO, k).read_bytes()
        )


def test_the_collector_is_left_as_it_was(tmp_path):
    assert gc.get_freeze_count() == 0
    generate_quietly(SCENARIO, tmp_path / "a", episodes=1, seed=SEED, duration=5.0, options=OPTIONS)
    assert gc.get_freeze_count() == 0  # what the run froze is collected again
    gc.freeze()
    try:
        generate_quietly(
            SCENARIO, tmp_path / "b", episodes=1, seed=SEED, duration=5.0, options=OPTIONS
        )
        assert gc.get_freeze_count() > 0  # the caller's own freeze is kept (not undone)
    finally:
        gc.unfreeze()
