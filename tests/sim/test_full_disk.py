"""A full disk while a recording or a dataset file is written is named as a full disk, with the
path and the space needed, in one line, and leaves no temporary file; the size estimated for a
recording is within a factor of two of the real file's. The disk is a real small filesystem (a
tmpfs mounted in a user and mount namespace of the test's own, ``unshare -rm``: no root needed);
where the system forbids such namespaces the full-disk tests are skipped."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from killed_run import CLI

from reform.datasets import load_dataset
from sim.cli import main
from sim.episode import estimate_episode
from sim.recording import record_episode
from sim.sizing import recording_disk

pytestmark = pytest.mark.faults  # the fault suite: pytest -m faults

ROOT = Path(__file__).resolve().parents[2]
RUN_TIMEOUT_S = 120.0  # a hang fails the test, not the suite
SIMULATE = ["simulate", "--scenario", "mingle", "--set", "people=4", "--duration", "20"]
SIMULATE += ["--seed", "0", "--quiet"]


def _in_small_disk(tmp_path: Path, size_kb: int, argv: list[str]) -> subprocess.CompletedProcess:
    """Runs ``argv`` with a tmpfs of ``size_kb`` KiB mounted at ``tmp_path / "small"``."""
    small = tmp_path / "small"
    small.mkdir()
    script = f'mount -t tmpfs -o size={size_kb}k tmpfs "$1" && shift && exec "$@"'
    return subprocess.run(
        ["unshare", "-rm", "sh", "-c", script, "sh", str(small), *argv],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
    )


@pytest.fixture(scope="module")
def small_disks(tmp_path_factory) -> None:
    """Skips where no tmpfs can be mounted in a namespace of this user's."""
    if shutil.which("unshare") is None:
        pytest.skip("needs unshare (util-linux)")
    probe = tmp_path_factory.mktemp("probe")
    if _in_small_disk(probe, 64, ["true"]).returncode != 0:
        pytest.skip("this system forbids mounting a tmpfs in a user namespace")


@pytest.mark.usefixtures("small_disks")
def test_a_recording_that_fills_the_disk_is_named_as_a_full_disk(tmp_path):
    rrd = tmp_path / "small" / "party.rrd"
    run = _in_small_disk(
        tmp_path, 60, [*CLI, *SIMULATE, "--out", tmp_path / "party.parquet", "--save", rrd]
    )
    assert run.returncode == 2
    (line,) = [ln for ln in run.stderr.splitlines() if not ln.startswith(str(tmp_path))]
    assert re.fullmatch(
        rf"reform-sim simulate: error: {re.escape(str(rrd))}: the disk is full \(no space left "
        r"on the device after [\d.]+ kB of it were written; [\d.]+ kB free there without it, "
        r"about 1\d\d kB needed\); free some space there or write elsewhere",
        line,
    ), run.stderr
    assert "File-writer" not in run.stderr


@pytest.fixture(scope="module")
def party(tmp_path_factory) -> Path:
    """A simulated party of 4 people, 20 s (40 frames), as Parquet."""
    out = tmp_path_factory.mktemp("party") / "party.parquet"
    assert main([*SIMULATE, "--out", str(out)]) == 0
    return out


@pytest.mark.usefixtures("small_disks")
def test_a_dataset_file_that_fills_the_disk_is_named_and_leaves_nothing(tmp_path, party):
    source = party
    target = tmp_path / "small" / "copy.parquet"
    copy = (
        "import sys; from reform.datasets import load_dataset, write_parquet\n"
        "try:\n    write_parquet(load_dataset(sys.argv[1]), sys.argv[2])\n"
        "except OSError as exc:\n"
        "    import os; print(exc.errno, exc); print(os.listdir(os.path.dirname(sys.argv[2])))\n"
    )
    run = _in_small_disk(tmp_path, 8, [sys.executable, "-c", copy, source, target])
    first, leftovers = run.stdout.splitlines()
    assert first.startswith(f"28 {target}: the disk is full (no space left on the device after ")
    assert leftovers == "[]"  # the unfinished file is removed


def test_the_estimate_of_a_recording_is_within_two_times_the_real_file(tmp_path, party):
    """A short recording, most of it its fixed part, which the estimate once left out (4x)."""
    people, duration, rrd = 4, 20.0, tmp_path / "party.rrd"
    frames = load_dataset(party).frames
    record_episode(rrd, frames, seed=0, name="party")
    options = {"people": people}
    estimate = estimate_episode("mingle", seed=0, duration=duration, options=options)
    recorded = estimate_episode(
        "mingle", seed=0, duration=duration, options=options, recording=True
    )
    real = rrd.stat().st_size
    assert 0.5 < (recorded.disk - estimate.disk) / real < 2.0
    assert 0.5 < recording_disk(people, len(frames)) / real < 2.0
