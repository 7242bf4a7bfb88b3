"""Procedural cabinets, the PartNet-Mobility writer/loader, and their physics in MuJoCo."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from planners.errors import ConfigError, PlannersError, UnknownNameError
from strug_manip.objects import generator as gen
from strug_manip.objects.generator import PartSpec, generate_cabinet
from strug_manip.objects.loader import (
    ArticulatedObject,
    add_to_spec,
    load_articulated_object,
    load_cabinet_spec,
)
from strug_manip.objects.partnet import cabinet_urdf, write_partnet

EXAMPLES = Path(__file__).resolve().parents[1] / "models" / "cabinets"
EXAMPLE_DIRS = sorted(p for p in EXAMPLES.iterdir() if (p / "mobility.urdf").is_file())


def _inside(x: float, bounds: tuple[float, float], tol: float = 1e-9) -> bool:
    return bounds[0] - tol <= x <= bounds[1] + tol


# ------------------------------------------------------------------------------------
# Generator
# ------------------------------------------------------------------------------------


def test_same_seed_same_cabinet_different_seed_different() -> None:
    assert cabinet_urdf(generate_cabinet(5)) == cabinet_urdf(generate_cabinet(5))
    assert cabinet_urdf(generate_cabinet(5)) != cabinet_urdf(generate_cabinet(6))


def test_documented_ranges_hold() -> None:
    for seed in range(60):
        c = generate_cabinet(seed)
        assert _inside(c.width, gen.WIDTH_RANGE) and _inside(c.depth, gen.DEPTH_RANGE)
        assert _inside(c.height, gen.HEIGHT_RANGE) and _inside(c.wall, gen.WALL_RANGE)
        assert 1 <= c.rows <= gen.MAX_ROWS and 1 <= c.cols <= gen.MAX_COLS
        assert all(_inside(w, gen.CELL_WIDTH_RANGE, 1e-6) for w in c.col_widths)
        assert all(_inside(h, gen.CELL_HEIGHT_RANGE, 1e-6) for h in c.row_heights)
        assert _inside(c.mass, gen.TOTAL_MASS, 1e-6)
        assert len(c.parts) == c.rows * c.cols and c.movable_parts
        for p in c.parts:
            assert p.semantic == p.kind
            if p.kind == "drawer":
                assert p.joint_type == "prismatic" and np.allclose(p.axis, [1, 0, 0])
                assert p.lower == 0 and 0.1 < p.upper < c.depth
                assert _inside(p.damping, gen.DRAWER_DAMPING)
                assert _inside(p.friction, gen.DRAWER_FRICTION)
            elif p.kind == "door":
                assert p.joint_type == "revolute" and p.hinge in gen.HINGE_WEIGHTS
                side = p.hinge in ("left", "right")
                assert _inside(p.upper, gen.DOOR_SIDE_LIMIT if side else gen.DOOR_FLAP_LIMIT)
                assert _inside(p.damping, gen.DOOR_DAMPING)
                if side:
                    assert _inside(p.friction, gen.DOOR_FRICTION)
                else:  # a flap's stay holds it against gravity even when horizontal
                    lever = abs(float(p.inertial.com[2]))
                    hold = p.friction / (p.inertial.mass * gen.GRAVITY * lever)
                    assert _inside(hold, gen.FLAP_STAY_HOLD, 1e-9)
            else:
                assert p.joint_type == "fixed" and p.handle_pos is None
            if p.movable:
                assert p.handle in gen.HANDLE_KINDS
                # The grasp point is on or in front of the front plane, within the cell.
                assert p.handle_pos[0] >= c.depth / 2 - 1e-9
                half = np.array([0.0, *p.cell_size]) / 2
                assert np.all(np.abs(p.handle_pos - p.cell_center)[1:] <= half[1:])


def test_positive_joint_motion_opens_outward() -> None:
    for seed in range(30):
        for p in generate_cabinet(seed).movable_parts:
            q = 0.3 * p.upper
            moved = p.handle_at(q) - p.handle_at(0.0)
            assert moved[0] > 0.0, (seed, p.link, p.hinge)
            T = np.eye(4)
            T[:3, 3] = (1.0, 2.0, 0.0)
            assert np.allclose(p.handle_at(q, T), p.handle_at(q) + T[:3, 3])


@pytest.mark.parametrize(
    ("kinds", "expected"),
    [(("drawer",), {"drawer"}), (("door",), {"door"}), (("shelf",), {"shelf"})],
)
def test_kinds_restrict_the_parts(kinds: tuple[str, ...], expected: set[str]) -> None:
    for seed in range(10):
        c = generate_cabinet(seed, kinds=kinds)
        assert {p.kind for p in c.parts} == expected


def test_mixed_cabinets_always_have_a_movable_part() -> None:
    kinds = ("drawer", "shelf", "panel")
    assert all(generate_cabinet(s, kinds=kinds).movable_parts for s in range(40))


def test_bad_generator_options() -> None:
    with pytest.raises(ConfigError, match="seed must be an integer >= 0, got -1"):
        generate_cabinet(-1)
    with pytest.raises(UnknownNameError, match="unknown part kind 'drawr'"):
        generate_cabinet(0, kinds=("drawr",))
    with pytest.raises(ConfigError, match="at least one part kind"):
        generate_cabinet(0, kinds=())
    with pytest.raises(UnknownNameError, match="unknown handle style 'hook'"):
        generate_cabinet(0, handles=("hook",))


# ------------------------------------------------------------------------------------
# Writer and loader
# ------------------------------------------------------------------------------------


def test_two_hundred_cabinets_load_in_mujoco_and_pinocchio(tmp_path: Path) -> None:
    for seed in range(200):
        spec = generate_cabinet(seed)
        obj = load_articulated_object(write_partnet(spec, tmp_path / f"c{seed}"))
        n_movable = len(spec.movable_parts)
        assert obj.pin_model.nv == obj.mj_model.nv - 6 == n_movable
        assert obj.pin_model.njoints - 1 == obj.mj_model.njnt - 1 == n_movable
        pin_names = set(list(obj.pin_model.names)[1:])
        assert (
            pin_names
            == {j.name for j in obj.movable_joints}
            == {p.joint for p in spec.movable_parts}
        )
        assert not np.any(np.isnan(obj.mj_model.body_mass))
        assert obj.mass == pytest.approx(spec.mass, rel=1e-6)


def test_loader_metadata_matches_the_spec(tmp_path: Path) -> None:
    spec = generate_cabinet(17)
    obj = load_articulated_object(write_partnet(spec, tmp_path / "c"), free=False, floor=False)
    assert obj.root == "base" and obj.links["link_0"].semantic == "furniture_body"
    assert obj.links["link_0"].semantic_type == "heavy"
    for p in spec.parts:
        j = obj.joint(p.joint)
        assert j.child == p.link and j.semantic == p.semantic
        assert j.type == p.joint_type
        assert np.allclose(j.T_base_joint[:3, 3], p.origin, atol=1e-8)
        if p.movable:
            assert np.allclose(j.axis_base, p.axis, atol=1e-8)
            assert (j.lower, j.upper) == pytest.approx((p.lower, p.upper), abs=1e-8)
            assert (j.damping, j.friction) == pytest.approx((p.damping, p.friction), rel=1e-7)
            mj = obj.mj_model.joint(p.joint)
            assert mj.range == pytest.approx([p.lower, p.upper], abs=1e-8)
            assert mj.damping[0] == pytest.approx(p.damping, rel=1e-7)
            assert mj.frictionloss[0] == pytest.approx(p.friction, rel=1e-7)
    # Handles are named geoms of their part's body.
    drawer = next(p for p in spec.parts if p.kind == "drawer" and p.handle != "none")
    names = [obj.mj_model.geom(i).name for i in range(obj.mj_model.ngeom)]
    assert any(n.startswith(f"{drawer.link}/handle") for n in names)
    glide = gen.GLIDE_RADIUS  # the glides stand below the bottom plane
    assert np.allclose(obj.bounds[0], [-spec.depth / 2, -spec.width / 2, -glide], atol=1e-6)
    assert '<compiler angle="radian"/>' in obj.to_mjcf()


def test_contacts_excluded_between_base_and_parts(tmp_path: Path) -> None:
    spec = generate_cabinet(17)
    obj = load_articulated_object(write_partnet(spec, tmp_path / "c"))
    m = obj.mj_model
    excluded = {
        frozenset((m.body(int(s >> 16)).name, m.body(int(s & 0xFFFF)).name))
        for s in m.exclude_signature
    }
    base_group = {"base", "link_0"} | {p.link for p in spec.parts if not p.movable}
    for p in spec.movable_parts:
        for b in base_group:
            assert frozenset((b, p.link)) in excluded
    # Sibling moving parts still collide with each other.
    a, b = spec.movable_parts[:2]
    assert frozenset((a.link, b.link)) not in excluded


# ------------------------------------------------------------------------------------
# Physics
# ------------------------------------------------------------------------------------


def _warnings(data: mujoco.MjData) -> int:
    return sum(int(data.warning[i].number) for i in range(len(data.warning)))


@pytest.mark.parametrize("folder", EXAMPLE_DIRS, ids=[p.name for p in EXAMPLE_DIRS])
def test_examples_stand_still_on_the_floor(folder: Path) -> None:
    obj = load_articulated_object(folder)
    m = obj.mj_model
    data = mujoco.MjData(m)
    base0 = data.qpos[:3].copy()
    for _ in range(round(2.0 / m.opt.timestep)):
        mujoco.mj_step(m, data)
    assert _warnings(data) == 0
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
    assert np.linalg.norm(data.qpos[:3] - base0) < 0.01
    assert 10.0 <= obj.mass <= 40.0


def test_committed_examples_are_what_the_generator_makes() -> None:
    kinds = {"drawers": ("drawer",), "doors": ("door",), "mixed": gen.PART_KINDS}
    assert len(EXAMPLE_DIRS) >= 3
    for folder in EXAMPLE_DIRS:
        prefix, seed = folder.name.rsplit("_", 1)
        spec = generate_cabinet(int(seed), kinds=kinds[prefix])
        assert (folder / "mobility.urdf").read_text() == cabinet_urdf(spec), folder.name


def _pull(
    obj: ArticulatedObject, part: PartSpec, direction: str, force: float, seconds: float
) -> tuple[np.ndarray, np.ndarray, mujoco.MjData]:
    """Pull ``part``'s handle; return the joint position and base displacement [m] per step.

    ``direction``: ``axis`` (along the drawer axis), ``tangent`` (perpendicular to the
    door at the handle, in the opening sense, re-aimed every step) or ``side`` (+y).
    """
    m = obj.mj_model
    data = mujoco.MjData(m)
    body = m.body(part.link).id
    local = part.handle_pos - part.origin  # grasp point in the part frame
    adr = obj.mujoco_qpos_address(m, part.joint)
    base0 = data.qpos[:3].copy()
    qs, disp = [], []
    mujoco.mj_forward(m, data)  # body poses for the first step
    for _ in range(round(seconds / m.opt.timestep)):
        R = data.xmat[body].reshape(3, 3)
        point = data.xpos[body] + R @ local
        if direction == "axis":
            f = R @ part.axis
        elif direction == "tangent":
            f = np.cross(R @ part.axis, R @ local)
            f /= np.linalg.norm(f)
        else:
            f = np.array([0.0, 1.0, 0.0])
        data.qfrc_applied[:] = 0.0
        mujoco.mj_applyFT(m, data, force * f, np.zeros(3), point, body, data.qfrc_applied)
        mujoco.mj_step(m, data)
        disp.append(float(np.linalg.norm(data.qpos[:3] - base0)))
        qs.append(float(data.qpos[adr]))
    assert _warnings(data) == 0 and np.all(np.isfinite(data.qpos))
    return np.array(qs), np.array(disp), data


@pytest.mark.parametrize("name", ["drawers_11", "mixed_17"])
def test_pulling_a_drawer_handle_along_its_axis_opens_it(name: str) -> None:
    obj = load_articulated_object(EXAMPLES / name)
    spec = generate_cabinet(
        int(name.rsplit("_", 1)[1]), kinds=("drawer",) if "drawers" in name else gen.PART_KINDS
    )
    for part in (p for p in spec.movable_parts if p.kind == "drawer"):
        qs, _, _ = _pull(obj, part, "axis", 30.0, 1.0)
        assert qs[-1] > 0.05, part.link


def test_a_tangential_force_opens_each_door_about_its_hinge() -> None:
    obj = load_articulated_object(EXAMPLES / "doors_7")
    spec = generate_cabinet(7, kinds=("door",))
    assert {p.hinge for p in spec.parts} == {"left", "right", "top", "bottom"}
    for part in spec.parts:
        qs, _, data = _pull(obj, part, "tangent", 30.0, 1.0)
        assert qs[-1] > 0.5, (part.link, part.hinge)
        # It turned about its hinge: the hinge line stayed where it was on the carcass.
        carcass = data.body("link_0")
        R = carcass.xmat.reshape(3, 3)
        hinge = R.T @ (data.body(part.link).xpos - carcass.xpos)
        assert np.allclose(hinge, part.origin, atol=1e-9)
        assert np.allclose(R.T @ data.body(part.link).xmat.reshape(3, 3) @ part.axis, part.axis)


def test_a_wrong_pull_drags_the_free_standing_cabinet() -> None:
    """Pulling a drawer handle sideways (as if it were a door) drags the whole cabinet:
    its base passes the task's 0.1 m failure threshold and keeps going; the right pull,
    even gentle, opens the drawer and leaves the base in place."""
    obj = load_articulated_object(EXAMPLES / "drawers_11")
    part = generate_cabinet(11, kinds=("drawer",)).parts[1]
    _, disp, _ = _pull(obj, part, "side", 150.0, 0.5)
    quarter = len(disp) // 4
    assert disp[-1] > 0.1
    assert disp[-1] > disp[2 * quarter] > disp[quarter] > 0.0  # and keeps sliding
    qs, disp_ok, _ = _pull(obj, part, "axis", 10.0, 0.5)
    assert qs[-1] > 0.05 and disp_ok[-1] < 0.01


# ------------------------------------------------------------------------------------
# Pinocchio vs MuJoCo kinematics
# ------------------------------------------------------------------------------------


def _assert_fk_matches(obj: ArticulatedObject, rng: np.random.Generator, trials: int) -> None:
    m = obj.mj_model
    data = mujoco.MjData(m)
    pdata = obj.pin_model.createData()
    for _ in range(trials):
        config = obj.random_configuration(rng)
        for name, value in config.items():
            data.qpos[obj.mujoco_qpos_address(m, name)] = value
        mujoco.mj_kinematics(m, data)
        pin.framesForwardKinematics(obj.pin_model, pdata, obj.pin_configuration(config))
        for link in obj.links:
            fid = obj.pin_model.getFrameId(link, pin.BODY)
            body = m.body(link).id
            oMf = pdata.oMf[fid]
            assert np.linalg.norm(oMf.translation - data.xpos[body]) < 1e-6, link
            assert np.abs(oMf.rotation - data.xmat[body].reshape(3, 3)).max() < 1e-6, link


def test_pinocchio_and_mujoco_agree_on_part_poses(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    for seed in range(0, 40, 4):
        path = write_partnet(generate_cabinet(seed), tmp_path / f"c{seed}")
        _assert_fk_matches(load_articulated_object(path, free=False, floor=False), rng, 5)


# ------------------------------------------------------------------------------------
# A PartNet-Mobility-style object: meshes, helper links, y-up rotation, bare limits
# ------------------------------------------------------------------------------------

_CUBE_OBJ = """# unit cube
v -0.5 -0.5 -0.5
v 0.5 -0.5 -0.5
v 0.5 0.5 -0.5
v -0.5 0.5 -0.5
v -0.5 -0.5 0.5
v 0.5 -0.5 0.5
v 0.5 0.5 0.5
v -0.5 0.5 0.5
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
"""

_PARTNET_URDF = """<?xml version="1.0" ?>
<robot name="partnet_like">
  <link name="base"/>
  <link name="link_0">
    <visual name="lid-1"><origin xyz="0.2 0 0"/>
      <geometry><mesh filename="textured_objs/original-2.obj" scale="0.4 0.02 0.3"/></geometry>
    </visual>
    <collision><origin xyz="0.2 0 0"/>
      <geometry><mesh filename="textured_objs/original-2.obj" scale="0.4 0.02 0.3"/></geometry>
    </collision>
  </link>
  <joint name="joint_0" type="continuous">
    <origin xyz="0 0 0"/><axis xyz="0 1 0"/>
    <child link="link_0"/><parent link="link_0_helper"/>
  </joint>
  <link name="link_1">
    <visual name="body-5"><origin xyz="0 0 0"/>
      <geometry><mesh filename="textured_objs/original-1.obj" scale="0.5 0.6 0.4"/></geometry>
    </visual>
    <collision><origin xyz="0 0 0"/>
      <geometry><mesh filename="textured_objs/original-1.obj" scale="0.5 0.6 0.4"/></geometry>
    </collision>
  </link>
  <joint name="joint_1" type="fixed">
    <origin rpy="1.570796326794897 0 -1.570796326794897" xyz="0 0 0"/>
    <child link="link_1"/><parent link="base"/>
  </joint>
  <link name="link_0_helper"/>
  <joint name="joint_2" type="prismatic">
    <origin xyz="-0.1 0.3 0.05"/><axis xyz="0 1 0"/>
    <child link="link_0_helper"/><parent link="link_1"/>
    <limit lower="0" upper="0.2"/>
  </joint>
  <link name="link_2">
    <visual><origin xyz="0 0 0.1"/><geometry><box size="0.1 0.1 0.2"/></geometry></visual>
    <visual><geometry><mesh filename="textured_objs/decal.dae"/></geometry></visual>
  </link>
  <joint name="joint_3" type="revolute">
    <origin xyz="0.25 -0.3 0.0" rpy="0.1 0.2 0.3"/><axis xyz="1 1 0"/>
    <child link="link_2"/><parent link="link_1"/>
    <limit lower="-0.5" upper="0.5"/>
  </joint>
</robot>
"""


@pytest.fixture
def partnet_folder(tmp_path: Path) -> Path:
    folder = tmp_path / "12345"
    (folder / "textured_objs").mkdir(parents=True)
    for name in ("original-1.obj", "original-2.obj"):
        (folder / "textured_objs" / name).write_text(_CUBE_OBJ)
    (folder / "textured_objs" / "decal.dae").write_text("<COLLADA/>")
    (folder / "mobility.urdf").write_text(_PARTNET_URDF)
    (folder / "semantics.txt").write_text(
        "link_0 hinge lid\nlink_1 heavy body\nlink_2 hinge door\n"
    )
    return folder


def test_a_partnet_style_object_loads_and_stands_on_the_floor(partnet_folder: Path) -> None:
    obj = load_articulated_object(partnet_folder, total_mass=15.0)
    assert obj.mass == pytest.approx(15.0)
    assert len(obj.warnings) == 1 and "decal.dae" in obj.warnings[0]  # MuJoCo can't read it
    assert obj.pin_model.nv == obj.mj_model.nv - 6 == 3
    assert obj.joint("joint_3").semantic == "door" and obj.joint("joint_2").semantic == ""
    assert obj.joint("joint_0").lower == -math.inf
    m = obj.mj_model
    data = mujoco.MjData(m)
    mujoco.mj_kinematics(m, data)
    # joint_1 turns the y-up body (0.6 m along its y) z-up; the lid (0.02 m thick, centred
    # 0.3 m up) adds 0.01 m; conforming puts the origin on the body's bottom.
    assert obj.scale == 1.0  # 0.5 x 0.4 x 0.6 m lies in the generator's ranges
    assert obj.bounds[:, 2] == pytest.approx([0.0, 0.61], abs=1e-6)
    assert data.body("base").xpos[2] == pytest.approx(0.0, abs=1e-6)  # float32 meshes
    for _ in range(500):
        mujoco.mj_step(m, data)
    assert _warnings(data) == 0 and np.all(np.isfinite(data.qpos))
    assert abs(data.qpos[2] - m.qpos0[2]) < 0.01
    _assert_fk_matches(
        load_articulated_object(partnet_folder, free=False, floor=False),
        np.random.default_rng(1),
        10,
    )


def test_add_to_spec_places_objects_in_a_scene(tmp_path: Path, partnet_folder: Path) -> None:
    cab = load_articulated_object(write_partnet(generate_cabinet(3), tmp_path / "c"))
    other = load_articulated_object(partnet_folder)
    scene = mujoco.MjSpec()  # a scene in degrees: hinge ranges must be converted
    scene.compiler.degree = True
    scene.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[5, 5, 0.1])
    add_to_spec(scene, cab, (1.0, 0.5, 0.0), math.pi / 2, prefix="cabinet/")
    add_to_spec(scene, other, (-1.0, 0.0, 0.0), 0.0, free=False, prefix="box/")
    with pytest.raises(ConfigError, match="already has a body 'box/base'"):
        add_to_spec(scene, other, prefix="box/")
    m = scene.compile()
    data = mujoco.MjData(m)
    mujoco.mj_forward(m, data)
    assert np.allclose(data.body("cabinet/base").xpos, [1.0, 0.5, gen.GLIDE_RADIUS])
    R = data.body("cabinet/base").xmat.reshape(3, 3)
    assert np.allclose(R[:, 0], [0.0, 1.0, 0.0], atol=1e-9)  # the front now faces +y
    assert m.joint("box/joint_3").range == pytest.approx([-0.5, 0.5])
    assert data.body("box/base").xpos[2] == pytest.approx(-other.bounds[0, 2])
    for _ in range(200):
        mujoco.mj_step(m, data)
    assert _warnings(data) == 0


# ------------------------------------------------------------------------------------
# Malformed URDFs: one ConfigError each, naming the file and the problem
# ------------------------------------------------------------------------------------

_GOOD = """<robot name="r">
  <link name="base"/>
  <link name="link_0"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <joint name="joint_0" type="{type}">
    <origin xyz="{xyz}"/><axis xyz="1 0 0"/>
    <parent link="base"/><child link="{child}"/>
    <limit lower="0" upper="1" effort="1" velocity="1"/>
  </joint>
</robot>
"""


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (None, "URDF file .*mobility.urdf not found"),
        ("<robot><link name='a'>", "malformed URDF .*mobility.urdf: not valid XML"),
        (
            _GOOD.format(type="hinge", xyz="0 0 0", child="link_0"),
            "joint 'joint_0' has unknown type 'hinge'; expected one of: revolute",
        ),
        (
            _GOOD.format(type="revolute", xyz="0 0 0", child="link_9"),
            "joint 'joint_0' references child link 'link_9', which is not defined",
        ),
        (
            _GOOD.format(type="revolute", xyz="nan 0 0", child="link_0"),
            r"joint 'joint_0' <origin xyz> must be 3 finite number\(s\), got 'nan 0 0'",
        ),
        (
            _GOOD.format(type="floating", xyz="0 0 0", child="link_0"),
            "joint 'joint_0' has type 'floating', which is not supported",
        ),
        (
            _GOOD.format(type="prismatic", xyz="0 0 0", child="link_0").replace(
                'upper="1"', 'upper="-z0.008"'
            ),
            r"joint 'joint_0' <limit upper> must be 1 finite number\(s\), got '-z0.008'",
        ),
        (
            _GOOD.format(type="revolute", xyz="0 0 0", child="link_0").replace(
                '<box size="0.1 0.1 0.1"/>', '<mesh filename="missing.obj"/>'
            ),
            "link 'link_0' <collision> mesh file 'missing.obj' not found",
        ),
    ],
    ids=[
        "missing",
        "bad-xml",
        "unknown-type",
        "undefined-link",
        "nan",
        "floating",
        "bad-number",
        "mesh",
    ],
)
def test_malformed_urdf_gives_one_clear_config_error(
    tmp_path: Path, text: str | None, message: str
) -> None:
    if text is not None:
        (tmp_path / "mobility.urdf").write_text(text)
    with pytest.raises(ConfigError, match=message) as info:
        load_articulated_object(tmp_path)
    assert isinstance(info.value, PlannersError)
    assert str(tmp_path) in str(info.value)


def test_a_malformed_semantics_file_is_named(tmp_path: Path) -> None:
    folder = write_partnet(generate_cabinet(0), tmp_path / "c")
    (folder / "semantics.txt").write_text("link_0 heavy furniture_body\nlink_1 slider\n")
    with pytest.raises(ConfigError, match=r"semantics.txt line 2: expected 'link_name joint_wo"):
        load_articulated_object(folder)


def test_shelf_only_cabinets_have_no_joints(tmp_path: Path) -> None:
    spec = generate_cabinet(2, kinds=("shelf",))
    obj = load_cabinet_spec(spec)  # in memory, as the Shelf task builds it
    assert obj.pin_model.nq == 0 and obj.mj_model.nv == 6 and not obj.movable_joints
    # A folder is an object to act on: one without a movable part is refused.
    with pytest.raises(ConfigError, match="no movable part"):
        load_articulated_object(write_partnet(spec, tmp_path))
    assert {li.semantic for li in obj.links.values()} == {"", "furniture_body", "shelf"}


def test_the_generation_tool_writes_the_partnet_layout(tmp_path: Path) -> None:
    path = Path(__file__).resolve().parents[1] / "tools" / "generate_cabinets.py"
    module_spec = importlib.util.spec_from_file_location("generate_cabinets", path)
    tool = importlib.util.module_from_spec(module_spec)
    module_spec.loader.exec_module(tool)
    assert (
        tool.main(["--seed", "4", "--count", "2", "--kinds", "door", "--out", str(tmp_path)]) == 0
    )
    for seed in (4, 5):
        folder = tmp_path / f"doors_{seed}"
        assert {p.name for p in folder.iterdir()} == {"mobility.urdf", "semantics.txt", "spec.json"}
        lines = (folder / "semantics.txt").read_text().splitlines()
        assert lines[0] == "link_0 heavy furniture_body"
        assert all(line.endswith(" hinge door") for line in lines[1:])
