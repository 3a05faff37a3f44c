"""The world and the robot's view of it as plain arrays, read straight from MuJoCo.

An environment step cannot afford two validated `reform.Frame` objects (ground truth and the
sensor's view) at 10 Hz: building one costs more than moving the whole world by a control step.
`Eyes` reads the same numbers a `sim.World.frame` and a `sim.Sensor.observe` would give, as
arrays over every agent of the scene (people in scene order, then the robot), and builds Frames
only when asked (for the detector, a few times a second, and for recordings).

`Eyes.look` sees as `sim.Sensor.observe` does (field of view and range from the head sensor,
MuJoCo ray casts for occlusion) in compiled kernels, then applies the sensor's tracker errors
through the one model, `reform.perturb.TrackerNoise` (the same draws in the same order), so the
view equals ``Sensor.observe(world, rng)`` for the same generator state; the tests check that.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from reform.frame import ROBOT, Frame, Group
from reform.perturb import restrict_groups
from sim.sensor import Sensor, rays_clear
from sim.world import World, yaw_from_quat

__all__ = ["Eyes", "Truth", "View", "robot_frame"]


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
        self._is_robot = np.array([k == ROBOT for k in world.kinds], dtype=np.bool_)
        self._human = ~self._is_robot
        self._all = np.arange(self.ids.size, dtype=np.int64)
        self._half_fov = math.radians(sensor.fov_deg) / 2.0
        self._noise = sensor.tracker_noise
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
        # The agents of World.frame, in its order: the rows the noise model draws for.
        rows = self._all if truth.present.all() else np.flatnonzero(truth.present)
        origin = data.site_xpos[world.sensor_site].copy()
        xmat = data.site_xmat[world.sensor_site]
        seen = np.empty(self.ids.size, dtype=np.bool_)
        _in_view(
            truth.position,
            truth.present,
            self._human,
            origin[0],
            origin[1],
            math.atan2(xmat[3], xmat[0]),
            self._half_fov,
            sensor.min_range,
            sensor.max_range,
            seen,
        )
        head_seen = seen.copy()
        if sensor.occlusion and seen.any():
            cand = np.flatnonzero(seen)
            targets = np.concatenate([truth.torso_xyz[cand], truth.head_xyz[cand]])
            roots = self._roots[cand]
            clear = rays_clear(world.model, data, origin, targets, np.concatenate([roots, roots]))
            k = cand.size
            seen[cand] = clear[:k] | clear[k:]
            head_seen[cand] = clear[k:]
        # The tracker's noise and dropouts on the seen: the one model `Sensor.observe` applies,
        # with the same draws.
        noisy = self._noise.perturb_poses(
            rng,
            truth.position[rows],
            truth.yaw[rows],
            truth.head_position[rows],
            truth.head_yaw[rows],
            affected=seen[rows],
        )
        seen[rows] &= noisy.kept
        head_seen &= seen
        position, yaw = truth.position.copy(), truth.yaw.copy()
        head_position, head_yaw = truth.head_position.copy(), truth.head_yaw.copy()
        position[rows] = noisy.position
        yaw[rows] = noisy.yaw
        head_position[rows] = noisy.head_position
        head_yaw[rows] = noisy.head_yaw
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
        return Frame(
            ids=ids,
            kinds=tuple(k for k, kept in zip(self.kinds, keep, strict=True) if kept),
            position=position,
            yaw=yaw,
            head_position=head_position,
            head_yaw=head_yaw,
            groups=restrict_groups(groups, set(ids.tolist())),
            time=time,
            sequence=sequence,
        )


# ---------------------------------------------------------------------------------------------
# Compiled kernels: the same arithmetic as `sim.Sensor.in_view` (numpy there), per agent, and
# the robot-centred observation, without the overhead of many small array operations per
# control step.


@numba.njit(cache=True)
def _in_view(
    position: np.ndarray,
    present: np.ndarray,
    human: np.ndarray,
    ox: float,
    oy: float,
    heading: float,
    half_fov: float,
    min_range: float,
    max_range: float,
    out: np.ndarray,
) -> None:
    """``out[i]``: person ``i`` is present and within the field of view and range."""
    for i in range(position.shape[0]):
        dx = position[i, 0] - ox
        dy = position[i, 1] - oy
        distance = math.hypot(dx, dy)
        bearing = (math.atan2(dy, dx) - heading + math.pi) % (2.0 * math.pi) - math.pi
        out[i] = (
            human[i]
            and present[i]
            and distance >= min_range
            and distance <= max_range
            and abs(bearing) <= half_fov
        )


@numba.njit(cache=True)
def robot_frame(
    rows: np.ndarray,
    seen: np.ndarray,
    head_seen: np.ndarray,
    position: np.ndarray,
    yaw: np.ndarray,
    head_yaw: np.ndarray,
    x: float,
    y: float,
    heading: float,
    reach: float,
    out_position: np.ndarray,
    out_yaw: np.ndarray,
    out_head_yaw: np.ndarray,
    out_seen: np.ndarray,
    out_head_seen: np.ndarray,
) -> None:
    """The people ``rows`` (slot ``k`` = ``rows[k]``) in the robot's frame, into the ``out``
    arrays (zeroed first): position (x forward, y left, clipped to ``reach``), body and head yaw
    relative to ``heading``, wrapped; zeros where not seen."""
    c, s = math.cos(heading), math.sin(heading)
    out_position[:] = 0.0
    out_yaw[:] = 0.0
    out_head_yaw[:] = 0.0
    out_seen[:] = 0
    out_head_seen[:] = 0
    for k in range(rows.size):
        i = rows[k]
        if not seen[i]:
            continue
        dx = position[i, 0] - x
        dy = position[i, 1] - y
        out_position[k, 0] = min(max(c * dx + s * dy, -reach), reach)
        out_position[k, 1] = min(max(-s * dx + c * dy, -reach), reach)
        out_yaw[k] = (yaw[i] - heading + math.pi) % (2.0 * math.pi) - math.pi
        out_seen[k] = 1
        if head_seen[i]:
            out_head_yaw[k] = (head_yaw[i] - heading + math.pi) % (2.0 * math.pi) - math.pi
            out_head_seen[k] = 1
