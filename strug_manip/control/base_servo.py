"""The Fetch's planar base alone: how it follows a commanded base path.

A whole-body line moves the base with the arm; the base's three PID servos (``base_x``,
``base_y``, ``base_yaw`` of ``models/fetch``) drive some 120 kg, so the base lags behind
its command while it accelerates and overshoots where it stops (a few centimetres on a
drawer pull), and the hand with it. The forces at the hand (tens of newtons) barely
move a base that heavy, so its response to a command can be computed by itself: a
MuJoCo model of one body on the Fetch's three base joints (x and y slides, yaw hinge)
with the Fetch's base actuators (the same PID gains, integral clamps and force limits,
copied from the compiled robot), its mass and yaw inertia set per call to the robot's at
the configuration in question. The planning twin (:mod:`.twin`) moves its floating
hand's command with this response, as the full robot's hand moves with its base.
"""

from __future__ import annotations

from collections.abc import Mapping

import mujoco
import numpy as np
from mujoco import rollout

from strug_manip.robot.fetch import ACTUATORS, BASE_JOINTS

#: The rollout state the responses start from and return.
_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


class BaseServo:
    """The base's servo response (see the module docstring).

    Args:
        robot: a compiled model holding the Fetch's base joints and actuators (e.g. the
            IK's), whose servo parameters are copied.
        timestep: the step of the responses [s].
    """

    def __init__(self, robot: mujoco.MjModel, timestep: float) -> None:
        spec = mujoco.MjSpec()
        spec.option.timestep = timestep
        spec.option.gravity = [0.0, 0.0, 0.0]
        body = spec.worldbody.add_body(name="base", mass=100.0, inertia=[1.0, 1.0, 1.0])
        body.explicitinertial = True
        kinds = (mujoco.mjtJoint.mjJNT_SLIDE, mujoco.mjtJoint.mjJNT_SLIDE,
                 mujoco.mjtJoint.mjJNT_HINGE)  # fmt: skip
        for name, kind, axis in zip(BASE_JOINTS, kinds, np.eye(3), strict=True):
            jid = robot.joint(name).id
            body.add_joint(name=name, type=kind, axis=axis,
                           damping=float(robot.dof_damping[robot.jnt_dofadr[jid]]),
                           armature=float(robot.dof_armature[robot.jnt_dofadr[jid]]))  # fmt: skip
            src = robot.actuator(ACTUATORS[name]).id
            act = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
            act.dyntype = mujoco.mjtDyn(int(robot.actuator_dyntype[src]))
            act.gaintype = mujoco.mjtGain(int(robot.actuator_gaintype[src]))
            act.biastype = mujoco.mjtBias(int(robot.actuator_biastype[src]))
            act.dynprm[:] = robot.actuator_dynprm[src][: len(act.dynprm)]
            act.gainprm[:] = robot.actuator_gainprm[src][: len(act.gainprm)]
            act.biasprm[:] = robot.actuator_biasprm[src][: len(act.biasprm)]
            act.forcelimited = True
            act.forcerange = robot.actuator_forcerange[src].copy()
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self._body = self.model.body("base").id
        self._ctrl = np.array([self.model.actuator_ctrladr[i] for i in range(3)])
        self._ctrlnum = int(self.model.nu)

    def response(self, targets: np.ndarray, inertia: np.ndarray) -> np.ndarray:
        """Where the base is at every step (n, 3) (x, y [m], yaw [rad]) when commanded
        ``targets`` (n, 3) one per step (the velocity targets their differences, zero at
        the last), starting at rest on the first target; ``inertia`` (3,): the robot's
        mass along x and y [kg] and yaw inertia [kg m^2] at the configuration."""
        targets = np.asarray(targets, dtype=float)
        m, d = self.model, self.data
        m.body_mass[self._body] = 0.5 * (inertia[0] + inertia[1])
        m.body_inertia[self._body] = (1.0, 1.0, inertia[2])
        mujoco.mj_resetData(m, d)
        d.qpos[:] = targets[0]
        dt = m.opt.timestep
        vel = np.diff(np.vstack([targets[:1], targets]), axis=0) / dt
        vel[-1] = 0.0
        ctrl = np.zeros((len(targets), self._ctrlnum))
        ctrl[:, self._ctrl] = targets
        ctrl[:, self._ctrl + 1] = vel
        state = np.empty(mujoco.mj_stateSize(m, _STATE))
        mujoco.mj_getState(m, d, state, _STATE)
        states, _ = rollout.rollout(m, d, state[None], ctrl[None])
        # The state after each step: time, then qpos.
        return states[0][:, 1:4].copy()


def base_inertia(robot: mujoco.MjModel, q: Mapping[str, float]) -> np.ndarray:
    """The robot's mass along the base's x and y [kg] and its yaw inertia [kg m^2] (3,)
    with its joints at ``q`` (by name [m, rad]; the others at the model's ``qpos0``):
    the diagonal of the joint-space inertia at the base's dofs."""
    data = mujoco.MjData(robot)
    for name, value in q.items():
        data.qpos[robot.jnt_qposadr[robot.joint(name).id]] = value
    mujoco.mj_forward(robot, data)
    M = np.zeros((robot.nv, robot.nv))
    mujoco.mj_fullM(robot, data, M)  # (armature included)
    dofs = [int(robot.jnt_dofadr[robot.joint(j).id]) for j in BASE_JOINTS]
    return np.array([M[i, i] for i in dofs])
