"""sim: MuJoCo scenes of people and the Directions Robot, moved by scripts, seen by the robot.

Public surface (loaded on first use, so that the command line starts fast):

* scenes: `SceneSpec`, `PersonSpec`, `RobotSpec`, `build_scene`;
* the world: `World`, `Intent`, `RobotCommand`, `Script`, `MotionLimits`,
  `PERSON_LIMITS`, `ROBOT_LIMITS`;
* the robot's view: `Sensor`, `HeadCamera` (optional rendering);
* assets: `asset_names`, `asset_path`, `asset_xml`.

The Gymnasium environments (``ReformSim/...``) live in `sim.envs`: ``import sim.envs`` registers
them, or name the module in the id, ``gymnasium.make("sim.envs:ReformSim/Mingle-v0")``.
The documented studies (the demo, sim-to-real, the HRI re-enactment, the stress tests, the
calibration, the paper's experiment, the GCFF comparison, the benchmark), each a run and its
report, live in `sim.experiments`, built on this core; nothing here imports them.
``import sim`` alone loads neither gymnasium nor MuJoCo, so the ``reform-sim`` command starts
fast.
"""

from __future__ import annotations

import os
import sys

from reform._lazy import lazy_exports

# Offscreen rendering on a headless Linux machine needs EGL, chosen before mujoco is imported.
if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")

_EXPORTS = {
    "SceneSpec": "sim.scene",
    "PersonSpec": "sim.scene",
    "RobotSpec": "sim.scene",
    "build_scene": "sim.scene",
    "World": "sim.world",
    "Intent": "sim.world",
    "RobotCommand": "sim.world",
    "Script": "sim.world",
    "MotionLimits": "sim.motion",
    "PERSON_LIMITS": "sim.motion",
    "ROBOT_LIMITS": "sim.motion",
    "Sensor": "sim.sensor",
    "HeadCamera": "sim.camera",
    "asset_names": "sim.assets",
    "asset_path": "sim.assets",
    "asset_xml": "sim.assets",
}

__all__ = sorted(_EXPORTS)


# The names above, and the package's modules (``sim.envs`` registers the environments when
# first looked up), are imported on first use.
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
