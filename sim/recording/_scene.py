"""The static scene: the room, and any compiled MuJoCo model's geometry with its body poses.

Entity tree:

* ``world/room``: the floor (a flat box) and its outline, static.
* ``camera/<name>``: images rendered by a camera (the robot's head camera), as JPEG.
* ``world/model/<body>``: one entity per MuJoCo body, carrying the body's pose (a static
  transform, or one per frame from :func:`log_body_poses`); under it ``capsules``, ``boxes``,
  ``spheres`` (and ellipsoids), ``cylinders``, ``planes`` and ``meshes`` hold that body's geoms
  in the body's frame, static. The world body's geoms (floor, walls) sit under
  ``world/model/world``. A crowd's recording leaves the people's bodies out (one entity per
  body would make thousands): people are drawn batched under ``world/people``.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from io import BytesIO
from typing import Any

import numpy as np
import rerun as rr
from PIL import Image

from reform import Frame
from sim.recording import _colours
from sim.recording._columns import FrameColumns, send_rows
from sim.recording._timeline import Clock

__all__ = [
    "CAMERA_ROOT",
    "MODEL_ROOT",
    "ROOM_ROOT",
    "BodyPoses",
    "CameraImages",
    "body_entity",
    "log_body_poses",
    "log_camera_images",
    "log_model",
    "log_room",
    "person_bodies",
    "room_bounds",
]

MODEL_ROOT = "world/model"
ROOM_ROOT = "world/room"
ROOM_MARGIN_M = 1.0  # metres of floor around the people's extent
INFINITE_PLANE_HALF_M = 10.0  # metres: how far an infinite MuJoCo plane is drawn
VISIBLE_GEOM_GROUPS = (0, 1, 2)  # MuJoCo's viewer shows geom groups 0-2 by default

# mjtGeom values (MuJoCo 4.0): plane 0, hfield 1, sphere 2, capsule 3, ellipsoid 4, cylinder 5,
# box 6, mesh 7, sdf 8.
_PLANE, _HFIELD, _SPHERE, _CAPSULE, _ELLIPSOID, _CYLINDER, _BOX, _MESH, _SDF = range(9)
_DEFAULT_RGBA = (0.5, 0.5, 0.5, 1.0)  # MuJoCo's default geom colour


def _xyzw(wxyz: np.ndarray) -> np.ndarray:
    """MuJoCo quaternions ``(w, x, y, z)`` to Rerun's ``(x, y, z, w)``, along the last axis."""
    return np.asarray(wxyz, dtype=np.float64)[..., [1, 2, 3, 0]]


def _rotate(wxyz: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotates vectors ``v`` (n, 3) by unit quaternions ``wxyz`` (n, 4)."""
    w = wxyz[:, :1]
    u = wxyz[:, 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def _name(model, body: int) -> str:
    import mujoco  # here, as in `log_model`: a recording of a dataset has no MuJoCo model

    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body) or f"body{body}"
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name)


def body_entity(model, body: int, *, root: str = MODEL_ROOT) -> str:
    """Entity path of MuJoCo body ``body`` (its name, with characters outside [A-Za-z0-9_.-]
    replaced by ``_``; ``body<k>`` when unnamed)."""
    return f"{root}/{_name(model, body)}"


def _colours_of(model, geoms: np.ndarray) -> np.ndarray:
    """(n, 4) uint8 colours: the geom's rgba, or its material's when the geom keeps the default."""
    rgba = np.array(model.geom_rgba[geoms], dtype=np.float64)
    matid = model.geom_matid[geoms]
    default = np.all(np.isclose(rgba, _DEFAULT_RGBA), axis=1)
    use_material = (matid >= 0) & default
    if np.any(use_material):
        rgba[use_material] = model.mat_rgba[matid[use_material]]
    return np.clip(np.round(rgba * 255.0), 0, 255).astype(np.uint8)


def log_model(
    rec: rr.RecordingStream,
    model,
    *,
    data=None,
    static_poses: bool = True,
    root: str = MODEL_ROOT,
    geom_groups: Iterable[int] = VISIBLE_GEOM_GROUPS,
    bodies: Iterable[int] | None = None,
) -> dict[str, int]:
    """Logs every visible geom of a compiled ``mujoco.MjModel`` as Rerun shapes, static.

    Geoms are grouped per body and type and logged in the body's frame; the body's entity
    carries its pose. Height fields and SDF geoms are not drawn (they are counted under
    ``"skipped"``), nor are geoms outside ``geom_groups`` or fully transparent.

    Args:
        rec: the recording stream.
        model: a compiled ``mujoco.MjModel``.
        data: a ``mujoco.MjData`` whose ``xpos``/``xquat`` give the static body poses; default:
            the model's reference pose (``mj_kinematics`` on fresh data).
        static_poses: log each body's pose as a static transform. Pass False when the poses
            come per frame from :func:`log_body_poses` (a static pose would hide them).
        root: entity under which the bodies go.
        geom_groups: MuJoCo geom groups to draw.
        bodies: the bodies to log (ids); default every body. A crowd's recording leaves its
            people's bodies out (:func:`person_bodies`): one entity per body would make
            thousands.

    Returns:
        Number of geoms logged per kind (``"capsules"``, ``"boxes"``, ...), and ``"skipped"``.
    """

    import mujoco  # here: recording a dataset, which has no MuJoCo model, does not import it

    if not isinstance(model, mujoco.MjModel):
        raise ValueError(f"model must be a compiled mujoco.MjModel, got {type(model).__name__}")
    if data is None and static_poses:
        data = mujoco.MjData(model)
        mujoco.mj_kinematics(model, data)
    groups = np.asarray(sorted(set(int(g) for g in geom_groups)), dtype=np.int64)
    visible = np.isin(model.geom_group, groups) & (model.geom_rgba[:, 3] > 0)
    counts = {
        "capsules": 0,
        "boxes": 0,
        "spheres": 0,
        "cylinders": 0,
        "planes": 0,
        "meshes": 0,
        "skipped": 0,
    }
    for body in range(model.nbody) if bodies is None else sorted(set(bodies)):
        entity = body_entity(model, body, root=root)
        geoms = np.flatnonzero((model.geom_bodyid == body) & visible)
        if static_poses and body > 0:
            rec.log(
                entity,
                rr.Transform3D(
                    translation=np.asarray(data.xpos[body], dtype=np.float64),
                    quaternion=_xyzw(data.xquat[body]),
                ),
                static=True,
            )
        if geoms.size == 0:
            continue
        types = model.geom_type[geoms]
        size = np.asarray(model.geom_size[geoms], dtype=np.float64)
        pos = np.asarray(model.geom_pos[geoms], dtype=np.float64)
        quat = np.asarray(model.geom_quat[geoms], dtype=np.float64)
        colours = _colours_of(model, geoms)
        for kind, pick, archetype, shape in _primitives(types, size, pos, quat):
            if not np.any(pick):
                continue
            rec.log(
                f"{entity}/{kind}",
                archetype(
                    **shape,
                    quaternions=_xyzw(quat[pick]),
                    colors=colours[pick],
                    fill_mode=rr.components.FillMode.Solid,
                ),
                static=True,
            )
            counts[kind] += int(pick.sum())
        meshes = geoms[types == _MESH]
        for k, geom in enumerate(meshes.tolist()):
            mesh = int(model.geom_dataid[geom])
            first, n_vert = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
            face0, n_face = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
            vertices = np.asarray(model.mesh_vert[first : first + n_vert], dtype=np.float64)
            vertices = _rotate(np.repeat(model.geom_quat[geom][None, :], n_vert, axis=0), vertices)
            vertices += model.geom_pos[geom]
            rec.log(
                f"{entity}/meshes/{k}",
                rr.Mesh3D(
                    vertex_positions=vertices,
                    triangle_indices=np.asarray(model.mesh_face[face0 : face0 + n_face]),
                    albedo_factor=_colours_of(model, np.array([geom]))[0],
                ),
                static=True,
            )
        counts["meshes"] += int(meshes.size)
        counts["skipped"] += int(np.count_nonzero((types == _HFIELD) | (types == _SDF)))
    return counts


def _primitives(
    types: np.ndarray, size: np.ndarray, pos: np.ndarray, quat: np.ndarray
) -> list[tuple[str, np.ndarray, Any, dict[str, np.ndarray]]]:
    """One body's geoms by kind of primitive: (entity name, which geoms, the Rerun archetype,
    its shape and position arguments). A capsule is placed by its bottom end, a sphere is an
    ellipsoid with equal half sizes, a plane a flat box."""
    capsule = types == _CAPSULE
    half = size[capsule, 1]
    axis = _rotate(quat[capsule], np.column_stack([np.zeros_like(half), np.zeros_like(half), half]))
    cylinder = types == _CYLINDER
    box = types == _BOX
    ball = (types == _SPHERE) | (types == _ELLIPSOID)
    plane = types == _PLANE
    half_xy = np.where(size[plane, :2] > 0, size[plane, :2], INFINITE_PLANE_HALF_M)
    return [
        (
            "capsules",
            capsule,
            rr.Capsules3D,
            {"lengths": 2.0 * half, "radii": size[capsule, 0], "translations": pos[capsule] - axis},
        ),
        (
            "cylinders",
            cylinder,
            rr.Cylinders3D,
            {
                "lengths": 2.0 * size[cylinder, 1],
                "radii": size[cylinder, 0],
                "centers": pos[cylinder],
            },
        ),
        ("boxes", box, rr.Boxes3D, {"half_sizes": size[box], "centers": pos[box]}),
        (
            "spheres",
            ball,
            rr.Ellipsoids3D,
            {
                "half_sizes": np.where(
                    (types[ball] == _SPHERE)[:, None], size[ball, :1], size[ball]
                ),
                "centers": pos[ball],
            },
        ),
        (
            "planes",
            plane,
            rr.Boxes3D,
            {
                "half_sizes": np.column_stack([half_xy, np.zeros(half_xy.shape[0])]),
                "centers": pos[plane],
            },
        ),
    ]


@dataclass(frozen=True, eq=False)
class BodyPoses:
    """World poses of a model's bodies over a run, as MuJoCo gives them (``data.xpos/xquat``).

    Attributes:
        time: (n_steps,) float64 seconds, the time stamp of the frame each pose belongs to.
        position: (n_steps, n_body, 3) float64 metres (``data.xpos`` copies).
        quaternion: (n_steps, n_body, 4) float64 unit quaternions, MuJoCo order (w, x, y, z).
        sequence: the sequence (episode) the poses belong to.
    """

    time: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray
    sequence: str = ""

    def __post_init__(self) -> None:
        time = np.asarray(self.time, dtype=np.float64)
        if time.ndim != 1:
            raise ValueError(f"time must have shape (n_steps,), got {time.shape}")
        position = np.asarray(self.position, dtype=np.float64)
        if position.ndim != 3 or position.shape[0] != time.size or position.shape[2] != 3:
            raise ValueError(
                f"position must have shape ({time.size}, n_body, 3), got {position.shape}"
            )
        quaternion = np.asarray(self.quaternion, dtype=np.float64)
        if quaternion.shape != position.shape[:2] + (4,):
            raise ValueError(
                f"quaternion must have shape {position.shape[:2] + (4,)}, got {quaternion.shape}"
            )
        if not (np.all(np.isfinite(position)) and np.all(np.isfinite(quaternion))):
            raise ValueError("position and quaternion must be finite, got NaN or inf")
        for name, value in (("time", time), ("position", position), ("quaternion", quaternion)):
            value = np.array(value, copy=True)
            value.flags.writeable = False
            object.__setattr__(self, name, value)


def log_body_poses(
    rec: rr.RecordingStream,
    model,
    poses: BodyPoses,
    *,
    clock: Clock | None = None,
    root: str = MODEL_ROOT,
    bodies: Iterable[int] | None = None,
) -> int:
    """Logs the bodies' poses over a run: moving bodies per frame, still ones once (static).

    Pair it with ``log_model(rec, model, static_poses=False)``.

    Args:
        rec: the recording stream.
        model: the compiled ``mujoco.MjModel`` the poses belong to.
        poses: the poses, one row per frame of the run.
        clock: the run's clock, to place each row by (sequence, time); default: row ``i`` is
            frame ``i`` and ``sim_time`` is ``poses.time``.
        root: as given to :func:`log_model`.
        bodies: as given to :func:`log_model` (the world body is never logged here).

    Returns:
        Number of bodies logged per frame (the moving ones).

    Raises:
        ValueError: if the poses hold another number of bodies than the model, or a time
            matches no frame of ``clock``.
    """
    if poses.position.shape[1] != model.nbody:
        raise ValueError(
            f"poses must hold the model's {model.nbody} bodies, got {poses.position.shape[1]}"
        )
    times = _time_columns(clock, poses.sequence, poses.time, what="poses.time")
    moving = 0
    for body in range(1, model.nbody) if bodies is None else sorted(set(bodies) - {0}):
        entity = body_entity(model, body, root=root)
        position = poses.position[:, body]
        quaternion = _xyzw(poses.quaternion[:, body])
        if np.all(position == position[:1]) and np.all(quaternion == quaternion[:1]):
            rec.log(
                entity,
                rr.Transform3D(translation=position[0], quaternion=quaternion[0]),
                static=True,
            )
            continue
        send_rows(
            rec,
            entity,
            None,
            times,
            rr.Transform3D.columns(translation=position, quaternion=quaternion),
        )
        moving += 1
    return moving


def _time_columns(
    clock: Clock | None, sequence: str, time: np.ndarray, *, what: str
) -> list[rr.TimeColumn]:
    """Time columns of one sequence's time stamps (seconds): placed on ``clock`` by (sequence,
    time), or without a clock, row ``i`` at stamp ``i``.

    Raises:
        ValueError: naming ``what`` if a time stamp matches no frame of ``clock``.
    """
    sequences = [sequence] * time.size
    clock = Clock.from_times(sequences, time) if clock is None else clock
    return clock.columns(clock.rows_at(sequences, time, what=what))


def person_bodies(model) -> np.ndarray:
    """(k,) int64 ids of the bodies of the people in a scene built by `sim.scene.build_scene`
    (their names start with `sim.scene.PERSON_PREFIX`), in body order."""
    import mujoco  # here, as in `log_model`: a recording of a dataset has no MuJoCo model

    from sim.scene import PERSON_PREFIX

    names = (
        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or "" for b in range(model.nbody)
    )
    return np.array(
        [b for b, name in enumerate(names) if name.startswith(PERSON_PREFIX)], dtype=np.int64
    )


def room_bounds(
    frames: Iterable[Frame] | FrameColumns, *, margin_m: float = ROOM_MARGIN_M
) -> tuple[float, float, float, float]:
    """``(x_min, x_max, y_min, y_max)`` metres: everyone's extent over the run plus a margin."""
    position = FrameColumns.coerce(frames).position
    if not position.size:
        return (-margin_m, margin_m, -margin_m, margin_m)
    x, y = position[:, 0], position[:, 1]  # (one column at a time: far faster than axis=0)
    return (
        float(x.min() - margin_m),
        float(x.max() + margin_m),
        float(y.min() - margin_m),
        float(y.max() + margin_m),
    )


def log_room(rec: rr.RecordingStream, bounds: Sequence[float]) -> None:
    """The floor as a flat box and its outline, static.

    Args:
        rec: the recording stream.
        bounds: ``(x_min, x_max, y_min, y_max)`` metres, e.g. from :func:`room_bounds`.
    """
    x0, x1, y0, y1 = (float(b) for b in bounds)
    if not (x0 < x1 and y0 < y1):
        raise ValueError(
            f"bounds must be (x_min, x_max, y_min, y_max) with min < max, got {tuple(bounds)}"
        )
    rec.log(
        f"{ROOM_ROOT}/floor",
        rr.Boxes3D(
            centers=[((x0 + x1) / 2, (y0 + y1) / 2, -0.005)],
            half_sizes=[((x1 - x0) / 2, (y1 - y0) / 2, 0.005)],
            colors=[_colours.FLOOR],
            fill_mode=rr.components.FillMode.Solid,
        ),
        static=True,
    )
    rec.log(
        f"{ROOM_ROOT}/outline",
        rr.LineStrips3D(
            [[(x0, y0, 0.0), (x1, y0, 0.0), (x1, y1, 0.0), (x0, y1, 0.0), (x0, y0, 0.0)]],
            colors=[_colours.WALL],
            radii=[0.02],
        ),
        static=True,
    )


CAMERA_ROOT = "camera"
JPEG_QUALITY = 85  # 0-100: head-camera frames are stored as JPEG


@dataclass(frozen=True, eq=False)
class CameraImages:
    """Frames rendered by a camera during a run (e.g. the robot's head camera).

    Attributes:
        time: (n,) float64 seconds, each image's frame time stamp.
        images: (n, height, width, 3) uint8 RGB images, or a sequence of such arrays.
        sequence: the sequence (episode) the images belong to.
        name: the camera's name; the images go to ``camera/<name>``.
    """

    time: np.ndarray
    images: Sequence[np.ndarray] | np.ndarray
    sequence: str = ""
    name: str = "head"

    def __post_init__(self) -> None:
        time = np.asarray(self.time, dtype=np.float64)
        if time.ndim != 1 or len(self.images) != time.size:
            raise ValueError(
                f"time must have shape (n,) with one image each: got {time.shape} and "
                f"{len(self.images)} images"
            )
        for k, image in enumerate(self.images):
            image = np.asarray(image)
            if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
                raise ValueError(
                    f"images[{k}] must be an (height, width, 3) uint8 RGB array, "
                    f"got shape {image.shape} dtype {image.dtype}"
                )
        if not self.name or "/" in self.name:
            raise ValueError(f"name must be non-empty without '/', got {self.name!r}")
        object.__setattr__(self, "time", time)


def log_camera_images(
    rec: rr.RecordingStream,
    camera: CameraImages,
    *,
    clock: Clock | None = None,
    jpeg_quality: int = JPEG_QUALITY,
) -> int:
    """Logs a camera's images as JPEG, one row per image, on the run's timelines.

    Args:
        rec: the recording stream.
        camera: the images and their time stamps.
        clock: the run's clock (images are placed by (sequence, time)); default: row ``i`` is
            image ``i`` and ``sim_time`` is its time.
        jpeg_quality: 1-100.

    Returns:
        Bytes of JPEG logged.
    """

    if not 1 <= jpeg_quality <= 100:
        raise ValueError(f"jpeg_quality must be in [1, 100], got {jpeg_quality}")
    times = _time_columns(clock, camera.sequence, camera.time, what="camera.time")
    blobs = []
    for image in camera.images:
        buffer = BytesIO()
        Image.fromarray(np.asarray(image)).save(buffer, format="JPEG", quality=jpeg_quality)
        blobs.append(buffer.getvalue())
    send_rows(
        rec,
        f"{CAMERA_ROOT}/{camera.name}",
        rr.EncodedImage.from_fields(media_type="image/jpeg"),
        times,
        rr.EncodedImage.columns(blob=blobs),
    )
    return sum(len(b) for b in blobs)
