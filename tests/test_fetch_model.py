"""Asset tests for ``models/fetch``: MuJoCo compiles and simulates it cleanly, and the
URDF loaded by Pinocchio has the same kinematics (joints mapped by name)."""

from __future__ import annotations

import importlib.util
import math
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np
import pytest
from fetch_pinocchio import FetchKinematics

from planners.errors import ConfigError, PlannersError
from strug_manip.robot import (
    ACTUATORS,
    ALL_JOINTS,
    ARM_JOINTS,
    BASE_JOINTS,
    FETCH_DIR,
    FETCH_SCENE_XML,
    FETCH_URDF,
    FETCH_XML,
    GRIPPER_JOINTS,
    GRIPPER_SITE,
    HEAD_CAMERA,
    HEAD_JOINTS,
    HOME_KEYFRAME,
    TORSO_JOINT,
)

SIM_SECONDS = 2.0
BASE_XY_RANGE = 3.0  # [m] random base positions are drawn in [-3, 3]^2


@pytest.fixture(scope="module")
def mj_model() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(FETCH_XML))


@pytest.fixture(scope="module")
def kin() -> FetchKinematics:
    return FetchKinematics(FETCH_URDF)


def _simulate_home(model: mujoco.MjModel, seconds: float) -> mujoco.MjData:
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key(HOME_KEYFRAME).id)
    for _ in range(round(seconds / model.opt.timestep)):
        mujoco.mj_step(model, data)
    return data


def _random_q(model: mujoco.MjModel, rng: np.random.Generator) -> dict[str, float]:
    """A random configuration within the MuJoCo joint limits, by joint name."""
    q: dict[str, float] = {}
    for j in range(model.njnt):
        name = model.joint(j).name
        if model.jnt_limited[j]:
            q[name] = float(rng.uniform(*model.jnt_range[j]))
        elif name == "base_yaw_joint":
            q[name] = float(rng.uniform(-math.pi, math.pi))
        else:
            q[name] = float(rng.uniform(-BASE_XY_RANGE, BASE_XY_RANGE))
    return q


def _mj_set(model: mujoco.MjModel, data: mujoco.MjData, q: dict[str, float]) -> None:
    for name, value in q.items():
        data.qpos[model.joint(name).qposadr[0]] = value
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)  # camera poses (fixed cameras need no mj_comPos)


# -- MuJoCo ------------------------------------------------------------------------------


@pytest.mark.parametrize("path", [FETCH_XML, FETCH_SCENE_XML], ids=["fetch", "scene"])
def test_compiles_and_simulates_without_warnings(path: Path) -> None:
    model = mujoco.MjModel.from_xml_path(str(path))
    data = _simulate_home(model, SIM_SECONDS)
    warnings = {mujoco.mjtWarning(i).name: data.warning[i].number for i in range(len(data.warning))}
    assert all(n == 0 for n in warnings.values()), warnings
    for field in ("qpos", "qvel", "qacc", "ctrl", "actuator_force"):
        assert np.isfinite(getattr(data, field)).all(), field


def test_home_keyframe_holds(mj_model: mujoco.MjModel) -> None:
    key = mj_model.key(HOME_KEYFRAME)
    data = _simulate_home(mj_model, SIM_SECONDS)
    for name in ARM_JOINTS:
        adr = mj_model.joint(name).qposadr[0]
        assert abs(data.qpos[adr] - key.qpos[adr]) < 0.02, name
    for name in GRIPPER_JOINTS:  # open
        assert data.qpos[mj_model.joint(name).qposadr[0]] > 0.045, name
    assert data.ncon == 0  # tucked without touching itself


def test_joints_actuators_sites(mj_model: mujoco.MjModel) -> None:
    names = {mj_model.joint(j).name for j in range(mj_model.njnt)}
    assert names == set(ALL_JOINTS)
    types = {mj_model.joint(j).name: mj_model.jnt_type[j] for j in range(mj_model.njnt)}
    assert [types[n] for n in BASE_JOINTS] == [
        mujoco.mjtJoint.mjJNT_SLIDE,
        mujoco.mjtJoint.mjJNT_SLIDE,
        mujoco.mjtJoint.mjJNT_HINGE,
    ]
    pid = int(mujoco.mjtDyn.mjDYN_PID)
    for joint, act in ACTUATORS.items():
        a = mj_model.actuator(act)
        if joint in GRIPPER_JOINTS:  # one force-limited position servo on a tendon
            assert a.trntype[0] == mujoco.mjtTrn.mjTRN_TENDON
            assert a.forcelimited[0] and a.forcerange[1] > 0
        elif joint in HEAD_JOINTS:  # position servo, ctrlrange = joint range
            assert a.gainprm[0] > 0 and a.biasprm[1] == -a.gainprm[0], act
            np.testing.assert_array_equal(a.ctrlrange, mj_model.joint(joint).range, err_msg=act)
        else:  # base, torso, arm: PID position servo (kp, damping, integral with
            # anti-windup), clamped at the effort limit; two controls (position, velocity)
            assert int(a.dyntype[0]) == pid, act
            # MuJoCo's PID layout: gain ki, bias (0, -kp, -kv), dynprm[0] the integral clamp.
            assert a.gainprm[0] > 0 and a.biasprm[1] < 0 and a.biasprm[2] < 0, act
            assert a.dynprm[0] > 0, act
            assert a.forcelimited[0] and a.forcerange[1] > 0, act
            if joint not in BASE_JOINTS:
                j = mj_model.joint(joint)
                np.testing.assert_array_equal(a.ctrlrange[0], j.range, err_msg=act)
    assert mj_model.site(GRIPPER_SITE).id >= 0
    assert mj_model.site(HEAD_CAMERA).id >= 0 and mj_model.camera(HEAD_CAMERA).id >= 0


def test_scene_has_no_shadows() -> None:
    model = mujoco.MjModel.from_xml_path(str(FETCH_SCENE_XML))
    assert model.nlight >= 1 and not model.light_castshadow.any()
    root = ET.parse(FETCH_SCENE_XML).getroot()
    assert root.find("compiler").get("angle") == "radian"
    assert ET.parse(FETCH_XML).getroot().find("compiler").get("angle") == "radian"


# -- Pinocchio against MuJoCo ------------------------------------------------------------


def test_urdf_has_the_same_joints(mj_model: mujoco.MjModel, kin: FetchKinematics) -> None:
    assert set(kin.joint_names) == set(ALL_JOINTS)
    limits = kin.joint_limits()
    for j in range(mj_model.njnt):
        name = mj_model.joint(j).name
        if mj_model.jnt_limited[j]:
            np.testing.assert_allclose(limits[name], mj_model.jnt_range[j], err_msg=name)


def test_pinocchio_matches_mujoco_at_random_configurations(
    mj_model: mujoco.MjModel, kin: FetchKinematics
) -> None:
    data = mujoco.MjData(mj_model)
    rng = np.random.default_rng(0)
    for _ in range(50):
        q = _random_q(mj_model, rng)
        _mj_set(mj_model, data, q)
        for frame, site in ((None, GRIPPER_SITE), (HEAD_CAMERA, HEAD_CAMERA)):
            T = kin.forward(q) if frame is None else kin.frame_pose(frame, q)
            np.testing.assert_allclose(T[:3, 3], data.site(site).xpos, atol=1e-6, rtol=0)
            R_mj = data.site(site).xmat.reshape(3, 3)
            np.testing.assert_allclose(T[:3, :3], R_mj, atol=1e-6, rtol=0)
        # the camera and its site coincide
        np.testing.assert_allclose(data.cam(HEAD_CAMERA).xpos, data.site(HEAD_CAMERA).xpos)


def test_gripper_jacobian_matches_finite_differences(
    mj_model: mujoco.MjModel, kin: FetchKinematics
) -> None:
    rng = np.random.default_rng(1)
    h = 1e-6
    for _ in range(5):
        q = _random_q(mj_model, rng)
        J = kin.jacobian(q, ALL_JOINTS)
        assert J.shape == (6, len(ALL_JOINTS))
        T0 = kin.forward(q)
        for k, name in enumerate(ALL_JOINTS):
            Tp = kin.forward({**q, name: q[name] + h})
            Tm = kin.forward({**q, name: q[name] - h})
            v = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
            dR = (Tp[:3, :3] - Tm[:3, :3]) / (2 * h) @ T0[:3, :3].T  # = [w]x
            w = np.array([dR[2, 1], dR[0, 2], dR[1, 0]])
            np.testing.assert_allclose(J[:3, k], v, atol=1e-5, rtol=0, err_msg=name)
            np.testing.assert_allclose(J[3:, k], w, atol=1e-5, rtol=0, err_msg=name)


def test_jacobian_columns_follow_the_requested_names(kin: FetchKinematics) -> None:
    q = {"shoulder_pan_joint": 0.3, "elbow_flex_joint": -0.5}
    full = kin.jacobian(q)
    sub = kin.jacobian(q, ["elbow_flex_joint", "base_x_joint"])
    np.testing.assert_array_equal(sub[:, 0], full[:, kin.joint_names.index("elbow_flex_joint")])
    np.testing.assert_array_equal(sub[:, 1], [1, 0, 0, 0, 0, 0])


# -- errors ------------------------------------------------------------------------------


def test_unknown_joint_name_lists_the_valid_ones(kin: FetchKinematics) -> None:
    with pytest.raises(PlannersError, match="elbow_flex_joint"):
        kin.forward({"elbow": 1.0})
    with pytest.raises(PlannersError, match="shoulder_pan_joint"):
        kin.jacobian({}, ["nope"])
    with pytest.raises(PlannersError, match="gripper"):
        kin.frame_pose("tcp", {})


@pytest.mark.parametrize("value", [math.nan, math.inf, "1.0", None])
def test_bad_joint_values_are_rejected(kin: FetchKinematics, value: object) -> None:
    with pytest.raises(ConfigError, match="torso_lift_joint"):
        kin.forward({TORSO_JOINT: value})  # type: ignore[dict-item]


def test_bad_urdf_path_or_content(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="not found"):
        FetchKinematics(tmp_path / "missing.urdf")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'/><joint name='j' type='bogus'/></robot>")
    with pytest.raises(ConfigError, match=r"bad\.urdf"):
        FetchKinematics(bad)


def test_joint_groups_partition_the_robot() -> None:
    groups = (*BASE_JOINTS, TORSO_JOINT, *ARM_JOINTS, *GRIPPER_JOINTS, *HEAD_JOINTS)
    assert len(groups) == len(set(groups)) == 15 and set(groups) == set(ALL_JOINTS)


# -- the generated files are what the build script writes ---------------------------------


@pytest.mark.skipif(
    importlib.util.find_spec("gymnasium_robotics") is None,
    reason="gymnasium-robotics (the model's source) is not installed",
)
def test_model_files_are_up_to_date(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location(
        "build_fetch_model", FETCH_DIR.parents[1] / "tools" / "build_fetch_model.py"
    )
    assert spec is not None and spec.loader is not None
    tool = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = tool  # dataclasses resolve annotations through sys.modules
    try:
        spec.loader.exec_module(tool)
        tool.build(tmp_path)
    finally:
        del sys.modules[spec.name]
    for name in ("fetch.xml", "scene.xml", "fetch.urdf"):
        assert (tmp_path / name).read_text() == (FETCH_DIR / name).read_text(), name
    for mesh in (tmp_path / "assets").iterdir():
        assert mesh.read_bytes() == (FETCH_DIR / "assets" / mesh.name).read_bytes(), mesh.name
