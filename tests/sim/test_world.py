"""The world: Frames read from MuJoCo, scripts and intents, presence, robot commands, streaming."""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping

import mujoco
import numpy as np
import pytest

import scenarios
from reform import Frame, FrameBlock, wrap_angle
from sim import Intent, RobotCommand, RobotSpec, SceneSpec, World
from sim.episode import scene_spec
from sim.scene import PersonSpec
from sim.world import yaw_from_quat


def _circle(n: int, radius: float = 1.6, *, robot: bool = True) -> SceneSpec:
    people = [
        PersonSpec(
            id=i + 1,
            position=(
                radius * math.cos(2 * math.pi * i / n),
                radius * math.sin(2 * math.pi * i / n),
            ),
            yaw=2 * math.pi * i / n + math.pi,
        )
        for i in range(n)
    ]
    return SceneSpec(people=people, robot=RobotSpec(id=0) if robot else None, room=(5.0, 5.0))


class _Constant:
    """A script whose intents and groups are the same at every time."""

    def __init__(self, *, intents: Mapping[int, object] | None = None, groups: object = None):
        self._intents = {} if intents is None else intents
        self._groups = groups

    def intents(self, t: float) -> Mapping[int, object]:
        return self._intents

    def groups(self, t: float) -> object:
        return self._groups


class Shuffle:
    """Everyone walks to a new random spot every 3 s; pairs are declared as groups."""

    def __init__(self, spec: SceneSpec, seed: int) -> None:
        rng = np.random.default_rng(seed)
        self.ids = [p.id for p in spec.people]
        self.spots = rng.uniform(-1.8, 1.8, size=(100, len(self.ids), 2))

    def intents(self, t: float) -> Mapping[int, Intent]:
        k = int(t // 3.0) % len(self.spots)
        return {
            pid: Intent(goal=tuple(self.spots[k, i]), gaze_agent=self.ids[i - 1])
            for i, pid in enumerate(self.ids)
        }

    def groups(self, t: float) -> tuple[tuple[int, ...], ...]:
        return ((self.ids[0], self.ids[1]), (self.ids[2], self.ids[3], 0))


def test_frames_are_read_from_mujoco_kinematics() -> None:
    spec = _circle(4)
    world = World(spec, seed=0, script=Shuffle(spec, 1))
    frame = next(iter(world.run(1.0, rate=1.0)))
    data, model = world.data, world.model
    torso = model.body("person2/torso").id
    head = model.body("person2/head").id
    row = frame.index_of(2)
    np.testing.assert_array_equal(frame.position[row], data.xpos[torso, :2])
    assert frame.yaw[row] == yaw_from_quat(data.xquat[torso])
    np.testing.assert_array_equal(frame.head_position[row], data.xpos[head, :2])
    # The head sits 0.03 m in front of the torso axis (asset geometry), turned with the body.
    offset = frame.head_position[row] - frame.position[row]
    yaw = frame.yaw[row]
    np.testing.assert_allclose(offset, 0.03 * np.array([math.cos(yaw), math.sin(yaw)]), atol=1e-9)
    # The head yaw is the body yaw plus the neck joint.
    neck = data.qpos[model.jnt_qposadr[model.joint("person2/neck_yaw").id]]
    assert wrap_angle(frame.head_yaw[row] - frame.yaw[row]) == pytest.approx(neck, abs=1e-9)


def test_frame_layout_kinds_groups_time() -> None:
    spec = _circle(4)
    world = World(spec, seed=0, script=Shuffle(spec, 1), sequence="episode-3")
    frames = list(world.run(2.0, rate=2.0))
    assert [f.time for f in frames] == pytest.approx([0.5, 1.0, 1.5, 2.0])
    frame = frames[-1]
    assert isinstance(frame, Frame)
    assert frame.ids.tolist() == [1, 2, 3, 4, 0]
    assert frame.kinds == ("human",) * 4 + ("robot",)
    assert frame.groups == ((1, 2), (3, 4, 0))
    assert frame.sequence == "episode-3"
    assert world.time == pytest.approx(2.0)


def test_same_seed_same_frames_other_seed_other_sway() -> None:
    spec = _circle(5)
    runs = [
        list(World(spec, seed=s, script=Shuffle(spec, 2)).run(4.0, rate=10.0)) for s in (7, 7, 8)
    ]
    assert all(a == b for a, b in zip(runs[0], runs[1], strict=True))
    assert any(a != b for a, b in zip(runs[0], runs[2], strict=True))


def test_rollout_blocks_equal_run_frames() -> None:
    spec = _circle(5)
    by_frame = list(World(spec, seed=3, script=Shuffle(spec, 4)).run(6.0, rate=20.0))
    world = World(spec, seed=3, script=Shuffle(spec, 4))
    blocks = list(world.rollout(6.0, rate=20.0, block_rows=37))
    assert all(isinstance(b, FrameBlock) and len(b) <= 37 for b in blocks)
    by_block = [f for block in blocks for f in block.frames()]
    assert len(by_block) == len(by_frame) == 120
    assert all(a == b for a, b in zip(by_frame, by_block, strict=True))
    # After a block, the world's data is at the block's last time.
    assert world.frame() == by_block[-1]


def test_rollout_streams_a_generator() -> None:
    world = World(_circle(3), seed=0)
    stream = world.rollout(3600.0, rate=100.0, block_rows=200)
    assert isinstance(stream, Iterator)
    first = next(stream)
    assert len(first) == 200
    assert first.position.shape == (200, 4, 2)
    assert world.time == pytest.approx(2.0)
    stream.close()


def test_people_leave_and_enter() -> None:
    spec = _circle(3)

    class Leave:
        def intents(self, t: float) -> Mapping[int, Intent]:
            if 1.0 <= t < 2.0:
                return {2: Intent(present=False)}
            if t >= 2.0:
                return {2: Intent(present=True, appear_at=(0.0, -2.0))}
            return {}

        def groups(self, t: float) -> tuple[tuple[int, ...], ...]:
            return ((1, 2, 3),)

    frames = {round(f.time, 2): f for f in World(spec, seed=0, script=Leave()).run(3.0, rate=10.0)}
    assert 2 in frames[0.5].ids
    assert 2 not in frames[1.5].ids
    assert frames[1.5].groups == ((1, 3),)
    back = frames[2.5]
    assert 2 in back.ids
    np.testing.assert_allclose(back.position[back.index_of(2)], (0.0, -2.0), atol=0.05)


def test_robot_follows_velocity_commands_within_limits() -> None:
    spec = SceneSpec(robot=RobotSpec(id=0, position=(-1.5, 0.0)), room=(6.0, 6.0))
    world = World(spec, seed=0)
    world.command_robot(RobotCommand(speed=0.5, pan_rate=10.0))
    world.step(200)
    frame = world.frame()
    x, y = frame.position[0]
    # 0.8 m/s^2 to reach 0.5 m/s: 0.3125 m lost to accelerating over 2 s (kinematics).
    assert x == pytest.approx(-1.5 + 0.5 * 2.0 - 0.5 * 0.5**2 / 0.8, abs=0.02)
    assert y == pytest.approx(0.0, abs=1e-9)
    pan = wrap_angle(frame.head_yaw[0] - frame.yaw[0])
    assert pan == pytest.approx(math.radians(100.0), abs=1e-9)  # clipped at the pan limit
    world.command_robot(RobotCommand(turn_rate=math.pi / 4, pan_rate=-1.0, tilt_rate=1.0))
    world.step(100)
    frame = world.frame()
    assert frame.yaw[0] == pytest.approx(math.pi / 4, abs=1e-6)
    tilt = world.data.qpos[world.model.jnt_qposadr[world.model.joint("robot/head_tilt").id]]
    assert tilt == pytest.approx(math.radians(30.0))
    world.command_robot(None)
    world.set_intents({0: Intent(goal=(1.0, 1.0))})
    world.step(500)
    np.testing.assert_allclose(world.frame().position[0], (1.0, 1.0), atol=0.05)


def test_set_groups_without_script() -> None:
    world = World(_circle(3), seed=0)
    assert world.frame().groups is None
    world.set_groups([[1, 2]])
    assert world.frame().groups == ((1, 2),)


@pytest.mark.parametrize(
    ("intents", "message"),
    [
        ({1: Intent(goal=(3.0, 0.0))}, r"intent of human 1 at t=0 s: goal \(3, 0\) is outside"),
        ({9: Intent()}, r"intents at t=0 s name agent 9, who is not in the scene"),
        ({1: Intent(gaze_agent=1)}, r"gaze_agent must be another agent"),
        ({1: Intent(face_agent=42)}, r"face_agent 42 is not in the scene"),
        ({0: Intent(present=False)}, r"the robot cannot leave the scene"),
        ({1: "walk"}, r"agent 1 must get an Intent, got str"),
    ],
)
def test_bad_intents_fail_before_simulating(intents, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        World(_circle(3), seed=0, script=_Constant(intents=intents))


@pytest.mark.parametrize(
    ("groups", "message"),
    [
        (
            ((1, 2), (2, 3)),
            r"groups at t=0 s must be disjoint, agent 2 appears twice \(groups\[1\]\)",
        ),
        (((1, 2), ()), r"groups\[1\] at t=0 s is empty"),
        (
            ((1, 9),),
            r"groups\[0\] at t=0 s names agent 9, who is not in the scene \(ids \[0, 1, 2, 3\]\)",
        ),
    ],
)
def test_bad_groups_fail(groups, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        World(_circle(3), seed=0, script=_Constant(groups=groups))


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Intent(speed=0.0), r"Intent.speed must be positive"),
        (lambda: Intent(goal=(1.0,)), r"Intent.goal must be a finite \(x, y\)"),
        (lambda: Intent(face_yaw=1.0, face_agent=2), r"at most one of face_yaw, face_point"),
        (lambda: Intent(gaze_point=(0, 0), gaze_agent=2), r"at most one of gaze_point"),
        (lambda: RobotCommand(speed=float("inf")), r"RobotCommand.speed must be finite"),
    ],
)
def test_bad_records_fail(make, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        make()


def test_bad_rates_fail() -> None:
    world = World(_circle(2), seed=0)
    with pytest.raises(ValueError, match=r"1 / rate must be a whole number of control steps"):
        next(world.run(1.0, rate=30.0))
    with pytest.raises(ValueError, match=r"duration must be a whole number of output periods"):
        next(world.run(1.05, rate=10.0))
    with pytest.raises(ValueError, match=r"dt must be within \(0, 0.1\]"):
        World(_circle(2), seed=0, dt=-0.01)
    with pytest.raises(ValueError, match=r"script must have intents\(t\) and groups\(t\)"):
        World(_circle(2), seed=0, script=object())
    with pytest.raises(ValueError, match=r"n_steps must be a positive int"):
        world.step(0)


def test_a_prebuilt_model_is_reused() -> None:
    from sim import build_scene

    spec = _circle(3)
    model = build_scene(spec)
    world = World(spec, seed=0, model=model)
    assert world.model is model
    other = SceneSpec(people=[PersonSpec(id=5, position=(0.0, 0.0))])
    with pytest.raises(ValueError, match=r"model does not match the spec: it has no body"):
        World(other, seed=0, model=model)


def test_data_is_current_while_a_frame_is_handled() -> None:
    spec = _circle(4)
    world = World(spec, seed=0, script=Shuffle(spec, 0))
    for frame in world.run(1.0, rate=5.0):
        torso = world.model.body("person1/torso").id
        np.testing.assert_array_equal(world.data.xpos[torso, :2], frame.position[0])
        assert world.data.time == pytest.approx(frame.time)
    assert isinstance(world.model, mujoco.MjModel)


def test_long_rollouts_stream_in_constant_memory() -> None:
    import tracemalloc

    def peak(seconds: float) -> int:
        world = World(_circle(6), seed=0, script=Shuffle(_circle(6), 0))
        tracemalloc.start()
        rows = sum(len(block) for block in world.rollout(seconds, rate=100.0, block_rows=250))
        _, top = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        assert rows == round(seconds * 100)
        return top

    short, long = peak(30.0), peak(300.0)
    # 10x the rows (30,000 rows x 7 agents of poses would be ~10 MiB), about the same peak.
    assert long < 1.5 * short + 2**20


def test_native_and_batched_kinematics_agree() -> None:
    from sim import _native

    assert _native.NATIVE  # the MuJoCo library ships with the mujoco package
    spec = _circle(5)
    blocks = {
        threads: list(World(spec, seed=2, script=Shuffle(spec, 3)).rollout(3.0, threads=threads))
        for threads in (1, 2)
    }
    for a, b in zip(blocks[1], blocks[2], strict=True):
        for name in ("time", "present", "position", "yaw", "head_position", "head_yaw"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert a.groups == b.groups


def test_a_commanded_robot_stops_at_a_person_instead_of_shoving() -> None:
    spec = SceneSpec(
        people=[PersonSpec(id=1, position=(0.0, 0.0))],
        robot=RobotSpec(id=0, position=(-1.5, 0.0)),
        room=(5.0, 5.0),
    )
    world = World(spec, seed=0)
    world.command_robot(RobotCommand(speed=0.8))
    world.step(500)
    frame = world.frame()
    person, robot = frame.position[frame.index_of(1)], frame.position[frame.index_of(0)]
    assert np.linalg.norm(person) < 0.02  # idle sway only
    gap = np.linalg.norm(person - robot) - world.radii.sum()
    assert 0.0 <= gap < 0.1


def test_a_world_settles_its_groups_by_the_ground_truth_rule():
    """With ``truth=``, the world's groups are the rule's (a group starts when its members have
    arrived), the same on the fast path and frame by frame; without it, the script's."""
    made = scenarios.make("hri-conversation", seed=2, talk_duration=5.0)
    spec = scene_spec(made.stage, name=made.name)

    def world(truth):
        return World(spec, seed=0, script=made.timeline, truth=truth)

    declared = [f.groups for f in world(None).run(12.0, rate=2.0)]
    frames = [f.groups for f in world(made.ground_truth()).run(12.0, rate=2.0)]
    blocks = [
        g
        for b in world(made.ground_truth()).rollout(12.0, rate=2.0, block_rows=5)
        for g in b.groups
    ]
    assert frames == [tuple(g) for g in blocks]
    walking_up = [k for k, (d, s) in enumerate(zip(declared, frames, strict=True)) if d and not s]
    assert walking_up and walking_up[0] == 0  # planned from the start, formed only on arrival
    assert any(len(g) == 3 for groups in frames for g in groups)
    other = scenarios.make("hri-passing", seed=0, people=3).ground_truth()
    with pytest.raises(ValueError, match=r"truth must settle the groups over this world's agents"):
        world(other)
