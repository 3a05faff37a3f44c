"""Motion primitives for people and the robot: one compiled kernel that moves every agent.

The world keeps each agent's motion state in one float64 matrix (a row per agent, columns
``S_*``), what the script wants in another (``I_*``) and fixed per-agent parameters in a third
(``P_*``). `advance` moves all agents by a number of control steps and writes the resulting
mocap poses and joint angles, which MuJoCo then turns into body poses. The kernel is compiled
with numba and loops over agents in machine code: a Python loop over agents at 100 Hz would cost
more than MuJoCo's kinematics itself.

Primitives, per control step ``dt`` (seconds):

* **Walk to a goal** at the preferred speed (1.0-1.4 m/s for people), with bounded
  acceleration (``max_accel``), braking to stop on the goal. Beyond ``SIDESTEP_M`` from the goal
  the body turns to the walking direction (turn rate bounded by ``max_turn_rate``) and the speed
  drops while the heading is wrong; closer than that people side-step at low speed without
  turning.
* **Avoid** other agents while walking: a short-range repulsion with a bias to pass on the right
  (not in the last side step into place, so that people can close up a tight circle).
* **Keep personal space**, strictly: nobody moves toward an agent they touch (the velocity
  component toward them is dropped; a commanded robot stops at people too); after each step,
  overlapping discs (body radius plus ``margin``) are pushed apart (walkers yield more than
  people standing), clamped inside the walls, and any agent still in conflict is put back where
  it was, where no conflict existed.
  So no two present agents are ever closer than the sum of their radii plus ``margin``.
* **Face** a yaw, a point or another agent when standing (turn rate bounded).
* **Turn the head** toward a gaze target (a point or an agent) within ``±head_limit`` of the
  body (people: 70 degrees); beyond that the standing body turns just enough to follow.
* **Idle sway**: standing people sway a little (position within ``P_SWAY_POS`` metres, yaw
  within ``P_SWAY_YAW`` radians; two slow sines of 0.17 and 0.41 Hz with per-person phases); the
  sway fades out with walking speed. Sway is added to the rendered pose only, inside the
  clearance margin.
* **Robot velocity commands**: with ``I_CMD`` set, the robot's base follows a forward speed and
  a turn rate (unicycle), and its head pan and tilt follow rates, all within its limits.
* **Leave and enter**: an absent agent is parked below the floor outside the room; it enters at
  ``I_APPEAR_*`` (or where it left) as soon as that spot is free.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from reform._checks import non_negative
from sim._numba_cache import use_a_writable_cache

use_a_writable_cache()  # before the kernel's functions are compiled and cached
# Motion state columns (one row per agent).
S_X, S_Y, S_VX, S_VY, S_YAW, S_HEAD, S_TILT, S_PRESENT = range(8)
N_STATE = 8

# Intent columns: what the script (or a controller) wants, per agent.
(
    I_HAS_GOAL,
    I_GOAL_X,
    I_GOAL_Y,
    I_SPEED,
    I_FACE_MODE,
    I_FACE_YAW,
    I_FACE_X,
    I_FACE_Y,
    I_FACE_AGENT,
    I_GAZE_MODE,
    I_GAZE_X,
    I_GAZE_Y,
    I_GAZE_AGENT,
    I_PRESENT,
    I_HAS_APPEAR,
    I_APPEAR_X,
    I_APPEAR_Y,
    I_CMD,
    I_CMD_SPEED,
    I_CMD_TURN,
    I_CMD_PAN,
    I_CMD_TILT,
) = range(22)
N_INTENT = 22

FACE_NONE, FACE_YAW, FACE_POINT, FACE_AGENT = 0, 1, 2, 3
GAZE_NONE, GAZE_POINT, GAZE_AGENT = 0, 1, 2

# Per-agent parameter columns.
(
    P_RADIUS,
    P_MAX_SPEED,
    P_MAX_ACCEL,
    P_MAX_TURN,
    P_HEAD_LIMIT,
    P_HEAD_RATE,
    P_TILT_LIMIT,
    P_TILT_RATE,
    P_X_MIN,
    P_X_MAX,
    P_Y_MIN,
    P_Y_MAX,
    P_PARK_X,
    P_PARK_Y,
    P_SWAY_POS,
    P_SWAY_YAW,
    P_SWAY_X1C,
    P_SWAY_X1S,
    P_SWAY_X2C,
    P_SWAY_X2S,
    P_SWAY_Y1C,
    P_SWAY_Y1S,
    P_SWAY_Y2C,
    P_SWAY_Y2S,
    P_SWAY_W1C,
    P_SWAY_W1S,
    P_SWAY_W2C,
    P_SWAY_W2S,
) = range(28)
N_PARAM = 28

ARRIVE_TOLERANCE_M = 0.03  # metres, a goal closer than this is reached
SIDESTEP_M = 0.5  # metres, closer to the goal than this people step without turning
SIDESTEP_SPEED_M_S = 0.5  # m/s, top speed of a side step
MIN_HEADING_FACTOR = 0.15  # share of the speed kept while facing away from the goal
BRAKE_SHARE = 0.8  # share of max_accel used to brake on the goal
WALK_TURN_MIN_SPEED_M_S = 0.1  # m/s, slower than this the body does not turn to the velocity
TURN_GAIN_PER_S = 6.0  # 1/s, body yaw follows its target with this gain (rate-limited)
HEAD_GAIN_PER_S = 8.0  # 1/s, head yaw follows its target with this gain (rate-limited)
AVOID_RANGE_M = 1.5  # metres, walkers react to agents closer than this
AVOID_GAIN_M_S = 0.9  # m/s, repulsion at contact
AVOID_DECAY_M = 0.3  # metres, decay length of the repulsion with the gap
AVOID_TANGENT = 0.6  # share of the repulsion turned into passing on the right
AVOID_FRONT_COS = -0.2  # agents further behind than this cosine are ignored
CONTACT_GAP_M = 0.03  # metres, closer than this (beyond radii and margin) agents are in touch
STANDING_WEIGHT = 0.25  # a standing agent yields this much relative to a walker (1.0)
PROJECTION_ITERATIONS = 12  # passes of the pairwise push-apart per step
SWAY_FADE_SPEED_M_S = 0.3  # m/s, sway is gone at this walking speed
SWAY_POS_M = 0.01  # metres, idle sway amplitude of the position (each axis)
SWAY_YAW_RAD = 0.03  # radians, idle sway amplitude of the body yaw
SWAY_FREQ_1_HZ = 0.17  # Hz, the slower of the two sway sines (phases differ per person)
SWAY_FREQ_2_HZ = 0.41  # Hz, the faster one
PARK_Z_M = -10.0  # metres, absent agents are parked this far below the floor


@dataclass(frozen=True)
class MotionLimits:
    """Bounds on how fast an agent moves.

    Attributes:
        max_speed: m/s.
        max_accel: m/s^2.
        max_turn_rate: body yaw rate, rad/s.
        head_limit: |head yaw - body yaw| never exceeds this, radians.
        head_rate: head yaw rate (relative to the body), rad/s.
        tilt_limit: |head tilt| never exceeds this, radians (robot only).
        tilt_rate: head tilt rate, rad/s (robot only).
    """

    max_speed: float
    max_accel: float
    max_turn_rate: float
    head_limit: float
    head_rate: float
    tilt_limit: float = 0.0
    tilt_rate: float = 0.0

    def __post_init__(self) -> None:
        for name in ("max_speed", "max_accel", "max_turn_rate", "head_rate"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"MotionLimits.{name} must be positive and finite, got {value}")
            object.__setattr__(self, name, value)
        for name in ("head_limit", "tilt_limit", "tilt_rate"):
            value = non_negative(f"MotionLimits.{name}", float(getattr(self, name)))
            object.__setattr__(self, name, value)
        if self.head_limit > math.pi:
            raise ValueError(f"MotionLimits.head_limit must be <= pi, got {self.head_limit}")


PERSON_LIMITS = MotionLimits(
    max_speed=1.5, max_accel=1.2, max_turn_rate=3.0, head_limit=math.radians(70.0), head_rate=4.0
)
ROBOT_LIMITS = MotionLimits(
    max_speed=0.8,
    max_accel=0.8,
    max_turn_rate=1.5,
    head_limit=math.radians(100.0),
    head_rate=2.0,
    tilt_limit=math.radians(30.0),
    tilt_rate=1.0,
)


@numba.njit(cache=True, inline="always")
def _wrap(angle: float) -> float:
    if -math.pi <= angle < math.pi:
        return angle
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


@numba.njit(cache=True, inline="always")
def _norm(x: float, y: float) -> float:
    return math.sqrt(x * x + y * y)


@numba.njit(cache=True, inline="always")
def _clip(value: float, low: float, high: float) -> float:
    return min(max(value, low), high)


@numba.njit(cache=True, inline="always")
def _approach(value: float, target: float, gain: float, rate: float, dt: float) -> float:
    """One rate-limited proportional step of ``value`` toward ``target`` (no overshoot)."""
    error = target - value
    step = _clip(gain * error, -rate, rate) * dt
    if abs(step) > abs(error):
        step = error
    return value + step


@numba.njit(cache=True)
def _insertion_sort(order, keys):  # pragma: no cover - compiled
    """Sorts ``order`` (indices) by ``keys`` in place; linear when nearly sorted already."""
    for a in range(1, order.shape[0]):
        item = order[a]
        key = keys[item]
        b = a - 1
        while b >= 0 and keys[order[b]] > key:
            order[b + 1] = order[b]
            b -= 1
        order[b + 1] = item


@numba.njit(cache=True)
def _window(order, keys, at, half):  # pragma: no cover - compiled
    """Ranks [lo, hi) of the entries of ``order`` whose key is within ``half`` of rank ``at``'s."""
    centre = keys[order[at]]
    lo = at
    while lo > 0 and centre - keys[order[lo - 1]] < half:
        lo -= 1
    hi = at + 1
    while hi < order.shape[0] and keys[order[hi]] - centre < half:
        hi += 1
    return lo, hi


@numba.njit(cache=True)
def _keep_off(state, params, i, vx, vy, margin, order, xs, rank, widest):  # pragma: no cover
    """Agent ``i``'s velocity without its components toward the agents it touches."""
    if vx == 0.0 and vy == 0.0:
        return vx, vy
    x, y = state[i, S_X], state[i, S_Y]
    touch = params[i, P_RADIUS] + widest + margin + CONTACT_GAP_M
    lo, hi = _window(order, xs, rank[i], touch)
    for b in range(lo, hi):
        j = order[b]
        if j == i or state[j, S_PRESENT] < 0.5:
            continue
        rx, ry = state[j, S_X] - x, state[j, S_Y] - y
        reach = params[i, P_RADIUS] + params[j, P_RADIUS] + margin + CONTACT_GAP_M
        d2 = rx * rx + ry * ry
        if d2 >= reach * reach or d2 < 1e-18:
            continue
        d = math.sqrt(d2)
        approach = (vx * rx + vy * ry) / d
        if approach > 0.0:
            vx -= approach * rx / d
            vy -= approach * ry / d
    return vx, vy


@numba.njit(cache=True)
def _is_free(state, params, i, x, y, margin):  # pragma: no cover - compiled
    """Whether agent ``i`` could stand at (x, y) without overlapping a present agent."""
    for j in range(state.shape[0]):
        if j == i or state[j, S_PRESENT] < 0.5:
            continue
        need = params[i, P_RADIUS] + params[j, P_RADIUS] + margin
        dx, dy = state[j, S_X] - x, state[j, S_Y] - y
        if dx * dx + dy * dy < need * need:
            return False
    return True


@numba.njit(cache=True)
def _target_yaw(state, intent, i, mode, yaw_col, x_col, y_col, agent_col, default):
    """The yaw toward a face/gaze target of ``mode``, or ``default`` when there is none."""
    x, y = state[i, S_X], state[i, S_Y]
    if mode == FACE_YAW and yaw_col >= 0:
        return intent[i, yaw_col]
    if mode == FACE_POINT:
        dx, dy = intent[i, x_col] - x, intent[i, y_col] - y
        if dx * dx + dy * dy > 1e-12:
            return math.atan2(dy, dx)
    elif mode == FACE_AGENT:
        j = int(intent[i, agent_col])
        if j != i and state[j, S_PRESENT] > 0.5:
            dx, dy = state[j, S_X] - x, state[j, S_Y] - y
            if dx * dx + dy * dy > 1e-12:
                return math.atan2(dy, dx)
    return default


@numba.njit(cache=True)
def _gaze_yaw(state, intent, i):
    """(has_gaze, yaw toward the gaze target)."""
    mode = int(intent[i, I_GAZE_MODE])
    if mode == GAZE_NONE:
        return False, 0.0
    # Gaze modes map onto the face modes: point -> FACE_POINT, agent -> FACE_AGENT.
    face_mode = FACE_POINT if mode == GAZE_POINT else FACE_AGENT
    yaw = _target_yaw(state, intent, i, face_mode, -1, I_GAZE_X, I_GAZE_Y, I_GAZE_AGENT, np.nan)
    if np.isnan(yaw):
        return False, 0.0
    return True, yaw


@numba.njit(cache=True)
def write_pose(state, params, time, row, layout, records):  # pragma: no cover - compiled
    """Writes every agent's mocap pose and joint angles at ``time`` into row ``row``.

    Present agents get their position and yaw plus idle sway; absent ones are parked.

    Args:
        state: (n, N_STATE) motion state.
        params: (n, N_PARAM) per-agent parameters.
        time: seconds (the phase of the idle sway).
        row: the row of ``records`` to write.
        layout: ``(mocap_of, head_adr, tilt_adr)``: (n,) mocap index of each agent's root body
            and (n,) qpos address of its head yaw / tilt joint, or -1.
        records: ``(mpos, mquat, qpos, present)``: (rows, nmocap, 3) mocap positions,
            (rows, nmocap, 4) mocap quaternions (w, x, y, z), (rows, nq) joint positions (only
            the head joints are written) and (rows, n) presence.
    """
    mocap_of, head_adr, tilt_adr = layout
    rec_mpos, rec_mquat, rec_qpos, rec_present = records
    w1 = 2.0 * math.pi * SWAY_FREQ_1_HZ * time
    w2 = 2.0 * math.pi * SWAY_FREQ_2_HZ * time
    s1, c1, s2, c2 = math.sin(w1), math.cos(w1), math.sin(w2), math.cos(w2)
    for i in range(state.shape[0]):
        m = mocap_of[i]
        if state[i, S_PRESENT] > 0.5:
            speed = _norm(state[i, S_VX], state[i, S_VY])
            fade = _clip(1.0 - speed / SWAY_FADE_SPEED_M_S, 0.0, 1.0)
            sx, sy, syaw = 0.0, 0.0, 0.0
            if fade > 0.0:
                p = params[i]
                # sin(w + phase) = sin(w) cos(phase) + cos(w) sin(phase)
                amp = fade * p[P_SWAY_POS]
                sx = amp * (
                    0.6 * (s1 * p[P_SWAY_X1C] + c1 * p[P_SWAY_X1S])
                    + 0.4 * (s2 * p[P_SWAY_X2C] + c2 * p[P_SWAY_X2S])
                )
                sy = amp * (
                    0.6 * (s1 * p[P_SWAY_Y1C] + c1 * p[P_SWAY_Y1S])
                    + 0.4 * (s2 * p[P_SWAY_Y2C] + c2 * p[P_SWAY_Y2S])
                )
                syaw = (
                    fade
                    * p[P_SWAY_YAW]
                    * (
                        0.6 * (s1 * p[P_SWAY_W1C] + c1 * p[P_SWAY_W1S])
                        + 0.4 * (s2 * p[P_SWAY_W2C] + c2 * p[P_SWAY_W2S])
                    )
                )
            half = 0.5 * (state[i, S_YAW] + syaw)
            rec_mpos[row, m, 0] = state[i, S_X] + sx
            rec_mpos[row, m, 1] = state[i, S_Y] + sy
            rec_mpos[row, m, 2] = 0.0
            rec_mquat[row, m, 0] = math.cos(half)
            rec_mquat[row, m, 1] = 0.0
            rec_mquat[row, m, 2] = 0.0
            rec_mquat[row, m, 3] = math.sin(half)
            rec_present[row, i] = True
        else:
            rec_mpos[row, m, 0] = params[i, P_PARK_X]
            rec_mpos[row, m, 1] = params[i, P_PARK_Y]
            rec_mpos[row, m, 2] = PARK_Z_M
            rec_mquat[row, m, 0] = 1.0
            rec_mquat[row, m, 1] = 0.0
            rec_mquat[row, m, 2] = 0.0
            rec_mquat[row, m, 3] = 0.0
            rec_present[row, i] = False
        if head_adr[i] >= 0:
            rec_qpos[row, head_adr[i]] = state[i, S_HEAD]
        if tilt_adr[i] >= 0:
            rec_qpos[row, tilt_adr[i]] = state[i, S_TILT]


@numba.njit(cache=True)
def workspace(state, params):  # pragma: no cover - compiled
    """Scratch for `step`, kept across the steps of a call (agents sorted by x).

    Returns:
        ``(new_x, new_y, weight, revert, xs, order, moved_order, rank, widest)``: (n,) arrays
        and the widest body radius, metres; passed to `step` as one tuple.
    """
    n = state.shape[0]
    new_x = np.empty(n)
    new_y = np.empty(n)
    weight = np.empty(n)
    revert = np.zeros(n, dtype=np.bool_)
    xs = np.empty(n)
    order = np.argsort(state[:, S_X])
    moved_order = order.copy()
    rank = np.empty(n, dtype=np.int64)
    widest = 0.0
    for i in range(n):
        widest = max(widest, params[i, P_RADIUS])
    return new_x, new_y, weight, revert, xs, order, moved_order, rank, widest


@numba.njit(cache=True)
def step(state, intent, params, dt, margin, work):  # noqa: C901 - one step, every primitive
    """Moves every agent by one control step of ``dt`` seconds, in place (see `advance`).

    ``work`` is the `workspace` of the call. Pair loops visit neighbours along x only:
    ``order`` keeps the agents sorted by x (nearly sorted from one step to the next, so
    re-sorting is linear).
    """
    new_x, new_y, weight, revert, xs, order, moved_order, rank, widest = work
    n = state.shape[0]
    # Leaving and entering.
    for i in range(n):
        here = state[i, S_PRESENT] > 0.5
        want = intent[i, I_PRESENT] > 0.5
        if here and not want:
            state[i, S_PRESENT] = 0.0
            state[i, S_VX] = 0.0
            state[i, S_VY] = 0.0
        elif want and not here:
            x, y = state[i, S_X], state[i, S_Y]
            if intent[i, I_HAS_APPEAR] > 0.5:
                x, y = intent[i, I_APPEAR_X], intent[i, I_APPEAR_Y]
            if _is_free(state, params, i, x, y, margin):
                state[i, S_X] = x
                state[i, S_Y] = y
                state[i, S_VX] = 0.0
                state[i, S_VY] = 0.0
                state[i, S_PRESENT] = 1.0

    for i in range(n):
        xs[i] = state[i, S_X]
    _insertion_sort(order, xs)
    for a in range(n):
        rank[order[a]] = a

    # Desired motion, per agent.
    for i in range(n):
        x, y, yaw = state[i, S_X], state[i, S_Y], state[i, S_YAW]
        new_x[i], new_y[i] = x, y
        weight[i] = STANDING_WEIGHT
        if state[i, S_PRESENT] < 0.5:
            continue
        max_speed = params[i, P_MAX_SPEED]
        max_accel = params[i, P_MAX_ACCEL]
        head_limit = params[i, P_HEAD_LIMIT]

        if intent[i, I_CMD] > 0.5:
            # Velocity commands (the robot): unicycle base, head pan and tilt rates.
            forward = state[i, S_VX] * math.cos(yaw) + state[i, S_VY] * math.sin(yaw)
            goal_speed = _clip(intent[i, I_CMD_SPEED], -max_speed, max_speed)
            forward += _clip(goal_speed - forward, -max_accel * dt, max_accel * dt)
            turn = _clip(intent[i, I_CMD_TURN], -params[i, P_MAX_TURN], params[i, P_MAX_TURN])
            yaw = _wrap(yaw + turn * dt)
            state[i, S_YAW] = yaw
            state[i, S_VX] = forward * math.cos(yaw)
            state[i, S_VY] = forward * math.sin(yaw)
            pan = _clip(intent[i, I_CMD_PAN], -params[i, P_HEAD_RATE], params[i, P_HEAD_RATE])
            state[i, S_HEAD] = _clip(state[i, S_HEAD] + pan * dt, -head_limit, head_limit)
            tilt_limit = params[i, P_TILT_LIMIT]
            tilt = _clip(intent[i, I_CMD_TILT], -params[i, P_TILT_RATE], params[i, P_TILT_RATE])
            state[i, S_TILT] = _clip(state[i, S_TILT] + tilt * dt, -tilt_limit, tilt_limit)
            vx, vy = _keep_off(
                state, params, i, state[i, S_VX], state[i, S_VY], margin, order, xs, rank, widest
            )
            state[i, S_VX], state[i, S_VY] = vx, vy
            new_x[i] = x + vx * dt
            new_y[i] = y + vy * dt
            weight[i] = 1.0
            continue

        vdx, vdy = 0.0, 0.0
        ux, uy = 0.0, 0.0
        dist_goal = 0.0
        moving = False
        cap = 0.0
        if intent[i, I_HAS_GOAL] > 0.5:
            ex, ey = intent[i, I_GOAL_X] - x, intent[i, I_GOAL_Y] - y
            dist_goal = _norm(ex, ey)
            if dist_goal > ARRIVE_TOLERANCE_M:
                ux, uy = ex / dist_goal, ey / dist_goal
                cap = min(intent[i, I_SPEED], max_speed)
                speed = cap
                if dist_goal > SIDESTEP_M:
                    err = _wrap(math.atan2(uy, ux) - yaw)
                    speed *= max(0.5 * (1.0 + math.cos(err)), MIN_HEADING_FACTOR)
                else:
                    speed = min(speed, SIDESTEP_SPEED_M_S)
                brake = math.sqrt(2.0 * BRAKE_SHARE * max_accel * (dist_goal - ARRIVE_TOLERANCE_M))
                speed = min(speed, brake)
                vdx, vdy = ux * speed, uy * speed
                moving = True
        if moving:
            weight[i] = 1.0
        if moving and dist_goal > SIDESTEP_M:
            # Walkers avoid others; the last side step into place does not (personal space
            # and contact still hold), or people could not close up a tight circle.
            lo, hi = _window(order, xs, rank[i], AVOID_RANGE_M)
            for b in range(lo, hi):
                j = order[b]
                if j == i or state[j, S_PRESENT] < 0.5:
                    continue
                rx, ry = x - state[j, S_X], y - state[j, S_Y]
                d2 = rx * rx + ry * ry
                if d2 >= AVOID_RANGE_M * AVOID_RANGE_M or d2 < 1e-18:
                    continue
                d = math.sqrt(d2)
                nx, ny = rx / d, ry / d
                ahead = -(nx * ux + ny * uy)
                if ahead < AVOID_FRONT_COS:
                    continue
                gap = max(d - params[i, P_RADIUS] - params[j, P_RADIUS] - margin, 0.0)
                push = AVOID_GAIN_M_S * math.exp(-gap / AVOID_DECAY_M)
                side = push * AVOID_TANGENT * max(ahead, 0.0)
                vdx += push * nx + side * uy
                vdy += push * ny - side * ux
            norm = _norm(vdx, vdy)
            if norm > cap:
                vdx, vdy = vdx * cap / norm, vdy * cap / norm

        # Bounded acceleration.
        dvx, dvy = vdx - state[i, S_VX], vdy - state[i, S_VY]
        dv = _norm(dvx, dvy)
        if dv > max_accel * dt:
            dvx, dvy = dvx * max_accel * dt / dv, dvy * max_accel * dt / dv
        vx, vy = _keep_off(
            state,
            params,
            i,
            state[i, S_VX] + dvx,
            state[i, S_VY] + dvy,
            margin,
            order,
            xs,
            rank,
            widest,
        )
        state[i, S_VX], state[i, S_VY] = vx, vy
        new_x[i] = x + vx * dt
        new_y[i] = y + vy * dt

        # Body yaw: the walking direction, else the facing target, turned to follow the gaze.
        has_gaze, gaze = _gaze_yaw(state, intent, i)
        walking = moving and dist_goal > SIDESTEP_M and _norm(vx, vy) > WALK_TURN_MIN_SPEED_M_S
        if walking:
            target = math.atan2(vy, vx)
        else:
            target = _target_yaw(
                state,
                intent,
                i,
                int(intent[i, I_FACE_MODE]),
                I_FACE_YAW,
                I_FACE_X,
                I_FACE_Y,
                I_FACE_AGENT,
                yaw,
            )
            if has_gaze:
                rel = _wrap(gaze - target)
                if rel > head_limit:
                    target = gaze - head_limit
                elif rel < -head_limit:
                    target = gaze + head_limit
        error = _wrap(target - yaw)
        yaw = _wrap(yaw + (_approach(0.0, error, TURN_GAIN_PER_S, params[i, P_MAX_TURN], dt)))
        state[i, S_YAW] = yaw

        # Head: toward the gaze target, within the limit of the body.
        goal_head = 0.0
        if has_gaze:
            goal_head = _clip(_wrap(gaze - yaw), -head_limit, head_limit)
        head = _approach(state[i, S_HEAD], goal_head, HEAD_GAIN_PER_S, params[i, P_HEAD_RATE], dt)
        state[i, S_HEAD] = _clip(head, -head_limit, head_limit)

    # Personal space: push overlapping discs apart, keep inside the walls. A pass that finds
    # no overlap moves nobody, so its verdict is exact.
    for i in range(n):
        if state[i, S_PRESENT] > 0.5:
            new_x[i] = _clip(new_x[i], params[i, P_X_MIN], params[i, P_X_MAX])
            new_y[i] = _clip(new_y[i], params[i, P_Y_MIN], params[i, P_Y_MAX])
    farthest = 2.0 * widest + margin
    overlap_found = False
    for _ in range(PROJECTION_ITERATIONS):
        overlap_found = False
        _insertion_sort(moved_order, new_x)
        for a in range(n):
            i = moved_order[a]
            if state[i, S_PRESENT] < 0.5:
                continue
            for b in range(a + 1, n):
                j = moved_order[b]
                if new_x[j] - new_x[i] >= farthest:
                    break
                if state[j, S_PRESENT] < 0.5:
                    continue
                dx, dy = new_x[j] - new_x[i], new_y[j] - new_y[i]
                d2 = dx * dx + dy * dy
                need = params[i, P_RADIUS] + params[j, P_RADIUS] + margin
                if d2 >= need * need:
                    continue
                d = math.sqrt(d2)
                overlap_found = True
                if d < 1e-9:
                    # Coincident: separate along the line between the old positions.
                    dx, dy = state[j, S_X] - state[i, S_X], state[j, S_Y] - state[i, S_Y]
                    d = _norm(dx, dy)
                    if d < 1e-9:
                        dx, dy, d = 1.0, 0.0, 1.0
                    dx, dy = dx / d, dy / d
                    d = 0.0
                else:
                    dx, dy = dx / d, dy / d
                push = need - d + 1e-6
                share = weight[i] / (weight[i] + weight[j])
                new_x[i] -= dx * push * share
                new_y[i] -= dy * push * share
                new_x[j] += dx * push * (1.0 - share)
                new_y[j] += dy * push * (1.0 - share)
        for i in range(n):
            if state[i, S_PRESENT] > 0.5:
                new_x[i] = _clip(new_x[i], params[i, P_X_MIN], params[i, P_X_MAX])
                new_y[i] = _clip(new_y[i], params[i, P_Y_MIN], params[i, P_Y_MAX])
        if not overlap_found:
            break

    # Never faster than the speed limit, even when pushed.
    capped = False
    for i in range(n):
        if state[i, S_PRESENT] < 0.5:
            continue
        dx, dy = new_x[i] - state[i, S_X], new_y[i] - state[i, S_Y]
        d = _norm(dx, dy)
        reach = params[i, P_MAX_SPEED] * dt
        if d > reach:
            new_x[i] = state[i, S_X] + dx * reach / d
            new_y[i] = state[i, S_Y] + dy * reach / d
            capped = True

    # Whoever still overlaps goes back to where they were (where nobody overlapped).
    for i in range(n):
        revert[i] = False
    for _ in range(n + 1 if (overlap_found or capped) else 0):
        changed = False
        for i in range(n):
            if state[i, S_PRESENT] < 0.5:
                continue
            for j in range(i + 1, n):
                if state[j, S_PRESENT] < 0.5:
                    continue
                need = params[i, P_RADIUS] + params[j, P_RADIUS] + margin
                dx, dy = new_x[j] - new_x[i], new_y[j] - new_y[i]
                if dx * dx + dy * dy < need * need:
                    for k in (i, j):
                        if not revert[k]:
                            revert[k] = True
                            new_x[k], new_y[k] = state[k, S_X], state[k, S_Y]
                            changed = True
        if not changed:
            break

    for i in range(n):
        if state[i, S_PRESENT] < 0.5:
            continue
        state[i, S_VX] = (new_x[i] - state[i, S_X]) / dt
        state[i, S_VY] = (new_y[i] - state[i, S_Y]) / dt
        state[i, S_X] = new_x[i]
        state[i, S_Y] = new_y[i]


@numba.njit(cache=True)
def advance(state, intent, params, step0, dt, margin, record_at, layout, records):
    """Moves every agent by ``len(record_at)`` control steps of ``dt`` seconds, in place.

    Args:
        state: (n, N_STATE) motion state, updated in place.
        intent: (n, N_INTENT) what each agent wants (held over the steps).
        params: (n, N_PARAM) per-agent limits, bounds and sway parameters.
        step0: index of the first step (the time before it is ``step0 * dt``).
        dt: control step, seconds.
        margin: metres kept between agents beyond the sum of their body radii.
        record_at: (n_steps,) int: after step s, write the pose into row ``record_at[s]`` of the
            records, or nothing when it is negative.
        layout: ``(mocap_of, head_adr, tilt_adr)`` as for `write_pose`.
        records: ``(mpos, mquat, qpos, present)`` as for `write_pose`, a row per recorded step.
    """
    work = workspace(state, params)
    for s in range(record_at.shape[0]):
        step(state, intent, params, dt, margin, work)
        row = record_at[s]
        if row >= 0:
            write_pose(state, params, (step0 + s + 1) * dt, row, layout, records)


def sway_parameters(rng: np.random.Generator, *, standing: bool) -> np.ndarray:
    """(14,) idle sway parameters of one agent: two amplitudes, then (cos, sin) of six phases.

    Args:
        rng: the agent's own generator.
        standing: False for agents that do not sway (the robot): amplitudes are zero.

    Returns:
        ``[pos_amp_m, yaw_amp_rad, cos/sin of the phases of x1, x2, y1, y2, yaw1, yaw2]``.
    """
    phases = rng.uniform(0.0, 2.0 * math.pi, size=6)
    amps = [SWAY_POS_M, SWAY_YAW_RAD] if standing else [0.0, 0.0]
    pairs = np.stack([np.cos(phases), np.sin(phases)], axis=1).ravel()
    return np.concatenate([amps, pairs])
