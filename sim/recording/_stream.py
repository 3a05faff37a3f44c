"""One Rerun recording stream per run, sent where a `RecordingTarget` says (file, viewer, server).

Every recording of the project has the application id ``reform-sim`` and a recording id derived
from the run's name and seed, so that one run always lands in the same recording and two runs
with one seed produce the same content. The wall-clock ``log_time`` and the ``log_tick``
timelines are off: a recording holds only the run's own ``frame`` and ``sim_time`` timelines.
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.parse
import uuid
from collections.abc import Iterator
from pathlib import Path

import rerun as rr

from reform.atomic import atomic_path
from sim.recording._program import rerun_in_this_shell, stop_viewer, viewer_command
from sim.recording._target import (
    SERVE_BIND_IP,
    SERVE_GRPC_PORT,
    SERVE_WEB_PORT,
    RecordingTarget,
)

__all__ = ["APPLICATION_ID", "open_recording", "recording_id"]

APPLICATION_ID = "reform-sim"
WEB_VIEWER_START_S = 20.0  # seconds the web viewer of --serve is given to answer
FULL_DISK_BYTES = 1_000_000  # bytes: a folder with less left when a write stopped is full
FLUSH_S = 10.0  # seconds the end of a recording may take to reach its sinks, plus its size at
FLUSH_BYTES_PER_S = 10e6  # bytes a second (a slow disk)
DISCONNECT_S = 5.0  # seconds a recording whose sink failed is given to disconnect
# Namespace of the recording ids (uuid5 of "name:seed"): fixed, so ids are stable across runs.
_RECORDING_NAMESPACE = uuid.UUID("6f1c2a4e-0d5b-4c59-9a64-2f6f3c1b7e21")


def recording_id(name: str, *, seed: int | None = None) -> str:
    """Deterministic recording id (a UUID) of the run called ``name`` with ``seed``."""
    if not name:
        raise ValueError("name must be a non-empty run name, got ''")
    return str(uuid.uuid5(_RECORDING_NAMESPACE, f"{name}:{'' if seed is None else int(seed)}"))


@contextlib.contextmanager
def open_recording(
    target: RecordingTarget | str | os.PathLike[str],
    *,
    name: str,
    seed: int | None = None,
    blueprint: rr.blueprint.BlueprintLike | None = None,
    expected_bytes: float | None = None,
) -> Iterator[rr.RecordingStream]:
    """A recording stream for one run, sent to ``target``; closed (and the file renamed into
    place) when the block ends.

    Args:
        target: a :class:`RecordingTarget` or a ``.rrd`` path to save to.
        name: the run's name, shown by the viewer; with ``seed`` it fixes the recording id.
        seed: the run's seed, or None.
        blueprint: the default layout (e.g. :func:`sim.recording.default_blueprint`).
        expected_bytes: the size the ``.rrd`` is expected to reach (`sim.sizing.recording_disk`),
            for the message of a full disk.

    Yields:
        The stream; pass it to the ``log_*`` functions.

    Raises:
        reform.atomic.DiskFull: the disk the ``.rrd`` is saved on filled up (one line naming the
            file, what was written, the space left and the space needed).
        OSError: a viewer that cannot be reached, or a file that cannot be written.
    """
    target = RecordingTarget.coerce(target)
    with contextlib.ExitStack() as stack:
        sinks: list[object] = []
        if target.save is not None:
            saving = stack.enter_context(atomic_path(target.save, needed=expected_bytes))
            sinks.append(rr.FileSink(saving))
        if target.connect is not None:
            sinks.append(rr.GrpcSink(target.connect or None))
        server = None
        if target.serve:
            server = rr.GrpcServerSink(bind_ip=SERVE_BIND_IP, port=SERVE_GRPC_PORT)
            sinks.append(server)
        rec = rr.RecordingStream(
            APPLICATION_ID,
            recording_id=recording_id(name, seed=seed),
            send_properties=False,
            # One chunk per log call: chunk boundaries do not depend on timing.
            batcher_config=rr.ChunkBatcherConfig(flush_num_rows=1),
        )
        failed = False
        try:
            rec.set_log_time_enabled(False)
            rec.set_log_tick_enabled(False)
            rec.set_sinks(*sinks, default_blueprint=blueprint)
            rec.send_recording_name(name)
            yield rec
            try:
                rec.flush(timeout_sec=_flush_seconds(expected_bytes))
            except RuntimeError as exc:  # a viewer that cannot be reached, a file not written
                failed = True
                text = " ".join(str(exc).split())
                if target.save is not None and target.connect is None:
                    raise _file_error(saving, text) from None
                where = f"--connect {target.connect or 'the default viewer'}"
                raise OSError(f"{where}: {text}") from None
            if server is not None:
                _serve_until_interrupted(server.uri)
        finally:
            if failed:  # Rerun's disconnect can wait for ever on a sink that failed
                _disconnect_within(rec, DISCONNECT_S)
                # and so can the flush of every stream Rerun makes at exit: the streams that
                # did not fail were flushed and disconnected where they ended, as this one
                rr.unregister_shutdown()
            else:
                rec.disconnect()


def _disconnect_within(rec: rr.RecordingStream, seconds: float) -> None:
    """``rec.disconnect()``, left to a daemon thread after ``seconds``."""
    thread = threading.Thread(target=rec.disconnect, name="rerun disconnect", daemon=True)
    thread.start()
    thread.join(seconds)


def _flush_seconds(expected_bytes: float | None) -> float:
    """Seconds the last of a recording may take to reach its sinks: Rerun's flush can wait for
    ever on a file writer that stopped (a full disk)."""
    return FLUSH_S + (expected_bytes or 0.0) / FLUSH_BYTES_PER_S


def _file_error(path: Path, text: str) -> OSError:
    """What Rerun's file writer stopping on ``path`` means: a full disk when its folder has less
    than `FULL_DISK_BYTES` left (Rerun says only that its writer stopped; its own log, which the
    command line silences, names the system's error), else ``text``."""
    try:
        free = shutil.disk_usage(path.parent).free
    except OSError:
        free = None
    if free is not None and free < FULL_DISK_BYTES:
        return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
    return OSError(f"{path}: the recording could not be written ({text})")


def _serve_until_interrupted(uri: str) -> None:
    """Hosts the web viewer of the recording served at ``uri`` (on this machine only) until
    Ctrl-C."""
    viewer = subprocess.Popen(
        viewer_command("--serve-web", "--web-viewer-port", str(SERVE_WEB_PORT), uri),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        _wait_for_web_viewer(viewer)
        web = f"http://{SERVE_BIND_IP}:{SERVE_WEB_PORT}/?url={urllib.parse.quote(uri, safe='')}"
        print(
            f"serving the recording at {uri}: open it with `{rerun_in_this_shell()} {uri}` or in "
            "a browser at "
            f"{web}; Ctrl-C stops",
            file=sys.stderr,
            flush=True,
        )
        while viewer.poll() is None:
            time.sleep(0.2)
        raise OSError(f"--serve: the web viewer stopped (exit status {viewer.returncode})")
    except KeyboardInterrupt:
        print("stopped serving", file=sys.stderr)
    finally:
        # SIGTERM: the web viewer holds nothing to save, and on SIGINT it waits for its
        # connection to the recording's server, still open here, until it is killed.
        stop_viewer(viewer, stop_signal=signal.SIGTERM)


def _wait_for_web_viewer(viewer: subprocess.Popen) -> None:
    """Returns once the web viewer answers on its port; an OSError if it exits first."""
    deadline = time.monotonic() + WEB_VIEWER_START_S
    while time.monotonic() < deadline:
        if viewer.poll() is not None:
            raise OSError(
                f"--serve: the web viewer could not start on port {SERVE_WEB_PORT} (exit status "
                f"{viewer.returncode}); is another program using it?"
            )
        with (
            contextlib.suppress(OSError),
            socket.create_connection((SERVE_BIND_IP, SERVE_WEB_PORT), timeout=0.2),
        ):
            return
        time.sleep(0.1)
    raise OSError(f"--serve: the web viewer did not answer on port {SERVE_WEB_PORT}")
