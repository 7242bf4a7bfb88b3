"""What a skill execution reports: facts, not a verdict.

A skill ends in an :class:`Outcome` (dm_robotics' ``OptionResult`` in spirit): how the
execution ended (:class:`Status`: it ran to the end, or why it stopped), and what the
world looks like afterwards: how far every cabinet part joint moved, in its own unit,
how far the cabinet base moved, where the object is, whether the fingers hold
something, and the timings. Whether a *task* succeeded (a drawer open far enough to put
the object in, the object inside, the cabinet dragged) is for the task to decide from
these facts (the manipulation domain), never for the skill.

Statuses, in the order a run can meet them:

- ``ok``: every phase ran to its end (a wrong model can still end ``ok``: the handle
  followed the gripper because the whole cabinet did), or an opening ended where its
  part stopped following the hand past half its path (its end, a limit no view
  shows; ``detail`` says where, ``phase`` is the line it stopped in);
- ``ik_infeasible``: no base placement from which the key poses and the Cartesian lines
  of the skill are reachable without collision (or, for the planning twin, reachable);
- ``no_motion_plan``: OMPL found no collision-free arm motion to the pre-grasp or back;
- ``grasp_lost``: the fingers closed on nothing while they should have held the handle
  or the object (the gripper's own reading: its finger travel);
- ``collision``: the gripper fell more than its tracking tolerance behind its path (the
  arm is blocked: by the part's real constraint, or by an obstacle the plan did not
  know);
- ``timeout``: the simulated time budget ran out.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np

from strug_manip.control.motion import GOAL_INVALID, NO_PLAN, WALL_CAP_HIT


class Status(StrEnum):
    """How a skill execution ended."""

    OK = "ok"
    IK_INFEASIBLE = "ik_infeasible"
    NO_MOTION_PLAN = "no_motion_plan"
    GRASP_LOST = "grasp_lost"
    COLLISION = "collision"
    TIMEOUT = "timeout"
    #: The cabinet slid more than ``SkillParams.cabinet_motion_limit``, or tipped more
    #: than ``SkillParams.cabinet_tilt_limit``, during the skill.
    CABINET_MOVED = "cabinet_moved"


#: Every status, as strings (the order above).
STATUSES: tuple[str, ...] = tuple(s.value for s in Status)


class SkillStop(Exception):  # noqa: N818 (control flow, not an error of the caller)
    """Raised inside an execution to stop it with a :class:`Status` (caught by the
    skill runner and turned into an :class:`Outcome`; never escapes a skill)."""

    def __init__(self, status: Status, detail: str, phase: str = "") -> None:
        super().__init__(detail)
        self.status, self.detail, self.phase = status, detail, phase


#: The phase of the way to the part: the stow before a drive, the drive, the reach to
#: the pre-grasp (:class:`~.fetch_body.FullRobot`; the planning twin's hand enters the
#: scene at the pre-grasp and has none).
REACH = "reach"


@dataclass(frozen=True, eq=False)
class Outcome:
    """The facts of one skill execution (full robot or planning twin).

    Attributes:
        skill: the skill's name (``OpenDrawer``, ...).
        status: how it ended (:class:`Status`).
        detail: a human-readable explanation ("" if nothing to add).
        phase: the phase it ended in (``plan``, ``reach``, ``approach``, ``grasp``,
            ``move``, ``release``, ``retreat``, ``stow``; "" when ``ok``).
        part_motion: change of every cabinet part joint during the run, by joint name
            [m for prismatic, rad for revolute joints: see ``part_units``].
        part_units: ``"m"`` or ``"rad"`` per joint of ``part_motion``.
        part_positions: every part joint's position at the end [m or rad].
        cabinet_displacement: horizontal distance of the cabinet base from where it
            stood at the episode's reset, at the end [m] (cumulative over skills).
        cabinet_motion: horizontal distance the cabinet base moved during this run [m].
        object_pose: ``T_world_object`` at the end, (4, 4) [m].
        holding: the fingers are closed on something at the end.
        times: recording times since the run started, shape (T,) [s].
        qpos: the world's ``qpos`` at those times, shape (T, nq) (robot, cabinet and
            object: enough to replay the run in a viewer).
        sim_time: simulated time of the run [s].
        wall_seconds: wall time of the run [s], of which ``ik_seconds`` (inverse
            kinematics and base placement), ``planning_seconds`` (OMPL and collision
            checks) and ``physics_seconds`` (MuJoCo stepping).
    """

    skill: str
    status: Status
    detail: str
    phase: str
    part_motion: dict[str, float]
    part_units: dict[str, str]
    part_positions: dict[str, float]
    cabinet_displacement: float
    cabinet_motion: float
    object_pose: np.ndarray
    holding: bool
    times: np.ndarray = field(repr=False)
    qpos: np.ndarray = field(repr=False)
    sim_time: float = 0.0
    wall_seconds: float = 0.0
    ik_seconds: float = 0.0
    planning_seconds: float = 0.0
    physics_seconds: float = 0.0

    @property
    def ok(self) -> bool:
        """The skill ran to its end (``status == ok``)."""
        return self.status is Status.OK

    @property
    def met_end(self) -> bool:
        """It ended ``ok`` because an opening's part met its end before the path's end
        (:func:`~.executor.at_part_end`; ``phase`` names the line it stopped in): the
        part stands at a limit no view shows."""
        return self.status is Status.OK and self.phase != ""

    @property
    def on_the_way(self) -> bool:
        """It stopped after the robot moved but before the hand reached the part: the
        arm, or what it carries, met something in the drive or the reach
        (``cabinet_moved``, ``collision``). What the part would have done is not
        shown."""
        return self.phase == REACH and self.status in (Status.CABINET_MOVED, Status.COLLISION)

    @property
    def cannot_reach(self) -> bool:
        """It stopped before anything moved because its grasp or placement cannot be
        reached: no base pose and arm reach it (``ik_infeasible``), or where they
        would, the arm or what it carries touches the cabinet it plans against
        (``no_motion_plan``, the motion plan's goal invalid at every base pose tried),
        or the motion plan's search spent its checks without a way there (a goal in a
        narrow gap: two level places in a drawer out 15.5 cm under another timed out
        where the place nearest the drawer's front, tried after them, was reached;
        oracle OpenDrawer episode 9983). Another grasp or placement of the same action
        may be reached either way; a start in contact is no fault of the placement,
        and a search the wall-clock cap stopped is the machine's load's, not the
        goal's."""
        if self.status is Status.IK_INFEASIBLE:
            return True
        if self.status is not Status.NO_MOTION_PLAN or WALL_CAP_HIT in self.detail:
            return False
        return self.detail.startswith((GOAL_INVALID, NO_PLAN))

    def motion_of(self, joint: str) -> float:
        """``part_motion`` of ``joint`` (with or without the ``cabinet/`` prefix)."""
        if joint in self.part_motion:
            return self.part_motion[joint]
        for name, v in self.part_motion.items():
            if name.endswith("/" + joint):
                return v
        raise KeyError(f"no cabinet joint {joint!r}; the run reports {sorted(self.part_motion)}")

    def same_as(self, other: Outcome) -> bool:
        """Equal in everything but the wall-clock timings."""
        return (
            self.skill == other.skill
            and self.status == other.status
            and self.detail == other.detail
            and self.phase == other.phase
            and self.part_motion == other.part_motion
            and self.cabinet_displacement == other.cabinet_displacement
            and np.array_equal(self.object_pose, other.object_pose)
            and self.holding == other.holding
            and np.array_equal(self.qpos, other.qpos)
            and self.sim_time == other.sim_time
        )

    def summary(self) -> str:
        """One line: status, the largest part motion, the cabinet's displacement."""
        moved = max(self.part_motion.items(), key=lambda kv: abs(kv[1]), default=("-", 0.0))
        unit = self.part_units.get(moved[0], "")
        return (
            f"{self.skill}: {self.status.value}"
            + (f" ({self.detail})" if self.detail else "")
            + f"; {moved[0]} moved {moved[1]:+.3f} {unit}"
            + f"; cabinet {self.cabinet_displacement:.3f} m"
        )
