"""The full robot: a :class:`~strug_manip.control.plan.SkillPlan` executed by the Fetch.

One of the executor's two bodies (:class:`~.executor.Body`; the other is the planning
twin, :mod:`.twin_body`): the stop rules, the stow and the outcome are the core's
(:mod:`.executor`), the motions the Fetch's.

:meth:`FullRobot.run` plans everything before anything moves, then executes it with
MuJoCo physics stepping all along (:class:`~strug_manip.control.driver.JointDriver`):

1. **plan**: the base placement (:func:`~strug_manip.control.placement.find_placement`:
   IK of the pre-grasp and of every Cartesian line, collision checked in the planning
   world, with the believed part moving along), then the free motions to the first
   placement for which they plan (stow, route, reach);
2. **drive** (if the base must move): the arm goes to its tuck first (no driving with
   the arm out; carrying the object, to its carry posture), the base follows a
   collision-checked route (straight, else around the obstacles on a floor grid;
   turning in place at its ends where turning on the way would touch), the torso
   rising on the way;
3. **reach**: an OMPL motion to the pre-grasp (the straight joint-space line where it
   is free; carrying an object, it moves with the gripper in the checks);
4. **phases**: each line followed (its IK path, the base along where it is a whole-body
   line), each grip closed or opened; while a line runs, a lost grasp (fingers closed
   on nothing) or the gripper more than ``tracking_tolerance`` behind its commanded
   pose (the arm is blocked) stops the run; the robot then *recovers*: lets go (unless
   it carries the object), backs off and stows, so that the next skill can start; an
   opening whose part stops following the hand past half its path has met the part's
   end: it recovers the same way and reports ``ok`` (:func:`~.executor.at_part_end`);
5. **stow**: back to the tuck (holding the object: to its carry posture), so the next
   skill may drive and the head camera sees the cabinet past the arm; planned with the
   rest before anything moves (:func:`~.executor.plan_stow`: from where the last line ends, the
   believed parts where the lines took them, back the way the hand came first).

Collision checks and plans use ``plan_world`` (the believed cabinet; default the world
itself), into which the robot's and the object's state is copied by joint name before
each check; execution and the facts of the outcome come from ``world``. The same world
state, plan and seed give the same outcome, bit for bit.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from planners.errors import ConfigError
from strug_manip.control.cabinet_guard import CabinetGuard
from strug_manip.control.compliance import HandCompliance
from strug_manip.control.context import ControlContext
from strug_manip.control.driver import MONITOR_PERIOD, JointDriver
from strug_manip.control.executor import (
    OPENING_LINES,
    STOW_SEED,
    clear_first,
    drive_posture,
    facts_before,
    grasp_lost,
    held_back,
    holds,
    keeping_clear,
    near_posture,
    plan_stow,
    report,
    settle,
    stop_detail,
)
from strug_manip.control.motion import (
    ArmMotionPlanner,
    ArmValidity,
    MotionPlan,
    escape_start,
)
from strug_manip.control.navigation import plan_route
from strug_manip.control.outcome import REACH, Outcome, SkillStop, Status
from strug_manip.control.params import DEFAULT_PARAMS, SkillParams
from strug_manip.control.placement import Placement, find_placement
from strug_manip.control.plan import Grip, Line, SkillPlan
from strug_manip.control.recovery import Recovery
from strug_manip.robot.fetch import (
    ARM_TORSO_JOINTS,
    BASE_JOINTS,
    CARRY,
    GRIPPER_SITE,
    GRIPPER_SQUEEZE,
    TUCK,
)
from strug_manip.world.sim import ManipulationWorld

#: A callback told the name of each key instant of a run (e.g. to render a frame).
Observer = Callable[[str], None]


#: Seed offset of the wide round's plans (:meth:`FullRobot._plan_arm`): they neither
#: take nor shift the seeds of the plans after them, so that where the wide round finds
#: nothing, the motions are those planned before it existed, bit for bit. Counted, its
#: two failed plans shifted the seed of the plain plan that followed, and the oracle's
#: OpenDrawer 10207 drew a reach that slid the cabinet where it had placed at once.
WIDE_SEED = 104_729


@dataclass(frozen=True, eq=False)
class FreeMotion:
    """The free motions before a skill's first line, planned before anything moves.

    Attributes:
        stow: torso + arm waypoints to the drive posture (N, 8), or None.
        route: base poses to drive through, or None (the base stays).
        torso: the torso height to rise to while driving [m], or None.
        reach: torso + arm waypoints to the pre-grasp (N, 8).
        after: torso + arm waypoints from the end of the last line to the drive
            posture (:func:`plan_stow`), (N, 8).
    """

    stow: np.ndarray | None
    route: list[np.ndarray] | None
    torso: float | None
    reach: np.ndarray
    after: np.ndarray


def wrap_to(yaw: float, near: float) -> float:
    """``yaw`` [rad] plus the multiple of 2 pi that brings it closest to ``near``."""
    return near + (yaw - near + np.pi) % (2 * np.pi) - np.pi


class FullRobot(Recovery):
    """Runs skill plans on the Fetch of ``world``.

    Args:
        world: where physics runs and the outcome is measured.
        ctx: shared solvers and caches (default: a new :class:`ControlContext`).
        params: skill constants (default :data:`DEFAULT_PARAMS`).
        plan_world: the world plans and collision checks use (the believed cabinet);
            default ``world``.
        seed: seed of the OMPL plans (an int >= 0).
        observer: told the name of each key instant.
    """

    def __init__(
        self,
        world: ManipulationWorld,
        ctx: ControlContext | None = None,
        params: SkillParams = DEFAULT_PARAMS,
        plan_world: ManipulationWorld | None = None,
        seed: int = 0,
        observer: Observer | None = None,
    ) -> None:
        if not isinstance(world, ManipulationWorld):
            raise ConfigError(f"world must be a ManipulationWorld, got {world!r}")
        if plan_world is not None and not isinstance(plan_world, ManipulationWorld):
            raise ConfigError(f"plan_world must be a ManipulationWorld or None, got {plan_world!r}")
        if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
            raise ConfigError(f"seed must be a non-negative int, got {seed!r}")
        self.world, self.params, self.seed, self.observer = world, params, int(seed), observer
        self.plan_world = world if plan_world is None else plan_world
        self.ctx = ctx or ControlContext()

    # -- the run -------------------------------------------------------------------------
    def run(self, plan: SkillPlan) -> Outcome:
        """Execute ``plan`` (see the module docstring); never raises for a failure of the
        skill: the :class:`Outcome` says how it ended."""
        t_wall = time.perf_counter()
        self.drv = JointDriver(self.world, self.params.time_budget, self.params.record_period)
        self.ik_seconds = self.plan_seconds = 0.0
        self.n_plans = 0
        before = facts_before(self.world)
        self._guard = CabinetGuard(self.world, self.params)
        self._path = self._guard.opening(plan)  # None: not an opening
        hand = None if self._path is None else HandCompliance(self.world, self._path, self.params)
        self._comply = None if hand is None else hand.update
        phase = "plan"
        try:
            self._plan = plan
            placement, free = self._plan_free(plan)
            plan = placement.plan  # the fingers may be swapped
            phase = REACH
            self._key("start")
            self._free_motion(free)
            self._key("pre-grasp")
            k = 0  # index of the next line
            for p in plan.phases:
                phase = p.name
                if isinstance(p, Grip):
                    self.drv.grip(p.closed, self.params.grip_time, GRIPPER_SQUEEZE)
                else:
                    self._line(p, placement, k)
                    k += 1
                self._key(p.name)
            phase = "stow"
            if len(free.after):
                self.drv.follow(list(free.after), 0.3, monitor=self._line_monitor(None))
                self.drv.hold(self.params.settle_time)
            self._key("end")
        except SkillStop as stop:
            detail = stop.detail
            if phase == REACH:  # on the way: what it carries or its arm met something
                detail += self._withdraw()
            elif phase != "plan":  # the hand is at the part: let go, back off
                detail += self._recover()
            return self._outcome(plan, stop.status, detail, stop.phase or phase, before, t_wall)
        return self._outcome(plan, Status.OK, "", "", before, t_wall)

    # -- planning ------------------------------------------------------------------------
    def believed(self) -> ManipulationWorld:
        """The planning world with the robot's and the object's state of ``world``: what
        skills plan against (:class:`~.executor.Body`)."""
        if self.plan_world is not self.world:
            self.plan_world.copy_robot_state(self.world)
        return self.plan_world

    def _checker(self, carrying: tuple[str, np.ndarray] | None):
        pw = self.believed()
        checker = self.ctx.checker(pw.model).load(pw.data)
        if carrying is None:
            checker.attach(None)
        else:
            checker.attach(*carrying)
        return checker.allow()

    def _placements(self, plan: SkillPlan) -> list[Placement]:
        """Where the base may stand for ``plan``, best first."""
        t = time.perf_counter()
        try:
            speeds = (self.drv.vmax, self.drv.base_speed)
            postures = (np.array(TUCK), self._reach_start(plan))
            found = find_placement(
                plan, self.ctx.ik, self.ctx.wb_ik, self.drv.base, postures, speeds,
                self._checker(plan.carrying),
            )  # fmt: skip
            return [found, *found.alternatives]
        finally:
            self.ik_seconds += time.perf_counter() - t

    def _reach_start(self, plan: SkillPlan) -> np.ndarray:
        """Torso + arm where the reach to a pre-grasp will start: where the arm is if it
        may drive like that (tucked or carrying), else the posture it will drive in."""
        if self._tucked():
            return self.drv.q
        return drive_posture(plan.carrying)

    def _plan_arm(
        self,
        q_from: np.ndarray,
        q_to: np.ndarray,
        carrying: tuple[str, np.ndarray] | None,
        base: np.ndarray | None = None,
        phase: str = "",
    ) -> np.ndarray:
        """OMPL waypoints (N, 8) from ``q_from`` to ``q_to`` (the start excluded) with
        the base at ``base`` (default: where it is); a start that touches something is
        first nudged free (:func:`~.motion.escape_start`), and the nudged start leads."""
        t = time.perf_counter()
        checker = self._checker(carrying)
        validity = ArmValidity(checker, self.drv.base if base is None else base)
        # A start that touches something (a stop, or a guarded recovery, left the arm
        # against the cabinet) is nudged free first.
        planners = self.ctx.planners(self.plan_world.model)
        lead = None
        if not validity.free(q_from):
            rng = np.random.default_rng(self.seed + self.n_plans)
            bounds = (planners[0].lower, planners[0].upper)
            lead = escape_start(q_from, validity, rng, bounds)
        q_from = q_from if lead is None else lead
        held = self.params.held_clearance if carrying is not None else 0.0

        def run(i: int, planner: ArmMotionPlanner, checks: int, in_wide: bool) -> MotionPlan:
            offset = WIDE_SEED if in_wide else 0  # the wide round's own seeds: WIDE_SEED
            return self._arm_plan(planner, q_from, q_to, validity, checks, offset)

        def clear(room: bool) -> contextlib.AbstractContextManager[None]:
            ends = (q_from, q_to)
            return keeping_clear(checker, validity.base, ends, self.params, held, room)

        def wide() -> contextlib.AbstractContextManager[None]:
            w = self.params.wide_clearance
            ends = (q_from, q_to)
            return keeping_clear(
                checker, validity.base, ends, self.params, w if carrying else 0.0, True, w
            )

        plan = clear_first(planners, run, clear, self.params, wide)
        self.plan_seconds += time.perf_counter() - t
        if not plan.success:
            raise SkillStop(Status.NO_MOTION_PLAN, f"{plan.reason}: {plan.detail}", phase)
        return plan.waypoints[1:] if lead is None else plan.waypoints

    def _arm_plan(
        self,
        planner: ArmMotionPlanner,
        q_from: np.ndarray,
        q_to: np.ndarray,
        validity: ArmValidity,
        checks: int,
        offset: int = 0,
    ) -> MotionPlan:
        """``planner``'s plan from ``q_from`` to ``q_to`` (torso + arm, (8,)) within
        ``checks`` validity checks, seeded by the plans made so far; with an
        ``offset`` (the wide round's), seeded apart from them and not counted."""
        plan = planner.plan(
            dict(zip(ARM_TORSO_JOINTS, q_from.tolist(), strict=True)),
            dict(zip(ARM_TORSO_JOINTS, q_to.tolist(), strict=True)),
            validity,
            checks=checks,
            timeout=self.params.plan_wall_cap,
            seed=self.seed + self.n_plans + offset,
        )
        self.n_plans += offset == 0
        return plan

    def _route(self, target: np.ndarray, arm: np.ndarray, carrying) -> list[np.ndarray]:
        """Base poses to drive through to ``target`` with the arm at ``arm`` (its drive
        posture) and what it carries (:func:`~strug_manip.control.navigation.plan_route`),
        keeping ``wide_clearance`` from the scene where a route can, else touching
        nothing."""
        t = time.perf_counter()
        checker, start = self._checker(carrying), self.drv.base
        try:
            # First with the arm motions' wide berth (what the ends leave): a route
            # planned touching-free in the believed cabinet runs past a door the robot
            # swung open, which perception puts centimetres off. (On OpenDoor 10166 the
            # torso still met the real door: the base cut the route's corner by 4.6 cm.)
            ends = (np.r_[start, arm], np.r_[target, arm])
            w = self.params.wide_clearance
            held = w if carrying is not None else 0.0
            with keeping_clear(checker, None, ends, self.params, held, True, w):
                route = plan_route(checker, start, target, arm)
            if route is None:
                route = plan_route(checker, start, target, arm)
        finally:
            self.plan_seconds += time.perf_counter() - t
        if route is None:
            raise SkillStop(Status.NO_MOTION_PLAN, "no collision-free route for the base", REACH)
        return route

    # -- motions -------------------------------------------------------------------------
    def _near(self, posture: Sequence[float]) -> bool:
        """The arm (torso aside) is within :data:`~.executor.TUCKED_TOLERANCE` of ``posture``."""
        return near_posture(self.drv.q, np.array(posture))

    def _tucked(self) -> bool:
        """The arm is in (or near) its tuck or a carry posture: it may drive."""
        return any(self._near(p) for p in (TUCK, *CARRY.values()))

    def _fingers(self) -> float:
        """How far apart the fingers stand [m] (the gripper tendon's length)."""
        return float(self.world.data.ten_length[self.world.model.tendon("gripper").id])

    def _plan_free(self, plan: SkillPlan) -> tuple[Placement, FreeMotion]:
        """The first placement (best first) whose free motions plan: the stow (if the
        base must move and the arm is not in its drive posture), the base's route, the
        reach to the pre-grasp. Everything is planned before anything moves."""
        first: SkillStop | None = None
        for placement in self._placements(plan):
            try:
                return placement, self._free_plan(placement)
            except SkillStop as stop:
                first = first or stop
        assert first is not None
        raise first  # the best placement's reason

    def _free_plan(self, placement: Placement) -> FreeMotion:
        carrying = placement.plan.carrying
        q_pre = placement.q_pre
        far = np.max(np.abs(placement.base[:2] - self.drv.base[:2])) > self.params.drive_tolerance
        turn = abs(wrap_to(placement.base[2], self.drv.base[2]) - self.drv.base[2]) > 0.02
        after = self._plan_after(placement)
        if not (far or turn):
            reach = self._plan_arm(self.drv.q, q_pre, carrying, phase=REACH)
            return FreeMotion(None, None, None, reach, after)
        drive_q = drive_posture(carrying)
        stow = None
        if not self._near(drive_q):
            stow = self._plan_arm(self.drv.q, drive_q, carrying, phase="stow before driving")
        start = drive_q if stow is not None else self.drv.q
        route = self._route(placement.base, start, carrying)
        torso = None
        if carrying is None:  # the torso moves on the way (it is the slowest joint)
            torso = float(q_pre[0])
            start = start.copy()
            start[0] = torso
        reach = self._plan_arm(start, q_pre, carrying, base=placement.base, phase=REACH)
        return FreeMotion(stow, route, torso, reach, after)

    def _plan_after(self, placement: Placement) -> np.ndarray:
        """The stow after the skill (:func:`plan_stow`), planned before anything moves."""
        t = time.perf_counter()
        try:
            pw = self.believed()
            return plan_stow(self.ctx, pw, placement, self.params, self.seed + STOW_SEED)
        finally:
            self.plan_seconds += time.perf_counter() - t

    def _free_motion(self, free: FreeMotion) -> None:
        """Execute a planned free motion (stow, drive, reach)."""
        if free.stow is not None:
            self.drv.follow(list(free.stow), 0.3, monitor=self._line_monitor(None))
            self.drv.hold(self.params.settle_time)
        if free.route is not None:
            # Watched: a route planned in the believed cabinet, which the real one stands
            # a few centimetres from, drove the carried object into it unwatched and
            # slid it 0.27 m before the reach's first check (OpenDoor 10188, POMCPOW).
            self.drv.drive(free.route, torso=free.torso, monitor=self._watch("drive"))
        self.drv.follow(list(free.reach), 0.3, monitor=self._line_monitor(None))
        self.drv.hold(self.params.settle_time)

    def _touched(self) -> list[str]:
        """The bodies the current skill's lines may touch (its part, the object)."""
        return sorted({b for line in self._plan.lines for b in line.touch})

    def _carried(self) -> tuple[str, np.ndarray]:
        """The held object and ``T_gripper_object`` now."""
        T_wg = self.world.site_pose(GRIPPER_SITE)
        return "object", np.linalg.inv(T_wg) @ self.world.object_pose()

    def _line(self, line: Line, placement: Placement, k: int) -> None:
        """Follow line ``k`` of the placement, monitoring the grasp and the tracking."""
        seconds = max(0.3, line.length / line.speed)
        base_path = placement.base_paths[k]
        mon = self._line_monitor(line)
        moved = line.part_joint is not None and line.part_q is not None
        comply = self._comply if line.name in OPENING_LINES else None
        try:
            self.drv.follow(
                list(placement.lines[k]), seconds, base_path=base_path, monitor=mon, comply=comply
            )
            self.drv.hold(self.params.settle_time)
            mon(0.0)
        except SkillStop as stop:
            if moved and stop.status is Status.OK:  # the part met its end: it is where
                # the hand let it (the recovery's stow plans around it there)
                tcp = self.world.site_pose(GRIPPER_SITE)[:3, 3]
                i = int(np.argmin(np.linalg.norm(line.poses[:, :3, 3] - tcp, axis=1)))
                self._believe_part(line, i)
            raise
        if moved:
            self._believe_part(line, len(line.poses) - 1)

    def _believe_part(self, line: Line, i: int) -> None:
        """The believed part is where pose ``i`` of ``line`` takes it (the next skill and
        a recovery's stow plan with it there, as the robot believes it)."""
        if self.plan_world is not self.world and line.part_joint is not None:
            assert line.part_q is not None
            self.plan_world.set_parts({line.part_joint: float(line.part_q[i])})

    def _line_monitor(self, line: Line | None) -> Callable[[float], None]:
        """Stops a motion when the grasp of ``line`` is lost (if it holds something),
        an opening's part has met its end (:func:`~.executor.at_part_end`: stopped
        ``ok``), the cabinet has slid or tipped past its guards since the skill started
        (:class:`~.cabinet_guard.CabinetGuard`), or the gripper lags more than the
        tracking tolerance behind its command (None: a free motion)."""
        m, d, p = self.world.model, self.world.data, self.params
        tendon = m.tendon("gripper").id
        site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, GRIPPER_SITE)
        tol = p.free_tolerance if line is None else p.tracking_tolerance
        if line is not None and line.tolerance is not None:
            tol = line.tolerance
        name = "free motion" if line is None else line.name
        guard = self._guard
        path = self._path if name in OPENING_LINES else None

        def monitor(_: float) -> None:
            if line is not None and grasp_lost(line.holding, float(d.ten_length[tendon])):
                raise SkillStop(Status.GRASP_LOST, stop_detail(Status.GRASP_LOST, name))
            cmd = self.ctx.ik.forward(self._command())[:3, 3]
            behind = cmd - d.site_xpos[site]
            lag = float(np.linalg.norm(behind))
            if path is not None:
                guard.check_end(path, cmd, behind, name)
            guard.check(name)
            if held_back(lag, tol):
                raise SkillStop(Status.COLLISION, stop_detail(Status.COLLISION, name, lag))

        return monitor

    def _command(self) -> dict[str, float]:
        return {
            **dict(zip(BASE_JOINTS, self.drv.base_target.tolist(), strict=True)),
            **dict(zip(ARM_TORSO_JOINTS, self.drv.arm_cmd.tolist(), strict=True)),
        }

    def _key(self, name: str) -> None:
        if self.observer is not None:
            mujoco.mj_forward(self.world.model, self.world.data)
            self.observer(name)

    # -- the report ----------------------------------------------------------------------
    def _outcome(
        self,
        plan: SkillPlan,
        status: Status,
        detail: str,
        phase: str,
        before: tuple[dict[str, float], np.ndarray],
        t_wall: float,
    ) -> Outcome:
        settle(self.world, self.drv.hold, MONITOR_PERIOD, self.params)
        mujoco.mj_forward(self.world.model, self.world.data)
        times, qpos = self.drv.recording()
        return report(
            self.world, plan, status, detail, phase, before,
            holding=holds(self.drv.grip_cmd, self._fingers()), times=times, qpos=qpos,
            sim_time=self.drv.elapsed, t_wall=t_wall, ik_seconds=self.ik_seconds,
            planning_seconds=self.plan_seconds, physics_seconds=self.drv.physics_seconds,
        )  # fmt: skip
