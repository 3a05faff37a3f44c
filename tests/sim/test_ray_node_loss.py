"""A Ray node lost while it runs a unit: the unit runs again on the nodes left, with one line on
stderr naming the node and the unit; with no node left, or its retries spent, the run stops in
one line naming the node(s), the unit and what to do; a command stopped (SIGTERM, SIGKILL)
leaves no unit running on the cluster. A real cluster of several Ray nodes on this machine
(`ray.cluster_utils.Cluster`), nodes added and removed as a test goes."""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

import sim.executor
from sim.cli import main
from sim.executor import ClusterError, Executor

pytestmark = pytest.mark.faults  # the fault suite: pytest -m faults

START_S = 60.0  # at most this long for a unit to start on a new node (the machine is shared)
STORE_BYTES = 80 * 2**20  # each node's object store
GONE_S = 5.0  # a stopped command's units must be gone from the cluster this soon
CONSOLE = [
    sys.executable,
    "-c",
    "import sys; from sim.cli import console_main; sys.exit(console_main())",
]


@pytest.fixture(scope="module")
def cluster():
    """A Ray cluster whose head has no CPU (units run only on the nodes a test adds), joined by
    this process; shut down, with every process it started, when the module is done. The
    tests' local Ray instance, if this process had joined it, is left first (one per process)."""
    ray = pytest.importorskip("ray")
    from ray.cluster_utils import Cluster

    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    if ray.is_initialized():
        ray.shutdown()
    cluster = Cluster(
        initialize_head=True,
        head_node_args=dict(num_cpus=0, include_dashboard=False, object_store_memory=STORE_BYTES),
    )
    try:
        ray.init(address=cluster.address, log_to_driver=False)
        yield cluster
    finally:
        ray.shutdown()
        cluster.shutdown()


def _runs_on(x: int, folder: str, doomed: str) -> int:
    """Notes which node runs unit ``x`` (a file named for the node's ID), then waits there
    for the node's end on the ``doomed`` node; elsewhere, until a unit has started on the
    ``doomed`` one (so that a node slow to start its worker still gets a unit)."""
    import ray

    node = ray.get_runtime_context().get_node_id()
    (Path(folder) / node).write_text(str(x))
    if node == doomed:
        time.sleep(START_S)
    deadline = time.monotonic() + START_S
    while not (Path(folder) / doomed).exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    return x


def _lose_node_under(cluster, units: list[int], folder: Path) -> tuple[object, int, object]:
    """Runs ``units`` on the cluster with one node added, and removes that node while it runs a
    unit: ``(the node, the unit it ran, the run's future)``."""
    doomed = cluster.add_node(num_cpus=1, object_store_memory=STORE_BYTES)
    cluster.wait_for_nodes()
    pool = ThreadPoolExecutor(1)
    executor = Executor("ray", progress=False)
    run = pool.submit(executor.map, _runs_on, units, shared=(str(folder), doomed.node_id))
    pool.shutdown(wait=False)
    note = folder / doomed.node_id
    deadline = time.monotonic() + START_S
    while not note.exists() and time.monotonic() < deadline and not run.done():
        time.sleep(0.05)
    cluster.remove_node(doomed)  # whether or not a unit started there: no node left over
    assert note.exists(), "no unit started on the node added"
    return doomed, int(note.read_text()), run


def _named(node) -> str:
    return f"{node.node_ip_address} (ID {node.node_id})"


def test_work_whose_node_is_lost_completes_on_the_others(cluster, tmp_path, capsys) -> None:
    kept = cluster.add_node(num_cpus=1, object_store_memory=STORE_BYTES)
    try:
        doomed, unit, run = _lose_node_under(cluster, [0, 1], tmp_path)
        assert run.result(timeout=START_S) == [0, 1]
    finally:
        cluster.remove_node(kept)
    assert (tmp_path / kept.node_id).read_text() in ("0", "1")
    lines = capsys.readouterr().err.splitlines()
    assert lines == [
        f"reform-sim: the Ray cluster lost node {_named(doomed)} while it ran unit {unit}; it "
        f"runs again (1 of {sim.executor.MAX_RETRIES}) on the cluster's other nodes"
    ]


def test_a_unit_whose_retries_run_out_is_one_line(cluster, tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(sim.executor, "MAX_RETRIES", 0)
    doomed, unit, run = _lose_node_under(cluster, [0], tmp_path)
    with pytest.raises(ClusterError) as info:
        run.result(timeout=START_S)
    assert str(info.value) == (
        f"unit 0 was lost once on the Ray cluster (the cluster lost node {_named(doomed)}, which "
        "ran it): its nodes keep failing (`ray list nodes --detail` says why: preemption, "
        "memory, a crashed raylet); run the command again on a steadier cluster"
    )


def test_a_command_whose_cluster_loses_its_last_node_ends_in_one_line(
    cluster, tmp_path, capsys, monkeypatch
) -> None:
    """generate on the cluster, its only node with CPUs removed once the first shard is back:
    a line for the unit it ran (run again once a node joins), then, no node having joined
    within the wait, the command's one line naming the units, the node and what to do; never
    a traceback."""
    monkeypatch.setattr(sim.executor, "NODE_WAIT_S", 1.0)
    monkeypatch.setattr(sim.executor, "NODE_CHECK_S", 0.2)
    node = cluster.add_node(num_cpus=1, object_store_memory=STORE_BYTES)
    cluster.wait_for_nodes()
    out = tmp_path / "ds"
    argv = ["generate", "--scenario", "hri-conversation", "--episodes", "8", "--seed", "1"]
    argv += ["--duration", "60", "--out", str(out), "--backend", "ray", "--quiet"]
    pool = ThreadPoolExecutor(1)
    run = pool.submit(main, argv)
    pool.shutdown(wait=False)
    deadline = time.monotonic() + START_S
    while not any(out.rglob("part.parquet")) and time.monotonic() < deadline and not run.done():
        time.sleep(0.05)
    cluster.remove_node(node)
    assert run.result(timeout=START_S) == 2
    *rerun, line = capsys.readouterr().err.splitlines()
    named = re.escape(_named(node))
    assert re.fullmatch(
        rf"reform-sim generate: error: episodes \d+-\d+ of hri-conversation( \(and \d+ more "
        rf"unit\(s\)\))? cannot run: the Ray cluster lost node {named}(, which ran it,)? and has "
        r"had no node with a CPU for 1 s; add nodes to the cluster \(`ray start --address "
        r"HEAD:PORT` on another machine\) and run the command again",
        line,
    )
    for said in rerun:  # a unit the node was running when it went (none if between two)
        assert re.fullmatch(
            rf"reform-sim: the Ray cluster lost node {named} while it ran episodes \d+-\d+ of "
            r"hri-conversation; it runs again \(1 of 3\) when a node with a CPU joins the "
            r"cluster: none is left, and the run waits 1 s for one",
            said,
        )


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["sigterm", "sigkill"])
def test_a_stopped_command_leaves_no_task_running_on_the_cluster(cluster, tmp_path, sig) -> None:
    """generate on the cluster, stopped by ``sig`` while its units run: within GONE_S seconds no
    process of the cluster still runs one of them (Ray's idle workers may stay, computing
    nothing); SIGTERM also says in one line how to resume."""
    node = cluster.add_node(num_cpus=2, object_store_memory=STORE_BYTES)
    cluster.wait_for_nodes()
    argv = ["generate", "--scenario", "mingle", "--episodes", "40", "--seed", "0"]
    argv += ["--duration", "20", "--out", str(tmp_path / "ds"), "--backend", "ray"]
    argv += ["--address", cluster.address, "--quiet"]
    try:
        process = subprocess.Popen(
            [*CONSOLE, *argv], stderr=subprocess.PIPE, text=True, start_new_session=True
        )
        deadline = time.monotonic() + START_S
        while not _running_units() and process.poll() is None:
            assert time.monotonic() < deadline, "no unit started on the cluster"
            time.sleep(0.05)
        assert process.poll() is None, process.stderr.read()
        os.kill(process.pid, sig)
        status = process.wait(timeout=START_S)
        deadline = time.monotonic() + GONE_S
        while _running_units() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert _running_units() == []
        err = process.stderr.read()
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)
        cluster.remove_node(node)
    if sig == signal.SIGTERM:
        assert status == 128 + signal.SIGTERM, err
        assert err == (
            "reform-sim generate: stopped by SIGTERM; run the same command again to resume\n"
        )
    else:
        assert status == -signal.SIGKILL


def _running_units() -> list[int]:
    """The processes of this machine running a Ray task of sim.executor (titled ``ray::_apply``
    by Ray while they run it)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            with contextlib.suppress(OSError):
                if (entry / "cmdline").read_bytes().startswith(b"ray::_apply"):
                    found.append(int(entry.name))
    return found
