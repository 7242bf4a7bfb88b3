"""Arm motion planning with OMPL in the manipulation scene.

Scene: ``models/cabinets/drawers_11`` (generator seed 11, drawers with bar handles
1.06, 0.87 and 0.63 m high; the front 0.96 m ahead of the robot), the base at the
origin. The key configurations are IK solutions (deterministic) of gripper poses
pointing +x: in front of the cabinet, inside the top drawer's front, and below and above
the top drawer opened 0.2 m (the straight joint-space line between those two hits the
drawer, so the planner must go around it).

Plans are replayed twice: kinematically (waypoints densely interpolated in a scratch
``MjData``, contacts read by code independent of the planner's checker) and executed by
the joint driver with physics; neither may produce a robot contact, and the cabinet must
not move.
"""

from __future__ import annotations

import itertools
import math
import time

import mujoco
import numpy as np
import pytest

from planners.errors import ConfigError, UnknownNameError
from strug_manip.control import ControlContext
from strug_manip.control.driver import JointDriver
from strug_manip.control.motion import (
    GOAL_INVALID,
    NO_PLAN,
    START_INVALID,
    WALL_CAP_HIT,
    ArmMotionPlanner,
    ArmValidity,
    MotionPlan,
)
from strug_manip.control.params import DEFAULT_PARAMS
from strug_manip.robot.fetch import ARM_TORSO_JOINTS, BASE_JOINTS, TUCK
from strug_manip.world.sim import ManipulationWorld

BASE = np.zeros(3)
#: Gripper positions [m] (pointing +x) of the key configurations.
IN_FRONT = (0.75, 0.0, 1.0)
INTO_CABINET = (1.05, 0.0, 1.06)
BELOW_DRAWER = (0.82, 0.0, 0.97)
ABOVE_DRAWER = (0.82, 0.0, 1.25)
DRAWER_OPEN = {"joint_1": 0.2}
#: Joint step of the kinematic replay [rad or m].
REPLAY_STEP = 0.005
#: Bodies that are not the robot's (besides the cabinet's).
NON_ROBOT = ("world", "table", "object", "cabinet_table")


@pytest.fixture(scope="module")
def q(ctx) -> dict[str, np.ndarray]:
    """Torso + arm (8,) of the key configurations, by name."""
    out = {"tuck": np.array(TUCK)}
    for name, p in (
        ("in_front", IN_FRONT),
        ("into_cabinet", INTO_CABINET),
        ("below", BELOW_DRAWER),
        ("above", ABOVE_DRAWER),
    ):
        T = np.eye(4)
        T[:3, 3] = p
        r = ctx.ik.solve(T, dict(zip(BASE_JOINTS, BASE.tolist(), strict=True)))
        assert r.success, name
        out[name] = np.array([r.q[j] for j in ARM_TORSO_JOINTS])
    return out


@pytest.fixture(scope="module")
def planner(world) -> ArmMotionPlanner:
    return ArmMotionPlanner(world.model)


def by_name(x: np.ndarray) -> dict[str, float]:
    return dict(zip(ARM_TORSO_JOINTS, x.tolist(), strict=True))


def place_robot(world: ManipulationWorld, x: np.ndarray, parts=None) -> None:
    """Reset the world, then put torso + arm at ``x`` (kinematically, servos holding)."""
    world.reset(parts)
    m, d = world.model, world.data
    for name, v in zip(ARM_TORSO_JOINTS, x, strict=True):
        d.qpos[m.jnt_qposadr[m.joint(name).id]] = v
    world.hold_position()
    mujoco.mj_forward(m, d)


def validity(ctx: ControlContext, world: ManipulationWorld, allowed=()) -> ArmValidity:
    checker = ctx.checker(world.model).load(world.data)
    checker.attach(None)
    checker.allow(allowed)
    return ArmValidity(checker, BASE)


class RobotContacts:
    """Robot contacts in a MuJoCo state (independent of the planner's checker)."""

    def __init__(self, world: ManipulationWorld) -> None:
        m = self.m = world.model
        pre = world.scene.cabinet_prefix
        self.robot = {
            b
            for b in range(m.nbody)
            if not (m.body(b).name.startswith(pre) or m.body(b).name in NON_ROBOT)
        }
        assert m.body("shoulder_pan_link").id in self.robot

    def __call__(self, d: mujoco.MjData) -> list[str]:
        m, out = self.m, []
        for k in range(d.ncon):
            c = d.contact[k]
            b1, b2 = int(m.geom_bodyid[c.geom1]), int(m.geom_bodyid[c.geom2])
            if (b1 in self.robot) != (b2 in self.robot):  # not the robot with itself
                out.append(f"{m.body(b1).name}/{m.body(b2).name} ({c.dist * 1000:.1f} mm)")
        return out


def replay_kinematic(world: ManipulationWorld, waypoints: np.ndarray) -> list[str]:
    """Robot contacts along the waypoint polyline, sampled every REPLAY_STEP."""
    m = world.model
    d = mujoco.MjData(m)
    d.qpos[:] = world.data.qpos
    adr = [m.jnt_qposadr[m.joint(n).id] for n in ARM_TORSO_JOINTS]
    contacts = RobotContacts(world)
    for qa, qb in itertools.pairwise(waypoints):
        n = max(1, math.ceil(float(np.max(np.abs(qb - qa))) / REPLAY_STEP))
        for k in range(n + 1):
            d.qpos[adr] = qa + (k / n) * (qb - qa)
            mujoco.mj_kinematics(m, d)
            mujoco.mj_collision(m, d)
            hits = contacts(d)
            if hits:
                return hits
    return []


def execute(world: ManipulationWorld, waypoints: np.ndarray) -> tuple[list[str], float]:
    """Follow the waypoints with the joint driver (physics), then hold 0.5 s. Returns the
    robot contacts seen (every 10 ms) and the final joint error [rad or m]."""
    drv = JointDriver(world)
    contacts = RobotContacts(world)
    seen: list[str] = []
    drv.follow(list(waypoints[1:]), 0.3, monitor=lambda _: seen.extend(contacts(world.data)))
    drv.hold(0.5)
    return seen, float(np.max(np.abs(drv.q - waypoints[-1])))


def check_replays(world: ManipulationWorld, plan: MotionPlan) -> None:
    parts_before = world.part_positions()
    assert replay_kinematic(world, plan.waypoints) == []
    hits, err = execute(world, plan.waypoints)
    assert hits == [], hits[:5]
    assert err < 0.02, f"final joint error {err:.3f}"
    assert world.cabinet_displacement() < 1e-3
    for name, v in world.part_positions().items():
        assert abs(v - parts_before[name]) < 1e-3, name


@pytest.mark.parametrize("try_straight", [True, False], ids=["straight-first", "rrtconnect"])
def test_tuck_to_front_of_cabinet_replays_collision_free(world, ctx, q, try_straight) -> None:
    planner = ArmMotionPlanner(world.model, try_straight=try_straight)
    place_robot(world, q["tuck"])
    v = validity(ctx, world)
    assert v.free(q["tuck"]) and v.free(q["in_front"])
    plan = planner.plan(by_name(q["tuck"]), by_name(q["in_front"]), v, timeout=2.0, seed=0)
    assert plan.success, (plan.reason, plan.detail)
    assert plan.reason == "" and plan.joints == ARM_TORSO_JOINTS
    assert plan.waypoints.shape[1] == len(ARM_TORSO_JOINTS) and len(plan.waypoints) >= 2
    np.testing.assert_array_equal(plan.waypoints[0], q["tuck"])
    np.testing.assert_array_equal(plan.waypoints[-1], q["in_front"])
    straight = float(np.linalg.norm(q["in_front"] - q["tuck"]))
    assert plan.path_length >= straight - 1e-9
    assert 0 < plan.planning_time < 2.0 + 5.0
    check_replays(world, plan)


def test_plan_around_an_open_drawer_replays_collision_free(world, ctx, q, planner) -> None:
    place_robot(world, q["below"], DRAWER_OPEN)
    v = validity(ctx, world)
    # The straight line is blocked: planning is needed, and the replay sees it.
    assert v.checker.segment(np.r_[BASE, q["below"]], np.r_[BASE, q["above"]]) != []
    assert replay_kinematic(world, np.array([q["below"], q["above"]])) != []
    plan = planner.plan(by_name(q["below"]), by_name(q["above"]), v, timeout=3.0, seed=1)
    assert plan.success, (plan.reason, plan.detail)
    assert len(plan.waypoints) >= 3
    check_replays(world, plan)


def test_no_plan_within_a_tiny_check_budget(world, ctx, q, planner) -> None:
    place_robot(world, q["below"], DRAWER_OPEN)
    plan = planner.plan(by_name(q["below"]), by_name(q["above"]), validity(ctx, world), checks=5)
    assert not plan.success and plan.reason == NO_PLAN and WALL_CAP_HIT not in plan.detail
    assert plan.waypoints.shape == (0, len(ARM_TORSO_JOINTS)) and math.isnan(plan.path_length)
    # OMPL asks once per iteration, and an iteration checks a whole edge.
    assert 5 <= plan.checks < 5 + 100


def test_the_wall_clock_cap_stops_a_search_and_says_so(world, ctx, q, planner) -> None:
    place_robot(world, q["below"], DRAWER_OPEN)
    plan = planner.plan(
        by_name(q["below"]), by_name(q["above"]), validity(ctx, world), timeout=1e-4
    )
    assert not plan.success and plan.reason == NO_PLAN and WALL_CAP_HIT in plan.detail


#: Added to every check of the slowed search [s]: most of a check's own cost (about
#: 0.07 ms on an idle core), a machine half as fast.
DELAY = 5e-5


class _Slow:
    """A validity that answers as ``inner`` does, ``delay`` [s] later per check: the
    same search on a machine several times slower (or loaded)."""

    def __init__(self, inner: ArmValidity, delay: float) -> None:
        self.inner, self.delay = inner, delay

    def free(self, x: np.ndarray) -> bool:
        t = time.perf_counter() + self.delay
        while time.perf_counter() < t:  # busy: as a slow CPU would
            pass
        return self.inner.free(x)

    def contacts(self, x: np.ndarray) -> list[str]:
        return self.inner.contacts(x)


@pytest.mark.parametrize("name", ["RRTConnect", "LBKPIECE1"])
def test_a_slower_machine_plans_the_same_motion(world, ctx, q, name) -> None:
    """The budget counts checks, not seconds (issue 37: the demo's episode changed with
    the machine's load): a search whose every check takes :data:`DELAY` longer makes
    the same checks and returns the same waypoints, within the skills'
    budgets (:class:`~strug_manip.control.params.SkillParams`)."""
    planner = ArmMotionPlanner(world.model, planner=name)
    place_robot(world, q["below"], DRAWER_OPEN)
    v = validity(ctx, world)
    start, goal = by_name(q["below"]), by_name(q["above"])
    checks = DEFAULT_PARAMS.planner_checks(1, 2)
    fast = planner.plan(start, goal, v, checks=checks, seed=3)
    slow = planner.plan(start, goal, _Slow(v, DELAY), checks=checks, seed=3)
    assert fast.success and fast.checks > 0, (fast.reason, fast.detail)
    assert slow.planning_time > fast.planning_time + DELAY * fast.checks / 2
    assert slow.checks == fast.checks
    np.testing.assert_array_equal(slow.waypoints, fast.waypoints)
    # A budget the search needs all of fails the same way, however slow.
    few = max(1, fast.checks // 4)
    a = planner.plan(start, goal, v, checks=few, seed=3)
    b = planner.plan(start, goal, _Slow(v, DELAY), checks=few, seed=3)
    assert (a.success, a.checks, a.reason) == (b.success, b.checks, b.reason)


def test_goal_inside_the_cabinet_is_goal_invalid(world, ctx, q, planner) -> None:
    place_robot(world, q["tuck"])
    plan = planner.plan(by_name(q["tuck"]), by_name(q["into_cabinet"]), validity(ctx, world))
    assert not plan.success and plan.reason == GOAL_INVALID
    assert "cabinet/link_1" in plan.detail
    assert plan.waypoints.shape == (0, len(ARM_TORSO_JOINTS))


def test_start_invalid_and_allowed_contacts(world, ctx, q, planner) -> None:
    place_robot(world, q["tuck"])
    plan = planner.plan(by_name(q["into_cabinet"]), by_name(q["tuck"]), validity(ctx, world))
    assert plan.reason == START_INVALID and "cabinet/link_1" in plan.detail
    out_of_range = by_name(q["tuck"]) | {"elbow_flex_joint": 3.0}
    plan = planner.plan(out_of_range, by_name(q["tuck"]), validity(ctx, world))
    assert plan.reason == START_INVALID and "elbow_flex_joint" in plan.detail
    # Allowing the hand's contacts with the drawer it touches makes the start valid.
    checker = ctx.checker(world.model)
    hand_drawer = checker.hand_with([checker.body_id("cabinet/link_1")])
    v = validity(ctx, world, hand_drawer)
    assert v.free(q["into_cabinet"])
    plan = planner.plan(by_name(q["into_cabinet"]), by_name(q["in_front"]), v, seed=0)
    assert plan.success, (plan.reason, plan.detail)


def test_bad_inputs_raise(world, ctx, q, planner) -> None:
    place_robot(world, q["tuck"])
    v = validity(ctx, world)
    start, goal = by_name(q["tuck"]), by_name(q["in_front"])
    with pytest.raises(UnknownNameError, match=r"'elbow_joint'.*shoulder_pan_joint"):
        planner.plan(start | {"elbow_joint": 0.0}, goal, v)
    with pytest.raises(UnknownNameError, match="'no_such_joint'"):
        ArmMotionPlanner(world.model, ["torso_lift_joint", "no_such_joint"])
    with pytest.raises(UnknownNameError, match=r"'RRTConect'.*RRTConnect"):
        ArmMotionPlanner(world.model, planner="RRTConect")
    with pytest.raises(ConfigError, match=r"wrist_flex_joint.*finite.*nan"):
        planner.plan(start, goal | {"wrist_flex_joint": float("nan")}, v)
    with pytest.raises(ConfigError, match="misses"):
        planner.plan({"torso_lift_joint": 0.3}, goal, v)
    with pytest.raises(ConfigError, match=r"timeout.*-1.0"):
        planner.plan(start, goal, v, timeout=-1.0)
    with pytest.raises(ConfigError, match=r"checks.*0"):
        planner.plan(start, goal, v, checks=0)
    with pytest.raises(ConfigError, match=r"seed.*-1"):
        planner.plan(start, goal, v, seed=-1)
    with pytest.raises(ConfigError, match="distinct"):
        ArmMotionPlanner(world.model, ["torso_lift_joint", "torso_lift_joint"])
    with pytest.raises(ConfigError, match="str"):
        ArmMotionPlanner(world.model, "torso_lift_joint")


def test_a_start_that_touches_something_is_nudged_free_by_the_smallest_nudge() -> None:
    """``escape_start``: None when nothing near is free; else a free configuration
    within the radius, the torso kept, found among the small nudges first."""
    from strug_manip.control.motion import ESCAPE_RADIUS, escape_start

    q = np.array([0.2, 0.1, -0.3, 0.5, 1.0, -0.2, 0.4, 0.0])

    class Ball:  # touches whatever lies within `reach` [rad] of q
        def __init__(self, reach: float) -> None:
            self.reach = reach

        def free(self, x: np.ndarray) -> bool:
            return float(np.abs(x - q).max()) > self.reach

    bounds = (np.full(8, -2.0), np.r_[2.0, 2.0, 2.0, 2.0, 1.02, 2.0, 2.0, 2.0])
    x = escape_start(q, Ball(0.05), np.random.default_rng(0), bounds)
    assert x is not None and Ball(0.05).free(x)
    assert x[0] == q[0] and np.abs(x - q).max() <= ESCAPE_RADIUS
    assert np.abs(x - q).max() < 0.15  # a small nudge, not the largest
    assert np.all(x <= bounds[1])  # joint 4 starts 2 cm from its upper limit
    assert escape_start(q, Ball(1.0), np.random.default_rng(0), bounds) is None
