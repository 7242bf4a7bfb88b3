"""Arm motion planning with OMPL in the manipulation scene (issue 5, second bullet).

Plans are replayed in MuJoCo twice: kinematically (densely interpolated waypoints set
in a scratch ``MjData``, contacts checked by code independent of the planner's) and
executed by the position actuators while stepping physics; neither may produce a robot
contact, and the cabinet must not move.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from planners.errors import ConfigError, UnknownNameError
from strug_manip.control.motion import (
    DEFAULT_JOINTS,
    GOAL_INVALID,
    NO_PLAN,
    START_INVALID,
    ArmMotionPlanner,
    MotionPlan,
)
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

#: Untucked ready posture (torso + arm, DEFAULT_JOINTS order): the scripted opening's
#: untuck waypoint, forearm forward, gripper pointing forward.
READY = (0.3, 1.32, 1.40, -1.5, 1.72, 0.0, 0.0, 0.0)
#: Gripper at (0.80, 0, 0.85) m pointing +x, 0.2 m in front of the cabinet (IK solution).
IN_FRONT = (0.376, 0.794, 0.853, -1.383, 1.538, 0.976, -0.906, 1.382)
#: Arm stretched forward: the gripper is inside the top drawer's front.
INTO_CABINET = (0.064, 0.0, 0.0, -1.013, -0.001, 0.465, 0.001, 0.548)
#: With the top drawer open by DRAWER_OPEN: gripper below it at (0.70, 0, 0.45) m and
#: above it at (0.75, 0, 1.10) m, both pointing +x; the straight joint-space line between
#: them hits the drawer, so the planner must go around it.
BELOW_DRAWER = (0.011, 1.196, 1.425, -1.44, 1.595, 1.418, -0.508, 1.58)
ABOVE_DRAWER = (0.376, 0.746, 0.599, -1.734, 2.145, 0.317, -1.277, 2.024)
DRAWER_OPEN = {"joint_1": 0.22}
#: Joint step of the kinematic replay [rad or m].
REPLAY_STEP = 0.005


def q_of(values: tuple[float, ...]) -> dict[str, float]:
    return dict(zip(DEFAULT_JOINTS, values, strict=True))


@pytest.fixture(scope="module")
def world() -> ManipulationWorld:
    w = ManipulationWorld(SceneConfig(cabinet_seed=3))
    yield w
    w.close()


@pytest.fixture(scope="module")
def planner(world: ManipulationWorld) -> ArmMotionPlanner:
    return ArmMotionPlanner(world.model)


def place_robot(world: ManipulationWorld, q: tuple[float, ...], parts=None) -> None:
    """Reset the world, then put torso + arm at ``q`` (kinematically, actuators too)."""
    world.reset(parts)
    m, d = world.model, world.data
    for name, v in zip(DEFAULT_JOINTS, q, strict=True):
        d.qpos[m.jnt_qposadr[m.joint(name).id]] = v
        d.ctrl[m.actuator(name.removesuffix("_joint")).id] = v
    mujoco.mj_forward(m, d)


class RobotContacts:
    """Robot contacts in a MuJoCo state (independent of the planner's bookkeeping)."""

    def __init__(self, world: ManipulationWorld) -> None:
        m = world.model
        self.m = m
        pre = world.scene.cabinet_prefix
        non_robot = ("world", "table", "object")
        self.robot = {
            b
            for b in range(m.nbody)
            if not (m.body(b).name.startswith(pre) or m.body(b).name in non_robot)
        }
        assert m.body("shoulder_pan_link").id in self.robot

    def __call__(self, d: mujoco.MjData) -> list[str]:
        m = self.m
        out = []
        for k in range(d.ncon):
            c = d.contact[k]
            b1, b2 = int(m.geom_bodyid[c.geom1]), int(m.geom_bodyid[c.geom2])
            if b1 in self.robot or b2 in self.robot:
                out.append(f"{m.body(b1).name}/{m.body(b2).name} ({c.dist * 1000:.1f} mm)")
        return out


def replay_kinematic(world: ManipulationWorld, plan: MotionPlan) -> list[str]:
    """Contacts along the waypoint polyline, sampled every REPLAY_STEP."""
    m = world.model
    d = mujoco.MjData(m)
    d.qpos[:] = world.data.qpos
    adr = [m.jnt_qposadr[m.joint(n).id] for n in plan.joints]
    contacts = RobotContacts(world)
    for qa, qb in zip(plan.waypoints[:-1], plan.waypoints[1:], strict=True):
        n = max(1, math.ceil(float(np.max(np.abs(qb - qa))) / REPLAY_STEP))
        for k in range(n + 1):
            d.qpos[adr] = qa + (k / n) * (qb - qa)
            mujoco.mj_kinematics(m, d)
            mujoco.mj_collision(m, d)
            hits = contacts(d)
            if hits:
                return hits
    return []


def execute(world: ManipulationWorld, plan: MotionPlan) -> tuple[list[str], float]:
    """Run the trajectory through the position actuators, stepping physics, then hold for
    0.5 s. Returns (robot contacts seen at any step, max tracking error [rad or m])."""
    m, d = world.model, world.data
    act = [m.actuator(n.removesuffix("_joint")).id for n in plan.joints]
    adr = [m.jnt_qposadr[m.joint(n).id] for n in plan.joints]
    contacts = RobotContacts(world)
    _, qs = plan.trajectory(m.opt.timestep)
    hold = np.repeat(qs[-1:], round(0.5 / m.opt.timestep), axis=0)
    seen: list[str] = []
    err = 0.0
    for q in np.vstack([qs, hold]):
        d.ctrl[act] = q
        mujoco.mj_step(m, d)
        err = max(err, float(np.max(np.abs(d.qpos[adr] - q))))
        seen += contacts(d)
    return seen, err


def check_replays(world: ManipulationWorld, plan: MotionPlan) -> None:
    parts_before = world.part_positions()
    assert replay_kinematic(world, plan) == []
    hits, err = execute(world, plan)
    assert hits == [], hits[:5]
    assert err < 0.08, f"tracking error {err:.3f}"  # position actuators lag a little
    assert world.cabinet_displacement() < 1e-3
    for name, q in world.part_positions().items():
        assert abs(q - parts_before[name]) < 1e-3, name
    m, d = world.model, world.data
    final = [d.qpos[m.jnt_qposadr[m.joint(n).id]] for n in plan.joints]
    np.testing.assert_allclose(final, plan.waypoints[-1], atol=0.02)


@pytest.mark.parametrize("try_straight", [True, False], ids=["straight-first", "rrtconnect"])
def test_ready_to_front_of_cabinet_replays_collision_free(world, try_straight: bool) -> None:
    planner = ArmMotionPlanner(world.model, try_straight=try_straight)
    place_robot(world, READY)
    start, goal = q_of(READY), q_of(IN_FRONT)
    assert planner.contacts(start, world.data) == []
    assert planner.contacts(goal, world.data) == []
    plan = planner.plan(start, goal, world.data, timeout=2.0, seed=0)
    assert plan.success, (plan.reason, plan.detail)
    assert plan.reason == ""
    assert plan.waypoints.shape[1] == len(DEFAULT_JOINTS) and len(plan.waypoints) >= 2
    np.testing.assert_array_equal(plan.waypoints[0], READY)
    np.testing.assert_array_equal(plan.waypoints[-1], IN_FRONT)
    straight = float(np.linalg.norm(np.subtract(IN_FRONT, READY)))
    assert plan.path_length >= straight - 1e-9
    assert 0 < plan.planning_time < 2.0 + 5.0
    check_replays(world, plan)


def test_plan_around_open_drawer_replays_collision_free(world, planner) -> None:
    place_robot(world, BELOW_DRAWER, DRAWER_OPEN)
    start, goal = q_of(BELOW_DRAWER), q_of(ABOVE_DRAWER)
    # The straight line is blocked: planning is needed.
    line = [{n: start[n] + s * (goal[n] - start[n]) for n in start} for s in np.linspace(0, 1, 101)]
    assert any(planner.contacts(q, world.data) for q in line)
    straight = MotionPlan(True, DEFAULT_JOINTS, np.array([BELOW_DRAWER, ABOVE_DRAWER]), 0, 0)
    assert replay_kinematic(world, straight) != []  # the replay does see collisions
    plan = planner.plan(start, goal, world.data, timeout=3.0, seed=1)
    assert plan.success, (plan.reason, plan.detail)
    assert len(plan.waypoints) >= 3
    check_replays(world, plan)


def test_no_plan_within_tiny_timeout(world, planner) -> None:
    place_robot(world, BELOW_DRAWER, DRAWER_OPEN)
    plan = planner.plan(q_of(BELOW_DRAWER), q_of(ABOVE_DRAWER), world.data, timeout=1e-4)
    assert not plan.success
    assert plan.reason == NO_PLAN


def test_same_seed_same_plan(world, planner) -> None:
    place_robot(world, BELOW_DRAWER, DRAWER_OPEN)
    start, goal = q_of(BELOW_DRAWER), q_of(ABOVE_DRAWER)
    a = planner.plan(start, goal, world.data, timeout=3.0, seed=7)
    b = planner.plan(start, goal, world.data, timeout=3.0, seed=7)
    assert a.success and b.success
    np.testing.assert_array_equal(a.waypoints, b.waypoints)


def test_trajectory_within_velocity_limits(world, planner) -> None:
    place_robot(world, READY)
    plan = planner.plan(q_of(READY), q_of(IN_FRONT), world.data, seed=0)
    assert plan.success
    dt = 0.01
    times, qs = plan.trajectory(dt)
    assert times[0] == 0.0 and math.isclose(times[-1], plan.duration)
    assert np.all(np.diff(times) > 0) and np.all(np.diff(times) <= dt + 1e-12)
    assert qs.shape == (len(times), len(DEFAULT_JOINTS))
    np.testing.assert_allclose(qs[0], READY, atol=1e-12)
    np.testing.assert_allclose(qs[-1], IN_FRONT, atol=1e-12)
    speed = np.abs(np.diff(qs, axis=0)) / np.diff(times)[:, None]
    assert np.all(speed <= plan.velocity_limits * (1 + 1e-6))
    with pytest.raises(ConfigError):
        plan.trajectory(0.0)


def test_goal_inside_cabinet_is_goal_invalid(world, planner) -> None:
    place_robot(world, READY)
    plan = planner.plan(q_of(READY), q_of(INTO_CABINET), world.data, seed=0)
    assert not plan.success
    assert plan.reason == GOAL_INVALID
    assert "cabinet/" in plan.detail
    assert plan.waypoints.shape == (0, len(DEFAULT_JOINTS))
    with pytest.raises(ConfigError):
        plan.trajectory(0.01)


def test_start_invalid_and_allowed_contacts(world) -> None:
    place_robot(world, READY)
    planner = ArmMotionPlanner(world.model)
    plan = planner.plan(q_of(INTO_CABINET), q_of(READY), world.data, seed=0)
    assert plan.reason == START_INVALID
    out_of_range = q_of(READY) | {"elbow_flex_joint": 3.0}
    plan = planner.plan(out_of_range, q_of(READY), world.data, seed=0)
    assert plan.reason == START_INVALID and "elbow_flex_joint" in plan.detail
    # Allowing the gripper's contacts with the drawer it touches makes the state valid.
    assert planner.contacts(q_of(INTO_CABINET), world.data) != []
    allowed = [
        (a, "cabinet/link_1")
        for a in ("gripper_link", "r_gripper_finger_link", "l_gripper_finger_link")
    ]
    assert planner.contacts(q_of(INTO_CABINET), world.data, allowed) == []


def test_bad_inputs_raise(world, planner) -> None:
    place_robot(world, READY)
    start, goal = q_of(READY), q_of(IN_FRONT)
    with pytest.raises(UnknownNameError, match="shoulder_pan_joint"):
        planner.plan(start | {"elbow_joint": 0.0}, goal, world.data)
    with pytest.raises(UnknownNameError, match="torso_lift_joint"):
        ArmMotionPlanner(world.model, ["torso_lift_joint", "no_such_joint"])
    with pytest.raises(UnknownNameError, match="RRTConnect"):
        ArmMotionPlanner(world.model, planner="RRTConect")
    with pytest.raises(ConfigError, match="finite"):
        planner.plan(start, goal | {"wrist_flex_joint": float("nan")}, world.data)
    with pytest.raises(ConfigError, match="misses"):
        planner.plan({"torso_lift_joint": 0.3}, goal, world.data)
    with pytest.raises(ConfigError, match="timeout"):
        planner.plan(start, goal, world.data, timeout=-1.0)
    with pytest.raises(ConfigError, match="seed"):
        planner.plan(start, goal, world.data, seed=-1)
