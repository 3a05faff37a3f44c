"""Gymnasium environments: the contract, determinism, the joining task's reward and endings,
bad input, vectorisation, the robot's view, rendering and recording, the scripted baseline."""

from __future__ import annotations

import json
import math
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.error import InvalidAction, ResetNeeded
from gymnasium.utils.env_checker import check_env, data_equivalence

import sim.envs  # noqa: F401  (registers the environments)
from reform.detectors import DetectorError
from scenarios import RobotPlace, Role, Scenario, Stage, TimelineBuilder
from sim import Sensor
from sim.envs import (
    ENV_IDS,
    REWARD_TERMS,
    JoinPolicy,
    JoinTask,
    OSpace,
    SocialEnv,
    estimate_o_space,
    evaluate_policy,
    joining_place,
)
from sim.envs.reward import assess, reward_terms
from sim.envs.view import Eyes
from sim.ticking import TICK_S
from sim.world import World

PAIR_HALF_M = 0.5  # metres, half the distance between the toy pair
ROBOT_START_Y_M = -2.0  # metres, where the toy scene's robot starts (facing +y, the pair)


def toy_pair(
    *, seed: int, end: float = math.inf, length: float = 30.0, half: float = PAIR_HALF_M
) -> Scenario:
    """Two people ``2 half`` apart facing each other across the origin; the robot 2 m south,
    facing them. The plan declares them a group from the start (they stand at their places)
    until ``end``.
    """
    places = np.array([[-half, 0.0], [half, 0.0]])
    facings = np.array([0.0, math.pi])
    people = tuple(
        Role(id=i + 1, position=tuple(places[i]), yaw=float(facings[i])) for i in range(2)
    )
    builder = TimelineBuilder([1, 2, 0])
    builder.group([1, 2], places, facings, np.zeros(2), start=0.0, end=end)
    return Scenario(
        name="toy-pair",
        seed=seed,
        options={},
        stage=Stage(
            room=(6.0, 6.0),
            people=people,
            robot=RobotPlace(id=0, position=(0.0, ROBOT_START_Y_M), yaw=math.pi / 2),
        ),
        timeline=builder.build(),
        duration=length,
    )


def toy_env(**kwargs) -> SocialEnv:
    kwargs.setdefault("robot_start", "scenario")
    return SocialEnv(toy_pair, **kwargs)


def _rollout(env: gym.Env, seed: int, steps: int) -> list:
    observation, info = env.reset(seed=seed)
    env.action_space.seed(seed)
    out = [(observation, info)]
    for _ in range(steps):
        step = env.step(env.action_space.sample())
        out.append(step)
        if step[2] or step[3]:
            break
    return out


# ---------------------------------------------------------------------------------------------
# Registration and the Gymnasium contract


def test_import_sim_envs_registers_every_id_and_stays_light() -> None:
    code = (
        "import sys, gymnasium, sim.envs\n"
        "ids = [i for i in gymnasium.registry if i.startswith('ReformSim/')]\n"
        "heavy = [m for m in sys.modules if m in ('mujoco', 'sklearn', 'sim.envs.social') "
        "or m.startswith('reform.') and m != 'reform._lazy']\n"
        "print(len(ids), heavy)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split()[0] == str(len(ENV_IDS))
    assert out.stdout.strip().endswith("[]")


def test_ids_name_a_task_and_an_observe_variant_per_scenario() -> None:
    """Every registered scenario with a place for the robot has its two environments (but the
    randomised ones: their room changes with the seed)."""
    names = {i.split("/")[1].removesuffix("-v0").removesuffix("Observe") for i in ENV_IDS}
    assert names == {
        "HRIConversation",
        "HRIRobotExcluded",
        "HRIPassing",
        "WordImprov",
        "Mingle",
    }
    assert len(ENV_IDS) == 10
    assert gym.spec("ReformSim/Mingle-v0").kwargs["scenario_options"] == {
        "robot": True,
        "duration": 60.0,
    }
    assert gym.spec("ReformSim/WordImprovObserve-v0").kwargs["scenario_options"] == {
        "robot": "watch"
    }
    for env_id in ENV_IDS:
        spec = gym.spec(env_id)
        assert spec.entry_point == "sim.envs.social:SocialEnv"
        assert spec.kwargs["task"] == ("observe" if "Observe" in env_id else "join")


def test_each_id_carries_its_time_limit_for_the_time_limit_wrapper() -> None:
    from gymnasium.wrappers import TimeLimit

    from sim.envs.timing import JOIN_EPISODE_S, OBSERVE_EPISODE_S

    for env_id in ENV_IDS:
        spec = gym.spec(env_id)
        seconds = OBSERVE_EPISODE_S if "Observe" in env_id else JOIN_EPISODE_S
        assert spec.kwargs["episode_seconds"] == seconds
        assert spec.max_episode_steps == round(seconds * 10)  # 10 Hz control steps
    env = gym.make("ReformSim/HRIRobotExcluded-v0", detector="truth")
    wrapper, limits = env, []
    while isinstance(wrapper, gym.Wrapper):
        if isinstance(wrapper, TimeLimit):
            limits.append(wrapper._max_episode_steps)
        wrapper = wrapper.env
    assert limits == [400]
    env.close()


def test_the_env_and_the_time_limit_truncate_on_the_same_step() -> None:
    # The pair talks for 40 s after walking in: the 40 s limit comes first. The env ends its
    # own episode on the step TimeLimit truncates: its summary is there, nothing doubles up.
    env = gym.make("ReformSim/HRIRobotExcluded-v0", detector="truth")
    env.reset(seed=0, options={"scenario_seed": 0})
    steps, done = 0, False
    while not done:
        _, _, terminated, truncated, info = env.step(np.zeros(3, dtype=np.float32))
        steps += 1
        done = terminated or truncated
    assert steps == 400 and truncated and not terminated
    assert info["episode"]["steps"] == 400 and info["episode"]["time"] == pytest.approx(40.0)
    with pytest.raises(ResetNeeded, match="after the episode ended"):
        env.unwrapped.step(np.zeros(3, dtype=np.float32))
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS, ids=lambda i: i.split("/")[1])
def test_check_env_passes(env_id: str) -> None:
    env = gym.make(env_id, episode_seconds=3.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a warning from the checker fails the test
        check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_two_envs_with_one_seed_roll_out_identically() -> None:
    a = gym.make("ReformSim/HRIConversation-v0", disable_env_checker=True)
    b = gym.make("ReformSim/HRIConversation-v0", disable_env_checker=True)
    first, second = _rollout(a, 7, 60), _rollout(b, 7, 60)
    assert len(first) == len(second) > 1
    for x, y in zip(first, second, strict=True):
        assert data_equivalence(x, y, exact=True)
    other = _rollout(a, 8, 60)
    assert not data_equivalence(first[0][0], other[0][0], exact=True)


def test_observation_layout_and_info() -> None:
    env = toy_env()
    observation, info = env.reset(seed=0)
    assert env.observation_space.contains(observation)
    assert set(observation) == {
        "robot_pose",
        "head_pan",
        "people_position",
        "people_yaw",
        "people_head_yaw",
        "people_seen",
        "people_head_seen",
        "people_group",
        "people_target",
    }
    # The robot, 2 m south facing north, sees both people ahead: person 1 (x = -0.5) on its
    # left (robot frame y > 0), person 2 on its right.
    np.testing.assert_allclose(
        observation["robot_pose"], [0.0, ROBOT_START_Y_M, math.pi / 2], atol=1e-5
    )
    assert observation["people_seen"].tolist() == [1, 1]
    np.testing.assert_allclose(observation["people_position"], [[2.0, 0.5], [2.0, -0.5]], atol=0.03)
    # Their bodies face east and west: -90 and +90 degrees relative to the robot's heading.
    np.testing.assert_allclose(observation["people_yaw"], [-math.pi / 2, math.pi / 2], atol=0.05)
    assert observation["people_target"].tolist() == [1, 1]
    assert info["target"] == (1, 2)
    assert info["groups"] == ((1, 2),)
    assert set(info["reward_terms"]) == set(REWARD_TERMS)
    assert set(info["metrics"]) == {"precision", "recall", "f1", "pairwise_accuracy"}
    # The detector's partition covers the robot and the people it sees.
    assert sorted(m for g in info["detected_groups"] for m in g) == [0, 1, 2]


# ---------------------------------------------------------------------------------------------
# The joining task


def _drive_north(
    env: SocialEnv, *, stop_y: float, top: float = 0.5, gain: float = 2.0, seed: int = 0
) -> list[tuple]:
    """Drives the robot straight north (at most ``top`` m/s, slowing ``gain`` m/s per metre
    before ``stop_y``), then stands; returns every step."""
    observation, _ = env.reset(seed=seed)
    steps = []
    done = False
    while not done:
        y = float(observation["robot_pose"][1])
        speed = float(np.clip((stop_y - y) * gain, 0.0, top)) / env.action_scale[0]
        observation, reward, terminated, truncated, info = env.step(
            np.array([speed, 0.0, 0.0], dtype=np.float32)
        )
        steps.append((reward, terminated, truncated, info))
        done = terminated or truncated
    return steps


def test_joining_terminates_with_success_and_terms_sum_to_the_reward() -> None:
    env = toy_env()
    # Stopping 0.6 m south of the pair's centre: on the circle (radius 0.5, tolerance 0.3), 0.78 m
    # from each person (clear of 0.35 + 0.28 m), facing the centre.
    steps = _drive_north(env, stop_y=-0.6)
    reward, terminated, truncated, info = steps[-1]
    assert terminated and not truncated
    assert info["is_success"]
    assert info["reward_terms"]["success"] == JoinTask().success_reward
    assert info["intruded"] == ()
    for reward, _, _, info in steps:
        assert reward == pytest.approx(sum(info["reward_terms"].values()), abs=1e-12)
    # Approaching the circle earns progress: 1.5 m from the circle at the start, ~0.1 at the end.
    progress = sum(info["reward_terms"]["progress"] for _, _, _, info in steps)
    assert progress == pytest.approx(1.4, abs=0.1)
    assert steps[-1][3]["episode"]["scenario"] == "toy-pair"


def test_walking_into_the_o_space_is_penalised_and_never_succeeds() -> None:
    # A pair 1.6 m apart: the robot fits between them, 0.8 m from each (clear of their personal
    # space) but in the o-space (closer to the centre than 0.8 - 0.3 m). It crosses the ring at
    # 0.8 m/s, in less than the 1 s a place must be held.
    env = SocialEnv(
        lambda *, seed: toy_pair(seed=seed, half=0.8), robot_start="scenario", episode_seconds=8.0
    )
    steps = _drive_north(env, stop_y=0.0, top=0.8, gain=1.6)
    reward, terminated, truncated, info = steps[-1]
    assert truncated and not terminated and not info["is_success"]
    assert info["distance_to_circle"] == pytest.approx(0.8, abs=0.05)
    assert info["reward_terms"]["o_space"] == -JoinTask().o_space_penalty
    assert info["intruded"] == ()
    assert reward == pytest.approx(-JoinTask().o_space_penalty - JoinTask().time_penalty, abs=0.01)


def test_the_episode_ends_when_the_target_group_is_gone() -> None:
    # The pair is planned to talk for 21 s (a target must be planned to last 20 s).
    env = SocialEnv(lambda *, seed: toy_pair(seed=seed, end=21.0), robot_start="scenario")
    env.reset(seed=0)
    steps, done = 0, False
    while not done:
        _, _, terminated, truncated, info = env.step(np.zeros(3, dtype=np.float32))
        steps += 1
        done = terminated or truncated
    assert terminated and not info["is_success"]
    assert steps == 210  # the plan ends at t = 21 s: step 210 at 10 Hz
    assert info["target"] == ()
    with pytest.raises(ResetNeeded, match="after the episode ended"):
        env.step(np.zeros(3, dtype=np.float32))


def test_observe_variant_has_zero_reward_and_is_truncated_at_its_limit() -> None:
    env = gym.make("ReformSim/HRIConversationObserve-v0", episode_seconds=2.0)
    observation, info = env.reset(seed=1)
    assert "people_target" not in observation
    total, steps, done = 0.0, 0, False
    while not done:
        _, reward, terminated, truncated, info = env.step(env.action_space.sample())
        total += reward
        steps += 1
        assert info["reward_terms"] == {} and reward == 0.0
        done = terminated or truncated
    assert truncated and not terminated and steps == 20
    assert info["episode"]["detections"] == 5  # at t = 0, 0.5, ... 2.0 s: 2 Hz


def test_random_start_keeps_the_robot_outside_the_circle_facing_it() -> None:
    env = toy_env(robot_start="random")
    for seed in range(5):
        observation, info = env.reset(seed=seed)
        x, y, yaw = (float(v) for v in observation["robot_pose"])
        distance = math.hypot(x, y)
        assert PAIR_HALF_M + 1.0 - 0.05 <= distance <= PAIR_HALF_M + 2.5 + 0.05
        bearing = math.atan2(-y, -x)
        assert abs(math.remainder(bearing - yaw, 2 * math.pi)) <= math.pi / 4 + 1e-6


def test_reset_options_pick_the_scenario_seed_and_options() -> None:
    env = gym.make("ReformSim/HRIConversation-v0", disable_env_checker=True)
    _, a = env.reset(seed=0, options={"scenario_seed": 5})
    _, b = env.reset(seed=1, options={"scenario_seed": 5, "robot_start": "scenario"})
    assert env.unwrapped.scenario.seed == 5
    assert a["target"] == b["target"] == (1, 2)
    env.reset(seed=2, options={"scenario_options": {"radius": 0.9}})
    assert env.unwrapped.scenario.options["radius"] == 0.9


# ---------------------------------------------------------------------------------------------
# Bad input


def test_actions_outside_the_space_are_refused() -> None:
    env = toy_env()
    env.reset(seed=0)
    with pytest.raises(InvalidAction, match=r"action\[0\] \(speed\) must be within .*, got 1.5"):
        env.step(np.array([1.5, 0.0, 0.0], dtype=np.float32))
    with pytest.raises(InvalidAction, match=r"action\[2\] \(head-pan rate\).*got nan"):
        env.step(np.array([0.0, 0.0, np.nan]))
    with pytest.raises(InvalidAction, match=r"must have shape \(3,\).*got shape \(2,\)"):
        env.step(np.zeros(2))
    with pytest.raises(InvalidAction, match="must be an array of shape"):
        env.step("forward")


def test_step_before_reset_is_refused() -> None:
    env = toy_env()
    with pytest.raises(ResetNeeded, match=r"Cannot call env.step\(\) before calling env.reset\(\)"):
        env.step(np.zeros(3, dtype=np.float32))


def test_unknown_options_and_bad_arguments_are_refused() -> None:
    env = toy_env()
    with pytest.raises(ValueError, match=r"unknown options \['speed'\]; expected some of"):
        env.reset(seed=0, options={"speed": 2})
    with pytest.raises(ValueError, match="robot_start must be one of"):
        env.reset(seed=0, options={"robot_start": "corner"})
    with pytest.raises(ValueError, match="scenario_seed must be an int"):
        env.reset(seed=0, options={"scenario_seed": 1.5})
    with pytest.raises(ValueError, match=r"unknown scenario 'party'; known scenarios: .*factory\)"):
        SocialEnv("party")
    with pytest.raises(ValueError, match="task must be one of"):
        toy_env(task="dance")
    with pytest.raises(ValueError, match="max_people must be at least the scenario's 2 people"):
        toy_env(max_people=1)
    with pytest.raises(ValueError, match="detect_rate: 1 / rate = 0.25 s must be a whole number"):
        toy_env(detect_rate=4.0)
    with pytest.raises(ValueError, match="render_mode must be None or one of"):
        toy_env(render_mode="ansi")
    with pytest.raises(ValueError, match="has no robot"):
        gym.make("ReformSim/WordImprov-v0", scenario_options={"robot": "none"})


# ---------------------------------------------------------------------------------------------
# Vectorisation, the robot's view, rendering, recording


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_make_vec_works(mode: str) -> None:
    envs = gym.make_vec(
        "ReformSim/HRIRobotExcluded-v0", num_envs=2, vectorization_mode=mode, episode_seconds=1.0
    )
    try:
        observation, info = envs.reset(seed=3)
        assert observation["people_position"].shape == (2, 2, 2)
        ended = []
        for _ in range(12):  # past the 1 s limit: the envs reset themselves
            observation, reward, terminated, truncated, info = envs.step(envs.action_space.sample())
            ended.append(bool(truncated.all()))
        assert ended.index(True) == 9  # the tenth step of 0.1 s ends both episodes
        assert reward.shape == (2,) and observation["robot_pose"].shape == (2, 3)
    finally:
        envs.close()


def test_the_view_equals_the_sensor_model() -> None:
    scenario = toy_pair(seed=0)
    from sim.episode import scene_spec

    world = World(scene_spec(scenario.stage), seed=1)
    sensor = Sensor(position_noise=0.05, yaw_noise=0.1, dropout=0.2)
    eyes = Eyes(world, sensor)
    for seed in range(10):
        expected = sensor.observe(world, np.random.default_rng(seed))
        truth = eyes.truth()
        view = eyes.look(truth, np.random.default_rng(seed))
        frame = eyes.observed_frame(truth, view, None)
        assert frame.ids.tolist() == expected.ids.tolist()
        np.testing.assert_array_equal(frame.position, expected.position)
        np.testing.assert_array_equal(frame.yaw, expected.yaw)
        np.testing.assert_array_equal(frame.head_position, expected.head_position)
        np.testing.assert_array_equal(frame.head_yaw, expected.head_yaw)


def test_render_gives_an_overview_image() -> None:
    env = toy_env(render_mode="rgb_array", render_size=(160, 120))
    env.reset(seed=0)
    image = env.render()
    assert image.shape == (120, 160, 3) and image.dtype == np.uint8
    assert image.std() > 5.0  # a scene, not a blank
    env.close()


def _coloured(image: np.ndarray, colour) -> np.ndarray:
    """(k, 2) row, column of the pixels exactly of ``colour``."""
    return np.argwhere(np.all(image == np.array(colour[:3], dtype=np.uint8), axis=-1))


def test_rgb_frames_ring_the_true_and_detected_groups_where_they_stand() -> None:
    from sim.envs.overlay import DETECTED_MARGIN_M, TRUTH_MARGIN_M, project
    from sim.recording import group_colour

    width, height = 320, 240
    env = toy_env(render_mode="rgb_array", render_size=(width, height), detector="truth")
    env.reset(seed=0)
    image = env.render()
    cameras = env._renderer.scene.camera
    # The pair stands at x = -0.5 and 0.5 around the origin: the truth's ring has radius
    # 0.5 + 0.35 m, the detection's (the truth detector: matched, so the same colour) 0.5 +
    # 0.2 m. The camera looks north over x = 0: the rings sit mid-image.
    pixels = _coloured(image, group_colour(1))
    assert len(pixels) > 150
    assert abs(pixels[:, 1].mean() - width / 2) < 3.0
    outer = PAIR_HALF_M + TRUTH_MARGIN_M
    inner = PAIR_HALF_M + DETECTED_MARGIN_M
    ends = project(np.array([[-outer, 0, 0.02], [outer, 0, 0.02]]), cameras, width, height)
    span = ends[1, 0] - ends[0, 0]
    assert pixels[:, 1].min() >= ends[0, 0] - 4 and pixels[:, 1].max() <= ends[1, 0] + 4
    assert pixels[:, 1].max() - pixels[:, 1].min() > 0.9 * span
    # Two rings: on the row through the centre, coloured pixels near both radii, each side.
    centre = project(np.array([[0.0, 0.0, 0.02]]), cameras, width, height)[0]
    row = pixels[np.abs(pixels[:, 0] - centre[1]) <= 1, 1] - centre[0]
    metre = span / (2 * outer)
    for radius in (outer, inner):
        for side in (-1, 1):
            assert np.min(np.abs(row - side * radius * metre)) <= 3, (radius, side)
    env.close()


def test_rgb_frames_draw_no_ring_once_the_group_is_gone() -> None:
    from sim.recording import group_colour

    env = SocialEnv(
        lambda *, seed: toy_pair(seed=seed, end=0.5),
        robot_start="scenario",
        task="observe",
        render_mode="rgb_array",
        detector="truth",
    )
    env.reset(seed=0)
    assert len(_coloured(env.render(), group_colour(1))) > 100
    for _ in range(11):  # past 0.5 s and the detection at 1.0 s
        env.step(np.zeros(3, dtype=np.float32))
    assert env.unwrapped._groups_now == ()
    assert len(_coloured(env.render(), group_colour(1))) == 0
    env.close()


def test_check_env_passes_with_the_render_check() -> None:
    env = gym.make("ReformSim/HRIRobotExcludedObserve-v0", render_mode="rgb_array")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # The checker makes a human-mode twin too: here, with no viewer, it says so once.
        warnings.filterwarnings("ignore", message=".*no Rerun viewer at")
        check_env(env.unwrapped)
    env.close()


def test_human_mode_without_a_viewer_or_display_warns_once_and_runs(monkeypatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    port = _free_port()  # nothing listens there
    env = toy_env(render_mode="human", viewer=f"rerun+http://127.0.0.1:{port}/proxy")
    start = time.perf_counter()
    with pytest.warns(UserWarning, match="no Rerun viewer at .* and no display"):
        env.reset(seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a second warning would fail
        for _ in range(5):
            env.step(np.zeros(3, dtype=np.float32))
        assert env.render() is None
        env.reset(seed=1)
    env.close()
    assert time.perf_counter() - start < 10.0
    with pytest.raises(ValueError, match="viewer is for render_mode='human'"):
        toy_env(viewer="rerun+http://127.0.0.1:9876/proxy")
    with pytest.raises(
        ValueError, match=r"^viewer must be a Rerun viewer.s address .* got .http://example.org.$"
    ):
        toy_env(render_mode="human", viewer="http://example.org")


def test_record_dir_saves_a_readable_recording(tmp_path: Path) -> None:
    from rerun.chunk import RrdReader

    env = toy_env(record_dir=tmp_path, episode_seconds=1.0)
    env.reset(seed=0)
    done = False
    while not done:
        *_, terminated, truncated, info = env.step(np.zeros(3, dtype=np.float32))
        done = terminated or truncated
    path = Path(info["episode"]["recording"])
    assert path.parent == tmp_path and path.exists()
    store = RrdReader(path).stream().collect()
    entities = {chunk.entity_path for chunk in store.stream()}
    assert any("people" in e for e in entities)
    assert any("groups" in e for e in entities)


def _free_port() -> int:
    import socket

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.fixture
def rerun_server(tmp_path: Path):
    """A real Rerun server (the viewer program, no window) on 127.0.0.1 saving what it
    receives; stopped at the end."""
    from listening import listening_hosts, supported

    from sim.envs.viewer import viewer_listening
    from sim.recording import stop_viewer, viewer_command

    port = _free_port()
    saved = tmp_path / "received.rrd"
    log = (tmp_path / "server.log").open("w")
    server = subprocess.Popen(
        viewer_command("--port", str(port), "--save", str(saved)),
        stdout=log,
        stderr=subprocess.STDOUT,
        preexec_fn=_dies_with_parent,  # a test process killed before teardown takes it along
    )
    url = f"rerun+http://127.0.0.1:{port}/proxy"
    try:
        for _ in range(100):
            if viewer_listening(url):
                break
            time.sleep(0.1)
        else:
            raise AssertionError(f"the rerun server did not listen on port {port}")
        if supported():
            assert listening_hosts(port) == {"127.0.0.1"}  # this machine only
        yield url, saved, server
    finally:
        stop_viewer(server)
        log.close()


def _dies_with_parent() -> None:
    """In the child before it runs: on Linux, SIGTERM when the process that started it dies."""
    if sys.platform.startswith("linux"):
        import ctypes

        pr_set_pdeathsig = 1
        ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, signal.SIGTERM)


def _written_out(path: Path, *, quiet_s: float = 1.0, limit_s: float = 30.0) -> None:
    """Waits until the server's file has not grown for ``quiet_s`` seconds (at most
    ``limit_s``): the client's close returns once the data are sent, not once they are saved."""
    deadline = time.monotonic() + limit_s
    size, since = -1, time.monotonic()
    while time.monotonic() < deadline:
        now = path.stat().st_size if path.exists() else -1
        if now != size:
            size, since = now, time.monotonic()
        elif now >= 0 and time.monotonic() - since >= quiet_s:
            return
        time.sleep(0.1)


def _stores(path: Path) -> dict[str, list[tuple]]:
    """Recording id -> everything its recording holds, minus row ids, in a canonical order."""
    from rerun.chunk import RrdReader

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a file a server wrote has no footer: read it whole
        reader = RrdReader(path)
        out = {}
        for store in reader.recordings():
            rows = []
            for chunk in reader.stream(store=store):
                batch = chunk.to_record_batch()
                keep = [n for n in batch.schema.names if not n.startswith("rerun.controls")]
                rows.append((str(chunk.entity_path), repr(batch.select(keep).to_pydict())))
            out[store.recording_id] = sorted(rows)
    return out


def test_human_mode_streams_each_episode_to_the_viewer(rerun_server) -> None:
    from recorded_layout import assert_every_panel_holds_data

    from sim.recording import recording_id

    url, saved, server = rerun_server
    env = toy_env(
        render_mode="human", viewer=url, detector="truth", task="observe", episode_seconds=1.0
    )
    names = []
    for _ in range(2):  # one seed twice: the same content in two recordings
        env.reset(seed=0, options={"scenario_seed": 4})
        names.append(f"toy-pair-4-{env.unwrapped._episodes}")
        assert env.render() is None
        _run_out(env)
    env.close()
    from sim.recording import stop_viewer

    _written_out(saved)  # the server writes what it received after the client is done
    stop_viewer(server)  # all it received is in the file
    stores = _stores(saved)
    ids = [recording_id(name, seed=4) for name in names]
    assert set(ids) <= set(stores)
    first, second = (stores[i] for i in ids)
    assert f"[['{names[0]}']]" in dict(first)["/__properties"]
    # The episodes' names differ; everything they hold is the same.
    assert [r for r in first if r[0] != "/__properties"] == [
        r for r in second if r[0] != "/__properties"
    ]
    entities = {e for e, _ in first}
    assert {"/world/people", "/world/robot", "/world/groups/truth"} <= entities
    assert "/world/groups/truth-detector" in entities and "/world/room/floor" in entities
    people = [rows for e, rows in first if e == "/world/people"]
    assert len(people) == 11  # the reset and ten steps of 0.1 s: one log each
    rings = [rows for e, rows in first if e == "/world/groups/truth"]
    assert all("'1,2'" in rows for rows in rings)  # the pair, ringed at every step
    assert {f"'frame': [{k}]" for k in range(11)} == {r.split(",")[0][1:] for r in people}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no footer: read whole
        shown = assert_every_panel_holds_data(saved, ids[0])
    assert [p.kind for p in shown] == ["3D"]


def _run_out(env: SocialEnv) -> dict:
    """Steps ``env`` (reset) standing still to the end of its episode; the last info."""
    done = False
    while not done:
        *_, terminated, truncated, info = env.step(np.zeros(3, dtype=np.float32))
        done = terminated or truncated
    return info


# A lab's own detectors, in a module of their own (not installed): SocialEnv(detector=
# "envplugin:make") imports it from sys.path.
ENV_PLUGIN = '''
def make():
    return Alone()


class Alone:
    """Everyone alone."""

    def predict(self, frames):
        return [tuple((int(i),) for i in frame.ids) for frame in frames]


class Forgets:
    """Puts the frame's first agent in a group, forgets the others."""

    def predict(self, frames):
        return [((int(frame.ids[0]),),) for frame in frames]


class Raises:
    def predict(self, frames):
        raise RuntimeError("no model loaded")
'''


@pytest.fixture
def env_plugin(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    folder = tmp_path / "plugin"
    folder.mkdir()
    (folder / "envplugin.py").write_text(ENV_PLUGIN)
    monkeypatch.syspath_prepend(str(folder))
    yield "envplugin"
    sys.modules.pop("envplugin", None)


def test_a_plugin_detector_by_its_module_and_factory(env_plugin: str, tmp_path: Path) -> None:
    env = toy_env(
        detector=f"{env_plugin}:make", task="observe", episode_seconds=1.0, record_dir=tmp_path
    )
    assert env.detector_name == "envplugin:make"
    _, info = env.reset(seed=0)
    assert sorted(info["detected_groups"]) == [(0,), (1,), (2,)]
    assert info["metrics"]["f1"] == 0.0  # the pair stands together; everyone alone misses it
    episode = _run_out(env)["episode"]
    assert episode["detector"] == "envplugin:make" and episode["f1"] == 0.0
    assert Path(episode["recording"]).is_file()


def test_a_registered_detector_by_its_name() -> None:
    env = toy_env(detector="majority")
    assert env.detector_name == "majority"
    _, info = env.reset(seed=0)
    assert sorted(info["detected_groups"]) == [(0,), (1,), (2,)]


@pytest.mark.parametrize(
    ("factory", "message"),
    [
        (
            "Forgets",
            r"^envplugin:Forgets: detector output for frame 0 \(toy-pair-\d+ t=0 s\): person \d "
            r"is in no group; a prediction must be a full partition",
        ),
        (
            "Raises",
            r"^envplugin:Raises: detector raised RuntimeError on frame 0 \(toy-pair-\d+ t=0 s\): "
            r"no model loaded$",
        ),
    ],
    ids=["forgets-people", "raises"],
)
def test_a_broken_plugin_detector_is_one_line_naming_it(
    env_plugin: str, factory: str, message: str
) -> None:
    env = toy_env(detector=f"{env_plugin}:{factory}")
    with pytest.raises(DetectorError, match=message):
        env.reset(seed=0)


@pytest.mark.parametrize(
    ("name", "what"), [("gcff-own", "a dataset"), ("gcff-tuned", "training frames")]
)
def test_a_catalogued_detector_that_needs_more_is_refused_when_the_env_is_made(
    name: str, what: str
) -> None:
    with pytest.raises(
        DetectorError, match=rf"^detector '{name}' must be given {what} before it predicts"
    ):
        toy_env(detector=name)


def test_a_plugin_that_is_not_there_fails_when_the_env_is_made(env_plugin: str) -> None:
    with pytest.raises(
        DetectorError, match=r"^detector 'envplugin:nothing': module 'envplugin' has no attribute"
    ):
        toy_env(detector=f"{env_plugin}:nothing")


def test_the_truth_detector_s_episode_is_recorded(tmp_path: Path) -> None:
    from rerun.chunk import RrdReader

    env = toy_env(detector="truth", task="observe", episode_seconds=1.0, record_dir=tmp_path)
    env.reset(seed=0)
    path = Path(_run_out(env)["episode"]["recording"])
    entities = {str(chunk.entity_path) for chunk in RrdReader(path).stream()}
    # The recording's ground truth and the truth detector's detections, side by side.
    assert {"/world/groups/truth/members", "/world/groups/truth-detector/members"} <= entities
    # The detected pair is matched to the true pair: one colour class in both trees.
    classes = {}
    for chunk in RrdReader(path).stream():
        tree = str(chunk.entity_path)
        if tree.endswith("/members") and not chunk.is_static:
            batch = chunk.to_record_batch().to_pydict()
            for ids, labels in zip(batch["person_id"], batch["Cylinders3D:class_ids"], strict=True):
                classes.setdefault(tree, set()).update(
                    (i, c) for i, c in zip(ids, labels, strict=True) if i in (1, 2)
                )
    assert classes["/world/groups/truth/members"] == {(1, 1), (2, 1)}
    assert classes["/world/groups/truth-detector/members"] == {(1, 1), (2, 1)}


# ---------------------------------------------------------------------------------------------
# The task's geometry (hand-worked scenes)


def test_o_space_of_a_circle_a_facing_pair_and_an_open_pair() -> None:
    angles = np.array([0.3, 2.2, 4.1])
    ring = 0.8 * np.stack([np.cos(angles), np.sin(angles)], axis=1) + [1.0, 2.0]
    circle = estimate_o_space(ring, angles + math.pi)
    np.testing.assert_allclose(circle.centre, [1.0, 2.0], atol=1e-9)
    assert circle.radius == pytest.approx(0.8)
    # Two people facing each other, both turned 0.2 rad the same way: their facing lines cross
    # the bisector 0.1 m either side of the midpoint, which is the centre.
    pair = estimate_o_space([[-0.5, 0.0], [0.5, 0.0]], [0.2, math.pi + 0.2])
    np.testing.assert_allclose(pair.centre, [0.0, 0.0], atol=1e-9)
    # Facings that disagree (crossings 0.68 m apart, more than half the pair's distance): the
    # midpoint too.
    pair = estimate_o_space([[-0.5, 0.0], [0.5, 0.0]], [0.9, math.pi - 0.1])
    np.testing.assert_allclose(pair.centre, [0.0, 0.0], atol=1e-9)
    # Two of an equilateral triangle of side 1, facing its centre: the centre, 0.29 m off their
    # midpoint toward the empty corner.
    a, b = np.array([-0.5, 0.0]), np.array([0.5, 0.0])
    centre = np.array([0.0, -0.5 / math.sqrt(3.0)])
    yaws = [math.atan2(*(centre - p)[::-1]) for p in (a, b)]
    open_pair = estimate_o_space([a, b], yaws)
    np.testing.assert_allclose(open_pair.centre, centre, atol=1e-9)


def test_joining_place_takes_a_gap_clear_of_everyone() -> None:
    circle = OSpace(centre=[0.0, 0.0], radius=0.6)
    members = 0.6 * np.array([[1.0, 0.0], [-0.5, math.sqrt(0.75)], [-0.5, -math.sqrt(0.75)]])
    place = joining_place(circle, members, [0.0, -3.0], clearance=0.63, max_offset=0.3)
    # The gap facing the robot is between the members at -120 and 0 degrees: bisector -60.
    assert math.degrees(math.atan2(place[1], place[0])) == pytest.approx(-60.0)
    assert np.min(np.hypot(*(members - place).T)) >= 0.63
    assert 0.6 <= np.hypot(*place) <= 0.9
    # A wall north of the pair's gap sends the robot to the other side.
    pair = np.array([[-0.5, 0.0], [0.5, 0.0]])
    walled = joining_place(
        OSpace(centre=[0.0, 0.0], radius=0.5),
        pair,
        [0.0, 2.0],
        clearance=0.63,
        max_offset=0.3,
        bounds=(-3.0, 3.0, -3.0, 0.2),
    )
    assert walled[1] < 0.0


def test_assessment_and_terms_by_hand() -> None:
    task = JoinTask()
    circle = OSpace(centre=[0.0, 0.0], radius=0.5)
    people = np.array([[-0.5, 0.0], [0.5, 0.0]])

    def robot_at(position: list[float], yaw: float):
        return assess(
            task,
            robot_position=position,
            robot_yaw=yaw,
            people_ids=[1, 2],
            people_position=people,
            o_space=circle,
        )

    placed = robot_at([0.0, -0.6], math.pi / 2)
    assert placed.placed and placed.distance_to_circle == pytest.approx(0.1)
    assert placed.facing_error == pytest.approx(0.0)
    turned = robot_at([0.0, -0.6], 0.0)
    assert turned.on_circle and not turned.facing and not turned.placed
    inside = robot_at([0.0, -0.1], math.pi / 2)
    assert inside.in_o_space and inside.intruded == (1, 2)
    terms = reward_terms(task, turned, placed, joined=True)
    assert terms["progress"] == pytest.approx(0.0)
    assert terms["facing"] == pytest.approx(task.facing_weight)
    assert terms["success"] == task.success_reward
    assert sum(terms.values()) == pytest.approx(
        task.facing_weight - task.time_penalty + task.success_reward
    )
    with pytest.raises(ValueError, match="JoinTask.hold must be finite and >= 0, got -1"):
        JoinTask(hold=-1)


# ---------------------------------------------------------------------------------------------
# The scripted baseline and its command


def test_the_baseline_joins_the_toy_pair_from_a_random_start() -> None:
    env = toy_env(robot_start="random")
    policy = JoinPolicy(task=env.task, action_scale=env.action_scale, room=env.room)
    for seed in range(3):
        observation, info = env.reset(seed=seed)
        policy.reset()
        done = False
        while not done:
            observation, _, terminated, truncated, info = env.step(policy(observation))
            done = terminated or truncated
        assert info["is_success"], f"seed {seed}: {info['episode']}"


def test_evaluate_policy_reports_seeded_episodes() -> None:
    result = evaluate_policy("ReformSim/HRIRobotExcluded-v0", episodes=2, seed=4)
    assert [e.seed for e in result.episodes] == [4, 5]
    assert result.detector == "gcff"
    data = result.to_json()
    assert data["episodes"] == 2 and 0.0 <= data["success_rate"] <= 1.0
    with pytest.raises(ValueError, match="no joining task"):
        evaluate_policy("ReformSim/HRIPassingObserve-v0", episodes=1)
    with pytest.raises(ValueError, match="episodes must be a positive int"):
        evaluate_policy("ReformSim/HRIPassing-v0", episodes=0)


class _SlowFirstStep:
    """The scripted baseline, whose first step takes ``seconds`` (as the first step of a fresh
    install compiles the motion kernels)."""

    def __init__(self, policy: JoinPolicy, seconds: float) -> None:
        self.policy, self.seconds = policy, seconds

    def reset(self) -> None:
        self.policy.reset()

    def __call__(self, observation):
        time.sleep(self.seconds)
        self.seconds = 0.0
        return self.policy(observation)


def test_evaluate_policy_redraws_its_bar_while_an_episode_runs(capsys) -> None:
    env = gym.make("ReformSim/HRIRobotExcluded-v0", disable_env_checker=True)
    base = env.unwrapped
    policy = JoinPolicy(task=base.task, action_scale=base.action_scale, room=base.room)
    env.close()
    evaluate_policy(
        "ReformSim/HRIRobotExcluded-v0",
        episodes=1,
        policy=_SlowFirstStep(policy, 2.5 * TICK_S),
        progress=True,
    )
    before_the_episode_ends = capsys.readouterr().err.split("\r")
    assert sum("0/1" in draw for draw in before_the_episode_ends) >= 3  # drawn, redrawn twice


def test_policy_evaluate_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from sim.cli import main

    out = tmp_path / "baseline.json"
    code = main(
        [
            "policy",
            "evaluate",
            "--env",
            "ReformSim/HRIRobotExcluded-v0",
            "--episodes",
            "2",
            "--seed",
            "4",
            "--json",
            str(out),
        ]
    )
    assert code == 0
    printed = capsys.readouterr().out
    assert "success rate" in printed and "ReformSim/HRIRobotExcluded-v0" in printed
    data = json.loads(out.read_text())
    assert data["episodes"] == 2 and len(data["per_episode"]) == 2
    assert main(["policy", "evaluate", "--env", "ReformSim/Nope-v0", "--episodes", "1"]) == 2
    assert main(["policy", "evaluate", "--env", "CartPole-v1", "--episodes", "1"]) == 2
    assert "got an environment of another task" in capsys.readouterr().err
    argv = ["policy", "evaluate", "--env", "ReformSim/Mingle-v0", "--episodes", "1", "--seed", "-5"]
    with pytest.raises(SystemExit) as stopped:  # refused as the command line is read
        main(argv)
    assert stopped.value.code == 2
    assert "argument --seed: expected a whole number from 0 to" in capsys.readouterr().err


def test_detectors_truth_gcff_and_a_reform_model_file(tmp_path: Path) -> None:
    from toy_scenes import toy_frames

    from reform import Reform
    from reform.persistence import save_model

    truth = toy_env(detector="truth")
    _, info = truth.reset(seed=0)
    assert truth.detector_name == "truth"
    assert info["detected_groups"] == ((1, 2), (0,))  # the pair (the robot alone) it sees
    assert info["metrics"]["f1"] == 1.0
    assert toy_env(detector="gcff").detector_name == "gcff"
    path = tmp_path / "reform.skops"
    save_model(Reform().fit(toy_frames(0, 20)), path)
    reform = toy_env(model=path)
    assert reform.detector_name == "reform"
    _, info = reform.reset(seed=0)
    assert sorted(m for g in info["detected_groups"] for m in g) == [0, 1, 2]
    with pytest.raises(
        DetectorError,
        match=r"^detector must be 'truth', a detector's name \((\S+, )*gcff, (\S+, )*majority, "
        r"(\S+, )*reform(, \S+)*\), a plugin's package\.module:factory or an object with "
        r"predict\(frames\), got 'oracle'$",
    ):
        toy_env(detector="oracle")
    with pytest.raises(DetectorError, match=r"^detector 'reform' needs the option model="):
        toy_env(detector="reform")
    with pytest.raises(ValueError, match="give a detector or a model file, not both"):
        toy_env(detector="truth", model=path)
