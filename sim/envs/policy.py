"""The scripted baseline of the joining task, and its evaluation over seeded episodes.

`JoinPolicy` acts on the observation alone (the robot's own pose, the people its sensor reports,
the detector's groups, which people it is to join):

1. it remembers where it last saw each person (in the room's frame);
2. the **detected o-space**: among the detector's F-formations holding people it is to join, the
   one holding most of them; its people's reported poses give the o-space circle
   (`sim.envs.reward.estimate_o_space`: the point nearest every member's facing line) and the
   place to take, in the widest gap, clear of every member's personal space
   (`sim.envs.reward.joining_place`); the last detected circle is kept while none is detected;
3. it drives there, going around the circle (on a ring `DETOUR_M` outside it, the short way
   unless a wall is in the way) rather than through the o-space, then turns to face the
   centre; its head keeps the group in view. A circle is taken only from people who have stood
   (moved slower than `STANDING_M_S`) for `STANDING_S`, and dropped when not detected again
   for `STALE_S`;
4. with no group detected yet, it walks toward where it last saw the people it is to join and
   stops `WAIT_DISTANCE_M` from them to watch, moving `ORBIT_RAD` around them for another view
   after each `WAIT_S` without a detection; having seen none of them, it turns in place.

`evaluate_policy` runs it for a number of seeded episodes (episode ``k`` is reset with seed
``seed + k``) and reports the success rate.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sim.envs.reward import JoinTask, OSpace, estimate_o_space, joining_place
from sim.motion import ROBOT_LIMITS

__all__ = ["EpisodeResult", "JoinPolicy", "PolicyEvaluation", "evaluate_policy"]

ARRIVE_M = 0.08  # metres from the place at which the robot stops and turns to the centre
LEAVE_M = 0.25  # metres: once arrived, the robot moves again only when pushed this far off
SLOW_M = 0.6  # metres from a waypoint within which the robot slows down
KEEP_OUT_M = 0.45  # metres outside the circle: paths cross this disc only on the last leg
APPROACH_M = 0.6  # metres outside the place, on its ray, where the last (radial) leg begins
DETOUR_M = 0.75  # metres outside the circle of the ring the robot goes around on
DETOUR_STEP_RAD = 0.6  # radians around the circle per detour waypoint
DIRECT_RAD = 0.35  # radians around the circle from the place where the last leg may start
SMOOTHING = 0.3  # share of a new circle estimate taken when it is near the last one
SAME_CIRCLE_M = 1.0  # metres: estimates this close to the last circle refine it
WAIT_DISTANCE_M = 1.6  # metres from the people's centroid where it waits for a detection
WAIT_S = 3.0  # seconds waited at one spot before moving around the people for another view
ORBIT_RAD = 0.8  # radians around the people's centroid to the next spot to wait at
WALL_GAP_M = 0.45  # metres: waypoints keep the robot's centre this far from the walls
CLEARANCE_MARGIN_M = 0.06  # metres added to the task's clearance when choosing the place
STANDING_M_S = 0.3  # m/s: people slower than this stand
STANDING_S = 1.5  # seconds a detected circle's people must have stood to be taken
STALE_S = 6.0  # seconds a circle is kept without being detected again
TURN_GAIN = 2.5  # rad/s per radian of heading error
SPEED_GAIN = 1.2  # m/s per metre of distance to the waypoint
PAN_GAIN = 3.0  # rad/s per radian of head-pan error
SCAN_TURN_RAD_S = 0.6  # rad/s, turning in place while no one it is to join was seen
CONTROL_DT_S = 0.1  # seconds between observations (the environments' 10 Hz)


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


class JoinPolicy:
    """Go to the gap in the detected o-space of the group to join, face its centre.

    Args:
        task: the task's parameters (its clearance sets how far from members the place is).
        action_scale: (3,) the environment's `SocialEnv.action_scale` (speed m/s, turn rate
            rad/s, head-pan rate rad/s at action 1).
        room: (x extent, y extent) of the room, metres (`SocialEnv.room`): waypoints stay
            inside; None for no walls.
        head_limit: the head's pan limit, radians.
        control_dt: seconds between observations.
    """

    def __init__(
        self,
        *,
        task: JoinTask | None = None,
        action_scale: Sequence[float] | None = None,
        room: tuple[float, float] | None = None,
        head_limit: float = ROBOT_LIMITS.head_limit,
        control_dt: float = CONTROL_DT_S,
    ) -> None:
        self.task = JoinTask() if task is None else task
        scale = (
            (ROBOT_LIMITS.max_speed, ROBOT_LIMITS.max_turn_rate, ROBOT_LIMITS.head_rate)
            if action_scale is None
            else action_scale
        )
        self.action_scale = np.asarray(scale, dtype=np.float64)
        if self.action_scale.shape != (3,) or not np.all(self.action_scale > 0):
            raise ValueError(f"action_scale must be 3 positive numbers, got {action_scale!r}")
        self.room = None if room is None else (float(room[0]), float(room[1]))
        self.head_limit = float(head_limit)
        self.control_dt = float(control_dt)
        self.reset()

    def reset(self) -> None:
        """Forgets the last episode."""
        self._step = 0
        self._seen_at: dict[int, tuple[int, np.ndarray]] = {}
        self._still_since: dict[int, int] = {}
        self._confirmed = 0
        self._circle: OSpace | None = None
        self._members = np.zeros((0, 2))
        self._place: np.ndarray | None = None
        self._side = 0.0
        self._arrived = False
        self._wait_from: int | None = None
        self._wait_bearing = 0.0

    def __call__(self, observation: Mapping[str, np.ndarray]) -> np.ndarray:
        """The action (3,) float32 in [-1, 1] for ``observation``."""
        self._step += 1
        x, y, yaw = (float(v) for v in observation["robot_pose"])
        pan = float(observation["head_pan"][0])
        robot = np.array([x, y])
        seen = np.flatnonzero(observation["people_seen"])
        local = np.asarray(observation["people_position"], dtype=np.float64)[seen]
        c, s = math.cos(yaw), math.sin(yaw)
        world = robot + local @ np.array([[c, s], [-s, c]])
        world_yaw = yaw + np.asarray(observation["people_yaw"], dtype=np.float64)[seen]
        for k, slot in enumerate(seen.tolist()):
            last = self._seen_at.get(slot)
            moving = True
            if last is not None:
                elapsed = (self._step - last[0]) * self.control_dt
                moving = float(np.hypot(*(world[k] - last[1]))) > STANDING_M_S * elapsed
            if moving:
                self._still_since[slot] = self._step
            self._seen_at[slot] = (self._step, world[k])
        if self._circle is not None and (self._step - self._confirmed) * self.control_dt > STALE_S:
            self._circle = None
        target = np.flatnonzero(observation["people_target"])
        self._update_circle(observation, seen, world, world_yaw, set(target.tolist()))

        if self._circle is not None:
            centre = self._circle.centre
            self._place = self._inside(
                joining_place(
                    self._circle,
                    self._members,
                    robot,
                    clearance=self.task.clearance + CLEARANCE_MARGIN_M,
                    max_offset=0.8 * self.task.ring_tolerance,
                )
            )
            speed, turn = self._drive(robot, yaw, self._waypoint(robot), centre)
            look = centre
        else:
            known = [self._seen_at[k][1] for k in target.tolist() if k in self._seen_at]
            if known:
                look = np.mean(known, axis=0)
                if self._wait_from is None:
                    away = robot - look
                    self._wait_bearing = math.atan2(away[1], away[0])
                    self._wait_from = self._step
                elif (self._step - self._wait_from) * self.control_dt > WAIT_S and self._arrived:
                    self._wait_bearing += ORBIT_RAD
                    self._wait_from = self._step
                direction = np.array([math.cos(self._wait_bearing), math.sin(self._wait_bearing)])
                stop = self._inside(look + WAIT_DISTANCE_M * direction)
                speed, turn = self._drive(robot, yaw, stop, look)
            else:
                look = None
                speed, turn = 0.0, SCAN_TURN_RAD_S
        pan_rate = 0.0
        if look is not None:
            want = _wrap(math.atan2(look[1] - y, look[0] - x) - yaw)
            want = min(max(want, -self.head_limit), self.head_limit)
            pan_rate = PAN_GAIN * (want - pan)
        command = np.array([speed, turn, pan_rate]) / self.action_scale
        return np.clip(command, -1.0, 1.0).astype(np.float32)

    def _update_circle(
        self,
        observation: Mapping[str, np.ndarray],
        seen: np.ndarray,
        world: np.ndarray,
        world_yaw: np.ndarray,
        target: set[int],
    ) -> None:
        """Takes the detected F-formation holding most people to join, standing, as the circle."""
        groups = np.asarray(observation.get("people_group", np.zeros(0)), dtype=np.int64)
        if groups.size == 0 or not target:
            return
        labels = groups[seen]
        slots = seen.tolist()
        votes = [int(g) for g, slot in zip(labels, slots, strict=True) if g and slot in target]
        if not votes:
            return
        label = max(set(votes), key=lambda g: (votes.count(g), -g))
        rows = np.flatnonzero(labels == label)
        if rows.size < 2:
            return
        still = STANDING_S / self.control_dt
        if any(self._step - self._still_since[slots[r]] < still for r in rows):
            return
        estimate = estimate_o_space(world[rows], world_yaw[rows])
        old = self._circle
        if old is not None and np.hypot(*(estimate.centre - old.centre)) < SAME_CIRCLE_M:
            estimate = OSpace(
                centre=old.centre + SMOOTHING * (estimate.centre - old.centre),
                radius=old.radius + SMOOTHING * (estimate.radius - old.radius),
            )
        self._circle = estimate
        self._members = world[rows]
        self._confirmed = self._step
        self._wait_from = None

    def _inside(self, point: np.ndarray) -> np.ndarray:
        if self.room is None:
            return point
        hx = max(0.5 * self.room[0] - WALL_GAP_M, 0.0)
        hy = max(0.5 * self.room[1] - WALL_GAP_M, 0.0)
        return np.array([min(max(point[0], -hx), hx), min(max(point[1], -hy), hy)])

    def _waypoint(self, robot: np.ndarray) -> np.ndarray:
        """The next point on the way to the place, never through the o-space.

        The last leg is radial: from a point `APPROACH_M` outside the place, on its ray from the
        centre, straight in. The robot goes there directly when the segment keeps out of the
        disc `KEEP_OUT_M` outside the circle, else around the circle on a ring `DETOUR_M`
        outside it (pressed inward by the walls), the short way unless the walls leave no room
        (the side chosen is kept until the last leg).
        """
        assert self._circle is not None and self._place is not None
        centre, radius = self._circle.centre, self._circle.radius
        out = self._place - centre
        reach = float(np.hypot(*out))
        phi_place = math.atan2(out[1], out[0])
        here = robot - centre
        phi_here = math.atan2(here[1], here[0])
        delta = _wrap(phi_place - phi_here)
        if abs(delta) <= DIRECT_RAD and float(np.hypot(*here)) >= reach - 0.15:
            self._side = 0.0
            return self._place
        approach = self._inside(
            centre + (reach + APPROACH_M) * np.array([math.cos(phi_place), math.sin(phi_place)])
        )
        if _segment_clear(robot, approach, centre, radius + KEEP_OUT_M):
            return approach
        if self._side == 0.0:
            self._side = math.copysign(1.0, delta)
        ring = radius + DETOUR_M
        first = None
        for side in (self._side, -self._side):
            angle = phi_here + side * DETOUR_STEP_RAD
            point = self._inside(centre + ring * np.array([math.cos(angle), math.sin(angle)]))
            first = point if first is None else first
            if float(np.hypot(*(point - centre))) >= radius + KEEP_OUT_M - 0.05:
                self._side = side
                return point
        return first

    def _drive(
        self, robot: np.ndarray, yaw: float, goal: np.ndarray, face: np.ndarray
    ) -> tuple[float, float]:
        """Unicycle control to ``goal``; once there, turn toward ``face``."""
        delta = goal - robot
        distance = float(np.hypot(*delta))
        arrived = distance <= (LEAVE_M if self._arrived else ARRIVE_M)
        self._arrived = arrived
        if arrived:
            error = _wrap(math.atan2(face[1] - robot[1], face[0] - robot[0]) - yaw)
            return 0.0, TURN_GAIN * error
        error = _wrap(math.atan2(delta[1], delta[0]) - yaw)
        speed = min(self.action_scale[0], SPEED_GAIN * distance) * max(0.0, math.cos(error)) ** 2
        if distance < SLOW_M:
            speed = min(speed, 0.3 + 0.5 * distance)
        return float(speed), TURN_GAIN * error


def _segment_clear(a: np.ndarray, b: np.ndarray, centre: np.ndarray, radius: float) -> bool:
    """Whether the segment from ``a`` to ``b`` keeps out of the disc (``centre``, ``radius``)."""
    ab = b - a
    length2 = float(ab @ ab)
    t = 0.0 if length2 == 0.0 else min(max(float((centre - a) @ ab) / length2, 0.0), 1.0)
    nearest = a + t * ab
    return float(np.hypot(*(centre - nearest))) >= radius


@dataclass(frozen=True)
class EpisodeResult:
    """One evaluated episode.

    Attributes:
        seed: the reset seed.
        success: whether the robot joined.
        steps: control steps taken.
        episode_return: sum of rewards.
        scenario_seed: the scenario's seed.
    """

    seed: int
    success: bool
    steps: int
    episode_return: float
    scenario_seed: int


@dataclass(frozen=True)
class PolicyEvaluation:
    """Success of the scripted baseline over seeded episodes.

    Attributes:
        env_id: the environment.
        seed: the first reset seed (episode ``k`` uses ``seed + k``).
        episodes: per-episode results.
        detector: the detector the environment used.
        seconds: wall-clock time of the evaluation.
    """

    env_id: str
    seed: int
    episodes: tuple[EpisodeResult, ...]
    detector: str
    seconds: float = field(default=0.0, compare=False)

    @property
    def success_rate(self) -> float:
        return sum(e.success for e in self.episodes) / len(self.episodes)

    @property
    def mean_return(self) -> float:
        return float(np.mean([e.episode_return for e in self.episodes]))

    @property
    def mean_steps_to_success(self) -> float | None:
        steps = [e.steps for e in self.episodes if e.success]
        return float(np.mean(steps)) if steps else None

    def to_json(self) -> dict[str, Any]:
        return {
            "env_id": self.env_id,
            "seed": self.seed,
            "episodes": len(self.episodes),
            "detector": self.detector,
            "success_rate": self.success_rate,
            "successes": sum(e.success for e in self.episodes),
            "mean_return": self.mean_return,
            "mean_steps_to_success": self.mean_steps_to_success,
            "per_episode": [
                {
                    "seed": e.seed,
                    "scenario_seed": e.scenario_seed,
                    "success": e.success,
                    "steps": e.steps,
                    "return": e.episode_return,
                }
                for e in self.episodes
            ],
        }


def evaluate_policy(
    env_id: str,
    *,
    episodes: int = 100,
    seed: int = 0,
    policy: JoinPolicy | None = None,
    progress: bool = False,
    **env_kwargs: Any,
) -> PolicyEvaluation:
    """Runs the scripted baseline (or ``policy``) for ``episodes`` seeded episodes.

    Args:
        env_id: a registered joining environment, e.g. ``"ReformSim/Mingle-v0"``.
        episodes: how many (> 0).
        seed: episode ``k`` is reset with ``seed + k``.
        policy: the policy; default `JoinPolicy` with the environment's task and action scale.
        progress: show a progress bar.
        **env_kwargs: passed to ``gymnasium.make`` (``detector=``, ``model=``, ...).

    Raises:
        ValueError: for a non-positive episode count or an environment without the joining
            task.
    """
    import gymnasium as gym

    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes must be a positive int, got {episodes!r}")
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ValueError(f"seed must be an int, got {seed!r}")
    env = gym.make(env_id, disable_env_checker=True, **env_kwargs)
    try:
        base = env.unwrapped
        if "people_target" not in base.observation_space.spaces:
            raise ValueError(
                f"{env_id} has no joining task (an observe environment?): evaluate the policy on "
                "a joining environment such as ReformSim/HRIConversation-v0"
            )
        if policy is None:
            policy = JoinPolicy(task=base.task, action_scale=base.action_scale, room=base.room)
        results = []
        start = time.perf_counter()
        indices: Any = range(episodes)
        if progress:
            from tqdm import tqdm

            indices = tqdm(indices, desc=env_id, unit="episode")
        for k in indices:
            observation, info = env.reset(seed=seed + k)
            policy.reset()
            total, steps, success, done = 0.0, 0, False, False
            while not done:
                observation, reward, terminated, truncated, info = env.step(policy(observation))
                total += reward
                steps += 1
                success = success or bool(info["is_success"])
                done = terminated or truncated
            results.append(
                EpisodeResult(
                    seed=seed + k,
                    success=success,
                    steps=steps,
                    episode_return=total,
                    scenario_seed=int(info["episode"]["scenario_seed"]),
                )
            )
        return PolicyEvaluation(
            env_id=env_id,
            seed=seed,
            episodes=tuple(results),
            detector=base.detector_name,
            seconds=time.perf_counter() - start,
        )
    finally:
        env.close()
