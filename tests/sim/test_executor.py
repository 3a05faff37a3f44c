"""sim.executor: units in order on every backend, shared arguments, errors as raised, a lost Ray
worker run again, and a cluster address probed before any work."""

from __future__ import annotations

import http.server
import os
import signal
import socket
import sys
import threading
import time

import pytest

from sim.cli import main
from sim.executor import (
    MAX_RETRIES,
    PROBE_TIMEOUT_S,
    ClusterError,
    Executor,
    WorkerDied,
    check_address,
)


@pytest.fixture(autouse=True, scope="module")
def _functions_travel_by_value():
    """Ray's workers cannot import this test module: its functions are sent by value."""
    ray = pytest.importorskip("ray")
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])


def _square_plus(x: int, offset: int = 0) -> int:
    return x * x + offset


def _slow_first(x: int) -> int:
    """Unit 0 finishes last, so that finishing order and unit order differ."""
    if x == 0:
        time.sleep(0.5)
    return x


def _fails_on(x: int) -> int:
    if x == 2:
        raise ValueError(f"unit {x}: expected an odd number, got {x}")
    return x


@pytest.fixture
def free_port() -> int:
    """A port on 127.0.0.1 where nothing listens (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def http_server():
    """A real HTTP server on 127.0.0.1: something answers, but not a Ray cluster."""
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


# --------------------------------------------------------------------------------------------
# Mapping


@pytest.mark.parametrize("jobs", [1, 2], ids=["in-process", "two-processes"])
def test_local_results_come_in_unit_order(jobs) -> None:
    executor = Executor("local", jobs=jobs)
    assert executor.map(_slow_first, range(5)) == [0, 1, 2, 3, 4]
    assert executor.map(_square_plus, [1, 2, 3], shared=(10,)) == [11, 14, 19]
    assert executor.map(_square_plus, []) == []
    assert executor.workers == jobs


def test_unordered_stream_says_which_unit_each_result_is() -> None:
    pairs = list(Executor("local", jobs=2).imap_unordered(_slow_first, range(4)))
    assert sorted(pairs) == [(0, 0), (1, 1), (2, 2), (3, 3)]
    assert pairs[-1] == (0, 0)  # the slow unit came last


def test_work_that_cannot_be_sent_to_local_workers_is_one_line() -> None:
    locked = threading.Lock()  # what a detector may hold: no process can be handed it
    with pytest.raises(
        ValueError,
        match=r"^the work cannot be sent to 2 worker processes \(TypeError: cannot pickle "
        r"'_thread\.lock' object\): .* or run with --jobs 1$",
    ):
        Executor("local", jobs=2).map(_square_plus, [1, 2], shared=(locked,))


def test_on_done_counts_every_unit() -> None:
    seen = []
    Executor("local", jobs=1).map(_square_plus, [3, 4], on_done=lambda *a: seen.append(a))
    assert seen == [(1, 2, 9), (2, 2, 16)]


def test_ray_results_match_the_local_ones(ray_instance) -> None:
    with Executor("ray") as executor:
        assert executor.workers == 2
        assert executor.map(_slow_first, range(5)) == [0, 1, 2, 3, 4]
        assert executor.map(_square_plus, [1, 2, 3], shared=(10,)) == [11, 14, 19]
        assert executor.describe() == {"backend": "ray", "workers": 2}
    assert ray_instance.is_initialized()  # joined, not started: left running


@pytest.mark.parametrize("backend", ["local", "ray"])
def test_a_units_error_is_raised_as_it_was(backend, request) -> None:
    if backend == "ray":
        request.getfixturevalue("ray_instance")
    executor = Executor(backend, jobs=2 if backend == "local" else None)
    with pytest.raises(ValueError, match=r"^unit 2: expected an odd number, got 2$"):
        executor.map(_fails_on, range(4))


def test_a_lost_ray_worker_is_run_again(ray_instance, tmp_path) -> None:
    """The worker running unit 3 dies once (its process exits, as on a lost node); Ray runs the
    unit again on another worker and the run completes with every result."""
    marker = tmp_path / "died"

    def square_or_die(x: int) -> int:
        if x == 3 and not marker.exists():
            marker.write_text(str(os.getpid()))
            os._exit(1)
        return x * x

    with Executor("ray") as executor:
        assert executor.map(square_or_die, range(6)) == [0, 1, 4, 9, 16, 25]
    assert marker.is_file()  # the worker did die
    assert MAX_RETRIES >= 1


def test_a_unit_that_ends_its_ray_worker_every_time_is_blamed_in_one_line(ray_instance) -> None:
    """Run again once (a worker may die of something else), then blamed on the unit, not on
    the cluster."""

    def always_die(x: int) -> int:
        os._exit(1)

    with pytest.raises(
        WorkerDied, match=r"^unit 0 ended the Ray worker process that ran it, twice"
    ):
        Executor("ray").map(always_die, [0])


def test_local_workers_take_the_environment_as_given_now(monkeypatch) -> None:
    """A pool started before a variable was set (and reused between runs) is not reused by an
    executor that gives the variable: its workers see the value."""
    monkeypatch.delenv("REFORM_SIM_TEST_VALUE", raising=False)
    names = ["REFORM_SIM_TEST_VALUE"] * 3
    assert Executor("local", jobs=2).map(os.getenv, names) == [None] * 3
    given = Executor("local", jobs=2, environment={"REFORM_SIM_TEST_VALUE": "now"})
    assert given.map(os.getenv, names) == ["now"] * 3
    assert os.getenv("REFORM_SIM_TEST_VALUE") is None  # this process's own is left alone


def test_bad_arguments() -> None:
    with pytest.raises(ValueError, match=r"backend must be one of \('local', 'ray'\), got 'dask'"):
        Executor("dask")
    with pytest.raises(ValueError, match="jobs must be None or an int >= 1, got 0"):
        Executor(jobs=0)
    with pytest.raises(ValueError, match="with backend 'ray' every CPU of the cluster works"):
        Executor("ray", jobs=2)
    with pytest.raises(ValueError, match="address is for backend 'ray'"):
        Executor("local", address="127.0.0.1:6379")
    with pytest.raises(ValueError, match=r"environment is for backend 'local'.*\['AWS_REGION'\]"):
        Executor("ray", environment={"AWS_REGION": "eu-west-1"})


# --------------------------------------------------------------------------------------------
# The address probe


def test_an_address_where_nothing_listens_is_refused_at_once(free_port) -> None:
    start = time.perf_counter()
    with pytest.raises(ClusterError, match=f"nothing listens at 127.0.0.1:{free_port}"):
        Executor("ray", address=f"127.0.0.1:{free_port}")
    assert time.perf_counter() - start < PROBE_TIMEOUT_S + 1


@pytest.mark.parametrize(
    ("address", "message"),
    [
        ("no-such-host.invalid", "host 'no-such-host.invalid' is not known"),
        ("no-such-host.invalid:6380", "host 'no-such-host.invalid' is not known"),
        ("127.0.0.1:http", "expected a port number 1-65535 after the host, got 'http'"),
        ("127.0.0.1:70000", "expected a port number 1-65535 after the host, got '70000'"),
        (":6379", "expected HOST:PORT, ray://HOST:PORT or auto, got no host"),
        ("", "expected HOST:PORT, ray://HOST:PORT or auto, got no address"),
    ],
)
def test_a_malformed_or_unknown_address_is_one_line(address, message) -> None:
    with pytest.raises(ClusterError, match=message) as info:
        check_address(address)
    assert "\n" not in str(info.value)


def test_a_server_that_is_not_a_ray_cluster_is_told_apart(http_server) -> None:
    with pytest.raises(ClusterError, match=f"address {http_server}: no Ray cluster reachable"):
        check_address(http_server)


def test_the_running_cluster_passes_the_probe(ray_instance, monkeypatch) -> None:
    address = ray_instance.get_runtime_context().gcs_address
    assert check_address(address) == address
    monkeypatch.setenv("RAY_ADDRESS", address)
    assert check_address("auto") == address


def test_auto_without_a_running_cluster(monkeypatch, tmp_path) -> None:
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    monkeypatch.setenv("RAY_TMPDIR", str(tmp_path))
    with pytest.raises(ClusterError, match="no Ray cluster is running on this machine"):
        check_address("auto")


# Every command whose work splits into units takes --backend ray --address; an address where no
# cluster answers is one line before any work (no output written).
COMMANDS = {
    "generate": ["generate", "--scenario", "mingle", "--episodes", "1", "--seed", "0"],
    "stress": ["stress", "--grid", "small"],
    "benchmark": ["benchmark", "--data", "salsa"],
    "calibrate": ["calibrate", "--data", "DATASETS"],
    "sim2real": ["experiment", "sim2real", "--data", "DATASETS"],
    "hri": ["experiment", "hri"],
}


@pytest.mark.parametrize("command", list(COMMANDS))
def test_an_unreachable_cluster_is_one_line_before_any_work(
    command, free_port, tmp_path, capsys, shared_datasets
) -> None:
    argv = [str(shared_datasets) if w == "DATASETS" else w for w in COMMANDS[command]]
    out = tmp_path / "out"
    argv += ["--out", str(out), "--backend", "ray", "--address", f"127.0.0.1:{free_port}"]
    if command == "sim2real":
        argv += ["--synthetic", str(tmp_path / "synthetic")]
    start = time.perf_counter()
    assert main(argv) == 2
    assert time.perf_counter() - start < 30  # no Ray timeouts, no simulation
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"error: --address 127.0.0.1:{free_port}: no Ray cluster reachable" in err
    assert not out.exists()


@pytest.mark.parametrize("command", list(COMMANDS))
def test_jobs_is_for_the_local_backend(command, tmp_path, capsys, shared_datasets) -> None:
    argv = [str(shared_datasets) if w == "DATASETS" else w for w in COMMANDS[command]]
    argv += ["--out", str(tmp_path / "out"), "--backend", "ray", "--jobs", "2"]
    assert main(argv) == 2
    assert "--jobs sets local worker processes (--backend local)" in capsys.readouterr().err


def test_a_failure_while_a_stop_is_handled_is_that_stop():
    from sim.cli._interrupt import Stopped
    from sim.executor import _interruption

    def cleanup_failing_during(stop: BaseException) -> BaseException:
        try:
            try:
                raise stop
            except KeyboardInterrupt:
                raise RuntimeError("cannot join thread before it is started") from None
        except RuntimeError as exc:
            return exc

    stop = Stopped(signal.SIGTERM)
    assert _interruption(cleanup_failing_during(stop)) is stop
    assert _interruption(RuntimeError("alone")) is None
