"""Datasets at scale: shards, card, determinism across workers and backends, resume, bad input."""

from __future__ import annotations

import json
import shlex
import shutil
import socket
import subprocess
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from killed_run import CLI, RUN_TIMEOUT_S, kill_when
from quiet_generate import generate_quietly

from reform.annotation import AnnotationModel
from reform.datasets import load_dataset, read_parquet, write_parquet
from reform.frame import Dataset
from sim.cli import main
from sim.episode import simulate_episode
from sim.generate import (
    CARD_JSON,
    CARD_MARKDOWN,
    episode_seed,
    read_card,
    shard_path,
)

REPO_ROOT = Path(__file__).resolve().parents[2]
SCENARIO = "hri-conversation"  # two people and the robot: a cheap scene with groups and a robot
EPISODES = 4
SEED = 11
DURATION_S = 300.0  # seconds per episode (600 frames at 2 Hz)
SENSOR = {"position_noise": 0.02, "yaw_noise": 0.05, "dropout": 0.1}
# The same dataset as command-line arguments.
ARGS = [
    "--scenario",
    SCENARIO,
    "--episodes",
    str(EPISODES),
    "--seed",
    str(SEED),
    "--duration",
    "300",
    "--view",
    "robot",
    "--position-noise",
    "0.02",
    "--yaw-noise",
    "0.05",
    "--dropout",
    "0.1",
]


def generate(out_dir: Path, **overrides):
    kwargs = dict(episodes=EPISODES, seed=SEED, duration=DURATION_S, view="robot", sensor=SENSOR)
    return generate_quietly(SCENARIO, out_dir, **(kwargs | overrides))


def contents(folder: Path) -> dict[str, bytes]:
    """Every visible file of a generated folder (shards and cards), by relative path."""
    return {
        p.relative_to(folder).as_posix(): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and not any(part.startswith(".") for part in p.relative_to(folder).parts)
    }


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    """The dataset made serially, in one uninterrupted run."""
    out = tmp_path_factory.mktemp("reference") / "data"
    report = generate(out)
    assert report.generated == tuple(range(EPISODES)) and report.skipped == ()
    return out


def test_episode_seeds_are_the_spawned_children_of_the_master_seed():
    children = np.random.SeedSequence(SEED).spawn(5)
    for k, child in enumerate(children):
        expected = int(child.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))
        assert episode_seed(SEED, k) == expected
    assert len({episode_seed(SEED, k) for k in range(1000)}) == 1000
    assert episode_seed(SEED, 3) != episode_seed(SEED + 1, 3)


def test_shards_load_one_by_one_and_as_one_dataset(reference):
    whole = read_parquet(reference)
    assert load_dataset(reference).sequences() == whole.sequences()
    assert whole.sequences() == tuple(f"{SCENARIO}-{k}" for k in range(EPISODES))
    assert whole.name == SCENARIO
    offset = 0
    for k in range(EPISODES):
        path = shard_path(reference, SCENARIO, k)
        assert path.relative_to(reference).as_posix() == (
            f"data/scenario={SCENARIO}/episode={k}/part.parquet"
        )
        shard = read_parquet(path)
        assert len(shard) == DURATION_S * 2  # 2 Hz
        assert {f.sequence for f in shard} == {f"{SCENARIO}-{k}"}
        assert all(a == b for a, b in zip(shard, whole.frames[offset:], strict=False))
        assert shard.metadata["episode"]["seed"] == episode_seed(SEED, k)
        offset += len(shard)
    assert offset == len(whole)
    # The robot's view: the robot is in every frame, people come and go from its sight.
    assert all("robot" in f.kinds for f in whole)
    assert min(f.n_people for f in whole) < max(f.n_people for f in whole)


def test_card_records_every_parameter_and_the_counts(reference):
    card = read_card(reference)
    p = card["parameters"]
    assert p["scenario"] == SCENARIO and p["seed"] == SEED and p["view"] == "robot"
    assert p["rate_hz"] == 2.0 and p["duration_s"] == DURATION_S and p["options"] == {}
    assert p["sensor"]["dropout"] == 0.1 and p["sensor"]["fov_deg"] == 57.0
    assert p["package_version"].startswith("reform-sim ")
    assert card["complete"] is True and card["episodes"] == EPISODES
    assert card["scenario_options_resolved"]["radius"] == 0.6  # the scenario's default
    dataset = read_parquet(reference)
    sizes: Counter[int] = Counter()
    for frame in dataset.annotated():
        sizes.update(len(g) for g in frame.partition())
    totals = card["totals"]
    assert totals["frames"] == len(dataset)
    assert totals["annotated_frames"] == len(dataset.annotated())
    assert totals["rows"] == sum(f.n_people for f in dataset)
    assert totals["group_sizes"] == {str(k): v for k, v in sorted(sizes.items())}
    assert sizes[2] > 0  # the robot and the one person it sees of its conversation
    assert [s["seed"] for s in card["shards"]] == [episode_seed(SEED, k) for k in range(EPISODES)]
    markdown = (reference / CARD_MARKDOWN).read_text()
    counts = f"| 2 | {sizes[2]:,} |"
    for text in (SCENARIO, "master seed | 11", "2 Hz", "300 s", "dropout=0.1", counts):
        assert text in markdown
    assert "reform-sim generate --scenario hri-conversation --episodes 4 --seed 11" in markdown


def test_same_seed_same_bytes_with_two_workers_and_another_seed_differs(reference, tmp_path):
    report = generate(tmp_path / "two", n_jobs=2)
    assert report.n_jobs == 2
    assert contents(tmp_path / "two") == contents(reference)
    other = generate(tmp_path / "other", seed=SEED + 1, episodes=1)
    first = read_parquet(shard_path(tmp_path / "other", SCENARIO, 0))
    assert first.frames != read_parquet(shard_path(reference, SCENARIO, 0)).frames
    assert other.episodes == 1


def test_extending_keeps_finished_shards_and_matches_one_run(reference, tmp_path):
    out = tmp_path / "data"
    generate(out, episodes=2)
    first = shard_path(out, SCENARIO, 0).stat()
    report = generate(out)
    assert report.skipped == (0, 1) and report.generated == (2, 3)
    again = shard_path(out, SCENARIO, 0).stat()
    assert (again.st_ino, again.st_mtime_ns) == (first.st_ino, first.st_mtime_ns)
    assert contents(out) == contents(reference)
    assert generate(out).generated == ()  # idempotent


def test_a_killed_run_leaves_whole_shards_and_resumes_to_the_same_data(reference, tmp_path):
    out = tmp_path / "data"
    command = [*CLI, "generate", *ARGS, "--out", str(out)]
    process = subprocess.Popen(
        [*command, "--jobs", "1", "--quiet"],
        cwd=REPO_ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    first = shard_path(out, SCENARIO, 0)
    kill_when(process, first.exists, poll_s=0.005)
    written = sorted(out.glob("data/scenario=*/episode=*/part.parquet"))
    assert 1 <= len(written) < EPISODES, "the run was not killed mid-way"
    for path in written:  # every shard on disk is whole
        assert len(read_parquet(path)) == DURATION_S * 2
    assert read_card(out)["complete"] is False
    # The unfinished folder reads only when asked for, as its card says.
    assert "read_parquet('DIR', allow_incomplete=True)" in (out / CARD_MARKDOWN).read_text()
    with pytest.raises(ValueError, match=r"field 'complete': expected true"):
        read_parquet(out)
    assert len(read_parquet(out, allow_incomplete=True)) == len(written) * DURATION_S * 2

    resumed = subprocess.run(
        [*command, "--jobs", "2", "--quiet"],
        cwd=REPO_ROOT,
        capture_output=True,
        timeout=RUN_TIMEOUT_S,
        text=True,
    )
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    assert f"{len(written)} already there" in resumed.stdout
    assert not list(out.rglob("*.tmp"))
    assert contents(out) == contents(reference)


def test_ray_backend_gives_the_local_data(reference, tmp_path, ray_instance):
    report = generate(tmp_path / "ray", backend="ray")
    assert report.backend == "ray" and report.n_jobs == 2
    assert contents(tmp_path / "ray") == contents(reference)
    # The command line joins the running cluster by its address.
    address = ray_instance.get_runtime_context().gcs_address
    run = subprocess.run(
        [*CLI, "generate", *ARGS, "--out", str(tmp_path / "cli")]
        + ["--backend", "ray", "--address", address, "--quiet"],
        cwd=REPO_ROOT,
        capture_output=True,
        timeout=RUN_TIMEOUT_S,
        text=True,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    assert "CPUs (Ray)" in run.stdout
    assert contents(tmp_path / "cli") == contents(reference)


@pytest.mark.parametrize("where", ["folder", "store"])
def test_an_unreachable_cluster_is_one_line_before_any_work(tmp_path, where):
    """The library call probes the address first: one line, no folder, no object, no Ray."""
    ray = pytest.importorskip("ray")
    from sim.executor import ClusterError

    joined = ray.is_initialized()

    with socket.socket() as s:  # a port on 127.0.0.1 where nothing listens
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "data" if where == "folder" else f"memory://reform-sim-test/{tmp_path.name}"
    for address, message in [
        (f"127.0.0.1:{port}", f"nothing listens at 127.0.0.1:{port}"),
        ("bogus", "host 'bogus' is not known"),
    ]:
        with pytest.raises(ClusterError, match=rf"^address {address}: .*{message}") as info:
            generate(out, backend="ray", address=address)
        assert "\n" not in str(info.value)
    assert ray.is_initialized() == joined  # no Ray instance was started or joined
    if where == "folder":
        assert not (tmp_path / "data").exists()
    else:
        from reform.datasets.store import open_store

        assert open_store(out).sizes() == {}


def test_command_line_writes_the_dataset_and_train_reads_it(tmp_path, capsys):
    out = tmp_path / "data"
    code = main(
        ["generate", "--scenario", "hri-robot-excluded", "--episodes", "2", "--seed", "3"]
        + ["--out", str(out), "--duration", "30", "--set", "radius=0.5", "--quiet"]
    )
    assert code == 0
    assert "2 generated, 0 already there" in capsys.readouterr().out
    card = read_card(out)
    assert card["parameters"]["options"] == {"radius": 0.5}
    assert card["scenario_options_resolved"]["radius"] == 0.5
    assert "--set radius=0.5" in card["command"]
    dataset = load_dataset(out)
    assert len(dataset) == 2 * 60
    assert all("robot" in f.kinds and len(f.kinds) == 3 for f in dataset)  # the truth view
    model = tmp_path / "model.skops"
    code = main(
        ["train", "--data", str(out), "--classifier", "logistic-regression"]
        + ["--frames", "train", "--out", str(model)]
    )
    assert code == 0 and model.is_file()
    assert "hri-robot-excluded" in capsys.readouterr().out


def test_truth_view_fast_path_writes_the_frames_of_simulate_episode(tmp_path):
    # Without recordings the truth view writes columns from the world's pose blocks; with them
    # it goes through simulate_episode's Frames. The shards are the same bytes.
    fast, slow = tmp_path / "fast", tmp_path / "slow"
    kwargs = dict(episodes=2, duration=30.0, view="truth", sensor=None, n_jobs=1)
    generate(fast, **kwargs)
    generate(slow, save_recordings=True, **kwargs)
    for k in range(2):
        assert (
            shard_path(fast, SCENARIO, k).read_bytes() == shard_path(slow, SCENARIO, k).read_bytes()
        )
    assert read_card(fast) == read_card(slow)
    episode = simulate_episode(
        SCENARIO, seed=episode_seed(SEED, 1), duration=30.0, sequence=f"{SCENARIO}-1"
    )
    assert read_parquet(shard_path(fast, SCENARIO, 1)).frames == episode.dataset.frames


def test_progress_bar_on_stderr(tmp_path, capsys):
    generate(tmp_path / "data", episodes=2, duration=5.0, progress=True)
    captured = capsys.readouterr()
    assert f"generate {SCENARIO}" in captured.err and "2/2" in captured.err
    assert captured.out == ""


def test_recordings_hold_each_episode(tmp_path):
    rrd = pytest.importorskip("rerun.chunk")
    out = tmp_path / "data"
    generate(out, episodes=1, duration=5.0, save_recordings=True)
    path = out / "recordings" / "episode=0.rrd"
    (store,) = rrd.RrdReader(path).recordings()
    assert store.application_id == "reform-sim"
    entities = {chunk.entity_path for chunk in rrd.RrdReader(path).stream()}
    assert any(e.startswith("/world/people") for e in entities), sorted(entities)[:20]
    assert any(e.startswith("/world/observed") for e in entities), sorted(entities)[:20]
    # Asking for recordings later re-makes the episodes that lack one, with the same shard.
    plain = tmp_path / "plain"
    generate(plain, episodes=1, duration=5.0)
    shard = shard_path(plain, SCENARIO, 0).read_bytes()
    report = generate(plain, episodes=1, duration=5.0, save_recordings=True)
    assert report.generated == (0,)
    assert (plain / "recordings" / "episode=0.rrd").is_file()
    assert shard_path(plain, SCENARIO, 0).read_bytes() == shard


@pytest.mark.parametrize(
    ("scenario", "overrides", "match"),
    [
        (
            "mingle-party",
            {},
            r"unknown scenario 'mingle-party'; known scenarios: .*hri-conversation",
        ),
        ("word-improv", {"options": {"players": 1}}, r"players"),
        ("hri-passing", {"options": {"people": 300}}, r"option people must be within"),
        ("hri-passing", {"options": {"crowd": 3}}, r"unknown option 'crowd'"),
        (SCENARIO, {"duration": -5.0}, r"duration must be a positive number \(seconds\)"),
        (SCENARIO, {"duration": 0.2}, r"holds no frame at 2 Hz"),
        (SCENARIO, {"rate": 0.0}, r"rate must be a positive number \(Hz\)"),
        (SCENARIO, {"rate": 3.0}, r"rate must be a rate whose period is a whole number of 0.01"),
        (SCENARIO, {"episodes": 0}, r"episodes must be an int >= 1, got 0"),
        (SCENARIO, {"episodes": -2}, r"episodes must be an int >= 1, got -2"),
        (SCENARIO, {"seed": -1}, r"seed must be an int >= 0"),
        (SCENARIO, {"view": "truth", "sensor": {"dropout": 0.2}}, r"view='robot' only"),
        (SCENARIO, {"sensor": {"dropout": 2.0}}, r"dropout must be in \[0, 1\], got 2.0"),
        (SCENARIO, {"sensor": {"zoom": 2.0}}, r"sensor options must be among"),
        (
            "word-improv",
            {"options": {"robot": "none"}},
            r"view='robot' needs a robot, and scenario word-improv has none with these options "
            r"\(robot=watch puts it there\)$",
        ),
        (
            "concourse",
            {"options": {"people": 50}},
            r"view='robot' needs a robot, and scenario concourse has no place for the robot$",
        ),
        (SCENARIO, {"backend": "dask"}, r"backend must be one of \('local', 'ray'\)"),
        (SCENARIO, {"address": "auto"}, r"address is for backend='ray'"),
        (SCENARIO, {"n_jobs": 0}, r"n_jobs must be an int >= 1"),
    ],
    ids=lambda value: str(value)[:40],
)
def test_bad_input_fails_before_any_work(tmp_path, scenario, overrides, match):
    kwargs = dict(episodes=2, seed=1, view="robot")
    with pytest.raises(ValueError, match=match):
        generate_quietly(scenario, tmp_path / "data", **(kwargs | overrides))
    assert not (tmp_path / "data").exists()


def test_a_folder_holding_another_dataset_is_refused_before_any_work(reference, tmp_path):
    before = contents(reference)
    with pytest.raises(ValueError, match=r"holds another dataset .*differs in seed.*seed: folder"):
        generate(reference, seed=SEED + 1)
    with pytest.raises(ValueError, match=r"differs in duration_s, options"):
        generate(reference, duration=60.0, options={"radius": 0.7})
    with pytest.raises(ValueError, match=r"holds a dataset of 4 episodes, asked for 2"):
        generate(reference, episodes=2)
    assert contents(reference) == before
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match=r"holds files but no dataset card .*notes.txt"):
        generate(foreign)
    assert sorted(p.name for p in foreign.iterdir()) == ["notes.txt"]
    (tmp_path / "file").write_text("")
    with pytest.raises(ValueError, match=r"out_dir .*file is a file: expected a folder"):
        generate(tmp_path / "file")
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / CARD_JSON).write_text("[1, 2]")
    with pytest.raises(ValueError, match=r"expected a reform-sim dataset card"):
        generate(broken)
    # A field the resume would rewrite is refused, not mended: (field, value written, found).
    made = tmp_path / "made"
    generate(made, episodes=1, duration=5.0)
    card = json.loads((made / CARD_JSON).read_text())
    for field, value, found in (
        ("card_version", 99, "99"),
        ("episodes", -1, "-1"),
        ("episodes", float("nan"), "nan"),
        ("complete", "yes", "'yes'"),
    ):
        (made / CARD_JSON).write_text(json.dumps({**card, field: value}))
        with pytest.raises(ValueError) as caught:
            generate(made, episodes=1, duration=5.0)
        assert str(caught.value).startswith(f"{made / CARD_JSON}: field {field!r}: expected ")
        assert str(caught.value).endswith(f", found {found}")
    (broken / CARD_JSON).write_text('{"card_version": ' + "1" * 5000 + "}")
    with pytest.raises(
        ValueError,
        match=r"dataset.json: expected a reform-sim dataset card \(JSON\), found a number of "
        r"more digits than can be read \(4,300\)$",
    ):
        generate(broken)


def test_a_folder_being_written_by_another_run_is_refused(tmp_path):
    fcntl = pytest.importorskip("fcntl")
    out = tmp_path / "data"
    out.mkdir()
    with open(out / ".generate.lock", "w") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        with pytest.raises(ValueError, match=r"being written by another reform-sim generate run"):
            generate(out, episodes=1, duration=5.0)
        assert (out / ".generate.lock").exists()  # the other run's, left as it is
    assert not list(out.glob("**/*.parquet"))


def test_a_run_removes_its_lock_and_one_a_killed_run_left(tmp_path):
    out = tmp_path / "data"
    out.mkdir()
    (out / ".generate.lock").touch()  # a killed run's: nobody holds it
    report = generate(out, episodes=1, duration=5.0)
    assert report.generated == (0,)
    assert sorted(p.name for p in out.iterdir()) == [CARD_MARKDOWN, "data", CARD_JSON]


def test_command_line_errors_are_one_line(tmp_path, capsys):
    code = main(
        ["generate", *ARGS, "--out", str(tmp_path / "x"), "--backend", "local"]
        + [
            "--address",
            "auto",
        ]
    )
    assert code == 2
    assert "--address needs --backend ray" in capsys.readouterr().err
    code = main(
        ["generate", "--scenario", "hri-passing", "--episodes", "1", "--seed", "1"]
        + ["--out", str(tmp_path / "y"), "--dropout", "0.3"]
    )
    assert code == 2
    assert "sensor options need --view robot, got --dropout" in capsys.readouterr().err
    code = main(
        ["generate", "--scenario", "hri-passing", "--episodes", "1", "--seed", "1"]
        + ["--out", str(tmp_path / "y"), "--set", "people"]
    )
    assert code == 2
    assert "--set must be KEY=VALUE" in capsys.readouterr().err
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()


def test_shard_metadata_says_where_it_came_from(reference):
    shard = read_parquet(shard_path(reference, SCENARIO, 2))
    meta = shard.metadata
    assert meta["generator"] == "reform-sim generate"
    assert meta["parameters"] == read_card(reference)["parameters"]
    assert meta["episode"]["episode"] == 2
    assert meta["scenario"]["seed"] == episode_seed(SEED, 2)
    assert meta["scenario"]["options"]["radius"] == 0.6
    assert json.loads(json.dumps(dict(meta))) == dict(meta)


def copy_of(reference: Path, out: Path) -> Path:
    shutil.copytree(reference, out, ignore=shutil.ignore_patterns(".*"))
    return out


def test_a_shard_copied_to_another_episode_is_refused_on_resume(reference, tmp_path, capsys):
    out = copy_of(reference, tmp_path / "data")
    moved = shard_path(out, SCENARIO, 1)
    shutil.copyfile(shard_path(out, SCENARIO, 2), moved)
    before = contents(out)
    expected = (
        rf"out_dir .*: 1 of the 4 shards already there is not the episode its place says: "
        rf".*episode=1/part\.parquet: field 'metadata\.episode': expected the shard of episode "
        rf"1 \(sequence '{SCENARIO}-1', seed {episode_seed(SEED, 1)}\), found the shard of "
        rf"episode 2 \(sequence '{SCENARIO}-2', seed {episode_seed(SEED, 2)}\)\. Nothing was "
        r"changed: delete the file\(s\) named"
    )
    with pytest.raises(ValueError, match=expected):
        generate(out)
    assert main(["generate", *ARGS, "--out", str(out), "--quiet"]) == 2
    assert "episode=1/part.parquet: field 'metadata.episode'" in capsys.readouterr().err
    assert contents(out) == before  # nothing regenerated, the card left as it was
    moved.unlink()  # the user's say: the file goes, the next run makes it again
    assert generate(out).generated == (1,)
    assert contents(out) == contents(reference)


def test_a_shard_of_another_dataset_is_refused_on_resume(reference, tmp_path):
    short = tmp_path / "short"
    generate(short, episodes=2, duration=5.0)  # same episodes and seeds, another duration
    out = copy_of(reference, tmp_path / "data")
    shutil.copyfile(shard_path(short, SCENARIO, 1), shard_path(out, SCENARIO, 1))
    with pytest.raises(
        ValueError,
        match=r"episode=1/part\.parquet: field 'metadata\.parameters': expected the parameters "
        r"of this dataset's dataset\.json, found a shard of another dataset: duration_s 5\.0 "
        r"\(expected 300\.0\)",
    ):
        generate(out)


@pytest.mark.parametrize("statistics", [True, False], ids=["statistics", "no-statistics"])
def test_a_shard_whose_frames_are_another_sequence_is_refused_on_resume(
    reference, tmp_path, statistics
):
    import pyarrow.parquet as pq

    out = copy_of(reference, tmp_path / "data")
    # Episode 1's metadata over episode 2's frames: only the sequence column tells.
    path = shard_path(out, SCENARIO, 1)
    shard = read_parquet(path)
    frames = read_parquet(shard_path(out, SCENARIO, 2)).frames
    write_parquet(
        Dataset(frames=frames, name=shard.name, source=shard.source, metadata=shard.metadata),
        path,
    )
    if not statistics:  # the check then reads the first row group's sequence values
        for k in (0, 1):
            table = pq.read_table(shard_path(out, SCENARIO, k))
            pq.write_table(table, shard_path(out, SCENARIO, k), write_statistics=False)
        assert not pq.ParquetFile(path).metadata.row_group(0).column(0).is_stats_set
    with pytest.raises(
        ValueError,
        match=rf"1 of the 4 shards .*episode=1/part\.parquet: field 'sequence': expected frames "
        rf"of sequence '{SCENARIO}-1' only \(episode 1 .*\), found sequence\(s\) "
        rf"\['{SCENARIO}-2'\]",
    ):
        generate(out)


def test_every_wrong_shard_is_named_on_resume(reference, tmp_path):
    out = copy_of(reference, tmp_path / "data")
    shard_path(out, SCENARIO, 1).write_bytes(b"not parquet")
    shutil.copyfile(shard_path(out, SCENARIO, 0), shard_path(out, SCENARIO, 3))
    with pytest.raises(ValueError, match=r"2 of the 4 shards already there are not") as caught:
        generate(out)
    message = str(caught.value)
    assert (
        "episode=1/part.parquet: field 'schema metadata': expected a shard written by "
        "reform-sim generate" in message
    )
    assert "episode=3/part.parquet: field 'metadata.episode'" in message
    assert "episode=0/" not in message and "episode=2/" not in message


def test_an_annotation_model_records_each_episode_as_it_says(tmp_path):
    """--annotation: the shards hold the frames as the model records them, the card and each
    shard record it, the card's command reproduces the data byte for byte."""
    model = AnnotationModel(directions=4, scale_sd=0.05, position_noise=0.03, dropout=0.05)
    run = dict(episodes=2, seed=3, duration=20)
    plain = generate_quietly("word-improv", tmp_path / "plain", **run)
    made = generate_quietly("word-improv", tmp_path / "coded", annotation=model, **run)
    card = read_card(made.out_dir)
    assert card["parameters"]["annotation"] == model.to_json()
    assert "annotation" not in read_card(plain.out_dir)["parameters"]
    assert "--annotation directions=4" in card["command"]
    step = np.pi / 2
    for k in range(2):
        truth = read_parquet(shard_path(plain.out_dir, "word-improv", k))
        coded = read_parquet(shard_path(made.out_dir, "word-improv", k))
        assert coded.metadata["annotation"] == model.to_json()
        yaws = np.concatenate([f.yaw for f in coded.frames])
        np.testing.assert_allclose(np.round(yaws / step) * step, yaws)
        assert sum(f.n_people for f in coded.frames) < sum(f.n_people for f in truth.frames)
    again = tmp_path / "again"
    words = shlex.split(card["command"].replace("DIR", str(again)))
    assert main([*words[1:], "--jobs", "1", "--quiet"]) == 0
    for k in range(2):
        first = shard_path(made.out_dir, "word-improv", k).read_bytes()
        assert shard_path(again, "word-improv", k).read_bytes() == first


def test_a_randomised_annotation_draws_one_model_per_episode(tmp_path):
    made = generate_quietly(
        "mingle", tmp_path / "r", episodes=3, seed=5, duration=10, annotation="random"
    )
    card = read_card(made.out_dir)
    assert card["parameters"]["annotation"] == "random"
    assert card["parameters"]["annotation_ranges"]["directions"] == [None, 4, 8, 24]
    models = [
        read_parquet(shard_path(made.out_dir, "mingle", k)).metadata["annotation"] for k in range(3)
    ]
    assert len({json.dumps(m, sort_keys=True) for m in models}) == 3
    for m in models:
        AnnotationModel(**m)  # each a valid model


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--annotation", "directions=0"], "directions must be a whole number >= 1"),
        (
            ["--annotation", "scale_sd=-1"],
            "annotation scale_sd must be a finite number >= 0, got -1.0",
        ),
        (["--annotation", "random", "--annotation", "dropout=0.1"], "takes no other"),
        (["--annotation", "depth=3"], "annotation setting 'depth=3': expected KEY=VALUE"),
    ],
)
def test_bad_annotation_settings_are_one_line_before_any_work(tmp_path, capsys, flags, message):
    out = tmp_path / "never"
    argv = ["generate", "--scenario", "mingle", "--episodes", "1", "--seed", "1", "--out", str(out)]
    assert main([*argv, *flags]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
