"""One Rerun recording stream per run, and where it goes (file, viewer, server).

Every recording of the project has the application id ``reform-sim`` and a recording id derived
from the run's name and seed, so that one run always lands in the same recording and two runs
with one seed produce the same content. The wall-clock ``log_time`` and the ``log_tick``
timelines are off: a recording holds only the run's own ``frame`` and ``sim_time`` timelines.

Command-line flags follow ``rr.script_add_args``: ``--save PATH`` writes an ``.rrd`` file
(open it with ``rerun PATH``), ``--connect`` streams to a running viewer (``--url`` picks which),
``--serve`` hosts the recording for viewers to connect to, until Ctrl-C.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
import urllib.parse
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import rerun as rr

from reform.atomic import atomic_path

__all__ = [
    "APPLICATION_ID",
    "RecordingTarget",
    "add_recording_arguments",
    "open_recording",
    "recording_id",
    "target_from_args",
]

APPLICATION_ID = "reform-sim"
# Namespace of the recording ids (uuid5 of "name:seed"): fixed, so ids are stable across runs.
_RECORDING_NAMESPACE = uuid.UUID("6f1c2a4e-0d5b-4c59-9a64-2f6f3c1b7e21")
SERVE_BIND_IP = "127.0.0.1"  # --serve listens on this machine only
SERVE_GRPC_PORT = 9876  # Rerun's default gRPC port
SERVE_WEB_PORT = 9090  # Rerun's default web viewer port


def recording_id(name: str, *, seed: int | None = None) -> str:
    """Deterministic recording id (a UUID) of the run called ``name`` with ``seed``."""
    if not name:
        raise ValueError("name must be a non-empty run name, got ''")
    return str(uuid.uuid5(_RECORDING_NAMESPACE, f"{name}:{'' if seed is None else int(seed)}"))


@dataclass(frozen=True)
class RecordingTarget:
    """Where a recording goes; any combination.

    Attributes:
        save: write an ``.rrd`` file here (atomically: it appears when the run is complete).
        connect: stream to the viewer at this URL; ``""`` for Rerun's default
            (``rerun+http://127.0.0.1:9876/proxy``); None for no viewer.
        serve: host the recording over gRPC (and a web viewer) on this machine until Ctrl-C.
    """

    save: Path | None = None
    connect: str | None = None
    serve: bool = False

    def __post_init__(self) -> None:
        if self.save is not None:
            path = Path(self.save)
            if path.suffix != ".rrd":
                raise ValueError(f"save must be a path ending in .rrd, got {str(path)!r}")
            object.__setattr__(self, "save", path)
        if self.save is None and self.connect is None and not self.serve:
            raise ValueError("a recording target needs save, connect or serve; got none")

    @classmethod
    def coerce(cls, target: RecordingTarget | str | os.PathLike[str]) -> RecordingTarget:
        """A target from a target or a path to save to."""
        if isinstance(target, RecordingTarget):
            return target
        if isinstance(target, (str, os.PathLike)):
            return cls(save=Path(target))
        raise ValueError(
            f"target must be a RecordingTarget or a .rrd path, got {type(target).__name__}"
        )


@contextlib.contextmanager
def open_recording(
    target: RecordingTarget | str | os.PathLike[str],
    *,
    name: str,
    seed: int | None = None,
    blueprint: rr.blueprint.BlueprintLike | None = None,
) -> Iterator[rr.RecordingStream]:
    """A recording stream for one run, sent to ``target``; closed (and the file renamed into
    place) when the block ends.

    Args:
        target: a :class:`RecordingTarget` or a ``.rrd`` path to save to.
        name: the run's name, shown by the viewer; with ``seed`` it fixes the recording id.
        seed: the run's seed, or None.
        blueprint: the default layout (e.g. :func:`sim.recording.default_blueprint`).

    Yields:
        The stream; pass it to the ``log_*`` functions.
    """
    target = RecordingTarget.coerce(target)
    with contextlib.ExitStack() as stack:
        sinks: list[object] = []
        if target.save is not None:
            sinks.append(rr.FileSink(stack.enter_context(atomic_path(target.save))))
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
        try:
            rec.set_log_time_enabled(False)
            rec.set_log_tick_enabled(False)
            rec.set_sinks(*sinks, default_blueprint=blueprint)
            rec.send_recording_name(name)
            yield rec
            rec.flush()
            if server is not None:
                _serve_until_interrupted(server.uri)
        finally:
            rec.disconnect()


def _serve_until_interrupted(uri: str) -> None:
    rr.serve_web_viewer(web_port=SERVE_WEB_PORT, open_browser=False, connect_to=uri)
    web = f"http://{SERVE_BIND_IP}:{SERVE_WEB_PORT}/?url={urllib.parse.quote(uri, safe='')}"
    print(
        f"serving the recording at {uri}: open it with `rerun {uri}` or in a browser at "
        f"{web}; Ctrl-C stops",
        file=sys.stderr,
    )
    try:
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        print("stopped serving", file=sys.stderr)


def add_recording_arguments(parser: argparse.ArgumentParser) -> None:
    """``--save PATH.rrd``, ``--connect``, ``--url URL``, ``--serve`` (``rr.script_add_args``)."""
    group = parser.add_argument_group("Rerun recording")
    group.add_argument(
        "--save",
        metavar="PATH.rrd",
        default=None,
        help="save the run as a Rerun recording; open it with `rerun PATH.rrd`",
    )
    group.add_argument(
        "--connect", action="store_true", help="stream the run to a running Rerun viewer"
    )
    group.add_argument(
        "--url",
        default=None,
        help="viewer URL for --connect (default: rerun+http://127.0.0.1:9876/proxy)",
    )
    group.add_argument(
        "--serve",
        action="store_true",
        help=f"host the recording for viewers on {SERVE_BIND_IP} until Ctrl-C",
    )


def target_from_args(args: argparse.Namespace) -> RecordingTarget | None:
    """The target named by :func:`add_recording_arguments`' flags, or None when none is given."""
    save = getattr(args, "save", None)
    connect = (args.url or "") if getattr(args, "connect", False) else None
    serve = bool(getattr(args, "serve", False))
    if getattr(args, "url", None) and connect is None:
        raise ValueError("--url needs --connect")
    if save is None and connect is None and not serve:
        return None
    return RecordingTarget(save=None if save is None else Path(save), connect=connect, serve=serve)
