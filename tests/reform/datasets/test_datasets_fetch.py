"""Fetching the public datasets: `reform.datasets.fetch`, `resolve`, the packaged registry and
``reform-sim datasets``, against mirrors served from temporary folders on 127.0.0.1."""

from __future__ import annotations

import contextlib
import hashlib
import http.server
import json
import os
import pickle
import re
import shutil
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from cli_errors import cli_error

from reform.datasets import (
    DataFormatError,
    FetchError,
    cache_dir,
    fetch,
    is_fetched,
    load_dataset,
    local_datasets_dir,
    one_per_recording,
    registry,
    resolve,
)
from reform.datasets.fetch import MANIFEST, download_deadline
from sim.cli import main

pytestmark = pytest.mark.faults  # the fault suite: pytest -m faults

REPO_ROOT = Path(__file__).resolve().parents[3]
REPO = "lab/fformations"
COMMIT = "1" * 40
OTHER_COMMIT = "2" * 40
# Two synthetic datasets: "tiny" shares a folder prefix (dropped locally) and has sequences in
# subfolders; "flat" has its files at the repository's root, each at its own commit.
FILES = {
    "tiny": [
        ("data/octave/Tiny/Seq1/features.txt", COMMIT, b"seq1 features\n" * 40),
        ("data/octave/Tiny/Seq1/groundtruth.txt", COMMIT, b"seq1 groups\n"),
        ("data/octave/Tiny/Seq2/features.txt", COMMIT, b"seq2 features\n" * 7),
    ],
    "flat": [
        ("Motion.csv", COMMIT, b"a,b\n1,2\n"),
        ("annotated.csv", OTHER_COMMIT, b"frame\n5\n"),
    ],
}
TINY_LOCAL = ["Seq1/features.txt", "Seq1/groundtruth.txt", "Seq2/features.txt"]


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _registry_document(files: dict[str, list[tuple[str, str, bytes]]]) -> dict:
    return {
        "about": "synthetic datasets for the tests",
        "datasets": [
            {
                "name": name,
                "title": f"The {name} set",
                "format": "dante-txt",
                "units": "m",
                "repo": REPO,
                "files": [
                    {"path": path, "commit": commit, "bytes": len(data), "sha256": _sha256(data)}
                    for path, commit, data in entries
                ],
                "citation": "Nobody et al. 2024",
                "notes": "made up; licence CC0" if name == "flat" else "made up",
            }
            for name, entries in files.items()
        ],
    }


@pytest.fixture()
def registry_file(tmp_path: Path) -> Path:
    path = tmp_path / "registry.json"
    path.write_text(json.dumps(_registry_document(FILES)))
    return path


@pytest.fixture()
def mirror_dir(tmp_path: Path) -> Path:
    """A mirror laid out as ``<repo>/<commit>/<path>``."""
    root = tmp_path / "mirror"
    for entries in FILES.values():
        for path, commit, data in entries:
            target = root / REPO / commit / path
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
    return root


class _Server(http.server.ThreadingHTTPServer):
    requests: list[str]
    # path -> (bytes sent, Content-Length announced): a download that stops early.
    truncate: dict[str, tuple[int, int]]
    # path -> seconds between bytes: a mirror that trickles, each byte in time for a read timeout.
    trickle: dict[str, float]
    # paths sent without end, as fast as they are read: the file, then zeros until the client goes.
    endless: set[str]


class _Handler(http.server.SimpleHTTPRequestHandler):
    server: _Server

    def do_GET(self) -> None:
        self.server.requests.append(self.path)
        if self.path in self.server.trickle:
            self._trickle(self.server.trickle[self.path])
            return
        if self.path in self.server.endless:
            self._endless()
            return
        cut = self.server.truncate.get(self.path)
        if cut is None:
            super().do_GET()
            return
        sent, announced = cut
        data = Path(self.translate_path(self.path)).read_bytes()
        self.send_response(200)
        self.send_header("Content-Length", str(announced))
        self.end_headers()
        self.wfile.write(data[:sent])
        self.close_connection = True

    def _trickle(self, every_s: float) -> None:
        data = Path(self.translate_path(self.path)).read_bytes()
        self.send_response(200)
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.close_connection = True
        for k in range(len(data)):
            try:
                self.wfile.write(data[k : k + 1])
                self.wfile.flush()
            except OSError:  # the client has gone
                return
            time.sleep(every_s)

    def _endless(self) -> None:
        self.send_response(200)
        self.end_headers()  # no Content-Length: the body ends when the connection does
        self.close_connection = True
        chunk = Path(self.translate_path(self.path)).read_bytes()
        while True:
            try:
                self.wfile.write(chunk)
            except OSError:  # the client has gone
                return
            chunk = bytes(64 * 1024)

    def log_message(self, format: str, *args) -> None:  # noqa: A002 - the base's signature
        pass


@contextlib.contextmanager
def _serve(root: Path) -> Iterator[tuple[str, _Server]]:
    def handler(*args, **kwargs):
        return _Handler(*args, directory=str(root), **kwargs)

    server = _Server(("127.0.0.1", 0), handler)
    server.requests = []
    server.truncate = {}
    server.trickle = {}
    server.endless = set()
    thread = threading.Thread(target=server.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}", server
    finally:
        server.shutdown()
        server.server_close()
        thread.join()


@pytest.fixture()
def http_mirror(mirror_dir: Path) -> Iterator[tuple[str, _Server]]:
    with _serve(mirror_dir) as served:
        yield served


@pytest.fixture()
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A fresh cache, also made the default one ($REFORM_SIM_DATA)."""
    folder = tmp_path / "cache"
    monkeypatch.setenv("REFORM_SIM_DATA", str(folder))
    return folder


def _url(base: str, name: str, k: int) -> str:
    path, commit, _ = FILES[name][k]
    return f"{base}/{REPO}/{commit}/{path}"


def _assert_nothing_looks_complete(cache: Path, name: str, registry_file: Path) -> None:
    """No manifest, every file left in the dataset's folder is a verified file under its final
    name (no partial download, no temporary file), and no folder is left empty."""
    folder = cache / name
    assert not (folder / MANIFEST).exists()
    assert not is_fetched(name, cache, registry=registry_file)
    (dataset,) = [d for d in registry(registry_file) if d.name == name]
    expected = dict(zip(dataset.local_names, FILES[name], strict=True))
    left = [p for p in folder.rglob("*") if p.is_file()] if folder.exists() else []
    for path in left:
        local = path.relative_to(folder).as_posix()
        assert local in expected, f"unexpected file left: {local}"
        assert path.read_bytes() == expected[local][2], f"unverified file left: {local}"
    folders = [folder, *folder.rglob("*")] if folder.exists() else []
    empty = [p for p in folders if p.is_dir() and not any(q.is_file() for q in p.rglob("*"))]
    assert not empty, f"empty folders left: {empty}"  # no empty shell of the dataset


def _assert_fetch_fails(
    base: str, name: str, k: int, found: str, cache: Path, registry_file: Path, *, ends=True
) -> FetchError:
    """Fetching ``name`` from ``base`` fails on its file ``k`` with the one message
    ``<file>: dataset '<name>' from <url>: <found>`` (followed by more when not ``ends``), and
    leaves nothing that looks complete (`_assert_nothing_looks_complete`)."""
    expected = f"{FILES[name][k][0]}: dataset '{name}' from {_url(base, name, k)}: {found}"
    with pytest.raises(
        FetchError, match=f"^{re.escape(expected)}" + ("$" if ends else "")
    ) as caught:
        fetch(name, mirror=base, cache=cache, registry=registry_file)
    _assert_nothing_looks_complete(cache, name, registry_file)
    return caught.value


# --- fetching ------------------------------------------------------------------------------


def test_fetch_over_http_lays_out_the_dataset_without_its_common_folders(
    http_mirror, cache, registry_file
):
    base, server = http_mirror
    folder = fetch("tiny", mirror=base, cache=cache, registry=registry_file)
    assert folder == cache / "tiny"
    files = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())
    assert files == sorted([*TINY_LOCAL, MANIFEST])
    for local, (_, _, data) in zip(TINY_LOCAL, FILES["tiny"], strict=True):
        assert (folder / local).read_bytes() == data
    assert sorted(server.requests) == sorted(
        f"/{REPO}/{commit}/{path}" for path, commit, _ in FILES["tiny"]
    )
    manifest = json.loads((folder / MANIFEST).read_text())
    assert manifest["source"] == base
    assert [f["name"] for f in manifest["files"]] == TINY_LOCAL
    assert is_fetched("tiny", cache, registry=registry_file)
    assert not is_fetched("flat", cache, registry=registry_file)


def test_files_at_the_repository_root_keep_their_names_and_each_its_commit(
    http_mirror, cache, registry_file
):
    base, server = http_mirror
    folder = fetch("flat", mirror=base, cache=cache, registry=registry_file)
    assert (folder / "Motion.csv").read_bytes() == FILES["flat"][0][2]
    assert (folder / "annotated.csv").read_bytes() == FILES["flat"][1][2]
    assert f"/{REPO}/{OTHER_COMMIT}/annotated.csv" in server.requests


def test_a_second_fetch_downloads_nothing(http_mirror, cache, registry_file):
    base, server = http_mirror
    first = fetch("tiny", mirror=base, cache=cache, registry=registry_file)
    count = len(server.requests)
    assert count == 3
    assert fetch("tiny", mirror=base, cache=cache, registry=registry_file) == first
    assert len(server.requests) == count


def test_a_fetch_completes_what_an_earlier_one_left(http_mirror, cache, registry_file):
    base, server = http_mirror
    server.truncate[f"/{REPO}/{COMMIT}/{FILES['tiny'][2][0]}"] = (3, 3)
    with pytest.raises(FetchError):
        fetch("tiny", mirror=base, cache=cache, registry=registry_file)
    server.truncate.clear()
    server.requests.clear()
    fetch("tiny", mirror=base, cache=cache, registry=registry_file)
    assert server.requests == [f"/{REPO}/{COMMIT}/{FILES['tiny'][2][0]}"]  # only the missing one


def test_a_damaged_cached_file_is_fetched_again(http_mirror, cache, registry_file):
    base, server = http_mirror
    folder = fetch("tiny", mirror=base, cache=cache, registry=registry_file)
    damaged = folder / TINY_LOCAL[0]
    data = damaged.read_bytes()
    damaged.write_bytes(b"X" + data[1:])  # same size: only the sha256 tells
    assert not is_fetched("tiny", cache, registry=registry_file)
    server.requests.clear()
    fetch("tiny", mirror=base, cache=cache, registry=registry_file)
    assert server.requests == [f"/{REPO}/{COMMIT}/{FILES['tiny'][0][0]}"]
    assert damaged.read_bytes() == data


def test_a_fetched_copy_changed_since_is_named_not_called_unfetched(
    http_mirror, cache, registry_file, tmp_path, monkeypatch
):
    base, _ = http_mirror
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("REFORM_SIM_DATASETS", raising=False)
    folder = fetch("tiny", mirror=base, cache=cache, registry=registry_file)
    damaged = folder / TINY_LOCAL[0]
    damaged.write_bytes(b"X" + damaged.read_bytes()[1:])
    with pytest.raises(FileNotFoundError) as raised:
        resolve("tiny", registry=registry_file)
    assert str(raised.value).startswith(
        f"dataset 'tiny' in the cache has changed since it was fetched: {damaged}: expected "
        "sha256 "
    )
    assert str(raised.value).endswith(
        "as fetched, found another; fetch it again: `reform-sim datasets fetch tiny`"
    )


def test_a_cached_file_of_the_wrong_size_is_not_fetched(http_mirror, cache, registry_file):
    base, _ = http_mirror
    folder = fetch("tiny", mirror=base, cache=cache, registry=registry_file)
    (folder / TINY_LOCAL[1]).write_bytes(b"short")
    assert not is_fetched("tiny", cache, registry=registry_file)


@pytest.mark.parametrize("kind", ["file-url", "folder"])
def test_fetch_from_a_local_mirror(kind, mirror_dir, cache, registry_file):
    mirror = mirror_dir.as_uri() if kind == "file-url" else str(mirror_dir)
    folder = fetch("tiny", mirror=mirror, cache=cache, registry=registry_file)
    assert (folder / TINY_LOCAL[2]).read_bytes() == FILES["tiny"][2][2]
    assert is_fetched("tiny", cache, registry=registry_file)
    assert json.loads((folder / MANIFEST).read_text())["source"] == mirror_dir.resolve().as_uri()


def test_the_default_cache_is_reform_sim_data(http_mirror, cache, registry_file):
    base, _ = http_mirror
    assert cache_dir() == cache
    assert fetch("tiny", mirror=base, registry=registry_file) == cache / "tiny"


def test_the_default_cache_is_the_user_data_folder(monkeypatch):
    monkeypatch.delenv("REFORM_SIM_DATA", raising=False)
    import platformdirs

    assert cache_dir() == Path(platformdirs.user_data_dir("reform-sim", appauthor=False))


def test_progress_bars_name_each_file_on_stderr(http_mirror, cache, registry_file, capsys):
    base, _ = http_mirror
    fetch("tiny", mirror=base, cache=cache, registry=registry_file, progress=True)
    err = capsys.readouterr().err
    for local in TINY_LOCAL:
        assert f"tiny {local}: " in err
    assert "/560 [" in err  # the bar's total: Seq1/features.txt's 560 bytes
    fetch("tiny", mirror=base, cache=cache, registry=registry_file, progress=True)
    assert capsys.readouterr().err == ""  # nothing downloaded, nothing shown


def test_fetched_files_have_the_permissions_of_a_plain_open(http_mirror, cache, registry_file):
    base, _ = http_mirror
    folder = fetch("tiny", mirror=base, cache=cache, registry=registry_file)
    umask = os.umask(0)
    os.umask(umask)
    assert (folder / TINY_LOCAL[0]).stat().st_mode & 0o777 == 0o666 & ~umask


# --- failures: one FetchError, nothing that looks complete ---------------------------------


def test_a_wrong_checksum(http_mirror, mirror_dir, cache, registry_file):
    base, _ = http_mirror
    path, commit, data = FILES["tiny"][1]
    forged = b"S" + data[1:]
    (mirror_dir / REPO / commit / path).write_bytes(forged)
    found = f"expected sha256 {_sha256(data)}, found sha256 {_sha256(forged)}"
    error = _assert_fetch_fails(base, "tiny", 1, found, cache, registry_file)
    assert (error.dataset, error.file) == ("tiny", path)
    assert not (cache / "tiny" / TINY_LOCAL[1]).exists()


def test_a_truncated_download_with_an_honest_length(http_mirror, cache, registry_file):
    base, server = http_mirror
    path, commit, data = FILES["tiny"][0]
    server.truncate[f"/{REPO}/{commit}/{path}"] = (100, 100)
    found = f"expected {len(data)} bytes, found 100 bytes"
    _assert_fetch_fails(base, "tiny", 0, found, cache, registry_file)


def test_a_download_that_breaks_off(http_mirror, cache, registry_file):
    base, server = http_mirror
    path, commit, data = FILES["tiny"][0]
    server.truncate[f"/{REPO}/{commit}/{path}"] = (100, len(data))
    found = f"expected {len(data)} bytes, found 100 bytes, then the download broke off"
    _assert_fetch_fails(base, "tiny", 0, found, cache, registry_file, ends=False)


def test_a_mirror_that_trickles_is_cut_off_at_its_deadline(
    http_mirror, cache, registry_file, monkeypatch
):
    base, server = http_mirror
    path, commit, data = FILES["tiny"][0]
    server.trickle[f"/{REPO}/{commit}/{path}"] = 1.0  # a byte a second: no read ever times out
    fetch_module = sys.modules[download_deadline.__module__]  # the name fetch is the function
    monkeypatch.setattr(fetch_module, "DOWNLOAD_TIMEOUT_S", 2.0)
    deadline = download_deadline(len(data))
    assert deadline == 2.0 + len(data) / fetch_module.MIN_DOWNLOAD_RATE
    started = time.monotonic()
    found = f"expected {len(data)} bytes within {deadline:g} s, found "
    error = _assert_fetch_fails(base, "tiny", 0, found, cache, registry_file, ends=False)
    assert time.monotonic() - started < deadline + 10
    assert re.search(
        r"found \d+ bytes when cut off: too slow a mirror \(try another --mirror\)$", str(error)
    )
    assert not [p for p in cache.rglob("*") if p.is_file()]  # no temporary file left behind


def test_a_download_that_never_ends_is_cut_at_the_registrys_size(http_mirror, cache, registry_file):
    base, server = http_mirror
    path, commit, data = FILES["tiny"][0]
    server.endless.add(f"/{REPO}/{commit}/{path}")
    started = time.monotonic()
    found = (
        f"expected {len(data)} bytes, found more than {len(data)} bytes, cut off there: too "
        "large, the download did not end at the registry's size (nothing kept)"
    )
    _assert_fetch_fails(base, "tiny", 0, found, cache, registry_file)
    assert time.monotonic() - started < 10
    assert not [p for p in cache.rglob("*") if p.is_file()]  # no temporary file left behind


def test_a_download_announced_larger_than_the_registrys_size_is_refused_at_once(
    http_mirror, cache, registry_file
):
    base, server = http_mirror
    path, commit, data = FILES["tiny"][0]
    server.truncate[f"/{REPO}/{commit}/{path}"] = (len(data), 10**12)
    found = (
        f"expected {len(data)} bytes, found {10**12} bytes announced by the server: too large, "
        "not the file the registry names (nothing kept)"
    )
    _assert_fetch_fails(base, "tiny", 0, found, cache, registry_file)


def test_a_file_missing_from_the_http_mirror(http_mirror, mirror_dir, cache, registry_file):
    base, _ = http_mirror
    path, commit, _ = FILES["tiny"][2]
    (mirror_dir / REPO / commit / path).unlink()
    found = "expected HTTP 200 with the file, found HTTP 404 File not found"
    _assert_fetch_fails(base, "tiny", 2, found, cache, registry_file)
    assert (cache / "tiny" / TINY_LOCAL[0]).exists()  # verified files stay for the next fetch


def test_a_host_nobody_listens_on(cache, registry_file):
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    base = f"http://127.0.0.1:{port}"
    found = (
        f"expected an answer from 127.0.0.1:{port}, found Connection refused; no network here? "
        "fetch from a copy with --mirror URL"
    )
    error = _assert_fetch_fails(base, "tiny", 0, found, cache, registry_file, ends=False)
    assert "\n" not in str(error)
    assert str(pickle.loads(pickle.dumps(error))) == str(error)


def test_a_file_missing_from_a_file_mirror(mirror_dir, cache, registry_file):
    path, commit, _ = FILES["flat"][1]
    (mirror_dir / REPO / commit / path).unlink()
    base = mirror_dir.as_uri()
    found = "expected a file at that path, found no such file"
    _assert_fetch_fails(base, "flat", 1, found, cache, registry_file)


def test_a_failed_fetch_unmarks_a_dataset_whose_registry_changed(
    http_mirror, mirror_dir, cache, tmp_path, registry_file
):
    base, _ = http_mirror
    fetch("tiny", mirror=base, cache=cache, registry=registry_file)
    # The registry now pins another version of a file the mirror does not hold.
    changed = dict(FILES, tiny=[*FILES["tiny"][:2], (FILES["tiny"][2][0], "3" * 40, b"v2\n")])
    other = tmp_path / "registry-v2.json"
    other.write_text(json.dumps(_registry_document(changed)))
    assert not is_fetched("tiny", cache, registry=other)
    with pytest.raises(FetchError, match="found HTTP 404"):
        fetch("tiny", mirror=base, cache=cache, registry=other)
    assert not (cache / "tiny" / MANIFEST).exists()
    assert not (cache / "tiny" / TINY_LOCAL[2]).exists()  # the old version is not left as the new


def test_fetch_errors_survive_pickling(http_mirror, mirror_dir, cache, registry_file):
    import pickle

    base, _ = http_mirror
    path, commit, _ = FILES["tiny"][2]
    (mirror_dir / REPO / commit / path).unlink()
    with pytest.raises(FetchError) as caught:
        fetch("tiny", mirror=base, cache=cache, registry=registry_file)
    again = pickle.loads(pickle.dumps(caught.value))
    assert str(again) == str(caught.value)
    assert (again.dataset, again.file, again.url) == ("tiny", path, _url(base, "tiny", 2))


def test_an_unknown_name_lists_the_known_ones(cache, registry_file):
    with pytest.raises(
        ValueError, match=r"^unknown dataset 'nope'; the public datasets are: tiny, flat$"
    ):
        fetch("nope", cache=cache, registry=registry_file)
    with pytest.raises(ValueError, match="unknown dataset 'nope'"):
        is_fetched("nope", cache, registry=registry_file)


@pytest.mark.parametrize(
    ("mirror", "message"),
    [
        ("ftp://example.org", r"mirror: expected an http://, https:// or file:// URL or a folder"),
        ("{tmp}/nowhere", r"mirror: expected a folder, got '.*nowhere' \(no such folder\)"),
    ],
    ids=["unknown-scheme", "missing-folder"],
)
def test_a_bad_mirror_is_refused_before_any_download(mirror, message, tmp_path, registry_file):
    with pytest.raises(ValueError, match=message):
        fetch("tiny", mirror=mirror.format(tmp=tmp_path), cache=tmp_path, registry=registry_file)
    assert not (tmp_path / "tiny").exists()


# --- resolve -------------------------------------------------------------------------------


def test_resolve_returns_an_existing_path_as_given(tmp_path, registry_file):
    (tmp_path / "tiny").mkdir()
    assert resolve(tmp_path / "tiny", registry=registry_file) == tmp_path / "tiny"
    assert resolve(str(registry_file), registry=registry_file) == registry_file


def test_resolve_a_fetched_name(http_mirror, cache, registry_file, tmp_path, monkeypatch):
    base, _ = http_mirror
    monkeypatch.chdir(tmp_path)  # no folder named tiny here
    fetch("tiny", mirror=base, registry=registry_file)
    assert resolve("tiny", registry=registry_file) == cache / "tiny"


# What an unfetched dataset's message offers: a folder's path, the variable, or fetching it.
HOW_TO_GIVE_TINY = (
    "give the path of the folder that holds it, or set REFORM_SIM_DATASETS to the folder "
    "holding tiny/, or fetch it once online: `reform-sim datasets fetch tiny` (--mirror URL "
    "fetches from a copy)"
)


def test_resolve_an_unfetched_name_says_every_way_to_give_it(
    cache, registry_file, tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)  # no ../shared/datasets from here
    monkeypatch.setenv("REFORM_SIM_DATASETS", str(tmp_path / "no-datasets"))
    with pytest.raises(FileNotFoundError) as raised:
        resolve("tiny", registry=registry_file)
    assert str(raised.value) == (
        f"dataset 'tiny' is not fetched (cache {cache}) and no tiny/ in "
        f"{tmp_path / 'no-datasets'}; {HOW_TO_GIVE_TINY}"
    )
    monkeypatch.delenv("REFORM_SIM_DATASETS")
    with pytest.raises(FileNotFoundError) as raised:
        resolve("tiny", registry=registry_file)
    assert str(raised.value) == (
        f"dataset 'tiny' is not fetched (cache {cache}) and REFORM_SIM_DATASETS is not set; "
        f"{HOW_TO_GIVE_TINY}"
    )
    # Each way it names works.
    (tmp_path / "no-datasets" / "tiny").mkdir(parents=True)
    assert resolve(tmp_path / "no-datasets" / "tiny", registry=registry_file).name == "tiny"
    monkeypatch.setenv("REFORM_SIM_DATASETS", str(tmp_path / "no-datasets"))
    assert resolve("tiny", registry=registry_file) == tmp_path / "no-datasets" / "tiny"


def test_resolve_an_unknown_name_lists_the_datasets(cache, registry_file, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("REFORM_SIM_DATASETS", str(tmp_path / "no-datasets"))
    with pytest.raises(
        FileNotFoundError,
        match=r"^nope: no such file or folder, nor a dataset name; "
        r"the public datasets are: tiny, flat$",
    ):
        resolve("nope", registry=registry_file)


def test_resolve_a_folder_among_the_real_datasets(cache, registry_file, tmp_path, monkeypatch):
    real = tmp_path / "real"
    (real / "flat").mkdir(parents=True)
    (real / "mine").mkdir()
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("REFORM_SIM_DATASETS", str(real))
    assert local_datasets_dir() == real
    assert resolve("mine", registry=registry_file) == real / "mine"
    assert resolve("flat", registry=registry_file) == real / "flat"  # not fetched, but there


def test_the_real_datasets_folder_defaults_to_shared_datasets(tmp_path, monkeypatch):
    monkeypatch.delenv("REFORM_SIM_DATASETS", raising=False)
    monkeypatch.chdir(tmp_path)
    assert local_datasets_dir() is None
    (tmp_path.parent / "shared" / "datasets").mkdir(parents=True, exist_ok=True)
    assert local_datasets_dir() == Path("../shared/datasets")


# --- the registry --------------------------------------------------------------------------


def _reference_registry() -> Path | None:
    candidates = [REPO_ROOT.parent / "shared" / "reference" / "public-datasets.json"]
    if os.environ.get("REFORM_SIM_DATASETS"):
        candidates.append(
            Path(os.environ["REFORM_SIM_DATASETS"]).parent / "reference" / "public-datasets.json"
        )
    return next((c for c in candidates if c.is_file()), None)


def _packaged_registry() -> Path:
    return REPO_ROOT / "reform" / "datasets" / "public-datasets.json"


def test_the_packaged_registry_is_the_shared_reference():
    """The shared reference, plus what the project knows: which entries repackage a recording."""
    reference = _reference_registry()
    if reference is None:
        pytest.skip("../shared/reference/public-datasets.json not found")
    packaged = json.loads(_packaged_registry().read_text())
    same = {e["name"]: e.pop("recording") for e in packaged["datasets"] if "recording" in e}
    assert packaged == json.loads(reference.read_text())
    assert same == {"cocktail-party-dante": "cocktail-party"}


def test_the_packaged_registry_pins_every_file():
    document = json.loads(_packaged_registry().read_text())
    assert len(document["datasets"]) >= 7
    for entry in document["datasets"]:
        for file in entry["files"]:
            assert re.fullmatch(r"[0-9a-f]{64}", file["sha256"]), (entry["name"], file)
            assert isinstance(file["bytes"], int) and file["bytes"] > 0, (entry["name"], file)
            assert re.fullmatch(r"[0-9a-f]{40}", file.get("commit", entry.get("commit", "")))


def test_registry_reads_the_packaged_file():
    datasets = {d.name: d for d in registry()}
    assert list(datasets) == [
        "coffeebreak",
        "cocktail-party",
        "synth",
        "gdet",
        "salsa",
        "cocktail-party-dante",
        "babble",
    ]
    coffee = datasets["coffeebreak"]
    assert coffee.local_names[0] == "Seq1/features.mat"
    assert coffee.files[0].path == "data/octave/CoffeeBreak/Seq1/features.mat"
    assert (coffee.format, coffee.units) == ("gcff-mat", "cm")
    assert coffee.bytes == sum(f.bytes for f in coffee.files) == 32361  # the registry's sizes
    assert datasets["salsa"].local_names == ("features.txt", "group_names.txt")
    assert datasets["salsa"].licence == "licence reported as CC BY-NC-SA 3.0"
    assert datasets["synth"].licence is None
    babble = datasets["babble"]
    assert babble.local_names == ("Motion-capture-data.csv", "annotated-frames.csv", "Readme.txt")
    assert [f.commit[:7] for f in babble.files] == ["f6f62a5", "4867794", "4867794"]
    assert datasets["cocktail-party-dante"].recording == "cocktail-party"
    assert {d.recording for n, d in datasets.items() if n != "cocktail-party-dante"} == {None}


def test_one_per_recording_leaves_out_a_second_packaging():
    names = ["coffeebreak", "cocktail-party", "salsa", "cocktail-party-dante", "babble"]
    kept, left_out = one_per_recording(names)
    assert kept == ["coffeebreak", "cocktail-party", "salsa", "babble"]
    assert left_out == {"cocktail-party-dante": "cocktail-party"}
    # alone, the second packaging is the recording's only copy: it stays
    assert one_per_recording(["salsa", "cocktail-party-dante"]) == (
        ["salsa", "cocktail-party-dante"],
        {},
    )


def _broken(tmp_path: Path, edit) -> Path:
    document = _registry_document(FILES)
    edit(document)
    path = tmp_path / "broken.json"
    path.write_text(json.dumps(document) if not isinstance(document, str) else document)
    return path


def _set_file(key, value):
    def edit(document):
        document["datasets"][1]["files"][0][key] = value

    return edit


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            _set_file("sha256", "abc"),
            r"dataset 1 \('flat'\): field 'files\[0\]\.sha256': "
            r"expected 64 lowercase hex digits, found 'abc'",
        ),
        (
            _set_file("bytes", 0),
            r"dataset 1 \('flat'\): field 'files\[0\]\.bytes': expected an integer > 0, found 0",
        ),
        (
            _set_file("path", "../etc/passwd"),
            r"dataset 1 \('flat'\): field 'files\[0\]\.path': expected a relative POSIX path "
            r"without '\.', '\.\.' or empty parts, found '\.\./etc/passwd'",
        ),
        (
            _set_file("commit", "main"),
            r"dataset 1 \('flat'\): field 'files\[0\]\.commit': "
            r"expected 40 lowercase hex digits, found 'main'",
        ),
        (
            lambda d: d["datasets"][0].pop("repo"),
            r"dataset 0 \('tiny'\): field 'repo': expected the key to be present",
        ),
        (
            lambda d: d["datasets"][1].update(name="tiny"),
            r"field 'name': expected each dataset name once, found tiny",
        ),
        (
            lambda d: d["datasets"][0].update(name="Tiny Set"),
            r"dataset 0 \('Tiny Set'\): field 'name': "
            r"expected lowercase letters, digits and dashes, found 'Tiny Set'",
        ),
        (
            lambda d: d["datasets"][0].update(files=[]),
            r"dataset 0 \('tiny'\): field 'files': expected a non-empty list, found \[\]",
        ),
        (lambda d: d.pop("datasets"), r"field 'datasets': expected an object with a list"),
        (
            lambda d: d["datasets"][1].update(recording="nowhere"),
            r"dataset 1 \('flat'\): field 'recording': expected the name of a dataset of the "
            r"registry that is a recording of its own \(tiny\), found 'nowhere'",
        ),
        (
            lambda d: d["datasets"][1].update(recording="flat"),
            r"dataset 1 \('flat'\): field 'recording': expected another dataset's name, "
            r"found 'flat'",
        ),
    ],
    ids=[
        "short-sha256",
        "zero-bytes",
        "path-escapes",
        "branch-not-commit",
        "missing-key",
        "duplicate-name",
        "bad-name",
        "no-files",
        "no-datasets",
        "recording-unknown",
        "recording-itself",
    ],
)
def test_a_malformed_registry_is_one_clear_error(edit, message, tmp_path):
    path = _broken(tmp_path, edit)
    with pytest.raises(DataFormatError, match=f"^{re.escape(str(path))}: {message}"):
        registry(path)


def test_a_registry_that_is_not_json(tmp_path):
    path = tmp_path / "registry.json"
    path.write_text('{"datasets": [')
    with pytest.raises(
        DataFormatError,
        match=r"registry.json: expected a registry file \(JSON\), found text that is not JSON "
        r"\(Expecting value at line 1, column 15\)$",
    ):
        registry(path)
    path.write_text("[" * 100_000 + "]" * 100_000)  # deeper than Python's recursion goes
    with pytest.raises(DataFormatError, match=r"found JSON nested too deep to read$"):
        registry(path)


# --- the command line ----------------------------------------------------------------------


def test_cli_list_shows_what_is_fetched_and_where(http_mirror, cache, registry_file, capsys):
    base, _ = http_mirror
    fetch("tiny", mirror=base, registry=registry_file)
    assert main(["datasets", "list", "--registry", str(registry_file)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == f"cache: {cache} (set $REFORM_SIM_DATA or --cache to change)"
    assert lines[1].split() == [
        "name",
        "title",
        "format",
        "size",
        "licence",
        "on",
        "this",
        "machine",
    ]
    assert re.fullmatch(
        rf"tiny +The tiny set +dante-txt +670 B +- +fetched, {re.escape(str(cache / 'tiny'))}",
        lines[2],
    )
    assert re.fullmatch(r"flat +The flat set +dante-txt +16 B +licence CC0 +no", lines[3])


def test_cli_list_json(cache, registry_file, tmp_path, capsys):
    other = tmp_path / "elsewhere"
    argv = ["datasets", "list", "--json", "--registry", str(registry_file), "--cache", str(other)]
    assert main(argv) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["cache"] == str(other)
    assert [(d["name"], d["bytes"], d["fetched"], d["path"]) for d in document["datasets"]] == [
        ("tiny", 670, False, None),  # 560 + 12 + 98 bytes
        ("flat", 16, False, None),  # 8 + 8 bytes
    ]


def test_cli_list_the_packaged_registry(cache, capsys):
    assert main(["datasets"]) == 0  # `datasets` alone lists
    out = capsys.readouterr().out
    assert re.search(
        r"\nsalsa +SALSA, both sessions \(DANTE packaging\) +dante-txt +935\.8 kB", out
    )
    assert "licence reported as CC BY-NC-SA 3.0" in out
    assert len(out.splitlines()) == 2 + len(registry())


def test_cli_fetch_from_a_mirror(http_mirror, cache, registry_file, capsys):
    base, server = http_mirror
    argv = ["datasets", "fetch", "--all", "--mirror", base, "--registry", str(registry_file)]
    assert main(argv) == 0
    assert capsys.readouterr().out.splitlines() == [
        f"tiny: {cache / 'tiny'}",
        f"flat: {cache / 'flat'}",
    ]
    assert len(server.requests) == 5
    assert main([*argv[:2], "flat", *argv[3:], "--quiet"]) == 0
    assert capsys.readouterr().out == f"flat: {cache / 'flat'} (already fetched)\n"
    assert len(server.requests) == 5


def test_cli_fetch_into_another_cache(mirror_dir, tmp_path, registry_file, capsys):
    other = tmp_path / "other-cache"
    argv = ["datasets", "fetch", "flat", "--mirror", str(mirror_dir), "--cache", str(other)]
    assert main([*argv, "--registry", str(registry_file)]) == 0
    assert (other / "flat" / "Motion.csv").read_bytes() == FILES["flat"][0][2]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["datasets", "fetch"], "give dataset names or --all; the public datasets are: tiny, flat"),
        (["datasets", "fetch", "tiny", "--all"], "give dataset names or --all, not both"),
        (
            ["datasets", "fetch", "flat", "nope"],
            "unknown dataset 'nope'; the public datasets are: tiny, flat",
        ),
        (
            ["datasets", "fetch", "tiny", "--mirror", "{base}/wrong"],
            "data/octave/Tiny/Seq1/features.txt: dataset 'tiny' from {base}/wrong/",
        ),
    ],
    ids=["nothing-named", "names-and-all", "unknown-name", "file-not-on-mirror"],
)
def test_cli_fetch_errors(argv, message, http_mirror, cache, registry_file, capsys):
    base, server = http_mirror
    argv = [a.format(base=base) for a in argv] + ["--registry", registry_file]
    error = cli_error(argv, capsys)
    assert error.startswith("reform-sim datasets: error: ")
    assert message.format(base=base) in error
    if "nope" in argv:
        assert server.requests == []  # refused before flat was fetched
    _assert_nothing_looks_complete(cache, "tiny", registry_file)


def test_cli_data_takes_a_fetched_name(http_mirror, cache, registry_file, capsys, monkeypatch):
    """``--data NAME``: an unfetched public dataset is named with the command that fetches it."""
    monkeypatch.setenv("REFORM_SIM_DATASETS", str(cache / "no-datasets"))
    error = cli_error(["evaluate", "--data", "salsa", "--detector", "gcff"], capsys)
    assert error.endswith(
        f"dataset 'salsa' is not fetched (cache {cache}) and no salsa/ in {cache / 'no-datasets'}"
        "; give the path of the folder that holds it, or set REFORM_SIM_DATASETS to the folder "
        "holding salsa/, or fetch it once online: `reform-sim datasets fetch salsa` (--mirror URL "
        "fetches from a copy)"
    )


def test_datasets_help_imports_nothing_heavy():
    code = (
        "import sys\n"
        "from sim.cli import main\n"
        "for argv in (['datasets', 'fetch', '--help'], ['datasets', 'list', '--help']):\n"
        "    try:\n"
        "        main(argv)\n"
        "    except SystemExit:\n"
        "        pass\n"
        "print([m for m in sys.modules if m.split('.')[0] in "
        "('numpy', 'pooch', 'requests', 'platformdirs') "
        "or m.startswith('reform.') and m != 'reform._lazy'])\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=REPO_ROOT
    )
    assert out.stdout.strip().splitlines()[-1] == "[]"


# --- the real registry, end to end, from a mirror of the real datasets ---------------------


def _real_mirror(shared_datasets: Path, root: Path, names: tuple[str, ...]) -> Path:
    """A mirror of the registry's files of ``names``, made from ../shared/datasets (whose files
    are the registry's, byte for byte)."""
    for dataset in registry():
        if dataset.name not in names:
            continue
        for local, file in zip(dataset.local_names, dataset.files, strict=True):
            target = root / dataset.repo / file.commit / file.path
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(shared_datasets / dataset.name / local, target)
    return root


@pytest.mark.parametrize("name", ["coffeebreak", "synth", "salsa", "babble"])
def test_a_fetched_dataset_loads_as_the_shared_copy(name, shared_datasets, tmp_path, cache):
    mirror = _real_mirror(shared_datasets, tmp_path / "mirror", (name,))
    with _serve(mirror) as (base, server):
        folder = fetch(name, mirror=base)
    (dataset,) = [d for d in registry() if d.name == name]
    assert len(server.requests) == len(dataset.files)
    assert resolve(name) == folder == cache / name
    assert load_dataset(folder).frames == load_dataset(shared_datasets / name).frames


def test_cli_fetch_then_data_name(shared_datasets, tmp_path, cache, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("REFORM_SIM_DATASETS", str(tmp_path / "no-datasets"))
    mirror = _real_mirror(shared_datasets, tmp_path / "mirror", ("synth",))
    assert main(["datasets", "fetch", "synth", "--mirror", mirror.as_uri()]) == 0
    assert capsys.readouterr().out == f"synth: {cache / 'synth'}\n"
    argv = ["evaluate", "--data", "synth", "--detector", "majority", "--json", "synth.json"]
    assert main(argv) == 0
    capsys.readouterr()
    result = json.loads((tmp_path / "synth.json").read_text())
    assert result["dataset"] == load_dataset(shared_datasets / "synth").name


def test_cli_list_shows_a_dataset_in_the_real_datasets_folder(
    registry_file, tmp_path, capsys, monkeypatch
):
    local = tmp_path / "datasets"
    (local / "flat").mkdir(parents=True)
    monkeypatch.setenv("REFORM_SIM_DATASETS", str(local))
    assert (
        main(["datasets", "list", "--registry", str(registry_file), "--cache", str(tmp_path / "c")])
        == 0
    )
    (flat,) = [line for line in capsys.readouterr().out.splitlines() if line.startswith("flat ")]
    assert flat.endswith(f"in {local / 'flat'}")
