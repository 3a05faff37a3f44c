"""The human render mode: each episode streamed live to a Rerun viewer.

`ViewerStream.open` finds a viewer at the given gRPC address (Rerun's default,
``rerun+http://127.0.0.1:9876/proxy``, unless told otherwise): one that is listening is used;
with none listening there and a display to show one on, a viewer window is started, listening
on this machine only (`sim.recording.viewer_command`);
with neither, nothing is shown and one warning says how to get a viewer — the environment
neither waits for a viewer nor fails. An episode is one recording (``reform-sim``, its id from
the scenario, its seed and the episode's number), on the ``frame`` (control step) and
``sim_time`` timelines only, so that one seed streams the same content: the room (static),
then per step the people (coloured by their true group), the robot and its heading, and the
rings of the true and the detected groups (`sim.envs.overlay`).
"""

from __future__ import annotations

import contextlib
import math
import os
import socket
import subprocess
import sys
import time
import urllib.parse
from collections.abc import Sequence

import numpy as np
import rerun as rr
from gymnasium import logger

from sim.envs.overlay import GroupRing, ring_points
from sim.recording import (
    FRAME_TIMELINE,
    SIM_TIME_TIMELINE,
    RecordingTarget,
    default_blueprint,
    log_room,
    open_recording,
    viewer_command,
)
from sim.recording._colours import ROBOT, SINGLETON
from sim.recording._target import VIEWER_SCHEMES

__all__ = ["DEFAULT_VIEWER", "ViewerStream", "viewer_listening"]

DEFAULT_VIEWER = "rerun+http://127.0.0.1:9876/proxy"  # Rerun's default viewer address
PROBE_TIMEOUT_S = 0.25  # seconds to wait for a viewer's port to answer
SPAWN_WAIT_S = 10.0  # seconds a viewer window started here is given to listen
PERSON_RADIUS_M = 0.22  # metres, the dot of a person (grey when alone)
PERSON_Z_M = 0.9  # metres: people's dots float at chest height
HEADING_M = 0.5  # metres, length of the robot's heading arrow
PEOPLE = "world/people"
ROBOT_ENTITY = "world/robot"
GROUPS = "world/groups"
_LOCAL = ("127.0.0.1", "localhost", "::1")


def _address(url: str) -> tuple[str, int]:
    parts = urllib.parse.urlsplit(url.split("+", 1)[-1] if url.startswith("rerun+") else url)
    return parts.hostname or "127.0.0.1", parts.port or 9876


def viewer_listening(url: str, *, timeout_s: float = PROBE_TIMEOUT_S) -> bool:
    """Whether something accepts connections at the viewer address ``url``."""
    try:
        with socket.create_connection(_address(url), timeout=timeout_s):
            return True
    except OSError:
        return False


def _display() -> bool:
    """Whether a viewer window could be shown here."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


class ViewerStream:
    """The live recording of one environment's episodes (see the module doc).

    Args:
        url: the viewer's gRPC address.
    """

    def __init__(self, url: str = DEFAULT_VIEWER) -> None:
        if not isinstance(url, str) or not url.startswith(VIEWER_SCHEMES):
            raise ValueError(
                f"viewer must be a Rerun viewer's address starting with one of "
                f"{', '.join(VIEWER_SCHEMES)} (e.g. {DEFAULT_VIEWER}), got {url!r}"
            )
        self.url = url
        self._stack: contextlib.ExitStack | None = None
        self._rec: rr.RecordingStream | None = None
        self._warned = False
        self._last_step = -1

    @property
    def streaming(self) -> bool:
        """Whether the current episode is being streamed."""
        return self._rec is not None

    def open(self, *, name: str, seed: int, room: Sequence[float]) -> bool:
        """Starts an episode's recording (ending the previous one); False when no viewer can
        be reached or started (then the episode is not shown)."""
        self.close()
        if not viewer_listening(self.url) and not self._spawn():
            if not self._warned:
                logger.warn(
                    f"render_mode='human': no Rerun viewer at {self.url} and no display to start "
                    "one, so the episodes are not shown; start a viewer (`rerun`, or `rerun "
                    "--serve-web` on a server) or give SocialEnv(viewer=...) its address"
                )
                self._warned = True
            return False
        half_x, half_y = 0.5 * float(room[0]), 0.5 * float(room[1])
        bounds = (-half_x, half_x, -half_y, half_y)
        stack = contextlib.ExitStack()
        self._rec = stack.enter_context(
            open_recording(
                RecordingTarget(connect=self.url),
                name=name,
                seed=seed,
                blueprint=default_blueprint(scores=False, events=False, bounds=bounds),
            )
        )
        self._stack = stack
        self._last_step = -1
        log_room(self._rec, bounds)
        return True

    def _spawn(self) -> bool:
        """Starts a viewer window at the address (a local one, with a display to show it on),
        listening on this machine only and left open when the environment closes."""
        host, port = _address(self.url)
        if host not in _LOCAL or not _display():
            return False
        viewer = subprocess.Popen(
            viewer_command(
                "--port",
                str(port),
                "--expect-data-soon",
                bind="::1" if host == "::1" else "127.0.0.1",
            ),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,  # a window of its own: it outlives the environment
            env={**os.environ, "RERUN_APP_ONLY": "true"},  # as rr.spawn starts it
        )
        deadline = time.monotonic() + SPAWN_WAIT_S
        while not viewer_listening(self.url):
            if viewer.poll() is not None or time.monotonic() > deadline:
                return False  # it could not open a window here, or took too long
            time.sleep(0.1)
        return True

    def show(
        self,
        *,
        step: int,
        time: float,
        ids: np.ndarray,
        kinds: Sequence[str],
        present: np.ndarray,
        position: np.ndarray,
        yaw: np.ndarray,
        rings: Sequence[GroupRing],
        sources: Sequence[str],
    ) -> None:
        """Logs control step ``step`` (once; again for the same step is a no-op).

        Args:
            step: the control step (the ``frame`` timeline).
            time: seconds since the start (the ``sim_time`` timeline).
            ids, kinds, present, position, yaw: everyone in the scene now (people then the
                robot): ids, ``"human"``/``"robot"``, in the room, (n, 2) metres, radians.
            rings: the groups' rings now (`sim.envs.overlay.group_rings`).
            sources: every ring source of the episode (``"truth"`` and the detector's name),
                so that a source without rings now is cleared.
        """
        rec = self._rec
        if rec is None or step == self._last_step:
            return
        self._last_step = step
        rec.set_time(FRAME_TIMELINE, sequence=step)
        rec.set_time(SIM_TIME_TIMELINE, duration=time)
        colour_of = {m: r.colour for r in rings if r.source == "truth" for m in r.members}
        is_robot = np.array([k == "robot" for k in kinds]) & present
        people = present & ~is_robot
        people_ids = ids[people].tolist()
        rec.log(
            PEOPLE,
            rr.Points3D(
                np.column_stack([position[people], np.full(len(people_ids), PERSON_Z_M)]),
                radii=PERSON_RADIUS_M,
                colors=[colour_of.get(int(i), SINGLETON) for i in people_ids],
                labels=[str(i) for i in people_ids],
            ),
        )
        if is_robot.any():
            r = int(np.flatnonzero(is_robot)[0])
            x, y, heading = float(position[r, 0]), float(position[r, 1]), float(yaw[r])
            rec.log(
                ROBOT_ENTITY,
                rr.Arrows3D(
                    origins=[(x, y, PERSON_Z_M)],
                    vectors=[(HEADING_M * math.cos(heading), HEADING_M * math.sin(heading), 0.0)],
                    colors=[ROBOT],
                    labels=["robot"],
                ),
            )
        for source in sources:
            mine = [r for r in rings if r.source == source]
            rec.log(
                f"{GROUPS}/{source}",
                rr.LineStrips3D(
                    [ring_points(r) for r in mine],
                    colors=[r.colour for r in mine],
                    radii=0.02 if source == "truth" else 0.012,
                    labels=[",".join(map(str, r.members)) for r in mine],
                ),
            )

    def close(self) -> None:
        """Ends the current episode's recording (a viewer gone meanwhile: one warning)."""
        stack, self._stack, self._rec = self._stack, None, None
        if stack is None:
            return
        try:
            stack.close()
        except OSError as exc:
            logger.warn(f"render_mode='human': the viewer stopped listening: {exc}")
