"""The robot's view: people as the Directions Robot's head sensor sees them.

A `Sensor` turns the ground truth into an observed `reform.Frame`:

1. **Field of view and range**: a person is a candidate when the bearing of their torso from the
   sensor, on the ground plane, is within ``fov_deg / 2`` of the sensor's heading and their
   ground-plane distance is within ``[min_range, max_range]`` (defaults: 57 degrees, 0.5-4.5 m,
   the Kinect of the REFORM paper's robot).
2. **Occlusion**: from a `sim.world.World`, MuJoCo casts one ray from the head sensor to the
   torso centre and one to the head centre of every candidate (``mujoco.mj_multiRay``; the
   robot's own geoms are left out, the walls and other people block). A ray is clear when the
   first thing it hits belongs to the target itself. A person is seen when either ray is clear;
   their head pose is reported only when the head ray is clear (else NaN). From a bare Frame,
   with no MuJoCo scene at hand, occlusion is approximated on the ground plane: a nearer person
   within ``occluder_radius`` of the line of sight to a torso hides it.
3. **Noise and dropouts** on the people seen: the tracker's error model,
   `reform.perturb.TrackerNoise` (`Sensor.tracker_noise`), the one the stress tests'
   `reform.perturb.Perturbation` applies: Gaussian noise of ``position_noise`` metres per axis on
   body and head positions, ``yaw_noise`` radians on body and head yaws (yaws wrapped again), and
   each seen person missed with probability ``dropout``.

The robot itself is kept in the observed frame at its true pose (it knows where it is), unless
``include_robot`` is False. The observed frame's groups are the ground-truth groups restricted to
the people it holds (`reform.perturb.restrict_groups`): a group of which one member is seen
becomes that member alone; groups with no member seen disappear.

Random draws come from the ``rng`` passed in, in `reform.perturb`'s one documented order, and are
made for every person of the frame, seen or not, so that the draws do not depend on what is
visible: the same rng state gives the same observation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from reform._checks import non_negative
from reform.frame import Frame, wrap_angle
from reform.perturb import TrackerNoise
from sim.scene import GEOM_GROUP_PEOPLE, GEOM_GROUP_ROOM
from sim.world import World

KINECT_FOV_DEG = 57.0  # degrees, horizontal field of view of the head sensor
KINECT_MIN_RANGE_M = 0.5  # metres
KINECT_MAX_RANGE_M = 4.5  # metres
OCCLUDER_RADIUS_M = 0.2  # metres, a person's width as an occluder on the ground plane
_RAY_SLACK_M = 1e-6  # metres, a hit this close to the target point counts as the target


@dataclass(frozen=True)
class Sensor:
    """The robot's head sensor: what it can see and how well.

    Attributes:
        fov_deg: horizontal field of view, degrees, in (0, 360].
        min_range: nearest ground-plane distance seen, metres.
        max_range: farthest ground-plane distance seen, metres.
        position_noise: standard deviation of position noise per axis, metres.
        yaw_noise: standard deviation of yaw noise, radians.
        dropout: probability that a seen person is missed, in [0, 1].
        occlusion: whether other bodies hide people.
        include_robot: whether the observed frame holds the robot itself.
        occluder_radius: ground-plane radius of a person as an occluder when observing a bare
            Frame, metres.
    """

    fov_deg: float = KINECT_FOV_DEG
    min_range: float = KINECT_MIN_RANGE_M
    max_range: float = KINECT_MAX_RANGE_M
    position_noise: float = 0.0
    yaw_noise: float = 0.0
    dropout: float = 0.0
    occlusion: bool = True
    include_robot: bool = True
    occluder_radius: float = OCCLUDER_RADIUS_M

    def __post_init__(self) -> None:
        for name in (
            "fov_deg",
            "min_range",
            "max_range",
            "position_noise",
            "yaw_noise",
            "dropout",
            "occluder_radius",
        ):
            value = non_negative(f"Sensor.{name}", float(getattr(self, name)))
            object.__setattr__(self, name, value)
        if not 0.0 < self.fov_deg <= 360.0:
            raise ValueError(f"Sensor.fov_deg must be within (0, 360] degrees, got {self.fov_deg}")
        if self.max_range <= self.min_range:
            raise ValueError(
                f"Sensor.max_range must exceed min_range, "
                f"got {self.max_range} <= {self.min_range} m"
            )
        non_negative("Sensor.dropout", self.dropout, high=1.0)
        object.__setattr__(self, "occlusion", bool(self.occlusion))
        object.__setattr__(self, "include_robot", bool(self.include_robot))

    @property
    def tracker_noise(self) -> TrackerNoise:
        """The noise and dropouts on the people seen (`reform.perturb.TrackerNoise`)."""
        return TrackerNoise(
            position_std=self.position_noise, yaw_std=self.yaw_noise, dropout=self.dropout
        )

    def in_view(self, origin: np.ndarray, heading: float, points: np.ndarray) -> np.ndarray:
        """Which ground-plane ``points`` (k, 2) are within the field of view and range.

        Args:
            origin: (2,) sensor position on the ground plane, metres.
            heading: sensor yaw, radians.
            points: (k, 2) positions, metres.

        Returns:
            (k,) bool.
        """
        delta = np.asarray(points, dtype=np.float64) - np.asarray(origin, dtype=np.float64)[:2]
        distance = np.hypot(delta[:, 0], delta[:, 1])
        bearing = wrap_angle(np.arctan2(delta[:, 1], delta[:, 0]) - heading)
        half = math.radians(self.fov_deg) / 2.0
        return (
            (distance >= self.min_range) & (distance <= self.max_range) & (np.abs(bearing) <= half)
        )

    def visibility(self, world: World) -> tuple[Frame, np.ndarray, np.ndarray]:
        """The ground truth now and, per entry, whether its body and its head are seen.

        No dropout or noise: this is what a perfect tracker with this field of view, range and
        occlusion would see. The robot's own entry is marked unseen.

        Returns:
            (truth, body_seen, head_seen): the ground-truth Frame and two (n,) bool arrays.
        """
        if world.sensor_site < 0:
            raise ValueError("observe: the world has no robot, so no head sensor")
        model, data = world.model, world.data
        truth = world.frame()
        origin = data.site_xpos[world.sensor_site].copy()
        xmat = data.site_xmat[world.sensor_site]
        heading = math.atan2(xmat[3], xmat[0])
        humans = ~truth.is_robot
        body_seen = humans & self.in_view(origin, heading, truth.position)
        head_seen = body_seen.copy()
        if self.occlusion and np.any(body_seen):
            rows = np.flatnonzero(body_seen)
            index = np.array([world.agent_index(int(i)) for i in truth.ids[rows]])
            torso = data.xpos[world.torso_bodies[index]]
            head = data.xpos[world.head_bodies[index]]
            roots = world.root_bodies[index]
            targets = np.concatenate([torso, head])
            clear = rays_clear(model, data, origin, targets, np.concatenate([roots, roots]))
            k = rows.size
            torso_clear, head_clear = clear[:k], clear[k:]
            body_seen[rows] = torso_clear | head_clear
            head_seen[rows] = head_clear
        return truth, body_seen, head_seen & body_seen

    def observe(self, source: World | Frame, rng: np.random.Generator) -> Frame:
        """The observed Frame: who the robot sees now, where, with noise and dropouts.

        Args:
            source: a World (MuJoCo ray casts for occlusion) or a ground-truth Frame holding the
                robot with a head pose (ground-plane occlusion).
            rng: the generator for dropouts and noise.

        Returns:
            A Frame of the robot (unless ``include_robot`` is False) and the people seen.
        """
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
        if isinstance(source, World):
            truth, body_seen, head_seen = self.visibility(source)
        elif isinstance(source, Frame):
            truth, body_seen, head_seen = self._visibility_2d(source)
        else:
            raise ValueError(f"source must be a World or a Frame, got {type(source).__name__}")
        robot = truth.is_robot
        return self.tracker_noise.apply(
            truth,
            rng,
            tracked=body_seen | (robot & self.include_robot),
            affected=body_seen & ~robot,
            hidden_heads=body_seen & ~head_seen,
        )

    def _visibility_2d(self, frame: Frame) -> tuple[Frame, np.ndarray, np.ndarray]:
        robot_rows = np.flatnonzero(frame.is_robot)
        if robot_rows.size != 1:
            raise ValueError(
                f"observe: a Frame source must hold exactly one robot, got {robot_rows.size} "
                f"(frame at t={frame.time:g} s)"
            )
        r = int(robot_rows[0])
        if frame.head_position is None or not np.all(np.isfinite(frame.head_position[r])):
            raise ValueError("observe: the robot's head pose is missing from the frame")
        origin = frame.head_position[r]
        heading = float(frame.head_yaw[r])
        humans = ~frame.is_robot
        seen = humans & self.in_view(origin, heading, frame.position)
        if self.occlusion and np.any(seen):
            delta = frame.position - origin
            distance = np.hypot(delta[:, 0], delta[:, 1])
            for t in np.flatnonzero(seen):
                direction = delta[t] / distance[t]
                along = delta @ direction
                across = np.abs(delta[:, 0] * direction[1] - delta[:, 1] * direction[0])
                blockers = (
                    humans
                    & (np.arange(frame.n_people) != t)
                    & (along > 0.0)
                    & (along < distance[t])
                    & (across < self.occluder_radius)
                )
                if np.any(blockers):
                    seen[t] = False
        return frame, seen, seen.copy()


def rays_clear(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    origin: np.ndarray,
    targets: np.ndarray,
    target_roots: np.ndarray,
) -> np.ndarray:
    """Whether the segment from ``origin`` to each of ``targets`` is unobstructed.

    One ``mujoco.mj_multiRay`` call casts every ray against the geoms of the room and the
    people (the robot's own geoms are left out). A ray is clear when it hits nothing before the
    target (a hit within a micrometre of it counts as the target), or when the first geom it
    hits belongs to the target's own body tree. This is the occlusion test of
    `Sensor.visibility`.

    Args:
        model: the scene's MuJoCo model.
        data: its data, with the kinematics of the moment computed.
        origin: (3,) where the rays start (the sensor), metres.
        targets: (k, 3) points the rays aim at, metres.
        target_roots: (k,) root body id of each target's body tree.

    Returns:
        (k,) bool: whether each target is in plain sight of ``origin``.
    """
    vec = targets - origin
    distance = np.linalg.norm(vec, axis=1)
    unit = vec / np.maximum(distance, 1e-12)[:, None]
    k = targets.shape[0]
    geomid = np.full(k, -1, dtype=np.int32)
    dist = np.full(k, -1.0)
    groups = np.zeros(mujoco.mjNGROUP, dtype=np.uint8)
    groups[GEOM_GROUP_ROOM] = 1
    groups[GEOM_GROUP_PEOPLE] = 1
    mujoco.mj_multiRay(
        model,
        data,
        np.asarray(origin, dtype=np.float64),
        np.ascontiguousarray(unit).ravel(),
        groups,
        1,
        -1,
        geomid,
        dist,
        None,
        k,
        float(np.max(distance)) + 1.0,
    )
    missed = geomid < 0
    hit_root = model.body_rootid[model.geom_bodyid[np.maximum(geomid, 0)]]
    own = hit_root == target_roots
    beyond = dist >= distance - _RAY_SLACK_M
    return missed | own | beyond
