"""The skills' planning twin: the same skill plan, run by the Fetch's hand alone.

A search simulates skills thousands of times on the particles of a belief; the full
robot costs a drive, an untuck, OMPL and seconds of arm physics per run. The twin runs
the same :class:`~strug_manip.control.plan.SkillPlan` in a world of the same cabinet
with the Fetch's floating hand (:mod:`strug_manip.world.floating_gripper`) and returns
the same :class:`~strug_manip.control.outcome.Outcome`:

1. **reachability**: the full robot's base placement search (the IK of the pre-grasp
   and every line, the Fetch's collisions checked in a world of the twin's cabinet as
   it is now; cached per twin, plan, base pose and scene state, so a search that
   simulates a skill again on a particle pays it once; a search first tries, alone,
   the base a similar plan took (the same skill on the same part in another particle,
   :class:`~.placement.PlacementHints`), so the twin may stand where the full robot,
   comparing three, would not): no placement is
   ``ik_infeasible``, as for the full robot; a placement gives each line's joint path,
   hence its duration under the one timing law (:mod:`.timing`), the same as the full
   robot's;
2. **compliance and strength**: the hand's translation servos get the stiffness of
   the Fetch's joint servos (base, torso, arm) seen at the hand at the placement's
   grasp configuration, along its principal axes (:func:`~.twin_servo.arm_servo`: the compliance
   ``J K^-1 J^T``; a reaching arm gives way horizontally far more than
   vertically, which decides whether a wrong pull slides the fingers off a handle's
   end), and the
   force and torque the Fetch's joints can exert there (their effort limits through
   the hand's Jacobian, the grasp passing a moment as well as a force);
3. **physics**: the hand starts at the pre-grasp (the free motion of the full robot,
   collision free by construction, is not simulated), then follows the lines (their
   Cartesian poses, on the same schedule as the arm's joint path; the retreat after a
   release too: backing away can catch a handle) and grips, with the same settle and
   grip times, the same stop rules (the executor core's, :mod:`.executor`: a lost
   grasp, the cabinet slid more than ``cabinet_motion_limit``, the hand held back more
   than the tracking tolerance) and the same facts measured at the end
   (:func:`~.executor.report`); after the last release the arm's links (mocap bodies)
   follow the arm's joint path too, so a forearm backing out of a drawer sweeps what
   the full robot's would (unless they would appear inside a part,
   :data:`~.twin_rollout.ARM_ENTRY_DEPTH`); after a stop, the full robot's recovery,
   which ends where the cabinet slides; then hand and arm follow the full robot's stow
   (the core's: its straight way back to the pre-grasp, :func:`~.executor.stow_retreat`,
   where that is free, else the same plan, :func:`~.executor.plan_stow`) until they
   are clear of the cabinet, leave the scene, and the cabinet and the object settle for
   :data:`~.twin_program.COAST_TIME`, and on while the cabinet still moves
   (:data:`~.executor.REST_SPEED`), up to the rest of the stow's duration (a drawer
   of a dragged, tilted cabinet creeps on while the full robot stows); everything after
   the last release runs :data:`~.twin_rollout.FREE_COARSENING` times coarser. Where a
   line moves the base, the hand's command moves with the full robot's base as it lags
   and overshoots its command (:class:`~.base_servo.BaseServo`); the monitors compare
   the hand with the plan, as the full robot's compare it with its command.

The twin is one of the executor's two bodies (:class:`~.executor.Body`; the other is
the full robot, :mod:`.fetch_body`); its class is split by concept: the body here
(state, placement, the hand's servos, the report), the programs
(:mod:`.twin_program`) and the rollouts (:mod:`.twin_rollout`); the arm's servo model
is :mod:`.twin_servo`.

A twin's state (:meth:`PlanningTwin.snapshot`) includes where the full robot's base is
believed to stand (the ``robot_base`` mocap body), from which the next placement starts.
"""

from __future__ import annotations

import dataclasses
import time
import weakref

import mujoco
import numpy as np

from planners.errors import ConfigError
from strug_manip.cache import LRU
from strug_manip.control.base_servo import BaseServo
from strug_manip.control.contacts import HAND_BODIES
from strug_manip.control.context import ControlContext
from strug_manip.control.executor import (
    OpeningPath,
    drive_posture,
    facts_before,
    holds,
    report,
)
from strug_manip.control.outcome import Outcome, SkillStop, Status
from strug_manip.control.params import DEFAULT_PARAMS, SkillParams
from strug_manip.control.placement import Placement, find_placement, work_frame
from strug_manip.control.plan import SkillPlan
from strug_manip.control.twin_program import BASE_SPEED, PROGRAMS, Program, TwinPrograms
from strug_manip.control.twin_rollout import ROLLOUT_STATE, TCP_OFFSET, TwinRollout, stopped
from strug_manip.control.twin_servo import arm_servo
from strug_manip.geometry import mat_of, quat_of
from strug_manip.objects.generator import CabinetSpec
from strug_manip.robot.fetch import (
    BASE_JOINTS,
    GRIPPER_JOINTS,
    GRIPPER_OPEN,
    GRIPPER_SITE,
    GRIPPER_SQUEEZE,
    TUCK,
    speed_limits,
)
from strug_manip.world.floating_gripper import (
    ARM_LINKS,
    ARM_PARK,
    BALL,
    INTEGRAL_TIME,
    SERVOS,
    SLIDES,
)
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld, WorldState

#: The twin's physics step [s]: 2.5 times the full robot's; the stiff contacts and
#: joint stops (a 4 ms time constant) soften to MuJoCo's floor of two steps, and the
#: twin still agrees with the full robot (``tools/eval_skills.py`` measures it).
TIMESTEP = 0.005


class PlanningTwin(TwinPrograms, TwinRollout):
    """A cabinet and the Fetch's floating hand: where skills are simulated fast.

    Args:
        spec: the cabinet (e.g. a belief particle), compiled in memory.
        config: the rest of the scene (default: the built-in one); its cabinet, robot and
            time step are replaced by ``spec``, the floating hand and ``timestep``.
        ctx: shared IK solvers and the placement cache (default: a new context).
        params: the skills' constants (default :data:`DEFAULT_PARAMS`).
        checked: the placement search checks the Fetch's collisions as the full robot's
            does (in a world of the same cabinet with the Fetch, built on first use),
            so the twin predicts the same placement and ``ik_infeasible``; False:
            kinematic only (faster on a cold cache, less faithful).
        timestep: the twin's physics step [s] (default :data:`TIMESTEP`): a smaller
            step agrees with the full robot more often and costs proportionally more
            (``tools/eval_skills.py --twin-steps`` measures both; the README has the
            figures).

    Raises:
        ConfigError: ``spec`` is not a :class:`CabinetSpec`, or ``timestep`` is not a
            positive number of at most 0.01 s.
    """

    def __init__(
        self,
        spec: CabinetSpec,
        config: SceneConfig | None = None,
        ctx: ControlContext | None = None,
        params: SkillParams = DEFAULT_PARAMS,
        checked: bool = True,
        timestep: float = TIMESTEP,
    ) -> None:
        if not isinstance(spec, CabinetSpec):
            raise ConfigError(f"spec must be a CabinetSpec, got {spec!r}")
        base = config or SceneConfig()
        cfg = dataclasses.replace(  # SceneConfig validates the step
            base, cabinet_spec=spec, cabinet_folder=None, robot="gripper", timestep=timestep
        )
        self.world = ManipulationWorld(cfg)
        self._robot_config = dataclasses.replace(
            base, cabinet_spec=spec, cabinet_folder=None, robot="fetch"
        )
        self.ctx = ctx or ControlContext()
        self.params = params
        self.checked = bool(checked)
        self._planning_world: ManipulationWorld | None = None
        self._programs = LRU(PROGRAMS)
        # What the twin derives from each placement (servos, base response, arm and
        # stow paths), dropped with the placement (:meth:`_of`).
        self._derived: weakref.WeakKeyDictionary[Placement, dict] = weakref.WeakKeyDictionary()
        self._base_servo: BaseServo | None = None
        m = self.world.model
        self._slide_adr = np.array([m.jnt_qposadr[m.joint(j).id] for j in SLIDES])
        self._slide_dof = np.array([m.jnt_dofadr[m.joint(j).id] for j in SLIDES])
        self._ball_adr = int(m.jnt_qposadr[m.joint(BALL).id])
        self._ball_dof = int(m.jnt_dofadr[m.joint(BALL).id])
        self._slide_act = np.array([m.actuator(j).id for j in SERVOS])
        self._slide_ctrl = np.array([self.world.ctrl_index(j) for j in SERVOS])
        self._servo_wraps = np.array([m.tendon_adr[m.tendon(t).id] for t in SERVOS])
        # The mass each slide carries [kg] (compiled critically damped: kv^2 / 4 kp).
        bias = m.actuator_biasprm[self._slide_act]
        self._slide_mass = bias[:, 2] ** 2 / (4.0 * -bias[:, 1])
        self._axes = np.eye(3)  # the servos' directions (columns), world frame
        self._rot_act = m.actuator(BALL).id
        self._rot_ctrl = self.world.ctrl_index(BALL)
        self._grip_ctrl = self.world.ctrl_index("gripper")
        self._site = m.site(GRIPPER_SITE).id
        self._tendon = m.tendon("gripper").id
        self._base_mocap = int(m.body_mocapid[m.body("robot_base").id])
        self._arm_mocap = np.array([int(m.body_mocapid[m.body(b).id]) for b in ARM_LINKS])
        self._arm_fetch = [self.ctx.ik.model.body(b).id for b in ARM_LINKS]
        self._arm_bodies = np.array([m.body(b).id for b in ARM_LINKS])
        self._obj_adr = int(m.jnt_qposadr[m.joint("object/free").id])
        self._fingers = [m.jnt_qposadr[m.joint(j).id] for j in GRIPPER_JOINTS]
        self.vmax = speed_limits(self.ctx.ik.model)
        hand = {m.body(b).id for b in HAND_BODIES}
        self._hand_geoms = [g for g in range(m.ngeom) if int(m.geom_bodyid[g]) in hand]
        self._hand_collide = {g: _collide(m, g) for g in self._hand_geoms}
        self._obj_body = m.body("object").id
        self._obj_geom = m.geom("object").id
        self._obj_collide = _collide(m, self._obj_geom)
        # The cabinet's joints (its own planning world follows them).
        self._cabinet_joints = [*self.world.part_joints, self.world.scene.cabinet_prefix + "free"]
        dofs = []
        for j in self._cabinet_joints:
            jid = m.joint(j).id
            n = 6 if m.jnt_type[jid] == mujoco.mjtJoint.mjJNT_FREE else 1
            dofs.append(np.arange(m.jnt_dofadr[jid], m.jnt_dofadr[jid] + n))
        self._cabinet_dofs = np.concatenate(dofs)
        free = m.joint(self.world.scene.cabinet_prefix + "free").id
        self._cabinet_xy = int(m.jnt_qposadr[free])  # its body's x, y in qpos
        #: Where the cabinet stood (x, y) [m] when the current skill started.
        self.cabinet_xy0 = np.zeros(2)
        self.cabinet0 = np.eye(4)
        #: An opening's part strained in its first ``end_share`` at an earlier check.
        self._early = False
        self._opening: OpeningPath | None = None  # the current run's, once per run
        self.reset()

    # -- state -------------------------------------------------------------------------
    def reset(
        self, part_positions: dict[str, float] | None = None, robot_base: np.ndarray | None = None
    ) -> None:
        """The scene at rest (the hand parked, the object on its table), the parts at
        ``part_positions``, the full robot's base believed at ``robot_base`` (x, y, yaw;
        default the origin)."""
        self.world.reset(part_positions)
        self.set_robot_base(np.zeros(3) if robot_base is None else robot_base)

    def set_robot_base(self, base: np.ndarray) -> None:
        """Where the full robot's base is believed to stand (x [m], y [m], yaw [rad])."""
        b = np.asarray(base, dtype=float)
        d = self.world.data
        d.mocap_pos[self._base_mocap] = [b[0], b[1], 0.0]
        d.mocap_quat[self._base_mocap] = [np.cos(b[2] / 2), 0.0, 0.0, np.sin(b[2] / 2)]

    @property
    def robot_base(self) -> np.ndarray:
        """The believed base pose of the full robot, (3,)."""
        d = self.world.data
        q = d.mocap_quat[self._base_mocap]
        yaw = 2.0 * np.arctan2(q[3], q[0])
        return np.array([*d.mocap_pos[self._base_mocap][:2], yaw])

    def snapshot(self) -> WorldState:
        """The whole state (physics, the believed robot base)."""
        return self.world.snapshot()

    def restore(self, state: WorldState) -> None:
        """Back to a :meth:`snapshot`."""
        self.world.restore(state)

    # -- the run -----------------------------------------------------------------------
    def run(self, plan: SkillPlan, plan_world: ManipulationWorld | None = None) -> Outcome:
        """Simulate ``plan`` (see the module docstring), made against ``plan_world`` (the
        world the robot believes in, whose cabinet the placement's collision checks
        see; default: this twin's own cabinet); never raises for a failure of the
        skill."""
        return run_batch([self], plan, plan_world)[0]

    def mark_cabinet(self) -> None:
        """Take where the cabinet base stands now as where the skill started: the stop
        rules measure its slide (``cabinet_xy0``, (2,) [m]) and its give at the grasp
        (``cabinet0``, (4, 4)) from there."""
        q, c = self.world.data.qpos, self._cabinet_xy
        self.cabinet_xy0 = q[c : c + 2].copy()
        self.cabinet0 = np.eye(4)
        self.cabinet0[:3, :3] = mat_of(q[c + 3 : c + 7])
        self.cabinet0[:3, 3] = q[c : c + 3]

    def _placement(self, plan: SkillPlan, plan_world: ManipulationWorld | None) -> Placement:
        base = self.robot_base
        reach = drive_posture(plan.carrying)
        pw = self._planning(plan_world)
        # What the collision checks see: the believed world's cabinet and the twin's
        # object (to the millimetre).
        state = b""
        if pw is not None:
            state = pw.cabinet_key()
        obj = np.round(self.world.data.qpos[self._obj_adr : self._obj_adr + 7], 3).tobytes()

        def search() -> Placement:
            hints = self.ctx.hints
            found = find_placement(
                plan, self.ctx.ik, self.ctx.wb_ik, base, (np.array(TUCK), reach),
                (self.vmax, BASE_SPEED), self._checker(plan, base, pw),
                like=hints.get(plan, base),
            )  # fmt: skip
            hints.put(plan, base, found)
            return found

        # The search sees the robot's base only through the candidates' work direction
        # (placement.work_frame), so particles standing elsewhere share one search.
        frame = np.round(work_frame(plan, base)[1], 4).tobytes()
        return self.ctx.placement(("twin", self._token(pw), plan.key, frame, state, obj), search)

    def _token(self, pw: ManipulationWorld | None) -> object:
        """A key for planning world ``pw`` in the context's placement cache
        (:meth:`~strug_manip.control.context.ControlContext.world_token`: twins that
        plan in one world share its placements)."""
        if pw is None:
            return None
        return self.ctx.world_token(pw)

    def _planning(self, plan_world: ManipulationWorld | None) -> ManipulationWorld | None:
        """The world of the placement's collision checks: ``plan_world``, else a world of
        the twin's own cabinet with the Fetch (built on first use) in the twin's cabinet
        state; None for a kinematic-only twin."""
        if not self.checked:
            return None
        if plan_world is not None:
            return plan_world
        if self._planning_world is None:
            self._planning_world = ManipulationWorld(self._robot_config)
        self._planning_world.copy_joints(self.world, self._cabinet_joints)
        return self._planning_world

    def _checker(self, plan: SkillPlan, base: np.ndarray, pw: ManipulationWorld | None):
        """The full robot's contact checker in ``pw`` with the twin's object, the base at
        ``base``; None without a planning world."""
        if pw is None:
            return None
        pw.copy_joints(self.world, ["object/free"])
        checker = self.ctx.checker(pw.model).load(pw.data)
        checker.set(dict(zip(BASE_JOINTS, base.tolist(), strict=True)))
        checker.attach(*plan.carrying) if plan.carrying is not None else checker.attach(None)
        return checker.allow()

    def _start(self, prog: Program) -> None:
        """The hand where the program starts, at rest, with the strength of the arm
        there; the carried object in its fingers."""
        plan = prog.plan
        touches = plan.carrying is not None or any("object" in ln.touch for ln in plan.lines)
        self._object_idle(not touches)
        self._servos(prog.placement)
        self._set_hand(prog.start)
        m, d = self.world.model, self.world.data
        if plan.carrying is not None:
            T_wo = prog.start @ plan.carrying[1]
            d.qpos[self._obj_adr : self._obj_adr + 3] = T_wo[:3, 3]
            d.qpos[self._obj_adr + 3 : self._obj_adr + 7] = quat_of(T_wo[:3, :3])
            d.qvel[m.jnt_dofadr[m.joint("object/free").id] :][:6] = 0.0
            # The fingers as the grasp left them: against the box's 0.06 m sides.
            for a in self._fingers:
                d.qpos[a] = 0.029
            self._grip(True)
        else:
            for a in self._fingers:
                d.qpos[a] = GRIPPER_OPEN
            self._grip(False)
        mujoco.mj_forward(m, d)

    def _set_hand(self, T: np.ndarray) -> None:
        """Put the hand (its TCP) at ``T`` (4, 4), at rest, its servo targets there."""
        d = self.world.data
        origin = T[:3, 3] - TCP_OFFSET * T[:3, 0]
        q = quat_of(T[:3, :3])
        d.qpos[self._slide_adr] = origin
        d.qpos[self._ball_adr : self._ball_adr + 4] = q
        d.qvel[self._slide_dof] = 0.0
        d.qvel[self._ball_dof : self._ball_dof + 3] = 0.0
        d.act[:] = 0.0  # the servos' integrals
        self._command(origin, np.zeros(3), q)

    def _command(self, origin: np.ndarray, velocity: np.ndarray, quat: np.ndarray) -> None:
        d = self.world.data
        d.ctrl[self._slide_ctrl] = origin @ self._axes
        d.ctrl[self._slide_ctrl + 1] = velocity @ self._axes
        d.ctrl[self._rot_ctrl : self._rot_ctrl + 4] = quat

    def _grip(self, closed: bool) -> None:
        self.grip_cmd = GRIPPER_SQUEEZE if closed else GRIPPER_OPEN
        self.world.data.ctrl[self._grip_ctrl] = self.grip_cmd

    def _servos(self, placement: Placement) -> None:
        """The hand's servos: the arm's principal directions, stiffnesses and force
        limits at the grasp (the end of the first line, else the pre-grasp), its torque
        limit."""
        m = self.world.model
        base, q = placement.start_of(1 if placement.lines else 0)
        whole_body = any(bp is not None for bp in placement.base_paths)
        # The arm's servos depend on the placement alone: every twin that runs it
        # (the particles of a search node) shares them.
        axes, kp, force, torque = self._shared(  # type: ignore[misc]
            placement, "servo", lambda: arm_servo(self.ctx, base, q, whole_body)
        )
        self._axes = axes
        for i, a in enumerate(self._slide_act):
            w = self._servo_wraps[i]
            m.wrap_prm[w : w + 3] = axes[:, i]  # the tendon's coefficients on the slides
            mass = float(self._slide_mass @ axes[:, i] ** 2)
            ki = kp[i] / INTEGRAL_TIME
            m.actuator_gainprm[a, 0] = ki
            m.actuator_biasprm[a, 1:3] = (-kp[i], -2.0 * np.sqrt(kp[i] * mass))
            m.actuator_forcerange[a] = [-force[i], force[i]]
            m.actuator_dynprm[a, 0] = force[i] / ki  # the integral alone: at most that
        m.actuator_forcerange[self._rot_act] = [0.0, torque]

    def finish(
        self,
        prog: Program,
        states: np.ndarray,
        judged: tuple[int, Status, str, str],
        tail: np.ndarray | None,
        t_wall: float,
        physics: float,
    ) -> Outcome:
        """Set the twin to where the run ended (after the recovery that follows a stop, and
        the coast) and report it."""
        w, m = self.world, self.world.model
        k, status, detail, phase = judged
        if tail is not None and len(tail):
            states = np.concatenate([states[: k + 1], tail])
            k = len(states) - 1
        mujoco.mj_setState(m, w.data, states[k], ROLLOUT_STATE)
        w.data.mocap_pos[self._arm_mocap] = ARM_PARK  # the arm is not simulated between runs
        w.data.mocap_quat[self._arm_mocap] = (1.0, 0.0, 0.0, 0.0)
        mujoco.mj_forward(m, w.data)
        if not stopped(judged):
            self.grip_cmd = float(prog.grip[-1])
            self.set_robot_base(prog.placement.start_of(len(prog.placement.lines))[0])
        else:  # recovered where it stopped, the base where the skill placed it
            self.grip_cmd = self._recovery_grip
            self.set_robot_base(prog.placement.base)
        w.data.ctrl[self._grip_ctrl] = self.grip_cmd
        # One row per record period (the steps after the last release are coarser).
        t = states[: k + 1, 0] - self.t0
        slot = np.floor(t / self.params.record_period + 1e-6)
        keep = np.flatnonzero(np.diff(slot, prepend=-1.0) > 0)
        rows, times = states[keep, 1 : 1 + m.nq], t[keep]
        return self._outcome(prog.plan, status, detail, phase, t_wall,
                             prog.placement.seconds, times, rows, physics)  # fmt: skip

    def _object_idle(self, idle: bool) -> None:
        """An object no skill touches rests where it is without its contacts (a
        quarter of the twin's contacts otherwise), gravity compensated; ``False``
        gives them back."""
        m = self.world.model
        m.geom_contype[self._obj_geom] = 0 if idle else self._obj_collide[0]
        m.geom_conaffinity[self._obj_geom] = 0 if idle else self._obj_collide[1]
        m.body_gravcomp[self._obj_body] = 1.0 if idle else 0.0
        if idle:  # at rest where it lies
            dof = m.jnt_dofadr[m.body_jntadr[self._obj_body]]
            self.world.data.qvel[dof : dof + 6] = 0.0

    # -- the report --------------------------------------------------------------------
    def _outcome(
        self, plan, status, detail, phase, t_wall, ik_seconds, times=None, qpos=None,
        physics=0.0,
    ) -> Outcome:  # fmt: skip
        """The run's :class:`Outcome` (:func:`~.executor.report`) against the facts
        measured before it (``_before``)."""
        w = self.world
        fingers = float(w.data.ten_length[self._tendon])
        if times is None:
            times, qpos = np.zeros(0), np.zeros((0, w.model.nq))
        return report(
            w, plan, status, detail, phase, self._before,
            holding=holds(getattr(self, "grip_cmd", GRIPPER_OPEN), fingers), times=times,
            qpos=qpos, sim_time=float(w.data.time) - self.t0, t_wall=t_wall,
            ik_seconds=ik_seconds, planning_seconds=0.0, physics_seconds=physics,
        )  # fmt: skip


@dataclasses.dataclass(frozen=True, eq=False)
class BoundTwin:
    """A planning twin with the world its plans are made against (``plan_world``; None:
    the twin's own cabinet): the twin as an executor :class:`~.executor.Body`, as
    :meth:`~.skills.Skill.simulate` runs it."""

    twin: PlanningTwin
    plan_world: ManipulationWorld | None = None

    @property
    def world(self) -> ManipulationWorld:
        return self.twin.world

    @property
    def ctx(self) -> ControlContext:
        return self.twin.ctx

    @property
    def params(self) -> SkillParams:
        return self.twin.params

    def believed(self) -> ManipulationWorld:
        return self.twin.world if self.plan_world is None else self.plan_world

    def run(self, plan: SkillPlan) -> Outcome:
        return self.twin.run(plan, self.plan_world)


def _collide(m: mujoco.MjModel, g: int) -> tuple[int, int]:
    """Geom ``g``'s collision bits (contype, conaffinity)."""
    return int(m.geom_contype[g]), int(m.geom_conaffinity[g])


def run_batch(
    twins: list[PlanningTwin], plan: SkillPlan, plan_world: ManipulationWorld | None = None
) -> list[Outcome]:
    """Simulate ``plan`` on every twin (e.g. the particles of a search node): the twins
    whose plans time the same share their controls (computed once); each is rolled out
    on its own (:meth:`~.twin_rollout.TwinRollout.head`, which stops at the monitors'
    stop). Returns one :class:`Outcome` per twin, as :meth:`PlanningTwin.run` would."""
    outs: list[Outcome | None] = [None] * len(twins)
    groups: dict[tuple, list[tuple[int, Program]]] = {}
    for i, tw in enumerate(twins):
        t_wall = time.perf_counter()
        w = tw.world
        tw.t0 = float(w.data.time)
        tw._before = facts_before(w)
        tw.mark_cabinet()
        tw._t_wall = t_wall
        try:
            prog = tw.program(plan, plan_world)
        except SkillStop as stop:
            outs[i] = tw._outcome(plan, stop.status, stop.detail, stop.phase or "plan",
                                  t_wall, 0.0)  # fmt: skip
            continue
        tw._start(prog)
        m = w.model
        key = (id(prog.placement), m.nq, m.nv, m.na, m.nu, m.ngeom, m.nbody)
        groups.setdefault(key, []).append((i, prog))
    for members in groups.values():
        ts = [twins[i] for i, _ in members]
        prog = members[0][1]
        ctrl = ts[0].controls(prog)  # the same plan and timing: computed once
        for (i, p), tw in zip(members, ts, strict=True):
            # One twin at a time, each on its own data: on one core a batched rollout
            # saves nothing, and a twin's run then stops where its monitors stop it.
            t = time.perf_counter()
            states, judged = tw.head(prog, ctrl)
            tail, final = tw.after(prog, ctrl, states, judged)
            physics = time.perf_counter() - t
            outs[i] = tw.finish(p, states, final, tail, tw._t_wall, physics)
    return [o for o in outs if o is not None]
