"""What a killed writer leaves behind is removed by the next write into that folder, and nothing
else: each writer is a real process killed with SIGKILL mid-write (an atomic write, a download
from a mirror that trickles)."""

from __future__ import annotations

import contextlib
import hashlib
import http.server
import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from reform.atomic import atomic_open, atomic_path, remove_stale_temporaries, temporary_folder
from reform.datasets import fetch
from reform.datasets.fetch import MANIFEST

pytestmark = [
    pytest.mark.faults,
    pytest.mark.skipif(os.name != "posix", reason="kills processes with SIGKILL"),
]

WAIT_S = 60.0  # seconds a child has to get to the middle of its write (the machine is shared)
# A child that starts an atomic write of ARGV[1], says so on stdout, and waits to be killed.
WRITER = (
    "import sys, time\n"
    "from reform.atomic import atomic_path\n"
    "with atomic_path(sys.argv[1]) as tmp:\n"
    "    tmp.write_bytes(b'half a file' * 1000)\n"
    "    print(tmp.name, flush=True)\n"
    "    time.sleep(600)\n"
)


def _wait_until(ready: Callable[[], bool], process: subprocess.Popen) -> None:
    deadline = time.monotonic() + WAIT_S
    while not ready():
        assert process.poll() is None, "the child ended before it was killed"
        assert time.monotonic() < deadline, "the child did not get to its write"
        time.sleep(0.05)


def _kill(process: subprocess.Popen) -> None:
    process.send_signal(signal.SIGKILL)
    process.wait(timeout=WAIT_S)  # reaped: its process id is free


@contextlib.contextmanager
def _writing(target: Path) -> Iterator[tuple[subprocess.Popen, str]]:
    """A child process in the middle of an atomic write of ``target``: it and its temporary
    file's name. Killed at the end if still alive."""
    process = subprocess.Popen(
        [sys.executable, "-c", WRITER, str(target)], stdout=subprocess.PIPE, text=True
    )
    try:
        name = process.stdout.readline().strip()
        assert name, "the child wrote nothing"
        yield process, name
    finally:
        if process.poll() is None:
            _kill(process)
        process.stdout.close()


def test_a_killed_writers_temporary_is_removed_by_the_next_write_there(tmp_path):
    with _writing(tmp_path / "big.rrd") as (process, name):
        _kill(process)
    assert (tmp_path / name).stat().st_size == len(b"half a file" * 1000)  # left behind
    assert name.startswith(f".big.rrd.{process.pid}@") and name.endswith(".tmp")
    with atomic_open(tmp_path / "report.json") as handle:  # another file, the same folder
        handle.write("{}")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]


def test_a_live_writers_temporary_and_other_files_are_left_alone(tmp_path):
    others = [
        ".big.rrd.abcd1234.tmp",  # the naming before writers were named: nobody's to judge
        ".big.rrd.999999999@abcdef.abcd1234.tmp",  # another machine's (host tag) writer
        "notes.tmp",
        ".hidden",
    ]
    for name in others:
        (tmp_path / name).write_text("not ours to remove")
    with _writing(tmp_path / "big.rrd") as (process, name):
        removed = remove_stale_temporaries(tmp_path)
        assert removed == []
        assert (tmp_path / name).exists()  # its writer is alive
        assert process.poll() is None
        assert sorted(p.name for p in tmp_path.iterdir()) == sorted([*others, name])


def test_a_killed_writers_temporary_folder_is_removed_too(tmp_path):
    child = (
        "import sys, time\n"
        "from reform.atomic import temporary_folder\n"
        "with temporary_folder(sys.argv[1]) as scratch:\n"
        "    (scratch / 'tmpdownload').write_bytes(b'x' * 100)\n"
        "    print(scratch.name, flush=True)\n"
        "    time.sleep(600)\n"
    )
    process = subprocess.Popen(
        [sys.executable, "-c", child, str(tmp_path / "data.bin")], stdout=subprocess.PIPE, text=True
    )
    with process.stdout:
        name = process.stdout.readline().strip()
    _kill(process)
    assert (tmp_path / name / "tmpdownload").exists()
    assert remove_stale_temporaries(tmp_path) == [tmp_path / name]
    assert list(tmp_path.iterdir()) == []


def test_a_write_cleans_a_folder_once_per_process(tmp_path, monkeypatch):
    """A folder is listed on this process's first write there, not on every write."""
    import reform.atomic as atomic

    looked = []
    monkeypatch.setattr(atomic, "remove_stale_temporaries", looked.append)
    monkeypatch.setattr(atomic, "_cleaned", set())
    for k in range(3):
        with atomic_path(tmp_path / f"part{k}.bin") as tmp:
            tmp.write_bytes(b"x")
    with temporary_folder(tmp_path / "other.bin"):
        pass
    assert looked == [tmp_path]


# -- a fetch killed while its mirror trickles ----------------------------------------------

REPO, COMMIT = "lab/fformations", "1" * 40
DATA = b"seq1 features\n" * 40


class _Trickle(http.server.BaseHTTPRequestHandler):
    """Serves DATA a byte at a time, every 0.1 s: a download that is still going when killed."""

    def do_GET(self) -> None:
        self.send_response(200)
        self.send_header("Content-Length", str(len(DATA)))
        self.end_headers()
        for k in range(len(DATA)):
            try:
                self.wfile.write(DATA[k : k + 1])
                self.wfile.flush()
            except OSError:  # the client has gone
                return
            time.sleep(0.1)

    def log_message(self, format: str, *args) -> None:  # noqa: A002 - the base's signature
        pass


@pytest.fixture()
def trickling_mirror() -> Iterator[str]:
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Trickle)
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()
        thread.join()


def test_a_killed_fetchs_temporary_file_is_removed_by_the_next_fetch(tmp_path, trickling_mirror):
    registry = tmp_path / "registry.json"
    path = "data/Tiny/features.txt"
    registry.write_text(
        json.dumps(
            {
                "about": "one made-up dataset",
                "datasets": [
                    {
                        "name": "tiny",
                        "title": "The tiny set",
                        "format": "dante-txt",
                        "units": "m",
                        "repo": REPO,
                        "files": [
                            {
                                "path": path,
                                "commit": COMMIT,
                                "bytes": len(DATA),
                                "sha256": hashlib.sha256(DATA).hexdigest(),
                            }
                        ],
                        "citation": "Nobody et al. 2024",
                        "notes": "made up",
                    }
                ],
            }
        )
    )
    cache = tmp_path / "cache"
    child = (
        "import sys\nfrom reform.datasets import fetch\n"
        "fetch('tiny', mirror=sys.argv[1], cache=sys.argv[2], registry=sys.argv[3])\n"
    )
    process = subprocess.Popen(
        [sys.executable, "-c", child, trickling_mirror, str(cache), str(registry)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )

    def downloading() -> bool:  # pooch's temporary file made, its bytes coming
        return any(p.is_file() for p in cache.rglob("*.tmp/*"))

    try:
        _wait_until(downloading, process)
    finally:
        _kill(process)
    left = [p.relative_to(cache).as_posix() for p in cache.rglob("*") if p.is_file()]
    assert len(left) == 1 and left[0].startswith(f"tiny/.features.txt.{process.pid}@"), left

    mirror = tmp_path / "mirror" / REPO / COMMIT / path
    mirror.parent.mkdir(parents=True)
    mirror.write_bytes(DATA)
    folder = fetch("tiny", mirror=tmp_path / "mirror", cache=cache, registry=registry)
    assert (folder / "features.txt").read_bytes() == DATA
    assert sorted(p.name for p in folder.iterdir()) == sorted(["features.txt", MANIFEST])
