"""A scripted (no planner, no model uncertainty) drawer opening by the Fetch in the scene.

:func:`open_drawer_scripted` reads the generator's ground truth of the cabinet
(``world.scene.cabinet_spec``), picks a drawer, and drives the simulated Fetch through
a fixed script, stepping MuJoCo physics all along:

1. **drive**: the base moves along the drawer's opening direction (its velocity
   actuators under a saturated position loop, which then holds it there) until the
   handle is :data:`REACH` from the shoulder pan axis, while the torso rises to
   :data:`UNTUCK_TORSO`;
2. **reach**: the arm leaves its tuck through the fixed waypoints :data:`UNTUCK_ARM`,
   then moves in joint space to a pre-grasp pose :data:`PREGRASP_OFFSET` in front of
   the handle, the gripper's approach axis against the opening direction and its
   fingers straddling the bar (finger opening perpendicular to the bar; horizontal
   for a knob);
3. **approach**: a straight line (IK solutions every centimetre) to the grasp pose,
   the TCP on the bar's axis (the knob's grasp point);
4. **grasp**: the gripper closes (command 0: it squeezes whatever is between the pads);
5. **pull**: a straight line of IK solutions along the opening direction, ``pull``
   metres (capped :data:`LIMIT_MARGIN` before the drawer's joint limit).

Inverse kinematics is damped least squares on :class:`~strug_manip.robot.FetchKinematics`
(Pinocchio) over the torso and the 7 arm joints, with the base at its goal, joint
limits enforced by clipping and a null-space pull toward the untucked posture. Before
anything moves, every planned joint-space segment is checked for robot contacts
(self, cabinet, table) kinematically in a scratch ``MjData``; the fingers may touch
only the drawer being grasped. Torso and arm follow minimum-jerk interpolations through
their position actuators, slowed so that no joint exceeds :data:`SPEED_FRACTION` of its
speed limit (fetch_ros' velocity limits, and the speed at which the joint's damping
absorbs the actuator's whole force). Everything is deterministic: no random numbers.

This is the issue's check that the scene, the robot and the cabinet work together; the
controllers of the manipulation domains (mink IK + OMPL) replace it.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from planners.errors import ConfigError, StrugError, UnknownNameError
from strug_manip.objects.generator import PartSpec
from strug_manip.robot.fetch import (
    ACTUATORS,
    ARM_JOINTS,
    BASE_JOINTS,
    GRIPPER_JOINTS,
    GRIPPER_SITE,
    TORSO_JOINT,
    FetchKinematics,
)
from strug_manip.world.sim import ManipulationWorld

#: Horizontal distance from the shoulder pan axis to the handle after driving [m]. The
#: Fetch's wrist is long (0.325 m from the wrist-flex axis to the TCP): at 0.75 m the IK
#: cannot keep the gripper level at the handle, and the pull ends 0.15 m closer still.
REACH = 0.85
#: Handle heights the default drawer choice accepts [m] (above the floor).
HANDLE_HEIGHT_RANGE = (0.45, 1.15)
#: Preferred handle height: the default choice takes the drawer closest to it [m].
PREFERRED_HANDLE_HEIGHT = 0.85
#: Distance of the pre-grasp TCP from the handle, against the approach direction [m].
PREGRASP_OFFSET = 0.08
#: Travel kept free before the drawer's joint limit when pulling [m].
LIMIT_MARGIN = 0.02
#: Gripper command: open (actuator ctrlrange max) and closed (squeezes the handle) [m].
GRIPPER_OPEN = 0.05
GRIPPER_CLOSED = 0.0
#: Base position loop: gain [1/s] and speed limit [m/s] (yaw: 3x, [rad/s]).
BASE_GAIN = 3.0
BASE_MAX_SPEED = 0.3
#: Shortest duration of a joint-space segment [s] and Cartesian speeds [m/s]. Every
#: segment is also slowed so that no joint exceeds :data:`SPEED_FRACTION` of its speed
#: limit (see :class:`JointDriver`).
SEGMENT_TIME = 1.0
APPROACH_SPEED = 0.08
PULL_SPEED = 0.10
#: Fraction of each joint's speed limit the interpolations may use at their peak [-].
SPEED_FRACTION = 0.7
#: Peak speed of a minimum-jerk profile, relative to its mean speed [-].
MIN_JERK_PEAK = 1.875
#: Time given to the gripper to close [s], and to the arm to settle after a motion [s].
GRASP_TIME = 0.6
SETTLE_TIME = 0.3
#: A grasp "held" if, after the pull, the TCP is this close to the handle [m].
HELD_TOLERANCE = 0.025
#: Torso height while the arm leaves its tuck [m] (the forearm then clears the base).
UNTUCK_TORSO = 0.3
#: Untuck, in :data:`ARM_JOINTS` order [rad], from the ``home`` tuck (1.32, 1.40, -0.2,
#: 1.72, 0, 1.56, 0): roll the upper arm so the folded forearm points forward (the tuck
#: lays it across the torso), then unfold the wrist so the gripper points forward.
#: The wrist roll of the second waypoint is replaced by the pre-grasp's.
UNTUCK_ARM: tuple[tuple[float, ...], ...] = (
    (1.32, 1.40, -1.5, 1.72, 0.0, 1.56, 0.0),
    (1.32, 1.40, -1.5, 1.72, 0.0, 0.0, 0.0),
)
#: Max joint step between collision checks of a joint-space segment [rad or m].
CHECK_STEP = 0.05
#: Joints the IK moves.
IK_JOINTS: tuple[str, ...] = (TORSO_JOINT, *ARM_JOINTS)


class ScriptError(StrugError, RuntimeError):
    """The script cannot be carried out (no reachable drawer, IK did not converge)."""


@dataclass(frozen=True)
class ScriptedResult:
    """What the scripted drawer opening achieved.

    Attributes:
        part_link: the drawer's link in the cabinet (``link_3``).
        joint: the drawer's MuJoCo joint (``cabinet/joint_3``).
        q_before: the drawer's joint position before the script [m].
        q_after: the drawer's joint position at the end [m].
        cabinet_displacement: horizontal displacement of the cabinet base since the
            world's reset [m].
        grasp_held: the TCP was still within :data:`HELD_TOLERANCE` of the handle, and
            the fingers were not closed on nothing, at the end of the pull.
        sim_time: simulated time the script took [s].
        handle_error: distance from the TCP to the handle at the end [m].
    """

    part_link: str
    joint: str
    q_before: float
    q_after: float
    cabinet_displacement: float
    grasp_held: bool
    sim_time: float
    handle_error: float

    @property
    def opening(self) -> float:
        """How far the drawer opened, ``q_after - q_before`` [m]."""
        return self.q_after - self.q_before


# --- geometry helpers -------------------------------------------------------------------


def _rotation_log(R: np.ndarray) -> np.ndarray:
    """Rotation vector (axis * angle [rad]), shape (3,), of a rotation matrix (3, 3)."""
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(R, dtype=float).reshape(9))
    if quat[0] < 0:
        quat = -quat
    vec = np.empty(3)
    mujoco.mju_quat2Vel(vec, quat, 1.0)
    return vec


def grasp_rotation(approach: np.ndarray, bar_axis: np.ndarray | None) -> np.ndarray:
    """Gripper orientation ``R_world_gripper`` (3, 3) for a handle.

    The gripper's x axis (out of the palm) is ``approach``; its y axis (finger opening)
    is perpendicular to the bar (``bar_axis``, world frame), so the fingers straddle
    it; for a knob (``bar_axis`` None or along ``approach``) the fingers open
    horizontally. Of the two finger directions, the one with a non-negative world z
    (or, if horizontal, world y) component is returned.
    """
    a = np.asarray(approach, dtype=float)
    a = a / np.linalg.norm(a)
    y = None
    if bar_axis is not None:
        b = np.asarray(bar_axis, dtype=float)
        y = np.cross(a, b)
        if np.linalg.norm(y) < 1e-6:
            y = None
    if y is None:
        y = np.cross(np.array([0.0, 0.0, 1.0]), a)
        if np.linalg.norm(y) < 1e-6:
            y = np.array([0.0, 1.0, 0.0])
    y = y - (y @ a) * a
    y /= np.linalg.norm(y)
    if y[2] < -1e-9 or (abs(y[2]) <= 1e-9 and y[1] < 0):
        y = -y
    return np.column_stack([a, y, np.cross(a, y)])


def flip_fingers(R: np.ndarray) -> np.ndarray:
    """The same grasp with the fingers swapped (a half turn about the approach axis)."""
    return np.column_stack([R[:, 0], -R[:, 1], -R[:, 2]])


# --- inverse kinematics -----------------------------------------------------------------


def solve_ik(
    kin: FetchKinematics,
    T_target: np.ndarray,
    q_fixed: Mapping[str, float],
    q_seed: Sequence[float],
    *,
    limits: Sequence[tuple[float, float]],
    posture: Sequence[float] | None = None,
    iterations: int = 200,
    damping: float = 0.05,
    posture_gain: float = 0.05,
    tol_pos: float = 5e-4,
    tol_rot: float = 5e-3,
) -> tuple[np.ndarray, float, float]:
    """Damped least-squares IK of the TCP on :data:`IK_JOINTS` (torso + 7 arm joints).

    Args:
        kin: Fetch kinematics.
        T_target: target ``T_world_gripper``, (4, 4) [m].
        q_fixed: joints that do not move (the base), by name [m or rad].
        q_seed: initial values of :data:`IK_JOINTS`, shape (8,) [m, rad].
        limits: ``(lower, upper)`` per IK joint [m or rad].
        posture: values the null space is drawn to, shape (8,); None: none.
        iterations: maximum number of iterations.
        damping: Levenberg-Marquardt damping ``lambda`` [-].
        posture_gain: step toward ``posture`` per iteration, in the null space [-].
        tol_pos, tol_rot: convergence tolerances [m], [rad].

    Returns:
        ``(q (8,), position error [m], orientation error [rad])`` of the best iterate.
    """
    lo = np.array([b[0] for b in limits])
    hi = np.array([b[1] for b in limits])
    q = np.clip(np.asarray(q_seed, dtype=float), lo, hi)
    p_goal, R_goal = T_target[:3, 3], T_target[:3, :3]
    names = IK_JOINTS
    best = (q.copy(), math.inf, math.inf)
    eye6, eye_n = np.eye(6), np.eye(len(names))
    for it in range(iterations):
        qd = {**q_fixed, **dict(zip(names, q.tolist(), strict=True))}
        T = kin.forward(qd)
        e_pos = p_goal - T[:3, 3]
        e_rot = _rotation_log(R_goal @ T[:3, :3].T)
        ep, er = float(np.linalg.norm(e_pos)), float(np.linalg.norm(e_rot))
        if ep + 0.1 * er < best[1] + 0.1 * best[2]:
            best = (q.copy(), ep, er)
        if ep < tol_pos and er < tol_rot:
            break
        err = np.concatenate([np.clip(e_pos, -0.1, 0.1), np.clip(e_rot, -0.5, 0.5)])
        J = kin.jacobian(qd, names)
        # Damping fades near the goal so the last millimetres converge.
        lam2 = damping**2 * min(1.0, max(0.01, (ep + 0.1 * er) / 0.05))
        J_pinv = J.T @ np.linalg.solve(J @ J.T + lam2 * eye6, eye6)
        dq = J_pinv @ err
        if posture is not None and it < iterations // 2:
            # Posture only in the first half: the damped projector leaks into the task.
            dq += posture_gain * (eye_n - J_pinv @ J) @ (np.asarray(posture) - q)
        q = np.clip(q + dq, lo, hi)
    return best


# --- the driver -------------------------------------------------------------------------


class JointDriver:
    """Sends actuator commands to the Fetch while stepping physics.

    The base is held at ``base_target`` (x [m], y [m], yaw [rad]) by a saturated
    proportional loop on its velocity actuators; torso and arm follow position targets.
    """

    def __init__(self, world: ManipulationWorld, kin: FetchKinematics) -> None:
        m = world.model
        self.m, self.d = m, world.data

        def actuator(joint: str) -> int:
            name = ACTUATORS[joint]
            aid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
            if aid < 0:
                raise ConfigError(f"the scene has no actuator {name!r} for joint {joint!r}")
            return aid

        self.base_act = np.array([actuator(j) for j in BASE_JOINTS])
        self.base_adr = np.array([m.jnt_qposadr[m.joint(j).id] for j in BASE_JOINTS])
        self.ik_act = np.array([actuator(j) for j in IK_JOINTS])
        self.ik_adr = np.array([m.jnt_qposadr[m.joint(j).id] for j in IK_JOINTS])
        self.grip_act = actuator("r_gripper_finger_joint")
        self.base_target = self.d.qpos[self.base_adr].copy()
        self.base_speed = np.array([BASE_MAX_SPEED, BASE_MAX_SPEED, 3 * BASE_MAX_SPEED])
        self.ik_cmd = self.d.qpos[self.ik_adr].copy()
        # Speed limits: fetch_ros' (URDF), and the speed at which the joint's damping
        # eats the actuator's whole force (wrist roll: 7.36 N m / 5 N m s = 1.5 rad/s).
        pm = kin.model  # Pinocchio
        v_urdf = np.array([pm.velocityLimit[pm.joints[pm.getJointId(j)].idx_v] for j in IK_JOINTS])
        dof = np.array([m.jnt_dofadr[m.joint(j).id] for j in IK_JOINTS])
        f_max = np.abs(m.actuator_forcerange[self.ik_act, 1])
        damping = np.maximum(m.dof_damping[dof], 1e-9)
        self.vmax = SPEED_FRACTION * np.minimum(v_urdf, f_max / damping)

    @property
    def base(self) -> np.ndarray:
        """Measured base (x [m], y [m], yaw [rad])."""
        return self.d.qpos[self.base_adr].copy()

    @property
    def q_ik(self) -> np.ndarray:
        """Measured torso + arm positions, (8,) [m, rad]."""
        return self.d.qpos[self.ik_adr].copy()

    def _step(self) -> None:
        err = self.base_target - self.d.qpos[self.base_adr]
        self.d.ctrl[self.base_act] = np.clip(BASE_GAIN * err, -self.base_speed, self.base_speed)
        self.d.ctrl[self.ik_act] = self.ik_cmd
        mujoco.mj_step(self.m, self.d)

    def hold(self, seconds: float) -> None:
        """Keep every command and step ``seconds`` [s]."""
        for _ in range(max(1, round(seconds / self.m.opt.timestep))):
            self._step()

    def duration(self, path: Sequence[np.ndarray], seconds: float) -> float:
        """Time [s] for a minimum-jerk traversal of the polyline from the current command
        through ``path`` (each (8,)): at least ``seconds``, and long enough that no joint
        exceeds :attr:`vmax` (uniform speed along the evenly timed segments)."""
        pts = np.vstack([self.ik_cmd, *path])
        steps = np.abs(np.diff(pts, axis=0)).max(axis=0) if len(pts) > 1 else 0.0
        need = MIN_JERK_PEAK * (len(pts) - 1) * float(np.max(steps / self.vmax))
        return max(seconds, need)

    def move(self, q_goal: np.ndarray, seconds: float) -> None:
        """Minimum-jerk joint interpolation of torso + arm to ``q_goal`` (8,) in at least
        ``seconds`` (longer if a joint's speed limit needs it)."""
        seconds = self.duration([q_goal], seconds)
        q0 = self.ik_cmd.copy()
        n = max(1, round(seconds / self.m.opt.timestep))
        for k in range(1, n + 1):
            s = k / n
            s = s * s * s * (10 - 15 * s + 6 * s * s)
            self.ik_cmd = q0 + s * (q_goal - q0)
            self._step()

    def follow(self, path: Sequence[np.ndarray], seconds: float) -> None:
        """Piecewise-linear torso + arm targets through ``path`` (each (8,)), evenly timed,
        with a minimum-jerk time scaling over the whole path of at least ``seconds``."""
        seconds = self.duration(path, seconds)
        pts = np.vstack([self.ik_cmd, *path])
        n = max(1, round(seconds / self.m.opt.timestep))
        segments = len(pts) - 1
        for k in range(1, n + 1):
            s = k / n
            s = s * s * s * (10 - 15 * s + 6 * s * s) * segments
            i = min(int(s), segments - 1)
            self.ik_cmd = pts[i] + (s - i) * (pts[i + 1] - pts[i])
            self._step()

    def gripper(self, value: float, seconds: float) -> None:
        """Command the gripper (mean finger travel [m]) and step ``seconds``."""
        self.d.ctrl[self.grip_act] = value
        self.hold(seconds)

    def drive(self, target: np.ndarray, torso: float) -> None:
        """Drive the base to ``target`` (x, y, yaw) and move the torso to ``torso`` [m]."""
        self.base_target = np.asarray(target, dtype=float).copy()
        dist = float(np.max(np.abs(self.base_target - self.base)[:2]))
        seconds = max(SEGMENT_TIME, dist / BASE_MAX_SPEED + 3.0 / BASE_GAIN)
        goal = self.ik_cmd.copy()
        goal[0] = torso
        self.move(goal, seconds)


# --- the script -------------------------------------------------------------------------


def _cabinet_pose(world: ManipulationWorld) -> np.ndarray:
    """Current ``T_world_cabinet`` of the cabinet's root body, (4, 4)."""
    m, d = world.model, world.data
    bid = m.body(world.scene.cabinet_prefix + world.scene.cabinet.root).id
    T = np.eye(4)
    T[:3, :3] = d.xmat[bid].reshape(3, 3)
    T[:3, 3] = d.xpos[bid]
    return T


def graspable_drawers(world: ManipulationWorld) -> list[PartSpec]:
    """The cabinet's drawers that have a handle (bar or knob) to grasp."""
    spec = world.scene.cabinet_spec
    if spec is None:
        raise ConfigError(
            "the scene's cabinet was loaded from a folder and has no generator ground "
            "truth (scene.cabinet_spec is None); the scripted opening needs a generated one"
        )
    return [
        p
        for p in spec.movable_parts
        if p.joint_type == "prismatic" and p.handle in ("bar", "knob") and p.handle_pos is not None
    ]


def choose_drawer(world: ManipulationWorld) -> PartSpec:
    """The drawer whose handle is easiest for the Fetch to reach.

    Among the drawers with a bar or knob handle at a height in
    :data:`HANDLE_HEIGHT_RANGE`, the one closest to :data:`PREFERRED_HANDLE_HEIGHT`
    (to the millimetre); ties go to the handle nearest the robot's forward line.

    Raises:
        ConfigError: the cabinet has no drawer, no drawer with a handle, or none whose
            handle is at a reachable height.
    """
    spec = world.scene.cabinet_spec
    drawers = graspable_drawers(world)
    seed = world.config.cabinet_seed
    if not drawers:
        all_drawers = [p for p in spec.parts if p.kind == "drawer"]
        if not all_drawers:
            kinds = ", ".join(sorted({p.kind for p in spec.parts}))
            raise ConfigError(
                f"cabinet seed {seed} has no drawer (its parts: {kinds}); build the scene "
                "with SceneConfig(cabinet_kinds=('drawer',)) or pick another seed"
            )
        raise ConfigError(
            f"the drawers of cabinet seed {seed} have no handle to grasp (handle style "
            f"{all_drawers[0].handle!r}); pick a seed whose handles are bars or knobs"
        )
    T = _cabinet_pose(world)
    m, d = world.model, world.data
    x, y, yaw = (float(d.qpos[m.jnt_qposadr[m.joint(j).id]]) for j in BASE_JOINTS)
    lateral = np.array([-math.sin(yaw), math.cos(yaw)])  # the robot's left, world frame
    lo, hi = HANDLE_HEIGHT_RANGE
    scored = []
    for p in drawers:
        q = float(d.qpos[m.jnt_qposadr[m.joint(world.scene.cabinet_prefix + p.joint).id]])
        h = p.handle_at(q, T)
        if lo <= h[2] <= hi:
            off = abs(float((h[:2] - (x, y)) @ lateral))
            scored.append((round(abs(h[2] - PREFERRED_HANDLE_HEIGHT), 3), off, p))
    if not scored:
        heights = ", ".join(f"{p.link}: {p.handle_at(0.0, T)[2]:.2f} m" for p in drawers)
        raise ConfigError(
            f"no drawer handle of cabinet seed {seed} lies between {lo} and {hi} m above "
            f"the floor ({heights}); pass part_link to try one anyway"
        )
    scored.sort(key=lambda t: (t[0], t[1]))
    return scored[0][2]


class PathCollisionChecker:
    """Robot contacts at kinematic configurations, on a scratch copy of the world's state.

    Contacts between the fingers and ``allowed`` bodies (the drawer being grasped) are
    ignored; every other contact of a robot body (with itself, the cabinet, the table,
    the object) counts.
    """

    def __init__(self, world: ManipulationWorld, base: np.ndarray) -> None:
        m = world.model
        self.m, self.d = m, mujoco.MjData(m)
        self.d.qpos[:] = world.data.qpos
        for j, v in zip(BASE_JOINTS, base, strict=True):
            self.d.qpos[m.jnt_qposadr[m.joint(j).id]] = v
        self.adr = np.array([m.jnt_qposadr[m.joint(j).id] for j in IK_JOINTS])
        pre = world.scene.cabinet_prefix
        names = [m.body(b).name for b in range(m.nbody)]
        others = ("world", "table", "object")
        self.robot = np.array([not (n.startswith(pre) or n in others) for n in names])
        self.fingers = {m.body(f"{n.removesuffix('_joint')}_link").id for n in GRIPPER_JOINTS}

    def contacts(self, q: np.ndarray, allowed: frozenset[int] = frozenset()) -> list[str]:
        """``body1/body2`` names of the robot's contacts at torso + arm ``q`` (8,)."""
        m, d = self.m, self.d
        d.qpos[self.adr] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        out = []
        for c in d.contact[: d.ncon]:
            b1, b2 = int(m.geom_bodyid[c.geom1]), int(m.geom_bodyid[c.geom2])
            if not (self.robot[b1] or self.robot[b2]):
                continue
            if (b1 in self.fingers and b2 in allowed) or (b2 in self.fingers and b1 in allowed):
                continue
            out.append(f"{m.body(b1).name}/{m.body(b2).name}")
        return out

    def segment(
        self, qa: np.ndarray, qb: np.ndarray, allowed: frozenset[int] = frozenset()
    ) -> list[str]:
        """Contacts anywhere on the straight joint-space segment ``qa -> qb``."""
        n = max(1, math.ceil(float(np.max(np.abs(qb - qa))) / CHECK_STEP))
        for k in range(n + 1):
            hits = self.contacts(qa + (k / n) * (qb - qa), allowed)
            if hits:
                return hits
        return []

    def path(self, qs: Sequence[np.ndarray], allowed: frozenset[int] = frozenset()) -> list[str]:
        """Contacts anywhere along the joint-space polyline ``qs``."""
        for qa, qb in itertools.pairwise(qs):
            hits = self.segment(qa, qb, allowed)
            if hits:
                return hits
        return []


def _pose(p: np.ndarray, R: np.ndarray) -> np.ndarray:
    """4x4 transform of rotation ``R`` (3, 3) and position ``p`` (3,) [m]."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T


def open_drawer_scripted(
    world: ManipulationWorld,
    part_link: str | None = None,
    pull: float = 0.15,
    *,
    drive_base: bool = True,
) -> ScriptedResult:
    """Open a drawer of the scene's cabinet with a fixed script (ground-truth model).

    Args:
        world: the scene, as after :meth:`ManipulationWorld.reset` (robot at home).
        part_link: the drawer's link (``link_2``); default :func:`choose_drawer`.
        pull: how far to pull the handle along the opening direction [m]; capped so
            that the drawer stops :data:`LIMIT_MARGIN` before its joint limit.
        drive_base: drive the base along the opening direction until the handle is
            :data:`REACH` from the shoulder pan axis; if False the base stays put.

    Returns:
        A :class:`ScriptedResult` (joint positions [m], displacement [m], time [s]).

    Raises:
        ConfigError: ``pull`` is not a distance in (0, 1) m, the part is not a drawer
            with a handle, it is already fully open, or the cabinet has no such drawer.
        UnknownNameError: ``part_link`` is not a link of the cabinet.
        ScriptError: no collision-free IK solution for the pre-grasp, the approach or
            the pull.
    """
    if isinstance(pull, bool) or not isinstance(pull, int | float) or not 0.0 < pull < 1.0:
        raise ConfigError(f"pull must be a distance in (0, 1) m, got {pull!r}")
    part = _resolve_part(world, part_link)
    m, d = world.model, world.data
    joint = world.scene.cabinet_prefix + part.joint
    jadr = m.jnt_qposadr[m.joint(joint).id]
    t0 = float(d.time)
    q_before = float(d.qpos[jadr])
    pull = min(float(pull), part.upper - LIMIT_MARGIN - q_before)
    if pull <= 0:
        raise ConfigError(
            f"drawer {part.link} is already open to {q_before:.3f} m of its "
            f"{part.upper:.3f} m travel; nothing left to pull"
        )

    # --- where: handle, opening direction, grasp orientation (world frame) -------------
    T_wc = _cabinet_pose(world)
    handle = part.handle_at(q_before, T_wc)
    opening = T_wc[:3, :3] @ part.axis
    bar = T_wc[:3, :3] @ part.handle_axis if part.handle == "bar" else None
    R_grasp = grasp_rotation(-opening, bar)
    drawer_body = frozenset({m.body(world.scene.cabinet_prefix + part.link).id})

    kin = FetchKinematics()
    lim = kin.joint_limits()
    limits = [(lim[j][0] + 0.01, lim[j][1] - 0.01) for j in IK_JOINTS]
    drv = JointDriver(world, kin)

    # --- (a) where the base goes ---------------------------------------------------------
    base = drv.base
    if drive_base:
        flat = opening[:2].copy()
        if np.linalg.norm(flat) < 1e-6:
            raise ScriptError(f"drawer {part.link} opens vertically; cannot drive toward it")
        flat /= np.linalg.norm(flat)
        q_now = {j: float(d.qpos[m.jnt_qposadr[m.joint(j).id]]) for j in BASE_JOINTS}
        shoulder = kin.frame_pose("shoulder_pan_link", q_now)[:3, 3]
        along = float((shoulder[:2] - handle[:2]) @ flat)  # shoulder to handle [m]
        base[:2] += (REACH - along) * flat
    q_fixed = dict(zip(BASE_JOINTS, base.tolist(), strict=True))
    checker = PathCollisionChecker(world, base)

    # --- (b) IK: pre-grasp, approach and pull lines, collision checked ---------------------
    pre = handle + PREGRASP_OFFSET * opening
    goal = handle + pull * opening

    def line(p0: np.ndarray, p1: np.ndarray, q: np.ndarray, R: np.ndarray) -> list[np.ndarray]:
        n = max(2, math.ceil(float(np.linalg.norm(p1 - p0)) / 0.01))
        out = []
        for k in range(1, n + 1):
            p = p0 + (k / n) * (p1 - p0)
            q, ep, er = solve_ik(kin, _pose(p, R), q_fixed, q, limits=limits, iterations=100)
            if ep > 2e-3 or er > 2e-2:
                raise ScriptError(
                    f"no IK solution at {np.round(p, 3).tolist()} m for drawer {part.link}: "
                    f"residual {ep * 1000:.1f} mm, {er:.3f} rad"
                )
            out.append(q)
        return out

    failures: list[str] = []
    plan = None
    for R in (R_grasp, flip_fingers(R_grasp)):
        torso = UNTUCK_TORSO
        untuck = [np.array([torso, *a]) for a in UNTUCK_ARM]
        q_pre, ep, er = solve_ik(
            kin,
            _pose(pre, R),
            q_fixed,
            untuck[-1],
            limits=limits,
            posture=untuck[-1],
            iterations=300,
        )
        if ep > 2e-3 or er > 2e-2:
            failures.append(f"pre-grasp unreachable ({ep * 1000:.0f} mm, {er:.2f} rad)")
            continue
        untuck[-1][-1] = q_pre[-1]
        try:
            approach = line(pre, handle, q_pre, R)
            pulling = line(handle, goal, approach[-1], R)
        except ScriptError as exc:
            failures.append(str(exc))
            continue
        tuck = drv.q_ik
        tuck[0] = torso
        hits = (
            checker.path([tuck, *untuck, q_pre])
            or checker.path([q_pre, *approach], drawer_body)
            or checker.path([approach[-1], *pulling], drawer_body)
        )
        if hits:
            failures.append(f"collision {hits[0]}")
            continue
        plan = (torso, untuck, q_pre, approach, pulling)
        break
    if plan is None:
        raise ScriptError(
            f"no collision-free grasp of drawer {part.link} (handle at "
            f"{np.round(handle, 3).tolist()} m, base at {np.round(base, 3).tolist()}): "
            + "; ".join(failures)
        )
    torso, untuck, q_pre, approach, pulling = plan

    # --- (c-e) execute -----------------------------------------------------------------
    drv.gripper(GRIPPER_OPEN, 0.0)
    drv.drive(base, torso)
    for q in untuck:
        drv.move(q, SEGMENT_TIME)
    drv.move(q_pre, SEGMENT_TIME)
    drv.hold(SETTLE_TIME)
    drv.follow(approach, max(1.0, PREGRASP_OFFSET / APPROACH_SPEED))
    drv.hold(SETTLE_TIME)
    drv.gripper(GRIPPER_CLOSED, GRASP_TIME)
    drv.follow(pulling, max(1.0, pull / PULL_SPEED))
    drv.hold(SETTLE_TIME)

    # --- (f) report --------------------------------------------------------------------
    mujoco.mj_forward(m, d)  # positions of sites and bodies at the final state
    q_after = float(d.qpos[jadr])
    h_now = part.handle_at(q_after, _cabinet_pose(world))
    err = float(np.linalg.norm(world.site_pose(GRIPPER_SITE)[:3, 3] - h_now))
    fingers = float(d.ten_length[m.tendon("gripper").id])
    return ScriptedResult(
        part_link=part.link,
        joint=joint,
        q_before=q_before,
        q_after=q_after,
        cabinet_displacement=world.cabinet_displacement(),
        grasp_held=err < HELD_TOLERANCE and fingers > 1e-3,
        sim_time=float(d.time) - t0,
        handle_error=err,
    )


def _resolve_part(world: ManipulationWorld, part_link: str | None) -> PartSpec:
    """The drawer to open: ``part_link``'s, checked, or :func:`choose_drawer`'s."""
    if part_link is None:
        return choose_drawer(world)
    drawers = graspable_drawers(world)  # raises if there is no ground truth
    spec = world.scene.cabinet_spec
    links = [p.link for p in spec.parts]
    if part_link not in links:
        raise UnknownNameError("cabinet part link", part_link, links)
    part = spec.part(part_link)
    if part not in drawers:
        raise ConfigError(
            f"part {part_link!r} is a {part.kind} with handle {part.handle!r}; expected a "
            "drawer (prismatic joint) with a bar or knob handle; this cabinet has "
            + (f"such drawers: {', '.join(p.link for p in drawers)}" if drawers else "none")
        )
    return part
