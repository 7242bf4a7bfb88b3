"""Skills plan against the *believed* cabinet and execute in the true one.

Cabinet: ``models/cabinets/drawers_11`` (generator seed 11, drawers only: ``link_1..3``
with bar handles 1.06, 0.87 and 0.63 m high). A planning world is a
:class:`ManipulationWorld` built from a (believed) cabinet spec
(:func:`~strug_manip.objects.hypotheses.believed_spec`); the robot's state is copied
into it by joint name before every collision check and motion plan, while physics and
the outcome stay in the execution world. Spies come in through the
:class:`~strug_manip.control.context.ControlContext` (no monkeypatching).
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from planners.errors import ConfigError, UnknownNameError
from strug_manip.control import ControlContext, OpenDoor, OpenDrawer, Status, handle_grasps
from strug_manip.control.motion import ArmMotionPlanner
from strug_manip.objects.hypotheses import BelievedJoint, believed_spec, cell_joints
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

CONFIG = SceneConfig(cabinet_seed=11, cabinet_kinds=("drawer",))
TOP = "cabinet/joint_1"


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


def door_joint(truth: ManipulationWorld) -> BelievedJoint:
    """``link_1`` believed a door hinged on its cell's left edge (world frame)."""
    T = truth.scene.T_world_cabinet
    j = cell_joints(truth.scene.cabinet_spec.part("link_1"))["left"]
    return BelievedJoint(j.type, T[:3, :3] @ j.axis, (T @ np.r_[j.origin, 1.0])[:3], 1.5)


@pytest.fixture(scope="module")
def door_belief(truth: ManipulationWorld) -> ManipulationWorld:
    """A planning world in which the drawer ``link_1`` is believed to be a door."""
    spec = believed_spec(
        truth.scene.cabinet_spec, "link_1", door_joint(truth), truth.scene.T_world_cabinet
    )
    world = ManipulationWorld.from_cabinet_spec(spec, CONFIG)
    yield world
    world.close()


def grasp(world: ManipulationWorld, link: str, q: float = 0.0, k: int = 0) -> np.ndarray:
    part = world.scene.cabinet_spec.part(link)
    return handle_grasps(part, q, world.scene.T_world_cabinet)[k]


def true_joint(world: ManipulationWorld, link: str) -> BelievedJoint:
    part = world.scene.cabinet_spec.part(link)
    return BelievedJoint.of_part(part, 0.0, world.scene.T_world_cabinet)


def link_geoms(world: ManipulationWorld, body: str) -> np.ndarray:
    m = world.model
    ids = np.flatnonzero(m.geom_bodyid == m.body(body).id)
    return world.data.geom_xpos[ids].copy()


class SpyPlanner:
    """An :class:`ArmMotionPlanner` that records, at every plan, the planning world's
    and the true world's robot state."""

    def __init__(self, planner: ArmMotionPlanner, ctx: SpyContext) -> None:
        self.planner, self.ctx = planner, ctx

    def plan(self, *args, **kw):
        self.ctx.states.append((self.ctx.plan_world.robot_qpos(), self.ctx.truth.robot_qpos()))
        return self.planner.plan(*args, **kw)


class SpyContext(ControlContext):
    """A context that records the models every plan and collision check is made in."""

    def __init__(self, truth: ManipulationWorld, plan_world: ManipulationWorld) -> None:
        super().__init__()
        self.truth, self.plan_world = truth, plan_world
        self.models: list[mujoco.MjModel] = []
        self.states: list[tuple[dict, dict]] = []

    def planners(self, model):
        self.models.append(model)
        return tuple(SpyPlanner(p, self) for p in super().planners(model))

    def checker(self, model):
        self.models.append(model)
        return super().checker(model)


# --- building a planning world --------------------------------------------------------


def test_believed_spec_replaces_one_joint_and_keeps_the_geometry(truth, door_belief) -> None:
    true_spec = truth.scene.cabinet_spec
    spec = door_belief.scene.cabinet_spec
    part, old = spec.part("link_1"), true_spec.part("link_1")
    assert old.joint_type == "prismatic" and part.joint_type == "revolute"  # truth untouched
    assert part.upper == pytest.approx(1.5) and part.lower == 0.0
    assert part.hinge == "left"
    # The believed joint, read back in the world frame, is the one given.
    door_belief.reset()
    truth.reset()
    back = true_joint(door_belief, "link_1")
    door = door_joint(truth)
    assert back.type == "revolute"
    np.testing.assert_allclose(back.axis, door.axis, atol=1e-9)
    np.testing.assert_allclose(back.origin, door.origin, atol=1e-9)
    # The closed part sits where it truly is; the other parts are the truth's.
    np.testing.assert_allclose(
        link_geoms(door_belief, "cabinet/link_1"), link_geoms(truth, "cabinet/link_1"), atol=1e-9
    )
    for a, b in zip(spec.parts, true_spec.parts, strict=True):
        assert (a is b) == (a.link != "link_1")
    # A prismatic belief with another axis keeps the link frame; its limit is q + travel.
    slanted = BelievedJoint("prismatic", np.array([0.0, 0.0, 1.0]), limit=0.1)
    s2 = believed_spec(true_spec, "link_1", slanted, truth.scene.T_world_cabinet, q=0.05)
    p2 = s2.part("link_1")
    np.testing.assert_allclose(p2.axis, [0, 0, 1], atol=1e-12)
    np.testing.assert_array_equal(p2.origin, old.origin)
    assert p2.upper == pytest.approx(0.15)


def test_bad_belief_arguments_raise(truth) -> None:
    spec = truth.scene.cabinet_spec
    door = door_joint(truth)
    with pytest.raises(UnknownNameError, match=r"'link_99'.*link_1"):
        believed_spec(spec, "link_99", door)
    with pytest.raises(ConfigError, match="'door'"):
        believed_spec(spec, "link_1", "door")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="q must be a finite"):
        believed_spec(spec, "link_1", door, q=float("nan"))
    with pytest.raises(ConfigError, match="T_world_cabinet"):
        believed_spec(spec, "link_1", door, np.zeros((4, 4)))
    with pytest.raises(ConfigError):
        SceneConfig(cabinet_spec=spec, cabinet_folder="somewhere")
    with pytest.raises(ConfigError, match="cabinet_0003"):
        SceneConfig(cabinet_spec="cabinet_0003")  # type: ignore[arg-type]
    # A spec replaces the config's cabinet, a folder's too (a real object's particle).
    folded = ManipulationWorld.from_cabinet_spec(spec, SceneConfig(cabinet_folder="somewhere"))
    assert folded.config.cabinet_folder is None and folded.scene.cabinet_spec is spec
    folded.close()
    with pytest.raises(ConfigError, match="'belief'"):
        OpenDrawer(grasp(truth, "link_1"), true_joint(truth, "link_1")).run(
            truth,
            plan_world="belief",  # type: ignore[arg-type]
        )


def test_config_with_a_spec_stays_comparable(truth) -> None:
    a = dataclasses.replace(CONFIG, cabinet_spec=truth.scene.cabinet_spec)
    assert a == CONFIG and hash(a) == hash(CONFIG)


# --- the robot state goes over by joint name --------------------------------------------


def test_robot_state_is_copied_by_name_and_the_cabinet_kept(truth, door_belief) -> None:
    truth.reset({"joint_1": 0.1})
    rng = np.random.default_rng(0)
    m = truth.model
    for name in truth.robot_joints:
        truth.data.qpos[m.jnt_qposadr[m.joint(name).id]] += rng.uniform(-0.05, 0.05)
    door_belief.reset({"joint_1": 0.3})
    door_belief.copy_robot_state(truth)
    assert door_belief.robot_qpos() == truth.robot_qpos()
    np.testing.assert_array_equal(door_belief.object_pose(), truth.object_pose())
    assert door_belief.part_positions()[TOP] == 0.3  # the belief, not the truth
    # The cabinet's free joint goes over when asked (where the real one was dragged to).
    free = truth.model.jnt_qposadr[truth.model.joint("cabinet/free").id]
    truth.data.qpos[free : free + 2] += [0.03, -0.02]
    mujoco.mj_kinematics(truth.model, truth.data)
    door_belief.copy_joints(truth, ["cabinet/free"])
    np.testing.assert_allclose(
        door_belief.body_pose("cabinet/base"), truth.body_pose("cabinet/base"), atol=1e-12
    )
    truth.reset()
    door_belief.reset()


def test_plans_and_checks_use_the_planning_world_holding_the_robot_state(truth, door_belief):
    """Under the door belief: every plan and check is made in the believed model, with
    the robot where it truly is; physics runs in the truth only."""
    ctx = SpyContext(truth, door_belief)
    truth.reset()
    door_belief.reset()
    # The planning world starts elsewhere: the run must bring its robot over.
    m = door_belief.model
    door_belief.data.qpos[m.jnt_qposadr[m.joint("torso_lift_joint").id]] = 0.1
    out = OpenDoor(grasp(truth, "link_1"), door_joint(truth)).run(
        truth, ctx=ctx, plan_world=door_belief
    )
    assert out.status is not Status.IK_INFEASIBLE, out.summary()
    assert ctx.models and all(model is door_belief.model for model in ctx.models)
    assert ctx.states
    for believed, true in ctx.states:
        assert believed == true
    assert door_belief.data.time == 0.0 and door_belief.cabinet_displacement() == 0.0
    assert out.part_units[TOP] == "m"  # the facts are the true drawer's
    assert out.motion_of(TOP) == truth.part_positions()[TOP]


def test_planning_under_the_true_spec_gives_the_same_run(truth, same_belief) -> None:
    """The same run, bit for bit, up to the end of the retreat; the stow after it is
    planned with the believed drawer where the opening line took it (its commanded
    travel), the true one a few millimetres further out, so OMPL may take another path
    back to the tuck."""
    g, joint = grasp(truth, "link_1"), true_joint(truth, "link_1")
    ctx = ControlContext()
    truth.reset()
    keys: list[tuple[str, float]] = []
    plain = OpenDrawer(g, joint).run(
        truth, ctx=ctx, observer=lambda name: keys.append((name, float(truth.data.time)))
    )
    truth.reset()
    same_belief.reset()
    out = OpenDrawer(g, joint).run(truth, ctx=ctx, plan_world=same_belief)
    assert out.ok and plain.ok, out.summary()
    assert out.motion_of(TOP) > 0.15
    assert out.motion_of(TOP) == pytest.approx(plain.motion_of(TOP), abs=1e-4)
    assert out.cabinet_displacement == pytest.approx(plain.cabinet_displacement, abs=1e-4)
    t_retreat = dict(keys)["retreat"] - keys[0][1]
    n = int(np.searchsorted(plain.times, t_retreat))
    assert n > 100
    np.testing.assert_array_equal(out.qpos[:n], plain.qpos[:n])


def test_believed_geometry_decides_the_plan(truth, same_belief) -> None:
    """The robot acts on its belief: a drawer believed open 0.2 m while it is truly
    closed is grasped where the belief has its handle, and the fingers close on
    nothing; the true drawer stays shut (and the plan is checked in the belief only)."""
    ctx = ControlContext()
    # Believed open 0.2 m while truly closed: the robot grasps where the belief has the
    # handle and closes its fingers on nothing; the true drawer stays shut.
    truth.reset()
    same_belief.reset({"joint_1": 0.2})
    out = OpenDrawer(grasp(truth, "link_1", q=0.2), true_joint(truth, "link_1")).run(
        truth, ctx=ctx, plan_world=same_belief
    )
    assert out.status is Status.GRASP_LOST, out.summary()
    assert abs(out.motion_of(TOP)) < 0.01 and not out.holding
    same_belief.reset()
