"""The paper's parameterised controllers, run closed-loop in the MuJoCo scene.

Seven skills: :class:`OpenDrawer`, :class:`OpenDoor`, :class:`Pick`, :class:`Place`,
:class:`Push`, :class:`PullV`, :class:`PullH`. Each is a small frozen dataclass of its
parameters with a ``run(world, seed=0) -> Outcome`` method (the :class:`Controller`
protocol). A run:

1. **key poses**: the pre-grasp (and grasp / place) gripper poses are solved with
   :class:`~strug_manip.control.ik.FetchIK` (mink) with the base where it will stand;
2. **arm motion**: the move of torso + arm from where they are to the pre-grasp is
   planned by :class:`~strug_manip.control.motion.ArmMotionPlanner` (OMPL RRTConnect,
   collision checked in MuJoCo against the scene; seeded by ``seed``); when the arm
   is in its home tuck it first leaves it through the proven waypoints of
   :data:`strug_manip.world.scripted.UNTUCK_ARM`;
3. **Cartesian lines**: the approach, the opening motion and the short probing motions
   are lines (or arcs) of gripper poses every :data:`LINE_STEP`, each solved by the
   damped-least-squares IK of :func:`strug_manip.world.scripted.solve_ik` (Pinocchio,
   warm started: a few iterations per waypoint);
4. **execution**: the base drives (saturated position loop), torso and arm follow the
   plans through their position actuators within their speed limits, MuJoCo physics
   stepping all along (the driver of :mod:`strug_manip.world.scripted`).

Opening motions follow the **believed** joint (:class:`BelievedJoint`): ``OpenDrawer``
pulls the gripper straight along a believed prismatic axis, ``OpenDoor`` swings it on
an arc about a believed hinge (both follow whatever joint type they are given). Under
a wrong model the gripper pulls against the real constraint: the grasp slips or the
free-standing cabinet is dragged, as physics decides. ``Push``, ``PullV`` and
``PullH`` grasp the part at ``g`` and move :data:`PROBE_DISTANCE`
along ``-approach``, world z and the horizontal direction of the finger opening.

Planning under the belief: ``run(world, ..., plan_world=w)`` makes the collision
checks of the key poses and paths and the OMPL state validity use ``w``, a
*planning world* built from the believed cabinet (:func:`believed_spec`,
:meth:`ManipulationWorld.from_cabinet_spec`) with the believed part positions, into
which the robot's (and the object's) current state is copied by joint name before
every check; execution and the outcome's judgement stay in ``world``. Without it the
controllers plan against ``world`` itself.

Every run returns an :class:`Outcome`: success or a failure reason
(:data:`REASONS`), the executed torso + arm trajectory, the simulated time and the wall
time spent in IK, motion planning and physics. The same world state, parameters and
seed give the same outcome, bit for bit.

Frames: ``T_world_gripper`` is the pose of the Fetch's ``gripper`` site (the TCP
between the finger pads): x out of the palm (the approach direction), y the finger
opening direction. Units: [m], [rad], [s].
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import mujoco
import numpy as np

from planners.errors import ConfigError, UnknownNameError
from strug_manip.control.ik import FetchIK, check_pose
from strug_manip.control.motion import ArmMotionPlanner
from strug_manip.objects.generator import PartSpec
from strug_manip.objects.hypotheses import BelievedJoint, believed_spec  # noqa: F401
from strug_manip.robot.fetch import BASE_JOINTS, GRIPPER_JOINTS, GRIPPER_SITE, FetchKinematics
from strug_manip.world.scripted import (
    GRIPPER_CLOSED,
    GRIPPER_OPEN,
    IK_JOINTS,
    SETTLE_TIME,
    UNTUCK_ARM,
    UNTUCK_TORSO,
    JointDriver,
    PathCollisionChecker,
    flip_fingers,
    grasp_rotation,
    solve_ik,
)
from strug_manip.world.sim import ManipulationWorld

#: Failure reasons of an :class:`Outcome` (``"ok"`` on success).
REASONS: tuple[str, ...] = (
    "ok",
    "ik_infeasible",
    "no_motion_plan",
    "grasp_lost",
    "collision",
    "timeout",
)
#: Distance from the pre-grasp TCP to the grasp, against the approach [m].
PREGRASP_OFFSET = 0.08
#: Spacing of the IK waypoints along Cartesian lines [m] (arcs: this arc length).
LINE_STEP = 0.02
#: Cartesian speeds: approach and opening motions [m/s].
APPROACH_SPEED = 0.15
OPEN_SPEED = 0.15
#: Joint-space time of an untuck waypoint [s] (slowed further by the speed limits).
UNTUCK_TIME = 0.6
#: Time the gripper gets to close or open [s].
GRIP_TIME = 0.4
#: Horizontal distance of the shoulder pan axis from the middle of a horizontal
#: grasp-and-move motion after driving [m] (the scripted opening's 0.85 m at the handle
#: minus half its 0.15 m pull).
REACH = 0.775
#: Where a top grasp or a placement lies in the robot's frame after driving [m].
TOP_REACH = (0.62, -0.12)
#: The base is only driven when its target is this far away [m].
DRIVE_TOLERANCE = 0.02
#: The cabinet counts as dragged when its base moved more than this [m] (the domain's
#: failure threshold).
CABINET_TOLERANCE = 0.1
#: A held grasp keeps the TCP this close to where the grasp point is now [m].
HELD_TOLERANCE = 0.03
#: Mean finger travel below which the fingers are closed on nothing [m].
FINGERS_EMPTY = 1e-3
#: Fraction of the commanded travel the part must follow for an opening to succeed [-].
OPEN_FRACTION = 0.5
#: Probing distance of ``Push``, ``PullV``, ``PullH`` [m].
PROBE_DISTANCE = 0.04
#: Default openings: drawer travel [m], door angle [rad].
DRAWER_TRAVEL = 0.15
DOOR_ANGLE = 0.8
#: Simulated time budget of one run [s]: beyond it the run stops with ``timeout``.
TIME_BUDGET = 60.0
#: Planning time budget per arm motion [s] (wall).
PLAN_TIMEOUT = 1.0
#: Torso + arm tracking error after a motion above which the arm is blocked [rad or m].
TRACKING_TOLERANCE = 0.08
#: Trajectory recording period [s].
RECORD_PERIOD = 0.02
#: Pick: grasp height above the object's centre [m], lift height [m].
PICK_HEIGHT = 0.01
LIFT_HEIGHT = 0.15
#: Place: release tolerance of the object's final position [m].
PLACE_TOLERANCE = 0.05


# --- parameters and outcome ---------------------------------------------------------------


@dataclass(frozen=True)
class Outcome:
    """What one controller execution did.

    Attributes:
        success: the controller achieved its effect (see each controller).
        reason: ``"ok"`` or a failure reason of :data:`REASONS`.
        detail: a human-readable explanation ("" if nothing to add).
        times: recording times since the run started, shape (T,) [s].
        trajectory: measured torso + arm positions (:data:`IK_JOINTS` order), shape
            (T, 8) [m, rad], every :data:`RECORD_PERIOD` of simulated time.
        sim_time: simulated time of the run [s].
        ik_seconds: wall time in inverse kinematics [s].
        planning_seconds: wall time in OMPL motion planning and collision checks [s].
        physics_seconds: wall time stepping MuJoCo [s].
        wall_seconds: total wall time of the run [s].
        cabinet_displacement: horizontal displacement of the cabinet base since the
            world's reset, at the end [m].
        part_motion: change of every cabinet part joint during the run [m or rad].
    """

    success: bool
    reason: str
    detail: str
    times: np.ndarray
    trajectory: np.ndarray
    sim_time: float
    ik_seconds: float
    planning_seconds: float
    physics_seconds: float
    wall_seconds: float
    cabinet_displacement: float
    part_motion: dict[str, float]

    def same_as(self, other: Outcome) -> bool:
        """Equal in everything but the wall-clock timings."""
        return (
            self.success == other.success
            and self.reason == other.reason
            and self.detail == other.detail
            and np.array_equal(self.trajectory, other.trajectory)
            and self.sim_time == other.sim_time
            and self.cabinet_displacement == other.cabinet_displacement
            and self.part_motion == other.part_motion
        )


#: A callback told the name of each key instant of a run (e.g. to render a frame).
Observer = Callable[[str], None]


@runtime_checkable
class Controller(Protocol):
    """A parameterised skill: ``run`` executes it in the world and reports."""

    def run(
        self,
        world: ManipulationWorld,
        seed: int = 0,
        observer: Observer | None = None,
        plan_world: ManipulationWorld | None = None,
    ) -> Outcome:
        """Execute in ``world`` (its physics state advances), planning against
        ``plan_world`` (default ``world``); deterministic in ``seed``."""
        ...


# --- helpers -------------------------------------------------------------------------------


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix (3, 3) of ``angle`` [rad] about unit ``axis`` (3,)."""
    k = np.asarray(axis, dtype=float)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _body_pose(world: ManipulationWorld, body: str) -> np.ndarray:
    """Current ``T_world_body`` (4, 4) of a named body."""
    bid = world.model.body(body).id
    T = np.eye(4)
    T[:3, :3] = world.data.xmat[bid].reshape(3, 3)
    T[:3, 3] = world.data.xpos[bid]
    return T


def _part(world: ManipulationWorld, link: str) -> PartSpec:
    """Ground truth of movable part ``link`` (raises if unknown or no ground truth)."""
    spec = world.scene.cabinet_spec
    if spec is None:
        raise ConfigError("the scene's cabinet has no generator ground truth (cabinet_spec)")
    links = [p.link for p in spec.movable_parts]
    if link not in links:
        raise UnknownNameError("movable cabinet part link", link, links)
    return spec.part(link)


def true_joint(world: ManipulationWorld, link: str) -> BelievedJoint:
    """The true joint of cabinet part ``link`` (generator ground truth), in the world
    frame at the cabinet's current pose, ``limit`` the travel left [m or rad]."""
    part = _part(world, link)
    T = _body_pose(world, world.scene.cabinet_prefix + world.scene.cabinet.root)
    q = world.part_positions()[world.scene.cabinet_prefix + part.joint]
    return BelievedJoint.of_part(part, q, T)


def _check_g(g: object) -> np.ndarray:
    return check_pose("g (T_world_gripper)", g)


def grasped_part(world: ManipulationWorld, T_world_gripper: np.ndarray) -> str | None:
    """The movable cabinet part whose handle is within 5 cm of the TCP position of
    ``T_world_gripper`` (ground truth; None if none)."""
    spec = world.scene.cabinet_spec
    if spec is None:
        return None
    T = _body_pose(world, world.scene.cabinet_prefix + world.scene.cabinet.root)
    qs = world.part_positions()
    best, best_d = None, 0.05
    for p in spec.movable_parts:
        if p.handle_pos is None:
            continue
        h = p.handle_at(qs[world.scene.cabinet_prefix + p.joint], T)
        dist = float(np.linalg.norm(h - T_world_gripper[:3, 3]))
        if dist < best_d:
            best, best_d = p.link, dist
    return best


def handle_grasp(world: ManipulationWorld, link: str, flip: bool = False) -> np.ndarray:
    """``T_world_gripper`` (4, 4) grasping part ``link``'s handle (ground truth), the
    approach into the cabinet front, fingers straddling the bar (as the scripted
    opening)."""
    part = _part(world, link)
    T = _body_pose(world, world.scene.cabinet_prefix + world.scene.cabinet.root)
    q = world.part_positions()[world.scene.cabinet_prefix + part.joint]
    out = np.eye(4)
    out[:3, 3] = part.handle_at(q, T)
    front = T[:3, :3] @ np.array([1.0, 0.0, 0.0])  # the cabinet's front normal
    bar = T[:3, :3] @ part.handle_axis if part.handle == "bar" else None
    R = grasp_rotation(-front, bar)
    out[:3, :3] = flip_fingers(R) if flip else R
    return out


class _RunFailureError(Exception):
    """Internal: stop the run with a failure reason."""

    def __init__(self, reason: str, detail: str) -> None:
        super().__init__(detail)
        self.reason, self.detail = reason, detail


class _Recorder(JointDriver):
    """The scripted driver, recording the measured trajectory and physics wall time."""

    def __init__(self, world: ManipulationWorld, kin: FetchKinematics, t_end: float) -> None:
        super().__init__(world, kin)
        self.every = max(1, round(RECORD_PERIOD / self.m.opt.timestep))
        self.count = 0
        self.t0 = float(self.d.time)
        self.t_end = t_end
        self.times: list[float] = []
        self.rows: list[np.ndarray] = []
        self.physics = 0.0

    def _step(self) -> None:
        if self.d.time - self.t0 > self.t_end:
            raise _RunFailureError(
                "timeout", f"the run exceeded its {self.t_end:.0f} s time budget"
            )
        t = time.perf_counter()
        super()._step()
        self.physics += time.perf_counter() - t
        if self.count % self.every == 0:
            self.times.append(float(self.d.time) - self.t0)
            self.rows.append(self.d.qpos[self.ik_adr].copy())
        self.count += 1


# Shared solvers, built once (they are deterministic and hold no per-run state).
_KIN: FetchKinematics | None = None
_IK: FetchIK | None = None
_PLANNERS: dict[int, ArmMotionPlanner] = {}


def _kin() -> FetchKinematics:
    global _KIN
    if _KIN is None:
        _KIN = FetchKinematics()
    return _KIN


def _fetch_ik() -> FetchIK:
    global _IK
    if _IK is None:
        _IK = FetchIK(restarts=4, seed=0)
    return _IK


#: At most this many planners (one per scene model) are kept.
_MAX_PLANNERS = 16


def _planner(model: mujoco.MjModel) -> ArmMotionPlanner:
    key = id(model)
    if key not in _PLANNERS or _PLANNERS[key].model is not model:
        while len(_PLANNERS) >= _MAX_PLANNERS:
            _PLANNERS.pop(next(iter(_PLANNERS)))  # the oldest (e.g. a discarded belief)
        _PLANNERS[key] = ArmMotionPlanner(model)
    return _PLANNERS[key]


class _Run:
    """One controller execution: shared machinery (IK, planning, driving, timing).

    Collision checks and motion plans use ``plan_world`` (default ``world``), synced
    with the robot's state in ``world`` by joint name before each; driving and the
    outcome use ``world``.
    """

    def __init__(
        self,
        world: ManipulationWorld,
        seed: int,
        observer: Observer | None,
        plan_world: ManipulationWorld | None = None,
    ) -> None:
        if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
            raise ConfigError(f"seed must be a non-negative int, got {seed!r}")
        if plan_world is not None and not isinstance(plan_world, ManipulationWorld):
            raise ConfigError(f"plan_world must be a ManipulationWorld or None, got {plan_world!r}")
        self.world, self.seed, self.observer = world, int(seed), observer
        self.plan_world = world if plan_world is None else plan_world
        self.t_wall = time.perf_counter()
        self.kin = _kin()
        self.ik = _fetch_ik()
        self.planner = _planner(self.plan_world.model)
        self.drv = _Recorder(world, self.kin, TIME_BUDGET)
        self.ik_time = 0.0
        self.plan_time = 0.0
        self.parts0 = world.part_positions()
        lim = self.kin.joint_limits()
        self.limits = [(lim[j][0] + 0.01, lim[j][1] - 0.01) for j in IK_JOINTS]
        self.base = self.drv.base
        m = self.plan_world.model  # body ids of the collision checks
        pre = self.plan_world.scene.cabinet_prefix
        self.cabinet_bodies = frozenset(b for b in range(m.nbody) if m.body(b).name.startswith(pre))
        self.object_body = frozenset({m.body("object").id})
        self.finger_bodies = [f"{n.removesuffix('_joint')}_link" for n in GRIPPER_JOINTS]
        self.n_plans = 0
        self.untucking = False
        self.untuck_first = False

    # -- bookkeeping -----------------------------------------------------------------------
    def key(self, name: str) -> None:
        """Tell the observer about a key instant."""
        if self.observer is not None:
            mujoco.mj_forward(self.world.model, self.world.data)
            self.observer(name)

    def outcome(self, success: bool, reason: str, detail: str = "") -> Outcome:
        """The run's :class:`Outcome` (the world state as it is now)."""
        w = self.world
        mujoco.mj_forward(w.model, w.data)
        parts = w.part_positions()
        rows = self.drv.rows
        return Outcome(
            success=success,
            reason=reason,
            detail=detail,
            times=np.array(self.drv.times),
            trajectory=np.vstack(rows) if rows else np.zeros((0, len(IK_JOINTS))),
            sim_time=float(w.data.time) - self.drv.t0,
            ik_seconds=self.ik_time,
            planning_seconds=self.plan_time,
            physics_seconds=self.drv.physics,
            wall_seconds=time.perf_counter() - self.t_wall,
            cabinet_displacement=w.cabinet_displacement(),
            part_motion={j: parts[j] - self.parts0[j] for j in parts},
        )

    def q_dict(self, q: np.ndarray) -> dict[str, float]:
        """Base (at its target) + torso + arm by name."""
        return {
            **dict(zip(BASE_JOINTS, self.base.tolist(), strict=True)),
            **dict(zip(IK_JOINTS, np.asarray(q).tolist(), strict=True)),
        }

    # -- base --------------------------------------------------------------------------------
    def base_for_line(self, poses: Sequence[np.ndarray]) -> None:
        """Base target: drive along the horizontal approach direction of ``poses[0]``
        so that the middle of the gripper path is :data:`REACH` from the shoulder."""
        approach = poses[0][:3, 0]
        flat = -approach[:2].copy()
        if np.linalg.norm(flat) < 0.3:
            return  # a near-vertical approach: stay
        flat /= np.linalg.norm(flat)
        mid = np.mean([T[:3, 3] for T in poses], axis=0)
        q_now = dict(zip(BASE_JOINTS, self.drv.base.tolist(), strict=True))
        shoulder = self.kin.frame_pose("shoulder_pan_link", q_now)[:3, 3]
        along = float((shoulder[:2] - mid[:2]) @ flat)
        base = self.drv.base
        base[:2] += (REACH - along) * flat
        self.base = base

    def base_for_top(self, p: np.ndarray) -> None:
        """Base target (yaw kept) that puts point ``p`` (3,) at :data:`TOP_REACH` in the
        robot's frame."""
        base = self.drv.base
        c, s = math.cos(base[2]), math.sin(base[2])
        off = np.array([c * TOP_REACH[0] - s * TOP_REACH[1], s * TOP_REACH[0] + c * TOP_REACH[1]])
        base[:2] = p[:2] - off
        self.base = base

    # -- IK ----------------------------------------------------------------------------------
    def key_pose(self, T: np.ndarray, seed_q: np.ndarray) -> np.ndarray:
        """Torso + arm (8,) reaching ``T`` with the base at its target (FetchIK)."""
        t = time.perf_counter()
        res = self.ik.solve(T, self.q_dict(seed_q))
        self.ik_time += time.perf_counter() - t
        if not res.success:
            raise _RunFailureError(
                "ik_infeasible",
                f"no IK solution for the key pose at {np.round(T[:3, 3], 3).tolist()} m "
                f"(residual {res.position_error * 1000:.1f} mm, {res.rotation_error:.3f} rad)",
            )
        return np.array([res.q[j] for j in IK_JOINTS])

    def line(self, poses: Sequence[np.ndarray], q: np.ndarray) -> list[np.ndarray]:
        """Torso + arm (8,) per pose of ``poses`` (a dense Cartesian path), warm started
        from ``q`` (damped least squares, Pinocchio)."""
        t = time.perf_counter()
        fixed = dict(zip(BASE_JOINTS, self.base.tolist(), strict=True))
        out = []
        try:
            for T in poses:
                q, ep, er = solve_ik(self.kin, T, fixed, q, limits=self.limits, iterations=60)
                if ep > 3e-3 or er > 3e-2:
                    raise _RunFailureError(
                        "ik_infeasible",
                        f"no IK solution along the path at {np.round(T[:3, 3], 3).tolist()} m "
                        f"(residual {ep * 1000:.1f} mm, {er:.3f} rad)",
                    )
                out.append(q)
        finally:
            self.ik_time += time.perf_counter() - t
        return out

    # -- planning ----------------------------------------------------------------------------
    def sync_plan(self) -> ManipulationWorld:
        """The planning world, the robot's and the object's state copied into it from the
        execution world by joint name (its cabinet stays as believed)."""
        if self.plan_world is not self.world:
            self.plan_world.copy_robot_state(self.world)
        return self.plan_world

    def scratch(self, base: np.ndarray | None = None) -> mujoco.MjData:
        """A copy of the planning world's state (synced, :meth:`sync_plan`) with the base
        at ``base`` (default its target)."""
        pw = self.sync_plan()
        m = pw.model
        d = mujoco.MjData(m)
        d.qpos[:] = pw.data.qpos
        for j, v in zip(BASE_JOINTS, self.base if base is None else base, strict=True):
            d.qpos[m.jnt_qposadr[m.joint(j).id]] = v
        mujoco.mj_kinematics(m, d)
        return d

    def is_tucked(self) -> bool:
        """The arm is near its home tuck (it must leave it through the untuck waypoints)."""
        home = np.array([self.world.scene.home_qpos[j] for j in IK_JOINTS[1:]])
        return bool(np.max(np.abs(self.drv.q_ik[1:] - home)) < 0.15)

    def plan_to(
        self,
        q_from: np.ndarray,
        q_goal: np.ndarray,
        allowed: Sequence[tuple[str, str]] = (),
        base: np.ndarray | None = None,
    ) -> np.ndarray:
        """Waypoints (N, 8) of a collision-free plan ``q_from -> q_goal`` (OMPL), the base
        at ``base`` (default its target)."""
        t = time.perf_counter()
        names = self.planner.joints
        plan = self.planner.plan(
            dict(zip(names, q_from.tolist(), strict=True)),
            dict(zip(names, q_goal.tolist(), strict=True)),
            self.scratch(base),
            timeout=PLAN_TIMEOUT,
            seed=self.seed + self.n_plans,
            allowed_contacts=list(allowed),
        )
        self.n_plans += 1
        self.plan_time += time.perf_counter() - t
        if not plan.success:
            raise _RunFailureError("no_motion_plan", f"{plan.reason}: {plan.detail}")
        return plan.waypoints

    def check_path(
        self, qs: Sequence[np.ndarray], allowed: frozenset[int], base: np.ndarray | None = None
    ) -> None:
        """Raise ``collision`` if the joint-space polyline ``qs`` makes unexpected contact
        (with the base at ``base``, default its target)."""
        t = time.perf_counter()
        where = self.base if base is None else base
        hits = PathCollisionChecker(self.sync_plan(), where).path(qs, allowed)
        self.plan_time += time.perf_counter() - t
        if hits:
            raise _RunFailureError("collision", f"the planned path touches {hits[0]}")

    # -- execution ---------------------------------------------------------------------------
    def reach(
        self,
        q_pre: np.ndarray,
        allowed: Sequence[tuple[str, str]] = (),
        untuck_torso: float | None = None,
    ) -> list:
        """Plan (untuck waypoints if tucked, then OMPL) from the current arm to
        ``q_pre``; returns the joint-space waypoints to execute (each (8,)). The torso
        rises to ``untuck_torso`` [m] (default: the pre-grasp's, so that it moves only
        once, while the base drives) before the arm leaves its tuck (checked kinematically
        for collisions)."""
        q = self.drv.q_ik
        out: list[np.ndarray] = []
        self.untucking = self.is_tucked()
        if self.untucking:
            # The torso (slow: 0.07 m/s) rises in even steps over the untuck waypoints,
            # while the base drives, instead of before them.
            t0 = float(q[0])
            t1 = float(q_pre[0]) if untuck_torso is None else untuck_torso
            n = len(UNTUCK_ARM)
            out = [np.array([t0 + (t1 - t0) * (k + 1) / n, *a]) for k, a in enumerate(UNTUCK_ARM)]
            out[-1][-1] = q_pre[-1]
            try:
                self.check_path([q, *out], frozenset())
            except _RunFailureError:
                # Blocked where the base goes (e.g. by the table): untuck where it is.
                self.untuck_first = True
                self.check_path([q, *out], frozenset(), base=self.drv.base)
            q = out[-1]
        way = self.plan_to(q, q_pre, allowed)
        return out + [w for w in way[1:]]

    def execute_reach(self, path: Sequence[np.ndarray]) -> None:
        """Drive the base to its target and follow the joint-space ``path`` segment by
        segment: from the tuck, the untuck waypoints run while the base drives; else the
        base arrives first."""
        far = (
            np.max(np.abs(self.base - self.drv.base)[:2]) > DRIVE_TOLERANCE
            or abs(self.base[2] - self.drv.base[2]) > 0.02
        )
        if far and not self.untucking:
            self.drv.drive(self.base, float(self.drv.ik_cmd[0]))
        if not self.untuck_first:
            self.drv.base_target = self.base.copy()
        for k, q in enumerate(path):
            self.drv.move(q, UNTUCK_TIME)
            if k == len(UNTUCK_ARM) - 1 and self.untucking:
                if self.untuck_first:
                    self.drv.drive(self.base, float(self.drv.ik_cmd[0]))
                self._await_base()
        self.drv.hold(SETTLE_TIME / 2)
        self.check_tracking(path[-1] if len(path) else self.drv.ik_cmd)

    def _await_base(self) -> None:
        """Hold (at most 3 s) until the base is within 5 mm of its target."""
        for _ in range(30):
            if np.max(np.abs(self.base - self.drv.base)[:2]) < 0.005:
                return
            self.drv.hold(0.1)

    def check_tracking(self, q_goal: np.ndarray) -> None:
        """Raise ``collision`` if the arm did not get to ``q_goal`` (blocked)."""
        err = float(np.max(np.abs(self.drv.q_ik - q_goal)))
        if err > TRACKING_TOLERANCE:
            raise _RunFailureError(
                "collision", f"the arm is blocked: tracking error {err:.3f} rad or m"
            )

    def follow(self, qs: Sequence[np.ndarray], length: float, speed: float) -> None:
        """Follow a dense joint-space path ``qs`` covering ``length`` [m] of TCP motion."""
        self.drv.follow(qs, max(0.4, length / speed))

    def fingers(self) -> float:
        """Mean finger travel [m] (0: closed on nothing)."""
        m, d = self.world.model, self.world.data
        return float(d.ten_length[m.tendon("gripper").id])

    def tcp(self) -> np.ndarray:
        """Current TCP pose (4, 4)."""
        mujoco.mj_forward(self.world.model, self.world.data)
        return self.world.site_pose(GRIPPER_SITE)


def _poses_along(
    T: np.ndarray, direction_pose: Callable[[float], np.ndarray], length: float
) -> list[np.ndarray]:
    """Poses ``direction_pose(s)`` for ``s`` evenly in (0, 1], every ~:data:`LINE_STEP`
    of ``length`` [m]."""
    n = max(2, math.ceil(length / LINE_STEP))
    return [direction_pose(k / n) for k in range(1, n + 1)]


def _straight(T: np.ndarray, d: np.ndarray) -> list[np.ndarray]:
    """Poses from ``T`` (excluded) to ``T`` translated by ``d`` (3,) [m]."""

    def pose(s: float) -> np.ndarray:
        out = T.copy()
        out[:3, 3] += s * d
        return out

    return _poses_along(T, pose, float(np.linalg.norm(d)))


# --- grasp-and-move controllers ------------------------------------------------------------


def _grasp_and_move(
    world: ManipulationWorld,
    g: np.ndarray,
    motion: Callable[[np.ndarray], tuple[list[np.ndarray], float]],
    seed: int,
    observer: Observer | None,
    *,
    close: bool = True,
    min_motion: float = 0.0,
    plan_world: ManipulationWorld | None = None,
) -> Outcome:
    """Reach ``g``, grasp (``close``) and move the gripper along ``motion(g)`` (its poses
    and their path length [m]), all under the believed model in ``motion``.

    Success: the TCP still holds the grasp point (if ``close``), the cabinet moved at
    most :data:`CABINET_TOLERANCE`, and the grasped part's joint moved by more than
    ``min_motion`` [m or rad] (ground truth, measured). Collision checks and plans use
    ``plan_world`` (default ``world``).
    """
    run = _Run(world, seed, observer, plan_world)
    g = _check_g(g)
    link = grasped_part(world, g)
    try:
        poses, length = motion(g)
        approach = g[:3, 0]
        pre = g.copy()
        pre[:3, 3] -= PREGRASP_OFFSET * approach
        run.base_for_line([g, *poses])
        # Key poses: pre-grasp (FetchIK), then the approach and the motion (DLS lines),
        # trying the fingers swapped if the first orientation fails.
        last: _RunFailureError | None = None
        plan = None
        for flip in (False, True):
            R = flip_fingers(g[:3, :3]) if flip else g[:3, :3]
            gg, pp = g.copy(), pre.copy()
            gg[:3, :3] = pp[:3, :3] = R
            mv = [T.copy() for T in poses]
            for T in mv:
                T[:3, :3] = T[:3, :3] @ g[:3, :3].T @ R
            try:
                seed_q = np.array([UNTUCK_TORSO, *UNTUCK_ARM[-1]])
                q_pre = run.key_pose(pp, seed_q)
                appr = run.line(_straight(pp, gg[:3, 3] - pp[:3, 3]), q_pre)
                moving = run.line(mv, appr[-1])
                allow = run.cabinet_bodies
                run.check_path([q_pre, *appr], allow)
                reach = run.reach(q_pre)
                plan = (reach, appr, moving)
                mv_end = mv[-1]
                break
            except _RunFailureError as exc:
                last = exc
        if plan is None:
            assert last is not None
            raise last
        reach, appr, moving = plan
        run.key("start")
        run.drv.gripper(GRIPPER_OPEN, 0.0)
        run.execute_reach(reach)
        run.key("pre-grasp")
        run.follow(appr, PREGRASP_OFFSET, APPROACH_SPEED)
        run.drv.hold(SETTLE_TIME / 2)
        if close:
            run.drv.gripper(GRIPPER_CLOSED, GRIP_TIME)
        run.key("grasp")
        run.follow(moving, length, OPEN_SPEED)
        run.drv.hold(SETTLE_TIME / 2)
        run.key("end")
        lag = float(np.linalg.norm(run.tcp()[:3, 3] - mv_end[:3, 3]))
        if lag > HELD_TOLERANCE:
            raise _RunFailureError(
                "collision",
                f"the gripper was held back {lag:.3f} m from the end of its path "
                "(the part does not move as believed)",
            )
        held_error = _held_error(run, link) if close else 0.0
        empty = close and run.fingers() < FINGERS_EMPTY
        if close:
            run.drv.gripper(GRIPPER_OPEN, GRIP_TIME)
    except _RunFailureError as exc:
        return run.outcome(False, exc.reason, exc.detail)
    # --- judge (ground truth) ---------------------------------------------------------
    out = run.outcome(True, "ok")
    moved = 0.0
    if link is not None:
        joint = world.scene.cabinet_prefix + _part(world, link).joint
        moved = abs(out.part_motion[joint])
    if out.cabinet_displacement > CABINET_TOLERANCE:
        return run.outcome(
            False, "collision", f"the cabinet was dragged {out.cabinet_displacement:.3f} m"
        )
    if empty or held_error > HELD_TOLERANCE:
        return run.outcome(
            False,
            "grasp_lost",
            f"the gripper lost the handle of {link}: TCP {held_error:.3f} m from it"
            + (", fingers closed on nothing" if empty else ""),
        )
    if moved <= min_motion:
        return run.outcome(
            False,
            "grasp_lost",
            f"the part ({link}) moved {moved:.3f} m or rad, needed more than {min_motion:.3f}",
        )
    return out


def _held_error(run: _Run, link: str | None) -> float:
    """Distance [m] from the TCP to where part ``link``'s handle is now (ground truth;
    inf if no part was grasped)."""
    if link is None:
        return math.inf
    world = run.world
    part = _part(world, link)
    T = _body_pose(world, world.scene.cabinet_prefix + world.scene.cabinet.root)
    q = world.part_positions()[world.scene.cabinet_prefix + part.joint]
    return float(np.linalg.norm(run.tcp()[:3, 3] - part.handle_at(q, T)))


def _opening_motion(joint: BelievedJoint, travel: float) -> Callable:
    """``motion(g)`` of an opening along ``joint`` by ``travel`` [m or rad] (capped)."""

    def motion(g: np.ndarray) -> tuple[list[np.ndarray], float]:
        amount = min(travel, joint.limit - (0.02 if joint.type == "prismatic" else 0.05))
        if amount <= 0:
            raise _RunFailureError(
                "ik_infeasible", f"the believed joint has no travel left ({joint.limit})"
            )
        if joint.type == "prismatic":
            length = amount
        else:
            r = np.cross(joint.axis, g[:3, 3] - joint.origin)
            length = float(np.linalg.norm(r)) * amount
        n = max(2, math.ceil(length / LINE_STEP))
        return [joint.move(g, amount * k / n) for k in range(1, n + 1)], length

    return motion


def _check_travel(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
        raise ConfigError(f"{name} must be a positive number, got {value!r}")
    return float(value)


#: Least part motion [m or rad] that counts as a probe (Push, PullV, PullH) moving it.
PROBE_MIN_MOTION = 0.005


class _GraspAndMove:
    """Shared ``run`` of the controllers that grasp at ``g`` and move the gripper.

    A subclass gives ``g`` (a dataclass field) and :meth:`motion`: the gripper path as a
    function of the grasp pose, and the least part motion that counts as success.
    """

    g: np.ndarray

    def motion(self) -> tuple[Callable[[np.ndarray], tuple[list[np.ndarray], float]], float]:
        raise NotImplementedError

    def run(
        self,
        world: ManipulationWorld,
        seed: int = 0,
        observer: Observer | None = None,
        plan_world: ManipulationWorld | None = None,
    ) -> Outcome:
        """Execute in ``world`` (see the class docstring), collision checks and motion
        plans against ``plan_world`` (default ``world``; e.g. the believed cabinet)."""
        path, min_motion = self.motion()
        return _grasp_and_move(
            world, self.g, path, seed, observer, min_motion=min_motion, plan_world=plan_world
        )


@dataclass(frozen=True)
class OpenDrawer(_GraspAndMove):
    """Grasp at ``g`` and pull straight along the believed prismatic axis.

    Attributes:
        g: grasp pose ``T_world_gripper``, (4, 4) [m].
        joint: the believed joint (followed whatever its type: a revolute belief
            swings the gripper on an arc).
        travel: how far to pull [m] (capped 2 cm before the believed limit).

    Success: the grasped part opened by more than :data:`OPEN_FRACTION` of ``travel``
    and the cabinet moved at most :data:`CABINET_TOLERANCE`.
    """

    g: np.ndarray
    joint: BelievedJoint
    travel: float = DRAWER_TRAVEL

    def motion(self) -> tuple[Callable, float]:
        travel = _check_travel("travel", self.travel)
        return (
            _opening_motion(self.joint, travel),
            OPEN_FRACTION * min(travel, self.joint.limit),
        )


@dataclass(frozen=True)
class OpenDoor(_GraspAndMove):
    """Grasp at ``g`` and swing the gripper on an arc about the believed hinge.

    Attributes:
        g: grasp pose ``T_world_gripper``, (4, 4) [m].
        joint: the believed joint (a prismatic belief gives a straight pull).
        angle: how far to open [rad] (for a prismatic belief: [m]).

    Success: the grasped part opened by more than :data:`OPEN_FRACTION` of ``angle``
    and the cabinet moved at most :data:`CABINET_TOLERANCE`.
    """

    g: np.ndarray
    joint: BelievedJoint
    angle: float = DOOR_ANGLE

    def motion(self) -> tuple[Callable, float]:
        angle = _check_travel("angle", self.angle)
        return _opening_motion(self.joint, angle), OPEN_FRACTION * min(angle, self.joint.limit)


def _probe(direction: Callable[[np.ndarray], np.ndarray]) -> Callable:
    def motion(g: np.ndarray) -> tuple[list[np.ndarray], float]:
        return _straight(g, PROBE_DISTANCE * direction(g)), PROBE_DISTANCE

    return motion


@dataclass(frozen=True)
class Push(_GraspAndMove):
    """Grasp the part at ``g`` and push :data:`PROBE_DISTANCE` along
    the approach direction. Success: the part moved by more than 5 mm or mrad."""

    g: np.ndarray

    def motion(self) -> tuple[Callable, float]:
        return _probe(lambda g: g[:3, 0]), PROBE_MIN_MOTION


@dataclass(frozen=True)
class PullV(_GraspAndMove):
    """Grasp at ``g`` and pull :data:`PROBE_DISTANCE` vertically (world +z; ``down``
    for -z). Success: the part moved by more than 5 mm or mrad."""

    g: np.ndarray
    down: bool = False

    def motion(self) -> tuple[Callable, float]:
        up = np.array([0.0, 0.0, -1.0 if self.down else 1.0])
        return _probe(lambda g: up), PROBE_MIN_MOTION


@dataclass(frozen=True)
class PullH(_GraspAndMove):
    """Grasp at ``g`` and pull :data:`PROBE_DISTANCE` horizontally out of the cabinet
    (against the approach, made horizontal; ``sideways`` pulls along the horizontal
    direction perpendicular to it instead, z x pull). Success: the part
    moved by more than 5 mm or mrad."""

    g: np.ndarray
    sideways: bool = False

    def motion(self) -> tuple[Callable, float]:
        def direction(g: np.ndarray) -> np.ndarray:
            a = -g[:3, 0].copy()
            a[2] = 0.0
            a /= max(float(np.linalg.norm(a)), 1e-9)
            if self.sideways:
                a = np.cross([0.0, 0.0, 1.0], a)
            return a

        return _probe(direction), PROBE_MIN_MOTION


# --- pick and place ------------------------------------------------------------------------

#: Bodies that may touch a held (or grasped) object.
_GRIPPER_BODIES: tuple[str, ...] = (
    "r_gripper_finger_link",
    "l_gripper_finger_link",
    "gripper_link",
)


def _check_object(world: ManipulationWorld, o: str) -> None:
    if o != "object":
        raise UnknownNameError("graspable object", o, ["object"])


def top_grasp(T_world_object: np.ndarray, height: float = PICK_HEIGHT) -> np.ndarray:
    """``T_world_gripper`` (4, 4) of a top grasp of the box at ``T_world_object``: the
    approach straight down, the fingers closing across the box's y side (its 0.06 m
    one), the TCP ``height`` [m] above the box's centre."""
    T = np.eye(4)
    x = np.array([0.0, 0.0, -1.0])
    y = T_world_object[:3, 1].copy()
    y[2] = 0.0
    y /= np.linalg.norm(y)
    T[:3, :3] = np.column_stack([x, y, np.cross(x, y)])
    T[:3, 3] = T_world_object[:3, 3] + np.array([0.0, 0.0, height])
    return T


def _vertical(run: _Run, T: np.ndarray, dz: float, q: np.ndarray) -> list[np.ndarray]:
    return run.line(_straight(T, np.array([0.0, 0.0, dz])), q)


@dataclass(frozen=True)
class Pick:
    """Pick object ``o`` from where it lies with a top grasp and lift it.

    Attributes:
        o: the object's body name (the scene has one: ``"object"``).
        lift: lift height after the grasp [m].

    Success: the object rose by more than half of ``lift`` and the fingers hold it
    (not closed on nothing).
    """

    o: str = "object"
    lift: float = LIFT_HEIGHT

    def run(
        self,
        world: ManipulationWorld,
        seed: int = 0,
        observer: Observer | None = None,
        plan_world: ManipulationWorld | None = None,
    ) -> Outcome:
        """Execute in ``world`` (see the class docstring), collision checks and motion
        plans against ``plan_world`` (default ``world``; e.g. the believed cabinet)."""
        _check_object(world, self.o)
        lift = _check_travel("lift", self.lift)
        run = _Run(world, seed, observer, plan_world)
        T_wo = world.object_pose()
        z0 = float(T_wo[2, 3])
        allow = [(b, self.o) for b in _GRIPPER_BODIES]
        try:
            g = top_grasp(T_wo)
            pre = g.copy()
            pre[2, 3] += lift
            run.base_for_top(g[:3, 3])
            seed_q = np.array([UNTUCK_TORSO, *UNTUCK_ARM[-1]])
            q_pre = run.key_pose(pre, seed_q)
            down = _vertical(run, pre, -lift, q_pre)
            up = _vertical(run, g, lift, down[-1])
            obj = run.object_body
            run.check_path([q_pre, *down], obj)
            reach = run.reach(q_pre, allow)
            run.key("start")
            run.drv.gripper(GRIPPER_OPEN, 0.0)
            run.execute_reach(reach)
            run.key("pre-grasp")
            run.follow(down, lift, APPROACH_SPEED)
            run.drv.hold(SETTLE_TIME / 2)
            run.drv.gripper(GRIPPER_CLOSED, GRIP_TIME)
            run.key("grasp")
            run.follow(up, lift, APPROACH_SPEED)
            run.drv.hold(SETTLE_TIME / 2)
            run.key("end")
        except _RunFailureError as exc:
            return run.outcome(False, exc.reason, exc.detail)
        mujoco.mj_forward(world.model, world.data)
        rise = float(world.object_pose()[2, 3]) - z0
        if run.fingers() < FINGERS_EMPTY or rise < 0.5 * lift:
            return run.outcome(
                False, "grasp_lost", f"the object rose {rise:.3f} m of the {lift:.3f} m lift"
            )
        return run.outcome(True, "ok")


@dataclass(frozen=True)
class Place:
    """Carry the held object ``o`` to pose ``p`` from above, release it and retreat.

    Attributes:
        o: the object's body name.
        p: target ``T_world_object``, (4, 4) [m] (the gripper keeps its grasp offset).
        clearance: height above ``p`` from which the object is lowered [m] (clears the
            walls of a drawer).

    Success: after the release the object rests within :data:`PLACE_TOLERANCE` of
    ``p``'s position.
    """

    o: str
    p: np.ndarray
    clearance: float = 0.45

    def run(
        self,
        world: ManipulationWorld,
        seed: int = 0,
        observer: Observer | None = None,
        plan_world: ManipulationWorld | None = None,
    ) -> Outcome:
        """Execute in ``world`` (see the class docstring), collision checks and motion
        plans against ``plan_world`` (default ``world``; e.g. the believed cabinet)."""
        _check_object(world, self.o)
        p = check_pose("p (T_world_object)", self.p)
        clearance = _check_travel("clearance", self.clearance)
        run = _Run(world, seed, observer, plan_world)
        allow = [(b, self.o) for b in _GRIPPER_BODIES]
        try:
            mujoco.mj_forward(world.model, world.data)
            T_wg, T_wo = run.tcp(), world.object_pose()
            if run.fingers() < FINGERS_EMPTY or np.linalg.norm(T_wg[:3, 3] - T_wo[:3, 3]) > 0.08:
                raise _RunFailureError("grasp_lost", "the gripper does not hold the object")
            T_og = np.linalg.inv(T_wo) @ T_wg
            g = p @ T_og
            pre = g.copy()
            pre[2, 3] += clearance
            run.base_for_top(g[:3, 3])
            q_pre = run.key_pose(pre, run.drv.q_ik)
            down = _vertical(run, pre, -clearance, q_pre)
            up = _vertical(run, g, clearance / 2, down[-1])
            # Carry: the arm takes its pre-place posture where the base is (the object
            # high above anything), then the base drives under it.
            here = run.drv.base
            carry = run.plan_to(run.drv.q_ik, q_pre, allow, base=here)
            run.key("start")
            run.drv.base_target = here
            for q in carry[1:]:
                run.drv.move(q, UNTUCK_TIME)
            run.drv.drive(run.base, float(q_pre[0]))
            run._await_base()
            run.drv.hold(SETTLE_TIME / 2)
            run.check_tracking(q_pre)
            run.key("pre-place")
            run.follow(down, clearance, APPROACH_SPEED)
            run.drv.hold(SETTLE_TIME / 2)
            run.drv.gripper(GRIPPER_OPEN, GRIP_TIME)
            run.key("release")
            run.follow(up, clearance / 2, APPROACH_SPEED)
            run.drv.hold(SETTLE_TIME)
            run.key("end")
        except _RunFailureError as exc:
            return run.outcome(False, exc.reason, exc.detail)
        mujoco.mj_forward(world.model, world.data)
        err = float(np.linalg.norm(world.object_pose()[:3, 3] - p[:3, 3]))
        if err > PLACE_TOLERANCE:
            return run.outcome(False, "grasp_lost", f"the object rests {err:.3f} m from p")
        return run.outcome(True, "ok")
