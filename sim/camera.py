"""Optional images from the robot's head camera: RGB and depth through `mujoco.Renderer`.

Rendering needs an OpenGL context. Headless Linux machines use EGL: ``MUJOCO_GL=egl`` must be
set before ``mujoco`` is first imported (``import sim`` sets it when no display is available
and nothing else was chosen). About 60 ms per 320 x 240 frame on a CPU.

The camera's vertical field of view is set from the image's aspect ratio so that the
horizontal field of view is the sensor's (57 degrees by default).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from sim.sensor import KINECT_FOV_DEG
from sim.world import World

DEFAULT_WIDTH_PX = 320
DEFAULT_HEIGHT_PX = 240


def vertical_fov_deg(horizontal_fov_deg: float, width: int, height: int) -> float:
    """The vertical field of view (degrees) giving ``horizontal_fov_deg`` at width x height."""
    half = math.radians(horizontal_fov_deg) / 2.0
    return math.degrees(2.0 * math.atan(math.tan(half) * height / width))


class HeadCamera:
    """Renders what the robot's head camera sees in a `World`, at the world's current state.

    Args:
        world: a world with a robot.
        width: image width, pixels (at most the model's offscreen buffer, 640 x 480).
        height: image height, pixels (at most 640 x 480, as ``width``).
        fov_deg: horizontal field of view, degrees.

    Use as a context manager, or call `close`, to free the OpenGL context.
    """

    def __init__(
        self,
        world: World,
        *,
        width: int = DEFAULT_WIDTH_PX,
        height: int = DEFAULT_HEIGHT_PX,
        fov_deg: float = KINECT_FOV_DEG,
    ) -> None:
        if world.head_camera < 0:
            raise ValueError("HeadCamera: the world has no robot, so no head camera")
        for name, value in (("width", width), ("height", height)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(
                    f"HeadCamera: {name} must be a positive int (pixels), got {value!r}"
                )
        if not 0.0 < float(fov_deg) < 180.0:
            raise ValueError(f"HeadCamera: fov_deg must be within (0, 180) degrees, got {fov_deg}")
        self._world = world
        world.model.cam_fovy[world.head_camera] = vertical_fov_deg(float(fov_deg), width, height)
        try:
            self._renderer = mujoco.Renderer(world.model, height=height, width=width)
        except Exception as exc:  # the GL back end raises several types
            raise RuntimeError(
                "HeadCamera: could not create an OpenGL context; on a headless machine set "
                f"MUJOCO_GL=egl before importing mujoco ({exc})"
            ) from exc

    def rgb(self) -> np.ndarray:
        """(height, width, 3) uint8 colour image."""
        self._update()
        self._renderer.disable_depth_rendering()
        return self._renderer.render().copy()

    def depth(self) -> np.ndarray:
        """(height, width) float32 depth along the optical axis, metres."""
        self._update()
        self._renderer.enable_depth_rendering()
        try:
            return self._renderer.render().copy()
        finally:
            self._renderer.disable_depth_rendering()

    def close(self) -> None:
        self._renderer.close()

    def __enter__(self) -> HeadCamera:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _update(self) -> None:
        world = self._world
        mujoco.mj_camlight(world.model, world.data)
        self._renderer.update_scene(world.data, camera=world.head_camera)
