"""A skill as data: the gripper's key pose, Cartesian lines and grip commands.

A skill (:mod:`.skills`) turns its parameters into a :class:`SkillPlan`, which says
nothing about the body that executes it:

- ``pre``: the gripper pose reached by a free (collision-free, contact-free) motion;
- ``phases``: what follows, in order: :class:`Line` (the gripper follows a dense
  Cartesian path, possibly in contact) and :class:`Grip` (close or open the fingers).

The full robot (:class:`~strug_manip.control.fetch_body.FullRobot`) finds where its base
stands, solves the IK of every pose, plans the free motion with OMPL and drives there;
the planning twin (:class:`~strug_manip.control.twin_body.PlanningTwin`) places a floating
gripper at ``pre`` and runs the phases. Both time the lines with the same law
(:mod:`.timing`) and report the same :class:`~strug_manip.control.outcome.Outcome`.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True, eq=False)
class Line:
    """The gripper follows a dense Cartesian path.

    Attributes:
        name: the phase's name (``approach``, ``move``, ``retreat``, ``lift``, ...).
        poses: ``T_world_gripper`` along the path (excluding where it starts),
            shape (N, 4, 4) [m].
        length: TCP path length [m] (its duration is at least ``length / speed``).
        speed: TCP speed [m/s].
        touch: bodies the hand may touch along it (the part being grasped, the object).
        holding: the fingers hold something along it (a lost grasp stops the run).
        part_joint: the believed joint that moves with the gripper (planning checks
            move it along), or None.
        part_q: that joint's believed positions at the poses, shape (N,) [m or rad].
        tolerance: the gripper this far behind its command means the arm is blocked
            [m] (None: the skills' ``tracking_tolerance``; a probe's is smaller than its
            travel, so that a blocked probe says so).
    """

    name: str
    poses: np.ndarray
    length: float
    speed: float
    touch: frozenset[str] = frozenset()
    holding: bool = False
    part_joint: str | None = None
    part_q: np.ndarray | None = None
    tolerance: float | None = None


@dataclass(frozen=True)
class Grip:
    """Close (``closed``: squeeze whatever is between the fingers) or open the fingers."""

    closed: bool

    @property
    def name(self) -> str:
        """``grasp`` or ``release``."""
        return "grasp" if self.closed else "release"


Phase = Line | Grip


@dataclass(frozen=True, eq=False)
class SkillPlan:
    """One skill, as gripper motions (world frame).

    Attributes:
        skill: the skill's name.
        pre: the gripper pose reached by free motion first, (4, 4) [m].
        phases: what follows, in order.
        carrying: the object held from the start and ``T_gripper_object`` (4, 4), or
            None (it moves with the gripper in the motion plans).
        part: the cabinet part the skill operates (its link), or None.
    """

    skill: str
    pre: np.ndarray
    phases: tuple[Phase, ...]
    carrying: tuple[str, np.ndarray] | None = None
    part: str | None = None
    key: bytes = field(init=False, repr=False)

    def __post_init__(self) -> None:
        h = hashlib.sha1(self.skill.encode())
        h.update(np.ascontiguousarray(self.pre).tobytes())
        for p in self.phases:
            if isinstance(p, Grip):
                h.update(b"g1" if p.closed else b"g0")
            else:
                h.update(p.name.encode() + np.ascontiguousarray(p.poses).tobytes())
                h.update(np.float64(p.speed).tobytes())
        if self.carrying is not None:
            h.update(self.carrying[0].encode() + self.carrying[1].tobytes())
        object.__setattr__(self, "key", h.digest())

    def flipped(self) -> SkillPlan:
        """The same plan with the fingers swapped at every pose (the wrist turned half a
        turn about the approach): the same grasp for a parallel gripper."""
        flip = np.diag([1.0, -1.0, -1.0, 1.0])
        phases = tuple(
            p if isinstance(p, Grip) else dataclasses.replace(p, poses=p.poses @ flip)
            for p in self.phases
        )
        carrying = None
        if self.carrying is not None:
            carrying = (self.carrying[0], flip @ self.carrying[1])
        return SkillPlan(self.skill, self.pre @ flip, phases, carrying, self.part)

    @property
    def lines(self) -> tuple[Line, ...]:
        """The Cartesian lines, in order."""
        return tuple(p for p in self.phases if isinstance(p, Line))


# --- building lines ---------------------------------------------------------------------


def straight(T: np.ndarray, d: np.ndarray, step: float) -> tuple[np.ndarray, float]:
    """Poses from ``T`` (excluded) to ``T`` translated by ``d`` (3,) [m], every ~``step``
    [m]; returns ``(poses (N, 4, 4), length [m])``."""
    d = np.asarray(d, dtype=float)
    length = float(np.linalg.norm(d))
    n = max(2, math.ceil(length / step))
    poses = np.repeat(T[None], n, axis=0)
    poses[:, :3, 3] += np.outer(np.arange(1, n + 1) / n, d)
    return poses, length


def along(
    move: Callable[[np.ndarray, float], np.ndarray],
    T: np.ndarray,
    amount: float,
    radius: float,
    step: float,
) -> tuple[np.ndarray, float]:
    """Poses ``move(T, amount * k / n)`` for k = 1..n, every ~``step`` of TCP travel;
    ``radius`` converts ``amount`` into a length (1 for a translation [m], the TCP's
    distance from a hinge for a rotation [rad]). Returns ``(poses, length [m])``."""
    length = abs(amount) * radius
    n = max(2, math.ceil(length / step))
    poses = np.array([move(T, amount * k / n) for k in range(1, n + 1)])
    return poses, length


def line_of(name: str, poses: tuple[np.ndarray, float], speed: float, **kw: object) -> Line:
    """A :class:`Line` from ``(poses, length)`` (as :func:`straight` returns)."""
    return Line(name, poses[0], poses[1], speed, **kw)  # type: ignore[arg-type]


def retreat_poses(T: np.ndarray, distance: float, step: float) -> tuple[np.ndarray, float]:
    """Back off ``distance`` [m] from ``T`` against its approach axis (its x)."""
    return straight(T, -distance * T[:3, 0], step)


def stack(poses: Sequence[np.ndarray]) -> np.ndarray:
    """``poses`` as one (N, 4, 4) array."""
    return np.asarray(poses, dtype=float).reshape(-1, 4, 4)
