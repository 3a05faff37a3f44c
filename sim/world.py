"""The world: people and the Directions Robot moved kinematically in MuJoCo, read back as Frames.

What the script wants and what the world does meet in two small types (defined in
`scenarios.script`, the vocabulary of the scenario layer, and re-exported here):

* `Intent` (frozen, per agent): where to walk (``goal``, at ``speed``), which way to face once
  there or while standing (``face_yaw``, ``face_point`` or ``face_agent``), where to look
  (``gaze_point`` or ``gaze_agent``), whether to be in the room (``present``, entering at
  ``appear_at``). An agent keeps its last intent until it gets a new one; the default `Intent()`
  is "stand where you are, keep your facing, look ahead".
* `Script` (protocol): ``intents(t) -> Mapping[agent_id, Intent]`` (agents left out keep their
  last intent) and ``groups(t) -> groups or None`` (the ground-truth F-formations the script
  declares; ``None`` means "not annotated"). Both are pure functions of time, sampled every
  ``1 / decision_rate`` seconds (10 Hz by default) and held in between.

The world applies the motion primitives of `sim.motion` to move every agent toward its intent
at ``1 / dt`` Hz (100 Hz by default) within speed, acceleration and turn-rate limits, never
letting two agents interpenetrate, writes the resulting poses to MuJoCo mocap bodies and joints,
runs MuJoCo's kinematics, and reads body and head poses back from ``xpos`` / ``xquat`` of each
agent's ``torso`` and ``head`` bodies. It hands them out as `reform.Frame` objects (`World.frame`,
`World.run`) or, for speed, as blocks of arrays (`reform.FrameBlock`, from `World.rollout`).

The robot follows intents like a person, or velocity commands (`World.command_robot` with a
`RobotCommand`: forward speed, turn rate, head pan and tilt rates), as a controller would drive
it step by step (`World.step`).

Frames hold the agents present at that instant, people in scene order, then the robot
(kind ``"robot"``). Their groups are the script's, restricted to the people present.

Determinism: the motion is deterministic; the seed only draws each agent's idle sway (one child
generator per agent, so adding an agent does not change the others). The same spec, script and
seed give identical frames.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
from mujoco import batch as mj_batch

from reform.frame import ROBOT, Frame, Group, check_groups, wrap_angle
from reform.frame_block import FrameBlock
from reform.perturb import restrict_groups
from scenarios.script import WALK_SPEED_M_S, Intent, Point, Script
from scenarios.truth import GroundTruth
from sim import _native, motion
from sim.motion import (
    PERSON_LIMITS,
    ROBOT_LIMITS,
    MotionLimits,
)
from sim.scene import (
    CLEARANCE_MARGIN_M,
    ROBOT_PREFIX,
    PersonSpec,
    RobotSpec,
    SceneSpec,
    build_scene,
)

DEFAULT_DT_S = 0.01  # seconds, control and kinematics step (100 Hz)
DEFAULT_DECISION_RATE_HZ = 10.0  # Hz, how often the script is asked for intents and groups
DEFAULT_BLOCK_ROWS = 500  # output rows per block of World.rollout
MAX_DT_S = 0.1  # seconds, the largest accepted control step
PARK_GAP_M = 0.7  # metres between parked (absent) agents outside the room
PARK_DISTANCE_M = 2.0  # metres from the east wall to the first parking spot
_RATE_TOLERANCE = 1e-6  # relative tolerance when checking that rates divide each other
_EXAMPLE_RATES_HZ = (1.0, 2.0, 4.0, 5.0, 10.0)  # Hz, rates a refusal suggests


@dataclass(frozen=True)
class RobotCommand:
    """Velocity commands for the robot (a unicycle base and a pan-tilt head).

    Values beyond the robot's limits are clipped to them.

    Attributes:
        speed: forward speed of the base, m/s (negative backs up).
        turn_rate: yaw rate of the base, rad/s (positive turns left).
        pan_rate: head pan rate, rad/s (positive to the left).
        tilt_rate: head tilt rate, rad/s (positive looks down).
    """

    speed: float = 0.0
    turn_rate: float = 0.0
    pan_rate: float = 0.0
    tilt_rate: float = 0.0

    def __post_init__(self) -> None:
        for name in ("speed", "turn_rate", "pan_rate", "tilt_rate"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise ValueError(f"RobotCommand.{name} must be finite, got {getattr(self, name)!r}")
            object.__setattr__(self, name, value)


def yaw_from_quat(quat: np.ndarray) -> np.ndarray:
    """Heading of a body's x axis on the ground plane, from MuJoCo quaternions (w, x, y, z).

    Args:
        quat: (..., 4) quaternions.

    Returns:
        (...) yaws, radians in [-pi, pi].
    """
    w, x, y, z = quat[..., 0], quat[..., 1], quat[..., 2], quat[..., 3]
    return np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _steps_per(period: float, dt: float, *, name: str, unit_hint: str) -> int:
    """How many steps of ``dt`` make ``period``, which must be a whole number of them."""
    steps = period / dt
    whole = round(steps)
    if whole < 1 or abs(steps - whole) > _RATE_TOLERANCE * max(1.0, steps):
        raise ValueError(
            f"{name} must be a whole number of control steps of dt = {dt:g} s {unit_hint}, "
            f"got {period:g} s ({steps:g} steps)"
        )
    return int(whole)


def steps_per_frame(rate: float, dt: float = DEFAULT_DT_S) -> int:
    """Control steps of ``dt`` between two output frames at ``rate`` Hz.

    Raises:
        ValueError: a rate that is not positive, or whose period ``1 / rate`` is not a whole
            number of steps (the world records frames on its steps only).
    """
    rate = float(rate)
    if not (math.isfinite(rate) and rate > 0.0):
        raise ValueError(f"rate must be positive (Hz), got {rate}")
    return _steps_per(1.0 / rate, dt, name="1 / rate", unit_hint="(choose a rate dividing 1/dt)")


def whole_step_rates(dt: float = DEFAULT_DT_S) -> str:
    """What `steps_per_frame` accepts, in words, for a message's "expected"."""
    examples = []
    for rate in _EXAMPLE_RATES_HZ:
        try:
            steps_per_frame(rate, dt)
        except ValueError:
            continue
        examples.append(f"{rate:g}")
    shown = f" (e.g. {', '.join(examples)})" if examples else ""
    return f"a rate whose period is a whole number of {dt:g} s control steps{shown}"


class World:
    """People and the robot of a `SceneSpec`, moved kinematically in MuJoCo.

    Args:
        spec: the scene.
        seed: seeds the idle sway (int, SeedSequence or Generator).
        script: scripted behaviour, or ``None`` to drive the agents with `set_intents`.
        dt: control and kinematics step, seconds (100 Hz by default).
        decision_rate: how often the script is sampled, Hz; ``1 / decision_rate`` must be a
            whole number of steps.
        sequence: name written into every Frame.
        person_limits: motion limits of the people.
        robot_limits: motion limits of the robot.
        model: a model built by ``build_scene(spec)`` to reuse; ``None`` builds one.
        truth: the ground-truth rule that settles the groups from the poses (a
            `scenarios.GroundTruth` over this world's ids, in order), applied here once to every
            output time; ``None``: the groups are the ones the script declares (or
            `set_groups`'s).

    Raises:
        ValueError: on an invalid step or rate, or if the script's first intents or groups are
            impossible (unknown agents, goals outside the walls), before anything is simulated.
    """

    def __init__(
        self,
        spec: SceneSpec,
        *,
        seed: int | np.random.SeedSequence | np.random.Generator,
        script: Script | None = None,
        dt: float = DEFAULT_DT_S,
        decision_rate: float = DEFAULT_DECISION_RATE_HZ,
        sequence: str = "",
        person_limits: MotionLimits = PERSON_LIMITS,
        robot_limits: MotionLimits = ROBOT_LIMITS,
        model: mujoco.MjModel | None = None,
        truth: GroundTruth | None = None,
    ) -> None:
        if not isinstance(spec, SceneSpec):
            raise ValueError(f"spec must be a SceneSpec, got {type(spec).__name__}")
        dt = float(dt)
        if not (math.isfinite(dt) and 0.0 < dt <= MAX_DT_S):
            raise ValueError(f"dt must be within (0, {MAX_DT_S}] seconds, got {dt}")
        decision_rate = float(decision_rate)
        if not (math.isfinite(decision_rate) and decision_rate > 0.0):
            raise ValueError(f"decision_rate must be positive (Hz), got {decision_rate}")
        if script is not None and not isinstance(script, Script):
            raise ValueError(
                f"script must have intents(t) and groups(t) (the Script protocol), got "
                f"{type(script).__name__}"
            )
        self._spec = spec
        self._script = script
        self._dt = dt
        self._steps_per_decision = _steps_per(
            1.0 / decision_rate,
            dt,
            name="1 / decision_rate",
            unit_hint="(choose a rate dividing 1/dt)",
        )
        self._sequence = str(sequence)
        self._model = build_scene(spec) if model is None else model
        self._data = mujoco.MjData(self._model)
        # Rollouts compute body poses on the kinematic twin: same bodies and joints, few geoms.
        self._twin = build_scene(spec, geometry=False)
        self._twin_data = mujoco.MjData(self._twin)
        self._twin_views = _native.data_views(self._twin_data)
        self._batch: mj_batch.Batch | None = None

        agents = spec.agents
        n = len(agents)
        self._ids = np.array([a.id for a in agents], dtype=np.int64)
        self._ids.flags.writeable = False
        self._kinds = tuple(a.kind for a in agents)
        self._index = {int(a.id): i for i, a in enumerate(agents)}
        if truth is not None and tuple(truth.ids) != tuple(self._ids.tolist()):
            raise ValueError(
                f"truth must settle the groups over this world's agents {self._ids.tolist()}, "
                f"in order; it holds {list(truth.ids)}"
            )
        self._truth = truth
        self._truth_now: tuple[int, tuple[Group, ...]] | None = None  # (step, its groups)
        self._robot = n - 1 if spec.robot is not None else -1
        self._bind_model(agents)
        for size in ("nbody", "nmocap", "nq"):
            if getattr(self._twin, size) != getattr(self._model, size):
                raise ValueError(
                    f"model does not match the spec: {size} is {getattr(self._model, size)}, the "
                    f"spec builds {getattr(self._twin, size)}"
                )

        # Per-agent parameters.
        rngs = np.random.default_rng(seed).spawn(n)
        params = np.zeros((n, motion.N_PARAM))
        x_max, y_min = spec.bounds[1], spec.bounds[2]
        for i, agent in enumerate(agents):
            limits = robot_limits if isinstance(agent, RobotSpec) else person_limits
            params[i, motion.P_RADIUS] = agent.radius
            params[i, motion.P_MAX_SPEED] = limits.max_speed
            params[i, motion.P_MAX_ACCEL] = limits.max_accel
            params[i, motion.P_MAX_TURN] = limits.max_turn_rate
            params[i, motion.P_HEAD_LIMIT] = limits.head_limit
            params[i, motion.P_HEAD_RATE] = limits.head_rate
            params[i, motion.P_TILT_LIMIT] = limits.tilt_limit
            params[i, motion.P_TILT_RATE] = limits.tilt_rate
            params[i, motion.P_X_MIN : motion.P_Y_MAX + 1] = spec.inner_bounds(agent.radius)
            params[i, motion.P_PARK_X] = x_max + PARK_DISTANCE_M + PARK_GAP_M * i
            params[i, motion.P_PARK_Y] = y_min
            params[i, motion.P_SWAY_POS :] = motion.sway_parameters(
                rngs[i], standing=isinstance(agent, PersonSpec)
            )
        self._params = params
        self._bounds = [
            tuple(float(v) for v in row) for row in params[:, motion.P_X_MIN : motion.P_Y_MAX + 1]
        ]
        self._limits = (person_limits, robot_limits)

        # Motion state and intents.
        state = np.zeros((n, motion.N_STATE))
        intent = np.zeros((n, motion.N_INTENT))
        for i, agent in enumerate(agents):
            state[i, motion.S_X], state[i, motion.S_Y] = agent.position
            state[i, motion.S_YAW] = float(wrap_angle(agent.yaw))
            state[i, motion.S_PRESENT] = float(agent.present)
            if isinstance(agent, RobotSpec):
                _, robot_lim = self._limits
                for name, value, bound in (
                    ("head_pan", agent.head_pan, robot_lim.head_limit),
                    ("head_tilt", agent.head_tilt, robot_lim.tilt_limit),
                ):
                    if abs(value) > bound:
                        raise ValueError(
                            f"robot: {name} must be within [-{bound:.4f}, {bound:.4f}] rad, "
                            f"got {value}"
                        )
                state[i, motion.S_HEAD] = agent.head_pan
                state[i, motion.S_TILT] = agent.head_tilt
            intent[i, motion.I_SPEED] = WALK_SPEED_M_S
            intent[i, motion.I_PRESENT] = float(agent.present)
        self._state = state
        self._intent = intent
        self._last_intents: list[Intent | None] = [None] * n
        self._last_mapping: Mapping[int, Intent] | None = None

        self._step_index = 0
        self._intent_tick = -1
        self._groups_cache: dict[int, tuple[Group, ...] | None] = {}
        self._last_raw_groups: Any = None
        self._last_groups: tuple[Group, ...] | None = None
        self._manual_groups: tuple[Group, ...] | None = None
        self._present = state[:, motion.S_PRESENT] > 0.5
        self._buffers: dict[int, tuple[np.ndarray, ...]] = {}

        if script is not None:
            self._apply_script_tick(0)
            self._groups_at_step(0)
        self._write_initial_pose()

    # ----------------------------------------------------------------------------------------
    # Public surface

    @property
    def spec(self) -> SceneSpec:
        return self._spec

    @property
    def model(self) -> mujoco.MjModel:
        """The compiled MuJoCo model (do not change its sizes)."""
        return self._model

    @property
    def data(self) -> mujoco.MjData:
        """MuJoCo data at the world's current time (kinematics computed)."""
        return self._data

    @property
    def dt(self) -> float:
        """Control step, seconds."""
        return self._dt

    @property
    def time(self) -> float:
        """Seconds since the start."""
        return self._step_index * self._dt

    @property
    def step_count(self) -> int:
        """Control steps taken since the start."""
        return self._step_index

    @property
    def ids(self) -> np.ndarray:
        """(n,) agent ids: people in scene order, then the robot."""
        return self._ids

    @property
    def kinds(self) -> tuple[str, ...]:
        return self._kinds

    @property
    def radii(self) -> np.ndarray:
        """(n,) body radii, metres."""
        return self._params[:, motion.P_RADIUS].copy()

    @property
    def present(self) -> np.ndarray:
        """(n,) bool: who is in the room now."""
        return self._present.copy()

    @property
    def robot_id(self) -> int | None:
        return None if self._robot < 0 else int(self._ids[self._robot])

    @property
    def sensor_site(self) -> int:
        """Site id of the robot's head sensor (-1 without a robot)."""
        return self._sensor_site

    @property
    def head_camera(self) -> int:
        """Camera id of the robot's head camera (-1 without a robot)."""
        return self._head_camera

    def agent_index(self, agent_id: int) -> int:
        """Row of ``agent_id`` in the world's per-agent arrays."""
        try:
            return self._index[int(agent_id)]
        except (KeyError, TypeError, ValueError):
            raise KeyError(
                f"no agent with id {agent_id!r} in the scene (ids {self._ids.tolist()})"
            ) from None

    @property
    def root_bodies(self) -> np.ndarray:
        """(n,) id of each agent's root (mocap) body: every geom of an agent hangs below it."""
        return self._root_body.copy()

    @property
    def torso_bodies(self) -> np.ndarray:
        """(n,) id of each agent's torso body (body pose)."""
        return self._torso_body.copy()

    @property
    def head_bodies(self) -> np.ndarray:
        """(n,) id of each agent's head body (head pose)."""
        return self._head_body.copy()

    def set_intents(self, intents: Mapping[int, Intent]) -> None:
        """Gives agents new intents now (a script's next sample may replace them).

        Raises:
            ValueError: for unknown agents or impossible targets (outside the walls).
        """
        self._apply_intents(intents, self.time)

    def set_groups(self, groups: Sequence[Sequence[int]] | None) -> None:
        """Declares the ground-truth groups from now on (worlds without a script)."""
        if self._script is not None:
            raise ValueError("set_groups: this world's groups come from its script")
        if self._truth is not None:
            raise ValueError("set_groups: this world's groups come from its ground-truth rule")
        self._manual_groups = self._validate_groups(groups, self.time)

    def command_robot(self, command: RobotCommand | None) -> None:
        """Drives the robot by velocity commands from now on; ``None`` returns it to intents."""
        if self._robot < 0:
            raise ValueError("command_robot: the scene has no robot")
        row = self._intent[self._robot]
        if command is None:
            row[motion.I_CMD] = 0.0
            return
        if not isinstance(command, RobotCommand):
            raise ValueError(
                f"command must be a RobotCommand or None, got {type(command).__name__}"
            )
        row[motion.I_CMD] = 1.0
        row[motion.I_CMD_SPEED] = command.speed
        row[motion.I_CMD_TURN] = command.turn_rate
        row[motion.I_CMD_PAN] = command.pan_rate
        row[motion.I_CMD_TILT] = command.tilt_rate

    def step(self, n_steps: int = 1) -> None:
        """Advances the world by ``n_steps`` control steps; `data` then holds the new state."""
        if isinstance(n_steps, bool) or not isinstance(n_steps, (int, np.integer)) or n_steps < 1:
            raise ValueError(f"n_steps must be a positive int, got {n_steps!r}")
        record_at = np.full(int(n_steps), -1, dtype=np.int64)
        record_at[-1] = 0
        records = self._buffer(1)
        self._advance(record_at, records)
        mpos, mquat, qpos, present = records
        self._load_row(mpos[0], mquat[0], qpos[0], present[0])

    def frame(self) -> Frame:
        """The ground truth now: poses read from MuJoCo's kinematics, the groups settled (by
        the ``truth`` rule, else as declared), restricted to the agents present."""
        keep = np.flatnonzero(self._present)
        torso, head = self._torso_body[keep], self._head_body[keep]
        ids = self._ids[keep]
        groups = restrict_groups(self.groups(), set(ids.tolist()))
        return Frame(
            ids=ids,
            kinds=tuple(self._kinds[i] for i in keep),
            position=self._data.xpos[torso, :2],
            yaw=yaw_from_quat(self._data.xquat[torso]),
            head_position=self._data.xpos[head, :2],
            head_yaw=yaw_from_quat(self._data.xquat[head]),
            groups=groups,
            time=self.time,
            sequence=self._sequence,
        )

    def groups(self) -> tuple[Group, ...] | None:
        """The ground-truth groups now, as the ``truth`` rule settles them from the poses (each
        output time settled once, in time order), else as the script or `set_groups` declares
        them; ``None``: not annotated."""
        if self._truth is None:
            return self._groups_at_step(self._step_index)
        if self._truth_now is None or self._truth_now[0] != self._step_index:
            xy = self._data.xpos[self._torso_body, :2]
            yaw = yaw_from_quat(self._data.xquat[self._torso_body])
            (now,) = self._truth.update(
                np.array([self.time]), self._present[None], xy[None], yaw[None]
            )
            self._truth_now = (self._step_index, now)
        return self._truth_now[1]

    def run(self, duration: float, *, rate: float = DEFAULT_DECISION_RATE_HZ) -> Iterator[Frame]:
        """Advances by ``duration`` seconds, yielding a Frame every ``1 / rate`` seconds.

        The first frame is at ``time + 1 / rate``. While a frame is being handled, `data` holds
        its state (so a sensor can observe it). Frames are made one at a time, never all held.
        """
        every, count = self._output_plan(duration, rate)
        for _ in range(count):
            self.step(every)
            yield self.frame()

    def rollout(
        self,
        duration: float,
        *,
        rate: float = 1.0 / DEFAULT_DT_S,
        block_rows: int = DEFAULT_BLOCK_ROWS,
        threads: int = 1,
    ) -> Iterator[FrameBlock]:
        """Advances by ``duration`` seconds, yielding poses every ``1 / rate`` s in blocks.

        The fast path: the compiled motion kernel moves the agents and calls MuJoCo's
        ``mj_kinematics`` itself after every output step (`sim._native`), on the scene's
        kinematic twin (``build_scene(spec, geometry=False)``: the same bodies and joints, hence
        the same body poses, without the geoms no pose depends on). With ``threads`` > 1, or
        where the MuJoCo library cannot be called from compiled code, each block's kinematics
        run in one ``mujoco.batch`` call instead (on that many threads; identical results).
        After each block the world (and `data`) is at the block's last time. Only one block is
        held at a time, so hour-long runs stream in constant memory.
        """
        if isinstance(block_rows, bool) or not isinstance(block_rows, (int, np.integer)):
            raise ValueError(f"block_rows must be a positive int, got {block_rows!r}")
        if block_rows < 1:
            raise ValueError(f"block_rows must be a positive int, got {block_rows}")
        if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or threads < 1:
            raise ValueError(f"threads must be a positive int, got {threads!r}")
        every, count = self._output_plan(duration, rate)
        block_rows, n = int(block_rows), self._ids.size
        bodies = np.concatenate([self._torso_body, self._head_body])
        native = _native.NATIVE and threads == 1
        if native:
            xy = np.empty((block_rows, 2 * n, 2))
            quat = np.empty((block_rows, 2 * n, 4))
            present = np.zeros((block_rows, n), dtype=np.bool_)
        else:
            batch = self._batch_of(block_rows, int(threads))
        done = 0
        while done < count:
            rows = min(block_rows, count - done)
            record_at = np.full(rows * every, -1, dtype=np.int64)
            record_at[every - 1 :: every] = np.arange(rows)
            first_step = self._step_index
            if native:
                self._advance_native(record_at, bodies, xy, quat, present)
                yaws = yaw_from_quat(quat[:rows])
                mpos, mquat, qpos = self._twin_views[:3]
                last = (mpos[0], mquat[0], qpos[0], present[rows - 1])
            else:
                records = self._buffer(block_rows)
                self._advance(record_at, records)
                mpos, mquat, qpos, present = records
                batch.mocap_pos[:rows] = mpos[:rows]
                batch.mocap_quat[:rows] = mquat[:rows]
                batch.qpos[:rows] = qpos[:rows]
                ids = None if rows == batch.nsim else np.arange(rows)
                batch.forward(ids=ids, stage=mujoco.mjtStage.mjSTAGE_POS)
                xy = np.take(batch.xpos[:rows], bodies, axis=1)[..., :2]
                yaws = yaw_from_quat(np.take(batch.xquat[:rows], bodies, axis=1))
                last = (mpos[rows - 1], mquat[rows - 1], qpos[rows - 1], present[rows - 1])
            steps = first_step + every * np.arange(1, rows + 1)
            if self._truth is None:
                groups = self._groups_of_steps(steps)
            else:
                groups = self._truth.update(
                    steps * self._dt, present[:rows], xy[:rows, :n], yaws[:, :n]
                )
            self._load_row(*last)
            done += rows
            # Values the world guarantees, in arrays of this block's own (the buffers are
            # reused by the next block): no second check on the fast path.
            yield FrameBlock._trusted(
                time=steps * self._dt,
                ids=self._ids,
                kinds=self._kinds,
                present=present[:rows].copy(),
                position=xy[:rows, :n].copy(),
                yaw=yaws[:, :n],
                head_position=xy[:rows, n:].copy(),
                head_yaw=yaws[:, n:],
                groups=groups,
                sequence=self._sequence,
            )

    # ----------------------------------------------------------------------------------------
    # Internals

    def _bind_model(self, agents: Sequence[PersonSpec | RobotSpec]) -> None:
        model = self._model

        def body(name: str) -> int:
            if not _has(model, mujoco.mjtObj.mjOBJ_BODY, name):
                raise ValueError(f"model does not match the spec: it has no body {name!r}")
            return int(model.body(name).id)

        def joint(name: str) -> int:
            if not _has(model, mujoco.mjtObj.mjOBJ_JOINT, name):
                raise ValueError(f"model does not match the spec: it has no joint {name!r}")
            return int(model.jnt_qposadr[model.joint(name).id])

        n = len(agents)
        self._root_body = np.empty(n, dtype=np.int64)
        self._torso_body = np.empty(n, dtype=np.int64)
        self._head_body = np.empty(n, dtype=np.int64)
        mocap_of = np.empty(n, dtype=np.int64)
        head_adr = np.full(n, -1, dtype=np.int64)
        tilt_adr = np.full(n, -1, dtype=np.int64)
        for i, agent in enumerate(agents):
            prefix = agent.prefix
            robot = isinstance(agent, RobotSpec)
            root = body(prefix + ("base" if robot else "root"))
            self._root_body[i] = root
            self._torso_body[i] = body(prefix + "torso")
            self._head_body[i] = body(prefix + "head")
            mocap_of[i] = int(model.body_mocapid[root])
            if mocap_of[i] < 0:
                raise ValueError(
                    f"model does not match the spec: {prefix} root is not a mocap body"
                )
            if robot:
                head_adr[i] = joint(prefix + "head_pan")
                tilt_adr[i] = joint(prefix + "head_tilt")
            else:
                head_adr[i] = joint(prefix + "neck_yaw")
        # Where the motion kernel writes each agent's pose (`sim.motion.write_pose`).
        self._layout = (mocap_of, head_adr, tilt_adr)
        self._sensor_site = -1
        self._head_camera = -1
        if any(isinstance(a, RobotSpec) for a in agents):
            self._sensor_site = model.site(ROBOT_PREFIX + "head_sensor").id
            self._head_camera = model.camera(ROBOT_PREFIX + "head_camera").id

    def _buffer(self, rows: int) -> tuple[np.ndarray, ...]:
        if rows not in self._buffers:
            model = self._model
            qpos = np.tile(model.qpos0, (rows, 1))
            self._buffers[rows] = (
                np.zeros((rows, model.nmocap, 3)),
                np.tile([1.0, 0.0, 0.0, 0.0], (rows, model.nmocap, 1)),
                qpos,
                np.zeros((rows, self._ids.size), dtype=np.bool_),
            )
        return self._buffers[rows]

    def _batch_of(self, rows: int, threads: int) -> mj_batch.Batch:
        batch = self._batch
        if batch is None or batch.nsim != rows or batch.nthread != threads:
            batch = self._batch = mj_batch.Batch(self._twin, nsim=rows, nthread=threads)
            # Outputs are copied out only once bound: bind them before the first call.
            batch.bind("xpos")
            batch.bind("xquat")
        return batch

    def _write_initial_pose(self) -> None:
        records = self._buffer(1)
        motion.write_pose(self._state, self._params, 0.0, 0, self._layout, records)
        mpos, mquat, qpos, present = records
        self._load_row(mpos[0], mquat[0], qpos[0], present[0])

    def _load_row(
        self, mpos: np.ndarray, mquat: np.ndarray, qpos: np.ndarray, present: np.ndarray
    ) -> None:
        data = self._data
        data.mocap_pos[:] = mpos
        data.mocap_quat[:] = mquat
        data.qpos[:] = qpos
        data.time = self.time
        mujoco.mj_kinematics(self._model, data)
        self._present = present.copy()

    def _advance(self, record_at: np.ndarray, records: tuple[np.ndarray, ...]) -> None:
        """Runs the motion kernel over ``len(record_at)`` steps, recording into ``records``."""
        self._segments(record_at, motion.advance, records)

    def _advance_native(
        self,
        record_at: np.ndarray,
        bodies: np.ndarray,
        xy: np.ndarray,
        quat: np.ndarray,
        present: np.ndarray,
    ) -> None:
        """The motion kernel with MuJoCo's kinematics (on the twin) at every recorded step."""
        self._segments(
            record_at,
            _native.advance_with_kinematics,
            self._twin._address,
            self._twin_data._address,
            self._twin_views,
            self._buffer(1)[3],
            bodies,
            xy,
            quat,
            present,
        )

    def _segments(self, record_at: np.ndarray, kernel: Any, *rest: Any) -> None:
        """Runs ``kernel`` (`sim.motion.advance` or a variant) between decision ticks.

        Each call moves the agents from one tick to the next: ``kernel(state, intent, params,
        first_step, dt, margin, record_at_slice, layout, *rest)``. The script is sampled on
        each tick before the steps that follow it.
        """
        spd = self._steps_per_decision
        start = self._step_index
        end = start + record_at.size
        k = start
        while k < end:
            if self._script is not None and k % spd == 0 and k // spd != self._intent_tick:
                self._apply_script_tick(k)
            segment_end = min(end, (k // spd + 1) * spd)
            kernel(
                self._state,
                self._intent,
                self._params,
                k,
                self._dt,
                CLEARANCE_MARGIN_M,
                record_at[k - start : segment_end - start],
                self._layout,
                *rest,
            )
            k = segment_end
        self._step_index = end

    def _apply_script_tick(self, step: int) -> None:
        assert self._script is not None
        tick = step // self._steps_per_decision
        self._intent_tick = tick
        t = step * self._dt
        intents = self._script.intents(t)
        if not isinstance(intents, Mapping):
            raise ValueError(
                f"script.intents({t:g}) must return a Mapping of agent id to Intent, got "
                f"{type(intents).__name__}"
            )
        if intents is not self._last_mapping:
            self._apply_intents(intents, t)
            self._last_mapping = intents

    def _groups_at_step(self, step: int) -> tuple[Group, ...] | None:
        if self._script is None:
            return self._manual_groups
        tick = step // self._steps_per_decision
        cache = self._groups_cache
        if tick not in cache:
            t = tick * self._steps_per_decision * self._dt
            raw = self._script.groups(t)
            if raw is not self._last_raw_groups or raw is None:
                self._last_groups = self._validate_groups(raw, t)
                self._last_raw_groups = raw
            groups = self._last_groups
            if len(cache) >= 4:
                cache.pop(min(cache))
            cache[tick] = groups
        return cache[tick]

    def _groups_of_steps(self, steps: np.ndarray) -> tuple[tuple[Group, ...] | None, ...]:
        if self._script is None:
            return (self._manual_groups,) * steps.size
        ticks = steps // self._steps_per_decision
        by_tick = {
            int(k): self._groups_at_step(int(k) * self._steps_per_decision)
            for k in np.unique(ticks)
        }
        return tuple(by_tick[k] for k in ticks.tolist())

    def _validate_groups(self, groups: Any, t: float) -> tuple[Group, ...] | None:
        if groups is None:
            return None
        try:
            items = [tuple(int(m) for m in g) for g in groups]
        except (TypeError, ValueError) as exc:
            raise ValueError(
                f"groups at t={t:g} s must be a sequence of sequences of agent ids, got {groups!r}"
            ) from exc
        return check_groups(items, self._ids, at=f" at t={t:g} s", noun="agent", place="scene")

    def _apply_intents(self, intents: Mapping[int, Intent], t: float) -> None:
        last, index = self._last_intents, self._index
        for agent_id, intent in intents.items():
            i = index.get(agent_id) if type(agent_id) is not bool else None
            if i is None:
                raise ValueError(
                    f"intents at t={t:g} s name agent {agent_id!r}, who is not in the scene "
                    f"(ids {self._ids.tolist()})"
                )
            previous = last[i]
            if intent is previous or (previous is not None and intent == previous):
                continue
            self._write_intent(i, intent, t)
            last[i] = intent

    def _intent_error(self, i: int, t: float, message: str) -> ValueError:
        return ValueError(f"intent of {self._kinds[i]} {self._ids[i]} at t={t:g} s: {message}")

    def _check_inside(self, i: int, t: float, name: str, point: Point) -> None:
        x0, x1, y0, y1 = self._bounds[i]
        x, y = point
        if not (x0 <= x <= x1 and y0 <= y <= y1):
            raise self._intent_error(
                i,
                t,
                f"{name} ({x:g}, {y:g}) is outside the walls: with body radius "
                f"{self._params[i, motion.P_RADIUS]:.3f} m it must be within "
                f"x [{x0:.3f}, {x1:.3f}], y [{y0:.3f}, {y1:.3f}] m",
            )

    def _other_agent(self, i: int, t: float, name: str, agent_id: int) -> float:
        j = self._index.get(agent_id)
        if j is None:
            raise self._intent_error(
                i, t, f"{name} {agent_id} is not in the scene (ids {self._ids.tolist()})"
            )
        if j == i:
            raise self._intent_error(i, t, f"{name} must be another agent, got the agent itself")
        return float(j)

    def _write_intent(self, i: int, intent: Intent, t: float) -> None:
        if not isinstance(intent, Intent):
            raise ValueError(
                f"intents at t={t:g} s: agent {self._ids[i]} must get an Intent, got "
                f"{type(intent).__name__}"
            )
        row = self._intent[i].tolist()
        if intent.goal is not None:
            self._check_inside(i, t, "goal", intent.goal)
            row[motion.I_HAS_GOAL] = 1.0
            row[motion.I_GOAL_X], row[motion.I_GOAL_Y] = intent.goal
        else:
            row[motion.I_HAS_GOAL] = 0.0
        row[motion.I_SPEED] = intent.speed
        row[motion.I_FACE_MODE] = motion.FACE_NONE
        if intent.face_yaw is not None:
            row[motion.I_FACE_MODE] = motion.FACE_YAW
            row[motion.I_FACE_YAW] = intent.face_yaw
        elif intent.face_point is not None:
            row[motion.I_FACE_MODE] = motion.FACE_POINT
            row[motion.I_FACE_X], row[motion.I_FACE_Y] = intent.face_point
        elif intent.face_agent is not None:
            row[motion.I_FACE_MODE] = motion.FACE_AGENT
            row[motion.I_FACE_AGENT] = self._other_agent(i, t, "face_agent", intent.face_agent)
        row[motion.I_GAZE_MODE] = motion.GAZE_NONE
        if intent.gaze_point is not None:
            row[motion.I_GAZE_MODE] = motion.GAZE_POINT
            row[motion.I_GAZE_X], row[motion.I_GAZE_Y] = intent.gaze_point
        elif intent.gaze_agent is not None:
            row[motion.I_GAZE_MODE] = motion.GAZE_AGENT
            row[motion.I_GAZE_AGENT] = self._other_agent(i, t, "gaze_agent", intent.gaze_agent)
        if not intent.present and self._kinds[i] == ROBOT:
            raise self._intent_error(i, t, "the robot cannot leave the scene (present=False)")
        row[motion.I_PRESENT] = 1.0 if intent.present else 0.0
        if intent.appear_at is not None:
            self._check_inside(i, t, "appear_at", intent.appear_at)
            row[motion.I_HAS_APPEAR] = 1.0
            row[motion.I_APPEAR_X], row[motion.I_APPEAR_Y] = intent.appear_at
        else:
            row[motion.I_HAS_APPEAR] = 0.0
        self._intent[i] = row

    def _output_plan(self, duration: float, rate: float) -> tuple[int, int]:
        every = steps_per_frame(rate, self._dt)
        duration = float(duration)
        if not (math.isfinite(duration) and duration >= 0.0):
            raise ValueError(f"duration must be >= 0 seconds, got {duration}")
        periods = duration / (every * self._dt)
        frames = round(periods)
        if abs(periods - frames) > _RATE_TOLERANCE * max(1.0, frames):
            raise ValueError(
                f"duration must be a whole number of output periods of {every * self._dt:g} s, "
                f"got {duration:g} s"
            )
        return every, int(frames)


def _has(model: mujoco.MjModel, kind: mujoco.mjtObj, name: str) -> bool:
    return mujoco.mj_name2id(model, kind, name) >= 0
