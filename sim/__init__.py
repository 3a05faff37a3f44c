"""sim: MuJoCo scenes of people and the Directions Robot, moved by scripts, seen by the robot.

Public surface (loaded on first use, so that the command line starts fast):

* scenes: `SceneSpec`, `PersonSpec`, `RobotSpec`, `build_scene`;
* the world: `World`, `Intent`, `RobotCommand`, `Script`, `Poses`, `MotionLimits`,
  `PERSON_LIMITS`, `ROBOT_LIMITS`;
* the robot's view: `Sensor`, `HeadCamera` (optional rendering);
* assets: `asset_names`, `asset_path`, `asset_xml`.

Importing ``sim`` registers the Gymnasium environments (``ReformSim/...``, `sim.envs`) with
gymnasium: at once when gymnasium is already imported, else the moment it is (so ``import sim``
alone, as the ``reform-sim`` command does, stays light). The environments themselves load on
``gymnasium.make``.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import os
import sys
from types import ModuleType
from typing import Any

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
    "Poses": "sim.world",
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


class _RegisterWithGymnasium(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Imports `sim.envs` (which registers the environments) right after gymnasium is imported.

    Sits first on ``sys.meta_path`` until gymnasium is looked up, then hands the import to
    gymnasium's own loader and steps aside: the module keeps that loader, nothing else changes.
    """

    def __init__(self) -> None:
        self._loader: importlib.abc.Loader | None = None

    def find_spec(
        self, fullname: str, path: Any = None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname != _GYMNASIUM:
            return None
        if self in sys.meta_path:
            sys.meta_path.remove(self)
        spec = importlib.util.find_spec(fullname)
        if spec is None or spec.loader is None:
            return spec
        self._loader, spec.loader = spec.loader, self
        return spec

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        assert self._loader is not None
        return self._loader.create_module(spec)

    def exec_module(self, module: ModuleType) -> None:
        assert self._loader is not None
        module.__loader__ = module.__spec__.loader = self._loader
        self._loader.exec_module(module)
        importlib.import_module("sim.envs")


_GYMNASIUM = "gymnasium"

if _GYMNASIUM in sys.modules:
    importlib.import_module("sim.envs")
else:
    sys.meta_path.insert(0, _RegisterWithGymnasium())


def __getattr__(name: str) -> Any:
    if name == "envs":
        return importlib.import_module("sim.envs")
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'sim' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
