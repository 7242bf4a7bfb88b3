"""The executor core: what the full robot and the planning twin share.

A skill's :class:`~strug_manip.control.plan.SkillPlan` runs on one of two bodies, the
full Fetch (:class:`~strug_manip.control.fetch_body.FullRobot`: base, IK, OMPL, arm
physics) and the Fetch's floating hand (:class:`~strug_manip.control.twin_body.
PlanningTwin`, the search's fast twin). Both implement :class:`Body` and differ only in
how they move; what decides how a run goes and what it reports is here, once:

- **the stop rules** (:func:`grasp_lost`, :func:`cabinet_slid`, :func:`held_back`, and
  for an opening :func:`at_part_end`, which ends it ``ok`` where its part stops; their
  reasons :func:`stop_detail`), checked while a motion runs (the full robot every
  control tick, the twin on its rollout's states, vectorised), and what counts as
  holding the object (:func:`holds`, :func:`keeps_object`);
- **the stow** after a skill (:func:`plan_stow`, its first part :func:`stow_retreat`,
  seeded by :data:`STOW_SEED`) and the back-off after a stop (:func:`recovery_poses`);
  free motions keep clear of the scene where they can (:func:`keeping_clear`);
- **the outcome**: the facts measured before (:func:`facts_before`) and after
  (:func:`report`) a run, once the cabinet is at rest (:func:`at_rest`,
  :data:`REST_SPEED`): what a skill reports is where its release and stow left the
  cabinet, not where it was still rocking.

A change to a rule is made here, and both bodies follow it.
"""

from __future__ import annotations

import contextlib
import functools
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from strug_manip.control.contacts import ContactChecker
from strug_manip.control.context import ControlContext
from strug_manip.control.grasps import held_grasp
from strug_manip.control.motion import NO_PLAN, ArmMotionPlanner, ArmValidity, MotionPlan
from strug_manip.control.outcome import Outcome, SkillStop, Status
from strug_manip.control.params import SkillParams
from strug_manip.control.placement import Placement
from strug_manip.control.plan import Grip, Line, SkillPlan, retreat_poses
from strug_manip.geometry import rotate
from strug_manip.robot.fetch import (
    ARM_TORSO_JOINTS,
    CARRY,
    FINGERS_EMPTY,
    GRIPPER_SQUEEZE,
    TUCK,
)
from strug_manip.world.sim import ManipulationWorld

#: Joint distance from the tuck below which the arm counts as tucked [rad or m].
TUCKED_TOLERANCE = 0.15
#: A cabinet at rest: every joint of it (the parts, the base's free joint) slower than
#: this [m/s or rad/s] (a drawer of a tilted cabinet creeping out moves 0.02 m/s).
REST_SPEED = 0.005
#: A pair of geoms near where a free motion starts or ends may come this much nearer
#: on the way than it is there [m] (:func:`keeping_clear`): the validity checks along
#: a path's edges see the pair a few millimetres apart from where the ends do.
EXCUSE_SLACK = 0.005


class Body(Protocol):
    """What runs a skill plan: the full robot or the planning twin.

    Attributes:
        world: where physics runs and the outcome is measured.
        ctx: the shared solvers and caches.
        params: the skills' constants.
    """

    world: ManipulationWorld
    ctx: ControlContext
    params: SkillParams

    def believed(self) -> ManipulationWorld:
        """The world skills plan against (the believed cabinet), in the body's state."""
        ...

    def run(self, plan: SkillPlan) -> Outcome:
        """Execute ``plan``; never raises for a failure of the skill (the
        :class:`Outcome` says how it ended)."""
        ...


# -- the stop rules --------------------------------------------------------------------
# Each takes scalars (the full robot, at every control tick) or arrays (the twin, over
# a rollout's states) alike.
Values = float | np.ndarray
Flags = bool | np.ndarray


def grasp_lost(holding: Flags, fingers: Values) -> Flags:
    """Stop rule ``grasp_lost``: where the fingers should hold something (``holding``)
    and their opening ``fingers`` [m] says they closed on nothing."""
    return holding & (fingers < FINGERS_EMPTY)


def cabinet_slid(slid: Values, params: SkillParams) -> Flags:
    """Stop rule ``cabinet_moved``: the cabinet base has slid ``slid`` [m] (since the
    skill started, or a recovery) more than ``cabinet_motion_limit``."""
    return slid > params.cabinet_motion_limit


def cabinet_tipped(up0: np.ndarray, up: np.ndarray, params: SkillParams) -> Flags:
    """Stop rule ``cabinet_moved`` too: the cabinet's up axis ``up`` ((3,) or (n, 3))
    has turned more than ``cabinet_tilt_limit`` from ``up0`` (3,) (since the skill
    started, or a recovery): it tips. A cabinet pulled high up tips about its front
    edge before its base slides (a drop flap's pull on a side door tipped one 29
    degrees while its base moved 1.4 cm, and it fell over)."""
    return np.asarray(up) @ up0 < np.cos(params.cabinet_tilt_limit)


def tilt_of(up0: np.ndarray, up: np.ndarray) -> Values:
    """The angle [rad] between the cabinet's up axes ``up0`` (3,) and ``up`` ((3,) or
    (n, 3))."""
    return np.arccos(np.clip(np.asarray(up) @ up0, -1.0, 1.0))


def held_back(lag: Values, tol: Values) -> Flags:
    """Stop rule ``collision``: the gripper is ``lag`` [m] behind its commanded pose,
    more than the tracking tolerance ``tol`` [m] (the arm or hand is blocked)."""
    return lag > tol


#: The lines of an opening along which its part moves with the hand: ``move``, then
#: its last few centimetres, the slow ``ease``.
OPENING_LINES = ("move", "ease")


@dataclass(frozen=True, eq=False)
class OpeningPath:
    """Where an opening's lines (:data:`OPENING_LINES`) take the TCP, and the cabinet's
    point at the grasp: what :func:`at_part_end` measures against.

    Attributes:
        points: the TCP path from the grasp to where the lines end, (n, 3) [m].
        anchor: that grasp point in the cabinet base's frame when the skill started,
            (3,) [m]; where the cabinet has moved it is how far the cabinet has given
            where the hand pulls (:meth:`give`).
    """

    points: np.ndarray
    anchor: np.ndarray

    @classmethod
    def of(cls, plan: SkillPlan, T_world_cabinet: np.ndarray) -> OpeningPath | None:
        """``plan``'s opening path, the cabinet base at ``T_world_cabinet`` (4, 4) as the
        skill starts; None for a plan without opening lines."""
        prev, pts = plan.pre, []
        for ph in plan.phases:
            if not isinstance(ph, Line):
                continue
            if ph.name in OPENING_LINES:
                pts += [prev[:3, 3]] if not pts else []
                pts += list(ph.poses[:, :3, 3])
            prev = ph.poses[-1]
        if len(pts) < 2:
            return None
        T = T_world_cabinet
        return cls(np.asarray(pts), T[:3, :3].T @ (pts[0] - T[:3, 3]))

    def share(self, tcp: np.ndarray) -> Values:
        """How far the commanded TCP ``tcp`` ((3,) or (n, 3)) [m] is along the path: its
        straight-line distance from the grasp over that of the path's end [-]
        (monotonic along a swing of up to 180 degrees)."""
        full = float(np.linalg.norm(self.points[-1] - self.points[0]))
        return np.linalg.norm(np.asarray(tcp) - self.points[0], axis=-1) / max(full, 1e-9)

    def tangent(self, tcp: np.ndarray) -> np.ndarray:
        """The unit direction of the path where it passes nearest ``tcp`` ((3,) or (n,
        3)) [m], the same shape."""
        tcp = np.asarray(tcp, dtype=float)
        d = np.linalg.norm(tcp[..., None, :] - self.points, axis=-1)
        i = np.clip(np.argmin(d, axis=-1), 1, len(self.points) - 1)
        t = self.points[i] - self.points[i - 1]
        return t / np.maximum(np.linalg.norm(t, axis=-1, keepdims=True), 1e-12)

    def give(self, pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
        """How the cabinet has moved at the grasp point, ((3,) or (n, 3)) [m]: the cabinet
        base at ``pos`` ((3,) or (n, 3)) turned by ``quat`` ((4,) or (n, 4), w x y z).
        A cabinet that tips toward the hand gives there before its base slides (a
        drawer 1.06 m high pulled into its stop)."""
        return np.asarray(pos) + rotate(quat, self.anchor) - self.points[0]


def strained(give: Values, lag: Values, params: SkillParams) -> Flags:
    """An opening's part does not follow the hand: the cabinet has given ``give`` >
    ``end_give`` where the hand pulls (:meth:`OpeningPath.give`) or the hand lags
    ``lag`` > ``end_lag`` behind its command [m] (magnitudes, or components along the
    path)."""
    return (give > params.end_give) | (lag > params.end_lag)


def at_part_end(share: Values, early: Flags, along: Flags, params: SkillParams) -> Flags:
    """Stop rule of an opening's lines, ``ok``: its part has met its end. The part
    followed the hand, unstrained, for the first ``end_share`` of the path (not
    ``early``: :func:`strained` in any direction before), and now, ``share`` >=
    ``end_share`` along, it holds the hand back *along* the path (``along``:
    :func:`strained` by the components along :meth:`OpeningPath.tangent`). A part that
    strains early does not move as the plan believes (a drawer swung as a door, a door
    pulled straight): the other rules stop it. A strain across the path (a hinge or an
    axis a little off) is not an end."""
    return ~early & (share >= params.end_share) & along


def tipped_detail(name: str, tilt: float) -> str:
    """Why :func:`cabinet_tipped` stopped the motion ``name`` (``cabinet_moved``):
    ``tilt`` [rad]."""
    return f"the cabinet tipped {np.degrees(tilt):.1f} degrees ({name})"


def stop_detail(status: Status, name: str, amount: float = 0.0) -> str:
    """Why a stop rule stopped the motion ``name``: ``amount`` is how far the cabinet
    slid or the gripper lags [m], or for ``ok`` (:func:`at_part_end`) the share of the
    opening done [-]."""
    if status is Status.OK:
        return f"the part met its end {amount:.0%} of the way ({name})"
    if status is Status.GRASP_LOST:
        return f"the fingers closed on nothing ({name})"
    if status is Status.CABINET_MOVED:
        return f"the cabinet slid {amount:.3f} m ({name})"
    return f"the gripper is held back {amount:.3f} m from its path ({name})"


def holds(grip_cmd: float, fingers: float) -> bool:
    """The gripper holds something: its fingers are commanded to squeeze and stand
    apart (``fingers`` [m]) on something."""
    return grip_cmd == GRIPPER_SQUEEZE and fingers > FINGERS_EMPTY


def keeps_object(plan: SkillPlan, grip_cmd: float, fingers: float) -> bool:
    """After a stop the gripper keeps what it holds (else it lets go) when the skill
    carries the object (a Place, or a plan that ends holding: a Pick)."""
    carrier = plan.carrying is not None or ends_holding(plan)
    return carrier and holds(grip_cmd, fingers)


# -- the stow --------------------------------------------------------------------------


def ends_holding(plan: SkillPlan) -> bool:
    """The plan ends with the fingers closed on something (a Pick)."""
    closed = plan.carrying is not None
    for ph in plan.phases:
        if isinstance(ph, Grip):
            closed = ph.closed
    return closed


def plan_stow(
    ctx: ControlContext,
    plan_world: ManipulationWorld,
    placement: Placement,
    params: SkillParams,
    seed: int,
) -> np.ndarray:
    """Torso + arm waypoints (N, 8) from where ``placement``'s last line ends to the
    drive posture (the tuck, or holding the object its carry posture), planned in
    ``plan_world`` with the base where that line ends, every believed part moved where
    the plan's lines took it and a held object attached as grasped; () for no motion.
    The full robot plans it before it moves; the planning twin follows its first part,
    :func:`stow_retreat`, out of the cabinet's way.

    First back to the pre-grasp configuration (:func:`stow_retreat`, where that
    straight line is free: the hand goes back the way it came) and from there: an arm
    in an open drawer or over one is a narrow passage for the samplers, which spent
    seconds on it (RRTConnect's budget, then LBKPIECE1's). Failing that, from where
    the lines end.

    Raises:
        SkillStop: ``no_motion_plan``.
    """
    setup = _stow_setup(ctx, plan_world, placement)
    checker, base, q_end, goal = setup
    if near_posture(q_end, goal):
        return np.zeros((0, len(goal)))
    validity = ArmValidity(checker, base)
    back = _retreat(setup, placement)
    starts = [] if back is None else [back]
    starts.append(np.zeros((0, len(goal))))
    res = None
    held = params.held_clearance if checker.attached_body >= 0 else 0.0
    planners = ctx.planners(plan_world.model)
    for prefix in starts:
        start = prefix[-1] if len(prefix) else q_end

        def run(
            i: int, planner: ArmMotionPlanner, checks: int, _wide: bool, start: np.ndarray = start
        ) -> MotionPlan:
            return _plan(planner, start, goal, validity, checks, params.plan_wall_cap, seed)

        def clear(room: bool, start: np.ndarray = start) -> contextlib.AbstractContextManager[None]:
            return keeping_clear(checker, base, (start, goal), params, held, room)

        res = clear_first(planners, run, clear, params)
        if res.success:
            return np.vstack([prefix, np.asarray(res.waypoints[1:])])
    assert res is not None
    raise SkillStop(Status.NO_MOTION_PLAN, f"{res.reason}: {res.detail}", "stow")


def clear_first(
    planners: Sequence[ArmMotionPlanner],
    run: Callable[[int, ArmMotionPlanner, int, bool], MotionPlan],
    clear: Callable[[bool], contextlib.AbstractContextManager[None]],
    params: SkillParams,
    wide: Callable[[], contextlib.AbstractContextManager[None]] | None = None,
) -> MotionPlan:
    """The first plan found by ``run(i, planner, checks, wide)`` (the ``i``-th of
    ``planners``, its budget ``checks`` validity checks, ``wide`` True in the wide
    round): each planner in turn inside
    ``wide()`` if given (a wider berth, :func:`keeping_clear` with ``wide_clearance``),
    then inside ``clear(True)`` (e.g. :func:`keeping_clear`, keeping the room the ends
    leave), then inside ``clear(False)`` (what is near the ends may touch), each
    round's budget capped at ``clear_checks``, then each in turn again with the plain
    check and its full budget; a planner's turn ends the round when it succeeds or
    fails for another reason than its budget."""
    res = None
    Round = tuple[Callable[[], contextlib.AbstractContextManager[None]], int | None, bool]
    rounds: tuple[Round, ...] = (
        (functools.partial(clear, True), params.clear_checks, False),
        (functools.partial(clear, False), params.clear_checks, False),
        (contextlib.nullcontext, None, False),
    )
    if wide is not None:
        rounds = ((wide, params.clear_checks, True), *rounds)
    for keep, cap, is_wide in rounds:
        with keep():
            for i, planner in enumerate(planners):
                checks = params.planner_checks(i, len(planners))
                res = run(i, planner, checks if cap is None else min(checks, cap), is_wide)
                if res.success or res.reason != NO_PLAN:
                    break
        if res is not None and res.success:
            break
    assert res is not None
    return res


def _plan(
    planner: ArmMotionPlanner,
    start: np.ndarray,
    goal: np.ndarray,
    validity: ArmValidity,
    checks: int,
    wall_cap: float,
    seed: int,
) -> MotionPlan:
    """``planner``'s torso + arm motion from ``start`` to ``goal`` (8,) within
    ``checks`` validity checks (``wall_cap`` [s]: the safety cap)."""
    return planner.plan(
        dict(zip(ARM_TORSO_JOINTS, start.tolist(), strict=True)),
        dict(zip(ARM_TORSO_JOINTS, goal.tolist(), strict=True)),
        validity,
        checks=checks,
        timeout=wall_cap,
        seed=seed,
    )


def scene_bodies(checker: ContactChecker) -> list[int]:
    """Ids of the scene's bodies in ``checker``'s model: neither the robot's, nor the
    world's (the floor), nor an attached one (the cabinet, the tables, the object
    where it rests)."""
    return [b for b in range(1, checker.model.nbody)
            if not checker.robot[b] and b != checker.attached_body]  # fmt: skip


@contextlib.contextmanager
def keeping_clear(
    checker: ContactChecker,
    base: np.ndarray | None,
    ends: Sequence[np.ndarray],
    params: SkillParams,
    held: float = 0.0,
    room: bool = True,
    clearance: float | None = None,
) -> Iterator[None]:
    """Within the block, ``checker`` counts the robot's contacts with the scene
    (:func:`scene_bodies`) from ``clearance`` [m] apart (default ``free_clearance``),
    and an attached object's with
    anything from ``held`` [m] apart (:meth:`~.contacts.ContactChecker.keep_clear`),
    except the pairs of geoms already that near where the motion starts or ends (torso
    + arm ``ends``, each (8,), the base at ``base`` (3,); or, ``base`` None, whole
    configurations base + torso + arm, each (11,): a route's): those count only nearer
    than they are there (less :data:`EXCUSE_SLACK`), so the path keeps what room the
    ends leave (``room``; else only where they touch). Afterwards the plain check is
    back.

    Why: free motions are planned touching-free and the arm follows them a few
    centimetres off (it lags its command, and the checks along an edge are 4 cm
    apart at the gripper), so a plan that grazes a part pushed it: an elbow swept an
    open drawer on the stow after a Place and slid the cabinet, a wrist knocked a
    drawer shut on the way to place into it. The tables count too: an arm kept clear
    of the cabinet alone stowed along the table under it and caught on its edge. A
    pair near where the motion ends was let touch all the way: a carried object
    grazed the edge of a door open beside its cell and slid the cabinet (OpenDoor
    episode 9846; ``tools/eval_place_offset.py``).
    """
    bodies = scene_bodies(checker)
    checker.keep_clear_of(bodies, params.free_clearance if clearance is None else clearance)
    if held > 0.0:
        checker.keep_clear(held)
    near: dict[tuple[int, int], float] = {}
    for q in ends:
        pairs, gaps = checker.geom_gaps(q if base is None else np.r_[base, q])
        for (a, b), gap in zip(pairs.tolist(), gaps.tolist(), strict=True):
            key = (min(a, b), max(a, b))
            near[key] = min(near.get(key, np.inf), gap - EXCUSE_SLACK if room else 0.0)
    checker.excuse(near.keys(), near.values())
    try:
        yield
    finally:
        checker.excuse()
        checker.keep_clear_of(bodies, 0.0)
        if held > 0.0:
            checker.keep_clear(0.0)


def stow_retreat(
    ctx: ControlContext, plan_world: ManipulationWorld, placement: Placement
) -> tuple[np.ndarray, np.ndarray] | None:
    """The stow's first waypoint (1, 8), the pre-grasp configuration, when the straight
    joint-space line to it from where the lines end is free in ``plan_world`` (set up
    as :func:`plan_stow` does), and the drive posture the stow ends in (8,); None when
    the line is not free, or when the arm needs no stow."""
    setup = _stow_setup(ctx, plan_world, placement)
    _, _, q_end, goal = setup
    if near_posture(q_end, goal):
        return None
    back = _retreat(setup, placement)
    return None if back is None else (back, goal)


_StowSetup = tuple[ContactChecker, np.ndarray, np.ndarray, np.ndarray]


def near_posture(q: np.ndarray, goal: np.ndarray) -> bool:
    """The arm (torso aside) of torso + arm ``q`` (8,) is within
    :data:`TUCKED_TOLERANCE` of ``goal`` (8,)."""
    return bool(np.max(np.abs(q[1:] - goal[1:])) < TUCKED_TOLERANCE)


def drive_posture(carrying: tuple[str, np.ndarray] | None) -> np.ndarray:
    """Torso + arm (8,) the robot drives and stows in: tucked, or carrying the object
    (``(name, T_gripper_object)``) in its grasp's carry posture."""
    return np.array(TUCK if carrying is None else CARRY[held_grasp(carrying[1])])


def _retreat(setup: _StowSetup, placement: Placement) -> np.ndarray | None:
    checker, base, q_end, _ = setup
    q_pre = placement.q_pre
    if not np.any(q_pre != q_end) or checker.segment(np.r_[base, q_end], np.r_[base, q_pre]):
        return None
    return np.asarray(q_pre, dtype=float)[None]


def _stow_setup(
    ctx: ControlContext, plan_world: ManipulationWorld, placement: Placement
) -> _StowSetup:
    """The checker of ``plan_world`` as the stow after ``placement`` sees it (parts where
    the lines took them, the object released or held), the base, where the lines end
    and the drive posture: ``(checker, base (3,), q_end (8,), goal (8,))``."""
    plan = placement.plan
    base, q_end = placement.start_of(len(placement.lines))
    carrying = None
    if ends_holding(plan):
        if plan.carrying is not None:
            carrying = plan.carrying
        else:  # a Pick: the object as the plan grasps it (where the line to the
            # closing grip ends)
            grip, last = None, None
            for ph in plan.phases:
                if isinstance(ph, Grip) and ph.closed and last is not None:
                    grip = last.poses[-1]
                elif isinstance(ph, Line):
                    last = ph
            grip = plan.pre if grip is None else grip
            carrying = ("object", np.linalg.inv(grip) @ plan_world.object_pose())
    goal = drive_posture(carrying)
    checker = ctx.checker(plan_world.model).load(plan_world.data)
    if plan.carrying is not None and carrying is None:  # a Place: the object left there
        checker.set_pose(plan.carrying[0], _release_pose(plan) @ plan.carrying[1])
    for line in plan.lines:
        if line.part_joint is not None and line.part_q is not None:
            checker.set({line.part_joint: float(line.part_q[-1])})
    checker.attach(*carrying) if carrying is not None else checker.attach(None)
    checker.allow()
    return checker, base, q_end, goal


def recovery_poses(T_world_gripper: np.ndarray, params: SkillParams) -> tuple[np.ndarray, float]:
    """The straight back-off after a stop: ``retreat_distance`` against the gripper's
    approach from ``T_world_gripper`` (4, 4): ``(poses (N, 4, 4), length [m])``."""
    return retreat_poses(T_world_gripper, params.retreat_distance, params.line_step)


def _release_pose(plan: SkillPlan) -> np.ndarray:
    """``T_world_gripper`` (4, 4) where ``plan`` opens its fingers (the end of the line
    before the opening grip)."""
    last = None
    for ph in plan.phases:
        if isinstance(ph, Grip) and not ph.closed:
            break
        if isinstance(ph, Line):
            last = ph
    return plan.pre if last is None else last.poses[-1]


#: Seed offset of the stow's plan (independent of how many plans came before it, so
#: that the planning twin plans the same one).
STOW_SEED = 7919


# -- the outcome -----------------------------------------------------------------------


def cabinet_dofs(world: ManipulationWorld) -> np.ndarray:
    """Indices into ``qvel`` of the cabinet's joints in ``world``: its base's free
    joint (6) and every part joint, (6 + n_parts,)."""
    m = world.model
    free = m.joint(world.scene.cabinet_prefix + "free")
    dofs = [np.arange(free.dofadr[0], free.dofadr[0] + 6)]
    dofs += [m.joint(j).dofadr for j in world.part_joints]
    return np.concatenate(dofs).astype(int)


def at_rest(qvel: np.ndarray) -> bool:
    """Every cabinet joint velocity of ``qvel`` (:func:`cabinet_dofs`) [m/s or rad/s]
    is below :data:`REST_SPEED`."""
    return bool(np.max(np.abs(qvel), initial=0.0) < REST_SPEED)


def settle(
    world: ManipulationWorld, hold: Callable[[float], None], period: float, params: SkillParams
) -> None:
    """Step ``world`` by ``hold(period)`` (every command held for ``period`` [s]) while
    the cabinet still moves (:func:`at_rest`), up to ``settle_limit``, or until the
    hold stops the run (its time budget): the outcome is measured where the cabinet
    came to rest. A cabinet at rest already is not stepped at all."""
    dofs = cabinet_dofs(world)
    waited = 0.0
    try:
        while not at_rest(world.data.qvel[dofs]) and waited < params.settle_limit:
            hold(period)
            waited += period
    except SkillStop:  # the time budget is spent: report the cabinet as it is
        pass


def facts_before(world: ManipulationWorld) -> tuple[dict[str, float], np.ndarray]:
    """What a run's outcome is measured against: the part positions and the cabinet's
    displacement vector (2,) [m] of ``world`` before the skill."""
    return world.part_positions(), world.cabinet_displacement_vector()


def report(
    world: ManipulationWorld,
    plan: SkillPlan,
    status: Status,
    detail: str,
    phase: str,
    before: tuple[dict[str, float], np.ndarray],
    *,
    holding: bool,
    times: np.ndarray,
    qpos: np.ndarray,
    sim_time: float,
    t_wall: float,
    ik_seconds: float,
    planning_seconds: float,
    physics_seconds: float,
) -> Outcome:
    """The :class:`Outcome` of a run of ``plan`` that ended in ``world`` as it is now,
    the parts and the cabinet compared with ``before`` (:func:`facts_before`)."""
    parts0, cab0 = before
    parts = world.part_positions()
    return Outcome(
        skill=plan.skill,
        status=status,
        detail=detail,
        phase=phase,
        part_motion={j: parts[j] - parts0[j] for j in parts},
        part_units=world.part_units(),
        part_positions=parts,
        cabinet_displacement=world.cabinet_displacement(),
        cabinet_motion=float(np.linalg.norm(world.cabinet_displacement_vector() - cab0)),
        object_pose=world.object_pose(),
        holding=holding,
        times=times,
        qpos=qpos,
        sim_time=sim_time,
        wall_seconds=time.perf_counter() - t_wall,
        ik_seconds=ik_seconds,
        planning_seconds=planning_seconds,
        physics_seconds=physics_seconds,
    )
