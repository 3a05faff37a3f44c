"""Datasets in object storage, end to end against a real S3-compatible server (moto's server mode,
on 127.0.0.1): written by local and Ray workers, killed and resumed, read back by reform-sim,
pyarrow, polars and DuckDB straight from the bucket, and every bad store refused in one line."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from damaged_shard import one_float_changed
from killed_run import CLI, RUN_TIMEOUT_S, kill_when

from reform.datasets import read_parquet
from reform.datasets.errors import DataFormatError
from reform.datasets.parquet import verify_folder
from reform.datasets.store import StoreError, open_store
from sim.cli import main
from sim.generate import CARD_JSON, CARD_MARKDOWN, generate_dataset, shard_path

pytestmark = pytest.mark.faults  # the fault suite: pytest -m faults

moto_server = pytest.importorskip("moto.server")
pytest.importorskip("s3fs")

REPO_ROOT = Path(__file__).resolve().parents[2]
BUCKET = "lab-data"
SCENARIO = "hri-conversation"  # two people and the robot: a cheap scene
EPISODES = 4
SEED = 3
DURATION_S = 60.0  # seconds per episode: 120 frames at 2 Hz
ARGS = ["--scenario", SCENARIO, "--episodes", str(EPISODES), "--seed", str(SEED)]
ARGS += ["--duration", "60", "--jobs", "1", "--quiet"]
KILL_EPISODES = 40  # a run long enough to be killed mid-way


@pytest.fixture(scope="module")
def server():
    """A real S3-compatible server on 127.0.0.1, and the environment that points at it."""
    started = moto_server.ThreadedMotoServer(ip_address="127.0.0.1", port=0, verbose=False)
    started.start()
    host, port = started.get_host_and_port()
    env = {
        "AWS_ACCESS_KEY_ID": "lab-key",
        "AWS_SECRET_ACCESS_KEY": "lab-secret",
        "AWS_ENDPOINT_URL": f"http://{host}:{port}",
        "AWS_DEFAULT_REGION": "us-east-1",
        "AWS_EC2_METADATA_DISABLED": "true",
    }
    saved = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    _clear_cache()
    import boto3

    boto3.client("s3").create_bucket(Bucket=BUCKET)
    try:
        yield env
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
        _clear_cache()
        started.stop()


def _clear_cache() -> None:
    import s3fs

    s3fs.S3FileSystem.clear_instance_cache()


def generate(out, episodes: int = EPISODES, **overrides):
    kwargs = dict(
        episodes=episodes, seed=SEED, out_dir=out, duration=DURATION_S, n_jobs=1, progress=False
    )
    return generate_dataset(SCENARIO, **(kwargs | overrides))


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    """The same dataset on local disk."""
    out = tmp_path_factory.mktemp("store") / "local"
    generate(out)
    return out


def objects(uri: str) -> dict[str, int]:
    return open_store(uri).sizes()


def same_as_reference(uri: str, reference: Path, episodes: int = EPISODES) -> None:
    store = open_store(uri)
    for k in range(episodes):
        relative = shard_path(reference, SCENARIO, k).relative_to(reference).as_posix()
        assert store.read(relative) == (reference / relative).read_bytes(), relative


def test_a_dataset_written_to_s3_is_the_one_written_to_disk(server, reference):
    uri = f"s3://{BUCKET}/same"
    report = generate(uri, n_jobs=2)
    assert report.out_dir == uri and report.card == f"{uri}/{CARD_JSON}"
    # Nothing but the dataset: no commit left, no lock left, no local folder named "s3:".
    names = sorted(objects(uri))
    assert names == sorted(
        [CARD_MARKDOWN, CARD_JSON]
        + [f"data/scenario={SCENARIO}/episode={k}/part.parquet" for k in range(EPISODES)]
    )
    assert not Path("s3:").exists()
    same_as_reference(uri, reference)
    store = open_store(uri)
    assert store.read(CARD_JSON) == (reference / CARD_JSON).read_bytes()
    assert store.read(CARD_MARKDOWN) == (reference / CARD_MARKDOWN).read_bytes()
    # reform-sim reads it straight from the bucket.
    assert read_parquet(uri).frames == read_parquet(reference).frames
    assert verify_folder(uri) == []
    for entry in json.loads(store.read(CARD_JSON))["shards"]:
        content = store.read(entry["path"])
        assert hashlib.sha256(content).hexdigest() == entry["sha256"]
        assert len(content) == entry["bytes"]


def test_other_tools_read_the_dataset_straight_from_the_bucket(server, reference):
    uri = f"s3://{BUCKET}/tools"
    generate(uri)
    import pyarrow.dataset as ds
    import pyarrow.fs
    import pyarrow.parquet as pq

    rows = sum(pq.ParquetFile(p).metadata.num_rows for p in reference.rglob("*.parquet"))

    s3 = pyarrow.fs.S3FileSystem(
        endpoint_override=server["AWS_ENDPOINT_URL"], scheme="http", region="us-east-1"
    )
    table = ds.dataset(f"{BUCKET}/tools/data", filesystem=s3, partitioning="hive").to_table()
    assert table.num_rows == rows
    assert sorted(set(table["episode"].to_pylist())) == list(range(EPISODES))

    polars = pytest.importorskip("polars")
    frame = polars.scan_parquet(f"{uri}/data/**/*.parquet", hive_partitioning=True).collect()
    assert frame.height == rows and set(frame["scenario"]) == {SCENARIO}

    duckdb = pytest.importorskip("duckdb")
    import s3fs

    con = duckdb.connect()
    con.register_filesystem(s3fs.S3FileSystem())  # httpfs needs a download; fsspec does not
    counts = con.sql(
        f"SELECT episode, count(*) FROM read_parquet('{uri}/data/**/*.parquet', "
        "hive_partitioning = true) GROUP BY episode ORDER BY episode"
    ).fetchall()
    local = con.sql(
        f"SELECT episode, count(*) FROM read_parquet('{reference.as_posix()}/data/**/*.parquet', "
        "hive_partitioning = true) GROUP BY episode ORDER BY episode"
    ).fetchall()
    assert counts == local and len(counts) == EPISODES


def test_a_run_killed_mid_shard_resumes_and_no_half_shard_is_ever_read(server, tmp_path):
    uri = f"s3://{BUCKET}/killed"
    store = open_store(uri)
    args = [*ARGS[:3], str(KILL_EPISODES), *ARGS[4:]]
    process = subprocess.Popen(
        [*CLI, "generate", *args, "--out", uri],
        cwd=REPO_ROOT,
        env=os.environ | server,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    # Killed once two shards are committed: the third is being simulated or written.
    kill_when(process, lambda: len(store.sizes("_commits")) >= 2, poll_s=0.01)
    left = objects(uri)
    commits = sorted(n for n in left if n.startswith("_commits/"))
    assert 2 <= len(commits) < KILL_EPISODES, "the run was not killed mid-way"
    assert ".generate.lock" in left  # the killed run's
    # A half-written shard (what a store without whole-object writes, or a copy cut short,
    # leaves) where the next episode goes: never read, never taken for done.
    k = len(commits)
    half = f"data/scenario={SCENARIO}/episode={k}/part.parquet"
    whole = store.read(f"data/scenario={SCENARIO}/episode=0/part.parquet")
    store.write(half, whole[: len(whole) // 2])
    with pytest.raises(DataFormatError, match=r"field 'complete': expected true"):
        read_parquet(uri)
    partial = read_parquet(uri, allow_incomplete=True)
    assert partial.sequences() == tuple(f"{SCENARIO}-{i}" for i in range(len(commits)))
    assert any(half in p and "no commit names" in p for p in partial.metadata["incomplete"])

    # The same command again: the killed run's lock is taken over, the half shard rewritten.
    run = subprocess.run(
        [*CLI, "generate", *args, "--out", uri],
        cwd=REPO_ROOT,
        env=os.environ | server,
        capture_output=True,
        timeout=RUN_TIMEOUT_S,
        text=True,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    assert f"({KILL_EPISODES - len(commits)} generated, {len(commits)} already there)" in run.stdout
    after = objects(uri)
    assert not any(n.startswith(("_commits/", ".generate.lock")) for n in after)
    assert verify_folder(uri) == []
    reference = tmp_path / "reference"
    generate(reference, episodes=KILL_EPISODES)
    same_as_reference(uri, reference, KILL_EPISODES)
    assert open_store(uri).read(CARD_JSON) == (reference / CARD_JSON).read_bytes()


def test_two_writers_on_one_prefix_are_refused(server):
    uri = f"s3://{BUCKET}/locked"
    store = open_store(uri)
    other = {"host": "node-7", "pid": 4242, "started": "2026-01-01T00:00:00Z"}
    assert store.create(".generate.lock", json.dumps(other).encode())
    with pytest.raises(
        ValueError,
        match=r"being written by another reform-sim generate run "
        r"\(host node-7, process 4242",
    ):
        generate(uri, episodes=1)
    assert sorted(objects(uri)) == [".generate.lock"]  # nothing else written
    # A lock of a run of this machine whose process is gone is taken over.
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    gone = {"host": socket.gethostname(), "pid": int(dead.stdout), "started": "then"}
    store.write(".generate.lock", json.dumps(gone).encode())
    report = generate(uri, episodes=1)
    assert report.generated == (0,) and ".generate.lock" not in objects(uri)
    # Only one of two writers gets a lock object (S3: a PUT with If-None-Match: *).
    assert store.create("race", b"first") and not store.create("race", b"second")
    assert store.read("race") == b"first"


def _one_line(capsys, argv) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err, err
    return err


def test_a_bad_store_is_refused_in_one_line_before_any_work(server, capsys, monkeypatch):
    out = ["generate", *ARGS, "--out"]
    err = _one_line(capsys, [*out, "s3://no-such-bucket/ds"])
    assert "bucket 'no-such-bucket' does not exist" in err
    # A prefix holding another dataset, or other objects.
    uri = f"s3://{BUCKET}/other"
    generate(uri, episodes=1, seed=SEED + 1)
    err = _one_line(capsys, [*out, uri])
    assert f"--out {uri} holds another dataset" in err and "seed" in err
    open_store(f"s3://{BUCKET}/foreign").write("notes.txt", b"mine")
    err = _one_line(capsys, [*out, f"s3://{BUCKET}/foreign"])
    assert "holds objects but no dataset card" in err and "notes.txt" in err
    # No credentials.
    for key in ("AWS_ACCESS_KEY_ID", "AWS_SECRET_ACCESS_KEY"):
        monkeypatch.delenv(key)
    monkeypatch.setenv("AWS_SHARED_CREDENTIALS_FILE", "/nonexistent")
    monkeypatch.setenv("AWS_CONFIG_FILE", "/nonexistent")
    _clear_cache()
    err = _one_line(capsys, [*out, f"s3://{BUCKET}/nocreds"])
    assert "no credentials for s3://" in err and "AWS_ACCESS_KEY_ID" in err
    assert main(["data", "info", "--data", f"s3://{BUCKET}/same"]) == 2
    assert "no credentials for s3://" in capsys.readouterr().err
    monkeypatch.undo()
    # A store that cannot be reached.
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        closed = sock.getsockname()[1]
    monkeypatch.setenv("AWS_ENDPOINT_URL", f"http://127.0.0.1:{closed}")
    _clear_cache()
    err = _one_line(capsys, [*out, f"s3://{BUCKET}/unreachable"])
    assert f"cannot reach the store at http://127.0.0.1:{closed}" in err
    monkeypatch.undo()
    _clear_cache()
    assert not any(n.startswith(("nocreds", "unreachable")) for n in objects(f"s3://{BUCKET}"))
    with pytest.raises(StoreError, match=r"cannot open a nosuch:// store"):
        open_store("nosuch://x/y")


def test_commands_that_write_local_files_refuse_a_uri(reference, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    err = _one_line(
        capsys, ["data", "convert", "--data", str(reference), "--out", "s3://lab-data/x.parquet"]
    )
    assert "--out s3://lab-data/x.parquet: expected a path on this machine" in err
    assert not (tmp_path / "s3:").exists()


def test_data_commands_read_a_dataset_in_the_store(server, capsys):
    uri = f"s3://{BUCKET}/cli"
    assert main(["generate", *ARGS, "--out", uri]) == 0
    assert uri in capsys.readouterr().out
    assert main(["data", "verify", "--data", uri]) == 0
    assert "whole" in capsys.readouterr().out
    assert main(["data", "info", "--data", uri, "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["frames"] == EPISODES * int(DURATION_S * 2)
    # An altered shard is named by its URI.
    store = open_store(uri)
    shard = f"data/scenario={SCENARIO}/episode=1/part.parquet"
    content = bytearray(store.read(shard))
    content[100] ^= 0xFF
    store.write(shard, bytes(content))
    assert main(["data", "verify", "--data", uri]) == 1
    assert f"{uri}/{shard}: field 'sha256'" in capsys.readouterr().out


def test_ray_workers_write_their_shards_to_the_store(server, reference, ray_restarted):
    uri = f"s3://{BUCKET}/ray"
    report = generate(uri, backend="ray")
    assert report.backend == "ray" and report.n_jobs == 2
    same_as_reference(uri, reference)
    assert open_store(uri).read(CARD_JSON) == (reference / CARD_JSON).read_bytes()


def test_any_fsspec_filesystem_is_a_store(reference):
    uri = "memory://reform-sim-test/ds"  # fsspec's in-memory filesystem, this process only
    generate(uri)
    same_as_reference(uri, reference)
    assert read_parquet(uri).frames == read_parquet(reference).frames
    assert verify_folder(uri) == []


def test_a_filesystem_not_installed_is_named_with_its_install_command():
    try:
        import gcsfs  # noqa: F401
    except ImportError:
        with pytest.raises(StoreError, match=r"gs://lab/ds: cannot open a gs:// store .*gcsfs"):
            open_store("gs://lab/ds")
    else:
        pytest.skip("gcsfs is installed")


def test_local_workers_see_the_credentials_as_they_are_now(server, reference, monkeypatch):
    from joblib import Parallel, delayed

    for key in server:  # a pool of workers started before the credentials were set
        monkeypatch.delenv(key)
    assert Parallel(n_jobs=2, backend="loky")(delayed(os.getenv)(k) for k in server) == [
        None
    ] * len(server)
    monkeypatch.undo()
    uri = f"s3://{BUCKET}/pool"
    assert generate(uri, n_jobs=2).n_jobs == 2
    same_as_reference(uri, reference)


def test_a_resume_makes_a_damaged_object_again_and_never_vouches_for_it(server, reference, capsys):
    uri = f"s3://{BUCKET}/damaged"
    generate(uri)
    store = open_store(uri)
    shard = f"data/scenario={SCENARIO}/episode=1/part.parquet"
    before = store.read(shard)
    store.write(shard, one_float_changed(before))  # one float changed, the same size
    assert objects(uri)[shard] == len(before)
    (problem,) = verify_folder(uri)
    assert f"{uri}/{shard}: field 'sha256'" in problem
    capsys.readouterr()

    report = generate(uri)  # the same dataset again, over its complete prefix
    assert report.generated == (1,) and report.skipped == (0, 2, 3)
    (line,) = [x for x in capsys.readouterr().err.splitlines() if "is damaged" in x]
    assert line.startswith(f"reform-sim generate: {uri}/{shard} is damaged (sha256 ")
    same_as_reference(uri, reference)
    assert store.read(CARD_JSON) == (reference / CARD_JSON).read_bytes()
    assert verify_folder(uri) == []


@contextlib.contextmanager
def _freezable(host: str, port: int) -> Iterator[tuple[int, threading.Event]]:
    """A TCP proxy on 127.0.0.1 in front of ``host:port``, and the event that freezes it: from
    then on it accepts connections and takes requests, and answers nothing."""
    frozen = threading.Event()
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(64)
    listener.settimeout(0.1)
    stop = threading.Event()
    opened: list[socket.socket] = []

    def pump(source: socket.socket, target: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while data := source.recv(65536):
                while frozen.is_set() and not stop.is_set():
                    time.sleep(0.05)
                target.sendall(data)

    def serve() -> None:
        while not stop.is_set():
            try:
                client = listener.accept()[0]
            except TimeoutError:
                continue
            opened.append(client)
            if frozen.is_set():
                continue
            upstream = socket.create_connection((host, port))
            opened.append(upstream)
            for ends in ((client, upstream), (upstream, client)):
                threading.Thread(target=pump, args=ends, daemon=True).start()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield listener.getsockname()[1], frozen
    finally:
        stop.set()
        thread.join()
        for connection in opened:
            connection.close()
        listener.close()


def test_a_store_that_stops_answering_mid_run_ends_it_in_one_line(server):
    """The store freezes once two shards are committed: the run ends within its deadline (plus
    10 s) with one line naming the object (or the dataset's prefix, when the store froze as the
    run listed it), the operation and the deadline."""
    deadline_s = 2.0
    endpoint = server["AWS_ENDPOINT_URL"].removeprefix("http://")
    host, port = endpoint.rsplit(":", 1)
    uri = f"s3://{BUCKET}/frozen"
    store = open_store(uri)
    args = [*ARGS[:3], str(KILL_EPISODES), *ARGS[4:]]
    with _freezable(host, int(port)) as (proxy, frozen):
        env = os.environ | server | {"AWS_ENDPOINT_URL": f"http://127.0.0.1:{proxy}"}
        process = subprocess.Popen(
            [*CLI, "generate", *args, "--out", uri],
            cwd=REPO_ROOT,
            env=env | {"REFORM_SIM_STORE_TIMEOUT": f"{deadline_s:g}"},
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )
        try:
            ready = time.monotonic() + RUN_TIMEOUT_S
            while len(store.sizes("_commits")) < 2 and time.monotonic() < ready:
                time.sleep(0.02)
            frozen.set()
            started = time.monotonic()
            _, err = process.communicate(timeout=deadline_s + 10 + 30)
            seconds = time.monotonic() - started
        finally:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)
    assert seconds < deadline_s + 10
    assert process.returncode == 2
    (line,) = err.splitlines()
    assert re.fullmatch(
        rf"reform-sim generate: error: {uri}(?:/\S+)?: the store did not answer within 2 s "
        r"\(\w+\); "
        r"check the store and the network, or give it longer with "
        r"REFORM_SIM_STORE_TIMEOUT=SECONDS",
        line,
    )


def test_a_resume_checks_each_committed_object_it_keeps(server, tmp_path):
    """A run killed mid-way, one of its committed shards then damaged (one float, same size):
    the resume names it on stderr, writes it again, and the dataset is whole."""
    uri = f"s3://{BUCKET}/killed-damaged"
    store = open_store(uri)
    args = [*ARGS[:3], str(KILL_EPISODES), *ARGS[4:]]
    command = [*CLI, "generate", *args, "--out", uri]
    process = subprocess.Popen(
        command,
        cwd=REPO_ROOT,
        env=os.environ | server,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    kill_when(process, lambda: len(store.sizes("_commits")) >= 2, poll_s=0.01)
    committed = len([n for n in objects(uri) if n.startswith("_commits/")])
    assert 2 <= committed < KILL_EPISODES, "the run was not killed mid-way"
    shard = f"data/scenario={SCENARIO}/episode=0/part.parquet"
    store.write(shard, one_float_changed(store.read(shard)))

    run = subprocess.run(
        command,
        cwd=REPO_ROOT,
        env=os.environ | server,
        capture_output=True,
        timeout=RUN_TIMEOUT_S,
        text=True,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    (line,) = [x for x in run.stderr.splitlines() if "is damaged" in x]
    assert line.startswith(f"reform-sim generate: {uri}/{shard} is damaged (sha256 ")
    kept = committed - 1
    assert f"({KILL_EPISODES - kept} generated, {kept} already there)" in run.stdout
    assert verify_folder(uri) == []
    reference = tmp_path / "reference"
    generate(reference, episodes=1)
    same_as_reference(uri, reference, episodes=1)


# A child that begins a multipart upload of ARGV[2] in the store at ARGV[1] (as s3fs sends an
# object of 100 MiB and more), sends its first part, says the upload's ID and waits to be killed.
UPLOADER = (
    "import sys, time\n"
    "from reform.datasets.store import open_store\n"
    "store = open_store(sys.argv[1])\n"
    "bucket, key, _ = store.fs.split_path(store.path(sys.argv[2]))\n"
    "upload = store.fs.call_s3('create_multipart_upload', Bucket=bucket, Key=key)['UploadId']\n"
    "store.fs.call_s3('upload_part', Bucket=bucket, Key=key, UploadId=upload, PartNumber=1,\n"
    "                 Body=b'half a shard' * 1000)\n"
    "print(upload, flush=True)\n"
    "time.sleep(600)\n"
)


def _killed_uploader(uri: str, relative: str) -> str:
    """The ID of the upload of a child killed (SIGKILL) while it sent ``relative``."""
    child = subprocess.Popen(
        [sys.executable, "-c", UPLOADER, uri, relative], stdout=subprocess.PIPE, text=True
    )
    upload = child.stdout.readline().strip()
    child.kill()
    child.wait(timeout=RUN_TIMEOUT_S)
    child.stdout.close()
    assert upload, "the child ended before it sent a part"
    return upload


def test_data_verify_lists_what_killed_runs_left_in_the_store_and_the_next_run_removes_it(
    server, capsys
):
    """An upload a killed writer never finished (no object, but its parts kept and billed) and
    a lock of a killed run are listed, with the upload's size and age, never removed by verify;
    none while a live run holds the lock; the next run in the prefix removes them."""
    uri = f"s3://{BUCKET}/leftovers"
    generate(uri, episodes=1)
    store = open_store(uri)
    relative = f"data/scenario={SCENARIO}/episode=1/part.parquet"  # the next run's
    upload = _killed_uploader(uri, relative)
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    gone = {
        "host": socket.gethostname(),
        "pid": int(dead.stdout),
        "started": "2026-12-05T10:00:00Z",
    }
    store.write(".generate.lock", json.dumps(gone).encode())

    assert main(["data", "verify", "--data", uri]) == 0
    first, *rest = capsys.readouterr().out.splitlines()
    assert re.fullmatch(
        rf"{re.escape(uri)}/{re.escape(relative)}: an unfinished upload \(11\.7 KiB sent, last "
        rf"written [\d.]+ s ago; upload ID {re.escape(upload)}\) of a run that did not finish; "
        "the next generate run in this prefix removes it",
        first,
    )
    assert rest == [
        f"{uri}/.generate.lock: a lock left by a run that did not finish (process {gone['pid']} "
        "of this machine, gone, since 2026-12-05T10:00:00Z); the next generate run in this "
        "prefix takes it over",
        f"{uri}: whole (every shard its card lists is there, unaltered); 2 leftover(s) of runs "
        "that did not finish, listed above",
    ]
    assert [u.upload_id for u in store.uploads()] == [upload]  # listed, not removed

    # A run of this machine that holds the lock now may be sending the upload: nothing listed.
    live = {"host": socket.gethostname(), "pid": os.getpid(), "started": "now"}
    store.write(".generate.lock", json.dumps(live).encode())
    assert main(["data", "verify", "--data", uri]) == 0
    assert (
        capsys.readouterr().out
        == f"{uri}: whole (every shard its card lists is there, unaltered)\n"
    )

    store.write(".generate.lock", json.dumps(gone).encode())
    generate(uri, episodes=2)
    assert store.uploads() == [] and ".generate.lock" not in objects(uri)
    assert main(["data", "verify", "--data", uri]) == 0
    assert (
        capsys.readouterr().out
        == f"{uri}: whole (every shard its card lists is there, unaltered)\n"
    )
