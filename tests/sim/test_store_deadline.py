"""Deadlines on the object store: a store that accepts connections and never answers ends
``generate`` and ``data info`` with one line naming the store, the operation and the deadline,
within that deadline (plus 10 s); a deadline that is not a duration above zero is one line
before any work. Against a real socket server on 127.0.0.1 that accepts and never answers."""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from killed_run import CLI

from reform.datasets.store import TIMEOUT_S, TIMEOUT_VARIABLE, StoreError, timeout

pytestmark = pytest.mark.faults  # the fault suite: pytest -m faults

REPO_ROOT = Path(__file__).resolve().parents[2]
DEADLINE_S = 2.0  # seconds: the deadline the tests set
SLACK_S = 10.0  # seconds a command may take beyond its deadline (start-up included)
GENERATE = ["generate", "--scenario", "hri-conversation", "--episodes", "2", "--duration", "5"]


@contextlib.contextmanager
def _silent_server() -> Iterator[int]:
    """A server on 127.0.0.1 that accepts every connection and never answers: its port."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(64)
    held: list[socket.socket] = []
    stop = threading.Event()

    def accept() -> None:
        server.settimeout(0.1)
        while not stop.is_set():
            with contextlib.suppress(TimeoutError):
                held.append(server.accept()[0])

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    try:
        yield server.getsockname()[1]
    finally:
        stop.set()
        thread.join()
        for connection in held:
            connection.close()
        server.close()


@pytest.fixture
def silent_store() -> Iterator[dict[str, str]]:
    """The environment of an S3 store at a server that never answers, with a 2 s deadline."""
    with _silent_server() as port:
        yield {
            "AWS_ACCESS_KEY_ID": "lab-key",
            "AWS_SECRET_ACCESS_KEY": "lab-secret",
            "AWS_ENDPOINT_URL": f"http://127.0.0.1:{port}",
            "AWS_DEFAULT_REGION": "us-east-1",
            "AWS_EC2_METADATA_DISABLED": "true",
            TIMEOUT_VARIABLE: f"{DEADLINE_S:g}",
        }


def _run(argv: list[str], env: dict[str, str]) -> tuple[subprocess.CompletedProcess, float]:
    started = time.monotonic()
    done = subprocess.run(
        [*CLI, *argv],
        cwd=REPO_ROOT,
        env=os.environ | env,
        capture_output=True,
        text=True,
        timeout=DEADLINE_S + SLACK_S + 30,  # a hang fails the test, not the suite
    )
    return done, time.monotonic() - started


@pytest.mark.parametrize(
    "argv",
    [[*GENERATE, "--out", "s3://lab/ds", "--quiet"], ["data", "info", "--data", "s3://lab/ds"]],
    ids=["generate", "data-info"],
)
def test_a_store_that_never_answers_ends_the_command_within_its_deadline(argv, silent_store):
    done, seconds = _run(argv, silent_store)
    assert seconds < DEADLINE_S + SLACK_S
    assert done.returncode == 2
    (line,) = done.stderr.splitlines()
    assert line.endswith(
        f"s3://lab/ds: the store did not answer within {DEADLINE_S:g} s (list); check the store "
        f"and the network, or give it longer with {TIMEOUT_VARIABLE}=SECONDS"
    )


@pytest.mark.parametrize("value", ["0", "-2", "0s", "soon", "2 hours", "1" + "0" * 30, "\u0663"])
def test_a_deadline_that_is_not_a_duration_above_zero_is_one_line_before_any_work(
    value, silent_store, tmp_path
):
    done, _ = _run(
        [*GENERATE, "--out", "s3://lab/ds", "--quiet"], silent_store | {TIMEOUT_VARIABLE: value}
    )
    assert done.returncode == 2
    (line,) = done.stderr.splitlines()
    assert line.endswith(
        f"{TIMEOUT_VARIABLE} must be a duration above zero and at most 30 days (seconds, or with "
        f"a unit: 90s, 2m, 500ms), got {value!r}"
    )


@pytest.mark.parametrize(
    ("text", "seconds"),
    [("30", 30.0), ("1.5", 1.5), ("90s", 90.0), ("2m", 120.0), ("500ms", 0.5), (" 3 s ", 3.0)],
)
def test_deadlines_read_as_durations(text, seconds):
    assert timeout(text) == seconds


def test_the_default_deadline(monkeypatch):
    monkeypatch.delenv(TIMEOUT_VARIABLE, raising=False)
    assert timeout() == TIMEOUT_S
    monkeypatch.setenv(TIMEOUT_VARIABLE, "7s")
    assert timeout() == 7.0
    monkeypatch.setenv(TIMEOUT_VARIABLE, "never")
    with pytest.raises(StoreError, match=f"^{TIMEOUT_VARIABLE} must be a duration above zero"):
        timeout()
