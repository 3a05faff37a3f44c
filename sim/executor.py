"""Where independent units of work run: this process, local worker processes, or a Ray cluster.

A command whose work splits into independent units (episodes to simulate, detectors to fit,
cells of a benchmark) maps one picklable function over them with an `Executor`::

    with Executor("ray", address="10.0.0.5:6379") as executor:
        cells = executor.map(score, units, desc="benchmark")

`Executor.map` returns the results in the order of the units, whichever worker ran which unit
and in whatever order they finished, so a run gives the same results bit for bit on either
backend and with any number of workers, provided each unit is deterministic on its own (seeded
from the unit, never from the worker). `Executor.imap_unordered` yields ``(index, result)`` as
units finish, for a caller that handles each result as it comes (writes a dataset's shard).

Backends (:data:`BACKENDS`):

* ``"local"``: ``jobs`` worker processes on this machine (joblib's loky; every core by
  default). With one job, or one unit, the units run in this process, in order. A run stopped
  by an exception (Ctrl-C, SIGTERM through `sim.cli`) terminates its workers; a driver killed
  outright takes them with it (each ends as soon as its parent is gone). A worker killed by a
  signal (the out-of-memory killer's SIGKILL, a crash in compiled code) stops the run with one
  `WorkerDied` naming the unit it held (each worker notes the unit it runs in a folder of the
  run's, with where a crash happened) and, for SIGKILL, the likely cause.
* ``"ray"``: one Ray task per unit on every CPU of the cluster at ``address``, of the Ray
  instance this process has already joined, or of one started on this machine. A unit whose
  node or result is lost runs again, up to :data:`MAX_RETRIES` times, with one line on stderr
  naming the node (a cluster left with no CPU is waited for :data:`NODE_WAIT_S` seconds, then
  the run stops with one `ClusterError`); one whose worker process died runs again once, and a
  second death is blamed on the unit (named, as `WorkerDied`), as is a worker Ray stopped for
  lack of memory. An exception the function raises is not retried (it would raise again): the
  run stops with that exception, as on the local backend.

Arguments every unit shares (``shared``: fitted detectors, a training set) are sent once: Ray
puts them in its object store once and each task reads them from there.

An ``address`` is probed before Ray is asked to join it (:func:`check_address`): where nothing
answers, the run stops within seconds with one line, before any work, rather than after Ray's
own long connection timeouts.
"""

from __future__ import annotations

import contextlib
import faulthandler
import logging
import os
import pickle
import re
import signal
import socket
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from reform.atomic import temporary_folder
from reform.deadline import hard_stopping, hard_stops
from sim.progress import progress_bar
from sim.ticking import ticking

__all__ = [
    "BACKENDS",
    "MAX_RETRIES",
    "ClusterError",
    "WorkerDied",
    "Executor",
    "check_address",
    "cpu_count",
    "import_ray",
]

BACKENDS = ("local", "ray")
MAX_RETRIES = 3  # times a unit runs again after its Ray node or its result was lost
PROBE_TIMEOUT_S = 3.0  # seconds a cluster address has to accept a connection
GCS_PORT = 6379  # Ray's default cluster (GCS) port: ``ray start --head`` listens there
CLIENT_PORT = 10001  # Ray Client's default port (``ray://host``)
CLIENT_SCHEME = "ray://"
AUTO = "auto"  # the cluster started on this machine by ``ray start --head``
RAY_ADDRESS_VARIABLE = "RAY_ADDRESS"
GCS_PROBE_METHOD = "/ray.rpc.NodeInfoGcsService/GetClusterId"  # every Ray GCS serves it
RAY_INSTALL = "pip install 'reform-sim[ray]' (or pip install ray)"
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>: the signal a process gets when its parent dies
NOTE_POLL_S = 0.1  # seconds between a run's looks for units its workers start
STUCK_NOTE = "stuck: "  # before the line of a worker's unit stuck in compiled code, in its note
NOTES_FOLDER = "reform-sim"  # in the system's temporary folder: where runs note their units
PARENT_CHECK_S = 0.5  # seconds between a local worker's looks at its parent (not on Linux)
EXIT_ORPHANED = 1  # exit status of a local worker whose parent is gone
NODE_CHECK_S = 5.0  # seconds between a Ray run's looks at its cluster's CPUs while it waits
NODE_WAIT_S = 300.0  # seconds a Ray run that lost a node waits for a CPU when none is left
CANCEL_WAIT_S = 20.0  # seconds a stopped Ray run waits for its cancelled units to end
_CRASHED = "WorkerCrashedError"  # a Ray unit whose worker process died: run again once


def _last_line(exc: BaseException) -> str:
    """An exception as one line: its message's last line that says something (a remote
    traceback's text ends with the error itself), else its type."""
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip().strip('"')]
    return lines[-1] if lines else type(exc).__name__


class ClusterError(ConnectionError):
    """A Ray cluster that cannot be reached, or that lost a unit's worker more often than
    :data:`MAX_RETRIES` allows. One line, naming the address or the unit."""


class WorkerDied(ChildProcessError):
    """A local worker process killed by a signal while it ran a unit: one line naming the unit
    (what ``describe`` says of it), the signal and, for SIGKILL, the likely cause."""


def cpu_count() -> int:
    """The CPUs this process may run on (its affinity, else the machine's)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def import_ray() -> Any:
    """The ``ray`` module; an ImportError with the install command when it is missing."""
    try:
        import ray
    except ImportError as exc:
        raise ImportError(f"backend 'ray' needs Ray: {RAY_INSTALL}") from exc
    return ray


def _split(address: str) -> tuple[str, int]:
    """``host:port`` (or ``host``, or ``[v6]:port``) as ``(host, port)``."""
    scheme_port = CLIENT_PORT if address.startswith(CLIENT_SCHEME) else GCS_PORT
    rest = address.removeprefix(CLIENT_SCHEME)
    if rest.startswith("["):  # [IPv6]:port
        host, _, tail = rest[1:].partition("]")
        port_text = tail.removeprefix(":")
    elif rest.count(":") == 1:
        host, port_text = rest.split(":")
    else:
        host, port_text = rest, ""
    if not host:
        raise ClusterError(
            f"address {address}: expected HOST:PORT, ray://HOST:PORT or {AUTO}, got no host"
        )
    if not port_text:
        return host, scheme_port
    if not port_text.isdigit() or not 0 < int(port_text) < 65536:
        raise ClusterError(
            f"address {address}: expected a port number 1-65535 after the host, got {port_text!r}"
        )
    return host, int(port_text)


def _running_cluster() -> str | None:
    """The address of the cluster ``ray start --head`` started on this machine, if any:
    ``$RAY_ADDRESS``, else the file Ray leaves in its temporary folder."""
    named = os.environ.get(RAY_ADDRESS_VARIABLE)
    if named and named != AUTO:
        return named
    temp = Path(os.environ.get("RAY_TMPDIR", "/tmp")) / "ray" / "ray_current_cluster"
    try:
        text = temp.read_text().strip()
    except OSError:
        return None
    return text or None


def check_address(address: str) -> str:
    """Probes a Ray cluster address with one short connection, before Ray is asked to join it.

    Args:
        address: ``HOST:PORT`` (the cluster's GCS, what ``ray start --head`` prints; the port
            defaults to 6379), ``ray://HOST:PORT`` (Ray Client, port 10001 by default), or
            ``"auto"`` (the cluster running on this machine).

    Returns:
        The address as given (``"auto"`` resolved to the running cluster's).

    Raises:
        ClusterError: nothing answers there within :data:`PROBE_TIMEOUT_S` seconds, the host
            name does not resolve, or the address is malformed; one line naming it.
    """
    if not isinstance(address, str) or not address.strip():
        raise ClusterError(
            f"address {address!r}: expected HOST:PORT, ray://HOST:PORT or {AUTO}, got no address"
        )
    address = address.strip()
    given = address
    if address == AUTO:
        found = _running_cluster()
        if found is None:
            raise ClusterError(
                f"address {AUTO}: no Ray cluster is running on this machine (start one with "
                "`ray start --head`, or give its HOST:PORT)"
            )
        address = found
    host, port = _split(address)
    why = _unreachable(host, port)
    if why is None and not address.startswith(CLIENT_SCHEME):
        why = _not_a_cluster(host, port)
    if why is None:
        return address
    shown = given if given == address else f"{given} ({address})"
    raise ClusterError(
        f"address {shown}: no Ray cluster reachable, {why}; start one with `ray start --head` "
        "and give the address it prints"
    )


def _unreachable(host: str, port: int) -> str | None:
    """Why no connection to ``host:port`` can be made, or None when one can."""
    try:
        with socket.create_connection((host, port), timeout=PROBE_TIMEOUT_S):
            return None
    except socket.gaierror:
        return f"host {host!r} is not known"
    except ConnectionRefusedError:
        return f"nothing listens at {host}:{port}"
    except TimeoutError:
        return f"{host}:{port} did not answer within {PROBE_TIMEOUT_S:g} s"
    except OSError as exc:
        return f"{host}:{port}: {exc.strerror or exc}"


def _not_a_cluster(host: str, port: int) -> str | None:
    """Why what answers at ``host:port`` is not a Ray cluster's GCS, or None when it is (or
    when gRPC, which Ray's extra installs, is missing to ask it).

    One gRPC call to the GCS (its cluster id): a Ray GCS answers it, or refuses it for a
    missing authentication token, which ``ray.init`` then supplies; a server of another kind
    (a proxy, a database on Redis's port) answers that it has no such method.
    """
    try:
        import grpc
    except ImportError:  # pragma: no cover - the ray extra installs it
        return None
    channel = grpc.insecure_channel(f"{host}:{port}")
    call = channel.unary_unary(
        GCS_PROBE_METHOD,
        request_serializer=lambda _request: b"",
        response_deserializer=lambda reply: reply,
    )
    try:
        call(None, timeout=PROBE_TIMEOUT_S)
    except grpc.RpcError as exc:
        code = exc.code()
        if code in (grpc.StatusCode.UNAUTHENTICATED, grpc.StatusCode.PERMISSION_DENIED):
            return None
        if code == grpc.StatusCode.DEADLINE_EXCEEDED:
            return f"{host}:{port} did not answer as a Ray cluster within {PROBE_TIMEOUT_S:g} s"
        if code == grpc.StatusCode.UNAVAILABLE:
            return f"{host}:{port} is unavailable ({exc.details()})"
        return f"what answers at {host}:{port} is not a Ray cluster ({exc.details()})"
    finally:
        channel.close()
    return None


@contextlib.contextmanager
def _signals_kept() -> Iterator[None]:
    """Within: whatever replaces this process's SIGTERM and SIGINT handlers is undone at the
    end. Joining Ray installs its core's own (which logs a stack and exits with status 1),
    over the command's, which stop its work and say so in one line."""
    main = threading.current_thread() is threading.main_thread()
    kept = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGINT)} if main else {}
    try:
        yield
    finally:
        for signum, handler in kept.items():
            if handler is not None:  # None: not set from Python, nothing to restore
                signal.signal(signum, handler)


def _start_worker(parent: int, environment: dict[str, str] | None) -> None:
    """A local worker's initializer: it ends with its parent, and sets ``environment``
    (``os.environ.update`` itself would travel as a bound method of a copy of this process's
    ``os.environ``, and update that copy)."""
    _end_with_parent(parent)
    if environment is not None:
        os.environ.update(environment)


def _end_with_parent(parent: int) -> None:
    """Makes this process end as soon as ``parent`` (the process that started it) is gone: a
    driver killed with SIGKILL cannot stop its workers, which would otherwise compute and write
    on for minutes.

    On Linux the kernel sends this process SIGKILL when its parent dies (``PR_SET_PDEATHSIG``;
    it follows the thread that started the worker, which in joblib's pool lives as long as the
    pool); elsewhere a daemon thread looks every :data:`PARENT_CHECK_S` seconds. A parent gone
    before either was set up is seen at once.
    """
    if sys.platform.startswith("linux"):
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        armed = libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) == 0
    else:
        armed = False
    if os.getppid() != parent:
        os._exit(EXIT_ORPHANED)
    if not armed:
        threading.Thread(
            target=_watch_parent, args=(parent,), name="reform-sim-parent", daemon=True
        ).start()


def _watch_parent(parent: int) -> None:
    while True:
        time.sleep(PARENT_CHECK_S)
        if os.getppid() != parent:
            os._exit(EXIT_ORPHANED)


def _apply(function: Callable[..., Any], unit: Any, *shared: Any) -> Any:
    return function(unit, *shared)


def _noted(
    notes: str,
    stop: str | None,
    function: Callable[..., Any],
    k: int,
    unit: Any,
    *shared: Any,
) -> tuple[int, Any]:
    """``(k, function(unit, *shared))`` in a local worker, which notes in the folder ``notes``
    that it runs unit ``k`` while it does (a crash's traceback written under the note), so that
    the driver can name the unit of a worker killed meanwhile; with ``stop`` (the driver's
    `reform.deadline.hard_stops`), a call stuck in compiled code past its deadline ends the
    worker, its line written under the note after :data:`STUCK_NOTE`."""
    path = os.path.join(notes, f"{k}.unit")
    with open(path, "w") as note:
        note.write(f"{os.getpid()}\n")
        note.flush()
        faulthandler.enable(file=note)  # a crash's Python traceback: here, not on the terminal
        try:
            with hard_stops(STUCK_NOTE, to=path) if stop else contextlib.nullcontext():
                result = function(unit, *shared)
        finally:
            faulthandler.disable()
    os.remove(path)
    return k, result


class _DeathWatch:
    """Watches the worker processes the notes in a folder name, and remembers the first to end:
    when one is killed, the pool kills the others at once, and only this order tells which
    worker's unit was the cause (Linux's process file descriptors; elsewhere nothing is
    remembered, and every unit that was running is named)."""

    def __init__(self, notes: str) -> None:
        self.notes = notes
        self.first: int | None = None  # the process id of the first worker seen to end
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        if hasattr(os, "pidfd_open"):
            self._thread = threading.Thread(
                target=self._watch, name="reform-sim-deaths", daemon=True
            )
            self._thread.start()

    def _watch(self) -> None:
        import select

        watched: dict[int, int] = {}  # pidfd -> pid
        try:
            while not self._stop.is_set() and self.first is None:
                for pid in _noted_pids(self.notes):
                    if pid not in watched.values():
                        try:
                            watched[os.pidfd_open(pid)] = pid
                        except OSError:  # gone already
                            self.first = pid
                            return
                ready, _, _ = select.select(list(watched), [], [], NOTE_POLL_S)
                if ready:
                    self.first = watched[ready[0]]
        finally:
            for fd in watched:
                os.close(fd)

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2 * NOTE_POLL_S)


def _noted_pids(notes: str) -> list[int]:
    """The process ids the notes in ``notes`` name (units being run)."""
    pids = []
    for entry in os.listdir(notes) if os.path.isdir(notes) else ():
        try:
            with open(os.path.join(notes, entry)) as note:
                pids.append(int(note.readline()))
        except (OSError, ValueError):  # removed meanwhile, or not written yet
            continue
    return pids


_STUCK = re.compile(f"^{STUCK_NOTE}(.+)$", re.MULTILINE)
_CODES = re.compile(r"\b(SIG[A-Z0-9]+)\((-?\d+)\)|\bEXIT\((-?\d+)\)")
_CRASH_AT = re.compile(r'File "([^"]+)", line (\d+) in (\S+)')


def _died(
    exc: BaseException,
    notes: str,
    units: Sequence[Any],
    describe: Callable[[Any], str] | None,
    first: int | None = None,
) -> WorkerDied:
    """The one-line `WorkerDied` for loky's ``TerminatedWorkerError`` ``exc``: the signal from
    the exit codes it lists, the unit(s) the notes in ``notes`` say were running: one whose note
    holds a crash's traceback, with where it crashed, else that of the worker ``first`` to end,
    else every one."""
    codes = _CODES.findall(str(exc))
    signals = [name for name, _, _ in codes if name]
    status = next((code for name, _, code in codes if not name), None)
    held: list[tuple[bool, int, str]] = []
    for entry in os.listdir(notes) if os.path.isdir(notes) else ():
        if not entry.endswith(".unit"):
            continue
        with open(os.path.join(notes, entry), errors="replace") as note:
            text = note.read()
        stuck = _STUCK.search(text)
        if stuck is not None:  # its deadline's watcher ended it, and said why
            return WorkerDied(stuck.group(1))
        k = int(entry.removesuffix(".unit"))
        crash = _CRASH_AT.search(text)
        where = (
            f" (crashed in {crash.group(3)} at {crash.group(1)}:{crash.group(2)})" if crash else ""
        )
        if crash is not None or text.split("\n", 1)[0] == str(first):
            held = [(False, k, where)]
            break
        held.append((True, k, where))
    held.sort()

    def name(k: int) -> str:
        return describe(units[k]) if describe is not None else f"unit {k}"

    if not held:
        what = "a unit of the run"
    elif not held[0][0] or len(held) == 1:
        what = name(held[0][1]) + held[0][2]
    else:
        what = " or ".join(name(k) for _, k, _ in held) + " (one of these)"
    if "SIGKILL" in signals:
        return WorkerDied(
            f"a worker process was killed (SIGKILL) while it ran {what}: most likely the machine "
            "ran out of memory and the system's out-of-memory killer ended it (see `dmesg`); "
            "give the run more memory, or run fewer units at once (--jobs)"
        )
    if signals:
        return WorkerDied(
            f"a worker process died of {signals[0]} while it ran {what}: a crash in compiled code "
            "it called (a native extension, a detector's library)"
        )
    how = f"with status {status}" if status is not None else "unexpectedly"
    return WorkerDied(f"a worker process ended {how} while it ran {what}")


def _interruption(exc: BaseException) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt (Ctrl-C, or a `sim.cli._interrupt.Stopped`) in whose handling
    ``exc`` was raised, following its context chain; None when there is none."""
    seen: set[int] = set()
    link: BaseException | None = exc.__context__
    while link is not None and id(link) not in seen:
        if isinstance(link, KeyboardInterrupt):
            return link
        seen.add(id(link))
        link = link.__context__
    return None


class Executor:
    """Runs a function over independent units, on local processes or on a Ray cluster.

    Use it as a context manager: a Ray instance it starts (or joins) is shut down at the end;
    one this process had joined before is left running.

    Args:
        backend: ``"local"`` or ``"ray"`` (:data:`BACKENDS`).
        jobs: local worker processes (None: every core); must be None with Ray, whose workers
            are the cluster's CPUs.
        address: the Ray cluster (``HOST:PORT``, ``ray://HOST:PORT``, ``"auto"``); None joins
            the Ray instance this process has joined, else starts one on this machine. Probed
            at once (:func:`check_address`). A process already joined to a Ray instance keeps
            it (Ray joins one per process).
        progress: show a tqdm bar on stderr for each `map` given a ``desc``.
        environment: variables every local worker process sets before its first unit (the
            store credentials a unit reads, as this process has them now): local worker
            processes outlive a run and are reused by the next, and keep the environment they
            were started with; a pool started with other values is not reused. Local backend
            only: Ray's workers take their node's environment.

    Raises:
        ValueError: an unknown backend, ``jobs`` < 1, ``jobs``, ``address`` or
            ``environment`` with the wrong backend.
        ClusterError: an ``address`` where no cluster answers.
        ImportError: ``"ray"`` without Ray installed.
    """

    def __init__(
        self,
        backend: str = "local",
        *,
        jobs: int | None = None,
        address: str | None = None,
        progress: bool = True,
        environment: Mapping[str, str] | None = None,
    ) -> None:
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
        if jobs is not None and (isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1):
            raise ValueError(f"jobs must be None or an int >= 1, got {jobs!r}")
        if backend == "ray" and jobs is not None:
            raise ValueError(
                f"jobs sets local worker processes; with backend 'ray' every CPU of the cluster "
                f"works, got jobs={jobs}"
            )
        if address is not None and backend != "ray":
            raise ValueError(
                f"address is for backend 'ray', got address={address!r} with {backend!r}"
            )
        if environment is not None and backend != "local":
            raise ValueError(
                f"environment is for backend 'local' (Ray's workers take their node's), got "
                f"{sorted(environment)} with {backend!r}"
            )
        self.backend = backend
        self.jobs = jobs
        self.environment = None if environment is None else dict(environment)
        self.address = address
        self.progress = progress
        self._ray: Any = None
        self._owned = False
        self._task: Any = None
        if backend == "ray":
            import_ray()
            if address is not None:
                check_address(address)

    def __repr__(self) -> str:
        where = f"jobs={self.jobs}" if self.backend == "local" else f"address={self.address!r}"
        return f"Executor({self.backend!r}, {where})"

    # -- lifecycle ------------------------------------------------------------------------

    def __enter__(self) -> Executor:
        if self.backend == "ray":
            self._connect()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Shuts down the Ray instance this executor started or joined (not one the process
        had joined before it)."""
        if self._owned and self._ray is not None:
            self._ray.shutdown()
        self._ray, self._owned, self._task = None, False, None

    def _connect(self) -> Any:
        if self._ray is None:
            ray = import_ray()
            if not ray.is_initialized():
                try:
                    with _signals_kept():
                        ray.init(
                            address=self.address,
                            log_to_driver=False,
                            include_dashboard=False,
                            logging_level=logging.WARNING,  # not "Connected to Ray cluster."
                        )
                except (ConnectionError, RuntimeError) as exc:  # answered the probe, not Ray
                    first = str(exc).strip().splitlines()[0] if str(exc).strip() else repr(exc)
                    raise ClusterError(
                        f"address {self.address}: Ray could not join the cluster ({first})"
                    ) from None
                self._owned = True
            self._ray = ray
        return self._ray

    # -- what it runs on --------------------------------------------------------------------

    @property
    def remote(self) -> bool:
        """Whether units may run on other machines (no shared disk with this process)."""
        return self.backend == "ray"

    @property
    def workers(self) -> int:
        """Units that run at once: local processes, or the Ray cluster's CPUs."""
        if self.backend == "ray":
            ray = self._connect()
            return max(1, int(ray.cluster_resources().get("CPU", 1)))
        return cpu_count() if self.jobs is None else self.jobs

    def describe(self) -> dict[str, Any]:
        """The backend and its workers, for a run's record (JSON values)."""
        out: dict[str, Any] = {"backend": self.backend, "workers": self.workers}
        if self.address is not None:
            out["address"] = self.address
        return out

    # -- mapping ----------------------------------------------------------------------------

    def map(
        self,
        function: Callable[..., Any],
        units: Sequence[Any],
        *,
        shared: Sequence[Any] = (),
        desc: str | None = None,
        unit: str = "task",
        on_done: Callable[[int, int, Any], None] | None = None,
        describe: Callable[[Any], str] | None = None,
    ) -> list[Any]:
        """``[function(u, *shared) for u in units]``, the units run in parallel.

        Args:
            function: a picklable function (defined at a module's top level).
            units: the units, each picklable.
            shared: further arguments every call takes, sent once.
            desc: the progress bar's label (no bar without it, or with ``progress=False``).
            unit: what a unit is called in the bar.
            on_done: called as ``on_done(done, total, result)`` as each unit finishes.
            describe: what a unit is, in a message (``"detector gcff on salsa"``), for a unit
                whose worker died; ``"unit K"`` without it.

        Returns:
            The results in the order of ``units``.
        """
        units = list(units)
        results: list[Any] = [None] * len(units)
        with (
            progress_bar(
                total=len(units),
                desc=desc,
                unit=unit,
                file=sys.stderr,
                disable=not (self.progress and desc),
                dynamic_ncols=True,
            ) as bar,
            ticking(bar),
        ):  # redrawn while the workers start or a long unit runs
            for done, (k, result) in enumerate(
                self.imap_unordered(function, units, shared=shared, describe=describe), start=1
            ):
                results[k] = result
                bar.update(1)
                if on_done is not None:
                    on_done(done, len(units), result)
        return results

    def imap_unordered(
        self,
        function: Callable[..., Any],
        units: Sequence[Any],
        *,
        shared: Sequence[Any] = (),
        describe: Callable[[Any], str] | None = None,
    ) -> Iterator[tuple[int, Any]]:
        """``(k, function(units[k], *shared))`` for every unit, as units finish (``describe``:
        as in `map`)."""
        units = list(units)
        shared = tuple(shared)
        if not units:
            return iter(())
        if self.backend == "ray":
            return self._ray_stream(function, units, shared, describe)
        return self._local_stream(function, units, shared, describe)

    def _local_stream(
        self,
        function: Callable[..., Any],
        units: list[Any],
        shared: tuple[Any, ...],
        describe: Callable[[Any], str] | None = None,
    ) -> Iterator[tuple[int, Any]]:
        workers = min(self.workers, len(units))
        if workers <= 1:
            for k, item in enumerate(units):
                yield k, function(item, *shared)
            return
        from joblib import Parallel, delayed
        from joblib.externals.loky.process_executor import TerminatedWorkerError

        parallel = Parallel(
            n_jobs=workers,
            backend="loky",
            return_as="generator_unordered",
            batch_size=1,
            initializer=_start_worker,
            initargs=(os.getpid(), self.environment),
        )
        # What each worker runs, noted in a folder named for this process: one that a killed
        # driver leaves is removed by the next run (reform.atomic's temporaries).
        with temporary_folder(Path(tempfile.gettempdir()) / NOTES_FOLDER / "units") as folder:
            notes = str(folder)
            deaths = _DeathWatch(notes)
            try:
                stop = hard_stopping()  # a unit stuck in compiled code ends its worker (the note)
                yield from parallel(
                    delayed(_noted)(notes, stop, function, k, item, *shared)
                    for k, item in enumerate(units)
                )
            except TerminatedWorkerError as exc:
                deaths.close()
                raise _died(exc, notes, units, describe, deaths.first) from None
            except pickle.PicklingError as exc:  # something the work holds cannot be sent
                what = _last_line(exc.__cause__ or exc)
                raise ValueError(
                    f"the work cannot be sent to {workers} worker processes ({what}): something "
                    "it holds, such as a detector's lock, socket or open file, cannot be copied "
                    "to another process; keep such things out of its attributes, or run with "
                    "--jobs 1"
                ) from exc
            except Exception as exc:
                # A stop (Ctrl-C, SIGTERM) that reached joblib while it started or ended its
                # pool can make the pool's clean-up fail in turn (loky joining a manager thread
                # the stop kept from starting): the stop is what happened, and it goes on.
                stop = _interruption(exc)
                if stop is None:
                    raise
                raise stop from None
            finally:
                deaths.close()

    def _ray_stream(
        self,
        function: Callable[..., Any],
        units: list[Any],
        shared: tuple[Any, ...],
        describe: Callable[[Any], str] | None = None,
    ) -> Iterator[tuple[int, Any]]:
        """Every unit a Ray task, run again here (not by Ray: the reason decides) when its
        worker is lost: a lost node or object up to :data:`MAX_RETRIES` times; a worker process
        that died under the unit once (the same unit ending a second worker is the unit's doing:
        a crash in compiled code, an exit, memory); never when Ray stopped it for memory.

        Each unit run again is one line on stderr naming why (the node lost, by its IP and ID as
        Ray gives them). A run whose cluster had CPUs and has none left (its nodes lost, under a
        unit or between two) waits :data:`NODE_WAIT_S` seconds for a node to join, then stops in
        one line."""
        ray = self._connect()
        if self._task is None:
            self._task = ray.remote(num_cpus=1, max_retries=0, retry_exceptions=False)(_apply)
        refs = [ray.put(value) for value in shared]
        index = {}
        for k, item in enumerate(units):
            index[self._task.remote(function, item, *refs)] = k
        pending = list(index)
        lost = dict.fromkeys(range(len(units)), 0)
        nodes: dict[int, list[str]] = {}  # unit -> the nodes lost while they ran it, in order
        known = _cpu_nodes(ray)  # every node with CPUs seen during the run
        starved_since: float | None = None  # when the cluster was first seen with no CPU
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1, timeout=NODE_CHECK_S)
                if not done:
                    live = _cpu_nodes(ray)
                    known.update(live)
                    # A cluster that never had a CPU may be starting its first node (autoscaler).
                    if live or not (known or nodes):
                        starved_since = None
                    else:
                        starved_since = starved_since or time.monotonic()
                        if time.monotonic() - starved_since >= NODE_WAIT_S:
                            raise _starved(index, units, describe, nodes, list(known.values()))
                    continue
                k = index.pop(done[0])
                what = _name(units, k, describe)
                try:
                    result = self._get(ray, done[0], what, lost[k], nodes.get(k, []))
                except _Lost as exc:
                    lost[k] += 1
                    if exc.node is not None:
                        nodes.setdefault(k, []).append(exc.node)
                    _say(_rerun_line(ray, what, exc, lost[k]))
                    again = self._task.remote(function, units[k], *refs)
                    index[again] = k
                    pending.append(again)
                    continue
                yield k, result
        finally:
            for ref in pending:  # stopped early (an error, Ctrl-C): the rest need not run
                ray.cancel(ref, force=True)
            if pending:  # and the run ends once they have: none is left computing after it
                ray.wait(pending, num_returns=len(pending), timeout=CANCEL_WAIT_S)

    def _get(self, ray: Any, ref: Any, what: str, lost: int, nodes: list[str]) -> Any:
        """The task's result; its own error raised as it was; `_Lost` when it should run
        again (``lost``: times its worker was lost before, ``nodes``: the nodes lost under it);
        else one line naming ``what``."""
        from ray.exceptions import OutOfMemoryError, RayError, RayTaskError, WorkerCrashedError

        try:
            return ray.get(ref)
        except RayTaskError as exc:
            cause = getattr(exc, "cause", None)
            if isinstance(cause, BaseException):  # the function's own error, as locally
                raise cause from None
            raise
        except RayError as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            why = f"{type(exc).__name__}: {first}"
            node = _lost_node(exc)
            if isinstance(exc, OutOfMemoryError):
                raise WorkerDied(
                    f"Ray stopped the worker that ran {what} for lack of memory ({why}); give "
                    "the cluster's nodes more memory, or run fewer units on each"
                ) from None
            if isinstance(exc, WorkerCrashedError):
                if lost < 1:
                    raise _Lost(None, _CRASHED) from None
                raise WorkerDied(
                    f"{what} ended the Ray worker process that ran it, twice ({why}): the unit "
                    "itself ends its process (a crash in compiled code it calls, an exit, or "
                    "the system's out-of-memory killer), not the cluster; the worker's log "
                    "(python-core-worker-*.log) has its last words"
                ) from None
            if lost < MAX_RETRIES:
                raise _Lost(node, type(exc).__name__) from None
            if node is not None:
                nodes = [*nodes, node]
            if nodes:
                why = f"the cluster lost {_nodes(nodes)}, which ran it"
            times = "once" if MAX_RETRIES == 0 else f"{MAX_RETRIES + 1} times"
            raise ClusterError(
                f"{what} was lost {times} on the Ray cluster ({why}): its nodes "
                "keep failing (`ray list nodes --detail` says why: preemption, memory, a crashed "
                "raylet); run the command again on a steadier cluster"
            ) from None


class _Lost(Exception):
    """A Ray task's worker was lost and the unit should run again: ``node``, the node lost
    (its IP and ID as Ray gives them) when that was the cause, else ``cause``, Ray's error."""

    def __init__(self, node: str | None, cause: str) -> None:
        super().__init__(node or cause)
        self.node = node
        self.cause = cause


def _name(units: Sequence[Any], k: int, describe: Callable[[Any], str] | None) -> str:
    return describe(units[k]) if describe is not None else f"unit {k}"


_NODE_DIED = re.compile(r"Node IP: (?P<ip>[^\s,]+), node ID: (?P<id>[0-9a-fA-F]+)")


def _lost_node(exc: BaseException) -> str | None:
    """The node a Ray error says was lost, as ``IP (ID id)``; None for another error. Ray
    names it in its text only (`ray.exceptions.NodeDiedError`)."""
    found = _NODE_DIED.search(str(exc))
    if found is None:
        return None
    return f"{found['ip']} (ID {found['id']})"


def _nodes(names: Sequence[str]) -> str:
    unique = list(dict.fromkeys(names))
    return f"node {unique[0]}" if len(unique) == 1 else f"nodes {', '.join(unique)}"


def _cpu_nodes(ray: Any) -> dict[str, str]:
    """The cluster's live nodes with CPUs: ID -> ``IP (ID id)``, as `_lost_node` names them."""
    return {
        node["NodeID"]: f"{node['NodeManagerAddress']} (ID {node['NodeID']})"
        for node in ray.nodes()
        if node.get("Alive") and node.get("Resources", {}).get("CPU", 0) > 0
    }


def _say(line: str) -> None:
    """A line on stderr, above any progress bar being drawn."""
    tqdm = sys.modules.get("tqdm")
    if tqdm is not None:
        tqdm.tqdm.write(line, file=sys.stderr)
    else:
        print(line, file=sys.stderr, flush=True)


def _rerun_line(ray: Any, what: str, lost: _Lost, times: int) -> str:
    """The line a unit run again gets: what was lost, and where the unit runs now."""
    if lost.cause == _CRASHED:
        return (
            f"reform-sim: the Ray worker process that ran {what} died; it runs again once (a "
            "second death is blamed on it)"
        )
    if lost.node is None:
        return (
            f"reform-sim: Ray lost {what} ({lost.cause}); it runs again ({times} of {MAX_RETRIES})"
        )
    if not _cpu_nodes(ray):
        where = (
            f"when a node with a CPU joins the cluster: none is left, and the run waits "
            f"{NODE_WAIT_S:g} s for one"
        )
    else:
        where = "on the cluster's other nodes"
    return (
        f"reform-sim: the Ray cluster lost node {lost.node} while it ran {what}; it runs again "
        f"({times} of {MAX_RETRIES}) {where}"
    )


def _starved(
    index: Mapping[Any, int],
    units: Sequence[Any],
    describe: Callable[[Any], str] | None,
    nodes: Mapping[int, list[str]],
    known: Sequence[str],
) -> ClusterError:
    """The error of a run whose cluster lost its nodes (``nodes``: those lost under a unit, by
    unit; ``known``: every node with CPUs the run saw, gone now) and has had no CPU for
    :data:`NODE_WAIT_S` seconds: a unit waiting to run (one that ran on a lost node first), the
    nodes lost, what to do."""
    waiting = sorted(set(index.values()))
    again = [k for k in waiting if k in nodes]
    first = (again or waiting)[0]
    what = _name(units, first, describe)
    more = f" (and {len(waiting) - 1} more unit(s))" if len(waiting) > 1 else ""
    ran = list(dict.fromkeys(nodes.get(first, [])))
    others = [node for node in dict.fromkeys(known) if node not in ran]
    if ran:
        lost = f"{_nodes(ran)}, which ran it," + (f" and {_nodes(others)}," if others else "")
    else:
        lost = _nodes(others)
    return ClusterError(
        f"{what}{more} cannot run: the Ray cluster lost {lost} and has had no node with a CPU "
        f"for {NODE_WAIT_S:g} s; add nodes to the cluster (`ray start --address HEAD:PORT` on "
        "another machine) and run the command again"
    )
