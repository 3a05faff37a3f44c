"""What a scene holds (`SceneSpec`, `PersonSpec`, `RobotSpec`) and how it becomes a MuJoCo model.

A scene is a rectangular room centred on the origin (floor, four walls), people and, optionally,
the Directions Robot. `build_scene` composes it in memory on `mujoco.MjSpec`: each person is
the shipped ``person`` model, scaled to its height and width, recoloured, and attached under the
prefix ``person<id>/``; the robot is the shipped ``robot`` model under ``robot/``. Every element
is named, so poses are read back by name (``person3/torso``, ``robot/head``).

Conventions: lengths in metres, angles in radians (the spec's compiler is set to radians),
x east, y north, z up; a yaw is counter-clockwise from +x. Every agent has a body radius (a disc
on the floor enclosing its arms and feet); agents never come closer than the sum of their radii.

A spec is validated when it is made: impossible requests (negative sizes, more people than fit
the room, start positions outside the walls or overlapping, an unknown asset) raise
`ValueError` naming the field, what was expected and what came, before anything is simulated.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar, NamedTuple

import mujoco
import numpy as np

from reform.frame import HUMAN, ROBOT
from sim.assets import PERSON_ASSET, ROBOT_ASSET, asset_names, asset_xml

PERSON_REFERENCE_HEIGHT_M = 1.75  # metres, height of the shipped person model
PERSON_REFERENCE_WIDTH_M = 0.44  # metres, between the shoulder joints of the shipped model
PERSON_HEIGHT_RANGE_M = (1.0, 2.3)  # metres, accepted person heights
PERSON_WIDTH_RANGE_M = (0.30, 0.70)  # metres, accepted shoulder widths
BODY_RADIUS_PER_WIDTH = 0.64  # body radius / shoulder width: the disc encloses arms and hands
BODY_RADIUS_RANGE_M = (0.15, 0.5)  # metres, accepted explicit body radii
FURNITURE_KINDS = ("table", "bar", "poster")
FURNITURE_SIZE_RANGE_M = (0.02, 10.0)  # metres, accepted furniture sizes
HEAD_REACH_PER_WIDTH = 0.07  # nose tip reach = this * width + HEAD_REACH_PER_HEIGHT * height
HEAD_REACH_PER_HEIGHT = 0.098  # (the head is set forward by the width, sized by the height)
ROBOT_REFERENCE_HEIGHT_M = 1.30  # metres, height of the shipped robot model
ROBOT_HEIGHT_RANGE_M = (1.2, 1.5)  # metres, accepted robot heights
ROBOT_RADIUS_M = 0.28  # metres, the robot's base disc with its bumper
CLEARANCE_MARGIN_M = 0.03  # metres, extra gap the motion keeps between agents (covers idle sway)
WALL_MARGIN_M = 0.015  # metres, extra gap the motion keeps to the walls (covers idle sway)
WALL_THICKNESS_M = 0.10  # metres
PACKING_DENSITY = math.pi / (2.0 * math.sqrt(3.0))  # densest packing of discs in the plane
ROOM_MAX_M = 100.0  # metres, largest accepted room side
ROBOT_PREFIX = "robot/"
PERSON_PREFIX = "person"  # every person's element names start with it (`person_prefix`)
PEOPLE_PER_BATCH = 32  # fewest people composed on a spec of their own, then attached together
# (2 sqrt(n) for n people: both the batches' attaches and each batch's own stay short)

# Geom groups: rays and renderers select on them.
GEOM_GROUP_ROOM = 0
GEOM_GROUP_PEOPLE = 1
GEOM_GROUP_ROBOT = 2

# Shirt colours (RGB), in order of the people in a scene; repeated darker beyond its length.
PALETTE: tuple[tuple[float, float, float], ...] = (
    (0.12, 0.47, 0.71),
    (1.00, 0.50, 0.05),
    (0.17, 0.63, 0.17),
    (0.84, 0.15, 0.16),
    (0.58, 0.40, 0.74),
    (0.55, 0.34, 0.29),
    (0.89, 0.47, 0.76),
    (0.50, 0.50, 0.50),
    (0.74, 0.74, 0.13),
    (0.09, 0.75, 0.81),
    (0.00, 0.30, 0.55),
    (0.60, 0.90, 0.30),
)


class _Texture(NamedTuple):
    """A texture MuJoCo draws itself: its ``builtin`` pattern between two RGB colours, on a
    square of ``pixels`` a side."""

    type: mujoco.mjtTexture
    builtin: mujoco.mjtBuiltin
    rgb1: tuple[float, float, float]
    rgb2: tuple[float, float, float]
    pixels: int


# The room's look: its textures (the floor's grid, the sky) and its plain materials' RGBA.
_ROOM_TEXTURES = {
    "floor_grid": _Texture(
        mujoco.mjtTexture.mjTEXTURE_2D,
        mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
        (0.82, 0.82, 0.80),
        (0.74, 0.74, 0.72),
        256,
    ),
    "sky": _Texture(
        mujoco.mjtTexture.mjTEXTURE_SKYBOX,
        mujoco.mjtBuiltin.mjBUILTIN_GRADIENT,
        (0.62, 0.72, 0.82),
        (0.25, 0.28, 0.32),
        64,
    ),
}
_ROOM_COLOURS = {"wall": (0.90, 0.88, 0.84, 1.0), "furniture": (0.55, 0.38, 0.24, 1.0)}

# Bodies and joints a person or robot asset must have (names inside the asset).
_PERSON_PARTS = {"body": ("root", "torso", "head"), "joint": ("neck_yaw",)}
_ROBOT_PARTS = {
    "body": ("base", "torso", "head_pan", "head"),
    "joint": ("head_pan", "head_tilt"),
    "site": ("head_sensor",),
    "camera": ("head_camera",),
}


def person_prefix(person_id: int) -> str:
    """Name prefix of person ``person_id``'s elements in a built scene, e.g. ``"person3/"``."""
    return f"{PERSON_PREFIX}{int(person_id)}/"


def default_color(index: int) -> tuple[float, float, float, float]:
    """A distinct RGBA shirt colour for the ``index``-th person of a scene."""
    r, g, b = PALETTE[index % len(PALETTE)]
    shade = 0.7 ** (index // len(PALETTE))
    return (r * shade, g * shade, b * shade, 1.0)


def _pair(name: str, value: Any) -> tuple[float, float]:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"{name} must be a pair of numbers (x, y) in metres, got {value!r}"
        ) from exc
    if array.shape != (2,) or not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be a finite pair (x, y) in metres, got {value!r}")
    return (float(array[0]), float(array[1]))


def _finite(name: str, value: Any) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a number, got {value!r}") from exc
    if not math.isfinite(number):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return number


def _in_range(name: str, value: Any, bounds: tuple[float, float], unit: str) -> float:
    number = _finite(name, value)
    low, high = bounds
    if not low <= number <= high:
        raise ValueError(f"{name} must be within [{low}, {high}] {unit}, got {number}")
    return number


def _check_id(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an int, got {value!r}")
    return int(value)


def _check_asset(name: str, value: Any) -> str:
    if value not in asset_names():
        raise ValueError(f"{name}: unknown asset {value!r}: expected one of {list(asset_names())}")
    return value


@dataclass(frozen=True)
class PersonSpec:
    """One person of a scene.

    Attributes:
        id: the person's id in every Frame (unique within the scene, robot included).
        position: (x, y) start position of the torso on the floor, metres.
        yaw: start body yaw, radians counter-clockwise from +x.
        height: standing height, metres (within ``PERSON_HEIGHT_RANGE_M``).
        width: distance between the shoulder joints, metres (within ``PERSON_WIDTH_RANGE_M``).
        color: shirt colour, RGB or RGBA in [0, 1]; ``None`` picks a distinct one.
        present: whether the person is in the room at the start (absent people can enter later).
        asset: name of the shipped model to use (see ``sim.assets.asset_names``).
        body_radius: the body disc's radius, metres (within ``BODY_RADIUS_RANGE_M``), or
            ``None`` for a disc enclosing arms, hands and nose; a smaller one lets people stand
            shoulder to shoulder (arms and noses may then touch).
    """

    id: int
    position: tuple[float, float]
    yaw: float = 0.0
    height: float = PERSON_REFERENCE_HEIGHT_M
    width: float = PERSON_REFERENCE_WIDTH_M
    color: tuple[float, ...] | None = None
    present: bool = True
    asset: str = PERSON_ASSET
    body_radius: float | None = None

    kind: ClassVar[str] = HUMAN

    def __post_init__(self) -> None:
        object.__setattr__(self, "id", _check_id("PersonSpec.id", self.id))
        label = f"person {self.id}"
        object.__setattr__(self, "position", _pair(f"{label}: position", self.position))
        object.__setattr__(self, "yaw", _finite(f"{label}: yaw", self.yaw))
        object.__setattr__(
            self, "height", _in_range(f"{label}: height", self.height, PERSON_HEIGHT_RANGE_M, "m")
        )
        object.__setattr__(
            self, "width", _in_range(f"{label}: width", self.width, PERSON_WIDTH_RANGE_M, "m")
        )
        if self.color is not None:
            color = tuple(float(c) for c in self.color)
            if len(color) not in (3, 4) or not all(0.0 <= c <= 1.0 for c in color):
                raise ValueError(
                    f"{label}: color must be RGB or RGBA with components in [0, 1], "
                    f"got {self.color!r}"
                )
            object.__setattr__(self, "color", color if len(color) == 4 else (*color, 1.0))
        object.__setattr__(self, "present", bool(self.present))
        _check_asset(f"{label}: asset", self.asset)
        if self.body_radius is not None:
            object.__setattr__(
                self,
                "body_radius",
                _in_range(f"{label}: body_radius", self.body_radius, BODY_RADIUS_RANGE_M, "m"),
            )

    @property
    def radius(self) -> float:
        """Body radius, metres: ``body_radius`` when given, else a disc enclosing the arms and
        hands (0.28 m by default)."""
        if self.body_radius is not None:
            return self.body_radius
        return max(
            BODY_RADIUS_PER_WIDTH * self.width,
            HEAD_REACH_PER_WIDTH * self.width + HEAD_REACH_PER_HEIGHT * self.height,
        )

    @property
    def prefix(self) -> str:
        return person_prefix(self.id)


@dataclass(frozen=True)
class RobotSpec:
    """The Directions Robot of a scene.

    Attributes:
        id: the robot's id in every Frame (unique within the scene).
        position: (x, y) start position of the base on the floor, metres.
        yaw: start base yaw, radians counter-clockwise from +x.
        height: total height, metres (within ``ROBOT_HEIGHT_RANGE_M``).
        head_pan: start head pan, radians (positive to the left).
        head_tilt: start head tilt, radians (positive looking down).
        asset: name of the shipped model to use.
    """

    id: int = 0
    position: tuple[float, float] = (0.0, 0.0)
    yaw: float = 0.0
    height: float = ROBOT_REFERENCE_HEIGHT_M
    head_pan: float = 0.0
    head_tilt: float = 0.0
    asset: str = ROBOT_ASSET

    kind: ClassVar[str] = ROBOT
    radius: ClassVar[float] = ROBOT_RADIUS_M  # metres, body radius: the base disc
    present: ClassVar[bool] = True  # the robot is always in the room
    prefix: ClassVar[str] = ROBOT_PREFIX

    def __post_init__(self) -> None:
        object.__setattr__(self, "id", _check_id("RobotSpec.id", self.id))
        object.__setattr__(self, "position", _pair("robot: position", self.position))
        object.__setattr__(self, "yaw", _finite("robot: yaw", self.yaw))
        object.__setattr__(
            self, "height", _in_range("robot: height", self.height, ROBOT_HEIGHT_RANGE_M, "m")
        )
        object.__setattr__(self, "head_pan", _finite("robot: head_pan", self.head_pan))
        object.__setattr__(self, "head_tilt", _finite("robot: head_tilt", self.head_tilt))
        _check_asset("robot: asset", self.asset)


Agent = PersonSpec | RobotSpec


@dataclass(frozen=True)
class FurnitureSpec:
    """A static object in the room (visual only: the motion does not collide with it).

    Attributes:
        kind: ``"table"`` (a cylinder), ``"bar"`` or ``"poster"`` (boxes).
        position: (x, y) of its centre on the floor, metres.
        size: (length, depth, height), metres, each within ``FURNITURE_SIZE_RANGE_M``.
        yaw: direction of its length, radians.
    """

    kind: str
    position: tuple[float, float]
    size: tuple[float, float, float]
    yaw: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in FURNITURE_KINDS:
            raise ValueError(
                f"furniture: kind must be one of {list(FURNITURE_KINDS)}, got {self.kind!r}"
            )
        label = f"furniture {self.kind}"
        object.__setattr__(self, "position", _pair(f"{label}: position", self.position))
        if len(tuple(self.size)) != 3:
            raise ValueError(f"{label}: size must be (length, depth, height), got {self.size!r}")
        size = tuple(_in_range(f"{label}: size", v, FURNITURE_SIZE_RANGE_M, "m") for v in self.size)
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "yaw", _finite(f"{label}: yaw", self.yaw))


@dataclass(frozen=True)
class SceneSpec:
    """A room with people and, optionally, the Directions Robot.

    Attributes:
        people: the people, in the order they appear in every Frame.
        robot: the robot, or ``None`` for a scene of people only. It comes last in Frames.
        room: (x extent, y extent) of the floor inside the walls, metres; the room is centred on
            the origin. Babble's play area was 5 m x 5 m.
        wall_height: metres.
        name: model name.
        furniture: static tables, bar counters and posters (geoms named ``furniture<k>``).
    """

    people: Sequence[PersonSpec] = ()
    robot: RobotSpec | None = None
    room: tuple[float, float] = (5.0, 5.0)
    wall_height: float = 1.0
    name: str = "scene"
    furniture: Sequence[FurnitureSpec] = ()
    _agents: tuple[Agent, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        people = tuple(self.people)
        for k, person in enumerate(people):
            if not isinstance(person, PersonSpec):
                raise ValueError(f"people[{k}] must be a PersonSpec, got {type(person).__name__}")
        if self.robot is not None and not isinstance(self.robot, RobotSpec):
            raise ValueError(f"robot must be a RobotSpec or None, got {type(self.robot).__name__}")
        object.__setattr__(self, "people", people)
        furniture = tuple(self.furniture)
        for k, item in enumerate(furniture):
            if not isinstance(item, FurnitureSpec):
                raise ValueError(
                    f"furniture[{k}] must be a FurnitureSpec, got {type(item).__name__}"
                )
        object.__setattr__(self, "furniture", furniture)
        room = _pair("room", self.room)
        if not (0.0 < room[0] <= ROOM_MAX_M and 0.0 < room[1] <= ROOM_MAX_M):
            raise ValueError(
                f"room must be (x extent, y extent), both within (0, {ROOM_MAX_M}] m, got {room}"
            )
        object.__setattr__(self, "room", room)
        wall_height = _finite("wall_height", self.wall_height)
        if wall_height <= 0.0:
            raise ValueError(f"wall_height must be positive, got {wall_height} m")
        object.__setattr__(self, "wall_height", wall_height)
        object.__setattr__(self, "name", str(self.name))
        agents: tuple[Agent, ...] = people + ((self.robot,) if self.robot is not None else ())
        object.__setattr__(self, "_agents", agents)
        self._check_ids()
        self._check_capacity()
        self._check_starts()

    @property
    def agents(self) -> tuple[Agent, ...]:
        """People then the robot: the order of every array the world keeps."""
        return self._agents

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) of the floor inside the walls, metres."""
        hx, hy = 0.5 * self.room[0], 0.5 * self.room[1]
        return (-hx, hx, -hy, hy)

    def inner_bounds(self, radius: float) -> tuple[float, float, float, float]:
        """Where the centre of an agent of body ``radius`` may be, keeping off the walls."""
        x0, x1, y0, y1 = self.bounds
        pad = radius + WALL_MARGIN_M
        return (x0 + pad, x1 - pad, y0 + pad, y1 - pad)

    def agent(self, agent_id: int) -> Agent:
        """The person or robot with id ``agent_id``."""
        for agent in self._agents:
            if agent.id == agent_id:
                return agent
        raise KeyError(f"no agent with id {agent_id} (ids {[a.id for a in self._agents]})")

    def _check_ids(self) -> None:
        seen: set[int] = set()
        for agent in self._agents:
            if agent.id in seen:
                raise ValueError(f"agent ids must be unique within a scene, got {agent.id} twice")
            seen.add(agent.id)

    def _check_capacity(self) -> None:
        need = sum(math.pi * a.radius**2 for a in self._agents)
        have = PACKING_DENSITY * self.room[0] * self.room[1]
        if need > have:
            r = self._agents[0].radius
            most = int(have / (math.pi * r**2))
            raise ValueError(
                f"too many people for the room: {len(self._agents)} agents need at least "
                f"{need:.2f} m^2 of floor (discs of their body radius, densest packing), a "
                f"{self.room[0]:g} m x {self.room[1]:g} m room offers {have:.2f} m^2 "
                f"(about {most} agents of radius {r:.3f} m)"
            )

    def _check_starts(self) -> None:
        placed: list[Agent] = []
        spots = np.empty((len(self._agents), 2))  # positions of the agents placed, in order
        radii = np.empty(len(self._agents))
        for agent in self._agents:
            label = _label(agent)
            x0, x1, y0, y1 = self.inner_bounds(agent.radius)
            x, y = agent.position
            if not (x0 <= x <= x1 and y0 <= y <= y1):
                raise ValueError(
                    f"{label}: start position ({x:g}, {y:g}) is outside the walls: with body "
                    f"radius {agent.radius:.3f} m it must be within x [{x0:.3f}, {x1:.3f}], "
                    f"y [{y0:.3f}, {y1:.3f}] m"
                )
            if not agent.present:
                continue
            k = len(placed)
            gaps = np.hypot(spots[:k, 0] - x, spots[:k, 1] - y)
            needs = radii[:k] + agent.radius + CLEARANCE_MARGIN_M
            close = np.flatnonzero(gaps < needs)
            if close.size:
                j = int(close[0])
                raise ValueError(
                    f"{label} and {_label(placed[j])} overlap at the start: their "
                    f"positions are {gaps[j]:.3f} m apart, at least {needs[j]:.3f} m expected "
                    "(sum of body radii plus clearance)"
                )
            spots[k] = (x, y)
            radii[k] = agent.radius
            placed.append(agent)


def _label(agent: Agent) -> str:
    return f"{'robot' if isinstance(agent, RobotSpec) else 'person'} {agent.id}"


def _quat_yaw(yaw: float) -> list[float]:
    return [math.cos(0.5 * yaw), 0.0, 0.0, math.sin(0.5 * yaw)]


def _scale(
    child: mujoco.MjSpec,
    *,
    horizontal: float,
    vertical: float,
    uniform_body: str | None = None,
) -> None:
    """Scales a child model in place: x and y (and radii) by ``horizontal``, z by ``vertical``.

    The geoms of ``uniform_body`` (a person's head) keep their proportions: they are scaled by
    ``vertical`` along every axis, so that the top of the head lands on the requested height.
    """
    body_scale = np.array([horizontal, horizontal, vertical])
    for body in child.bodies:
        body.pos = np.asarray(body.pos) * body_scale
    for geom in child.geoms:
        uniform = uniform_body is not None and geom.parent.name == uniform_body
        scale = np.full(3, vertical) if uniform else body_scale
        h = vertical if uniform else horizontal
        fromto = np.asarray(geom.fromto)
        if not np.isnan(fromto[0]):
            geom.fromto = fromto * np.tile(scale, 2)
        else:
            geom.pos = np.asarray(geom.pos) * scale
        size = np.array(geom.size, dtype=np.float64)
        if geom.type in (mujoco.mjtGeom.mjGEOM_CAPSULE, mujoco.mjtGeom.mjGEOM_CYLINDER):
            size[0] *= h
            size[1] *= vertical
        elif geom.type == mujoco.mjtGeom.mjGEOM_SPHERE:
            size[0] *= h
        else:
            size *= scale
        geom.size = size
    for site in child.sites:
        uniform = uniform_body is not None and site.parent.name == uniform_body
        site.pos = np.asarray(site.pos) * (vertical if uniform else body_scale)
    for camera in child.cameras:
        camera.pos = np.asarray(camera.pos) * body_scale


def _load(asset: str, parts: dict[str, tuple[str, ...]]) -> mujoco.MjSpec:
    child = mujoco.MjSpec.from_string(asset_xml(asset))
    for kind, names in parts.items():
        for name in names:
            if getattr(child, kind)(name) is None:
                raise ValueError(f"asset {asset!r} lacks the {kind} {name!r} the world needs")
    if not child.body(parts["body"][0]).mocap:
        raise ValueError(f"asset {asset!r}: body {parts['body'][0]!r} must be a mocap body")
    return child


def _add_room(spec: mujoco.MjSpec, scene: SceneSpec) -> None:
    sx, sy = scene.room
    world = spec.worldbody
    for name, texture in _ROOM_TEXTURES.items():
        spec.add_texture(
            name=name,
            type=texture.type,
            builtin=texture.builtin,
            rgb1=list(texture.rgb1),
            rgb2=list(texture.rgb2),
            width=texture.pixels,
            height=texture.pixels,
        )
    floor_material = spec.add_material(name="floor", texrepeat=[sx, sy], texuniform=False)
    floor_material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "floor_grid"
    spec.add_material(name="wall", rgba=list(_ROOM_COLOURS["wall"]))
    world.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[0.5 * sx + WALL_THICKNESS_M, 0.5 * sy + WALL_THICKNESS_M, 0.05],
        material="floor",
        contype=0,
        conaffinity=0,
        group=GEOM_GROUP_ROOM,
    )
    h, t = scene.wall_height, WALL_THICKNESS_M
    walls = {
        "wall_east": ([0.5 * sx + 0.5 * t, 0.0, 0.5 * h], [0.5 * t, 0.5 * sy + t, 0.5 * h]),
        "wall_west": ([-0.5 * sx - 0.5 * t, 0.0, 0.5 * h], [0.5 * t, 0.5 * sy + t, 0.5 * h]),
        "wall_north": ([0.0, 0.5 * sy + 0.5 * t, 0.5 * h], [0.5 * sx, 0.5 * t, 0.5 * h]),
        "wall_south": ([0.0, -0.5 * sy - 0.5 * t, 0.5 * h], [0.5 * sx, 0.5 * t, 0.5 * h]),
    }
    for name, (pos, size) in walls.items():
        world.add_geom(
            name=name,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            pos=pos,
            size=size,
            material="wall",
            contype=0,
            conaffinity=0,
            group=GEOM_GROUP_ROOM,
        )
    if scene.furniture:
        spec.add_material(name="furniture", rgba=list(_ROOM_COLOURS["furniture"]))
    for k, item in enumerate(scene.furniture):
        length, depth, height = item.size
        x, y = item.position
        if item.kind == "table":
            shape, size = mujoco.mjtGeom.mjGEOM_CYLINDER, [0.5 * length, 0.5 * height, 0.0]
        else:
            shape, size = mujoco.mjtGeom.mjGEOM_BOX, [0.5 * length, 0.5 * depth, 0.5 * height]
        world.add_geom(
            name=f"furniture{k}",
            type=shape,
            pos=[x, y, 0.5 * height],
            quat=[math.cos(0.5 * item.yaw), 0.0, 0.0, math.sin(0.5 * item.yaw)],
            size=size,
            material="furniture",
            contype=0,
            conaffinity=0,
            group=GEOM_GROUP_ROOM,
        )
    span = max(sx, sy)
    world.add_light(
        name="sun",
        type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
        pos=[0.0, 0.0, 3.0 + span],
        dir=[0.3, 0.4, -1.0],
        diffuse=[0.7, 0.7, 0.7],
        castshadow=False,
    )
    # An overview camera south of the room, looking down at its centre.
    back, up = 0.9 * span, 1.1 * span
    norm = math.hypot(back, up)
    camera = world.add_camera(name="overview", pos=[0.0, -back, up], fovy=50.0)
    camera.alt.type = mujoco.mjtOrientation.mjORIENTATION_XYAXES
    camera.alt.xyaxes = [1.0, 0.0, 0.0, 0.0, up / norm, back / norm]


def _keep_one_geom_per_body(child: mujoco.MjSpec) -> None:
    for body in child.bodies:
        for geom in body.geoms[1:]:
            child.delete(geom)


def _attach_people(spec: mujoco.MjSpec, batch: mujoco.MjSpec | None, end: int) -> None:
    """Attaches a batch of people (their elements named without `PERSON_PREFIX`) to ``spec``
    under that prefix, which completes their names. ``spec.attach`` takes time in proportion to
    what ``spec`` holds already: people attached a batch at a time keep a crowd's scene
    quick to compose (1,000 people: about a second rather than a minute)."""
    if batch is not None:
        mount = spec.worldbody.add_frame(name=f"people{end}_mount")
        spec.attach(batch, frame=mount, prefix=PERSON_PREFIX)


def build_scene(scene: SceneSpec, *, geometry: bool = True) -> mujoco.MjModel:
    """Composes ``scene`` on an `mujoco.MjSpec` and compiles it.

    People and the robot are mocap bodies placed at their start poses; absent people are placed
    at their start positions too (the world moves them out of the room while they are absent).

    Args:
        scene: the validated scene.
        geometry: False builds the kinematic twin: the same bodies, joints, sites and cameras
            (so the same body poses for the same state) with one geom per body and no walls,
            for computing poses fast. Rendering and ray casts need the full model.

    Returns:
        The compiled model: lengths in metres, angles in radians, contacts disabled (the world
        is kinematic).
    """
    if not isinstance(scene, SceneSpec):
        raise ValueError(f"scene must be a SceneSpec, got {type(scene).__name__}")
    spec = mujoco.MjSpec()
    spec.modelname = scene.name
    spec.compiler.degree = False
    spec.option.disableflags |= (
        mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    )
    spec.stat.center = [0.0, 0.0, 0.8]
    spec.stat.extent = max(scene.room)
    _add_room(spec, scene)
    if not geometry:
        for name in ("wall_east", "wall_west", "wall_north", "wall_south"):
            spec.delete(spec.geom(name))
        for k in range(len(scene.furniture)):
            spec.delete(spec.geom(f"furniture{k}"))
    batch = None
    per_batch = max(PEOPLE_PER_BATCH, math.isqrt(4 * len(scene.people)))
    templates: dict[str, mujoco.MjSpec] = {}  # asset -> its spec, loaded once and copied
    for index, person in enumerate(scene.people):
        if index % per_batch == 0:
            _attach_people(spec, batch, index)
            batch = mujoco.MjSpec()
            batch.compiler.degree = False
        if person.asset not in templates:
            templates[person.asset] = _load(person.asset, _PERSON_PARTS)
            if not geometry:
                _keep_one_geom_per_body(templates[person.asset])
        child = templates[person.asset].copy()
        _scale(
            child,
            horizontal=person.width / PERSON_REFERENCE_WIDTH_M,
            vertical=person.height / PERSON_REFERENCE_HEIGHT_M,
            uniform_body="head",
        )
        shirt = child.material("shirt")
        if shirt is not None:
            shirt.rgba = list(person.color or default_color(index))
        root = child.body("root")
        root.pos = [person.position[0], person.position[1], 0.0]
        root.quat = _quat_yaw(person.yaw)
        inner = person.prefix.removeprefix(PERSON_PREFIX)
        mount = batch.worldbody.add_frame(name=f"{inner}mount")
        batch.attach(child, frame=mount, prefix=inner)
    _attach_people(spec, batch, len(scene.people))
    if scene.robot is not None:
        robot = scene.robot
        child = _load(robot.asset, _ROBOT_PARTS)
        if not geometry:
            _keep_one_geom_per_body(child)
        _scale(child, horizontal=1.0, vertical=robot.height / ROBOT_REFERENCE_HEIGHT_M)
        base = child.body("base")
        base.pos = [robot.position[0], robot.position[1], 0.0]
        base.quat = _quat_yaw(robot.yaw)
        mount = spec.worldbody.add_frame(name=f"{ROBOT_PREFIX}mount")
        spec.attach(child, frame=mount, prefix=ROBOT_PREFIX)
    return spec.compile()
