"""A worker process that dies under a unit (killed by SIGKILL, as the out-of-memory killer does;
a crash in compiled code) stops the run with one line naming the unit it held and, for SIGKILL,
the likely cause, never a traceback; on Ray, a unit that ends its worker is blamed on the unit,
not on the cluster. Real worker processes, real signals, a real (local) Ray instance."""

from __future__ import annotations

import ctypes
import sys

import pytest
from cli_errors import cli_error
from quiet_generate import generate_quietly

from sim.executor import Executor, WorkerDied

pytestmark = pytest.mark.faults  # the fault suite: pytest -m faults

KILLER = """\
import os, signal, time


class Killed:
    def predict(self, frames):
        time.sleep(0.5)  # part-way through, as a run that outgrows its memory
        os.kill(os.getpid(), signal.SIGKILL)


def make():
    return Killed()
"""


def _describe(x: int) -> str:
    return f"episode {x} of the test"


def _crashes_on_1(x: int) -> int:
    if x == 1:
        ctypes.string_at(0)  # reads address 0: SIGSEGV
    return x


def test_a_worker_that_crashes_is_named_with_its_unit_and_where() -> None:
    with pytest.raises(WorkerDied) as info:
        Executor("local", jobs=2).map(_crashes_on_1, range(2), describe=_describe)
    message = str(info.value)
    assert message.startswith("a worker process died of SIGSEGV while it ran episode 1 of the test")
    assert f"crashed in string_at at {ctypes.__file__}" in message
    assert "\n" not in message


def test_benchmark_says_which_detector_a_killed_worker_held_in_one_line(
    tmp_path, capsys, monkeypatch
) -> None:
    (tmp_path / "killer.py").write_text(KILLER)
    generate_quietly("hri-conversation", tmp_path / "ds", episodes=1, seed=1, duration=2.0)
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    line = cli_error(
        ["benchmark", "--detector", "killer:make", "--detector", "majority", "--data", "ds"]
        + ["--out", "bench", "--jobs", "2", "--quiet", "--no-recordings"],
        capsys,
    )
    assert line.startswith(
        "reform-sim benchmark: error: a worker process was killed (SIGKILL) while it ran "
        "detector killer:make on ds: most likely the machine ran out of memory"
    )


@pytest.fixture
def _by_value():
    """Ray's workers cannot import this test module: its functions are sent by value."""
    ray = pytest.importorskip("ray")
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])


def _raises_on_1(x: int) -> int:
    if x == 1:
        raise RuntimeError(f"detector broke on unit {x}")
    return x


@pytest.mark.usefixtures("_by_value")
def test_on_ray_a_unit_that_crashes_its_worker_is_blamed_not_the_cluster(ray_instance) -> None:
    with Executor("ray") as executor, pytest.raises(WorkerDied) as info:
        executor.map(_crashes_on_1, range(2), describe=_describe)
    message = str(info.value)
    assert message.startswith(
        "episode 1 of the test ended the Ray worker process that ran it, twice "
        "(WorkerCrashedError: "
    )
    assert "not the cluster" in message and "\n" not in message


@pytest.mark.usefixtures("_by_value")
def test_on_ray_a_unit_that_raises_is_named_by_its_own_error(ray_instance) -> None:
    with (
        Executor("ray") as executor,
        pytest.raises(RuntimeError, match="^detector broke on unit 1$"),
    ):
        executor.map(_raises_on_1, range(2), describe=_describe)
