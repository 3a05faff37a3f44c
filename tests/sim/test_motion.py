"""Motion primitives, checked on MuJoCo's output at 100 Hz: limits, personal space, head, sway."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import numpy as np
import pytest

from reform import wrap_angle
from sim import (
    PERSON_LIMITS,
    Intent,
    MotionLimits,
    PersonSpec,
    RobotCommand,
    RobotSpec,
    SceneSpec,
    World,
)
from sim.motion import ROBOT_LIMITS, SWAY_POS_M, SWAY_YAW_RAD

# Idle sway moves the rendered torso by at most SWAY_POS_M per axis at a few tenths of a hertz
# (asset-independent motion constants): a velocity of at most ~0.04 m/s on top of walking.
SWAY_SPEED_M_S = 2 * math.pi * 0.45 * SWAY_POS_M * math.sqrt(2)


def _walk(goal: tuple[float, float], *, gaze=None, speed: float = 1.2):
    class Script:
        def intents(self, t: float) -> Mapping[int, Intent]:
            return {1: Intent(goal=goal, speed=speed, gaze_point=gaze)}

        def groups(self, t: float):
            return None

    return Script()


def _poses(world: World, seconds: float):
    blocks = list(world.rollout(seconds, rate=100.0))
    cat = {
        name: np.concatenate([getattr(b, name) for b in blocks])
        for name in ("time", "present", "position", "yaw", "head_position", "head_yaw")
    }
    return cat


def test_walking_to_a_target_at_human_speed_within_limits() -> None:
    spec = SceneSpec(people=[PersonSpec(id=1, position=(-2.0, 0.0), yaw=math.pi / 2)], room=(6, 6))
    world = World(spec, seed=0, script=_walk((2.0, 0.5)))
    poses = _poses(world, 6.0)
    xy = poses["position"][:, 0]
    velocity = np.diff(xy, axis=0) / 0.01
    speed = np.hypot(velocity[:, 0], velocity[:, 1])
    assert speed.max() <= PERSON_LIMITS.max_speed + SWAY_SPEED_M_S
    assert speed.max() >= 1.15  # reaches the preferred 1.2 m/s on a 4 m walk
    np.testing.assert_allclose(xy[-1], (2.0, 0.5), atol=0.04)
    # Bounded acceleration, measured over 0.1 s windows (sway adds a little).
    v10 = (xy[10:] - xy[:-10]) / 0.1
    accel = np.hypot(*(np.diff(v10[::10], axis=0) / 0.1).T)
    assert accel.max() <= PERSON_LIMITS.max_accel + 0.15
    # The body turned from facing north to the walking direction at a bounded rate.
    turn = np.abs(wrap_angle(np.diff(poses["yaw"][:, 0]))) / 0.01
    assert turn.max() <= PERSON_LIMITS.max_turn_rate + 0.1
    walking = speed > 1.0
    heading = np.arctan2(velocity[:, 1], velocity[:, 0])
    assert np.all(np.abs(wrap_angle(heading[walking] - poses["yaw"][1:, 0][walking])) < 0.2)


def test_head_turns_toward_the_gaze_within_70_degrees_and_the_body_follows() -> None:
    spec = SceneSpec(people=[PersonSpec(id=1, position=(0.0, 0.0), yaw=0.0)])
    # Gaze 40 degrees to the left: the head alone turns.
    world = World(spec, seed=0, script=_walk((0.0, 0.0), gaze=(math.cos(0.7), math.sin(0.7))))
    poses = _poses(world, 2.0)
    assert poses["head_yaw"][-1, 0] == pytest.approx(0.7, abs=SWAY_YAW_RAD + 0.01)
    assert abs(poses["yaw"][-1, 0]) < SWAY_YAW_RAD + 0.01
    # Gaze straight behind: the head stops at 70 degrees and the body turns the rest.
    world = World(spec, seed=0, script=_walk((0.0, 0.0), gaze=(-1.0, 0.01)))
    poses = _poses(world, 4.0)
    relative = np.abs(wrap_angle(poses["head_yaw"][:, 0] - poses["yaw"][:, 0]))
    assert relative.max() <= math.radians(70.0) + 1e-9
    assert relative.max() == pytest.approx(math.radians(70.0), abs=1e-6)
    assert abs(wrap_angle(poses["head_yaw"][-1, 0] - math.pi)) < SWAY_YAW_RAD + 0.02
    assert abs(wrap_angle(poses["yaw"][-1, 0] - (math.pi - math.radians(70)))) < 0.05


def test_standing_people_sway_a_little() -> None:
    spec = SceneSpec(people=[PersonSpec(id=1, position=(0.0, 0.0))])
    poses = _poses(World(spec, seed=5), 20.0)
    xy = poses["position"][:, 0]
    spread = np.abs(xy).max(axis=0)
    assert np.all(spread > 0.002)
    assert np.all(spread <= SWAY_POS_M + 1e-12)
    assert np.abs(poses["yaw"][:, 0]).max() <= SWAY_YAW_RAD + 1e-12


class Crowd:
    """Many people sent again and again to a handful of shared targets, looking at each other."""

    def __init__(self, ids: list[int], seed: int, targets: np.ndarray) -> None:
        rng = np.random.default_rng(seed)
        self.ids = ids
        self.choice = rng.integers(0, len(targets), size=(200, len(ids)))
        self.speed = rng.uniform(1.0, 1.5, size=(200, len(ids)))
        self.targets = targets
        self.gaze = rng.permutation(ids)

    def intents(self, t: float) -> Mapping[int, Intent]:
        k = int(t // 4.0)
        return {
            pid: Intent(
                goal=tuple(self.targets[self.choice[k, i]]),
                speed=float(self.speed[k, i]),
                gaze_agent=int(self.gaze[i]) if self.gaze[i] != pid else None,
            )
            for i, pid in enumerate(self.ids)
        }

    def groups(self, t: float):
        return None


def _min_clearance(poses, radii: np.ndarray) -> float:
    """Smallest (distance - r_i - r_j) over every frame and pair of present agents, metres."""
    xy = poses["position"]
    gap = np.linalg.norm(xy[:, :, None, :] - xy[:, None, :, :], axis=-1)
    gap -= radii[None, :, None] + radii[None, None, :]
    present = poses["present"]
    both = present[:, :, None] & present[:, None, :]
    n = radii.size
    both &= ~np.eye(n, dtype=bool)[None]
    return float(gap[both].min())


@pytest.mark.parametrize("seed", [0, 1])
def test_people_and_robot_never_interpenetrate(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    n = 20
    grid = [(x, y) for x in np.linspace(-2.0, 2.0, 5) for y in np.linspace(-2.0, 1.0, 4)]
    people = [
        PersonSpec(
            id=i + 1,
            position=grid[i],
            yaw=float(rng.uniform(-math.pi, math.pi)),
            width=float(rng.uniform(0.35, 0.5)),
        )
        for i in range(n)
    ]
    spec = SceneSpec(people=people, robot=RobotSpec(id=0, position=(0.0, 2.0)), room=(5.0, 5.0))
    targets = np.array([[0.0, 0.0], [1.5, 1.5], [-1.5, -1.5], [2.0, -2.0]])
    world = World(spec, seed=seed, script=Crowd([p.id for p in people], seed, targets))
    world.command_robot(RobotCommand(speed=0.8, turn_rate=0.6))
    worst = math.inf
    moved = 0.0
    for block in world.rollout(90.0, rate=100.0):
        poses = {"position": block.position, "present": block.present}
        worst = min(worst, _min_clearance(poses, world.radii))
        moved += float(np.abs(np.diff(block.position, axis=0)).sum())
        speed = np.linalg.norm(np.diff(block.position, axis=0), axis=-1) / 0.01
        assert speed[:, :n].max() <= PERSON_LIMITS.max_speed + SWAY_SPEED_M_S
        relative = np.abs(wrap_angle(block.head_yaw[:, :n] - block.yaw[:, :n]))
        assert relative.max() <= math.radians(70.0) + 1e-9
    assert worst >= 0.0
    assert moved > 100.0  # they did walk about


def test_motion_limits_are_validated() -> None:
    with pytest.raises(ValueError, match=r"MotionLimits.max_speed must be positive"):
        MotionLimits(
            max_speed=-1.0, max_accel=1.0, max_turn_rate=1.0, head_limit=1.0, head_rate=1.0
        )
    with pytest.raises(
        ValueError, match=r"MotionLimits.tilt_rate must be a finite number >= 0, got -1.0"
    ):
        dataclasses.replace(ROBOT_LIMITS, tilt_rate=-1)
    with pytest.raises(ValueError, match=r"MotionLimits.head_limit must be <= pi"):
        MotionLimits(max_speed=1.0, max_accel=1.0, max_turn_rate=1.0, head_limit=4.0, head_rate=1.0)


def test_custom_limits_bound_the_walk() -> None:
    slow = MotionLimits(
        max_speed=0.5, max_accel=0.5, max_turn_rate=1.0, head_limit=1.0, head_rate=1.0
    )
    spec = SceneSpec(people=[PersonSpec(id=1, position=(-2.0, 0.0))], room=(6, 6))
    world = World(spec, seed=0, script=_walk((2.0, 0.0), speed=1.4), person_limits=slow)
    poses = _poses(world, 4.0)
    speed = np.linalg.norm(np.diff(poses["position"][:, 0], axis=0), axis=-1) / 0.01
    assert speed.max() <= 0.5 + SWAY_SPEED_M_S
    assert speed.max() >= 0.45


def test_a_walker_goes_around_a_standing_person() -> None:
    people = [PersonSpec(id=1, position=(-2.0, 0.0)), PersonSpec(id=2, position=(0.0, 0.0))]
    spec = SceneSpec(people=people, room=(6.0, 6.0))
    world = World(spec, seed=0, script=_walk((2.0, 0.0)))
    poses = _poses(world, 8.0)
    np.testing.assert_allclose(poses["position"][-1, 0], (2.0, 0.0), atol=0.05)
    # The person standing in the way was barely moved.
    assert np.linalg.norm(poses["position"][-1, 1]) < 0.25
