"""The robot's view: field of view, range, occlusion by ray casts, noise, dropouts; head camera."""

from __future__ import annotations

import math

import numpy as np
import pytest

from reform import Perturbation, TrackerNoise, wrap_angle
from sim import HeadCamera, PersonSpec, RobotSpec, SceneSpec, Sensor, World
from sim.envs.view import Eyes


def _world(people: list[PersonSpec], *, room: tuple[float, float] = (12.0, 12.0)) -> World:
    """The robot at the origin facing +x, people standing still where placed."""
    spec = SceneSpec(people=people, robot=RobotSpec(id=0, position=(0.0, 0.0)), room=room)
    world = World(spec, seed=0)
    world.set_groups([[p.id for p in people] + [0]])
    return world


def _at(pid: int, distance: float, bearing_deg: float, **kw) -> PersonSpec:
    b = math.radians(bearing_deg)
    return PersonSpec(id=pid, position=(distance * math.cos(b), distance * math.sin(b)), **kw)


def test_field_of_view_is_57_degrees() -> None:
    world = _world(
        [_at(1, 2.5, 0), _at(2, 2.5, 25), _at(3, 2.5, -25), _at(4, 4.0, 31), _at(5, 2.5, -90)]
    )
    truth, body, head = Sensor(occlusion=False).visibility(world)
    seen = set(truth.ids[body].tolist())
    assert seen == {1, 2, 3}
    assert np.array_equal(body, head)


def test_range_is_half_a_metre_to_four_and_a_half() -> None:
    world = _world([_at(1, 1.6, 0), _at(2, 4.4, 10), _at(3, 4.7, -10), _at(4, 0.7, 20)])
    truth, body, _ = Sensor(occlusion=False).visibility(world)
    assert set(truth.ids[body].tolist()) == {1, 2, 4}
    truth, body, _ = Sensor(occlusion=False, min_range=0.8).visibility(world)
    assert set(truth.ids[body].tolist()) == {1, 2}


def test_a_person_behind_another_is_occluded() -> None:
    world = _world([_at(1, 1.5, 0), _at(2, 3.0, 0), _at(3, 3.0, 12)])
    truth, body, _ = Sensor().visibility(world)
    assert set(truth.ids[body].tolist()) == {1, 3}
    truth, body, _ = Sensor(occlusion=False).visibility(world)
    assert set(truth.ids[body].tolist()) == {1, 2, 3}


def test_a_child_does_not_hide_an_adult_and_the_head_may_show_alone() -> None:
    # A 1.0 m child 1.5 m ahead does not block the rays from the 1.3 m robot to a 2.0 m adult.
    world = _world([_at(1, 1.5, 0, height=1.0), _at(2, 3.0, 0, height=2.0)])
    truth, body, head = Sensor().visibility(world)
    assert body.tolist() == [True, True, False]
    # A tall person in front hides the torso and the head of a short one behind.
    world = _world([_at(1, 1.2, 0, height=2.0, width=0.6), _at(2, 2.4, 0, height=1.5)])
    truth, body, head = Sensor().visibility(world)
    assert body.tolist() == [True, False, False]


def test_observed_frame_holds_the_robot_and_the_visible_people() -> None:
    world = _world([_at(1, 2.0, 0), _at(2, 3.5, 0), _at(3, 2.0, 90)])
    observed = Sensor().observe(world, np.random.default_rng(0))
    truth = world.frame()
    assert observed.ids.tolist() == [1, 0]
    assert observed.kinds == ("human", "robot")
    # Ground-truth groups restricted to the people seen.
    assert observed.groups == ((1, 0),)
    np.testing.assert_array_equal(observed.position, truth.position[[0, 3]])
    assert observed.time == truth.time
    alone = Sensor(include_robot=False).observe(world, np.random.default_rng(0))
    assert alone.ids.tolist() == [1]


def test_noise_has_the_configured_spread_and_yaws_stay_wrapped() -> None:
    world = _world([_at(1, 2.0, 0, yaw=math.pi - 0.01)])
    sensor = Sensor(position_noise=0.05, yaw_noise=0.1)
    rng = np.random.default_rng(1)
    truth = world.frame()
    observed = [sensor.observe(world, rng) for _ in range(2000)]
    dx = np.array([o.position[0] - truth.position[0] for o in observed])
    dyaw = np.array([wrap_angle(o.yaw[0] - truth.yaw[0]) for o in observed])
    assert dx.std(axis=0) == pytest.approx([0.05, 0.05], rel=0.1)
    assert dyaw.std() == pytest.approx(0.1, rel=0.1)
    assert all(abs(o.yaw[0]) <= math.pi for o in observed)
    # The robot's own pose is exact.
    assert all(np.array_equal(o.position[1], truth.position[1]) for o in observed)


def test_dropouts_drop_people_at_the_configured_rate() -> None:
    world = _world([_at(1, 2.0, 0), _at(2, 2.0, 20)])
    rng = np.random.default_rng(2)
    counts = [Sensor(dropout=0.3).observe(world, rng).n_people - 1 for _ in range(1000)]
    assert np.mean(counts) / 2 == pytest.approx(0.7, abs=0.04)
    assert Sensor(dropout=1.0).observe(world, rng).ids.tolist() == [0]


def test_same_rng_same_observation() -> None:
    world = _world([_at(1, 2.0, 0), _at(2, 2.0, 20)])
    sensor = Sensor(position_noise=0.1, yaw_noise=0.1, dropout=0.2)
    a = [sensor.observe(world, rng) for rng in [np.random.default_rng(5)] * 5]
    b = [sensor.observe(world, rng) for rng in [np.random.default_rng(5)] * 5]
    assert all(x == y for x, y in zip(a, b, strict=True))


def test_observing_a_bare_frame_matches_the_world_in_simple_cases() -> None:
    world = _world([_at(1, 1.5, 0), _at(2, 3.0, 0), _at(3, 2.5, 20), _at(4, 2.5, 40)])
    rng = np.random.default_rng(0)
    from_world = Sensor().observe(world, rng)
    from_frame = Sensor().observe(world.frame(), np.random.default_rng(0))
    assert from_world.ids.tolist() == from_frame.ids.tolist() == [1, 3, 0]


def test_noisy_values_are_the_noise_models_draws() -> None:
    # Exact values: the truth plus the levels times default_rng(10)'s draws, made by hand in
    # reform.perturb's documented order for every entry of the frame (people, then the robot):
    # position normals (n, 2), head position normals (n, 2), yaw normals (n,), head yaw
    # normals (n,), dropout uniforms (n,). Before the sensor called reform.TrackerNoise it drew
    # the uniforms first, so the same seed gave other numbers (it kept person 3, dropped 2).
    world = _world([_at(1, 2.0, 0), _at(2, 2.5, 15), _at(3, 2.0, -20)])
    sensor = Sensor(position_noise=0.05, yaw_noise=0.1, dropout=0.3)
    assert sensor.tracker_noise == TrackerNoise(position_std=0.05, yaw_std=0.1, dropout=0.3)
    observed = sensor.observe(world, np.random.default_rng(10))
    truth = world.frame()
    rng = np.random.default_rng(10)
    n = truth.n_people
    z_position = rng.standard_normal((n, 2))
    z_head_position = rng.standard_normal((n, 2))
    z_yaw = rng.standard_normal(n)
    z_head_yaw = rng.standard_normal(n)
    uniform = rng.random(n)
    assert (uniform[:3] < 0.3).tolist() == [False, False, True]  # person 3 is missed
    assert observed.ids.tolist() == [1, 2, 0]
    rows = [0, 1]
    np.testing.assert_array_equal(
        observed.position[:2], truth.position[rows] + 0.05 * z_position[rows]
    )
    np.testing.assert_array_equal(
        observed.head_position[:2], truth.head_position[rows] + 0.05 * z_head_position[rows]
    )
    np.testing.assert_array_equal(observed.yaw[:2], wrap_angle(truth.yaw[rows] + 0.1 * z_yaw[rows]))
    np.testing.assert_array_equal(
        observed.head_yaw[:2], wrap_angle(truth.head_yaw[rows] + 0.1 * z_head_yaw[rows])
    )
    np.testing.assert_array_equal(observed.position[2], truth.position[3])  # the robot, exact
    assert observed.groups == ((1, 2, 0),)


def test_sensor_eyes_and_perturbation_give_the_same_noisy_frame() -> None:
    # A sensor that sees everyone (all round, no occlusion, the whole room in range) reports
    # what the perturbation makes of the ground truth, and the environment's eyes report the
    # same: one noise model, one order of draws.
    world = _world([_at(1, 2.0, 0), _at(2, 2.5, 100), _at(3, 1.5, -140), _at(4, 3.0, 200)])
    levels = {"position_noise": 0.08, "yaw_noise": 0.3, "dropout": 0.35}
    sensor = Sensor(fov_deg=360.0, min_range=0.0, max_range=20.0, occlusion=False, **levels)
    perturbation = Perturbation(**levels)
    eyes = Eyes(world, sensor)
    truth = world.frame()
    sizes = set()
    for seed in range(12):
        from_sensor = sensor.observe(world, np.random.default_rng(seed))
        from_truth = perturbation.apply(truth, np.random.default_rng(seed))
        arrays = eyes.truth()
        view = eyes.look(arrays, np.random.default_rng(seed))
        from_eyes = eyes.observed_frame(arrays, view, truth.groups, sequence=truth.sequence)
        assert from_sensor == from_truth == from_eyes, seed
        sizes.add(from_sensor.n_people)
    assert len(sizes) > 2  # the dropouts did drop people, differently from seed to seed


def test_observing_a_bare_frame_keeps_its_listed_groups() -> None:
    # The annotation names person 9, whom the tracker never had: people the sensor does not
    # see, or drops, stay in listed_groups with them; groups hold who is reported.
    world = _world([_at(1, 2.0, 0), _at(2, 2.0, 90), _at(3, 2.5, 10)])
    truth = world.frame()
    frame = truth.replace(groups=((1, 2, 3), (0,)), listed_groups=((1, 2, 3, 9),))
    for seed in range(5):
        observed = Sensor(dropout=0.3).observe(frame, np.random.default_rng(seed))
        assert 2 not in observed.ids.tolist()  # out of the field of view
        assert observed.listed_groups == ((1, 2, 3, 9),)
        held = set(observed.ids.tolist())
        assert observed.groups == tuple(
            kept for kept in (tuple(m for m in g if m in held) for g in frame.groups) if kept
        )
    plain = Sensor().observe(truth, np.random.default_rng(0))
    assert plain.listed_groups is None and plain.groups == ((1, 3, 0),)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Sensor(fov_deg=0.0), r"Sensor.fov_deg must be within \(0, 360\]"),
        (lambda: Sensor(min_range=5.0), r"Sensor.max_range must exceed min_range"),
        (lambda: Sensor(dropout=1.5), r"Sensor.dropout must be in \[0, 1\], got 1.5"),
        (
            lambda: Sensor(position_noise=-0.1),
            r"Sensor.position_noise must be a finite number >= 0, got -0.1",
        ),
        (lambda: Sensor(max_range=-1), r"Sensor.max_range must be a finite number >= 0, got -1.0"),
    ],
)
def test_bad_sensor_settings_fail(make, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        make()


def test_observing_without_a_robot_fails() -> None:
    world = World(SceneSpec(people=[_at(1, 1.0, 0)]), seed=0)
    with pytest.raises(ValueError, match=r"the world has no robot"):
        Sensor().observe(world, np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"a Frame source must hold exactly one robot, got 0"):
        Sensor().observe(world.frame(), np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"rng must be a numpy.random.Generator"):
        Sensor().observe(world.frame(), 0)


def test_head_camera_renders_rgb_and_depth() -> None:
    world = _world([_at(1, 2.0, 0)])
    try:
        camera = HeadCamera(world, width=160, height=120)
    except RuntimeError as exc:  # no OpenGL at all on this machine
        pytest.skip(str(exc))
    with camera:
        rgb = camera.rgb()
        depth = camera.depth()
    assert rgb.shape == (120, 160, 3) and rgb.dtype == np.uint8
    assert depth.shape == (120, 160)
    # The person straight ahead fills the centre: the camera sits 0.115 m in front of the
    # robot's axis, the torso surface ~0.14 m before its centre (asset geometry).
    assert depth[60, 80] == pytest.approx(2.0 - 0.115 - 0.14, abs=0.05)
    # Horizontal field of view 57 degrees: the vertical one follows the 4:3 aspect.
    fovy = world.model.cam_fovy[world.head_camera]
    assert fovy == pytest.approx(math.degrees(2 * math.atan(math.tan(math.radians(28.5)) * 0.75)))
    assert rgb[60, 80].tolist() != rgb[5, 5].tolist()
