"""Scene specs and the MjSpec builder: names, sizes, colours, shipped assets, bad input."""

from __future__ import annotations

import math
from importlib import resources

import mujoco
import numpy as np
import pytest

from sim import PersonSpec, RobotSpec, SceneSpec, asset_names, asset_path, asset_xml, build_scene
from sim.scene import BODY_RADIUS_PER_WIDTH, ROBOT_RADIUS_M, default_color


def _scene(**overrides) -> SceneSpec:
    fields = dict(
        people=(
            PersonSpec(id=1, position=(1.0, 0.0), yaw=math.pi, height=1.60, width=0.40),
            PersonSpec(id=2, position=(-1.0, 0.5), height=1.90, width=0.50, color=(1.0, 0.0, 0.0)),
        ),
        robot=RobotSpec(id=7, position=(0.0, -1.5), yaw=math.pi / 2, height=1.40),
        room=(5.0, 5.0),
    )
    fields.update(overrides)
    return SceneSpec(**fields)


def _compiled(spec: SceneSpec) -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = build_scene(spec)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    return model, data


def _geoms_of(model: mujoco.MjModel, prefix: str) -> np.ndarray:
    return np.array([g for g in range(model.ngeom) if model.geom(g).name.startswith(prefix)])


def _top(model: mujoco.MjModel, data: mujoco.MjData, prefix: str) -> float:
    """Highest point of an agent's geoms (spheres, ellipsoids and capsules along z)."""
    tops = []
    for g in _geoms_of(model, prefix):
        kind, size = model.geom_type[g], model.geom_size[g]
        if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
            extent = size[2]
        elif kind in (mujoco.mjtGeom.mjGEOM_CAPSULE, mujoco.mjtGeom.mjGEOM_CYLINDER):
            axis = data.geom_xmat[g].reshape(3, 3)[:, 2]
            extent = abs(axis[2]) * size[1] + (
                size[0] if kind == mujoco.mjtGeom.mjGEOM_CAPSULE else 0
            )
        else:
            extent = size[0] if kind == mujoco.mjtGeom.mjGEOM_SPHERE else size[2]
        tops.append(data.geom_xpos[g, 2] + extent)
    return float(max(tops))


def _reach(model: mujoco.MjModel, data: mujoco.MjData, prefix: str) -> float:
    """Farthest ground-plane distance of an agent's geoms from the origin."""
    reach = []
    for g in _geoms_of(model, prefix):
        kind, size, centre = model.geom_type[g], model.geom_size[g], data.geom_xpos[g]
        if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
            axis = data.geom_xmat[g].reshape(3, 3)[:, 2] * size[1]
            ends = np.stack([centre + axis, centre - axis])
            reach.append(np.max(np.hypot(ends[:, 0], ends[:, 1])) + size[0])
        elif kind == mujoco.mjtGeom.mjGEOM_SPHERE:
            reach.append(np.hypot(*centre[:2]) + size[0])
        else:
            reach.append(np.hypot(*centre[:2]) + np.hypot(*size[:2]))
    return float(max(reach))


def test_every_element_is_named_and_prefixed() -> None:
    model, _ = _compiled(_scene())
    kinds = {
        "body": model.nbody,
        "geom": model.ngeom,
        "joint": model.njnt,
        "site": model.nsite,
        "camera": model.ncam,
        "light": model.nlight,
        "material": model.nmat,
    }
    for kind, count in kinds.items():
        names = [getattr(model, kind)(i).name for i in range(count)]
        assert all(names), f"unnamed {kind}: {names}"
        assert len(set(names)) == len(names), f"duplicate {kind} names"
    for name in ("person1/torso", "person1/head", "person2/root", "robot/head", "robot/base"):
        assert model.body(name).id > 0
    for name in ("person1/neck_yaw", "robot/head_pan", "robot/head_tilt"):
        assert model.joint(name).id >= 0
    assert model.site("robot/head_sensor").id >= 0
    assert model.camera("robot/head_camera").id >= 0
    assert model.nmocap == 3
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT


def test_start_poses_are_the_mocap_defaults() -> None:
    model, data = _compiled(_scene())
    torso = data.xpos[model.body("person1/torso").id]
    np.testing.assert_allclose(torso[:2], [1.0, 0.0], atol=1e-12)
    xmat = data.xmat[model.body("robot/torso").id]
    assert math.atan2(xmat[3], xmat[0]) == pytest.approx(math.pi / 2)


@pytest.mark.parametrize("height", [1.2, 1.6, 1.75, 2.0])
def test_people_are_as_tall_as_asked(height: float) -> None:
    spec = SceneSpec(people=(PersonSpec(id=3, position=(0.0, 0.0), height=height),))
    model, data = _compiled(spec)
    assert _top(model, data, "person3/") == pytest.approx(height, abs=0.01)


@pytest.mark.parametrize("height", [1.2, 1.3, 1.5])
def test_the_robot_is_as_tall_as_asked(height: float) -> None:
    model, data = _compiled(SceneSpec(robot=RobotSpec(height=height)))
    assert _top(model, data, "robot/") == pytest.approx(height, abs=0.01)


@pytest.mark.parametrize("width", [0.35, 0.44, 0.6])
def test_people_are_as_wide_as_asked_and_fit_their_radius(width: float) -> None:
    person = PersonSpec(id=4, position=(0.0, 0.0), width=width)
    model, data = _compiled(SceneSpec(people=(person,)))
    arms = [model.geom(f"person4/arm_{side}").id for side in ("left", "right")]
    # Arms hang at +-width/2 at the shoulder (hand-set asset geometry, scaled).
    lateral = np.abs(data.geom_xpos[arms, 1])
    assert np.all(np.abs(lateral - width / 2) < 0.02)
    assert person.radius == pytest.approx(BODY_RADIUS_PER_WIDTH * width)
    assert _reach(model, data, "person4/") <= person.radius


def test_shirt_colours_are_distinct_or_as_given() -> None:
    spec = _scene()
    model, _ = _compiled(spec)
    first = model.mat_rgba[model.material("person1/shirt").id]
    second = model.mat_rgba[model.material("person2/shirt").id]
    np.testing.assert_allclose(first, default_color(0), atol=1e-6)
    np.testing.assert_allclose(second, [1.0, 0.0, 0.0, 1.0], atol=1e-6)
    colours = {default_color(i) for i in range(30)}
    assert len(colours) == 30


def test_assets_ship_as_package_data() -> None:
    # The models are resources of the ``assets`` package (pyproject's package-data), found
    # through importlib.resources as a non-editable install finds them.
    root = resources.files("assets")
    shipped = sorted(p.name for p in root.iterdir() if p.name.endswith(".xml"))
    assert shipped == ["person.xml", "robot.xml"]
    assert asset_names() == ("person", "robot")
    for name in asset_names():
        spec = mujoco.MjSpec.from_string(asset_xml(name))
        assert spec.compile().nbody >= 3
        assert asset_path(name).is_file()


def test_robot_radius_covers_its_base() -> None:
    model, data = _compiled(SceneSpec(robot=RobotSpec()))
    disc = model.geom("robot/base_disc").id
    assert model.geom_size[disc, 0] <= ROBOT_RADIUS_M
    bumper = model.geom("robot/bumper").id
    assert data.geom_xpos[bumper, 0] + model.geom_size[bumper, 0] <= ROBOT_RADIUS_M


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (
            lambda: PersonSpec(id=1, position=(0, 0), height=-1.7),
            r"person 1: height must be within",
        ),
        (lambda: PersonSpec(id=1, position=(0, 0), width=0.0), r"person 1: width must be within"),
        (lambda: PersonSpec(id=1, position=(0, float("nan"))), r"position must be a finite pair"),
        (lambda: PersonSpec(id=1, position=(0, 0), asset="android"), r"unknown asset 'android'"),
        (lambda: PersonSpec(id=1, position=(0, 0), color=(2, 0, 0)), r"color must be RGB"),
        (lambda: PersonSpec(id=1.5, position=(0, 0)), r"PersonSpec.id must be an int"),
        (lambda: RobotSpec(height=3.0), r"robot: height must be within \[1.2, 1.5\] m"),
        (lambda: RobotSpec(asset="humanoid"), r"robot: asset: unknown asset 'humanoid'"),
        (lambda: SceneSpec(room=(-5.0, 5.0)), r"room must be \(x extent, y extent\)"),
        (lambda: SceneSpec(wall_height=0.0), r"wall_height must be positive"),
    ],
)
def test_bad_sizes_and_names_fail_clearly(make, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        make()


def test_too_many_people_for_the_room() -> None:
    people = [PersonSpec(id=i, position=(0.0, 0.0), present=False) for i in range(40)]
    with pytest.raises(ValueError, match=r"too many people for the room: 40 agents need"):
        SceneSpec(people=people, room=(3.0, 3.0))


def test_overlapping_starts_fail() -> None:
    people = [PersonSpec(id=1, position=(0.0, 0.0)), PersonSpec(id=2, position=(0.4, 0.0))]
    with pytest.raises(ValueError, match=r"person 2 and person 1 overlap at the start: .* 0.400 m"):
        SceneSpec(people=people)


def test_robot_overlapping_a_person_fails() -> None:
    with pytest.raises(ValueError, match=r"robot 0 and person 1 overlap"):
        SceneSpec(people=[PersonSpec(id=1, position=(0.3, 0.0))], robot=RobotSpec())


def test_start_outside_the_walls_fails() -> None:
    with pytest.raises(
        ValueError, match=r"person 1: start position \(2.4, 0\) is outside the walls"
    ):
        SceneSpec(people=[PersonSpec(id=1, position=(2.4, 0.0))], room=(5.0, 5.0))


def test_duplicate_ids_fail() -> None:
    with pytest.raises(ValueError, match=r"agent ids must be unique within a scene, got 0 twice"):
        SceneSpec(people=[PersonSpec(id=0, position=(1.0, 0.0))], robot=RobotSpec(id=0))


def test_absent_people_may_share_a_start() -> None:
    people = [
        PersonSpec(id=1, position=(0.0, 0.0)),
        PersonSpec(id=2, position=(0.0, 0.0), present=False),
    ]
    assert len(SceneSpec(people=people).agents) == 2


def test_the_kinematic_twin_has_the_same_bodies_and_poses() -> None:
    spec = _scene()
    full, twin = build_scene(spec), build_scene(spec, geometry=False)
    assert twin.ngeom < full.ngeom / 3
    for size in ("nbody", "njnt", "nq", "nmocap", "nsite", "ncam"):
        assert getattr(twin, size) == getattr(full, size)
    assert [full.body(i).name for i in range(full.nbody)] == [
        twin.body(i).name for i in range(twin.nbody)
    ]
    datas = [mujoco.MjData(m) for m in (full, twin)]
    for data in datas:
        data.mocap_pos[:] = [1.0, -0.5, 0.0]
        data.mocap_quat[:] = [math.cos(0.3), 0.0, 0.0, math.sin(0.3)]
        data.qpos[:] = 0.4
    for model, data in zip((full, twin), datas, strict=True):
        mujoco.mj_kinematics(model, data)
    np.testing.assert_array_equal(datas[0].xpos, datas[1].xpos)
    np.testing.assert_array_equal(datas[0].xquat, datas[1].xquat)


def test_furniture_is_in_the_scene_and_bad_furniture_is_one_line():
    from sim.scene import FurnitureSpec

    spec = SceneSpec(
        people=[PersonSpec(id=1, position=(0.0, 0.0))],
        furniture=[FurnitureSpec("table", (1.0, 1.0), (0.8, 0.8, 0.75))],
    )
    model = build_scene(spec)
    assert model.geom("furniture0").size[0] == pytest.approx(0.4)
    assert build_scene(spec, geometry=False).ngeom < model.ngeom
    with pytest.raises(ValueError, match=r"^furniture: kind must be one of \['table', 'bar', "):
        FurnitureSpec("sofa", (0.0, 0.0), (1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match=r"^furniture bar: size must be within \[0.02, 10.0\] m"):
        FurnitureSpec("bar", (0.0, 0.0), (2.0, -0.5, 1.0))
