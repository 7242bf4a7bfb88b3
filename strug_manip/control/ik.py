"""Inverse kinematics of the Fetch gripper with mink (key poses of the controllers).

:class:`FetchIK` solves ``T_world_gripper`` targets on the MuJoCo Fetch model with
`mink <https://github.com/kevinzakka/mink>`_: each iteration is one differential-IK
quadratic program (solver ``daqp``) with

* a :class:`mink.FrameTask` on the ``gripper`` site (the TCP; position and orientation
  costs),
* a :class:`mink.PostureTask` toward a comfortable posture (:data:`READY_POSTURE`), used
  only while the gripper is far from the target (it would bias the converged pose
  otherwise: the arm is redundant, so the posture settles the null space on the way),
* a :class:`mink.ConfigurationLimit` (joint limits) and, optionally, a
  :class:`mink.CollisionAvoidanceLimit` between the given geom groups,
* the joints that do not take part (base unless ``include_base``, head, fingers) held
  still: the QP is mink's with their equality rows eliminated (:class:`~.ik_qp.ReducedQP`);
* with ``include_base``, a :class:`mink.DampingTask` that makes base motion
  ``base_cost`` times dearer than arm motion, so the base moves only where the arm
  alone cannot follow.

:meth:`FetchIK.solve` finds one key pose (with random restarts); :meth:`FetchIK.track`
follows a dense Cartesian line of poses, warm started from the previous solution
(no restarts, no posture), so consecutive solutions stay on one IK branch: the
controllers' approach, opening and retreat motions.

The moving joints are the torso and the 7 arm joints (and the planar base joints with
``include_base=True``). A solve that stalls restarts from random configurations within
the joint limits drawn from a generator seeded by the solver's ``seed``, so the same
target and ``q_init`` always give the same answer.

Joints are mapped BY NAME (``{joint name: value}``, [m] for prismatic, [rad] for
revolute joints), as everywhere in :mod:`strug_manip.robot.fetch`. Poses are 4x4
homogeneous transforms ``T_world_gripper`` [m].
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import mink
import mujoco
import numpy as np

from planners.errors import (
    ConfigError,
    UnknownNameError,
    check_positive_float,
    check_positive_int,
)
from strug_manip.control.ik_limits import (
    LIMIT_MARGIN,
    check_joint_values,
    clip_into_limits,
    joint_ranges,
    limit_bounds,
)
from strug_manip.control.ik_qp import ReducedQP, damping_costs
from strug_manip.geometry import rotation_angle
from strug_manip.objects.hypotheses import check_pose
from strug_manip.robot.fetch import (
    ALL_JOINTS,
    ARM_TORSO_JOINTS,
    BASE_JOINTS,
    FETCH_XML,
    GRIPPER_SITE,
    HOME_KEYFRAME,
    TORSO_JOINT,
)

#: A comfortable posture the posture task pulls toward and the default initial guess
#: [m, rad]: torso at 0.2 m, the elbow bent, the gripper level about 1.0 m ahead of the
#: base centre and 0.9 m above the floor.
READY_POSTURE: dict[str, float] = {
    TORSO_JOINT: 0.2,
    "shoulder_pan_joint": 0.0,
    "shoulder_lift_joint": -0.4,
    "upperarm_roll_joint": 0.0,
    "elbow_flex_joint": 1.2,
    "forearm_roll_joint": 0.0,
    "wrist_flex_joint": -0.8,
    "wrist_roll_joint": 0.0,
}
#: Distance beyond the margin at which a collision pair enters the QP [m].
COLLISION_DETECTION = 0.15
#: Tolerance of the collision check of a solution, below ``collision_margin`` [m].
COLLISION_TOL = 1e-3
#: Largest joint step between two consecutive poses of a tracked line [rad or m]: a
#: bigger one is a jump to another IK branch, not a continuous motion.
TRACK_MAX_STEP = 0.35

#: A collision pair for :class:`mink.CollisionAvoidanceLimit`: two groups of geom names
#: (or ids) to keep apart.
CollisionPair = tuple[Sequence[str | int], Sequence[str | int]]


@dataclass(frozen=True)
class IKResult:
    """Outcome of one :meth:`FetchIK.solve`.

    Attributes:
        q: every Fetch joint of the model, by name [m or rad]: the best configuration
            found (the solution if ``success``); joints the IK does not move keep their
            initial values.
        success: the gripper is within ``pos_tol`` and ``rot_tol`` of the target (and,
            with collision pairs, every pair is at least ``collision_margin`` minus
            :data:`COLLISION_TOL` apart).
        position_error: distance from the gripper site to the target position [m].
        rotation_error: angle of the rotation from the gripper to the target [rad].
        iterations: QP iterations over all attempts.
        seconds: wall time of the solve [s].
        attempts: starts used (1 + the number of random restarts).
    """

    q: dict[str, float]
    success: bool
    position_error: float
    rotation_error: float
    iterations: int
    seconds: float
    attempts: int = 1


@dataclass(frozen=True)
class TrackResult:
    """Outcome of one :meth:`FetchIK.track`.

    Attributes:
        q: the solutions of the poses reached, shape (K, n) in
            :attr:`FetchIK.active_joints` order [m or rad] (K = all poses on success).
        success: every pose was reached, continuously.
        failed_at: index of the first pose not reached (-1 on success).
        position_error, rotation_error: the largest residual over the poses tried
            [m], [rad].
        seconds: wall time [s].
    """

    q: np.ndarray
    success: bool
    failed_at: int
    position_error: float
    rotation_error: float
    seconds: float


def body_geoms(model: mujoco.MjModel, bodies: Sequence[str]) -> list[int]:
    """Ids of the geoms attached to ``bodies`` (names), for ``collision_pairs``.

    The Fetch's geoms are unnamed: group them by body, e.g.
    ``(body_geoms(m, ["gripper_link", "r_gripper_finger_link"]), body_geoms(m, ["base_link"]))``.

    Raises:
        UnknownNameError: a body is not in ``model``.
    """
    names = [model.body(i).name for i in range(model.nbody)]
    out: list[int] = []
    for b in bodies:
        if b not in names:
            raise UnknownNameError("body", b, names)
        out.extend(int(g) for g in np.flatnonzero(model.geom_bodyid == model.body(b).id))
    return out


class FetchIK:
    """Gripper-pose inverse kinematics of the Fetch with mink.

    Args:
        model: a MuJoCo model that contains the Fetch (joint and site names as in
            ``fetch.xml``), e.g. the scene's model to avoid collisions with the
            cabinet; default: ``models/fetch/fetch.xml`` (robot only, fastest).
        include_base: also move the planar base joints (x [m], y [m], yaw [rad]).
        base_cost: with ``include_base``, the cost of base motion relative to arm
            motion (a :class:`mink.DampingTask`) [-].
        posture: the comfortable posture, by name (default :data:`READY_POSTURE`);
            joints not given keep their initial value as posture target.
        position_cost: weight of the gripper position error [1/m].
        orientation_cost: weight of the gripper orientation error [1/rad].
        posture_cost: weight of the posture error [1/m or 1/rad], per joint.
        posture_until: the posture task is dropped once the gripper is within this
            distance [m] (and 10x this angle [rad]) of the target.
        collision_pairs: geom groups to keep apart (:class:`mink.CollisionAvoidanceLimit`);
            None or empty: no collision limit.
        collision_margin: minimum distance kept between the geoms of a pair [m].
        restarts: random restarts after a failed or stalled first attempt.
        seed: seed of the restarts' random configurations.
        damping: Levenberg-Marquardt damping of the QP [-], on every joint.
        solver: the QP solver; only ``"daqp"`` (the reduced QP calls it directly).

    Raises:
        ConfigError: a bad option, or ``model`` lacks the gripper site.
        UnknownNameError: ``model`` lacks a Fetch joint the IK needs, or ``posture``
            names an unknown joint.
    """

    def __init__(
        self,
        model: mujoco.MjModel | None = None,
        *,
        include_base: bool = False,
        base_cost: float = 10.0,
        posture: Mapping[str, float] | None = None,
        position_cost: float = 1.0,
        orientation_cost: float = 0.5,
        posture_cost: float = 1e-2,
        posture_until: float = 0.02,
        collision_pairs: Sequence[CollisionPair] | None = None,
        collision_margin: float = 0.005,
        restarts: int = 10,
        seed: int = 0,
        damping: float = 1e-4,
        solver: str = "daqp",
    ) -> None:
        position_cost = check_positive_float("position_cost", position_cost)
        orientation_cost = check_positive_float("orientation_cost", orientation_cost)
        posture_cost = check_positive_float("posture_cost", posture_cost, allow_zero=True)
        self.posture_until = check_positive_float("posture_until", posture_until)
        collision_margin = check_positive_float(
            "collision_margin", collision_margin, allow_zero=True
        )
        self.restarts = check_positive_int("restarts", restarts, allow_zero=True)
        self.seed = check_positive_int("seed", seed, allow_zero=True)
        self.damping = check_positive_float("damping", damping, allow_zero=True)
        if solver != "daqp":
            raise ConfigError(f"solver must be one of ['daqp'], got {solver!r}")
        self.solver = solver

        if model is None:
            model = mujoco.MjModel.from_xml_path(str(Path(FETCH_XML)))
        elif not isinstance(model, mujoco.MjModel):
            raise ConfigError(f"model must be a mujoco.MjModel or None, got {model!r}")
        self.model = model
        joint_names = [model.joint(i).name for i in range(model.njnt)]
        self.active_joints: tuple[str, ...] = (
            (*BASE_JOINTS, *ARM_TORSO_JOINTS) if include_base else ARM_TORSO_JOINTS
        )
        for name in self.active_joints:
            if name not in joint_names:
                raise UnknownNameError("Fetch joint of the IK model", name, joint_names)
        if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, GRIPPER_SITE) < 0:
            raise ConfigError(f"the IK model has no site {GRIPPER_SITE!r} (the gripper TCP)")
        self._site = model.site(GRIPPER_SITE).id
        #: Fetch joints of the model, reported in :attr:`IKResult.q`.
        self.robot_joints: tuple[str, ...] = tuple(j for j in ALL_JOINTS if j in joint_names)
        self._qadr = {j: int(model.jnt_qposadr[model.joint(j).id]) for j in joint_names}
        self._active_qadr = np.array([self._qadr[j] for j in self.active_joints])
        if any(model.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL for j in range(model.njnt)):
            raise ConfigError("the IK model must not have ball joints")
        # Bounds of the active joints (unlimited: +-inf), for restarts and clipping.
        self._lo, self._hi = joint_ranges(model, self.active_joints)

        # Default configuration: the home keyframe if the model has one, else qpos0.
        key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, HOME_KEYFRAME)
        self._q_default = (model.key_qpos[key] if key >= 0 else model.qpos0).copy()
        self.posture: dict[str, float] = dict(READY_POSTURE)
        if posture is not None:
            self.posture = self._check_q("posture", posture)
        for j, v in self.posture.items():
            self._q_default[self._qadr[j]] = v
        self._clip = limit_bounds(model)
        clip_into_limits(self._q_default, self._clip)

        self._config = mink.Configuration(model, self._q_default)
        self._frame = mink.FrameTask(
            GRIPPER_SITE,
            "site",
            position_cost=position_cost,
            orientation_cost=orientation_cost,
            lm_damping=1.0,
        )
        self._limits: list[mink.Limit] = [
            mink.ConfigurationLimit(model, min_distance_from_limits=LIMIT_MARGIN)
        ]
        self.collision_margin = collision_margin
        self._geom_pairs: list[tuple[int, int]] = []
        if collision_pairs:
            try:
                limit = mink.CollisionAvoidanceLimit(
                    model,
                    [(list(a), list(b)) for a, b in collision_pairs],
                    minimum_distance_from_collisions=collision_margin,
                    # Wide: one Gauss-Newton step can move the gripper decimetres.
                    collision_detection_distance=collision_margin + COLLISION_DETECTION,
                )
            except (ValueError, KeyError, TypeError) as exc:
                raise ConfigError(f"bad collision_pairs {collision_pairs!r}: {exc}") from None
            self._limits.append(limit)
            self._geom_pairs = [(int(a), int(b)) for a, b in limit.geom_id_pairs]
        self._qp = ReducedQP(model, self.active_joints, self._limits[0], posture_cost)
        # Diagonal costs of the moving dofs [-] (mink.DampingTask's, squared), in solves
        # and along tracked lines.
        self._solve_diag, self._line_diag = damping_costs(
            self.active_joints, include_base, base_cost
        )

    # -- helpers -------------------------------------------------------------------------

    def _check_q(self, what: str, q: Mapping[str, float]) -> dict[str, float]:
        """``q`` as ``{joint: float}``, names and values checked."""
        return check_joint_values(what, q, self._qadr)

    def _errors(self, p_goal: np.ndarray, R_goal: np.ndarray) -> tuple[float, float]:
        """(position error [m], rotation error [rad]) of the gripper at the current q."""
        d = self._config.data
        e = p_goal - d.site_xpos[self._site]
        R = d.site_xmat[self._site].reshape(3, 3)
        return math.sqrt(e.dot(e)), rotation_angle(R_goal.T @ R)  # |e| as np.linalg.norm

    def _clearance(self) -> float:
        """Smallest distance [m] between the geoms of the collision pairs at the current
        q (inf without pairs; capped at the detection distance)."""
        if not self._geom_pairs:
            return math.inf
        m, d = self.model, self._config.data
        cap = self.collision_margin + COLLISION_DETECTION
        return min(
            (mujoco.mj_geomDistance(m, d, a, b, cap, None) for a, b in self._geom_pairs),
            default=math.inf,
        )

    def _step(self, diag: np.ndarray, posture: np.ndarray | None = None) -> np.ndarray | None:
        """One differential-IK step (nv,) from the current configuration (None: no QP
        solution); ``diag``: the damping costs, ``posture``: the posture target (nq,)."""
        return self._qp.velocity(
            self._config, self._frame, diag, self.damping, posture, self._limits[1:]
        )

    def joint_limits(self) -> dict[str, tuple[float, float]]:
        """``{joint: (lower, upper)}`` of the joints the IK moves [m or rad] (+-inf: none)."""
        return {
            j: (float(a), float(b))
            for j, a, b in zip(self.active_joints, self._lo, self._hi, strict=True)
        }

    def forward(self, q: Mapping[str, float]) -> np.ndarray:
        """``T_world_gripper`` (4, 4) [m] by MuJoCo kinematics; unset joints: home/ready."""
        qv = self._q_default.copy()
        for j, v in self._check_q("q", q).items():
            qv[self._qadr[j]] = v
        self._config.update(qv)
        d = self._config.data
        T = np.eye(4)
        T[:3, :3] = d.site_xmat[self._site].reshape(3, 3)
        T[:3, 3] = d.site_xpos[self._site]
        return T

    def body_poses(
        self, q: Mapping[str, float], bodies: Sequence[int]
    ) -> tuple[np.ndarray, np.ndarray]:
        """World positions (n, 3) [m] and orientations (w, x, y, z) (n, 4) of the
        model's ``bodies`` (ids) at ``q`` (by name; unset joints: home/ready)."""
        return self.frames(q, bodies)[1:]

    def frames(
        self, q: Mapping[str, float], bodies: Sequence[int]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The TCP's pose (4, 4) and the ``bodies``' world positions (n, 3) [m] and
        orientations (w, x, y, z) (n, 4) at ``q``, from one forward pass."""
        T = self.forward(q)
        d = self._config.data
        idx = np.asarray(bodies, dtype=int)
        return T, d.xpos[idx].copy(), d.xquat[idx].copy()

    def jacobian(self, q: Mapping[str, float]) -> np.ndarray:
        """The TCP's Jacobian at ``q`` (by name; unset joints: home/ready), shape
        (6, nv): rows linear [m] then angular [rad] velocity in world axes per unit
        velocity of each of the model's dofs (``model.jnt_dofadr`` indexes them)."""
        self.forward(q)
        m, d = self.model, self._config.data
        jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        mujoco.mj_jacSite(m, d, jacp, jacr, self._site)
        return np.vstack([jacp, jacr])

    # -- solve ---------------------------------------------------------------------------

    def solve(
        self,
        T_world_gripper_target: np.ndarray,
        q_init: Mapping[str, float] | None = None,
        *,
        pos_tol: float = 1e-3,
        rot_tol: float = 1e-2,
        max_iters: int = 100,
    ) -> IKResult:
        """Joint positions that put the gripper site at ``T_world_gripper_target``.

        Args:
            T_world_gripper_target: target pose of the gripper site (the TCP), (4, 4),
                in the world frame [m].
            q_init: initial joint positions by name [m or rad]; joints not given start
                at :attr:`posture` (torso, arm) or the model's ``home`` keyframe (base,
                head, fingers). Values outside the joint limits are clipped into them.
                The base joints stay at their initial values unless ``include_base``.
            pos_tol: position tolerance [m].
            rot_tol: rotation tolerance [rad].
            max_iters: QP iterations per attempt (the first from ``q_init``, then up to
                ``restarts`` from random configurations).

        Returns:
            An :class:`IKResult`; ``success`` False (never an exception) when no attempt
            reached the tolerances, with the best configuration found.

        Raises:
            ConfigError: the target is not a finite 4x4 rigid transform, a tolerance is
                not positive, ``max_iters`` is not a positive integer, or a ``q_init``
                value is not a finite number.
            UnknownNameError: ``q_init`` names a joint the model does not have.
        """
        t0 = time.perf_counter()
        T = check_pose("T_world_gripper_target", T_world_gripper_target)
        pos_tol = check_positive_float("pos_tol", pos_tol)
        rot_tol = check_positive_float("rot_tol", rot_tol)
        max_iters = check_positive_int("max_iters", max_iters)
        q0 = self._q_default.copy()
        if q_init is not None:
            for j, v in self._check_q("q_init", q_init).items():
                q0[self._qadr[j]] = v
        clip_into_limits(q0, self._clip)

        p_goal, R_goal = T[:3, 3].copy(), T[:3, :3].copy()
        self._frame.set_target(mink.SE3.from_matrix(T))
        posture_q = q0.copy()
        for j, v in self.posture.items():
            posture_q[self._qadr[j]] = v
        near_rot = 10.0 * self.posture_until

        rng = np.random.default_rng(self.seed)
        config = self._config
        best: tuple[float, np.ndarray, float, float] = (math.inf, q0, math.inf, math.inf)
        iterations = 0
        attempts = 0
        success = False
        for attempt in range(1 + self.restarts):
            attempts += 1
            q_start = q0.copy()
            if attempt > 0:
                lo = np.where(np.isfinite(self._lo), self._lo, q0[self._active_qadr])
                hi = np.where(np.isfinite(self._hi), self._hi, q0[self._active_qadr])
                q_start[self._active_qadr] = rng.uniform(lo, hi)
            config.update(q_start)
            last_best = math.inf
            since_progress = 0
            for it in range(max_iters + 1):
                ep, er = self._errors(p_goal, R_goal)
                score = ep + 0.1 * er
                clear = self._clearance() >= self.collision_margin - COLLISION_TOL
                if not clear:
                    score += 1e3  # any collision-free configuration is better
                if score < best[0]:
                    best = (score, config.q.copy(), ep, er)
                if ep <= pos_tol and er <= rot_tol and clear:
                    success = True
                    best = (score, config.q.copy(), ep, er)
                    break
                if score < 0.98 * last_best:
                    last_best, since_progress = score, 0
                else:
                    since_progress += 1
                    if since_progress >= 10:  # stalled (local minimum, joint limit)
                        break
                if it == max_iters:
                    break
                near = ep < self.posture_until and er < near_rot
                v = self._step(self._solve_diag, None if near else posture_q)
                if v is None:
                    break
                config.integrate_inplace(v, 1.0)
                iterations += 1
            if success:
                break

        _, q_best, ep, er = best
        q_out = {j: float(q_best[self._qadr[j]]) for j in self.robot_joints}
        return IKResult(
            q=q_out,
            success=success,
            position_error=ep,
            rotation_error=er,
            iterations=iterations,
            seconds=time.perf_counter() - t0,
            attempts=attempts,
        )

    def track(
        self,
        poses: Sequence[np.ndarray],
        q_init: Mapping[str, float],
        *,
        pos_tol: float = 2e-3,
        rot_tol: float = 2e-2,
        max_iters: int = 25,
    ) -> TrackResult:
        """Follow a dense Cartesian line: joint positions for each pose of ``poses``.

        Each pose is solved warm started from the previous solution (the first from
        ``q_init``), without restarts or posture, so the solutions form one continuous
        motion; a pose missed by more than the tolerances, or a joint step above
        :data:`TRACK_MAX_STEP` between two poses, ends the line.

        Args:
            poses: gripper targets ``T_world_gripper``, each (4, 4) [m], a few
                centimetres apart.
            q_init: the configuration the line starts from, by name [m or rad].
            pos_tol, rot_tol: tolerances per pose [m], [rad].
            max_iters: QP iterations per pose.

        Returns:
            A :class:`TrackResult` (the solutions of the poses reached).

        Raises:
            ConfigError: a pose is not a rigid transform, or a bad option.
        """
        t0 = time.perf_counter()
        targets = [check_pose(f"poses[{k}]", T) for k, T in enumerate(poses)]
        pos_tol = check_positive_float("pos_tol", pos_tol)
        rot_tol = check_positive_float("rot_tol", rot_tol)
        max_iters = check_positive_int("max_iters", max_iters)
        q = self._q_default.copy()
        for j, v in self._check_q("q_init", q_init).items():
            q[self._qadr[j]] = v
        clip_into_limits(q, self._clip)
        config = self._config
        config.update(q)
        out: list[np.ndarray] = []
        worst = (0.0, 0.0)
        prev = q[self._active_qadr].copy()
        for k, T in enumerate(targets):
            self._frame.set_target(mink.SE3.from_matrix(T))
            p_goal, R_goal = T[:3, 3], T[:3, :3]
            ep, er = self._errors(p_goal, R_goal)
            for _ in range(max_iters):
                if ep <= pos_tol and er <= rot_tol:
                    break
                v = self._step(self._line_diag)
                if v is None:
                    break
                config.integrate_inplace(v, 1.0)
                ep, er = self._errors(p_goal, R_goal)
            now = config.q[self._active_qadr].copy()
            jump = float(np.max(np.abs(now - prev)))
            if ep > pos_tol or er > rot_tol or jump > TRACK_MAX_STEP:
                return TrackResult(
                    np.array(out).reshape(len(out), len(self.active_joints)),
                    False,
                    k,
                    max(worst[0], ep),
                    max(worst[1], er),
                    time.perf_counter() - t0,
                )
            worst = (max(worst[0], ep), max(worst[1], er))
            out.append(now)
            prev = now
        return TrackResult(
            np.array(out).reshape(len(out), len(self.active_joints)),
            True,
            -1,
            worst[0],
            worst[1],
            time.perf_counter() - t0,
        )
