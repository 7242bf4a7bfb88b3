"""The IK's differential quadratic program over the moving dofs only
(:class:`ReducedQP`) and its damping costs (:func:`damping_costs`)."""

from __future__ import annotations

from collections.abc import Sequence

import daqp
import mink
import mujoco
import numpy as np

from planners.errors import check_positive_float
from strug_manip.robot.fetch import BASE_JOINTS, TORSO_JOINT

#: Relative cost of torso motion along a tracked line [-] (the torso is slow).
TORSO_COST = 100.0


#: What DAQP takes for an absent bound (qpsolvers' convention).
NO_BOUND = 1e30


class ReducedQP:
    """The differential-IK quadratic program of :func:`mink.solve_ik`, over the moving
    dofs only.

    mink builds it over all ``nv`` dofs and holds the others still with equality rows
    (:class:`mink.DofFreezingTask`); with those rows eliminated the QP is the same
    problem with ``k`` variables and its joint limits simple bounds, which DAQP (the
    solver mink calls through qpsolvers) takes as such. The frame task's residual is
    mink's own; the posture and damping terms are diagonal and added as such. The
    step equals mink's to rounding (``tests/test_ik.py``) at a fraction of its cost:
    the generic assembly and qpsolvers' checks were most of a placement search's time.

    Args:
        model: the IK's model; joints: the moving joints (hinge or slide), k of them.
        limit: the model's :class:`mink.ConfigurationLimit` (bounds and gain).
        posture_cost: the posture task's cost per dof [-].
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        joints: Sequence[str],
        limit: mink.ConfigurationLimit,
        posture_cost: float,
    ) -> None:
        ids = [model.joint(j).id for j in joints]
        self.dofs = np.array([int(model.jnt_dofadr[i]) for i in ids])
        self.qadr = np.array([int(model.jnt_qposadr[i]) for i in ids])
        limited = np.isin(self.dofs, limit.indices)
        self._limited = limited
        self._lower = np.where(limited, limit.lower[self.qadr], 0.0)
        self._upper = np.where(limited, limit.upper[self.qadr], 0.0)
        self._gain = float(limit.gain)
        self._posture = posture_cost**2
        self._sense = np.zeros(len(ids), dtype=np.intc)
        self._no_rows = np.zeros((0, len(ids)))
        self.nv = model.nv

    def velocity(
        self,
        config: mink.Configuration,
        frame: mink.FrameTask,
        diag: np.ndarray,
        damping: float,
        posture: np.ndarray | None = None,
        limits: Sequence[mink.Limit] = (),
    ) -> np.ndarray | None:
        """The step (nv,) of ``mink.solve_ik(config, [frame, posture task, damping
        task], 1.0, "daqp", damping, [configuration limit, *limits], freezing)``.

        Args:
            config: the configuration (its kinematics up to date).
            frame: the gripper's frame task (target set).
            diag: the damping tasks' squared costs per moving dof, (k,) [-].
            damping: the Levenberg-Marquardt damping on every dof [-].
            posture: the posture target (nq,), or None without the posture task.
            limits: further limits (collision avoidance), their rows restricted to
                the moving dofs.

        Returns:
            The step per dof (frozen dofs 0) [rad or m], or None where DAQP finds no
            solution (mink raises :class:`mink.NoSolutionFound`).
        """
        W, e, mu = frame.compute_qp_residual(config)
        Wa = W[:, self.dofs]
        H = Wa.T @ Wa
        c = -(e @ Wa)
        d = diag + (damping + mu)
        q = config.q[self.qadr]
        if posture is not None:
            d = d + self._posture
            c += self._posture * (q - posture[self.qadr])
        H.flat[:: len(d) + 1] += d
        upper = np.where(self._limited, self._gain * (self._upper - q), NO_BOUND)
        lower = np.where(self._limited, self._gain * (self._lower - q), -NO_BOUND)
        A, sense = self._no_rows, self._sense
        rows = [lim.compute_qp_inequalities(config, 1.0) for lim in limits]
        rows = [con for con in rows if not con.inactive]
        if rows:
            A = np.vstack([con.G[:, self.dofs] for con in rows])
            h = np.concatenate([con.h for con in rows])
            upper = np.concatenate([upper, h])
            lower = np.concatenate([lower, np.full(len(h), -NO_BOUND)])
            sense = np.zeros(len(upper), dtype=np.intc)
        x, _, flag, _ = daqp.solve(H, c, A, upper, lower, sense)
        if flag <= 0:
            return None
        v = np.zeros(self.nv)
        v[self.dofs] = x
        return v


def damping_costs(
    active_joints: Sequence[str], include_base: bool, base_cost: float
) -> tuple[np.ndarray, np.ndarray]:
    """The diagonal costs of the moving dofs [-] (:class:`mink.DampingTask`'s, squared),
    ``(solves (k,), tracked lines (k,))``: with ``include_base``, base motion
    ``base_cost`` times dearer than the arm's; along lines the torso
    :data:`TORSO_COST` times too.

    Raises:
        ConfigError: with ``include_base``, ``base_cost`` is not a positive number.
    """
    # Solves: with ``include_base``, base motion ``base_cost`` times dearer than the arm's.
    dof = {j: k for k, j in enumerate(active_joints)}
    solve_diag = np.zeros(len(active_joints))
    if include_base:
        base_cost = check_positive_float("base_cost", base_cost)
        solve_diag[:] = 1e-3**2
        for j in BASE_JOINTS:
            solve_diag[dof[j]] = (1e-3 * base_cost) ** 2
    # Lines leave the torso alone where the arm can follow (it is 10x slower than
    # the arm joints: 0.1 m/s), as the base where the arm alone can.
    line_diag = np.full(len(active_joints), 1e-3**2)
    line_diag[dof[TORSO_JOINT]] = (1e-3 * TORSO_COST) ** 2
    if include_base:
        for j in BASE_JOINTS:
            line_diag[dof[j]] = (1e-3 * base_cost) ** 2
    return solve_diag, line_diag
