"""The planning twin's hand has the full robot's stiffness: :func:`arm_servo`'s
compliance against the Fetch's measured static deflection, and the floating hand's
servos along turned directions holding and tracking it."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from strug_manip.control import ControlContext
from strug_manip.control.base_servo import BaseServo, base_inertia
from strug_manip.control.twin_servo import arm_servo
from strug_manip.robot.fetch import ACTUATORS, ARM_TORSO_JOINTS, BASE_JOINTS, GRIPPER_SITE
from strug_manip.world import ManipulationWorld, SceneConfig
from strug_manip.world.floating_gripper import SERVOS, SLIDES

#: An arm reaching forward at handle height, clear of the robot's own body
#: (torso, shoulder pan, lift, upper-arm roll, elbow, forearm roll, wrist flex, roll).
REACH = np.array([0.25, 0.3, 0.2, 0.0, 1.3, 0.0, 0.9, 0.0])
#: The test force at the TCP [N]: well inside every joint's effort limit.
FORCE = 15.0


def _settle(world: ManipulationWorld, seconds: float) -> np.ndarray:
    m, d = world.model, world.data
    for _ in range(round(seconds / m.opt.timestep)):
        mujoco.mj_step(m, d)
    return d.site(GRIPPER_SITE).xpos.copy()


def _deflection(direction: np.ndarray) -> np.ndarray:
    """The Fetch's TCP displacement [m] (3,) under ``FORCE`` along ``direction`` at the
    TCP, at rest, its servos proportional only (integral action would null it)."""
    world = ManipulationWorld(SceneConfig(cabinet_kinds=("drawer",), cabinet_distance=3.0))
    m, d = world.model, world.data
    for j in (*BASE_JOINTS, *ARM_TORSO_JOINTS):
        m.actuator_gainprm[m.actuator(ACTUATORS[j]).id, 0] = 0.0  # no integral
    m.opt.gravity[:] = 0.0  # the arm is gravity compensated; no sag to subtract
    for j, q in zip(ARM_TORSO_JOINTS, REACH, strict=True):
        d.qpos[m.joint(j).qposadr[0]] = q
    world.hold_position()
    p0 = _settle(world, 1.0)
    body = m.body("gripper_link").id
    force = FORCE * direction
    d.qfrc_applied[:] = 0.0
    mujoco.mj_applyFT(m, d, force, np.zeros(3), p0, body, d.qfrc_applied)
    qfrc = d.qfrc_applied.copy()
    for _ in range(round(2.0 / m.opt.timestep)):
        d.qfrc_applied[:] = qfrc
        mujoco.mj_step(m, d)
    p1 = d.site(GRIPPER_SITE).xpos.copy()
    world.close()
    return p1 - p0


def test_the_hands_compliance_is_the_fetchs_measured_one() -> None:
    """Along each principal axis of :func:`arm_servo`, the full Fetch's TCP gives way by
    ``FORCE / kp`` (within 5 %) and no more than 5 % of that across it."""
    ctx = ControlContext()
    axes, kp, force, torque = arm_servo(ctx, np.zeros(3), REACH, whole_body=False)
    assert np.allclose(axes.T @ axes, np.eye(3), atol=1e-9)
    assert np.all(kp > 0) and np.all(force > 0) and torque > 0
    for i in range(3):
        delta = _deflection(axes[:, i])
        along = float(delta @ axes[:, i])
        expected = FORCE / kp[i]
        assert along == pytest.approx(expected, rel=0.05), (i, along, expected, kp)
        assert np.linalg.norm(delta - along * axes[:, i]) < 0.05 * expected


def test_servos_along_any_axes_hold_and_track_the_hand() -> None:
    """The floating hand's servos turned to other directions (as the twin turns them to
    the arm's principal axes) hold it where :meth:`~strug_manip.world.sim.
    ManipulationWorld.hold_position` leaves it, and bring it to a position commanded
    as its projections on those directions, to the millimetre."""
    world = ManipulationWorld(SceneConfig(robot="gripper", timestep=0.005))
    m, d = world.model, world.data
    axes, _ = np.linalg.qr(np.array([[1.0, 0.4, 0.2], [0.3, 1.0, -0.5], [0.1, 0.2, 1.0]]))
    slides = [m.joint(j).qposadr[0] for j in SLIDES]
    for i, name in enumerate(SERVOS):
        adr = m.tendon_adr[m.tendon(name).id]
        m.wrap_prm[adr : adr + 3] = axes[:, i]
    d.qpos[slides] = (0.6, -0.2, 0.9)
    mujoco.mj_forward(m, d)
    world.hold_position()
    start = d.qpos[slides].copy()
    _settle(world, 0.5)
    assert np.linalg.norm(d.qpos[slides] - start) < 1e-3
    goal = start + np.array([0.05, 0.04, -0.03])
    for i, name in enumerate(SERVOS):
        d.ctrl[world.ctrl_index(name)] = goal @ axes[:, i]
    _settle(world, 1.5)
    assert np.linalg.norm(d.qpos[slides] - goal) < 2e-3
    world.close()


def test_the_base_servo_model_moves_as_the_fetchs_base() -> None:
    """:class:`BaseServo` driven by a base command (a 0.2 m, 0.1 m, 0.15 rad move in a
    second, then a hold) follows the full Fetch's base under the same command: its
    error is under a quarter of the error of taking the base to be where it is
    commanded (the lag and the overshoot it models), and under 4 mm and 2 mrad."""
    world = ManipulationWorld(SceneConfig(cabinet_kinds=("drawer",), cabinet_distance=3.0))
    m, d = world.model, world.data
    world.hold_position()
    dt = m.opt.timestep
    ramp = np.minimum(np.arange(1, round(2.0 / dt) + 1) * dt, 1.0)
    start = np.array([d.qpos[m.joint(j).qposadr[0]] for j in BASE_JOINTS])
    targets = start + np.outer(ramp, (-0.2, 0.1, 0.15))
    velocities = np.diff(np.vstack([start, targets]), axis=0) / dt
    velocities[-1] = 0.0
    ctrl = [world.ctrl_index(ACTUATORS[j]) for j in BASE_JOINTS]
    actual = np.empty_like(targets)
    for k in range(len(targets)):
        d.ctrl[ctrl] = targets[k]
        d.ctrl[np.add(ctrl, 1)] = velocities[k]
        mujoco.mj_step(m, d)
        actual[k] = [d.qpos[m.joint(j).qposadr[0]] for j in BASE_JOINTS]
    q = {j: float(d.qpos[m.joint(j).qposadr[0]]) for j in (*BASE_JOINTS, *ARM_TORSO_JOINTS)}
    model = BaseServo(m, dt).response(targets, base_inertia(m, q))
    naive = np.abs(targets - actual).max(axis=0)
    error = np.abs(model - actual).max(axis=0)
    assert naive[0] > 0.01, "the command is too gentle to show the base's dynamics"
    assert np.all(error[:2] < 0.25 * naive[:2]), (error, naive)
    assert error[0] < 4e-3 and error[1] < 4e-3 and error[2] < 2e-3, error
    world.close()
