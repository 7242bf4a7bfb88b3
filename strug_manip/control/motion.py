"""Collision-free arm motions between key configurations, planned with OMPL.

:class:`ArmMotionPlanner` plans in the joint space of a few robot joints (by default the
Fetch's torso and its 7 arm joints), with box bounds from the MuJoCo joint ranges. A
configuration is valid if it is within the joint ranges and, set kinematically into a
scratch copy of the world's ``MjData`` (``mj_kinematics`` + ``mj_collision``), no robot
geom touches anything (itself, the cabinet, the table, the object, the floor) except
the *allowed* body pairs (e.g. the fingers with the handle they hold). Edges are
checked every :attr:`ArmMotionPlanner.check_resolution` of joint-space distance.

If the straight joint-space line from start to goal is collision-free it is the plan
(no sampling; ``try_straight``). Otherwise the planner's path is shortened with OMPL's
``PathSimplifier`` (``simplifyMax``: reduce vertices, shortcut, collapse close
vertices; deterministic, unlike the time-bounded ``simplify``). The waypoints are then
time-parameterised into a :class:`MotionPlan`: the robot stops at every waypoint, and
each straight joint-space segment follows a trapezoidal velocity profile, synchronised
over the joints, within each joint's velocity and acceleration limits (see
:data:`VELOCITY_SCALE`, :data:`ACCELERATION_TIME`). Sample it at the control rate with
:meth:`MotionPlan.trajectory`.

Units: prismatic joints [m], revolute joints [rad], times [s]. The joint space is a
plain Euclidean ``RealVectorStateSpace``, so distances and path lengths mix [rad] and
[m] (the torso): a path length is in "[rad or m]".

Determinism (OMPL 2.0.1, checked): every OMPL object draws from its own ``RNG``,
seeded at construction from a global seed generator. ``ompl.util.RNG.setSeed(s)``
re-seeds that generator every time it is called (OMPL logs an *error* "random number
generation already started ... will not lead to deterministic sampling" on every call
but the first, which is not true here: the objects created afterwards get the same
seeds), so :meth:`ArmMotionPlanner.plan` calls it with ``seed + 1`` (a seed of 0 is
replaced by 1 by OMPL) and then builds a fresh problem, planner and simplifier. The
same inputs and seed give the same waypoints, bit for bit. ``RNG.getSeed()`` keeps
returning the *first* seed ever set, not the current one.
"""

from __future__ import annotations

import contextlib
import math
import time
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from planners.errors import ConfigError, UnknownNameError, check_positive_float
from strug_manip.robot.fetch import ARM_JOINTS, FETCH_URDF, TORSO_JOINT

#: Joints planned by default: the torso lift [m] and the 7 arm joints [rad].
DEFAULT_JOINTS: tuple[str, ...] = (TORSO_JOINT, *ARM_JOINTS)
#: Fraction of each joint's speed limit a trajectory may use [-] (as the scripted
#: drawer opening: the position actuators lag behind faster targets).
VELOCITY_SCALE = 0.7
#: Time to accelerate from rest to the (scaled) speed limit [s]; each joint's
#: acceleration limit is its velocity limit divided by this.
ACCELERATION_TIME = 0.3
#: Speed limit of a joint that the URDF does not list [rad/s or m/s] (conservative).
DEFAULT_VELOCITY_LIMIT = 1.0
#: Joint-space distance between two collision checks along an edge [rad or m].
CHECK_RESOLUTION = 0.02
#: Measured joint values this far outside their range are clipped onto it [rad or m]
#: (physics lets a joint overshoot its soft limit a little); further out is invalid.
LIMIT_TOLERANCE = 1e-3
#: Range used for a joint without limits in the model [rad] (one turn each way).
UNLIMITED_RANGE = (-math.pi, math.pi)

#: Failure reasons of :class:`MotionPlan`.
START_INVALID = "start invalid"
GOAL_INVALID = "goal invalid"
NO_PLAN = "no plan within timeout"


def _planners() -> dict[str, type]:
    from ompl import geometric as og

    names = (
        "RRTConnect",
        "RRT",
        "RRTstar",
        "InformedRRTstar",
        "AORRTC",
        "PRM",
        "PRMstar",
        "KPIECE1",
        "BKPIECE1",
        "LBKPIECE1",
        "BITstar",
        "FMT",
        "BFMT",
    )
    return {n: getattr(og, n) for n in names if hasattr(og, n)}


def urdf_velocity_limits(urdf: str | Path = FETCH_URDF) -> dict[str, float]:
    """``{joint: velocity limit}`` [rad/s or m/s] from the ``<limit velocity=...>`` tags
    of a URDF (default: the Fetch's, fetch_ros' values).

    Raises:
        ConfigError: the file is missing or is not valid XML.
    """
    path = Path(urdf)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise ConfigError(f"cannot read velocity limits from URDF {str(path)!r}: {exc}") from None
    out: dict[str, float] = {}
    for joint in root.iter("joint"):
        limit = joint.find("limit")
        if limit is not None and limit.get("velocity") is not None:
            out[joint.get("name", "")] = float(limit.get("velocity", "nan"))
    return out


@contextlib.contextmanager
def _ompl_quiet(level_name: str = "LOG_WARN") -> Iterator[None]:
    """Raise OMPL's log level to at least ``level_name`` for the block (it is DEBUG by
    default in the 2.0.1 wheel, printing several lines per query)."""
    from ompl import util as ou

    old = ou.getLogLevel()
    new = getattr(ou, level_name)
    ou.setLogLevel(new if new.value > old.value else old)
    try:
        yield
    finally:
        ou.setLogLevel(old)


@dataclass(frozen=True, eq=False)
class MotionPlan:
    """The result of :meth:`ArmMotionPlanner.plan`.

    Attributes:
        success: a collision-free path from start to goal was found.
        joints: the planned joints, the column order of every array here.
        waypoints: path vertices, shape (N, n) [rad or m], start first, goal last
            (N >= 2 on success; shape (0, n) on failure).
        path_length: joint-space (Euclidean) length of the simplified path [rad or m]
            (``nan`` on failure).
        planning_time: wall time of planning and simplification [s].
        reason: ``""`` on success, else :data:`START_INVALID`, :data:`GOAL_INVALID` or
            :data:`NO_PLAN`.
        detail: what made the start or goal invalid (contacts ``body1/body2``, or a
            joint outside its range), or the planner's status; ``""`` if nothing to add.
        velocity_limits: per joint [rad/s or m/s], shape (n,) (already scaled).
        acceleration_limits: per joint [rad/s^2 or m/s^2], shape (n,).
        waypoint_times: time at which each waypoint is reached [s], shape (N,).
    """

    success: bool
    joints: tuple[str, ...]
    waypoints: np.ndarray
    path_length: float
    planning_time: float
    reason: str = ""
    detail: str = ""
    velocity_limits: np.ndarray = field(default_factory=lambda: np.zeros(0))
    acceleration_limits: np.ndarray = field(default_factory=lambda: np.zeros(0))
    waypoint_times: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def duration(self) -> float:
        """Time to execute the whole trajectory [s] (0 on failure)."""
        return float(self.waypoint_times[-1]) if self.waypoint_times.size else 0.0

    def sample(self, t: float | np.ndarray) -> np.ndarray:
        """Joint positions at time(s) ``t`` [s]: shape (n,) for a scalar, (T, n) for an
        array of shape (T,). Times outside ``[0, duration]`` are clamped.

        Raises:
            ConfigError: the plan failed (there is no trajectory) or ``t`` is not finite.
        """
        if not self.success:
            raise ConfigError(f"no trajectory: the motion plan failed ({self.reason})")
        ts = np.atleast_1d(np.asarray(t, dtype=float))
        if not np.all(np.isfinite(ts)):
            raise ConfigError(f"sample times must be finite, got {t!r}")
        ts = np.clip(ts, 0.0, self.duration)
        tw = self.waypoint_times
        k = np.clip(np.searchsorted(tw, ts, side="right") - 1, 0, len(tw) - 2)
        v_s, a_s, _ = _segment_profiles(
            self.waypoints, self.velocity_limits, self.acceleration_limits
        )
        seg_T = tw[k + 1] - tw[k]
        s = np.array(
            [
                _trapezoid_s(tau, T, v, a)
                for tau, T, v, a in zip(ts - tw[k], seg_T, v_s[k], a_s[k], strict=True)
            ]
        )
        q0, q1 = self.waypoints[k], self.waypoints[k + 1]
        q = q0 + s[:, None] * (q1 - q0)
        return q[0] if np.ndim(t) == 0 else q

    def trajectory(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """The trajectory sampled every ``dt`` [s] (e.g. the control period).

        Returns:
            ``(times (T,) [s], positions (T, n) [rad or m])``: times ``0, dt, 2 dt, ...``
            and the end time :attr:`duration` (the goal) as the last sample.

        Raises:
            ConfigError: ``dt`` is not a positive finite number, or the plan failed.
        """
        dt = check_positive_float("dt", dt)
        if not self.success:
            raise ConfigError(f"no trajectory: the motion plan failed ({self.reason})")
        n = math.floor(self.duration / dt + 1e-9)
        times = np.arange(n + 1) * dt
        if self.duration - times[-1] > 1e-9:
            times = np.append(times, self.duration)
        return times, self.sample(times)


def _segment_profiles(
    q: np.ndarray, vmax: np.ndarray, amax: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per segment of the polyline ``q`` (N, n): the largest path speed ds/dt and
    acceleration d2s/dt2 (s in [0, 1] along the segment) within every joint's limits,
    and the duration of the resulting trapezoidal (or triangular) profile [s]."""
    dq = np.abs(np.diff(q, axis=0))  # (N-1, n)
    with np.errstate(divide="ignore"):
        v_s = np.min(np.where(dq > 0, vmax / np.maximum(dq, 1e-300), np.inf), axis=1)
        a_s = np.min(np.where(dq > 0, amax / np.maximum(dq, 1e-300), np.inf), axis=1)
    T = np.zeros(len(dq))
    moving = np.isfinite(v_s)
    tri = moving & (v_s * v_s >= a_s)  # never reaches the speed limit
    T[tri] = 2.0 * np.sqrt(1.0 / a_s[tri])
    trap = moving & ~tri
    T[trap] = 1.0 / v_s[trap] + v_s[trap] / a_s[trap]
    v_peak = np.where(tri, np.sqrt(np.where(tri, a_s, 0.0)), v_s)
    return v_peak, a_s, T


def _trapezoid_s(tau: float, T: float, v: float, a: float) -> float:
    """Path parameter in [0, 1] at time ``tau`` of a rest-to-rest profile of duration
    ``T`` with peak speed ``v`` and acceleration ``a`` (v^2 <= a: cruise phase)."""
    if T <= 0 or not math.isfinite(v):
        return 1.0
    tau = min(max(tau, 0.0), T)
    ta = v / a  # acceleration phase
    if tau < ta:
        return 0.5 * a * tau * tau
    if tau <= T - ta:
        return 0.5 * a * ta * ta + v * (tau - ta)
    r = T - tau
    return 1.0 - 0.5 * a * r * r


class ArmMotionPlanner:
    """Plans collision-free joint-space motions of a robot's arm in a MuJoCo scene.

    Args:
        model: the world's MuJoCo model (robot + scene).
        joints: the joints to plan for (hinge or slide joints of one robot), in the
            column order of the plans (default :data:`DEFAULT_JOINTS`).
        planner: OMPL geometric planner name: ``RRTConnect`` (default), ``RRT``,
            ``RRTstar``, ``InformedRRTstar``, ``AORRTC``, ``PRM``, ``PRMstar``,
            ``KPIECE1``, ``BKPIECE1``, ``LBKPIECE1``, ``BITstar``, ``FMT``, ``BFMT``
            (asymptotically optimal ones use the whole timeout).
        allowed_contacts: body-name pairs ``(a, b)`` whose contacts are allowed (either
            order), e.g. ``("r_gripper_finger_link", "cabinet/link_1")``; can be
            replaced per query in :meth:`plan`.
        check_resolution: joint-space distance between collision checks along an edge
            [rad or m] (default :data:`CHECK_RESOLUTION`).
        velocity_limits: ``{joint: limit}`` [rad/s or m/s] overriding the defaults
            (default: the smaller of :func:`urdf_velocity_limits` of the Fetch, else
            :data:`DEFAULT_VELOCITY_LIMIT`, and the speed at which the joint's damping
            eats its actuator's whole force, ``forcerange / damping``; both times
            ``velocity_scale``).
        velocity_scale: fraction of the speed limits a trajectory uses (default
            :data:`VELOCITY_SCALE`).
        acceleration_time: time to reach the scaled speed limit from rest [s] (default
            :data:`ACCELERATION_TIME`).
        planner_range: the planner's maximum edge length [rad or m] (default: OMPL's
            choice, 20 % of the space's extent).
        simplify: shorten the path with ``PathSimplifier.simplifyMax`` (default True).
        try_straight: first check the straight joint-space line from start to goal
            and return it if it is collision-free, without planning (default True).
        robot_root: the robot's root body (default: the root of the first joint's body).

    Raises:
        UnknownNameError: a joint, a planner or a body name is unknown (lists valid ones).
        ConfigError: a joint is not a hinge or slide, is repeated, or a number is not
            positive and finite.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        joints: Sequence[str] = DEFAULT_JOINTS,
        *,
        planner: str = "RRTConnect",
        allowed_contacts: Iterable[tuple[str, str]] = (),
        check_resolution: float = CHECK_RESOLUTION,
        velocity_limits: Mapping[str, float] | None = None,
        velocity_scale: float = VELOCITY_SCALE,
        acceleration_time: float = ACCELERATION_TIME,
        planner_range: float | None = None,
        simplify: bool = True,
        try_straight: bool = True,
        robot_root: str | None = None,
    ) -> None:
        if not isinstance(model, mujoco.MjModel):
            raise ConfigError(f"model must be a mujoco.MjModel, got {type(model).__name__}")
        self.model = model
        m = model
        all_joints = [m.joint(j).name for j in range(m.njnt)]
        if isinstance(joints, str):
            raise ConfigError(f"joints must be a sequence of joint names, got the str {joints!r}")
        self.joints: tuple[str, ...] = tuple(joints)
        if not self.joints:
            raise ConfigError("joints must name at least one joint to plan for")
        if len(set(self.joints)) != len(self.joints):
            raise ConfigError(f"joints must be distinct, got {list(self.joints)}")
        ok_types = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
        ids = []
        for name in self.joints:
            jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name) if name else -1
            if jid < 0:
                raise UnknownNameError("MuJoCo joint", name, all_joints)
            if int(m.jnt_type[jid]) not in ok_types:
                raise ConfigError(f"joint {name!r} must be a hinge or slide joint to be planned")
            ids.append(jid)
        self._jids = np.array(ids)
        self._qadr = np.array([m.jnt_qposadr[j] for j in ids])
        lo, hi = [], []
        for j in ids:
            if m.jnt_limited[j]:
                lo.append(float(m.jnt_range[j, 0]))
                hi.append(float(m.jnt_range[j, 1]))
            else:
                lo.append(UNLIMITED_RANGE[0])
                hi.append(UNLIMITED_RANGE[1])
        #: Lower and upper bounds per joint [rad or m], shape (n,) each.
        self.lower, self.upper = np.array(lo), np.array(hi)

        available = _planners()
        if planner not in available:
            raise UnknownNameError("OMPL planner", planner, sorted(available))
        self.planner_name = planner
        self._planner_cls = available[planner]
        self.check_resolution = check_positive_float("check_resolution", check_resolution)
        self.velocity_scale = check_positive_float("velocity_scale", velocity_scale, upper=1.0)
        self.acceleration_time = check_positive_float("acceleration_time", acceleration_time)
        self.planner_range = (
            None if planner_range is None else check_positive_float("planner_range", planner_range)
        )
        self.simplify = bool(simplify)
        self.try_straight = bool(try_straight)

        urdf = urdf_velocity_limits()
        given = dict(velocity_limits or {})
        for name, v in given.items():
            if name not in self.joints:
                raise UnknownNameError("planned joint (velocity_limits)", name, self.joints)
            check_positive_float(f"velocity_limits[{name!r}]", v)
        v = []
        for name, jid in zip(self.joints, ids, strict=True):
            if name in given:
                v.append(float(given[name]))
                continue
            # The URDF's limit, and the speed at which the joint's damping absorbs its
            # actuator's whole force (Fetch wrist roll: 7.36 N m / 5 N m s = 1.47 rad/s).
            limit = urdf.get(name, DEFAULT_VELOCITY_LIMIT)
            damping = float(m.dof_damping[m.jnt_dofadr[jid]])
            for a in range(m.nu):
                is_joint = int(m.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT)
                if is_joint and m.actuator_trnid[a, 0] == jid and damping > 0:
                    f_max = float(np.max(np.abs(m.actuator_forcerange[a])))
                    if m.actuator_forcelimited[a] and f_max > 0:
                        limit = min(limit, f_max / damping)
            v.append(float(limit))
        #: Scaled speed limits [rad/s or m/s] and acceleration limits [rad/s^2 or m/s^2].
        self.velocity_limits = self.velocity_scale * np.array(v)
        self.acceleration_limits = self.velocity_limits / self.acceleration_time

        # Robot bodies: the subtree of the robot's root body.
        body_names = [m.body(b).name for b in range(m.nbody)]
        if robot_root is None:
            root = int(m.body_rootid[m.jnt_bodyid[ids[0]]])
        else:
            root = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, robot_root)
            if root < 0:
                raise UnknownNameError("MuJoCo body (robot_root)", robot_root, body_names)
        self._robot_body = np.array(
            [b != 0 and (b == root or _is_descendant(m, b, root)) for b in range(m.nbody)]
        )
        self._geom_body = np.asarray(m.geom_bodyid).copy()
        self._robot_geom = self._robot_body[self._geom_body]
        self._allowed_default = self._allowed_matrix(allowed_contacts)
        self._allowed = self._allowed_default
        self._scratch = mujoco.MjData(m)

    # -- configuration checks -------------------------------------------------------------

    def _allowed_matrix(self, pairs: Iterable[tuple[str, str]]) -> np.ndarray:
        m = self.model
        names = [m.body(b).name for b in range(m.nbody)]
        allowed = np.zeros((m.nbody, m.nbody), dtype=bool)
        for pair in pairs:
            if isinstance(pair, str) or len(pair) != 2:
                raise ConfigError(f"allowed contacts must be (body, body) pairs, got {pair!r}")
            a, b = pair
            ia = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, a) if isinstance(a, str) else -1
            ib = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, b) if isinstance(b, str) else -1
            for name, i in ((a, ia), (b, ib)):
                if i < 0:
                    raise UnknownNameError("MuJoCo body (allowed contact)", name, names)
            allowed[ia, ib] = allowed[ib, ia] = True
        return allowed

    def vector(self, q: Mapping[str, float], what: str = "configuration") -> np.ndarray:
        """``q`` as an array in :attr:`joints` order, shape (n,) [rad or m].

        Raises:
            ConfigError: ``q`` is not a mapping, misses a planned joint, or a value is
                not a finite number.
            UnknownNameError: a name is not a planned joint (lists the planned ones).
        """
        if not isinstance(q, Mapping):
            raise ConfigError(f"{what} must be a {{joint name: value}} mapping, got {q!r}")
        for name in q:
            if name not in self.joints:
                raise UnknownNameError(f"planned joint ({what})", name, self.joints)
        missing = [n for n in self.joints if n not in q]
        if missing:
            raise ConfigError(f"{what} misses the planned joint(s) {missing}")
        out = np.empty(len(self.joints))
        for i, name in enumerate(self.joints):
            v = q[name]
            if isinstance(v, bool) or not isinstance(v, int | float | np.number):
                raise ConfigError(f"{what}[{name!r}] must be a number [rad or m], got {v!r}")
            if not math.isfinite(float(v)):
                raise ConfigError(f"{what}[{name!r}] must be finite, got {v!r}")
            out[i] = float(v)
        return out

    def _load(self, data: mujoco.MjData) -> None:
        if not isinstance(data, mujoco.MjData):
            raise ConfigError(f"data must be a mujoco.MjData, got {type(data).__name__}")
        s = self._scratch
        s.qpos[:] = data.qpos
        if self.model.nmocap:
            s.mocap_pos[:] = data.mocap_pos
            s.mocap_quat[:] = data.mocap_quat

    def _contacts(self, q: np.ndarray) -> np.ndarray:
        """Forbidden contacts at ``q`` in the scratch data: array (k, 2) of body ids."""
        m, d = self.model, self._scratch
        d.qpos[self._qadr] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        if d.ncon == 0:
            return np.zeros((0, 2), dtype=int)
        geoms = d.contact.geom
        robot = self._robot_geom[geoms].any(axis=1)
        bodies = self._geom_body[geoms]
        bad = robot & ~self._allowed[bodies[:, 0], bodies[:, 1]]
        return bodies[bad]

    def contacts(
        self,
        q: Mapping[str, float],
        data: mujoco.MjData,
        allowed_contacts: Iterable[tuple[str, str]] | None = None,
    ) -> list[str]:
        """Forbidden robot contacts ``body1/body2`` at ``q`` (other joints as in ``data``,
        which is not modified); ``[]`` if the configuration is collision-free."""
        x = self.vector(q)
        self._load(data)
        old = self._allowed
        if allowed_contacts is not None:
            self._allowed = self._allowed_matrix(allowed_contacts)
        try:
            return self._names(self._contacts(x))
        finally:
            self._allowed = old

    def _names(self, pairs: np.ndarray) -> list[str]:
        m = self.model
        return sorted({f"{m.body(a).name}/{m.body(b).name}" for a, b in pairs.tolist()})

    def _why_invalid(self, x: np.ndarray) -> str:
        """``""`` if ``x`` is a valid configuration, else why not (limits, contacts)."""
        out = []
        for name, v, lo, hi in zip(self.joints, x, self.lower, self.upper, strict=True):
            if not lo <= v <= hi:
                out.append(f"{name}={v:.4g} outside [{lo:.4g}, {hi:.4g}]")
        if out:
            return "joint limits: " + ", ".join(out)
        hits = self._names(self._contacts(x))
        return "contacts: " + ", ".join(hits) if hits else ""

    def _clip_near_limits(self, x: np.ndarray) -> np.ndarray:
        lo, hi = self.lower - LIMIT_TOLERANCE, self.upper + LIMIT_TOLERANCE
        near = (x >= lo) & (x <= hi)
        return np.where(near, np.clip(x, self.lower, self.upper), x)

    # -- planning ---------------------------------------------------------------------------

    def plan(
        self,
        q_start: Mapping[str, float],
        q_goal: Mapping[str, float],
        data: mujoco.MjData,
        *,
        timeout: float = 1.0,
        seed: int = 0,
        allowed_contacts: Iterable[tuple[str, str]] | None = None,
    ) -> MotionPlan:
        """Plan a collision-free motion of :attr:`joints` from ``q_start`` to ``q_goal``.

        Args:
            q_start, q_goal: ``{joint: value}`` for every planned joint [rad or m];
                values within :data:`LIMIT_TOLERANCE` outside a range are clipped.
            data: the world's state; the other joints (base, head, fingers, cabinet
                parts, object) stay as they are here. Not modified.
            timeout: planning time budget [s] (simplification comes on top).
            seed: seed of OMPL's random numbers (an int in [0, 2**32 - 2]).
            allowed_contacts: body pairs allowed to touch in this query (replaces the
                constructor's; None: keep them).

        Returns:
            A :class:`MotionPlan`; on failure ``success`` is False and ``reason`` says
            why (:data:`START_INVALID`, :data:`GOAL_INVALID`, :data:`NO_PLAN`).

        Raises:
            UnknownNameError: a joint name is not a planned joint.
            ConfigError: a value is missing or not finite, ``timeout`` is not positive,
                ``seed`` is not an int in range.
        """
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou

        x0 = self._clip_near_limits(self.vector(q_start, "q_start"))
        x1 = self._clip_near_limits(self.vector(q_goal, "q_goal"))
        timeout = check_positive_float("timeout", timeout)
        if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
            raise ConfigError(f"seed must be an int, got {seed!r}")
        if not 0 <= int(seed) <= 2**32 - 2:
            raise ConfigError(f"seed must be in [0, 2**32 - 2], got {seed!r}")
        self._load(data)
        allowed = (
            self._allowed_default
            if allowed_contacts is None
            else self._allowed_matrix(allowed_contacts)
        )
        self._allowed = allowed
        try:
            return self._plan(ob, og, ou, x0, x1, timeout, int(seed))
        finally:
            self._allowed = self._allowed_default

    def _plan(self, ob, og, ou, x0, x1, timeout: float, seed: int) -> MotionPlan:
        t0 = time.perf_counter()
        n = len(self.joints)

        def failed(reason: str, detail: str) -> MotionPlan:
            return MotionPlan(
                success=False,
                joints=self.joints,
                waypoints=np.zeros((0, n)),
                path_length=math.nan,
                planning_time=time.perf_counter() - t0,
                reason=reason,
                detail=detail,
                velocity_limits=self.velocity_limits.copy(),
                acceleration_limits=self.acceleration_limits.copy(),
            )

        why = self._why_invalid(x0)
        if why:
            return failed(START_INVALID, why)
        why = self._why_invalid(x1)
        if why:
            return failed(GOAL_INVALID, why)

        with _ompl_quiet("LOG_NONE"):
            ou.RNG.setSeed(seed + 1)  # OMPL replaces 0 by 1; it logs an error after the 1st
        with _ompl_quiet("LOG_WARN"):
            space = ob.RealVectorStateSpace(n)
            bounds = ob.RealVectorBounds(n)
            for i in range(n):
                bounds.setLow(i, float(self.lower[i]))
                bounds.setHigh(i, float(self.upper[i]))
            space.setBounds(bounds)
            ss = og.SimpleSetup(space)
            lo, hi = self.lower, self.upper
            contacts = self._contacts

            def is_valid(state) -> bool:
                x = np.array(state[0:n])
                if np.any(x < lo) or np.any(x > hi):
                    return False
                return len(contacts(x)) == 0

            ss.setStateValidityChecker(is_valid)
            si = ss.getSpaceInformation()
            si.setStateValidityCheckingResolution(
                min(1.0, self.check_resolution / space.getMaximumExtent())
            )
            start, goal = space.allocState(), space.allocState()
            for i in range(n):
                start[i] = float(x0[i])
                goal[i] = float(x1[i])
            ss.setStartAndGoalStates(start, goal)
            si.setup()
            if self.try_straight and si.checkMotion(start, goal):
                # The straight joint-space line is free: nothing to plan or simplify.
                q = np.array([x0, x1])
                length = float(si.distance(start, goal))
            else:
                planner = self._planner_cls(si)
                if self.planner_range is not None and hasattr(planner, "setRange"):
                    planner.setRange(self.planner_range)
                ss.setPlanner(planner)
                status = ss.solve(timeout)
                if not ss.haveExactSolutionPath():
                    return failed(NO_PLAN, f"OMPL status: {status.asString()}")
                path = ss.getSolutionPath()
                if self.simplify:
                    og.PathSimplifier(si).simplifyMax(path)
                q = np.array([path.getState(i)[0:n] for i in range(path.getStateCount())])
                length = float(path.length())
        # Exact start and goal (OMPL copies them; keep the caller's values bit for bit).
        q[0], q[-1] = x0, x1
        _, _, seg_T = _segment_profiles(q, self.velocity_limits, self.acceleration_limits)
        return MotionPlan(
            success=True,
            joints=self.joints,
            waypoints=q,
            path_length=length,
            planning_time=time.perf_counter() - t0,
            velocity_limits=self.velocity_limits.copy(),
            acceleration_limits=self.acceleration_limits.copy(),
            waypoint_times=np.concatenate([[0.0], np.cumsum(seg_T)]),
        )


def _is_descendant(m: mujoco.MjModel, body: int, ancestor: int) -> bool:
    while body != 0:
        body = int(m.body_parentid[body])
        if body == ancestor:
            return True
    return False
