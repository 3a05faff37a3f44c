"""The world and the robot's view of it as plain arrays, read straight from MuJoCo.

An environment step cannot afford two validated `reform.Frame` objects (ground truth and the
sensor's view) at 10 Hz: building one costs more than moving the whole world by a control step.
`Eyes` reads the same numbers a `sim.World.frame` and a `sim.Sensor.observe` would give, as
arrays over every agent of the scene (people in scene order, then the robot), and builds Frames
only when asked (for the detector, a few times a second, and for recordings).

`Eyes.look` follows `sim.Sensor.observe` exactly (field of view and range from the head sensor,
MuJoCo ray casts for occlusion, then dropouts and noise drawn from the generator passed in, the
same draws in the same order), so the view equals ``Sensor.observe(world, rng)`` for the same
generator state; the tests check that.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from reform.frame import ROBOT, Frame, Group
from sim.sensor import Sensor, _rays_clear
from sim.world import World, yaw_from_quat

__all__ = ["Eyes", "Truth", "View"]


@dataclass(frozen=True, eq=False)
class Truth:
    """Ground-truth poses of every agent of the scene now (people in order, then the robot).

    Attributes:
        time: seconds since the start.
        present: (n,) bool, who is in the room.
        position: (n, 2) torso positions, metres.
        yaw: (n,) body yaws, radians.
        head_position: (n, 2) head positions, metres.
        head_yaw: (n,) head yaws, radians.
        torso_xyz: (n, 3) torso centres, metres (the sensor's ray targets).
        head_xyz: (n, 3) head centres, metres.
    """

    time: float
    present: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    head_position: np.ndarray
    head_yaw: np.ndarray
    torso_xyz: np.ndarray
    head_xyz: np.ndarray


@dataclass(frozen=True, eq=False)
class View:
    """What the robot's sensor reports now, for every agent of the scene.

    Attributes:
        seen: (n,) bool, people the sensor reports (never the robot itself).
        head_seen: (n,) bool, people whose head pose it reports.
        position: (n, 2) reported positions (with noise), metres; meaningful where ``seen``.
        yaw: (n,) reported body yaws, radians; meaningful where ``seen``.
        head_position: (n, 2) reported head positions, metres; meaningful where ``head_seen``.
        head_yaw: (n,) reported head yaws, radians; meaningful where ``head_seen``.
    """

    seen: np.ndarray
    head_seen: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    head_position: np.ndarray
    head_yaw: np.ndarray


class Eyes:
    """Reads ground truth and the robot's view from a `World` as arrays.

    Args:
        world: a world with a robot.
        sensor: the robot's head sensor.
    """

    def __init__(self, world: World, sensor: Sensor) -> None:
        if world.robot_id is None:
            raise ValueError("the scene has no robot: an environment needs one")
        self.world = world
        self.sensor = sensor
        self.ids = world.ids
        self.kinds = world.kinds
        self.robot = world.agent_index(world.robot_id)
        self._torso = world.torso_bodies
        self._head = world.head_bodies
        self._roots = world.root_bodies
        self._bodies = np.concatenate([self._torso, self._head])
        self._is_robot = np.array([k == ROBOT for k in world.kinds], dtype=bool)
        self._human = ~self._is_robot
        self._all = np.arange(self.ids.size)
        self._half_fov = math.radians(sensor.fov_deg) / 2.0
        model = world.model
        self._pan_adr = int(model.jnt_qposadr[model.joint("robot/head_pan").id])

    @property
    def head_pan(self) -> float:
        """The robot's head pan now, radians."""
        return float(self.world.data.qpos[self._pan_adr])

    def truth(self) -> Truth:
        """Ground-truth poses now (what `World.frame` reads, for every agent)."""
        data = self.world.data
        n = self.ids.size
        xpos = data.xpos[self._bodies]
        yaw = yaw_from_quat(data.xquat[self._bodies])
        return Truth(
            time=self.world.time,
            present=self.world.present,
            position=xpos[:n, :2],
            yaw=yaw[:n],
            head_position=xpos[n:, :2],
            head_yaw=yaw[n:],
            torso_xyz=xpos[:n],
            head_xyz=xpos[n:],
        )

    def look(self, truth: Truth, rng: np.random.Generator) -> View:
        """The sensor's view now, as `Sensor.observe` would give it with ``rng``.

        Args:
            truth: `truth` at the world's current state.
            rng: the generator for dropouts and noise.
        """
        world, sensor = self.world, self.sensor
        data = world.data
        total = self.ids.size
        everyone = bool(truth.present.all())
        rows = self._all if everyone else np.flatnonzero(truth.present)  # World.frame's agents
        n = rows.size
        origin = data.site_xpos[world.sensor_site].copy()
        xmat = data.site_xmat[world.sensor_site]
        heading = math.atan2(xmat[3], xmat[0])
        delta = truth.position - origin[:2]
        distance = np.hypot(delta[:, 0], delta[:, 1])
        bearing = np.arctan2(delta[:, 1], delta[:, 0]) - heading
        bearing = np.abs((bearing + math.pi) % (2.0 * math.pi) - math.pi)
        body_seen = (
            self._human
            & truth.present
            & (distance >= sensor.min_range)
            & (distance <= sensor.max_range)
            & (bearing <= self._half_fov)
        )
        head_seen = body_seen.copy()
        if sensor.occlusion and body_seen.any():
            cand = np.flatnonzero(body_seen)
            targets = np.concatenate([truth.torso_xyz[cand], truth.head_xyz[cand]])
            roots = self._roots[cand]
            clear = _rays_clear(world.model, data, origin, targets, np.concatenate([roots, roots]))
            k = cand.size
            body_seen[cand] = clear[:k] | clear[k:]
            head_seen[cand] = clear[k:]

        # Sensor.observe's draws, in its order: dropouts, then 6 n normals in one call (the
        # same numbers as its four calls).
        missed = rng.random(n) < sensor.dropout
        normal = rng.normal(0.0, 1.0, size=6 * n)
        seen = body_seen
        if everyone:
            seen &= ~missed
        else:
            seen[rows] &= ~missed
        head_seen &= seen
        position = truth.position.copy()
        yaw = truth.yaw.copy()
        head_position = truth.head_position.copy()
        head_yaw = truth.head_yaw.copy()
        if seen.any():
            noise = np.zeros((total, 6))
            noise[rows, 0:2] = normal[: 2 * n].reshape(n, 2) * sensor.position_noise
            noise[rows, 2:4] = normal[2 * n : 4 * n].reshape(n, 2) * sensor.position_noise
            noise[rows, 4] = normal[4 * n : 5 * n] * sensor.yaw_noise
            noise[rows, 5] = normal[5 * n :] * sensor.yaw_noise
            s = np.flatnonzero(seen)
            position[s] += noise[s, 0:2]
            head_position[s] += noise[s, 2:4]
            yaw[s] += noise[s, 4]
            head_yaw[s] += noise[s, 5]
        # Wrapped like Sensor.observe (reform.wrap_angle's arithmetic), every agent.
        yaw = (yaw + math.pi) % (2.0 * math.pi) - math.pi
        head_yaw = (head_yaw + math.pi) % (2.0 * math.pi) - math.pi
        return View(
            seen=seen,
            head_seen=head_seen,
            position=position,
            yaw=yaw,
            head_position=head_position,
            head_yaw=head_yaw,
        )

    def observed_frame(
        self, truth: Truth, view: View, groups: tuple[Group, ...] | None, *, sequence: str = ""
    ) -> Frame:
        """The view as a Frame (the seen people and, if the sensor keeps it, the robot).

        ``groups`` are the ground-truth groups now; the Frame holds them restricted to the
        agents it holds (as `Sensor.observe` does), or None when not annotated.
        """
        keep = view.seen.copy()
        if self.sensor.include_robot:
            keep[self.robot] = True
        robot = self.robot
        position = view.position[keep]
        yaw = view.yaw[keep]
        head_position = view.head_position.copy()
        head_yaw = view.head_yaw.copy()
        hidden = ~view.head_seen
        hidden[robot] = False
        head_position[hidden] = np.nan
        head_yaw[hidden] = np.nan
        return self._frame(
            keep, position, yaw, head_position[keep], head_yaw[keep], truth.time, groups, sequence
        )

    def truth_frame(
        self, truth: Truth, groups: tuple[Group, ...] | None, *, sequence: str = ""
    ) -> Frame:
        """The ground truth as a Frame of the agents present."""
        keep = truth.present
        return self._frame(
            keep,
            truth.position[keep],
            truth.yaw[keep],
            truth.head_position[keep],
            truth.head_yaw[keep],
            truth.time,
            groups,
            sequence,
        )

    def _frame(
        self,
        keep: np.ndarray,
        position: np.ndarray,
        yaw: np.ndarray,
        head_position: np.ndarray,
        head_yaw: np.ndarray,
        time: float,
        groups: tuple[Group, ...] | None,
        sequence: str,
    ) -> Frame:
        ids = self.ids[keep]
        if groups is not None:
            held = set(ids.tolist())
            groups = tuple(
                kept for kept in (tuple(m for m in g if m in held) for g in groups) if kept
            )
        return Frame(
            ids=ids,
            kinds=tuple(k for k, kept in zip(self.kinds, keep, strict=True) if kept),
            position=position,
            yaw=yaw,
            head_position=head_position,
            head_yaw=head_yaw,
            groups=groups,
            time=time,
            sequence=sequence,
        )
