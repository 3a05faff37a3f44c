"""Group events in generated datasets: each shard stores its episode's ground-truth events
(`reform.events`), the card counts them per kind, a resume checks them as part of the shard, a
dataset without them derives them on read, and the recordings show them on the timeline."""

from __future__ import annotations

import hashlib
import io
import json
import shutil
from collections import Counter
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from quiet_generate import generate_quietly
from rerun.chunk import RrdReader

from reform import group_events
from reform.datasets import (
    DataFormatError,
    dataset_group_events,
    read_parquet,
    write_parquet,
)
from reform.datasets.parquet import METADATA_KEY
from reform.events import EVENT_KINDS, LEAVES
from reform.frame import Dataset
from sim.generate import CARD_MARKDOWN, read_card, shard_path
from sim.recording import group_event_text

SCENARIO = "mingle-randomised"  # people wander between conversations: groups form, leave, end
EPISODES = 2
SEED = 1
DURATION_S = 60.0  # 120 frames at 2 Hz


def generate(out: Path, **overrides):
    kwargs = dict(episodes=EPISODES, seed=SEED, duration=DURATION_S)
    return generate_quietly(SCENARIO, out, **(kwargs | overrides))


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("events") / "data"
    generate(out)
    return out


def stored(path: Path) -> dict:
    """The group events a shard's header stores."""
    return read_parquet(path).metadata["group_events"]


def test_each_shard_stores_the_events_of_its_frames(reference):
    for k in range(EPISODES):
        shard = read_parquet(shard_path(reference, SCENARIO, k))
        record = shard.metadata["group_events"]
        events = group_events(shard.frames)  # the rules, on the frames as the shard holds them
        assert record["events"] == [json.loads(json.dumps(e.to_json())) for e in events]
        assert record["tracks"] == max(e.group for e in events)  # every track here has an event
        assert {e["sequence"] for e in record["events"]} == {f"{SCENARIO}-{k}"}
    # Tracks and frames count within the episode: frame k is row group `frame == k` of the shard.
    assert min(e["frame"] for e in record["events"]) >= 1  # nothing happens at the first frame


def test_read_back_the_events_are_those_of_the_whole_dataset(reference):
    dataset = read_parquet(reference)
    events = dataset_group_events(dataset)
    assert events == group_events(dataset.frames)  # frames and tracks over the whole dataset
    kinds = Counter(e.kind for e in events)
    assert kinds["forms"] and kinds["dissolves"] and kinds[LEAVES]
    assert {e.sequence for e in events} == {f"{SCENARIO}-{k}" for k in range(EPISODES)}
    # The second episode's tracks follow the first's.
    first = stored(shard_path(reference, SCENARIO, 0))["tracks"]
    assert min(e.group for e in events if e.sequence.endswith("-1")) > first


def test_the_card_counts_the_events_per_kind(reference):
    card = read_card(reference)
    counted = Counter(e.kind for e in dataset_group_events(read_parquet(reference)))
    assert card["totals"]["group_events"] == {kind: counted[kind] for kind in EVENT_KINDS}
    for k, entry in enumerate(card["shards"]):
        in_shard = Counter(e["kind"] for e in stored(shard_path(reference, SCENARIO, k))["events"])
        assert entry["group_events"] == {kind: in_shard[kind] for kind in EVENT_KINDS}
    markdown = (reference / CARD_MARKDOWN).read_text()
    assert "## Group events" in markdown
    for kind in EVENT_KINDS:
        assert f"| {kind} | {counted[kind]:,} |" in markdown
    assert f"| all | {sum(counted.values()):,} |" in markdown


def test_the_frame_path_and_an_annotation_model_store_the_events_of_the_frames_written(tmp_path):
    # With recordings the truth view goes through Frames: the same shard bytes as the fast path.
    slow = tmp_path / "slow"
    generate(slow, episodes=1, save_recordings=True)
    fast = tmp_path / "fast"
    generate(fast, episodes=1)
    assert shard_path(slow, SCENARIO, 0).read_bytes() == shard_path(fast, SCENARIO, 0).read_bytes()
    # Annotators who call only groups lasting 10 s: the events are those of the groups as
    # annotated, not as simulated.
    slow_calls = tmp_path / "annotated"
    generate(slow_calls, episodes=1, annotation={"min_group_seconds": 10.0})
    shard = read_parquet(shard_path(slow_calls, SCENARIO, 0))
    expected = [json.loads(json.dumps(e.to_json())) for e in group_events(shard.frames)]
    assert shard.metadata["group_events"]["events"] == expected
    assert expected != stored(shard_path(fast, SCENARIO, 0))["events"]


def test_an_episode_with_one_annotated_frame_stores_no_events(tmp_path):
    out = tmp_path / "one"
    generate(out, episodes=1, duration=0.5)  # one frame at 2 Hz
    assert stored(shard_path(out, SCENARIO, 0)) == {"tracks": 0, "events": []}
    assert read_card(out)["totals"]["group_events"] == dict.fromkeys(EVENT_KINDS, 0)


def test_same_seed_same_events(reference, tmp_path):
    again = tmp_path / "again"
    generate(again, n_jobs=2)
    for k in range(EPISODES):
        a, b = shard_path(again, SCENARIO, k), shard_path(reference, SCENARIO, k)
        assert a.read_bytes() == b.read_bytes()
    assert read_card(again) == read_card(reference)


def rewrite_header(path: Path, change) -> None:
    """The shard written again with its header's metadata changed by ``change``."""
    table = pq.read_table(path)
    header = json.loads(table.schema.metadata[METADATA_KEY])
    change(header["metadata"])
    schema = table.schema.with_metadata({METADATA_KEY: json.dumps(header).encode()})
    out = io.BytesIO()
    pq.write_table(table.cast(schema), out, compression="zstd")
    path.write_bytes(out.getvalue())


def test_altered_events_are_caught_by_the_checksum_and_made_again(reference, tmp_path, capsys):
    folder = tmp_path / "data"
    shutil.copytree(reference, folder)
    path = shard_path(folder, SCENARIO, 1)
    rewrite_header(path, lambda metadata: metadata["group_events"]["events"].pop())
    with pytest.raises(DataFormatError, match=r"episode=1/part\.parquet.*(bytes|sha256)"):
        read_parquet(folder)
    capsys.readouterr()
    report = generate(folder)
    assert report.generated == (1,)
    assert "is damaged" in capsys.readouterr().err
    assert path.read_bytes() == shard_path(reference, SCENARIO, 1).read_bytes()


def test_a_dataset_without_stored_events_derives_them_on_read(reference, tmp_path):
    # Shards as written before the events were stored: the same frames, no events in the header.
    old = tmp_path / "old"
    for k in range(EPISODES):
        shard = read_parquet(shard_path(reference, SCENARIO, k))
        metadata = {key: v for key, v in shard.metadata.items() if key != "group_events"}
        write_parquet(
            Dataset(shard.frames, name=shard.name, source=shard.source, metadata=metadata),
            old / f"episode={k}" / "part.parquet",
        )
    dataset = read_parquet(old)
    assert all("group_events" not in s["metadata"] for s in dataset.metadata["shards"])
    assert dataset_group_events(dataset) == dataset_group_events(read_parquet(reference))
    # A dataset made in memory, one file read alone: derived too.
    one = read_parquet(old / "episode=0" / "part.parquet")
    assert dataset_group_events(one) == group_events(one.frames)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda g: g.update(tracks="3"), r"'tracks' \(an int\) and 'events' \(a list\)"),
        (lambda g: g["events"][0].update(kind="meets"), r"event 0.*kind must be one of"),
        (lambda g: g["events"][0].update(frame=10_000), r"event 0.*a frame index below 120"),
        (lambda g: g["events"][0].update(group=99), r"event 0.*track ids from 1 to"),
        (lambda g: g["events"][0].pop("members"), r"event 0.*no field 'members'"),
    ],
    ids=["tracks", "kind", "frame", "track", "members"],
)
def test_malformed_stored_events_are_named(reference, tmp_path, change, match):
    path = tmp_path / "ds" / "part.parquet"  # a folder of one shard: errors name the file
    path.parent.mkdir()
    shutil.copy(shard_path(reference, SCENARIO, 0), path)
    rewrite_header(path, lambda metadata: change(metadata["group_events"]))
    with pytest.raises(DataFormatError, match=r"ds/part\.parquet.*metadata\.group_events") as error:
        dataset_group_events(read_parquet(path.parent))
    assert error.match(match)


def test_recordings_show_the_episode_s_group_events(tmp_path):
    out = tmp_path / "rec"
    generate(out, episodes=1, save_recordings=True)
    logged = []
    for chunk in RrdReader(out / "recordings" / "episode=0.rrd").stream():
        if chunk.entity_path == "/events/truth":
            data = chunk.to_record_batch().to_pydict()
            logged += [(f, t[0]) for f, t in zip(data["frame"], data["TextLog:text"], strict=True)]
    # The truth view, as simulated: the recording's events are the ones the shard stores.
    events = dataset_group_events(read_parquet(shard_path(out, SCENARIO, 0)))
    assert events
    assert logged == [(e.frame, group_event_text(e)) for e in events]


def test_a_folder_written_before_events_were_stored_reads_and_extends(reference, tmp_path):
    # The folder as an earlier reform-sim wrote it: shards and card without group events, the
    # card's sizes and checksums those of these shards.
    folder = tmp_path / "old"
    shutil.copytree(reference, folder)

    def forget(metadata):
        del metadata["group_events"]
        del metadata["episode"]["group_events"]

    card = json.loads((folder / "dataset.json").read_text())
    del card["totals"]["group_events"]
    for k, entry in enumerate(card["shards"]):
        path = shard_path(folder, SCENARIO, k)
        rewrite_header(path, forget)
        del entry["group_events"]
        entry["bytes"] = path.stat().st_size
        entry["sha256"] = hashlib.sha256(path.read_bytes()).hexdigest()
    (folder / "dataset.json").write_text(json.dumps(card, indent=2) + "\n")
    assert "group_events" not in read_parquet(shard_path(folder, SCENARIO, 0)).metadata
    # Its events are derived on read: those a new run stores.
    expected = dataset_group_events(read_parquet(reference))
    assert dataset_group_events(read_parquet(folder)) == expected
    # Extended by this reform-sim: the old shards are kept as they are, the new one stores its
    # events, and the card does not count what some shards do not say.
    report = generate(folder, episodes=EPISODES + 1)
    assert report.generated == (EPISODES,) and report.skipped == tuple(range(EPISODES))
    card = read_card(folder)
    assert card["totals"]["group_events"] is None
    assert "group_events" not in card["shards"][0] and "group_events" in card["shards"][-1]
    assert "Not counted: some shards were written before" in (folder / CARD_MARKDOWN).read_text()
    assert stored(shard_path(folder, SCENARIO, EPISODES))["tracks"] >= 0
    events = dataset_group_events(read_parquet(folder))
    assert events[: len(expected)] == expected
    assert {e.sequence for e in events[len(expected) :]} <= {f"{SCENARIO}-{EPISODES}"}
