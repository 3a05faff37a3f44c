"""The scripted baseline of the joining task, and its evaluation over seeded episodes.

`JoinPolicy` acts on the observation alone (the robot's own pose, the people its sensor reports,
the detector's groups, which people it is to join):

1. it remembers where it last saw each person (in the room's frame);
2. the **detected o-space**: the people the detector put in an F-formation with people it is
   to join, pooled over the last `MEMBER_MEMORY_S` (a circle wider than the field of view is
   pieced together from several views), at their last reported poses, give the o-space circle
   (`sim.envs.reward.estimate_o_space`) and the place to take, in the widest gap between the
   people seen on the circle, clear of their personal space (`sim.envs.reward.joining_place`);
3. it walks to the place on the shortest way clear of everyone lately seen and of the circle
   (`sim.envs.planner`; the last leg radial, straight in), its head on the gap (anyone seen
   standing there moves the place to another gap), then turns to face the centre. A circle is
   taken only from people who have stood (moved slower than `STANDING_M_S`) for
   `STANDING_S`, and dropped when not detected again for `STALE_S`; when driving forward has
   not moved the robot for `STUCK_S` (someone too close to be seen), it backs up;
4. with no group detected yet, it walks toward where it last saw the people it is to join and
   stops `WAIT_DISTANCE_M` from them to watch, moving `ORBIT_RAD` around them for another view
   after each `WAIT_S` without a detection; having seen none of them, it turns in place,
   sweeping its head from side to side.

`evaluate_policy` runs it for a number of seeded episodes (episode ``k`` is reset with seed
``seed + k``) and reports the success rate.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from sim.envs.planner import Field, next_point, plan_field
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
WALL_GAP_M = 0.4  # metres: places and waypoints keep the robot's centre this far from walls
OPEN_SIDE_M = 0.1  # metres off a pair's midpoint its centre must lie to mark an open side
OBSTACLE_MEMORY_S = 10.0  # seconds someone seen counts as an obstacle where last seen
STUCK_S = 2.0  # seconds of driving forward without moving `STUCK_M` that mean being stuck
STUCK_M = 0.1  # metres
BACK_UP_S = 1.0  # seconds the robot then backs up, turning
BACK_UP_M_S = 0.3  # m/s
PASS_M = 0.6  # metres between the robot's centre and a person's that paths keep (bodies clear)
NO_PROGRESS_M = 0.15  # metres: a way whose next point is this close leads nowhere
REPLAN_M = 0.2  # metres the goal may move before the way is planned again
REPLAN_STEPS = 5  # control steps a planned way is followed before it is planned again
PAIR_TOLERANCE_SHARE = 0.8  # share of the ring tolerance used when hedging a pair's centre
LOOK_AT_GAP_M = 1.0  # metres from the place beyond which the head watches the gap
CLEARANCE_MARGIN_M = 0.1  # metres added to the task's clearance when choosing the place
STANDING_M_S = 0.3  # m/s: people slower than this stand
STANDING_S = 1.5  # seconds a detected circle's people must have stood to be taken
STALE_S = 6.0  # seconds a circle is kept without being detected again
MEMBER_MEMORY_S = 5.0  # seconds someone detected with people to join counts as a member
VOTE_DECAY = 0.97  # per step: how fast old detections of who is with whom are forgotten
MIN_VOTES = 2.0  # (decayed) detections with people to join that make a member
OCCUPANT_MEMORY_S = 30.0  # seconds someone seen on the circle's ring counts as standing there
RING_SLACK_M = 0.5  # metres off the circle within which someone seen occupies it
TURN_GAIN = 2.5  # rad/s per radian of heading error
SPEED_GAIN = 1.2  # m/s per metre of distance to the waypoint
PAN_GAIN = 3.0  # rad/s per radian of head-pan error
SCAN_TURN_RAD_S = 0.4  # rad/s, turning in place while no one it is to join was seen
SWEEP_PERIOD_S = 3.0  # seconds per sweep of the head from side to side while looking round
SWEEP_SHARE = 0.8  # share of the head's pan limit the sweep reaches
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
        self._yaw_at: dict[int, float] = {}
        self._together: dict[int, int] = {}
        self._votes: dict[int, tuple[float, float]] = {}
        self._confirmed = 0
        self._circle: OSpace | None = None
        self._members = np.zeros((0, 2))
        self._place: np.ndarray | None = None
        self._side = 0.0
        self._arrived = False
        self._plan: Field | None = None
        self._planned_at = 0
        self._track: list[tuple[int, np.ndarray, float]] = []
        self._backing_until = 0
        self._back_turn = 0.0
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
            place = self._pair_place(robot) if len(self._members) == 2 else None
            if place is None:
                # The gap nearest the robot; once chosen, the gap nearest the last place (no
                # dithering between two gaps as the robot walks round).
                reference = robot
                if self._place is not None:
                    off = float(np.hypot(*(self._place - centre))) - self._circle.radius
                    if off < SAME_CIRCLE_M:
                        reference = self._place
                place = joining_place(
                    self._circle,
                    self._occupants(),
                    reference,
                    clearance=self.task.clearance + CLEARANCE_MARGIN_M,
                    max_offset=0.7 * self.task.ring_tolerance,
                    bounds=self._bounds(),
                )
            self._place = self._inside(place)
            place = self._place
            speed, turn = self._drive(robot, yaw, self._waypoint(robot, place), centre)
            # The head watches the gap on the way (anyone standing there moves the place), the
            # centre once there.
            look = place if float(np.hypot(*(place - robot))) > LOOK_AT_GAP_M else centre
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
                step_to = stop
                if self.room is not None and float(np.hypot(*(stop - robot))) > SLOW_M:
                    step_to = self._route(robot, stop)
                    step_to = stop if step_to is None else step_to
                speed, turn = self._drive(robot, yaw, step_to, look)
            else:
                look = None
                speed, turn = 0.0, SCAN_TURN_RAD_S
        pan_rate = 0.0
        if look is None:
            # Looking round: the base turns slowly, the head sweeps from side to side.
            phase = 2.0 * math.pi * self._step * self.control_dt / SWEEP_PERIOD_S
            want = SWEEP_SHARE * self.head_limit * math.sin(phase)
            pan_rate = PAN_GAIN * (want - pan)
        else:
            want = _wrap(math.atan2(look[1] - y, look[0] - x) - yaw)
            want = min(max(want, -self.head_limit), self.head_limit)
            pan_rate = PAN_GAIN * (want - pan)
        speed, turn = self._unstick(robot, yaw, speed, turn)
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
        """The circle of the people lately detected in an F-formation with people to join.

        Views are pooled: everyone detected in the same F-formation as someone to join within
        the last `MEMBER_MEMORY_S` counts, at the pose last seen, so that a group wider than
        the field of view is pieced together, provided the detector put them with the people
        to join at least as often as apart (a vote over the last few seconds, older detections
        counting less). Only standing people count, and only a fresh detection of someone to
        join refreshes the circle.
        """
        slots = seen.tolist()
        for k, slot in enumerate(slots):
            self._yaw_at[slot] = float(world_yaw[k])
        groups = np.asarray(observation.get("people_group", np.zeros(0)), dtype=np.int64)
        if groups.size == 0 or not target:
            return
        labels = groups[seen].tolist()
        joined = {g for g, slot in zip(labels, slots, strict=True) if g and slot in target}
        if not joined:
            return
        for slot in list(self._votes):
            together, apart = self._votes[slot]
            self._votes[slot] = (VOTE_DECAY * together, VOTE_DECAY * apart)
        for g, slot in zip(labels, slots, strict=True):
            together, apart = self._votes.get(slot, (0.0, 0.0))
            self._votes[slot] = (together + 1.0, apart) if g in joined else (together, apart + 1.0)
            if g in joined:
                self._together[slot] = self._step
        memory = MEMBER_MEMORY_S / self.control_dt
        still = STANDING_S / self.control_dt
        members = [
            slot
            for slot, when in self._together.items()
            if self._step - when <= memory
            and self._step - self._still_since[slot] >= still
            and self._votes[slot][0] >= max(self._votes[slot][1], MIN_VOTES)
        ]
        if len(members) < 2:
            return
        position = np.array([self._seen_at[m][1] for m in members])
        estimate = estimate_o_space(position, np.array([self._yaw_at[m] for m in members]))
        old = self._circle
        if old is not None and np.hypot(*(estimate.centre - old.centre)) < SAME_CIRCLE_M:
            estimate = OSpace(
                centre=old.centre + SMOOTHING * (estimate.centre - old.centre),
                radius=old.radius + SMOOTHING * (estimate.radius - old.radius),
            )
        self._circle = estimate
        self._members = position
        self._confirmed = self._step
        self._wait_from = None

    def _pair_place(self, robot: np.ndarray) -> np.ndarray | None:
        """A place beside a pair that is on the circle whether or not it is open.

        Two people's facings rarely tell where their o-space centre is: facing each other it is
        their midpoint, standing open (a place kept for a third) it lies off it on the
        perpendicular bisector. The robot stands on the bisector where it is on the circle under
        both readings (the midpoint, and the estimate; halfway between them when no place
        suits both), clear of both, on the open side (else the side it is on; a side once
        chosen is kept unless the pair is open the other way); None when no such place is
        free.
        """
        assert self._circle is not None
        a, b = self._members
        middle = 0.5 * (a + b)
        along = b - a
        half = 0.5 * float(np.hypot(*along))
        if half == 0.0:
            return None
        normal = np.array([-along[1], along[0]]) / (2.0 * half)
        h_est = float((self._circle.centre - middle) @ normal)
        tol = PAIR_TOLERANCE_SHARE * self.task.ring_tolerance
        clear = self.task.clearance + CLEARANCE_MARGIN_M
        rho_clear = math.sqrt(max(clear * clear - half * half, 0.0))
        lean = h_est if abs(h_est) > OPEN_SIDE_M else float((robot - middle) @ normal)
        first = math.copysign(1.0, lean)
        if self._place is not None and float(np.hypot(*(self._place - middle))) < SAME_CIRCLE_M:
            kept = math.copysign(1.0, float((self._place - middle) @ normal))
            if kept * h_est > -OPEN_SIDE_M:  # keep the side unless the pair is open the other way
                first = kept
        occupants = self._occupants()[2:]
        for side in (first, -first):
            readings = (0.0, abs(h_est)) if side * h_est > 0.0 else (0.0,)
            reach = [h + math.hypot(half, h) for h in readings]
            low = max(rho_clear, max(reach) - tol)
            high = min(reach) + tol
            # Where both readings hold, the middle of that stretch; when none does, halfway
            # between the two (each reading then misses by the same, least amount).
            rho = 0.5 * (low + high) if low <= high else max(rho_clear, 0.5 * sum(reach))
            place = middle + side * rho * normal
            if not np.allclose(self._inside(place), place):
                continue
            if len(occupants) and np.min(np.hypot(*(occupants - place).T)) < clear:
                continue
            return place
        return None

    def _occupants(self) -> np.ndarray:
        """(k, 2) the circle's members and anyone else lately seen standing on its ring."""
        assert self._circle is not None
        memory = OCCUPANT_MEMORY_S / self.control_dt
        recent = [p for when, p in self._seen_at.values() if self._step - when <= memory]
        if not recent:
            return self._members
        recent = np.array(recent)
        off = np.abs(np.hypot(*(recent - self._circle.centre).T) - self._circle.radius)
        return np.vstack([self._members, recent[off <= RING_SLACK_M]])

    def _bounds(self) -> tuple[float, float, float, float] | None:
        if self.room is None:
            return None
        hx = max(0.5 * self.room[0] - WALL_GAP_M, 0.0)
        hy = max(0.5 * self.room[1] - WALL_GAP_M, 0.0)
        return (-hx, hx, -hy, hy)

    def _inside(self, point: np.ndarray) -> np.ndarray:
        if self.room is None:
            return point
        hx = max(0.5 * self.room[0] - WALL_GAP_M, 0.0)
        hy = max(0.5 * self.room[1] - WALL_GAP_M, 0.0)
        return np.array([min(max(point[0], -hx), hx), min(max(point[1], -hy), hy)])

    def _waypoint(
        self, robot: np.ndarray, goal: np.ndarray, *, last_leg: bool = True
    ) -> np.ndarray:
        """The next point on the way to ``goal``, never through the o-space.

        For the place (``last_leg``), the last leg is radial: from a point `APPROACH_M` outside
        it, on its ray from the centre, straight in. In a known room the robot walks to that
        point (or to ``goal``) on the shortest way clear of everyone's personal space and of
        the disc `KEEP_OUT_M` outside the circle (`sim.envs.planner`); without walls to plan
        in, or with no way found, it goes directly when the segment keeps out of that disc,
        else around the circle on a ring `DETOUR_M` outside it, the short way unless the walls
        leave no room (the side chosen is kept until the way is clear).
        """
        assert self._circle is not None
        centre, radius = self._circle.centre, self._circle.radius
        out = goal - centre
        reach = float(np.hypot(*out))
        phi_goal = math.atan2(out[1], out[0])
        here = robot - centre
        phi_here = math.atan2(here[1], here[0])
        delta = _wrap(phi_goal - phi_here)
        if last_leg and abs(delta) <= DIRECT_RAD and float(np.hypot(*here)) >= reach - 0.15:
            self._side = 0.0
            return goal
        entry = goal
        if last_leg:
            entry = self._inside(
                centre + (reach + APPROACH_M) * np.array([math.cos(phi_goal), math.sin(phi_goal)])
            )
        if self.room is not None:
            point = self._route(robot, entry, keep_out=(centre, radius + KEEP_OUT_M))
            if point is not None:
                return point
        if _segment_clear(robot, entry, centre, radius + KEEP_OUT_M):
            self._side = 0.0
            return entry
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

    def _route(
        self,
        robot: np.ndarray,
        goal: np.ndarray,
        *,
        keep_out: tuple[np.ndarray, float] | None = None,
    ) -> np.ndarray | None:
        """The next point on the shortest way to ``goal`` around the people lately seen (None
        when there is no way); the plan is redone when the goal moves or grows old."""
        plan = self._plan
        if (
            plan is None
            or float(np.hypot(*(plan.goal - goal))) > REPLAN_M
            or self._step - self._planned_at >= REPLAN_STEPS
        ):
            memory = OBSTACLE_MEMORY_S / self.control_dt
            people = [p for when, p in self._seen_at.values() if self._step - when <= memory]
            bounds = self._bounds()
            assert bounds is not None
            plan = self._plan = plan_field(
                bounds,
                goal,
                np.array(people).reshape(-1, 2),
                radius=PASS_M,
                keep_out=keep_out,
            )
            self._planned_at = self._step
        point = next_point(plan, robot)
        if point is not None and float(np.hypot(*(point - robot))) < NO_PROGRESS_M:
            return None  # the way starts where the robot stands: boxed in, no way found
        return point

    def _unstick(
        self, robot: np.ndarray, yaw: float, speed: float, turn: float
    ) -> tuple[float, float]:
        """Backs up, turning, for `BACK_UP_S` when driving forward has not moved the robot
        `STUCK_M` in `STUCK_S` (someone too close to be seen stands in the way)."""
        if self._step < self._backing_until:
            return -BACK_UP_M_S, self._back_turn
        self._track.append((self._step, robot.copy(), speed))
        window = int(round(STUCK_S / self.control_dt))
        if len(self._track) > window:
            self._track.pop(0)
        if len(self._track) == window and all(s > 0.2 for _, _, s in self._track):
            moved = float(np.hypot(*(robot - self._track[0][1])))
            if moved < STUCK_M:
                self._backing_until = self._step + int(round(BACK_UP_S / self.control_dt))
                self._back_turn = math.copysign(SCAN_TURN_RAD_S, math.sin(7.0 * self._step))
                self._track.clear()
                self._plan = None
                return -BACK_UP_M_S, self._back_turn
        return speed, turn

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
        with contextlib.ExitStack() as bars:
            if progress:  # redrawn while an episode runs (the first compiles the motion kernels)
                from tqdm import tqdm

                from sim.ticking import ticking

                indices = bars.enter_context(
                    ticking(bars.enter_context(tqdm(indices, desc=env_id, unit="episode")))
                )
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
