"""The planning twin's programs: a skill plan as the floating hand's step-by-step
commands (:class:`Program`), timed by the full robot's placement, with the arm's links
along its joint path after the last release and the full robot's stow as far as the
hand follows it (:class:`Stow`). :class:`TwinPrograms` is the part of
:class:`~strug_manip.control.twin_body.PlanningTwin` that makes them."""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Hashable
from dataclasses import dataclass

import numpy as np

import strug_manip.control.timing as timing
from strug_manip.control.base_servo import BaseServo, base_inertia
from strug_manip.control.executor import STOW_SEED, ends_holding, plan_stow, stow_retreat
from strug_manip.control.outcome import SkillStop
from strug_manip.control.placement import Placement
from strug_manip.control.plan import Grip, Line, SkillPlan
from strug_manip.geometry import quats, slerp, with_base
from strug_manip.robot.fetch import ARM_TORSO_JOINTS, BASE_JOINTS, GRIPPER_OPEN, GRIPPER_SQUEEZE
from strug_manip.world.floating_gripper import ARM_LINKS, ARM_PARK
from strug_manip.world.sim import ManipulationWorld

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
#: The hand follows the full robot's stow until it is this far from the cabinet's box
#: for good [m] (the fingers reach 0.1 m past the TCP; the arm's links, which the twin
#: does not have, seldom sweep the cabinet where the hand does not).
STOW_CLEARANCE = 0.1
#: Room in front of the cabinet that its open parts take (a drawer pulled out, a door
#: swung open) [m].
FRONT_ROOM = 0.3
#: The base pose and arm speeds the twin assumes when none is given.
BASE_SPEED = np.array([0.3, 0.3, 0.9])


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
            there; :data:`~.twin_rollout.FREE_COARSENING`), ``nstep`` when the skill ends holding.
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
        limits = np.concatenate([vmax, BASE_SPEED])
    T = timing.duration(pts, limits, max(0.3, line.length / line.speed))
    seg, frac = timing.schedule(pts, T, dt, limits)
    ps = np.vstack([here[0][None], line.poses[:, :3, 3]])
    qs = np.vstack([here[1][None], quats(line.poses[:, :3, :3])])
    pos = ps[seg] + frac[:, None] * (ps[seg + 1] - ps[seg])
    joints = pts[seg] + frac[:, None] * (pts[seg + 1] - pts[seg])
    if placement.base_paths[k] is None:
        joints = np.hstack([joints, np.repeat(np.asarray(base0, float)[None], len(seg), axis=0)])
    joints = np.hstack([joints[:, -3:], joints[:, :-3]])  # base first
    return pos, slerp(qs[seg], qs[seg + 1], frac), joints


class TwinPrograms:
    """The planning twin's programs (a mixin of
    :class:`~strug_manip.control.twin_body.PlanningTwin`, whose state it uses)."""

    def program(self, plan: SkillPlan, plan_world: ManipulationWorld | None = None) -> Program:
        """The controls that run ``plan`` (made against ``plan_world``) on the twin, from
        its placement (raises :class:`SkillStop` ``ik_infeasible`` if there is none);
        the twin keeps its last :data:`PROGRAMS` programs (a search simulates the same
        skill on a particle many times; a program holds the arm's poses at every step,
        a few hundred kB, too much for the context's cache of thousands of entries)."""
        placement = self._placement(plan, plan_world)
        pw = plan_world if plan_world is not None or not self.checked else self._planning_world
        key = (placement, self._token(pw))  # (_placement made the twin's own world)
        prog = self._programs.lookup(key)
        if prog is None:
            prog = self._program(placement, plan_world)
            self._programs.store(key, prog)
        return prog

    def _program(self, placement: Placement, plan_world: ManipulationWorld | None) -> Program:
        plan = placement.plan
        dt = self.world.model.opt.timestep
        p = self.params
        pos: list[np.ndarray] = []  # commanded TCP position and orientation, per step
        quat: list[np.ndarray] = []
        grips, names, held, holds, tols = [], [], [], [], []
        tol = p.tracking_tolerance
        here = (plan.pre[:3, 3], quats(plan.pre[None, :3, :3])[0])
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
                here = (start[:3, 3], quats(start[None, :3, :3])[0])
                k += 1
                continue
            ps, qs, joints = _line_commands(ph, placement, k, here, self.vmax, dt)
            tol = p.tracking_tolerance if ph.tolerance is None else ph.tolerance
            base = joints[-1, :3]
            # After the last release the arm moves freely, along its joint path: its
            # links may sweep the cabinet (e.g. back out of a drawer).
            arm = (
                self._shared(placement, ("arm", k), lambda j=joints: self._arm_poses(j))
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
        drive_pos, drive_quat = with_base(pos_, quat_, planned, actual)
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

        return self._shared(placement, ("base", len(planned)), respond)  # type: ignore[return-value]

    def _parked_arm(self) -> np.ndarray:
        """The arm links' poses (L, 7) out of the scene (:data:`ARM_PARK`)."""
        return np.tile(np.r_[ARM_PARK, 1.0, 0.0, 0.0, 0.0], (len(ARM_LINKS), 1))

    def _shared(self, placement: Placement, key: Hashable, compute: Callable[[], object]) -> object:
        """What ``compute()`` gave for ``placement`` and ``key`` on any twin with this
        twin's context, time step and skill constants, else its result
        (:meth:`~.context.ControlContext.derived`): for what depends on the placement,
        the full robot and what ``key`` names alone, not on the twin's cabinet (the
        arm's servos, its poses along its joint path, the base's response; the stow
        planned in the planning world that ``key``'s token names), so the particles of
        a search node derive it once rather than once each."""
        dt = self.world.model.opt.timestep
        return self.ctx.derived(placement, ("twin", key, dt, self.params), compute)

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
            coarse[k, 0, 3:] = quats(T[None, :3, :3])[0]
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
        out[..., 3:] = slerp(a[..., 3:].reshape(-1, 4), b[..., 3:].reshape(-1, 4),
                              np.repeat(s, K)).reshape(n, K, 4)  # fmt: skip
        return out[:, 0], out[:, 1:]

    def _stow_commands(
        self, placement: Placement, plan_world: ManipulationWorld | None
    ) -> Stow | None:
        """The full robot's stow after ``placement`` as the twin follows it: its straight
        way back to the pre-grasp where that is free (:func:`~strug_manip.control.
        execution.stow_retreat`; the rest is collision-free in the model), else the same
        plan (:func:`~strug_manip.control.executor.plan_stow`) up to where the hand and
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
        found = self._shared(placement, ("stow plan", self._token(pw)), plan)
        if found is None:
            return None
        stow, goal = found
        dt = self.world.model.opt.timestep
        if not len(stow):
            return Stow(np.zeros((0, 3)), np.zeros((0, 4)), np.zeros((0, len(ARM_LINKS), 7)), 0)
        tcp, arm = self._shared(  # type: ignore[misc]
            placement, ("stow", self._token(pw)), lambda: self._stow_poses(placement, stow)
        )
        if goal is not None:  # the rest: as long as the straight line on to the goal
            rest = timing.duration(timing.polyline(stow[-1], [goal]), self.vmax, 0.3)
            return Stow(tcp[:, :3].copy(), tcp[:, 3:].copy(), arm, round(rest / dt))
        # The hand (its TCP) and the arm (its links' origins and the middles between
        # them) near the cabinet.
        mid = 0.5 * (arm[:, 1:, :3] + arm[:, :-1, :3])
        points = np.concatenate([tcp[:, None, :3], arm[:, :, :3], mid], axis=1)
        near = self._near_cabinet(points.reshape(-1, 3)).reshape(len(tcp), -1).any(axis=1)
        n = int(np.flatnonzero(near)[-1]) + 2 if near.any() else 1
        n = min(n, len(tcp))
        return Stow(tcp[:n, :3].copy(), tcp[:n, 3:].copy(), arm[:n], len(tcp) - n)

    def _stow_poses(self, placement: Placement, stow: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The TCP's poses (n, 7) and the arm links' (n, L, 7) every step along the
        stow's joint path ``stow`` (k, 8) (torso + arm) from the placement's end, on
        the full robot's timing."""
        base, q_end = placement.start_of(len(placement.lines))
        pts = timing.polyline(q_end, list(stow))
        T = timing.duration(pts, self.vmax, 0.3)
        qs = timing.samples(pts, T, self.world.model.opt.timestep, self.vmax)
        return self._fk_along(np.hstack([np.repeat(base[None], len(qs), axis=0), qs]))

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
