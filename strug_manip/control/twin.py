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
   grasp configuration, along its principal axes (:func:`arm_servo`: the compliance
   ``J K^-1 J^T``; a reaching arm gives way horizontally far more than
   vertically, which decides whether a wrong pull slides the fingers off a handle's
   end), and the
   force and torque the Fetch's joints can exert there (their effort limits through
   the hand's Jacobian, the grasp passing a moment as well as a force);
3. **physics**: the hand starts at the pre-grasp (the free motion of the full robot,
   collision free by construction, is not simulated), then follows the lines (their
   Cartesian poses, on the same schedule as the arm's joint path; the retreat after a
   release too: backing away can catch a handle) and grips, with the same settle and
   grip times, the same monitors (a lost grasp, the cabinet slid more than
   ``cabinet_motion_limit``, the hand held back more than the tracking tolerance)
   and the same facts measured at the end; after the last release the arm's links
   (mocap bodies) follow the arm's joint path too, so a forearm backing out of a
   drawer sweeps what the full robot's would (unless they would appear inside a part,
   :data:`ARM_ENTRY_DEPTH`); after a stop, the full robot's recovery, which ends where
   the cabinet slides; then hand and arm follow the full
   robot's stow (its straight way back to the pre-grasp, :func:`~strug_manip.control.
   execution.stow_retreat`, where that is free, else the same plan, :func:`~strug_manip.
   control.execution.plan_stow`) until they are clear of the cabinet, leave the scene, and the
   cabinet and the object settle for :data:`COAST_TIME`, and on while the cabinet still
   moves (:data:`REST_SPEED`), up to the rest of the stow's duration (a drawer of a
   dragged, tilted cabinet creeps on while the full robot stows); everything after the
   last release runs :data:`FREE_COARSENING` times coarser. Where a line moves
   the base, the hand's command moves with the full robot's base as it lags and
   overshoots its command (:class:`~.base_servo.BaseServo`); the monitors compare the
   hand with the plan, as the full robot's compare it with its command.

A twin's state (:meth:`PlanningTwin.snapshot`) includes where the full robot's base is
believed to stand (the ``robot_base`` mocap body), from which the next placement starts.
"""

from __future__ import annotations

import dataclasses
import functools
import time
import weakref
from collections import OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout
from scipy.optimize import linprog

import strug_manip.control.timing as timing
from planners.errors import ConfigError
from strug_manip.control.base_servo import BaseServo, base_inertia
from strug_manip.control.contacts import HAND_BODIES
from strug_manip.control.context import ControlContext
from strug_manip.control.execution import (
    STOW_SEED,
    ends_holding,
    plan_stow,
    recovery_poses,
    stow_retreat,
)
from strug_manip.control.grasps import held_grasp
from strug_manip.control.outcome import Outcome, SkillStop, Status
from strug_manip.control.params import DEFAULT_PARAMS, SkillParams
from strug_manip.control.placement import Placement, find_placement, work_frame
from strug_manip.control.plan import Grip, Line, SkillPlan
from strug_manip.objects.generator import CabinetSpec
from strug_manip.robot.fetch import (
    ACTUATORS,
    ARM_TORSO_JOINTS,
    BASE_JOINTS,
    CARRY,
    FINGERS_EMPTY,
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
#: After the last release (the fingers open, the hand backs away in free space: the
#: retreat, the withdraw, the stow, the coast) the twin steps this many times coarser
#: [-]: those motions seldom touch anything, and they are about 40 % of a run's steps.
#: Where they do touch (an arm link knocking an open door on the stow), the coarser
#: step can knock harder (1 of 200 tuning runs changed; README).
FREE_COARSENING = 2
#: An arm link that enters the scene (after the last release) deeper than this in
#: something [m] stays parked (:meth:`PlanningTwin._arm_starts_inside`): a link
#: resting against a door is simulated, one inside a part is not.
ARM_ENTRY_DEPTH = 0.005
#: Forward kinematics along a joint path (the stow, the lines after the last release)
#: runs every this many steps, the poses between interpolated [-]: the hand moves at
#: most a few centimetres in that time, along an arc whose chord is then well under a
#: millimetre off it (FK at every step was the largest share of a search's time).
FK_STRIDE = 8
#: Programs a twin keeps, the most recently used (:meth:`PlanningTwin.program`).
PROGRAMS = 32
#: After its last release the hand leaves the scene (its geoms stop colliding: the full
#: robot backs away and stows) and the cabinet and object settle for this long [s].
COAST_TIME = 0.25
#: A cabinet at rest: every joint of it (the parts, the base's free joint) slower than
#: this [m/s or rad/s] (a drawer of a tilted cabinet creeping out moves 0.02 m/s).
REST_SPEED = 0.005
#: The hand follows the full robot's stow until it is this far from the cabinet's box
#: for good [m] (the fingers reach 0.1 m past the TCP; the arm's links, which the twin
#: does not have, seldom sweep the cabinet where the hand does not).
STOW_CLEARANCE = 0.1
#: Room in front of the cabinet that its open parts take (a drawer pulled out, a door
#: swung open) [m].
FRONT_ROOM = 0.3
#: Where the TCP (the ``gripper`` site) is in the hand's frame [m] (fetch.xml).
TCP_OFFSET = 0.02
#: Bounds of the hand's force [N] and torque [N m] limits: at least what a wrist can
#: always push, at most the base's 300 N.
FORCE_BOUNDS = (10.0, 300.0)
TORQUE_BOUNDS = (2.0, 60.0)
#: The base pose and arm speeds the twin assumes when none is given.
_BASE_SPEED = np.array([0.3, 0.3, 0.9])


class PlanningTwin:
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
        self._programs: OrderedDict[tuple[Placement, object], Program] = OrderedDict()
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

    def _placement(self, plan: SkillPlan, plan_world: ManipulationWorld | None) -> Placement:
        base = self.robot_base
        reach = np.array(TUCK if plan.carrying is None else CARRY[held_grasp(plan.carrying[1])])
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
                (self.vmax, _BASE_SPEED), self._checker(plan, base, pw),
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
            q = np.empty(4)
            mujoco.mju_mat2Quat(q, np.ascontiguousarray(T_wo[:3, :3]).reshape(9))
            d.qpos[self._obj_adr + 3 : self._obj_adr + 7] = q
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
        q = np.empty(4)
        mujoco.mju_mat2Quat(q, np.ascontiguousarray(T[:3, :3]).reshape(9))
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
        axes, kp, force, torque = self._of(  # type: ignore[misc]
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

    # -- the program ------------------------------------------------------------------
    def program(self, plan: SkillPlan, plan_world: ManipulationWorld | None = None) -> Program:
        """The controls that run ``plan`` (made against ``plan_world``) on the twin, from
        its placement (raises :class:`SkillStop` ``ik_infeasible`` if there is none);
        the twin keeps its last :data:`PROGRAMS` programs (a search simulates the same
        skill on a particle many times; a program holds the arm's poses at every step,
        a few hundred kB, too much for the context's cache of thousands of entries)."""
        placement = self._placement(plan, plan_world)
        pw = plan_world if plan_world is not None or not self.checked else self._planning_world
        key = (placement, self._token(pw))  # (_placement made the twin's own world)
        prog = self._programs.pop(key, None)
        if prog is None:
            prog = self._program(placement, plan_world)
        self._programs[key] = prog
        while len(self._programs) > PROGRAMS:
            self._programs.popitem(last=False)
        return prog

    def _program(self, placement: Placement, plan_world: ManipulationWorld | None) -> Program:
        plan = placement.plan
        dt = self.world.model.opt.timestep
        p = self.params
        pos: list[np.ndarray] = []  # commanded TCP position and orientation, per step
        quat: list[np.ndarray] = []
        grips, names, held, holds, tols = [], [], [], [], []
        tol = p.tracking_tolerance
        here = (plan.pre[:3, 3], _quats(plan.pre[None, :3, :3])[0])
        grip = GRIPPER_SQUEEZE if plan.carrying is not None else GRIPPER_OPEN
        start = plan.pre

        arms: list[np.ndarray] = []  # the arm links' poses (n, L, 7), parked if unused
        parked = self._parked_arm()
        bases: list[np.ndarray] = []  # the base's command (n, 3)
        base = placement.start_of(1 if placement.lines else 0)[0]

        def add(ps: np.ndarray, qs: np.ndarray, name: str, hold: bool, holding: bool,
                arm: np.ndarray | None = None) -> None:  # fmt: skip
            bases.append(np.repeat(np.asarray(base, float)[None], len(ps), axis=0))
            pos.append(ps)
            quat.append(qs)
            grips.append(np.full(len(ps), grip))
            names.append(np.full(len(ps), name))
            held.append(np.full(len(ps), holding))
            holds.append(np.full(len(ps), hold))
            tols.append(np.full(len(ps), tol))
            arms.append(np.repeat(parked[None], len(ps), axis=0) if arm is None else arm)

        def hold(seconds: float, name: str, holding: bool) -> None:
            n = max(1, round(seconds / dt))
            add(np.repeat(here[0][None], n, axis=0), np.repeat(here[1][None], n, axis=0),
                name, True, holding)  # fmt: skip

        k = 0
        released = False
        free: int | None = None  # the first step after the last release
        stow = self._stow_commands(placement, plan_world)
        for ph in plan.phases:
            if isinstance(ph, Grip):
                grip = GRIPPER_SQUEEZE if ph.closed else GRIPPER_OPEN
                tol = p.tracking_tolerance
                hold(p.grip_time, ph.name, False)
                released = not ph.closed
                free = sum(len(x) for x in pos) if released else None
                continue
            if k == 0 and ph.name == "approach":  # free space: the hand starts at its end
                start = ph.poses[-1]
                here = (start[:3, 3], _quats(start[None, :3, :3])[0])
                k += 1
                continue
            ps, qs, joints = _line_commands(ph, placement, k, here, self.vmax, dt)
            tol = p.tracking_tolerance if ph.tolerance is None else ph.tolerance
            base = joints[-1, :3]
            # After the last release the arm moves freely, along its joint path: its
            # links may sweep the cabinet (e.g. back out of a drawer).
            arm = (
                self._of(placement, ("arm", k), lambda j=joints: self._arm_poses(j))
                if released
                else None
            )
            add(ps, qs, ph.name, False, ph.holding, arm)
            bases[-1] = joints[:, :3]
            here = (ps[-1], qs[-1])
            if not released:  # after the release the hand backs away in free space:
                hold(p.settle_time, ph.name, ph.holding)  # the arm's settling is moot
            k += 1
        rest = 0
        if stow is not None and len(stow.pos):  # the hand follows the stow out of the way
            tol = p.free_tolerance
            add(stow.pos, stow.quat, "stow", False, ends_holding(plan), stow.arm)
            here = (stow.pos[-1], stow.quat[-1])
            rest = stow.rest
        cat = np.concatenate
        # The cabinet settles while the full robot's stow goes on out of its way.
        coast = max(1, round(COAST_TIME / dt)) + rest if released else 0
        pos_, quat_, planned = cat(pos), cat(quat), cat(bases)
        actual = self._base_response(placement, planned)
        drive_pos, drive_quat = _with_base(pos_, quat_, planned, actual)
        free = len(pos_) if free is None or ends_holding(plan) else free
        return Program(plan, placement, pos_, quat_, cat(grips), cat(names), cat(held),
                       cat(holds), cat(tols), start, coast, cat(arms), drive_pos,
                       drive_quat, free)  # fmt: skip

    def _base_response(self, placement: Placement, planned: np.ndarray) -> np.ndarray:
        """Where the full robot's base is (n, 3) when commanded ``planned`` (n, 3) one
        per step from the placement's grasp (:class:`~.base_servo.BaseServo`, the
        robot's inertia at the grasp configuration), memoised per placement."""
        if self._base_servo is None:
            self._base_servo = BaseServo(self.ctx.ik.model, self.world.model.opt.timestep)
        servo = self._base_servo

        def respond() -> np.ndarray:
            base, q = placement.start_of(1 if placement.lines else 0)
            joints = {**dict(zip(BASE_JOINTS, base.tolist(), strict=True)),
                      **dict(zip(ARM_TORSO_JOINTS, q.tolist(), strict=True))}  # fmt: skip
            return servo.response(planned, base_inertia(self.ctx.ik.model, joints))

        return self._of(placement, ("base", len(planned)), respond)  # type: ignore[return-value]

    def _parked_arm(self) -> np.ndarray:
        """The arm links' poses (L, 7) out of the scene (:data:`ARM_PARK`)."""
        return np.tile(np.r_[ARM_PARK, 1.0, 0.0, 0.0, 0.0], (len(ARM_LINKS), 1))

    def _of(self, placement: Placement, key: Hashable, compute: Callable[[], object]) -> object:
        """What ``compute()`` gave for ``placement`` and ``key`` before, else its result,
        kept as long as the placement lives. Keyed by the placement object, not its id:
        a placement the context's cache lets go takes what was derived from it along,
        so a new one at the same address cannot find it."""
        table = self._derived.setdefault(placement, {})
        if key not in table:
            table[key] = compute()
        return table[key]

    def _arm_poses(self, joints: np.ndarray) -> np.ndarray:
        """The arm links' poses (n, L, 7) along ``joints`` (n, 11) (base + torso + arm)."""
        return self._fk_along(joints)[1]

    def _fk_along(self, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The TCP's poses (n, 7) and the arm links' (n, L, 7) (position, quaternion
        w x y z) along ``joints`` (n, 11) (base + torso + arm, one row per step):
        forward kinematics every :data:`FK_STRIDE` rows and at the last, interpolated
        between (linear positions, slerp)."""
        n = len(joints)
        idx = np.unique(np.r_[np.arange(0, n, FK_STRIDE), n - 1])
        names = (*BASE_JOINTS, *ARM_TORSO_JOINTS)
        coarse = np.empty((len(idx), 1 + len(ARM_LINKS), 7))
        for k, i in enumerate(idx):
            T, pos, quat = self.ctx.ik.frames(dict(zip(names, joints[i].tolist(), strict=True)),
                                              self._arm_fetch)  # fmt: skip
            coarse[k, 0, :3] = T[:3, 3]
            coarse[k, 0, 3:] = _quats(T[None, :3, :3])[0]
            coarse[k, 1:, :3], coarse[k, 1:, 3:] = pos, quat
        if len(idx) == 1:
            out = np.repeat(coarse, n, axis=0)
            return out[:, 0], out[:, 1:]
        seg = np.clip(np.searchsorted(idx, np.arange(n), side="right") - 1, 0, len(idx) - 2)
        s = (np.arange(n) - idx[seg]) / (idx[seg + 1] - idx[seg])
        a, b = coarse[seg], coarse[seg + 1]  # (n, K, 7)
        out = np.empty_like(a)
        out[..., :3] = a[..., :3] + s[:, None, None] * (b[..., :3] - a[..., :3])
        K = a.shape[1]
        out[..., 3:] = _slerp(a[..., 3:].reshape(-1, 4), b[..., 3:].reshape(-1, 4),
                              np.repeat(s, K)).reshape(n, K, 4)  # fmt: skip
        return out[:, 0], out[:, 1:]

    def _stow_commands(
        self, placement: Placement, plan_world: ManipulationWorld | None
    ) -> Stow | None:
        """The full robot's stow after ``placement`` as the twin follows it: its straight
        way back to the pre-grasp where that is free (:func:`~strug_manip.control.
        execution.stow_retreat`; the rest is collision-free in the model), else the same
        plan (:func:`~strug_manip.control.execution.plan_stow`) up to where the hand and
        the arm are clear of the cabinet for good (:data:`STOW_CLEARANCE`); None without
        a planning world (a kinematic-only twin) or when the stow finds no plan."""
        pw = self._planning(plan_world)
        if pw is None:
            return None
        return self._of(placement, ("stow", self._token(pw)),  # type: ignore[return-value]
                        lambda: self._stow_path(placement, pw))  # fmt: skip

    def _stow_path(self, placement: Placement, pw: ManipulationWorld) -> Stow | None:
        def plan() -> tuple[np.ndarray, np.ndarray | None] | None:
            # The full robot's stow starts back the way the hand came, where that line
            # is free, and is collision-free in the model from there: the twin follows
            # that line alone (the hand out of a drawer; the rest of the stow as long
            # as the straight line to the drive posture) and does not search the rest,
            # which took most of its time. A stow the full robot then finds no plan for
            # stops it before it moves, which the belief weighs as no evidence.
            back = stow_retreat(self.ctx, pw, placement)
            if back is not None:
                return back
            try:
                return plan_stow(self.ctx, pw, placement, self.params, STOW_SEED), None
            except SkillStop:
                return None

        # The plan depends on the planning world alone: every twin that runs this
        # placement there shares it (the particles of one hypothesis, mostly).
        found = self.ctx.derived(placement, ("stow", self._token(pw), self.params), plan)
        if found is None:
            return None
        stow, goal = found
        dt = self.world.model.opt.timestep
        base, q_end = placement.start_of(len(placement.lines))
        if not len(stow):
            return Stow(np.zeros((0, 3)), np.zeros((0, 4)), np.zeros((0, len(ARM_LINKS), 7)), 0)
        pts = timing.polyline(q_end, list(stow))
        T = timing.duration(pts, self.vmax, 0.3)
        qs = timing.samples(pts, T, dt, self.vmax)
        tcp, arm = self._fk_along(np.hstack([np.repeat(base[None], len(qs), axis=0), qs]))
        if goal is not None:  # the rest: as long as the straight line on to the goal
            rest = timing.duration(timing.polyline(stow[-1], [goal]), self.vmax, 0.3)
            return Stow(tcp[:, :3].copy(), tcp[:, 3:].copy(), arm, round(rest / dt))
        # The hand (its TCP) and the arm (its links' origins and the middles between
        # them) near the cabinet.
        mid = 0.5 * (arm[:, 1:, :3] + arm[:, :-1, :3])
        points = np.concatenate([tcp[:, None, :3], arm[:, :, :3], mid], axis=1)
        near = self._near_cabinet(points.reshape(-1, 3)).reshape(len(qs), -1).any(axis=1)
        n = int(np.flatnonzero(near)[-1]) + 2 if near.any() else 1
        n = min(n, len(tcp))
        return Stow(tcp[:n, :3].copy(), tcp[:n, 3:].copy(), arm[:n], len(qs) - n)

    def _near_cabinet(self, points: np.ndarray) -> np.ndarray:
        """Which ``points`` (n, 3) lie within :data:`STOW_CLEARANCE` of the cabinet's
        box (its open parts' room in front included), (n,)."""
        w = self.world
        spec = w.scene.cabinet_spec
        T = w.body_pose(w.scene.cabinet_prefix + w.scene.cabinet.root)
        p = (points - T[:3, 3]) @ T[:3, :3]  # cabinet frame
        lo = np.array([-spec.depth / 2, -spec.width / 2, 0.0]) - STOW_CLEARANCE
        hi = np.array([spec.depth / 2 + FRONT_ROOM, spec.width / 2, spec.height]) + STOW_CLEARANCE
        return np.all((p > lo) & (p < hi), axis=1)

    def controls(self, prog: Program) -> np.ndarray:
        """The twin's control vectors at every step of ``prog``, (nstep, nu + 7 nmocap):
        the actuators' controls, then the mocap bodies' positions and orientations
        (:data:`_CONTROL`)."""
        return self._controls(prog.drive_pos, prog.drive_quat, prog.grip, prog.holds, prog.arm)

    def recovery(self, prog: Program, state: np.ndarray) -> np.ndarray:
        """The controls (nstep, nu) of the full robot's recovery after a stop in
        ``state`` (a rollout state): the hand holds where it is while the fingers open
        (a skill that carries the object and holds it keeps it), then backs off along
        its approach (:func:`~strug_manip.control.execution.recovery_poses`) and
        settles."""
        m, p = self.world.model, self.params
        dt = m.opt.timestep
        qpos = state[1 : 1 + m.nq]
        quat = qpos[self._ball_adr : self._ball_adr + 4].copy()
        T = np.eye(4)
        mujoco.mju_quat2Mat(T[:3, :3].reshape(9), quat)
        T[:3, 3] = qpos[self._slide_adr] + TCP_OFFSET * T[:3, 0]
        fingers = 0.5 * (qpos[self._fingers[0]] + qpos[self._fingers[1]])
        carrier = prog.plan.carrying is not None or ends_holding(prog.plan)
        keep = carrier and fingers > FINGERS_EMPTY and self.grip_cmd_at_stop == GRIPPER_SQUEEZE
        grip = GRIPPER_SQUEEZE if keep else GRIPPER_OPEN
        self._recovery_grip = grip
        n_grip = 0 if keep else max(1, round(p.grip_time / dt))
        poses, length = recovery_poses(T, p)
        seconds = max(0.3, length / p.retreat_speed)
        pts = np.vstack([T[:3, 3], poses[:, :3, 3]])
        back = timing.samples(pts, seconds, dt)
        n_settle = max(1, round(p.settle_time / dt))
        pos = np.vstack([np.repeat(T[None, :3, 3], n_grip, axis=0), back,
                         np.repeat(back[-1:], n_settle, axis=0)])  # fmt: skip
        holds = np.ones(len(pos), dtype=bool)
        holds[n_grip : n_grip + len(back)] = False
        return self._controls(pos, np.repeat(quat[None], len(pos), axis=0),
                              np.full(len(pos), grip), holds)  # fmt: skip

    def _controls(
        self,
        pos: np.ndarray,
        quat: np.ndarray,
        grip: np.ndarray,
        holds: np.ndarray,
        arm: np.ndarray | None = None,
    ) -> np.ndarray:
        dt = self.world.model.opt.timestep
        origin = pos - TCP_OFFSET * _x_axes(quat)
        vel = np.zeros_like(origin)
        vel[1:] = np.diff(origin, axis=0) / dt
        vel[holds] = 0.0
        ctrl = np.repeat(self.world.data.ctrl[None].copy(), len(origin), axis=0)
        ctrl[:, self._slide_ctrl] = origin @ self._axes
        ctrl[:, self._slide_ctrl + 1] = vel @ self._axes
        ctrl[:, self._rot_ctrl : self._rot_ctrl + 4] = quat
        ctrl[:, self._grip_ctrl] = grip
        d, nm = self.world.data, self.world.model.nmocap
        mpos = np.repeat(d.mocap_pos[None].copy(), len(origin), axis=0)
        mquat = np.repeat(d.mocap_quat[None].copy(), len(origin), axis=0)
        arm = np.repeat(self._parked_arm()[None], len(origin), axis=0) if arm is None else arm
        mpos[:, self._arm_mocap] = arm[:, :, :3]
        mquat[:, self._arm_mocap] = arm[:, :, 3:]
        return np.hstack([ctrl, mpos.reshape(-1, 3 * nm), mquat.reshape(-1, 4 * nm)])

    def park_arm(self, ctrl: np.ndarray) -> np.ndarray:
        """Control rows (n, nu + 7 nmocap) with the arm links parked."""
        out = ctrl.copy()
        nu, nm = self.world.model.nu, self.world.model.nmocap
        mpos = out[:, nu : nu + 3 * nm].reshape(-1, nm, 3)
        mquat = out[:, nu + 3 * nm :].reshape(-1, nm, 4)
        mpos[:, self._arm_mocap] = ARM_PARK
        mquat[:, self._arm_mocap] = (1.0, 0.0, 0.0, 0.0)
        return out

    def judge(self, prog: Program, states: np.ndarray) -> tuple[int, Status, str, str]:
        """The first step whose monitors stop the run (a lost grasp where the fingers
        should hold, the cabinet slid more than ``cabinet_motion_limit`` since the
        skill started, the hand more than the tracking tolerance behind its command,
        checked every 10 ms as on the full robot) and why; the last step if none."""
        m = self.world.model
        qpos = states[:, 1 : 1 + m.nq]
        slid = self._slid(states, self.cabinet_xy0)
        fingers = 0.5 * (qpos[:, self._fingers[0]] + qpos[:, self._fingers[1]])
        tcp = qpos[:, self._slide_adr] + TCP_OFFSET * _x_axes(
            qpos[:, self._ball_adr : self._ball_adr + 4]
        )
        lag = np.linalg.norm(tcp - prog.pos, axis=1)
        every = self._check_every()
        check = np.zeros(len(lag), dtype=bool)
        check[every - 1 :: every] = True
        check[prog.phase_ends] = True
        check[-1] = True
        lost = check & prog.held & (fingers < FINGERS_EMPTY)
        moved = check & (slid > self.params.cabinet_motion_limit)
        blocked = check & (lag > prog.tol)
        blocked &= ~prog.holds | np.r_[prog.holds[1:] != prog.holds[:-1], False]
        stops = np.flatnonzero(lost | moved | blocked)
        if not len(stops):
            return len(lag) - 1, Status.OK, "", ""
        k = int(stops[0])
        if lost[k]:
            return (k, Status.GRASP_LOST, f"the fingers closed on nothing ({prog.names[k]})",
                    str(prog.names[k]))  # fmt: skip
        if moved[k]:
            return (k, Status.CABINET_MOVED,
                    f"the cabinet slid {slid[k]:.3f} m ({prog.names[k]})",
                    str(prog.names[k]))  # fmt: skip
        return (k, Status.COLLISION,
                f"the gripper is held back {lag[k]:.3f} m from its path ({prog.names[k]})",
                str(prog.names[k]))  # fmt: skip

    def after(
        self, prog: Program, ctrl: np.ndarray, states: np.ndarray, judged: tuple
    ) -> tuple[np.ndarray | None, tuple[int, Status, str, str]]:
        """What follows the rollout ``states`` of the program's steps before
        ``prog.free`` (``ctrl``: the whole program's controls), as the full robot goes
        on: after a stop the recovery; else the free steps (after the last release)
        :data:`FREE_COARSENING` times coarser, monitored, and the recovery if they stop;
        then the coast with the hand out of the scene. Returns the states that follow
        the head's judged step (None if none) and the run's verdict, its step index
        that of the head's last state when the head ran through."""
        m = self.world.model
        dt = m.opt.timestep
        k, status = judged[0], judged[1]
        start, parts, final = states[k], [], judged
        stop_prog, stop_k, last = prog, k, ctrl[k : k + 1]
        try:
            if status is Status.OK and prog.free < len(prog.pos):
                m.opt.timestep = dt * FREE_COARSENING
                sl = slice(prog.free, None, FREE_COARSENING)
                stop_prog, tail_ctrl = prog.steps(sl), ctrl[sl]
                if self._arm_starts_inside(start, tail_ctrl[0]):
                    tail_ctrl = self.park_arm(tail_ctrl)
                st, _ = rollout.rollout(m, self.world.data, start[None], tail_ctrl[None],
                                        control_spec=_CONTROL)  # fmt: skip
                j = self.judge(stop_prog, st[0])
                stop_k, start, last = j[0], st[0][j[0]], tail_ctrl[j[0] : j[0] + 1]
                parts.append(st[0][: j[0] + 1])
                final = (k, *j[1:])
            elif status is Status.OK and not prog.coast:
                return None, judged  # ends holding: nothing follows
            if final[1] is not Status.OK:
                self.grip_cmd_at_stop = float(stop_prog.grip[stop_k])
                extra = self.recovery(stop_prog, start)
                rec, _ = rollout.rollout(m, self.world.data, start[None], extra[None],
                                         control_spec=_CONTROL)  # fmt: skip
                rec = self._until_slid(rec[0], start)
                parts.append(rec)
                start, last = rec[-1], extra[len(rec) - 1 : len(rec)]
            budget = prog.coast if final[1] is Status.OK else 0
            budget = round(budget * dt / m.opt.timestep)
            parts.append(self.coast(start, self.park_arm(last), budget))
        finally:
            m.opt.timestep = dt
        return np.concatenate(parts), final

    def _arm_starts_inside(self, start: np.ndarray, row: np.ndarray) -> bool:
        """Whether the arm's links, set where control ``row`` (nu + 7 nmocap) puts them
        in rollout state ``start``, reach more than :data:`ARM_ENTRY_DEPTH` into
        anything. The links are simulated only after the last release and enter the
        scene there at once; a link inside this particle's cabinet (its parts are not
        where the model the path was planned in has them) would be pushed out with an
        impulse no arm exerts, and the twin's cabinet would fly off (README, "The
        planning twin"). The full robot's arm would have met that part on the way,
        where the twin has no arm; the twin then keeps the arm parked for the run, as
        before its release."""
        m, d = self.world.model, self.world.data
        saved = np.empty(mujoco.mj_stateSize(m, _SAVED))
        mujoco.mj_getState(m, d, saved, _SAVED)
        try:
            mujoco.mj_setState(m, d, start, _ROLLOUT_STATE)
            mujoco.mj_setState(m, d, row, _CONTROL)
            mujoco.mj_fwdPosition(m, d)
            con = d.contact[: d.ncon]
            arm = np.isin(m.geom_bodyid[con.geom1], self._arm_bodies) | np.isin(
                m.geom_bodyid[con.geom2], self._arm_bodies
            )
            return bool(np.any(arm & (con.dist < -ARM_ENTRY_DEPTH)))
        finally:
            mujoco.mj_setState(m, d, saved, _SAVED)

    def _until_slid(self, states: np.ndarray, start: np.ndarray) -> np.ndarray:
        """The recovery's rollout ``states`` (n, nstate) up to the first check (as in
        :meth:`judge`) at which the cabinet has slid more than ``cabinet_motion_limit``
        since ``start`` (all of them if it never does). The full robot's recovery is
        monitored so (:meth:`~strug_manip.control.execution.FullRobot._recover`): its
        arm stops where it is. Unmonitored, a hand caught on a handle as it backs off
        would drag the twin's cabinet on for the whole back-off, a drag no full robot
        makes."""
        a = 1 + self._cabinet_xy
        every = self._check_every()
        slid = self._slid(states, start[a : a + 2])
        over = np.flatnonzero(slid[every - 1 :: every] > self.params.cabinet_motion_limit)
        return states if not len(over) else states[: (int(over[0]) + 1) * every]

    def _slid(self, states: np.ndarray, xy0: np.ndarray) -> np.ndarray:
        """How far the cabinet stands from ``xy0`` (2,) in each rollout state, (n,) [m]."""
        a = 1 + self._cabinet_xy
        return np.linalg.norm(states[:, a : a + 2] - xy0, axis=1)

    def _check_every(self) -> int:
        """Steps between the monitors' checks: every 10 ms, as on the full robot."""
        return max(1, round(0.01 / self.world.model.opt.timestep))

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
        parts0, cab0 = self._before
        if tail is not None and len(tail):
            states = np.concatenate([states[: k + 1], tail])
            k = len(states) - 1
        mujoco.mj_setState(m, w.data, states[k], _ROLLOUT_STATE)
        w.data.mocap_pos[self._arm_mocap] = ARM_PARK  # the arm is not simulated between runs
        w.data.mocap_quat[self._arm_mocap] = (1.0, 0.0, 0.0, 0.0)
        mujoco.mj_forward(m, w.data)
        if status is Status.OK:
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
        return self._outcome(prog.plan, status, detail, phase, parts0, cab0, t_wall,
                             prog.placement.seconds, times, rows, physics)  # fmt: skip

    def coast(self, start: np.ndarray, last: np.ndarray, budget: int) -> np.ndarray:
        """The scene from rollout state ``start`` with the hand out of it and the arm
        parked, the controls held at ``last`` (1, nu + 7 nmocap): :data:`COAST_TIME`,
        then on in such spans while a cabinet joint still moves faster than
        :data:`REST_SPEED`, up to ``budget`` steps in all (the rest of the full robot's
        stow, during which its cabinet goes on settling); the states (n, nstate) from
        ``start`` on, just ``start`` when the cabinet is at rest already (the hand,
        clear of the cabinet by then, held nothing up)."""
        m = self.world.model
        span = max(1, round(COAST_TIME / m.opt.timestep))
        dofs = 1 + m.nq + self._cabinet_dofs  # the cabinet's velocities in a state
        out: list[np.ndarray] = [start[None]]
        done = 0
        self.ghost(True)
        try:
            while np.max(np.abs(start[dofs])) >= REST_SPEED and (done == 0 or done < budget):
                tl, _ = rollout.rollout(m, self.world.data, start[None],
                                        np.repeat(last, span, axis=0)[None],
                                        control_spec=_CONTROL)  # fmt: skip
                out.append(tl[0])
                done += span
                start = tl[0][-1]
        finally:
            self.ghost(False)
        return np.concatenate(out)

    def ghost(self, on: bool) -> None:
        """Take the hand out of (``on``) or back into the scene's collisions."""
        m = self.world.model
        for g in self._hand_geoms:
            m.geom_contype[g] = 0 if on else self._hand_collide[g][0]
            m.geom_conaffinity[g] = 0 if on else self._hand_collide[g][1]

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
        self, plan, status, detail, phase, parts0, cab0, t_wall, ik_seconds,
        times=None, qpos=None, physics=0.0,
    ) -> Outcome:  # fmt: skip
        w = self.world
        parts = w.part_positions()
        fingers = float(w.data.ten_length[self._tendon])
        if times is None:
            times, qpos = np.zeros(0), np.zeros((0, w.model.nq))
        return Outcome(
            skill=plan.skill,
            status=status,
            detail=detail,
            phase=phase,
            part_motion={j: parts[j] - parts0[j] for j in parts},
            part_units=w.part_units(),
            part_positions=parts,
            cabinet_displacement=w.cabinet_displacement(),
            cabinet_motion=float(np.linalg.norm(w.cabinet_displacement_vector() - cab0)),
            object_pose=w.object_pose(),
            holding=getattr(self, "grip_cmd", GRIPPER_OPEN) == GRIPPER_SQUEEZE
            and fingers > FINGERS_EMPTY,
            times=times,
            qpos=qpos,
            sim_time=float(w.data.time) - self.t0,
            wall_seconds=time.perf_counter() - t_wall,
            ik_seconds=ik_seconds,
            planning_seconds=0.0,
            physics_seconds=physics,
        )


def _with_base(
    pos: np.ndarray, quat: np.ndarray, planned: np.ndarray, actual: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """TCP poses ``pos`` (n, 3), ``quat`` (n, 4) planned with the base at ``planned``
    (n, 3: x, y, yaw) carried to the base at ``actual`` (n, 3): the same pose in the
    base's frame."""
    dyaw = actual[:, 2] - planned[:, 2]
    c, s = np.cos(dyaw), np.sin(dyaw)
    rel = pos[:, :2] - planned[:, :2]
    out = pos.copy()
    out[:, 0] = c * rel[:, 0] - s * rel[:, 1] + actual[:, 0]
    out[:, 1] = s * rel[:, 0] + c * rel[:, 1] + actual[:, 1]
    # (cos h, 0, 0, sin h) * (w, x, y, z): a turn by 2h about the world's z first.
    ch, sh = np.cos(dyaw / 2)[:, None], np.sin(dyaw / 2)[:, None]
    w, x, y, z = quat.T[:, :, None]
    q = np.hstack([ch * w - sh * z, ch * x - sh * y, ch * y + sh * x, ch * z + sh * w])
    return out, q


def _quats(R: np.ndarray) -> np.ndarray:
    """Unit quaternions (w, x, y, z), (n, 4), of rotation matrices (n, 3, 3)."""
    out = np.empty((len(R), 4))
    for i in range(len(R)):
        mujoco.mju_mat2Quat(out[i], np.ascontiguousarray(R[i]).reshape(9))
    return out


def _slerp(qa: np.ndarray, qb: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Unit quaternions the fractions ``s`` (n,) of the way from ``qa`` to ``qb`` (each
    (n, 4)) along the shortest arc, (n, 4)."""
    qb = np.where((np.sum(qa * qb, axis=1) < 0)[:, None], -qb, qb)
    theta = np.arccos(np.clip(np.sum(qa * qb, axis=1), -1.0, 1.0))
    small = theta < 1e-6
    sin = np.where(small, 1.0, np.sin(theta))
    wa = np.where(small, 1.0 - s, np.sin((1.0 - s) * theta) / sin)
    wb = np.where(small, s, np.sin(s * theta) / sin)
    q = wa[:, None] * qa + wb[:, None] * qb
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _x_axes(q: np.ndarray) -> np.ndarray:
    """The x axes (n, 3) of the rotations of unit quaternions ``q`` (n, 4)."""
    w, x, y, z = q.T
    return np.column_stack([1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)])


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


def _collide(m: mujoco.MjModel, g: int) -> tuple[int, int]:
    """Geom ``g``'s collision bits (contype, conaffinity)."""
    return int(m.geom_contype[g]), int(m.geom_conaffinity[g])


#: What a rollout's states hold (MuJoCo's full physics: time, qpos, qvel, act, ...).
_ROLLOUT_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
#: What a check on the side saves and puts back: the state and the controls.
_SAVED = int(mujoco.mjtState.mjSTATE_INTEGRATION)
#: What a rollout's controls set every step: the actuators' controls and the mocap
#: bodies' poses (the believed robot base, the arm links).
_CONTROL = int(
    mujoco.mjtState.mjSTATE_CTRL
    | mujoco.mjtState.mjSTATE_MOCAP_POS
    | mujoco.mjtState.mjSTATE_MOCAP_QUAT
)


@dataclass(frozen=True, eq=False)
class Program:
    """A skill plan as the twin's step-by-step commands.

    Attributes:
        plan: the plan (its fingers maybe swapped, as the placement found it).
        placement: the full robot's placement it is timed by.
        pos: commanded TCP position at every step, (nstep, 3) [m].
        quat: commanded hand orientation at every step (w, x, y, z), (nstep, 4).
        grip: finger command at every step, (nstep,) [m].
        names: the phase of every step, (nstep,).
        held: the fingers should hold something at that step (monitored), (nstep,).
        holds: the step belongs to a hold (settle or grip time), (nstep,).
        tol: the tracking tolerance at that step [m], (nstep,).
        start: where the hand starts, (4, 4): the pre-grasp, or the grasp (the end of
            an approach, which is not simulated).
        coast: steps simulated after the last release with the hand out of the scene
            (the full robot backs away and stows; the cabinet settles), or 0.
        arm: the arm links' poses at every step (position, quaternion), (nstep, L, 7):
            along the full robot's joint path after the last release, else parked.
        drive_pos, drive_quat: what the hand's servos are commanded, (nstep, 3) and
            (nstep, 4): ``pos`` and ``quat`` moved with the full robot's base where it
            lags behind or overshoots its command (:class:`~.base_servo.BaseServo`);
            the monitors compare the hand with ``pos``, as the full robot's compare
            it with its command.
        free: the first step after the last release (the hand moves freely from
            there; :data:`FREE_COARSENING`), ``nstep`` when the skill ends holding.
    """

    plan: SkillPlan
    placement: Placement
    pos: np.ndarray
    quat: np.ndarray
    grip: np.ndarray
    names: np.ndarray
    held: np.ndarray
    holds: np.ndarray
    tol: np.ndarray
    start: np.ndarray
    coast: int
    arm: np.ndarray
    drive_pos: np.ndarray
    drive_quat: np.ndarray
    free: int

    @functools.cached_property
    def phase_ends(self) -> np.ndarray:
        """Steps around which the phase changes, where the monitors check too, (k,)."""
        return np.flatnonzero(np.diff(self.names != np.roll(self.names, -1)))

    def steps(self, sl: slice) -> Program:
        """The program's steps ``sl`` (e.g. ``slice(free, None, 2)``), as a program."""
        per_step = ("pos", "quat", "grip", "names", "held", "holds", "tol", "arm",
                    "drive_pos", "drive_quat")  # fmt: skip
        cut = {f: getattr(self, f)[sl] for f in per_step}
        return dataclasses.replace(self, **cut, free=len(cut["pos"]))


@dataclass(frozen=True, eq=False)
class Stow:
    """The full robot's stow as the twin follows it, every step until the hand and the
    arm are clear of the cabinet: TCP positions ``pos`` (n, 3) [m], orientations
    ``quat`` (n, 4), the arm links' poses ``arm`` (n, L, 7); ``rest``: steps of the
    stow after that (the cabinet coasts through them)."""

    pos: np.ndarray
    quat: np.ndarray
    arm: np.ndarray
    rest: int


def _line_commands(
    line: Line,
    placement: Placement,
    k: int,
    here: tuple[np.ndarray, np.ndarray],
    vmax: np.ndarray,
    dt: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The commanded TCP positions (n, 3) and orientations (n, 4) of line ``k`` every
    ``dt``, from ``here`` (position, quaternion), on the schedule of the arm's joint
    path (the full robot's timing), and the joints there (n, 3 + 8: base x, y, yaw,
    then torso and arm)."""
    base0, q0 = placement.start_of(k)
    pts = timing.polyline(q0, placement.lines[k])
    limits = vmax
    if placement.base_paths[k] is not None:
        pts = np.hstack([pts, timing.polyline(base0, placement.base_paths[k])])
        limits = np.concatenate([vmax, _BASE_SPEED])
    T = timing.duration(pts, limits, max(0.3, line.length / line.speed))
    seg, frac = timing.schedule(pts, T, dt, limits)
    ps = np.vstack([here[0][None], line.poses[:, :3, 3]])
    qs = np.vstack([here[1][None], _quats(line.poses[:, :3, :3])])
    pos = ps[seg] + frac[:, None] * (ps[seg + 1] - ps[seg])
    joints = pts[seg] + frac[:, None] * (pts[seg + 1] - pts[seg])
    if placement.base_paths[k] is None:
        joints = np.hstack([joints, np.repeat(np.asarray(base0, float)[None], len(seg), axis=0)])
    joints = np.hstack([joints[:, -3:], joints[:, :-3]])  # base first
    return pos, _slerp(qs[seg], qs[seg + 1], frac), joints


def run_batch(
    twins: list[PlanningTwin], plan: SkillPlan, plan_world: ManipulationWorld | None = None
) -> list[Outcome]:
    """Simulate ``plan`` on every twin (e.g. the particles of a search node), batched:
    the twins whose plans time the same and whose models have the same size run in one
    :func:`mujoco.rollout.rollout` call (controls computed once). Returns one
    :class:`Outcome` per twin, as :meth:`PlanningTwin.run` would."""
    outs: list[Outcome | None] = [None] * len(twins)
    groups: dict[tuple, list[tuple[int, Program]]] = {}
    for i, tw in enumerate(twins):
        t_wall = time.perf_counter()
        w = tw.world
        tw.t0 = float(w.data.time)
        tw._before = (w.part_positions(), w.cabinet_displacement_vector())
        tw.cabinet_xy0 = w.data.qpos[tw._cabinet_xy : tw._cabinet_xy + 2].copy()
        tw._t_wall = t_wall
        try:
            prog = tw.program(plan, plan_world)
        except SkillStop as stop:
            outs[i] = tw._outcome(plan, stop.status, stop.detail, stop.phase or "plan",
                                  *tw._before, t_wall, 0.0)  # fmt: skip
            continue
        tw._start(prog)
        m = w.model
        key = (id(prog.placement), m.nq, m.nv, m.na, m.nu, m.ngeom, m.nbody)
        groups.setdefault(key, []).append((i, prog))
    for members in groups.values():
        ts = [twins[i] for i, _ in members]
        prog = members[0][1]
        states0 = []
        for tw in ts:
            st = np.empty(mujoco.mj_stateSize(tw.world.model, _ROLLOUT_STATE))
            mujoco.mj_getState(tw.world.model, tw.world.data, st, _ROLLOUT_STATE)
            states0.append(st)
        ctrl = ts[0].controls(prog)
        head = prog.steps(slice(0, prog.free))
        t = time.perf_counter()
        states, _ = rollout.rollout(
            [tw.world.model for tw in ts], ts[0].world.data, np.array(states0),
            ctrl[None, : prog.free], control_spec=_CONTROL,
        )  # fmt: skip
        physics = (time.perf_counter() - t) / len(ts)
        judged = [tw.judge(head, st) for tw, st in zip(ts, states, strict=True)]
        t = time.perf_counter()
        after = [tw.after(prog, ctrl, st, j) for tw, st, j in zip(ts, states, judged, strict=True)]
        physics += (time.perf_counter() - t) / len(ts)
        for n, ((i, p), tw, st) in enumerate(zip(members, ts, states, strict=True)):
            tail, final = after[n]
            outs[i] = tw.finish(p, st, final, tail, tw._t_wall, physics)
    return [o for o in outs if o is not None]
