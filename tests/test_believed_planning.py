"""Issue 5: controllers plan against the *believed* cabinet, execute in the true one.

Cabinet: generator seed 3, drawers only (top drawer ``link_1``, bar handle 0.82 m high
on the robot's forward line, 0.25 m of travel), as in ``test_controllers.py``. A
planning world is a :class:`ManipulationWorld` built from a (believed) cabinet spec;
the robot's state is copied into it by joint name before every collision check and
motion plan, while physics and the outcome stay in the execution world.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from planners.errors import ConfigError, UnknownNameError
from strug_manip.control import controllers
from strug_manip.control.controllers import (
    BelievedJoint,
    OpenDrawer,
    believed_spec,
    handle_grasp,
    true_joint,
)
from strug_manip.control.motion import ArmMotionPlanner
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

CONFIG = SceneConfig(cabinet_seed=3, cabinet_kinds=("drawer",))
DRAWER_JOINT = "cabinet/joint_1"


@pytest.fixture(scope="module")
def truth() -> ManipulationWorld:
    world = ManipulationWorld(CONFIG)
    yield world
    world.close()


@pytest.fixture(scope="module")
def same_belief(truth: ManipulationWorld) -> ManipulationWorld:
    """A planning world built from the true spec."""
    world = ManipulationWorld.from_cabinet_spec(truth.scene.cabinet_spec, CONFIG)
    yield world
    world.close()


def _door_belief(truth: ManipulationWorld) -> tuple[np.ndarray, BelievedJoint]:
    """The drawer's grasp and a belief that it is a door hinged 0.35 m to the handle's
    right (world frame)."""
    truth.reset()
    g = handle_grasp(truth, "link_1")
    door = BelievedJoint("revolute", np.array([0.0, 0.0, 1.0]), g[:3, 3] + [0.03, -0.35, 0], 1.5)
    return g, door


@pytest.fixture(scope="module")
def door_belief(truth: ManipulationWorld) -> ManipulationWorld:
    """A planning world in which the drawer ``link_1`` is believed to be a door."""
    _, door = _door_belief(truth)
    spec = believed_spec(truth.scene.cabinet_spec, "link_1", door, truth.scene.T_world_cabinet)
    world = ManipulationWorld.from_cabinet_spec(spec, CONFIG)
    yield world
    world.close()


def _link_geoms(world: ManipulationWorld, body: str) -> np.ndarray:
    m = world.model
    ids = np.flatnonzero(m.geom_bodyid == m.body(body).id)
    return world.data.geom_xpos[ids].copy()


# --- building a planning world --------------------------------------------------------------


def test_believed_spec_replaces_one_joint_and_keeps_the_geometry(
    truth: ManipulationWorld, door_belief: ManipulationWorld
) -> None:
    true_spec = truth.scene.cabinet_spec
    spec = door_belief.scene.cabinet_spec
    part, old = spec.part("link_1"), true_spec.part("link_1")
    assert old.joint_type == "prismatic" and part.joint_type == "revolute"  # truth untouched
    assert part.upper == pytest.approx(1.5) and part.lower == 0.0
    # The believed joint, read back in the world frame, is the one given.
    _, door = _door_belief(truth)
    door_belief.reset()
    back = true_joint(door_belief, "link_1")
    assert back.type == "revolute"
    np.testing.assert_allclose(back.axis, door.axis, atol=1e-9)
    np.testing.assert_allclose(back.origin, door.origin, atol=1e-9)
    # The closed part sits where it truly is; the other parts are the truth's.
    np.testing.assert_allclose(
        _link_geoms(door_belief, "cabinet/link_1"), _link_geoms(truth, "cabinet/link_1"), atol=1e-9
    )
    for a, b in zip(spec.parts, true_spec.parts, strict=True):
        assert (a is b) == (a.link != "link_1")
    # A prismatic belief with another axis keeps the link frame.
    slanted = BelievedJoint("prismatic", np.array([0.0, 0.0, 1.0]), limit=0.1)
    s2 = believed_spec(true_spec, "link_1", slanted, truth.scene.T_world_cabinet, q=0.05)
    p2 = s2.part("link_1")
    np.testing.assert_allclose(p2.axis, [0, 0, 1], atol=1e-12)
    np.testing.assert_array_equal(p2.origin, old.origin)
    assert p2.upper == pytest.approx(0.15)


def test_bad_belief_arguments_raise(truth: ManipulationWorld) -> None:
    _, door = _door_belief(truth)
    with pytest.raises(UnknownNameError):
        believed_spec(truth.scene.cabinet_spec, "link_99", door)
    with pytest.raises(ConfigError):
        believed_spec(truth.scene.cabinet_spec, "link_1", "door")  # type: ignore[arg-type]
    with pytest.raises(ConfigError):
        SceneConfig(cabinet_spec=truth.scene.cabinet_spec, cabinet_folder="somewhere")
    with pytest.raises(ConfigError):
        SceneConfig(cabinet_spec="cabinet_0003")  # type: ignore[arg-type]
    g, _ = _door_belief(truth)
    joint = true_joint(truth, "link_1")
    with pytest.raises(ConfigError):
        OpenDrawer(g, joint).run(truth, plan_world="belief")  # type: ignore[arg-type]


def test_config_with_a_spec_stays_comparable(truth: ManipulationWorld) -> None:
    a = dataclasses.replace(CONFIG, cabinet_spec=truth.scene.cabinet_spec)
    assert a == CONFIG and hash(a) == hash(CONFIG)


# --- (c) the robot state goes over by joint name --------------------------------------------


def test_robot_state_is_copied_by_name_and_the_cabinet_kept(
    truth: ManipulationWorld, door_belief: ManipulationWorld
) -> None:
    truth.reset({"joint_1": 0.1})
    rng = np.random.default_rng(0)
    m = truth.model
    for name in truth.robot_joints:
        truth.data.qpos[m.jnt_qposadr[m.joint(name).id]] += rng.uniform(-0.05, 0.05)
    door_belief.reset({"joint_1": 0.3})
    door_belief.copy_robot_state(truth)
    assert door_belief.robot_qpos() == truth.robot_qpos()
    np.testing.assert_array_equal(door_belief.object_pose(), truth.object_pose())
    assert door_belief.part_positions()[DRAWER_JOINT] == 0.3  # the belief, not the truth
    truth.reset()
    door_belief.reset()


def test_plan_world_holds_the_robot_state_before_each_plan(
    truth: ManipulationWorld, same_belief: ManipulationWorld, monkeypatch: pytest.MonkeyPatch
) -> None:
    seen: list[tuple[dict[str, float], dict[str, float]]] = []
    plan = ArmMotionPlanner.plan

    def spy(self, q_start, q_goal, data, **kw):
        seen.append((same_belief.robot_qpos(), truth.robot_qpos()))
        return plan(self, q_start, q_goal, data, **kw)

    monkeypatch.setattr(ArmMotionPlanner, "plan", spy)
    truth.reset()
    same_belief.reset()
    # The planning world starts elsewhere: the run must bring its robot over.
    same_belief.data.qpos[
        same_belief.model.jnt_qposadr[same_belief.model.joint("torso_lift_joint").id]
    ] = 0.3
    g = handle_grasp(truth, "link_1")
    OpenDrawer(g, true_joint(truth, "link_1")).run(truth, plan_world=same_belief)
    assert seen
    for believed, true in seen:
        assert believed == true


# --- (a) the true spec as belief changes nothing ---------------------------------------------


def test_planning_under_the_true_spec_gives_the_same_outcome(
    truth: ManipulationWorld, same_belief: ManipulationWorld
) -> None:
    truth.reset()
    g = handle_grasp(truth, "link_1")
    joint = true_joint(truth, "link_1")
    plain = OpenDrawer(g, joint).run(truth)
    truth.reset()
    same_belief.reset()
    out = OpenDrawer(g, joint).run(truth, plan_world=same_belief)
    assert out.success, out.detail
    assert out.part_motion[DRAWER_JOINT] > 0.1
    assert out.same_as(plain)
    assert same_belief.part_positions()[DRAWER_JOINT] == 0.0  # the belief did not move


# --- (b) plan under a wrong belief, execute in the truth --------------------------------------


def test_plans_against_the_believed_door_and_executes_in_the_true_drawer(
    truth: ManipulationWorld, door_belief: ManipulationWorld, monkeypatch: pytest.MonkeyPatch
) -> None:
    plan_models: list[mujoco.MjModel] = []
    check_models: list[mujoco.MjModel] = []
    plan = ArmMotionPlanner.plan

    def spy_plan(self, q_start, q_goal, data, **kw):
        plan_models.append(self.model)
        assert data.qpos.shape == (door_belief.model.nq,)
        return plan(self, q_start, q_goal, data, **kw)

    class SpyChecker(controllers.PathCollisionChecker):
        def __init__(self, world: ManipulationWorld, base: np.ndarray) -> None:
            check_models.append(world.model)
            super().__init__(world, base)

    monkeypatch.setattr(ArmMotionPlanner, "plan", spy_plan)
    monkeypatch.setattr(controllers, "PathCollisionChecker", SpyChecker)
    g, door = _door_belief(truth)
    door_belief.reset()
    out = OpenDrawer(g, door, travel=0.8).run(truth, plan_world=door_belief)
    assert plan_models and check_models
    assert all(m is door_belief.model for m in plan_models + check_models)
    # Physics in the true world decides: the arc pulls against the drawer's slide.
    assert not out.success
    assert out.reason in ("grasp_lost", "collision") or out.cabinet_displacement > 0.1
    assert door_belief.part_positions()[DRAWER_JOINT] == 0.0
    assert door_belief.cabinet_displacement() == 0.0


def test_believed_geometry_decides_the_plan(
    truth: ManipulationWorld, same_belief: ManipulationWorld
) -> None:
    """Believed open 0.25 m, the drawer fills the space the gripper would approach
    through: the plan fails under the belief although the true drawer is closed (and
    opens under the true model, see above); the true cabinet is not touched."""
    truth.reset()
    g = handle_grasp(truth, "link_1")
    joint = true_joint(truth, "link_1")
    same_belief.reset({"joint_1": 0.25})
    out = OpenDrawer(g, joint).run(truth, plan_world=same_belief)
    same_belief.reset()
    assert not out.success
    assert out.reason in ("collision", "no_motion_plan"), out.detail
    assert abs(out.part_motion[DRAWER_JOINT]) < 0.01
    assert out.cabinet_displacement < 0.01
