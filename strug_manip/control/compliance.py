"""An opening's hand that gives way across its path (issue 37, part 3).

The full robot opens a part along the joint the belief holds; a hinge a centimetre or
two off (perception's, :mod:`strug_manip.domains.manipulation.belief`) makes the
handle's arc differ from the hand's, and a stiff hand then slips off the handle
(``grasp_lost``) or drags the cabinet. :class:`HandCompliance` is an admittance law on
the hand's contact force: every :data:`~.driver.MONITOR_PERIOD` it reads the force the
cabinet exerts on the hand (the Fetch's wrist as a force sensor: the contact forces
between the hand's bodies and the cabinet's), keeps its part *across* the planned
path (the pull along the path is the opening's work, which the hand must not yield
to), and moves the hand along it at ``comply_gain`` metres per second per newton
above ``comply_deadband``, up to ``comply_limit`` from the plan. The shift becomes a
joint offset through the arm's Jacobian (damped least squares over the torso and arm,
the hand's orientation kept), which :meth:`~.driver.JointDriver.follow` adds to the
commands from then on.

Why a cap: a wrong *kind* of joint (a drawer swung as a door, a door pulled straight)
puts the handle tens of centimetres off the hand's path; the hand follows it no
farther than a hinge error perception makes (:data:`~.params.SkillParams.comply_limit`),
so such an opening still strains, slips or drags, as the belief update needs.
"""

from __future__ import annotations

import mujoco
import numpy as np

from strug_manip.control.contacts import HAND_BODIES
from strug_manip.control.driver import MONITOR_PERIOD
from strug_manip.control.executor import OpeningPath
from strug_manip.control.params import SkillParams
from strug_manip.robot.fetch import ARM_TORSO_JOINTS, GRIPPER_SITE
from strug_manip.world.sim import ManipulationWorld

#: Damping of the least-squares step from the hand's shift to the joints' [m^2]: small
#: beside the arm's reach, large enough near a singular posture.
DAMPING = 1e-4


def give_way(
    shift: np.ndarray, force: np.ndarray, tangent: np.ndarray, params: SkillParams, period: float
) -> np.ndarray:
    """The hand's shift from its plan (3,) [m] after ``period`` [s] more under ``force``
    (3,) [N], the cabinet's on the hand, the path's unit ``tangent`` (3,): the part of
    the force across the path above ``comply_deadband`` moves it at ``comply_gain``
    [m/(N s)] per newton, up to ``comply_limit`` [m] from the plan. ``shift`` itself
    (the same object) where the force is within the deadband."""
    across = force - (force @ tangent) * tangent
    size = float(np.linalg.norm(across))
    if size <= params.comply_deadband:
        return shift
    out = shift + params.comply_gain * (size - params.comply_deadband) * period * across / size
    reach = float(np.linalg.norm(out))
    return out * (params.comply_limit / reach) if reach > params.comply_limit else out


class HandCompliance:
    """The admittance of one opening (module docstring).

    Args:
        world: the full robot's world (its ``data`` is read, never written).
        path: the opening's path (:meth:`.OpeningPath.of`), whose tangent says which
            part of the force is the pull.
        params: ``comply_gain`` [m/(N s)], ``comply_deadband`` [N], ``comply_limit`` [m].
        period: the time between two updates [s] (the driver's monitor period).
    """

    def __init__(
        self,
        world: ManipulationWorld,
        path: OpeningPath,
        params: SkillParams,
        period: float = MONITOR_PERIOD,
    ) -> None:
        m = world.model
        self.world, self.path, self.params, self.period = world, path, params, period
        self.hand = np.zeros(m.nbody, dtype=bool)
        self.hand[[m.body(b).id for b in HAND_BODIES]] = True
        # The cabinet's base is a body of the world; its parts hang below it.
        self.cabinet = np.asarray(m.body_rootid) == world.cabinet_root_body
        self.site = m.site(GRIPPER_SITE).id
        self.dofs = np.array([m.jnt_dofadr[m.joint(j).id] for j in ARM_TORSO_JOINTS])
        self.shift = np.zeros(3)  # the hand's shift from its plan, world [m]
        self.q_offset = np.zeros(len(ARM_TORSO_JOINTS))

    def force(self) -> np.ndarray:
        """The force the cabinet exerts on the hand now, world (3,) [N]."""
        m, d = self.world.model, self.world.data
        total, f6 = np.zeros(3), np.zeros(6)
        for i in range(d.ncon):
            c = d.contact[i]
            b1, b2 = m.geom_bodyid[c.geom1], m.geom_bodyid[c.geom2]
            if self.hand[b1] and self.cabinet[b2]:
                sign = -1.0  # the force is geom1's on geom2: the hand's on the cabinet
            elif self.cabinet[b1] and self.hand[b2]:
                sign = 1.0
            else:
                continue
            mujoco.mj_contactForce(m, d, i, f6)
            total += sign * (c.frame.reshape(3, 3).T @ f6[:3])
        return total

    def update(self) -> np.ndarray:
        """One step of the law; the joint offset to add to the arm's commands, (8,)."""
        tcp = self.world.data.site_xpos[self.site]
        shift = give_way(self.shift, self.force(), self.path.tangent(tcp), self.params, self.period)
        if shift is not self.shift:
            self.q_offset = self.q_offset + self._joints(shift - self.shift)
            self.shift = shift
        return self.q_offset

    def _joints(self, dx: np.ndarray) -> np.ndarray:
        """The torso and arm motion (8,) that moves the hand by ``dx`` (3,) [m] and keeps
        its orientation (damped least squares on the site's Jacobian)."""
        m, d = self.world.model, self.world.data
        jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        mujoco.mj_jacSite(m, d, jp, jr, self.site)
        J = np.vstack([jp[:, self.dofs], jr[:, self.dofs]])
        e = np.concatenate([dx, np.zeros(3)])
        return J.T @ np.linalg.solve(J @ J.T + DAMPING * np.eye(6), e)
