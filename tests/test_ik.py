"""Tests of the mink IK of the Fetch gripper (strug_manip.control.ik)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from fetch_pinocchio import FetchKinematics

from planners.errors import ConfigError, PlannersError, UnknownNameError
from strug_manip.control.ik import FetchIK, IKResult, body_geoms
from strug_manip.robot.fetch import ARM_TORSO_JOINTS as IK_JOINTS
from strug_manip.robot.fetch import BASE_JOINTS, FETCH_XML

N_POSES = 100
POS_TOL = 1e-3  # [m]
ROT_TOL = 1e-2  # [rad]


@pytest.fixture(scope="module")
def ik() -> FetchIK:
    return FetchIK()


@pytest.fixture(scope="module")
def kin() -> FetchKinematics:
    return FetchKinematics()


def _rot_angle(R: np.ndarray) -> float:
    """Rotation angle [rad] of a (3, 3) rotation matrix."""
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(R).reshape(9))
    return 2.0 * math.atan2(float(np.linalg.norm(quat[1:])), abs(float(quat[0])))


@pytest.fixture(scope="module")
def sampled(ik: FetchIK, kin: FetchKinematics) -> list[tuple[np.ndarray, IKResult]]:
    """Reachable targets (forward kinematics of random torso + arm configurations within
    the joint limits, base at the origin) and their IK solutions from the ready posture."""
    rng = np.random.default_rng(20240605)
    limits = ik.joint_limits()
    out = []
    for _ in range(N_POSES):
        q = {j: float(rng.uniform(*limits[j])) for j in IK_JOINTS}
        T = kin.forward(q)
        out.append((T, ik.solve(T, pos_tol=POS_TOL, rot_tol=ROT_TOL)))
    return out


def test_reaches_95_percent_of_reachable_poses(sampled):
    ok = [r for _, r in sampled if r.success]
    rate = len(ok) / len(sampled)
    assert rate >= 0.95, f"IK success rate {rate:.2%} < 95%"
    for r in ok:
        assert r.position_error <= POS_TOL and r.rotation_error <= ROT_TOL
        assert r.iterations >= 0 and r.seconds > 0 and r.attempts >= 1


def test_solutions_respect_joint_limits(ik, sampled):
    limits = ik.joint_limits()
    for _, r in sampled:
        for j in IK_JOINTS:
            lo, hi = limits[j]
            assert lo - 1e-9 <= r.q[j] <= hi + 1e-9, (j, r.q[j], lo, hi)
        # the base did not move (include_base=False)
        for j in BASE_JOINTS:
            assert r.q[j] == 0.0


def test_pinocchio_reproduces_the_target(ik, kin, sampled):
    """Cross-check MuJoCo (mink) against Pinocchio: the solution's q, put through
    FetchKinematics.forward, gives the target pose."""
    for T, r in sampled:
        if not r.success:
            continue
        T_pin = kin.forward(r.q)
        assert np.linalg.norm(T_pin[:3, 3] - T[:3, 3]) <= POS_TOL + 1e-9
        assert _rot_angle(T[:3, :3].T @ T_pin[:3, :3]) <= ROT_TOL + 1e-9
        # and MuJoCo's own forward kinematics agrees with Pinocchio's
        assert np.allclose(T_pin, ik.forward(r.q), atol=1e-9)


def test_solve_respects_q_init_base_and_is_deterministic(ik, kin):
    base = {"base_x_joint": 1.0, "base_y_joint": -2.0, "base_yaw_joint": 0.7}
    arm = {j: 0.1 for j in IK_JOINTS}
    T = kin.forward({**base, **arm})
    r1 = ik.solve(T, q_init=base)
    r2 = ik.solve(T, q_init=base)
    assert r1.success
    assert r1.q == r2.q and r1.iterations == r2.iterations
    for j, v in base.items():
        assert r1.q[j] == pytest.approx(v, abs=1e-12)
    assert np.linalg.norm(kin.forward(r1.q)[:3, 3] - T[:3, 3]) <= POS_TOL


def test_include_base_moves_the_base_to_reach_far_targets(kin):
    ik = FetchIK(include_base=True)
    T = kin.forward({"base_x_joint": 1.5, "base_yaw_joint": 0.5, **{j: 0.2 for j in IK_JOINTS}})
    assert not FetchIK().solve(T).success  # 1.5 m further than the arm reaches
    r = ik.solve(T)
    assert r.success
    assert np.linalg.norm(kin.forward(r.q)[:3, 3] - T[:3, 3]) <= POS_TOL


def test_unreachable_target_fails_without_exception(ik):
    T = np.eye(4)
    T[:3, 3] = (5.0, 0.0, 1.0)
    r = ik.solve(T, max_iters=30)
    assert not r.success
    assert r.position_error > 3.0
    assert set(IK_JOINTS) <= set(r.q)


@pytest.mark.parametrize(
    "target",
    [
        np.eye(3),
        np.eye(4)[:3],
        np.full((4, 4), np.nan),
        np.array([[1, 0, 0, np.inf], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=float),
        np.diag([1.0, 1.0, -1.0, 1.0]),  # a reflection
        2 * np.eye(4),  # scaled rotation, bad last row
        "eye",
        None,
        [[1, 2], [3, 4]],
    ],
)
def test_bad_targets_raise_config_error(ik, target):
    with pytest.raises(ConfigError) as err:
        ik.solve(target)
    assert "T_world_gripper_target" in str(err.value)


def test_bad_options_raise(ik, kin):
    T = kin.forward({j: 0.0 for j in IK_JOINTS})
    with pytest.raises(UnknownNameError, match="elbow"):
        ik.solve(T, q_init={"elbow": 0.3})
    with pytest.raises(ConfigError, match="nan"):
        ik.solve(T, q_init={"elbow_flex_joint": float("nan")})
    with pytest.raises(ConfigError, match="pos_tol"):
        ik.solve(T, pos_tol=-1.0)
    with pytest.raises(ConfigError, match="max_iters"):
        ik.solve(T, max_iters=0)
    with pytest.raises(PlannersError, match="restarts"):
        FetchIK(restarts=-1)
    with pytest.raises(UnknownNameError, match="nose"):
        FetchIK(posture={"nose": 1.0})


def test_collision_avoidance_limit_keeps_gripper_off_the_base(kin):
    """With a collision limit between the gripper and the base, a target whose gripper
    pose intersects the base (reachable without the limit) is reported as a failure with
    a collision-free best configuration; targets clear of the base are still solved."""
    m = mujoco.MjModel.from_xml_path(str(FETCH_XML))
    grip = body_geoms(m, ["gripper_link", "r_gripper_finger_link", "l_gripper_finger_link"])
    body = body_geoms(m, ["base_link", "torso_fixed_link"])
    margin = 0.01
    free = FetchIK(m)
    ik = FetchIK(m, collision_pairs=[(grip, body)], collision_margin=margin)
    d = mujoco.MjData(m)

    def clearance(q: dict[str, float]) -> float:
        d.qpos[:] = m.key_qpos[0]
        for j, v in q.items():
            d.qpos[m.jnt_qposadr[m.joint(j).id]] = v
        mujoco.mj_kinematics(m, d)
        return min(mujoco.mj_geomDistance(m, d, a, b, 0.5, None) for a in grip for b in body)

    rng = np.random.default_rng(3)
    limits = ik.joint_limits()
    colliding = clear = 0
    for _ in range(2000):
        q = {j: float(rng.uniform(*limits[j])) for j in IK_JOINTS}
        dist = clearance(q)
        if dist < -0.02 and colliding < 3:
            T = kin.forward(q)
            assert free.solve(T).success
            r = ik.solve(T, max_iters=50)
            assert not r.success
            assert clearance(r.q) >= margin - 1.5e-3
            colliding += 1
        elif 0.02 < dist < 0.05 and clear < 3:
            r = ik.solve(kin.forward(q))
            assert r.success
            assert clearance(r.q) >= margin - 1.5e-3
            clear += 1
        if colliding == clear == 3:
            break
    assert colliding == clear == 3
    with pytest.raises(UnknownNameError):
        body_geoms(m, ["no_such_body"])


@pytest.mark.parametrize(
    ("include_base", "posture", "line", "pairs"),
    [
        (False, True, False, False),  # a key pose far from its target
        (False, False, False, False),  # near it: the frame task alone
        (True, True, False, False),  # whole body: the base's damping
        (False, False, True, False),  # a tracked line: the torso's damping
        (True, False, True, False),
        (False, True, False, True),  # a collision limit's rows
    ],
)
def test_the_reduced_qp_step_is_minks(include_base, posture, line, pairs):
    """Each iteration's step is the one mink.solve_ik gives for the same tasks and
    limits with the joints that do not move frozen by equality rows (what the IK did
    before it eliminated those rows), to rounding, from configurations near the limits
    (bounds active) and far from the target (the LM term large)."""
    import mink

    from strug_manip.control.ik_limits import LIMIT_MARGIN
    from strug_manip.control.ik_qp import TORSO_COST

    m = mujoco.MjModel.from_xml_path(str(FETCH_XML))
    grip = body_geoms(m, ["gripper_link", "r_gripper_finger_link", "l_gripper_finger_link"])
    body = body_geoms(m, ["base_link", "torso_fixed_link"])
    base_cost = 7.0
    ik = FetchIK(
        m,
        include_base=include_base,
        base_cost=base_cost,
        posture_cost=0.05,
        collision_pairs=[(grip, body)] if pairs else None,
    )
    dof = {j: int(m.jnt_dofadr[m.joint(j).id]) for j in ik.active_joints}
    cost = np.full(m.nv, 1e-3)  # the damping task's costs, as documented
    if line:
        cost[dof["torso_lift_joint"]] = 1e-3 * TORSO_COST
    if include_base:
        for j in BASE_JOINTS:
            cost[dof[j]] = 1e-3 * base_cost
    tasks = [ik._frame]
    posture_task = mink.PostureTask(m, cost=0.05)
    if posture:
        tasks.append(posture_task)
    if include_base or line:
        tasks.append(mink.DampingTask(m, cost))
    frozen = mink.DofFreezingTask(m, [i for i in range(m.nv) if i not in dof.values()])
    limits = ik.joint_limits()
    rng = np.random.default_rng(11)
    for _ in range(20):
        q = ik._q_default.copy()
        for j in ik.active_joints:
            lo, hi = limits[j]
            lo, hi = (lo, hi) if math.isfinite(lo) else (-1.0, 1.0)
            # Half the samples within 2 cm of a limit, where its bound is active.
            edge = rng.uniform(LIMIT_MARGIN, LIMIT_MARGIN + 0.02)
            q[m.jnt_qposadr[m.joint(j).id]] = rng.choice(
                [rng.uniform(lo + 0.05, hi - 0.05), lo + edge, hi - edge]
            )
        target = ik.forward({j: float(rng.uniform(*limits[j])) for j in IK_JOINTS})
        target[:3, 3] += rng.normal(0.0, 0.3, 3)
        ik._config.update(q)
        ik._frame.set_target(mink.SE3.from_matrix(target))
        goal = ik._q_default.copy()
        posture_task.set_target(goal)
        ours = ik._step(ik._line_diag if line else ik._solve_diag, goal if posture else None)
        theirs = mink.solve_ik(
            ik._config, tasks, 1.0, "daqp", damping=ik.damping,
            limits=ik._limits, constraints=[frozen],
        )  # fmt: skip
        assert ours is not None
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-9)
