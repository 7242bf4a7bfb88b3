"""Collision-free arm motions between key configurations, planned with OMPL.

:class:`ArmMotionPlanner` plans in the joint space of the Fetch's torso and 7 arm
joints, with box bounds from the MuJoCo joint ranges. A configuration is valid if it
is within the ranges and free of forbidden robot contacts as the shared
:class:`~strug_manip.control.contacts.ContactChecker` sees them (loaded by the caller
with the world's state, the allowed pairs and any attached object); edges are checked
every :data:`CHECK_RESOLUTION` of joint-space distance.

If the straight joint-space line from start to goal is collision-free it is the plan
(no sampling; ``try_straight``). Otherwise the planner's path is shortened with OMPL's
``PathSimplifier`` (``simplifyMax``: reduce vertices, shortcut, collapse close
vertices; deterministic, unlike the time-bounded ``simplify``). A plan is a polyline of
waypoints; the joint driver times it (:mod:`~strug_manip.control.timing`).

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
same inputs and seed give the same waypoints, bit for bit, *whatever the machine's
load*: the planner's budget is work, not time. It stops after ``checks`` state validity
checks (counted in the validity callback, through a
``PlannerTerminationCondition`` OMPL evaluates once per iteration), not after a number
of seconds: a wall-time budget (``ss.solve(seconds)``) let a loaded machine's planner
give up where an idle one found a path (or find a different one), and the demo's
episode changed with the load (issue 37). A wall-clock ``timeout`` stays as a safety
cap that a normal plan never reaches; a plan it stops says so in ``detail``
(:data:`WALL_CAP_HIT`), the one way a plan still depends on the clock.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import mujoco
import numpy as np

from planners.errors import ConfigError, UnknownNameError, check_positive_float
from strug_manip.control.contacts import ContactChecker
from strug_manip.robot.fetch import ARM_TORSO_JOINTS

#: Joint-space distance between two collision checks along an edge [rad or m]: the
#: gripper, at most 1.1 m from the shoulder, moves at most 4.4 cm between two checks,
#: less than the thickness of any robot link, so no link passes through a board unseen.
CHECK_RESOLUTION = 0.04
#: Measured joint values this far outside their range are clipped onto it [rad or m]
#: (physics lets a servo push a joint a few milliradians past its soft limit under
#: load); further out is invalid.
LIMIT_TOLERANCE = 0.01
#: Range used for a joint without limits in the model [rad] (one turn each way).
UNLIMITED_RANGE = (-math.pi, math.pi)

#: :func:`escape_start`: random tries, and the largest nudge per arm joint [rad].
ESCAPE_TRIES, ESCAPE_RADIUS = 100, 0.3

#: Failure reasons of :class:`MotionPlan`.
START_INVALID = "start invalid"
GOAL_INVALID = "goal invalid"
NO_PLAN = "no plan within budget"
#: :attr:`MotionPlan.detail` of a plan the wall-clock safety cap stopped before its
#: check budget was spent (not reproducible on another machine or load).
WALL_CAP_HIT = "wall-clock cap reached before the check budget"

#: Default state validity checks of one planner's search [checks]: RRTConnect finds the
#: open motions in a few hundred; about 1.5 s on an idle core (12,000-15,000 checks per
#: second measured in the demo's scene: MuJoCo's collision detection of the Fetch and
#: the cabinet, and the callback's Python). The skills set their own
#: (``SkillParams.plan_checks`` and its kin).
DEFAULT_CHECKS = 20_000
#: Default wall-clock safety cap of one planner's search [s]: only a machine many times
#: slower than the one the budgets were sized on (or a stuck callback) reaches it.
DEFAULT_WALL_CAP = 60.0


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
        joints: the planned joints, the column order of ``waypoints``.
        waypoints: path vertices, shape (N, n) [rad or m], start first, goal last
            (N >= 2 on success; shape (0, n) on failure).
        path_length: joint-space (Euclidean) length of the simplified path [rad or m]
            (``nan`` on failure).
        planning_time: wall time of planning and simplification [s].
        reason: ``""`` on success, else :data:`START_INVALID`, :data:`GOAL_INVALID` or
            :data:`NO_PLAN`.
        detail: what made the start or goal invalid (contacts ``body1/body2``, or a
            joint outside its range), or the planner's status (and
            :data:`WALL_CAP_HIT` if the safety cap stopped it); ``""`` if nothing to add.
        checks: state validity checks the planner's search made (0 for a straight
            line or an invalid start or goal) [checks].
    """

    success: bool
    joints: tuple[str, ...]
    waypoints: np.ndarray
    path_length: float
    planning_time: float
    reason: str = ""
    detail: str = ""
    checks: int = 0


class ArmMotionPlanner:
    """Plans collision-free joint-space motions of the torso and arm (OMPL).

    Args:
        model: the world's MuJoCo model (robot + scene).
        joints: the joints to plan for (hinge or slide joints), in the column order of
            the plans (default: torso + the 7 arm joints).
        planner: OMPL geometric planner name: ``RRTConnect`` (default), ``RRT``,
            ``RRTstar``, ``InformedRRTstar``, ``AORRTC``, ``PRM``, ``PRMstar``,
            ``KPIECE1``, ``BKPIECE1``, ``LBKPIECE1``, ``BITstar``, ``FMT``, ``BFMT``
            (asymptotically optimal ones use the whole budget).
        check_resolution: joint-space distance between collision checks along an edge
            [rad or m] (default :data:`CHECK_RESOLUTION`).
        planner_range: the planner's maximum edge length [rad or m] (default: OMPL's
            choice, 20 % of the space's extent).
        simplify: shorten the path with ``PathSimplifier.simplifyMax`` (default True).
        try_straight: first check the straight joint-space line from start to goal
            and return it if it is collision-free, without planning (default True).

    Raises:
        UnknownNameError: a joint or a planner name is unknown (lists valid ones).
        ConfigError: a joint is not a hinge or slide, is repeated, or a number is not
            positive and finite.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        joints: Sequence[str] = ARM_TORSO_JOINTS,
        *,
        planner: str = "RRTConnect",
        check_resolution: float = CHECK_RESOLUTION,
        planner_range: float | None = None,
        simplify: bool = True,
        try_straight: bool = True,
    ) -> None:
        if not isinstance(model, mujoco.MjModel):
            raise ConfigError(f"model must be a mujoco.MjModel, got {type(model).__name__}")
        self.model = m = model
        all_joints = [m.joint(j).name for j in range(m.njnt)]
        if isinstance(joints, str):
            raise ConfigError(f"joints must be a sequence of joint names, got the str {joints!r}")
        self.joints: tuple[str, ...] = tuple(joints)
        if not self.joints:
            raise ConfigError("joints must name at least one joint to plan for")
        if len(set(self.joints)) != len(self.joints):
            raise ConfigError(f"joints must be distinct, got {list(self.joints)}")
        ok_types = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
        lo, hi = [], []
        for name in self.joints:
            jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name) if name else -1
            if jid < 0:
                raise UnknownNameError("MuJoCo joint", name, all_joints)
            if int(m.jnt_type[jid]) not in ok_types:
                raise ConfigError(f"joint {name!r} must be a hinge or slide joint to be planned")
            limited = bool(m.jnt_limited[jid])
            lo.append(float(m.jnt_range[jid, 0]) if limited else UNLIMITED_RANGE[0])
            hi.append(float(m.jnt_range[jid, 1]) if limited else UNLIMITED_RANGE[1])
        #: Lower and upper bounds per joint [rad or m], shape (n,) each.
        self.lower, self.upper = np.array(lo), np.array(hi)
        available = _planners()
        if planner not in available:
            raise UnknownNameError("OMPL planner", planner, sorted(available))
        self.planner_name = planner
        self._planner_cls = available[planner]
        self.check_resolution = check_positive_float("check_resolution", check_resolution)
        self.planner_range = (
            None if planner_range is None else check_positive_float("planner_range", planner_range)
        )
        self.simplify = bool(simplify)
        self.try_straight = bool(try_straight)

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

    def _why_invalid(self, x: np.ndarray, free: Validity) -> str:
        """``""`` if ``x`` is a valid configuration, else why not (limits, contacts)."""
        out = []
        for name, v, lo, hi in zip(self.joints, x, self.lower, self.upper, strict=True):
            if not lo <= v <= hi:
                out.append(f"{name}={v:.4g} outside [{lo:.4g}, {hi:.4g}]")
        if out:
            return "joint limits: " + ", ".join(out)
        hits = free.contacts(x)
        return "contacts: " + ", ".join(hits) if hits else ""

    def _clip_near_limits(self, x: np.ndarray) -> np.ndarray:
        lo, hi = self.lower - LIMIT_TOLERANCE, self.upper + LIMIT_TOLERANCE
        near = (x >= lo) & (x <= hi)
        return np.where(near, np.clip(x, self.lower, self.upper), x)

    def plan(
        self,
        q_start: Mapping[str, float],
        q_goal: Mapping[str, float],
        validity: Validity,
        *,
        checks: int = DEFAULT_CHECKS,
        timeout: float = DEFAULT_WALL_CAP,
        seed: int = 0,
    ) -> MotionPlan:
        """Plan a collision-free motion of :attr:`joints` from ``q_start`` to ``q_goal``.

        Args:
            q_start, q_goal: ``{joint: value}`` for every planned joint [rad or m];
                values within :data:`LIMIT_TOLERANCE` outside a range are clipped.
            validity: what is free: ``free(x)`` and ``contacts(x)`` of a planned
                configuration ``x`` (n,), e.g. :class:`ArmValidity` over a loaded
                :class:`~strug_manip.control.contacts.ContactChecker`.
            checks: the search's budget: it stops after this many state validity
                checks [checks] (the plan does not depend on the machine's speed or
                load; the straight-line check and simplification come on top).
            timeout: wall-clock safety cap of the search [s]: it also stops once this
                long has passed (``detail`` then says :data:`WALL_CAP_HIT`); set it
                far above what ``checks`` take, so that it never decides.
            seed: seed of OMPL's random numbers (an int in [0, 2**32 - 2]).

        Returns:
            A :class:`MotionPlan`; on failure ``success`` is False and ``reason`` says
            why (:data:`START_INVALID`, :data:`GOAL_INVALID`, :data:`NO_PLAN`).

        Raises:
            UnknownNameError: a joint name is not a planned joint.
            ConfigError: a value is missing or not finite, ``checks`` is not an int
                >= 1, ``timeout`` is not positive, ``seed`` is not an int in range.
        """
        x0 = self._clip_near_limits(self.vector(q_start, "q_start"))
        x1 = self._clip_near_limits(self.vector(q_goal, "q_goal"))
        if isinstance(checks, bool) or not isinstance(checks, int | np.integer) or checks < 1:
            raise ConfigError(f"checks must be an int >= 1 (validity checks), got {checks!r}")
        timeout = check_positive_float("timeout", timeout)
        if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
            raise ConfigError(f"seed must be an int, got {seed!r}")
        if not 0 <= int(seed) <= 2**32 - 2:
            raise ConfigError(f"seed must be in [0, 2**32 - 2], got {seed!r}")
        return self._plan(x0, x1, validity, _Budget(int(checks), timeout), int(seed))

    def _plan(
        self, x0: np.ndarray, x1: np.ndarray, validity: Validity, budget: _Budget, seed: int
    ) -> MotionPlan:
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou

        t0 = time.perf_counter()
        n = len(self.joints)

        def failed(reason: str, detail: str) -> MotionPlan:
            return MotionPlan(
                False, self.joints, np.zeros((0, n)), math.nan, time.perf_counter() - t0,
                reason, detail, budget.used,
            )  # fmt: skip

        why = self._why_invalid(x0, validity)
        if why:
            return failed(START_INVALID, why)
        why = self._why_invalid(x1, validity)
        if why:
            return failed(GOAL_INVALID, why)

        with _ompl_quiet("LOG_NONE"):
            ou.RNG.setSeed(seed + 1)  # OMPL replaces 0 by 1; it logs an error after the 1st
        with _ompl_quiet("LOG_WARN"):
            ss, si, start, goal = self._setup(ob, og, x0, x1, validity, budget)
            if self.try_straight and si.checkMotion(start, goal):
                # The straight joint-space line is free: nothing to plan or simplify.
                q = np.array([x0, x1])
                length = float(si.distance(start, goal))
            else:
                planner = self._planner_cls(si)
                if self.planner_range is not None and hasattr(planner, "setRange"):
                    planner.setRange(self.planner_range)
                ss.setPlanner(planner)
                budget.start()
                try:
                    status = ss.solve(ob.PlannerTerminationCondition(budget.spent))
                finally:
                    budget.stop()  # the simplifier's checks are not the search's
                if not ss.haveExactSolutionPath():
                    cap = f"; {WALL_CAP_HIT}" if budget.capped else ""
                    return failed(NO_PLAN, f"OMPL status: {status.asString()}{cap}")
                path = ss.getSolutionPath()
                if self.simplify:
                    og.PathSimplifier(si).simplifyMax(path)
                q = np.array([path.getState(i)[0:n] for i in range(path.getStateCount())])
                length = float(path.length())
        # Exact start and goal (OMPL copies them; keep the caller's values bit for bit).
        q[0], q[-1] = x0, x1
        detail = WALL_CAP_HIT if budget.capped else ""
        return MotionPlan(
            True, self.joints, q, length, time.perf_counter() - t0, "", detail, budget.used
        )

    def _setup(self, ob, og, x0: np.ndarray, x1: np.ndarray, validity: Validity, budget: _Budget):
        """OMPL's problem from ``x0`` to ``x1`` (a fresh ``SimpleSetup``, its space
        information, the start and goal states), its validity checks counted by
        ``budget`` while the search runs."""
        n = len(self.joints)
        space = ob.RealVectorStateSpace(n)
        bounds = ob.RealVectorBounds(n)
        for i in range(n):
            bounds.setLow(i, float(self.lower[i]))
            bounds.setHigh(i, float(self.upper[i]))
        space.setBounds(bounds)
        ss = og.SimpleSetup(space)
        lo, hi = self.lower, self.upper

        def is_valid(state) -> bool:  # OMPL's hot loop: ndarray methods, no wrappers
            budget.used += budget.running
            x = np.array(state[0:n])
            if (x < lo).any() or (x > hi).any():
                return False
            return validity.free(x)

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
        return ss, si, start, goal


class _Budget:
    """The search's budget: ``checks`` validity checks (counted while it runs), with a
    wall-clock safety cap of ``cap`` [s]; :meth:`spent` is OMPL's termination
    condition."""

    def __init__(self, checks: int, cap: float) -> None:
        self.checks, self.cap = checks, cap
        #: Checks counted so far, and what a check adds to it: 1 while the search runs,
        #: 0 before and after (the straight-line check and simplification are free).
        self.used, self.running = 0, 0
        self.deadline = math.inf
        #: The safety cap stopped the search.
        self.capped = False

    def start(self) -> None:
        """The search starts: count its checks, start the safety cap's clock."""
        self.running, self.deadline = 1, time.perf_counter() + self.cap

    def stop(self) -> None:
        """The search ended: checks no longer count."""
        self.running = 0

    def spent(self) -> bool:
        """Whether the search must stop (OMPL asks once per iteration): the checks are
        spent, or (the safety cap, recorded in :attr:`capped`) the wall time."""
        if self.used >= self.checks:
            return True
        if time.perf_counter() >= self.deadline:
            self.capped = True
        return self.capped


class Validity(Protocol):
    """What the planner asks of a configuration ``x`` of the planned joints."""

    def free(self, x: np.ndarray) -> bool:
        """No forbidden contact at ``x``."""
        ...

    def contacts(self, x: np.ndarray) -> list[str]:
        """The forbidden contacts at ``x`` (for messages)."""
        ...


class ArmValidity:
    """:class:`Validity` of torso + arm configurations with the base at ``base``, through
    a :class:`~strug_manip.control.contacts.ContactChecker` over base + torso + arm."""

    def __init__(self, checker: ContactChecker, base: np.ndarray) -> None:
        self.checker, self.base = checker, np.asarray(base, dtype=float)

    def free(self, x: np.ndarray) -> bool:
        return self.checker.free(np.concatenate([self.base, x]))

    def contacts(self, x: np.ndarray) -> list[str]:
        return self.checker.contacts(np.concatenate([self.base, x]))


def escape_start(
    q: np.ndarray,
    validity: ArmValidity,
    rng: np.random.Generator,
    bounds: tuple[np.ndarray, np.ndarray],
    tries: int = ESCAPE_TRIES,
    radius: float = ESCAPE_RADIUS,
) -> np.ndarray | None:
    """A configuration near torso + arm ``q`` (8,) that touches nothing, within
    ``bounds`` (lower, upper, each (8,)), for a plan whose start touches something;
    None if none of ``tries`` random nudges does.

    MoveIt's FixStartStateCollision adapter: the k-th nudge draws each arm joint (not
    the torso) uniformly within ``radius * k / tries`` [rad] of ``q``, clipped to the
    bounds, the smallest nudges first. The default 0.3 rad moves the hand up to about
    20 cm at full reach: enough to unwedge an upper arm pressed against a cabinet's
    top (smaller nudges left it there on a tuning episode); the robot reaches the
    nudged start by a straight move.
    """
    lower, upper = (np.asarray(b, dtype=float) for b in bounds)
    for k in range(1, tries + 1):
        r = radius * k / tries
        x = np.asarray(q, dtype=float) + np.r_[0.0, rng.uniform(-r, r, len(q) - 1)]
        x = np.clip(x, lower, upper)
        if validity.free(x):
            return x
    return None
