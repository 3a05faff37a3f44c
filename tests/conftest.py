"""Shared fixtures. The real datasets are found through one helper: ``shared_datasets``."""

from __future__ import annotations

import fcntl
import os
import sys
from collections.abc import Callable
from pathlib import Path

import leftover_processes
import pytest

# Offscreen rendering (sim.camera) on a headless machine: EGL, chosen before mujoco is imported.
if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")

REPO_ROOT = Path(__file__).resolve().parents[1]
DATASETS_ENV = "REFORM_SIM_DATASETS"


def shared_datasets_dir() -> Path:
    """The folder of real datasets: ``$REFORM_SIM_DATASETS``, else ``../shared/datasets``.

    Under CI (``CI`` set) a missing folder is a failure, not a skip.
    """
    configured = os.environ.get(DATASETS_ENV)
    candidates = [Path(configured)] if configured else [REPO_ROOT.parent / "shared" / "datasets"]
    for candidate in candidates:
        if (candidate / "salsa").is_dir():
            return candidate
    message = (
        f"real datasets not found at {candidates[0]} (set {DATASETS_ENV} to the folder holding "
        "salsa/ and babble/)"
    )
    if os.environ.get("CI"):
        pytest.fail(message)
    pytest.skip(message)


@pytest.fixture(scope="session")
def shared_datasets() -> Path:
    return shared_datasets_dir()


@pytest.fixture(scope="session")
def salsa_dir(shared_datasets: Path) -> Path:
    return shared_datasets / "salsa"


@pytest.fixture(scope="session")
def babble_dir(shared_datasets: Path) -> Path:
    return shared_datasets / "babble"


@pytest.fixture(scope="session")
def salsa_dataset(salsa_dir: Path):
    """SALSA, loaded once per test session (frames are immutable, so sharing is safe)."""
    from reform.datasets import load_salsa

    return load_salsa(salsa_dir)


@pytest.fixture(scope="session")
def babble_dataset(babble_dir: Path):
    """Babble, loaded once per test session."""
    from reform.datasets import load_babble

    return load_babble(babble_dir)


@pytest.fixture(scope="session")
def gcff_reference_dir(shared_datasets: Path) -> Path:
    """The original GCFF code's answers on SALSA: ``<shared>/reference/gcff-reference``.

    Found beside the datasets folder; under CI a missing folder is a failure, not a skip.
    """
    path = shared_datasets.parent / "reference" / "gcff-reference"
    if not path.is_dir():
        message = f"GCFF reference partitions not found at {path}"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    return path


@pytest.fixture(scope="session")
def made_once(tmp_path_factory, worker_id) -> Callable[[str, Callable[[Path], object]], Path]:
    """``made_once(name, write)``: the file ``name`` that ``write(path)`` writes, written once
    for the whole run and read by every pytest-xdist worker (the first to ask writes it while the
    others wait for it; `pytest-xdist`'s way for a costly session fixture). For what costs a
    worker tens of seconds to make again (a twin's fit), not for what a test changes."""
    root = tmp_path_factory.getbasetemp()
    if worker_id != "master":  # every worker's base folder is beside the others'
        root = root.parent

    def made(name: str, write: Callable[[Path], object]) -> Path:
        path = root / name
        with open(root / f"{name}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not path.is_file():
                write(path)
        return path

    return made


@pytest.fixture(scope="session", autouse=True)
def no_process_left_running():
    """A test run leaves no process it started alive: when the last test has finished and the
    helpers that end with the interpreter are stopped (`leftover_processes.end_helpers`: the test
    Ray instance, reusable worker pools), any process the run started that is still running after
    `leftover_processes.GRACE_S` fails the run, each named by its id and command line, and is
    then stopped (Linux: the orphans of stopped parents are counted too, see
    `leftover_processes`). The test process's own resource trackers end with it and are not
    counted (`leftover_processes.own_trackers`)."""
    watching = leftover_processes.adopt_orphans()
    yield
    if not watching:
        return
    leftover_processes.end_helpers()
    left = leftover_processes.left_running()
    if left:
        leftover_processes.stop(left)
        lines = "\n".join(f"  {process}" for process in left)
        pytest.fail(f"the test run left {len(left)} process(es) it started running:\n{lines}")


# The local Ray instance of the tests: 2 CPUs, as this machine has.
RAY_TEST_INSTANCE = dict(
    num_cpus=2, object_store_memory=100 * 2**20, include_dashboard=False, log_to_driver=False
)


@pytest.fixture
def ray_instance():
    """A real local Ray instance (`RAY_TEST_INSTANCE`), started once and joined by every
    ``backend="ray"`` run (started again if a test shut it down); the ``ray`` module. Ray shuts
    it down when the session ends."""
    ray = pytest.importorskip("ray")
    if not ray.is_initialized():
        ray.init(**RAY_TEST_INSTANCE)
    return ray


@pytest.fixture
def ray_restarted():
    """The Ray instance of `ray_instance` started again now: its workers take this process's
    environment as it is now (credentials a fixture set after it was first started); shut down
    at the end."""
    ray = pytest.importorskip("ray")
    ray.shutdown()
    ray.init(**RAY_TEST_INSTANCE)
    yield ray
    ray.shutdown()
