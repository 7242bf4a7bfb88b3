"""Where the base stands for a skill: an IK reachability search over base poses.

For a :class:`~strug_manip.control.plan.SkillPlan`, :func:`find_placement` tries base
poses around the skill's *work point* (the mean of its gripper positions), facing the
skill's work direction (the horizontal part of the gripper's mean approach axis, e.g.
into the cabinet front; for a vertical approach, the direction from the robot to the
work point), in the order of :data:`CANDIDATES`: near the preferred shoulder distance
first, then farther, nearer and to the sides, each also turned by +-0.35 rad. A pose is
taken when, with the base there,

1. the robot in its carry posture stands free of the scene (tables, cabinet);
2. the pre-grasp pose has an IK solution (mink, a few restarts) free of contacts;
3. every Cartesian line of the skill is tracked continuously from it (arm only; for an
   opening or probing motion the arm cannot follow alone, whole-body: the base joins
   the IK at :data:`BASE_COST` times the arm's cost, so it moves only where the arm runs
   out of reach), each pose free of contacts except the hand's with what it may touch,
   the believed part moved along with the gripper.

A failure that holds for every base of the plan ends the search of that plan (fingers
that way) at the first base that shows it: the hand in the scene at the pre-grasp
(:data:`HAND_IN_COLLISION`) or deeper than :data:`LINE_HAND_DEPTH` along a line
(:data:`LINE_HAND_IN_COLLISION`), since the hand's poses are the plan's, to the IK's
tolerance, whichever base the arm reaches them from.

Steps 1 and the contact checks need the planning world (the believed cabinet); the
planning twin runs the search kinematically (``checker=None``), so the same plan gives
the same placement and the same ``ik_infeasible`` on every particle it is simulated on.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

import strug_manip.control.timing as timing
from strug_manip.control.contacts import ContactChecker
from strug_manip.control.ik import FetchIK
from strug_manip.control.outcome import SkillStop, Status
from strug_manip.control.plan import Line, SkillPlan
from strug_manip.robot.fetch import ARM_TORSO_JOINTS, BASE_JOINTS

#: Candidate base poses relative to the work point: (distance of the shoulder from the
#: work point along the work direction [m], lateral offset of the base [m], extra yaw
#: [rad]), in the order tried. Near the preferred :data:`PREFERRED_DISTANCE` first: with
#: the elbow bent the arm follows a pull toward the robot with small joint motions (a
#: stretched arm needs several times longer for the same pull, near its singularity).
PREFERRED_DISTANCE = 0.5
_DIST = (0.5, 0.6, 0.4, 0.7, 0.8, 0.9)
_LAT = (0.0, -0.15, 0.15, -0.3, 0.3)
_YAW = (0.0, 0.35, -0.35)
CANDIDATES: tuple[tuple[float, float, float], ...] = tuple(
    sorted(
        ((d, lat, y) for d in _DIST for lat in _LAT for y in _YAW),
        key=lambda c: abs(c[0] - PREFERRED_DISTANCE) + 0.5 * abs(c[1]) + 0.3 * abs(c[2]),
    )
)
#: Of the candidates that work, the first this many are compared and the one whose
#: lines take the least time (the joint driver's timing law) is taken.
COMPARED = 3
#: Why a candidate fails when its pre-grasp has the hand (or the object it holds) in
#: the scene: the hand's pose is the plan's, whichever base the arm reaches it from,
#: so every other base of that plan fails alike (to the IK's tolerance) and is not
#: tried; this was two thirds of the planning twin's time on a cabinet whose believed
#: part the hand cannot get at.
HAND_IN_COLLISION = "pre-grasp hand in collision"
#: Why a candidate fails when a line takes the hand (or the held object) into the
#: scene deeper than :data:`LINE_HAND_DEPTH`: as at the pre-grasp, the hand's poses
#: along the lines are the plan's whichever base the arm follows them from, so no other
#: base of that plan is tried.
LINE_HAND_IN_COLLISION = "line hand in collision"
#: Depth [m] beyond which a line's hand contact with the scene is taken as the plan's,
#: not the IK's: the tracked poses miss the plan's by up to the tracking tolerance
#: (:meth:`FetchIK.track`'s ``pos_tol``), so a shallower graze may come and go with the
#: base; how little the depth varies between one plan's bases is measured in the
#: README ("Manipulation tasks").
LINE_HAND_DEPTH = 0.002
#: Forward offset of the shoulder pan axis from the base centre [m] (fetch.xml).
SHOULDER_FORWARD = 0.0326
#: Relative cost of base motion in whole-body lines [-].
BASE_COST = 10.0
#: Lines whose motion the base may join (the part-moving ones).
WHOLE_BODY_LINES = ("move", "ease", "probe", "withdraw")
#: How much longer a planned detour takes than the straight joint-space line [-]
#: (RRTConnect's simplified paths around the robot's own body and the cabinet).
DETOUR = 3.0
#: Shortest duration of a line [s] (the driver's too).
MIN_LINE_TIME = 0.3
#: At most this many candidates are tried [-] (the search stops at the first success).
MAX_CANDIDATES = 40


@dataclass(frozen=True, eq=False)
class Placement:
    """Where the base stands and the joint paths of a skill from there.

    Attributes:
        base: base pose (x [m], y [m], yaw [rad]) at the pre-grasp.
        q_pre: torso + arm at the pre-grasp, (8,) [m, rad].
        lines: per :class:`Line` of the plan, torso + arm along it, (N, 8).
        base_paths: per line, the base pose along it (N, 3) where the base moves
            (whole-body lines), else None.
        tried: candidates tried; reasons: why the rejected ones failed (counts).
        seconds: wall time of the search [s].
        plan: the plan these paths execute (the one asked for, or it with the
            fingers swapped, :meth:`SkillPlan.flipped`).
        alternatives: the other placements that worked, next best first (e.g. where
            the free motion to this one finds no plan).
        candidate: which candidate this is: (index into :data:`CANDIDATES`, fingers
            swapped), a hint for a search of a similar plan (:func:`find_placement`).
    """

    base: np.ndarray
    q_pre: np.ndarray
    lines: tuple[np.ndarray, ...]
    base_paths: tuple[np.ndarray | None, ...]
    tried: int
    reasons: dict[str, int]
    seconds: float
    plan: SkillPlan
    alternatives: tuple[Placement, ...] = ()
    candidate: tuple[int, bool] = (0, False)

    def start_of(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """(base (3,), torso + arm (8,)) where line ``k`` starts."""
        if k == 0:
            return self.base, self.q_pre
        prev = self.base_paths[k - 1]
        base = prev[-1] if prev is not None else self.start_of(k - 1)[0]
        return base, self.lines[k - 1][-1]


#: Plans whose work points are this close share a placement hint [m] (the same part
#: in two belief particles: their handles lie within a few centimetres).
HINT_RADIUS = 0.05
#: Hints kept (the most recent first).
MAX_HINTS = 256


class Hint(NamedTuple):
    """What a placement that worked leaves for a similar plan's search: its candidate
    (:attr:`Placement.candidate`) and its pre-grasp torso + arm (8,)."""

    candidate: tuple[int, bool]
    q_pre: np.ndarray


class PlacementHints:
    """Which candidate worked for recent plans, to try first for a similar plan
    (``find_placement(like=...)``): the same skill, carrying or not, from the same base
    pose (to 1 cm, 0.02 rad), its work point within :data:`HINT_RADIUS`."""

    def __init__(self) -> None:
        self._hints: list[tuple[tuple, np.ndarray, Hint]] = []

    @staticmethod
    def _kind(plan: SkillPlan, robot_base: np.ndarray) -> tuple:
        b = np.asarray(robot_base, dtype=float)
        return (plan.skill, plan.carrying is not None, *np.round(b[:2], 2), round(b[2] / 0.02))

    def get(self, plan: SkillPlan, robot_base: np.ndarray) -> Hint | None:
        """The hint of the latest similar plan, or None."""
        kind = self._kind(plan, robot_base)
        work = work_frame(plan, robot_base)[0]
        for k, w, hint in self._hints:
            if k == kind and np.linalg.norm(w - work) < HINT_RADIUS:
                return hint
        return None

    def put(self, plan: SkillPlan, robot_base: np.ndarray, found: Placement) -> None:
        """Remember that ``found`` worked for ``plan`` (not ``found`` itself: what the
        twins derive from a placement lives as long as it does)."""
        hint = Hint(found.candidate, found.q_pre.copy())
        entry = (self._kind(plan, robot_base), work_frame(plan, robot_base)[0], hint)
        self._hints.insert(0, entry)
        del self._hints[MAX_HINTS:]


def work_frame(plan: SkillPlan, robot_base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The work point (3,) [m] and the unit horizontal work direction (2,) of ``plan``."""
    poses = [plan.pre, *[T for line in plan.lines for T in line.poses]]
    points = np.array([T[:3, 3] for T in poses])
    work = points.mean(axis=0)
    approach = np.mean([T[:3, 0] for T in poses], axis=0)
    flat = approach[:2]
    if np.linalg.norm(flat) < 0.3:
        flat = work[:2] - robot_base[:2]
    n = float(np.linalg.norm(flat))
    return work, (flat / n if n > 1e-9 else np.array([1.0, 0.0]))


def candidate_bases(plan: SkillPlan, robot_base: np.ndarray) -> list[np.ndarray]:
    """Base poses to try for ``plan``, best first (see :data:`CANDIDATES`)."""
    work, f = work_frame(plan, robot_base)
    left = np.array([-f[1], f[0]])
    yaw0 = math.atan2(f[1], f[0])
    out = []
    for d, lat, dyaw in CANDIDATES[:MAX_CANDIDATES]:
        xy = work[:2] - (d + SHOULDER_FORWARD) * f + lat * left
        out.append(np.array([xy[0], xy[1], yaw0 + dyaw]))
    return out


def _plan_level(why: str) -> bool:
    """Whether a candidate's failure ``why`` holds for every base of its plan."""
    return why == HAND_IN_COLLISION or why.endswith(LINE_HAND_IN_COLLISION)


def _line_hits(checker: ContactChecker, line: Line, qs: np.ndarray, bases: np.ndarray) -> float:
    """Whether a tracked line meets the scene (hand with ``line.touch`` allowed; the
    believed part moved along, then put back): -1 if free, else how deep the hand is in
    the scene at the first pose with a forbidden contact [m] (0: another body's)."""
    touch = [checker.body_id(b) for b in line.touch]
    checker.allow(checker.hand_with(touch))
    moving = line.part_joint is not None and line.part_q is not None
    q0 = checker.get(line.part_joint) if moving else 0.0
    try:
        for k in range(len(qs)):
            if moving:
                checker.set({line.part_joint: float(line.part_q[k])})
            if not checker.free(np.concatenate([bases[k], qs[k]])):
                return checker.hand_depth()
        return -1.0
    finally:
        if moving:
            checker.set({line.part_joint: q0})
        checker.allow()


def line_seconds(
    plan: SkillPlan, placement: Placement, speeds: tuple[np.ndarray, np.ndarray]
) -> float:
    """Total time [s] of the plan's lines from ``placement`` under the timing law, with
    ``speeds`` = (torso + arm speed limits (8,), base speed limits (3,))."""
    total = 0.0
    for k, line in enumerate(plan.lines):
        base0, q0 = placement.start_of(k)
        T = timing.duration(
            timing.polyline(q0, placement.lines[k]),
            speeds[0],
            max(MIN_LINE_TIME, line.length / line.speed),
        )
        bp = placement.base_paths[k]
        if bp is not None:
            T = timing.duration(timing.polyline(base0, bp), speeds[1], T)
        total += T
    return total


def find_placement(
    plan: SkillPlan,
    ik: FetchIK,
    wb_ik: FetchIK,
    robot_base: np.ndarray,
    postures: tuple[np.ndarray, np.ndarray],
    speeds: tuple[np.ndarray, np.ndarray],
    checker: ContactChecker | None = None,
    like: Hint | None = None,
) -> Placement:
    """A base pose of :func:`candidate_bases` from which ``plan`` is reachable: of the
    first :data:`COMPARED` that work, the one whose reach and lines take the least
    time; or the candidate ``like`` took alone, if it works.

    Args:
        plan: the skill's gripper motions.
        ik: the arm's IK (torso + arm); wb_ik: the whole-body IK (base + torso + arm).
        robot_base: the base's pose now (x, y, yaw).
        postures: torso + arm (8,) as the robot drives (the tuck) and where its
            reach to the pre-grasp starts (the posture it arrives in; the IK starts
            there too, and the reach's time counts): the base pose must be free with
            either.
        speeds: the speed limits of torso + arm (8,) and of the base (3,), which time
            the reach and the lines (:func:`line_seconds`).
        checker: contacts in the planning world over base + torso + arm, loaded with
            its state (the carried object attached if any); None: kinematic only.
        like: the hint of a similar plan's placement (the same skill on the same part in
            another belief particle, centimetres apart): its candidate is tried first,
            the pre-grasp IK starting from its pre-grasp configuration, and taken as it
            is if it works (one try instead of a dozen, at the price of not comparing
            it with others).

    Raises:
        SkillStop: ``ik_infeasible``, no candidate works (the reasons counted).
    """
    t0 = time.perf_counter()
    reasons: dict[str, int] = {}
    tried = 0
    plans = (plan, plan.flipped())  # the fingers swapped if need be
    first = None if like is None else like.candidate
    hand_blocked: set[int] = set()  # the flips whose pre-grasp puts the hand in the scene
    if like is not None:
        index, flip = like.candidate
        tried += 1
        candidate = plans[int(flip)]
        base = candidate_bases(candidate, robot_base)[index]
        why, found = _try(candidate, ik, wb_ik, base, postures, speeds, checker, like.q_pre)
        if found is not None:
            return Placement(base, *found, tried, {}, time.perf_counter() - t0, candidate,
                             candidate=(index, bool(flip)))  # fmt: skip
        reasons[why] = 1
        if _plan_level(why):
            hand_blocked.add(int(flip))
    works: list[tuple[float, int, Placement]] = []
    for flip, candidate in enumerate(plans):
        if flip in hand_blocked:
            continue
        for index, base in enumerate(candidate_bases(candidate, robot_base)):
            if (index, bool(flip)) == first:
                continue
            tried += 1
            why, found = _try(candidate, ik, wb_ik, base, postures, speeds, checker)
            if found is None:
                reasons[why] = reasons.get(why, 0) + 1
                if _plan_level(why):
                    break
                continue
            q_pre, lines, bases = found
            p = Placement(base, q_pre, lines, bases, tried, {}, 0.0, candidate,
                          candidate=(index, bool(flip)))  # fmt: skip
            seconds = _free_seconds(p, postures, speeds[0], checker)
            works.append((seconds + line_seconds(candidate, p, speeds), tried, p))
            if len(works) == COMPARED:
                break
        if works:
            break
    if works:
        ranked = [w[2] for w in sorted(works, key=lambda w: (w[0], w[1]))]
        return dataclasses.replace(
            ranked[0],
            tried=tried,
            reasons=dict(reasons),
            seconds=time.perf_counter() - t0,
            alternatives=tuple(ranked[1:]),
        )
    summary = ", ".join(f"{k}: {v}" for k, v in sorted(reasons.items(), key=lambda kv: -kv[1]))
    raise SkillStop(
        Status.IK_INFEASIBLE,
        f"no base pose of {tried} reaches the skill, fingers either way ({summary})",
        "plan",
    )


def _free_seconds(
    p: Placement,
    postures: tuple[np.ndarray, np.ndarray],
    speeds: np.ndarray,
    checker: ContactChecker | None,
) -> float:
    """Estimated time [s] of the free motions: from the reach's start to the pre-grasp,
    and from the last line's end back to the driving posture; each straight joint-space
    line that is not free (with a checker) counts :data:`DETOUR` times longer (a
    planned detour)."""
    total = 0.0
    end_base, end_q = p.start_of(len(p.lines))
    for base, qa, qb in ((p.base, postures[1], p.q_pre), (end_base, end_q, postures[0])):
        t = timing.duration(np.array([qa, qb]), speeds, 0.0)
        if checker is not None:
            checker.allow()
            if checker.segment(np.concatenate([base, qa]), np.concatenate([base, qb])):
                t *= DETOUR
        total += t
    return total


def _try(
    plan: SkillPlan,
    ik: FetchIK,
    wb_ik: FetchIK,
    base: np.ndarray,
    postures: tuple[np.ndarray, np.ndarray],
    speeds: tuple[np.ndarray, np.ndarray],
    checker: ContactChecker | None,
    warm: np.ndarray | None = None,
) -> tuple[str, tuple | None]:
    """Why ``base`` fails (``""`` and ``(q_pre, lines, base paths)`` if it works).

    The pre-grasp IK starts from the arm posture the reach starts from and from the
    IK's ready posture; of the solutions, the one the arm reaches soonest is tried.
    Given a ``warm`` start (torso + arm (8,), a similar plan's pre-grasp), from there
    alone, unless it finds none."""
    drive_q, reach_q = postures
    base_q = dict(zip(BASE_JOINTS, base.tolist(), strict=True))
    if checker is not None:
        checker.allow()
        # The robot arrives in the reach's start (carrying, its carry posture, which
        # reaches where the tuck does not: into a drawer it opened, held-out 9306).
        # (Tucked, the two are one posture: checked once.)
        arrive = (drive_q,) if np.array_equal(drive_q, reach_q) else (drive_q, reach_q)
        if not all(checker.free(np.concatenate([base, q])) for q in arrive):
            return "base blocked", None
    solutions = []
    for seed in (warm,) if warm is not None else (reach_q, None):
        init = {**base_q, "torso_lift_joint": _torso_for(plan.pre)}
        if seed is not None:
            init.update(zip(ARM_TORSO_JOINTS, seed.tolist(), strict=True))
        res = ik.solve(plan.pre, init)
        if res.success:
            q = np.array([res.q[j] for j in ARM_TORSO_JOINTS])
            solutions.append((timing.duration(np.array([reach_q, q]), speeds[0], 0.0), q))
    if not solutions and warm is not None:
        return _try(plan, ik, wb_ik, base, postures, speeds, checker)
    if not solutions:
        return "pre-grasp unreachable", None
    q_pre = min(solutions, key=lambda s: s[0])[1]
    if checker is not None:
        checker.allow()
        hits = checker.pairs(np.concatenate([base, q_pre]))
        if len(hits):
            why = HAND_IN_COLLISION if checker.hand_in_scene(hits) else "pre-grasp in collision"
            return why, None
    lines, bases = [], []
    b, q = base, q_pre
    for line in plan.lines:
        start = {
            **dict(zip(BASE_JOINTS, b.tolist(), strict=True)),
            **dict(zip(ARM_TORSO_JOINTS, q.tolist(), strict=True)),
        }
        tr = ik.track(line.poses, start)
        if tr.success:
            qs, bs, moved = tr.q, np.repeat(b[None], len(tr.q), axis=0), None
        elif line.name in WHOLE_BODY_LINES:
            wb = wb_ik.track(line.poses, start)
            if not wb.success:
                return f"{line.name} line unreachable", None
            qs, bs = wb.q[:, 3:], wb.q[:, :3]
            moved = bs
        else:
            return f"{line.name} line unreachable", None
        if checker is not None and (depth := _line_hits(checker, line, qs, bs)) >= 0.0:
            if depth > LINE_HAND_DEPTH:
                return f"{line.name} {LINE_HAND_IN_COLLISION}", None
            return f"{line.name} line in collision", None
        lines.append(qs)
        bases.append(moved)
        b, q = bs[-1], qs[-1]
    return "", (q_pre, tuple(lines), tuple(bases))


def _torso_for(T: np.ndarray) -> float:
    """A torso height to start the IK from: the shoulder 0.1 m above the target [m]
    (the shoulder is 0.726 m high with the torso down)."""
    return float(np.clip(T[2, 3] + 0.1 - 0.726, 0.0, 0.38))
