"""Takes the Rerun viewer's screenshots shown in the tutorials (docs/images/viewer-*.png).

    python docs/screenshots.py

Writes the recordings with the same commands as the tutorial "Reading a recording in the
viewer", opens each in a headless Rerun viewer (``rerun --headless``: no window, rendered
off-screen; on a machine without a GPU it needs a software Vulkan driver such as Mesa's
lavapipe, Debian's ``mesa-vulkan-drivers``), moves the time cursor to a moment worth seeing and
saves what the viewer shows. Nothing is drawn by hand: each picture is the viewer's own.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rerun.experimental import ViewerClient

from sim.recording import stop_viewer, viewer_command

IMAGES = Path(__file__).resolve().parent / "images"
WINDOW = "1600x900"  # logical points
SETTLE_S = 20.0  # the software rasteriser needs a while to draw every view

# (image, commands writing the recording, the recording, time on the sim_time timeline in s)
SHOTS = (
    (
        "viewer-conversation.png",
        [
            "reform-sim simulate --scenario hri-conversation --seed 1 --out conversation.parquet "
            "--quiet",
            "reform-sim evaluate --detector gcff --data conversation.parquet "
            "--save conversation-gcff.rrd",
        ],
        "conversation-gcff.rrd",
        20.0,
    ),
    (
        "viewer-party.png",
        [
            "reform-sim simulate --scenario mingle --seed 3 --duration 60 --set people=12 "
            "--out party.parquet --quiet",
            "reform-sim evaluate --detector gcff --data party.parquet --save party-gcff.rrd",
        ],
        "party-gcff.rrd",
        45.0,
    ),
)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main() -> int:
    IMAGES.mkdir(exist_ok=True)
    # This interpreter's reform-sim, whether or not its environment is activated.
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    with tempfile.TemporaryDirectory() as folder:
        for image, commands, recording, at in SHOTS:
            for command in commands:
                subprocess.run(command, shell=True, cwd=folder, env=env, check=True)
            port = _free_port()
            viewer = subprocess.Popen(
                viewer_command(
                    "--headless",
                    "--renderer",
                    "vulkan",
                    "--port",
                    str(port),
                    "--window-size",
                    WINDOW,
                    "--hide-welcome-screen",
                ),
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            try:
                time.sleep(4.0)
                client = ViewerClient.connect(f"rerun+http://127.0.0.1:{port}/proxy")
                client.open(str(Path(folder) / recording))
                time.sleep(3.0)
                client.set_time("sim_time", duration=at, play_state="paused")
                time.sleep(SETTLE_S)
                client.save_screenshot(str(IMAGES / image))
                time.sleep(2.0)
            finally:
                stop_viewer(viewer)
            print(f"wrote {IMAGES / image}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
