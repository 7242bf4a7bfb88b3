"""The Fetch's arm as the planning twin's hand servos see it (:func:`arm_servo`): the
hand's stiffness along the arm's principal directions of compliance, and the force and
torque the arm's joints can exert there."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog

from strug_manip.control.context import ControlContext
from strug_manip.robot.fetch import ACTUATORS, ARM_TORSO_JOINTS, BASE_JOINTS

#: Bounds of the hand's force [N] and torque [N m] limits: at least what a wrist can
#: always push, at most the base's 300 N.
FORCE_BOUNDS = (10.0, 300.0)
TORQUE_BOUNDS = (2.0, 60.0)


def arm_servo(
    ctx: ControlContext, base: np.ndarray, q: np.ndarray, whole_body: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """The Fetch's hand at base + torso + arm ``q`` as the twin's servos see it:

    - ``axes`` (3, 3), columns: the principal directions of the hand's translational
      compliance ``C = Jp K^-1 Jp^T`` (``K`` the proportional gains of the base's, the
      torso's and the arm's servos, ``Jp`` the TCP's position Jacobian over those
      joints: the base always gives way, its servos hold it where it stands);
    - ``kp`` (3,): the stiffness along each [N/m], ``1 / eigenvalue of C``;
    - ``force`` (3,): the force the joints can exert along each [N] and ``torque`` [N m],
      clipped to :data:`FORCE_BOUNDS` and :data:`TORQUE_BOUNDS`, over the torso and arm
      joints (with ``whole_body``, the base's too), ``tau`` their effort limits:

      - the torque: ``min_j tau_j / |J_rot,j|`` (the weakest joint, about any axis);
      - the force along direction ``a``: the largest ``F`` with joint torques
        ``(a . J_pos,j) F + J_rot,j . M`` within every ``tau_j`` for some moment ``M``
        at the hand no larger than that torque about each axis (a linear programme):
        the fingers on a handle pass a moment as well as a force, so the joints that
        would saturate under a pure force (the shoulder's pan under a sideways pull)
        share the load with the others. A pure force's bound is the fallback if the
        programme fails.
    """
    ik = ctx.ik
    m = ik.model
    J = ik.jacobian(
        {**dict(zip(BASE_JOINTS, base.tolist(), strict=True)),
         **dict(zip(ARM_TORSO_JOINTS, q.tolist(), strict=True))}
    )  # fmt: skip
    servoed = (*BASE_JOINTS, *ARM_TORSO_JOINTS)
    cols = [int(m.jnt_dofadr[m.joint(j).id]) for j in servoed]
    gains = np.array([-float(m.actuator_biasprm[m.actuator(ACTUATORS[j]).id, 1]) for j in servoed])
    jp = J[:3, cols]
    eig, axes = np.linalg.eigh((jp / gains) @ jp.T)
    kp = 1.0 / np.maximum(eig, 1e-9)

    joints = servoed if whole_body else ARM_TORSO_JOINTS
    cols = [int(m.jnt_dofadr[m.joint(j).id]) for j in joints]
    tau = np.array(
        [float(np.max(np.abs(m.actuator_forcerange[m.actuator(ACTUATORS[j]).id]))) for j in joints]
    )
    jacp, jacr = axes.T @ J[:3, cols], J[3:, cols]

    def cap(Jc: np.ndarray) -> np.ndarray:
        a = np.abs(Jc)
        with np.errstate(divide="ignore"):
            return np.min(np.where(a > 1e-6, tau / np.maximum(a, 1e-12), np.inf), axis=1)

    torque = float(np.clip(np.min(cap(jacr)), *TORQUE_BOUNDS))
    force = cap(jacp)
    for i in range(3):  # variables (F, Mx, My, Mz); maximise F
        A = np.column_stack([jacp[i], jacr.T])
        res = linprog(
            [-1.0, 0.0, 0.0, 0.0], A_ub=np.vstack([A, -A]), b_ub=np.r_[tau, tau],
            bounds=[(0.0, None)] + [(-torque, torque)] * 3, method="highs",
        )  # fmt: skip
        if res.success:
            force[i] = max(force[i], float(res.x[0]))
    return axes, kp, np.clip(force, *FORCE_BOUNDS), torque
