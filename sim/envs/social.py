"""`SocialEnv`: the Directions Robot as the agent in a scripted social scene.

The people follow a registered scenario's script (`scenarios.make`); the robot follows the
agent's velocity commands. Each control step (10 Hz by default) the world moves by ten of its
own 10 ms steps, the robot's head sensor looks (field of view, range, MuJoCo ray occlusion,
dropouts, noise: `sim.Sensor`), the ground truth is settled by the scenario's rule
(`scenarios.GroundTruth`), and, every ``1 / detect_rate`` seconds (2 Hz by default), the
F-formation detector runs on what the robot sees. The detected groups are held until the next
detection.

Spaces (``max_people`` slots, one per person of the scene in scene order):

* **action** ``Box(-1, 1, (3,))``, float32: forward speed of the base, turn rate of the base,
  head-pan rate, as fractions of the robot's limits (`sim.ROBOT_LIMITS`: 0.8 m/s, 1.5 rad/s,
  2.0 rad/s; `SocialEnv.action_scale`); negative speeds back up, positive turns go left. An
  action outside the box raises `gymnasium.error.InvalidAction`.
* **observation** ``Dict``:

  - ``robot_pose`` (3,): x, y (metres, the room's frame) and yaw (radians) of the robot's base;
  - ``head_pan`` (1,): the head's pan from the base, radians;
  - ``people_position`` (max_people, 2): each person seen, in the robot's frame (x forward, y
    left), metres; 0 where not seen;
  - ``people_yaw``, ``people_head_yaw`` (max_people,): body and head yaw relative to the robot's
    base, radians; 0 where not seen;
  - ``people_seen``, ``people_head_seen`` (max_people,): 1 where the sensor reports the person
    (their head);
  - ``people_group`` (max_people,): the last detection's F-formation number of each person
    (1, 2, ... in slot order; 0: not seen then, or alone), when ``observe_groups``;
  - ``people_target`` (max_people,): 1 for the people of the group the robot is to join (task
    ``"join"`` only).

* **info**: ``time`` (s), ``groups`` (ground-truth F-formations now), ``detected_groups`` (the
  last detection's full partition of the observed agents) and ``detected_at`` (its time),
  ``metrics`` (that detection's precision, recall and F1 at T = 2/3 and pairwise accuracy
  against the ground truth of what the robot saw), ``target``, ``target_formed``,
  ``reward_terms``, ``is_success``, ``intruded``, ``distance_to_circle``; on the last step
  also ``episode`` (the scenario and its seed, the steps, the detector's scores over the
  episode's detections, the recording's path).

Tasks: ``"join"`` (`sim.envs.reward`: join the target group's circle; terminated on joining
or when the target group is gone for good, truncated at the time limit) and ``"observe"`` (zero
reward, never terminated, truncated at the time limit; a testbed for detectors).

Options of `reset`: ``scenario_options`` (the scenario's options for this episode, over those
given at construction), ``scenario_seed`` (the scenario's seed; by default drawn from the
env's generator, drawn again when a party finds no floor for everyone or, joining, offers no
group to join or no free spot to start from near it), ``robot_start`` (``"random"``: a free
spot facing the target's open side, 1.0-2.5 m beyond the place it can take and within 60
degrees of its bearing from the centre, away from everyone's start and every place planned in
the first 30 s, turned toward the centre within 45 degrees; ``"scenario"``: where the scenario
puts the robot).

Timing, a design choice: the agent decides at 10 Hz (a person's reaction time; the robot's
top speed moves it 8 cm per step), the world moves at its own 100 Hz underneath, and the
detector, by far the costliest part of a step, runs at 2 Hz (Babble's annotation rate): the
groups a robot acts on are at most half a second old.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces
from gymnasium.error import InvalidAction, ResetNeeded

import scenarios
from reform.detectors import (
    DetectorError,
    detector_info,
    detector_names,
    make_detector,
    run_detector,
)
from reform.frame import Frame, Group
from reform.json_values import json_float
from reform.metrics import T_TWO_THIRDS, evaluate
from scenarios import PlannedGroup, Scenario, Stage
from scenarios.mingle import NoFloorError
from sim.envs.overlay import GroupRing, draw_rings, group_rings
from sim.envs.reward import JoinTask, OSpace, assess, reward_terms
from sim.envs.target import Target, choose_target, circle_of, joinable_place
from sim.envs.timing import CONTROL_RATE_HZ, DETECT_RATE_HZ, JOIN_EPISODE_S, episode_steps
from sim.envs.view import Eyes, Truth, View, robot_frame
from sim.envs.viewer import DEFAULT_VIEWER, ViewerStream
from sim.episode import ScenarioScript, scene_spec
from sim.motion import ROBOT_LIMITS
from sim.recording import FieldOfView, record_episode
from sim.scene import ROBOT_RADIUS_M
from sim.sensor import Sensor
from sim.world import DEFAULT_DT_S, RobotCommand, World

__all__ = [
    "CONTROL_RATE_HZ",
    "DETECT_RATE_HZ",
    "JOIN_EPISODE_S",
    "RESET_OPTIONS",
    "ROBOT_STARTS",
    "TASKS",
    "SocialEnv",
    "TruthDetector",
]

DEFAULT_DETECTOR = "gcff"  # the registry's detector an environment detects with by default
TRUTH = "truth"  # the detector option naming `TruthDetector`
VIEW_MARGIN_M = 1.0  # metres beyond the sensor's range that observed positions may reach
ROOM_MARGIN_M = 0.5  # metres beyond the walls in the bounds of the robot's position
START_DISTANCE_M = (1.0, 2.5)  # metres outside the target's circle where the robot may start
START_CLEARANCE_M = 0.9  # metres from anyone's start (centre to centre) the robot starts
START_WALL_GAP_M = 0.1  # metres between the robot's body and the walls at the start
START_TURN_RAD = math.pi / 4.0  # radians, the robot starts turned this much at most off the group
JOIN_WALL_GAP_M = 0.45  # metres from a wall to the robot's centre, at least, at a joinable place
START_SPREAD_RAD = math.radians(60.0)  # radians around the circle off the place's bearing
START_PLAN_S = 30.0  # seconds: the robot starts away from the places planned this soon
START_TRIES = 200  # random start spots tried before falling back to the scenario's
SCENARIO_DRAWS = 20  # scenario seeds tried for a party with floor for all and a group to join
RENDER_SIZE_PX = (480, 360)  # pixels, width x height of rendered frames
TASKS = ("join", "observe")
ROBOT_STARTS = ("random", "scenario")
RESET_OPTIONS = ("robot_start", "scenario_options", "scenario_seed")
_SEED_HIGH = 2**31 - 1  # scenario seeds drawn from the env's generator are below this
_TWO_PI = 2.0 * math.pi
_ACTION_NAMES = ("speed", "turn rate", "head-pan rate")

ScenarioFactory = Callable[..., Scenario]


def _rate(name: str, value: Any) -> float:
    try:
        rate = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number (Hz), got {value!r}") from None
    if not (math.isfinite(rate) and rate > 0.0):
        raise ValueError(f"{name} must be a positive number (Hz), got {value!r}")
    return rate


def _steps(period: float, step: float, *, name: str) -> int:
    count = round(period / step)
    if count < 1 or abs(count * step - period) > 1e-9 * max(1.0, period):
        raise ValueError(
            f"{name}: 1 / rate = {period:g} s must be a whole number of {step:g} s steps"
        )
    return int(count)


class SocialEnv(gym.Env[dict[str, np.ndarray], np.ndarray]):
    """The robot as the agent in a scripted social scene (see the module doc).

    Args:
        scenario: a registered scenario name (`scenarios.names`) or a factory
            ``factory(*, seed, **options) -> scenarios.Scenario``.
        task: ``"join"``, ``"observe"`` or a `JoinTask` (joining with other parameters).
        scenario_options: the scenario's options for every episode.
        max_people: observation slots; default: the people of the scenario made with seed 0.
        episode_seconds: time limit, seconds; default: 40 s for joining, the scenario's own
            length for observing (never beyond the scenario's length).
        control_rate: agent decisions per second (a divisor of the world's 100 Hz).
        detect_rate: detector runs per second (a divisor of ``control_rate``).
        sensor: the robot's head sensor (default: `sim.Sensor()`, a Kinect's view).
        detector: the F-formation detector: a name of the detector registry
            (`reform.detectors.detector_names`: ``"gcff"``, the default, is `reform.Gcff` with
            the reference settings; ``"majority"``; an installed package's detector), a
            plugin's ``"package.module:factory"`` path (imported from ``sys.path``), each made
            by `reform.detectors.make_detector` without options; ``"truth"``
            (`TruthDetector`: the ground truth of what the robot sees, an upper bound); or an
            object with ``predict(frames)``, fitted. Every detection is checked
            (`reform.detectors.run_detector`): a detector that raises or returns no partition
            of the frame's agents stops the step with one `reform.detectors.DetectorError`
            line naming it (``detector_name``) and the frame.
        model: path to a REFORM model file (`reform.persistence.save_model`) to detect with
            (``make_detector("reform", model=model)``).
        observe_groups: whether the observation holds ``people_group``.
        robot_start: default start of the robot, ``"random"`` or ``"scenario"``; default:
            random for joining, the scenario's for observing.
        render_mode: None, ``"rgb_array"`` (`render` returns an overview of the room from
            above, the true groups ringed wide and thick and the last detection's ringed
            inside them, a matched group in its true group's colour: `sim.envs.overlay`) or
            ``"human"`` (every step is streamed to a Rerun viewer, an episode a recording:
            `sim.envs.viewer`; with no viewer listening and no display to start one, one
            warning and nothing shown).
        render_size: (width, height) of rendered frames, pixels.
        viewer: the Rerun viewer's gRPC address for ``render_mode="human"`` (default Rerun's
            ``rerun+http://127.0.0.1:9876/proxy``).
        record_dir: a folder to save each episode's Rerun recording in (``<scenario>-<seed>
            -<episode>.rrd``), or None.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": int(CONTROL_RATE_HZ)}

    def __init__(
        self,
        scenario: str | ScenarioFactory,
        *,
        task: str | JoinTask = "join",
        scenario_options: Mapping[str, Any] | None = None,
        max_people: int | None = None,
        episode_seconds: float | None = None,
        control_rate: float = CONTROL_RATE_HZ,
        detect_rate: float = DETECT_RATE_HZ,
        sensor: Sensor | None = None,
        detector: Any = None,
        model: str | os.PathLike[str] | None = None,
        observe_groups: bool = True,
        robot_start: str | None = None,
        render_mode: str | None = None,
        render_size: tuple[int, int] = RENDER_SIZE_PX,
        record_dir: str | os.PathLike[str] | None = None,
        viewer: str | None = None,
    ) -> None:
        if isinstance(scenario, str):
            try:
                scenarios.describe(scenario)  # an unknown name: the registry's one message
            except ValueError as exc:
                raise ValueError(f"{exc} (or give a scenario factory)") from None
            self._factory: ScenarioFactory | None = None
            self._scenario_name = scenario
        elif callable(scenario):
            self._factory = scenario
            self._scenario_name = getattr(scenario, "__name__", "scenario")
        else:
            raise ValueError(
                f"scenario must be a registered name or a factory, got {type(scenario).__name__}"
            )
        if isinstance(task, JoinTask):
            self._task: JoinTask | None = task
        elif task == "join":
            self._task = JoinTask()
        elif task == "observe":
            self._task = None
        else:
            raise ValueError(f"task must be one of {TASKS} or a JoinTask, got {task!r}")
        self._scenario_options = dict(scenario_options or {})
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be None or one of {self.metadata['render_modes']}, "
                f"got {render_mode!r}"
            )
        self.render_mode = render_mode
        size = tuple(render_size)
        if len(size) != 2 or not all(isinstance(v, int) and v > 0 for v in size):
            raise ValueError(f"render_size must be (width, height) in pixels, got {render_size!r}")
        self._render_size = (int(size[0]), int(size[1]))
        self._robot_start = _robot_start(
            robot_start if robot_start is not None else ("random" if self._task else "scenario")
        )
        self._control_dt = 1.0 / _rate("control_rate", control_rate)
        self._world_steps = _steps(self._control_dt, DEFAULT_DT_S, name="control_rate")
        self._detect_every = _steps(
            1.0 / _rate("detect_rate", detect_rate), self._control_dt, name="detect_rate"
        )
        if episode_seconds is not None:
            episode_seconds = float(episode_seconds)
            if not (math.isfinite(episode_seconds) and episode_seconds > 0.0):
                raise ValueError(
                    f"episode_seconds must be a positive number of seconds, got {episode_seconds}"
                )
        self._episode_seconds = episode_seconds
        self._sensor = Sensor() if sensor is None else sensor
        if not isinstance(self._sensor, Sensor):
            raise ValueError(f"sensor must be a sim.Sensor, got {type(self._sensor).__name__}")
        self._detector, self.detector_name = _detector(detector, model)
        self._observe_groups = bool(observe_groups)
        self._record_dir = None
        if record_dir is not None:  # a file in its place is refused now, not after an episode
            from reform.atomic import check_folder_path

            try:
                self._record_dir = check_folder_path(record_dir)
            except ValueError as exc:
                raise ValueError(f"record_dir {exc}") from None

        probe = self._draw(self._scenario_options, rng=np.random.default_rng(0))
        if probe.stage.robot is None:
            raise ValueError(
                f"scenario {self._scenario_name!r} has no robot with options "
                f"{self._scenario_options}: an environment needs the robot (see its options)"
            )
        people = len(probe.stage.people)
        if max_people is None:
            max_people = people
        if isinstance(max_people, bool) or not isinstance(max_people, int) or max_people < 1:
            raise ValueError(f"max_people must be a positive int, got {max_people!r}")
        if max_people < people:
            raise ValueError(
                f"max_people must be at least the scenario's {people} people, got {max_people}"
            )
        self.max_people = max_people
        self._room = probe.stage.room
        self.action_scale = np.array(
            [ROBOT_LIMITS.max_speed, ROBOT_LIMITS.max_turn_rate, ROBOT_LIMITS.head_rate]
        )
        self.action_space = spaces.Box(low=-1.0, high=1.0, shape=(3,), dtype=np.float32)
        self.observation_space = self._observation_space()
        self._reach = float(self._sensor.max_range + VIEW_MARGIN_M)
        self._half_room = (
            0.5 * self._room[0] + ROOM_MARGIN_M,
            0.5 * self._room[1] + ROOM_MARGIN_M,
        )
        self._world: World | None = None
        self._renderer: Any = None
        self._viewer = None
        if render_mode == "human":
            self._viewer = ViewerStream(DEFAULT_VIEWER if viewer is None else viewer)
        elif viewer is not None:
            raise ValueError(f"viewer is for render_mode='human', got render_mode={render_mode!r}")
        self._episodes = 0
        self._done = True

    @property
    def task(self) -> JoinTask | None:
        """The joining task's parameters (None when observing)."""
        return self._task

    @property
    def room(self) -> tuple[float, float]:
        """(x extent, y extent) of the scenario's room, metres (centred on the origin)."""
        return self._room

    @property
    def scenario(self) -> Scenario | None:
        """The scenario of the current episode (None before the first reset)."""
        return getattr(self, "_scenario", None)

    # ---------------------------------------------------------------------------------------
    # Gymnasium API

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        super().reset(seed=seed)
        self._done = True  # until this reset succeeds
        options = dict(options or {})
        unknown = sorted(set(options) - set(RESET_OPTIONS))
        if unknown:
            raise ValueError(
                f"reset: unknown options {unknown}; expected some of {list(RESET_OPTIONS)}"
            )
        scenario_seed = options.get("scenario_seed")
        if scenario_seed is not None and (
            isinstance(scenario_seed, bool) or not isinstance(scenario_seed, (int, np.integer))
        ):
            raise ValueError(f"reset: scenario_seed must be an int, got {scenario_seed!r}")
        start = _robot_start(options.get("robot_start", self._robot_start))
        extra = options.get("scenario_options") or {}
        if not isinstance(extra, Mapping):
            raise ValueError(
                f"reset: scenario_options must be a mapping of option names to values, got "
                f"{type(extra).__name__}"
            )
        merged = {**self._scenario_options, **extra}
        for attempt in range(SCENARIO_DRAWS):
            if scenario_seed is not None:
                scenario = self._make(int(scenario_seed), merged)
            else:
                scenario = self._draw(merged)
            stage = scenario.stage
            self._check_stage(stage)
            first = self._choose_target(scenario)
            if start == "random" and first is not None:
                placed = self._place_robot(stage, first, scenario.plan)
                if placed is not None:
                    stage = placed
                elif scenario_seed is None and attempt < SCENARIO_DRAWS - 1:
                    continue  # no free spot near the group: draw again
            # A joining episode needs a group to join: a draw with none is drawn again (a scene
            # that plans no group at all, like hri-passing, is taken as it is).
            if first is not None or self._task is None or scenario_seed is not None:
                break
            if not scenario.plan or attempt == SCENARIO_DRAWS - 1:
                break
        self._scenario = scenario
        robot_id = stage.robot.id
        spec = scene_spec(stage, name=scenario.name)
        world_seed = int(self.np_random.integers(_SEED_HIGH))
        self._world = world = World(
            spec,
            seed=world_seed,
            script=ScenarioScript(scenario),
            sequence=f"{scenario.name}-{scenario.seed}",
            truth=scenario.ground_truth(),
        )
        world.command_robot(RobotCommand())
        self._eyes = Eyes(world, self._sensor)
        self._robot_index = self._eyes.robot
        self._people_rows = np.flatnonzero(world.ids != world.robot_id).astype(np.int64)
        self._target = None if first is None else Target(scenario.plan, first, world.ids, robot_id)
        limit = scenario.duration
        if self._episode_seconds is not None:
            limit = min(limit, self._episode_seconds)
        elif self._task is not None:
            limit = min(limit, JOIN_EPISODE_S)
        self._limit_steps = episode_steps(limit, 1.0 / self._control_dt)
        self._steps_taken = 0
        self._held = 0
        self._hold_steps = (
            0
            if self._task is None
            else max(1, math.ceil(self._task.hold / self._control_dt - 1e-9))
        )
        self._assessment = None
        self._mask_of: tuple[int, ...] | None = None
        self._target_mask = np.zeros(len(stage.people), dtype=np.int8)
        self._detections: list[tuple[Frame, tuple[Group, ...]]] = []
        self._recorded: list[Frame] = []
        self._episodes += 1
        self._done = False
        observation, info = self._advance(first_step=True)
        if self._viewer is not None:
            self._viewer.open(
                name=f"{self._sequence}-{self._episodes}",
                seed=int(scenario.seed),
                room=stage.room,
            )
            self._show()
        return observation, info

    def step(
        self, action: np.ndarray
    ) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        if self._world is None:
            raise ResetNeeded("Cannot call env.step() before calling env.reset()")
        if self._done:
            raise ResetNeeded(
                "Cannot call env.step() after the episode ended (terminated or truncated): call "
                "env.reset() first"
            )
        speed, turn, pan = self._check_action(action)
        self._world.command_robot(RobotCommand(speed=speed, turn_rate=turn, pan_rate=pan))
        self._world.step(self._world_steps)
        self._steps_taken += 1
        observation, info = self._advance(first_step=False)
        terms = info["reward_terms"]
        reward = float(sum(terms.values()))
        terminated = bool(info["is_success"] or self._target_gone)
        truncated = not terminated and self._steps_taken >= self._limit_steps
        if self._viewer is not None:
            self._show()
        if terminated or truncated:
            self._done = True
            info["episode"] = self._finish()
            if self._viewer is not None:
                self._viewer.close()
        return observation, reward, terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """``"rgb_array"``: the room from above with the groups ringed, (height, width, 3)
        uint8; ``"human"``: streams the current step to the viewer (steps do so themselves)
        and returns None."""
        if self.render_mode is None:
            gym.logger.warn(
                "render() was called without a render_mode; make the env with "
                "render_mode='rgb_array' or 'human'"
            )
            return None
        if self._world is None:
            raise ResetNeeded("Cannot call env.render() before calling env.reset()")
        if self.render_mode == "human":
            self._show()
            return None

        world = self._world
        width, height = self._render_size
        if self._renderer is None or self._renderer_model is not world.model:
            self._close_renderer()
            world.model.vis.global_.offwidth = max(world.model.vis.global_.offwidth, width)
            world.model.vis.global_.offheight = max(world.model.vis.global_.offheight, height)
            self._renderer = mujoco.Renderer(world.model, height=height, width=width)
            self._renderer_model = world.model
        camera = mujoco.MjvCamera()
        camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        camera.lookat[:] = (0.0, 0.0, 0.4)
        camera.distance = 1.15 * max(self._room)
        camera.elevation = -65.0
        camera.azimuth = 90.0
        self._renderer.update_scene(world.data, camera=camera)
        image = self._renderer.render().copy()
        return draw_rings(image, self._rings(), self._renderer.scene.camera)

    def close(self) -> None:
        self._close_renderer()
        if self._viewer is not None:
            self._viewer.close()
        super().close()

    def _rings(self) -> list[GroupRing]:
        """The rings of the true groups and the last detection's now."""
        truth = self._now
        return group_rings(
            self._eyes.ids,
            truth.position,
            self._groups_now,
            {_recorded_name(self.detector_name): self._detected},
        )

    def _show(self) -> None:
        """Streams the state now to the viewer (human render mode)."""
        assert self._viewer is not None
        truth = self._now
        self._viewer.show(
            step=self._steps_taken,
            time=truth.time,
            ids=self._eyes.ids,
            kinds=self._eyes.kinds,
            present=truth.present,
            position=truth.position,
            yaw=truth.yaw,
            rings=self._rings(),
            sources=("truth", _recorded_name(self.detector_name)),
        )

    # ---------------------------------------------------------------------------------------
    # Internals

    def _check_stage(self, stage: Stage) -> None:
        if stage.robot is None:
            raise ValueError("reset: the scenario has no robot with these options")
        if len(stage.people) > self.max_people:
            raise ValueError(
                f"reset: the scenario has {len(stage.people)} people, more than max_people = "
                f"{self.max_people} observation slots"
            )
        if stage.room[0] > self._room[0] or stage.room[1] > self._room[1]:
            raise ValueError(
                f"reset: the room {stage.room} is larger than the {self._room} the observation "
                "bounds were made for; give such options at construction (scenario_options)"
            )

    def _choose_target(self, scenario: Scenario) -> PlannedGroup | None:
        """The group to join (None when observing or when the scene has none to offer)."""
        if self._task is None:
            return None
        stage = scenario.stage
        assert stage.robot is not None
        hx, hy = 0.5 * stage.room[0] - JOIN_WALL_GAP_M, 0.5 * stage.room[1] - JOIN_WALL_GAP_M
        return choose_target(
            scenario.plan, stage.robot.id, self._task, self.np_random, bounds=(-hx, hx, -hy, hy)
        )

    def _draw(
        self, options: Mapping[str, Any], *, rng: np.random.Generator | None = None
    ) -> Scenario:
        """A scenario with a seed drawn from ``rng`` (the env's generator by default); a draw
        that finds no floor for everyone (`scenarios.mingle.NoFloorError`) is drawn again."""
        rng = self.np_random if rng is None else rng
        for attempt in range(SCENARIO_DRAWS):
            try:
                return self._make(int(rng.integers(_SEED_HIGH)), options)
            except NoFloorError:
                if attempt == SCENARIO_DRAWS - 1:
                    raise
        raise AssertionError("unreachable")

    def _make(self, seed: int, options: Mapping[str, Any]) -> Scenario:
        if self._factory is None:
            return scenarios.make(self._scenario_name, seed=seed, **dict(options))
        scenario = self._factory(seed=seed, **dict(options))
        if not isinstance(scenario, Scenario):
            raise ValueError(
                f"the scenario factory must return a scenarios.Scenario, got "
                f"{type(scenario).__name__}"
            )
        return scenario

    def _observation_space(self) -> spaces.Dict:
        m = self.max_people
        hx, hy = 0.5 * self._room[0] + ROOM_MARGIN_M, 0.5 * self._room[1] + ROOM_MARGIN_M
        reach = float(self._sensor.max_range + VIEW_MARGIN_M)
        head = ROBOT_LIMITS.head_limit
        pi = np.float32(math.pi)
        entries: dict[str, spaces.Space[Any]] = {
            "robot_pose": spaces.Box(
                low=np.array([-hx, -hy, -pi], dtype=np.float32),
                high=np.array([hx, hy, pi], dtype=np.float32),
                dtype=np.float32,
            ),
            "head_pan": spaces.Box(low=-head, high=head, shape=(1,), dtype=np.float32),
            "people_position": spaces.Box(low=-reach, high=reach, shape=(m, 2), dtype=np.float32),
            "people_yaw": spaces.Box(low=-pi, high=pi, shape=(m,), dtype=np.float32),
            "people_head_yaw": spaces.Box(low=-pi, high=pi, shape=(m,), dtype=np.float32),
            "people_seen": spaces.MultiBinary(m),
            "people_head_seen": spaces.MultiBinary(m),
        }
        if self._observe_groups:
            entries["people_group"] = spaces.MultiDiscrete(np.full(m, m + 1, dtype=np.int64))
        if self._task is not None:
            entries["people_target"] = spaces.MultiBinary(m)
        return spaces.Dict(entries)

    def _check_action(self, action: Any) -> tuple[float, float, float]:
        try:
            values = np.asarray(action, dtype=np.float64)
        except (TypeError, ValueError):
            raise InvalidAction(
                f"action must be an array of shape (3,) (speed, turn rate, head-pan rate, each "
                f"within [-1, 1]), got {action!r}"
            ) from None
        if values.shape != (3,):
            raise InvalidAction(
                f"action must have shape (3,) (speed, turn rate, head-pan rate, each within "
                f"[-1, 1]), got shape {values.shape}"
            )
        bad = ~np.isfinite(values) | (np.abs(values) > 1.0)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise InvalidAction(
                f"action[{k}] ({_ACTION_NAMES[k]}) must be within [-1, 1], got {float(values[k])} "
                f"(action {values.tolist()} is outside {self.action_space})"
            )
        speed, turn, pan = values * self.action_scale
        return float(speed), float(turn), float(pan)

    def _place_robot(
        self, stage: Stage, group: PlannedGroup, plan: Sequence[PlannedGroup]
    ) -> Stage | None:
        """The stage with the robot at a random free spot facing the target's open side: 1.0 to
        2.5 m beyond its place (`joinable_place`), within `START_SPREAD_RAD` of the place's
        bearing from the centre, away from everyone's start and every place planned in the
        first `START_PLAN_S`, turned toward the centre within `START_TURN_RAD` (None when no
        spot is found in `START_TRIES` draws)."""
        assert stage.robot is not None
        circle = circle_of(group, stage.robot.id)
        pad = ROBOT_RADIUS_M + START_WALL_GAP_M
        hx, hy = 0.5 * stage.room[0] - pad, 0.5 * stage.room[1] - pad
        place = joinable_place(group, stage.robot.id, self._task or JoinTask())
        out = (place if place is not None else circle.centre + (1.0, 0.0)) - circle.centre
        reach = float(np.hypot(*out))
        bearing = math.atan2(out[1], out[0])
        spread = START_SPREAD_RAD if place is not None else math.pi
        others = np.array([p.position for p in stage.people if p.present]).reshape(-1, 2)
        soon = [g.places for g in plan if g.start <= START_PLAN_S]
        taken = np.vstack([others, group.places, *soon])
        rng = self.np_random
        for _ in range(START_TRIES):
            angle = bearing + rng.uniform(-spread, spread)
            distance = reach + rng.uniform(*START_DISTANCE_M)
            turn = rng.uniform(-START_TURN_RAD, START_TURN_RAD)
            spot = circle.centre + distance * np.array([math.cos(angle), math.sin(angle)])
            if not (abs(spot[0]) <= hx and abs(spot[1]) <= hy):
                continue
            if np.min(np.hypot(*(taken - spot).T)) < START_CLEARANCE_M:
                continue
            toward = circle.centre - spot
            yaw = math.atan2(toward[1], toward[0]) + turn
            robot = dataclasses.replace(
                stage.robot,
                position=(float(spot[0]), float(spot[1])),
                yaw=math.atan2(math.sin(yaw), math.cos(yaw)),
            )
            return dataclasses.replace(stage, robot=robot)
        return None

    def _advance(self, *, first_step: bool) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Observation and info of the state the world is in now."""
        eyes = self._eyes
        truth = eyes.truth()
        groups = self._world.groups()
        view = eyes.look(truth, self.np_random)
        if self._steps_taken % self._detect_every == 0:
            self._detect(truth, view, groups)
        if self._record_dir is not None:
            self._recorded.append(eyes.truth_frame(truth, groups, sequence=self._sequence))
        self._now, self._groups_now = truth, groups
        info = self._task_info(truth, first_step=first_step)
        observation = self._observation(truth, view)
        info.update(
            time=truth.time,
            groups=groups,
            detected_groups=self._detected,
            detected_at=self._detected_at,
            metrics=dict(self._metrics),
        )
        return observation, info

    @property
    def _sequence(self) -> str:
        return f"{self._scenario.name}-{self._scenario.seed}"

    def _detect(self, truth: Truth, view: View, groups: tuple[Group, ...]) -> None:
        frame = self._eyes.observed_frame(truth, view, groups, sequence=self._sequence)
        (partition,) = run_detector(
            self.detector_name, self._detector, [frame], oracle=self.detector_name == TRUTH
        )
        partition = tuple(partition)
        self._detections.append((frame, partition))
        self._detected = partition
        self._detected_at = truth.time
        number = np.zeros(self.max_people, dtype=np.int64)
        slot = {int(i): k for k, i in enumerate(self._eyes.ids[self._people_rows])}
        label = 0
        for group in partition:
            if len(group) < 2:
                continue
            label += 1
            for member in group:
                k = slot.get(int(member))
                if k is not None:
                    number[k] = label
        self._group_number = number
        self._metrics = _frame_scores(frame, partition)

    def _observation(self, truth: Truth, view: View) -> dict[str, np.ndarray]:
        m = self.max_people
        r = self._robot_index
        x, y, yaw = float(truth.position[r, 0]), float(truth.position[r, 1]), float(truth.yaw[r])
        position = np.empty((m, 2), dtype=np.float32)
        body = np.empty(m, dtype=np.float32)
        head = np.empty(m, dtype=np.float32)
        seen = np.empty(m, dtype=np.int8)
        head_seen = np.empty(m, dtype=np.int8)
        robot_frame(
            self._people_rows,
            view.seen,
            view.head_seen,
            view.position,
            view.yaw,
            view.head_yaw,
            x,
            y,
            yaw,
            self._reach,
            position,
            body,
            head,
            seen,
            head_seen,
        )
        hx, hy = self._half_room
        obs = {
            "robot_pose": np.array(
                [min(max(x, -hx), hx), min(max(y, -hy), hy), (yaw + math.pi) % _TWO_PI - math.pi],
                dtype=np.float32,
            ),
            "head_pan": np.array([self._eyes.head_pan], dtype=np.float32),
            "people_position": position,
            "people_yaw": body,
            "people_head_yaw": head,
            "people_seen": seen,
            "people_head_seen": head_seen,
        }
        if self._observe_groups:
            obs["people_group"] = self._group_number * seen
        if self._task is not None:
            target = np.zeros(m, dtype=np.int8)
            if self._target is not None and not self._target.gone:
                target[: self._people_rows.size] = self._target_mask
            obs["people_target"] = target
        return obs

    def _task_info(self, truth: Truth, *, first_step: bool) -> dict[str, Any]:
        task = self._task
        self._target_gone = False
        if task is None:
            return {
                "reward_terms": {},
                "is_success": False,
                "target": (),
                "target_formed": False,
                "intruded": (),
                "distance_to_circle": None,
            }
        target = self._target
        circle: OSpace | None = None
        if target is not None:
            formed = target.update(truth.time, truth.present, truth.position, truth.yaw)
            if formed:
                circle = target.circle
            self._target_gone = target.gone
            if target.members is not self._mask_of:
                members = set(target.members)
                ids = self._eyes.ids[self._people_rows]
                self._target_mask = np.array([int(i) in members for i in ids], dtype=np.int8)
                self._mask_of = target.members
        r = self._robot_index
        rows = self._people_rows[truth.present[self._people_rows]]
        current = assess(
            task,
            robot_position=truth.position[r],
            robot_yaw=float(truth.yaw[r]),
            people_ids=self._eyes.ids[rows],
            people_position=truth.position[rows],
            o_space=circle,
        )
        previous = None if first_step else self._assessment
        self._assessment = current
        self._held = self._held + 1 if current.placed else 0
        joined = not first_step and self._held >= self._hold_steps
        terms = reward_terms(task, previous, current, joined=joined)
        if first_step:
            terms = dict.fromkeys(terms, 0.0)
        return {
            "reward_terms": terms,
            "is_success": bool(joined),
            "target": () if target is None or target.gone else target.members,
            "target_formed": circle is not None,
            "intruded": current.intruded,
            "distance_to_circle": current.distance_to_circle if current.formed else None,
        }

    def _finish(self) -> dict[str, Any]:
        """The episode's summary (and its recording, if asked)."""
        frames = [f for f, _ in self._detections]
        partitions = [p for _, p in self._detections]
        scores = evaluate(frames, partitions)
        at = scores.at(T_TWO_THIRDS)
        summary: dict[str, Any] = {
            "scenario": self._scenario.name,
            "scenario_seed": int(self._scenario.seed),
            "steps": self._steps_taken,
            "time": self._steps_taken * self._control_dt,
            "detector": self.detector_name,
            "detections": len(frames),
            "precision": float(at.precision),
            "recall": float(at.recall),
            "f1": float(at.f1),
            "pairwise_accuracy": json_float(scores.pairwise_accuracy),
            "recording": None,
        }
        if self._record_dir is not None:
            summary["recording"] = str(self._record(frames, partitions))
        return summary

    def _record(self, observed: list[Frame], partitions: list[tuple[Group, ...]]) -> Path:
        """Saves the episode's Rerun recording (written atomically by `sim.recording`)."""

        assert self._record_dir is not None
        scenario = self._scenario
        path = self._record_dir / f"{scenario.name}-{scenario.seed}-{self._episodes}.rrd"
        path.parent.mkdir(parents=True, exist_ok=True)
        record_episode(
            path,
            self._recorded,
            observed=observed,
            # The recording's ground-truth tree is "truth": the TruthDetector's is named apart.
            detections={_recorded_name(self.detector_name): partitions},
            events=scenario.events,
            seed=int(scenario.seed),
            name=self._sequence,
            field_of_view=FieldOfView.of(self._sensor),
        )
        return path

    def _close_renderer(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


@functools.lru_cache(maxsize=256)
def _scores(
    ids: tuple[int, ...], truth: tuple[Group, ...], partition: tuple[Group, ...]
) -> dict[str, float | None]:
    frame = Frame(
        ids=np.array(ids, dtype=np.int64),
        position=np.zeros((len(ids), 2)),
        yaw=np.zeros(len(ids)),
        groups=truth,
    )
    scores = evaluate([frame], [partition])
    at = scores.at(T_TWO_THIRDS)
    pairwise = float(scores.pairwise_accuracy)
    return {
        "precision": float(at.precision),
        "recall": float(at.recall),
        "f1": float(at.f1),
        "pairwise_accuracy": pairwise if math.isfinite(pairwise) else None,
    }


def _frame_scores(frame: Frame, partition: tuple[Group, ...]) -> dict[str, float | None]:
    """The evaluation protocol's scores of one detection (T = 2/3; None where undefined).

    They depend only on the ids, the true groups and the partition, so repeated detections of
    an unchanged scene are looked up, not scored again.
    """
    truth = tuple(tuple(int(m) for m in g) for g in frame.groups or ())
    partition = tuple(tuple(int(m) for m in g) for g in partition)
    return dict(_scores(tuple(frame.ids.tolist()), truth, partition))


def _robot_start(value: Any) -> str:
    if value not in ROBOT_STARTS:
        raise ValueError(f"robot_start must be one of {ROBOT_STARTS}, got {value!r}")
    return str(value)


class TruthDetector:
    """A detector that knows: each frame's ground truth as its partition (an upper bound for
    policies acting on detections; the frames an environment detects on carry the truth
    restricted to what the robot sees)."""

    def fit(self, frames: Sequence[Frame]) -> TruthDetector:
        return self

    def predict(self, frames: Sequence[Frame]) -> list[tuple[Group, ...]]:
        return [frame.partition() for frame in frames]


def _recorded_name(name: str) -> str:
    return f"{name}-detector" if name == TRUTH else name


def _detector(detector: Any, model: str | os.PathLike[str] | None) -> tuple[Any, str]:
    """The detector the options name, and its name (for messages, summaries, recordings)."""
    if detector is not None and model is not None:
        raise ValueError("give a detector or a model file, not both")
    if model is not None:
        return make_detector("reform", model=model), "reform"
    if detector is None:
        detector = DEFAULT_DETECTOR
    if isinstance(detector, str):
        if detector == TRUTH:
            return TruthDetector(), TRUTH
        if ":" not in detector and detector not in detector_names():
            raise DetectorError(
                f"detector must be {TRUTH!r}, a detector's name ({', '.join(detector_names())}), "
                f"a plugin's package.module:factory or an object with predict(frames), got "
                f"{detector!r}"
            )
        needs = detector_info(detector).needs if ":" not in detector else ""
        if needs:
            what = "a dataset" if needs == "dataset" else "training frames"
            raise DetectorError(
                f"detector {detector!r} must be given {what} before it predicts, which an "
                "environment does not have: make it with reform.make_detector, give it what it "
                "needs (reform.prepare_detector) and pass the object"
            )
        return make_detector(detector), detector
    if not callable(getattr(detector, "predict", None)):
        raise ValueError(
            f"detector must have predict(frames) (a fitted reform.Reform, reform.Gcff, ...), "
            f"got {type(detector).__name__}"
        )
    return detector, type(detector).__name__.lower()
