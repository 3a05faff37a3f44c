"""The Rerun viewer program, as the project starts it: itself, and on this machine only.

Installing ``rerun-sdk`` gives a ``rerun`` script that runs the viewer program shipped in the
``rerun_cli`` package as its child. The project starts that program directly, so that stopping
what it started stops the viewer (stopping the script would leave the program running), and
always with ``--bind 127.0.0.1`` (the program's own default is every interface).
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

from sim.recording._target import SERVE_BIND_IP

__all__ = ["VIEWER_STOP_S", "rerun_in_this_shell", "rerun_program", "stop_viewer", "viewer_command"]

VIEWER_STOP_S = 20.0  # seconds a stopped viewer is given to exit before it is killed
# Where rerun_cli keeps the program, by platform (the macOS build may be an app bundle).
_PROGRAMS = ("Rerun.app/Contents/MacOS/Rerun", "rerun", "rerun.exe")


def rerun_program() -> Path:
    """The Rerun viewer program of the installed ``rerun-sdk`` (not its ``rerun`` script)."""
    import rerun_cli  # ships with rerun-sdk; only a path is read from it

    folder = Path(rerun_cli.__file__).parent
    for name in _PROGRAMS:
        if (folder / name).is_file():
            return folder / name
    raise FileNotFoundError(
        f"no Rerun viewer program in {folder} (looked for {', '.join(_PROGRAMS)}); reinstall "
        f"it: {sys.executable} -m pip install --force-reinstall 'rerun-sdk==0.41.*'"
    )


def viewer_command(*args: str, bind: str = SERVE_BIND_IP) -> list[str]:
    """The command line of the viewer program listening on ``bind`` (this machine only by
    default), with ``args`` after it (``--port``, ``--serve-web``, a file or an address to
    open...)."""
    return [str(rerun_program()), "--bind", bind, *args]


def stop_viewer(
    viewer: subprocess.Popen,
    *,
    timeout_s: float = VIEWER_STOP_S,
    stop_signal: int = signal.SIGINT,
) -> int:
    """Stops a viewer started from `viewer_command` with ``stop_signal`` (as Ctrl-C does by
    default), killing it if it has not exited after ``timeout_s`` seconds; its exit status."""
    if viewer.poll() is None:
        viewer.send_signal(stop_signal)
        try:
            viewer.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            viewer.kill()
            viewer.wait()
    return int(viewer.returncode)


def rerun_in_this_shell() -> str:
    """How to type the ``rerun`` command here: ``rerun`` when the one on the PATH is this
    environment's, else this environment's by its path (``.venv/bin/rerun`` from a clone's
    folder whose environment is not activated)."""
    mine = Path(sys.executable).with_name("rerun")
    found = shutil.which("rerun")
    if not mine.is_file() or (found is not None and os.path.samefile(found, mine)):
        return "rerun"
    try:
        return str(mine.relative_to(Path.cwd()))
    except ValueError:
        return str(mine)
