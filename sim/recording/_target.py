"""Where a run's recording goes (file, viewer, server), and the command-line flags that say so.

Flags follow ``rr.script_add_args``: ``--save PATH`` writes an ``.rrd`` file (open it with
``rerun PATH``), ``--connect`` streams to a running viewer (``--url`` picks which), ``--serve``
hosts the recording for viewers to connect to, until Ctrl-C. This module imports neither Rerun
nor anything heavy, so that a command's flags cost nothing to declare.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "SERVE_BIND_IP",
    "SERVE_GRPC_PORT",
    "SERVE_WEB_PORT",
    "RecordingTarget",
    "add_recording_arguments",
    "target_from_args",
]

SERVE_BIND_IP = "127.0.0.1"  # --serve listens on this machine only
SERVE_GRPC_PORT = 9876  # Rerun's default gRPC port
SERVE_WEB_PORT = 9090  # Rerun's default web viewer port


# The address schemes of a Rerun viewer (rr.GrpcSink's).
VIEWER_SCHEMES = ("rerun://", "rerun+http://", "rerun+https://")


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
        if self.connect and not self.connect.startswith(VIEWER_SCHEMES):
            raise ValueError(
                f"--url must be a Rerun viewer's address starting with one of "
                f"{', '.join(VIEWER_SCHEMES)} (e.g. rerun+http://127.0.0.1:9876/proxy), got "
                f"{self.connect!r}"
            )

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


def add_recording_arguments(parser: argparse.ArgumentParser, *, what: str = "the run") -> None:
    """``--save PATH.rrd``, ``--connect``, ``--url URL``, ``--serve``, ``--headless``: the flags
    of ``rr.script_add_args`` (``what``: what the recording shows, for the help)."""
    group = parser.add_argument_group("Rerun recording")
    group.add_argument(
        "--save",
        metavar="PATH.rrd",
        default=None,
        help=f"save {what} as a Rerun recording; open it with `rerun PATH.rrd`",
    )
    group.add_argument(
        "--connect", action="store_true", help=f"stream {what} to a running Rerun viewer"
    )
    group.add_argument(
        "--url",
        default=None,
        metavar="URL",
        help="viewer URL for --connect (default: rerun+http://127.0.0.1:9876/proxy)",
    )
    group.add_argument(
        "--serve",
        action="store_true",
        help=f"host the recording for viewers on {SERVE_BIND_IP} until Ctrl-C",
    )
    group.add_argument(
        "--headless",
        action="store_true",
        help="never open a viewer window (the default here: the recording goes only where "
        "--save, --connect or --serve send it)",
    )


def target_from_args(args: argparse.Namespace) -> RecordingTarget | None:
    """The target named by :func:`add_recording_arguments`' flags, or None when none is given."""
    save = getattr(args, "save", None)
    if save is not None and Path(save).suffix != ".rrd":
        raise ValueError(f"--save must be a path ending in .rrd, got {save!r}")
    connect = (args.url or "") if getattr(args, "connect", False) else None
    serve = bool(getattr(args, "serve", False))
    if getattr(args, "url", None) and connect is None:
        raise ValueError("--url needs --connect")
    if save is None and connect is None and not serve:
        return None
    return RecordingTarget(save=None if save is None else Path(save), connect=connect, serve=serve)
