"""Robot control: the paper's seven skills on the Fetch and on their planning twin.

- :mod:`.skills`: ``OpenDrawer``, ``OpenDoor``, ``Push``, ``PullV``, ``PullH``,
  ``Pick``, ``Place`` (each a frozen dataclass of its parameters; ``run`` on the full
  robot, ``simulate`` on a :class:`~strug_manip.control.twin_body.PlanningTwin`);
- :mod:`.outcome`: the facts a skill reports (:class:`Outcome`, :class:`Status`);
- :mod:`.params`: the skills' constants (:class:`SkillParams`);
- :mod:`.grasps`, :mod:`.targets`: grasp poses of handles, where the object goes;
- :mod:`.plan`, :mod:`.placement`: a skill as gripper motions, where the base stands;
- :mod:`.executor`: the executor core both bodies share (the stop rules, the stow, the
  outcome) and their interface (:class:`~.executor.Body`);
- :mod:`.fetch_body`: the full robot (:class:`FullRobot`), whose opening hand gives way
  across its path (:mod:`.compliance`); :mod:`.twin_body`,
  :mod:`.twin_program`, :mod:`.twin_rollout`, :mod:`.twin_servo`, :mod:`.rotations`:
  the planning twin (:class:`PlanningTwin`, its programs, rollouts, servo model);
- :mod:`.ik` (its limits :mod:`.ik_limits`, its QP :mod:`.ik_qp`), :mod:`.motion`,
  :mod:`.contacts`, :mod:`.navigation`, :mod:`.driver`, :mod:`.timing`: inverse
  kinematics (mink), arm motion planning (OMPL), the robot's contacts, base routes, the
  joint driver, the one timing law;
- :mod:`.context`: the solvers and caches skills share (:class:`ControlContext`).
"""

from strug_manip.control.context import ControlContext
from strug_manip.control.fetch_body import FullRobot
from strug_manip.control.grasps import flip_fingers, handle_grasps, held_grasp
from strug_manip.control.outcome import STATUSES, Outcome, Status
from strug_manip.control.params import DEFAULT_PARAMS, SkillParams
from strug_manip.control.plan import Grip, Line, SkillPlan
from strug_manip.control.skills import (
    OpenDoor,
    OpenDrawer,
    Pick,
    Place,
    PullH,
    PullV,
    Push,
    Skill,
    part_at,
)
from strug_manip.control.targets import PlaceTarget, place_target, place_targets
from strug_manip.control.twin_body import PlanningTwin, run_batch

__all__ = [
    "DEFAULT_PARAMS",
    "STATUSES",
    "ControlContext",
    "FullRobot",
    "Grip",
    "Line",
    "OpenDoor",
    "OpenDrawer",
    "Outcome",
    "Pick",
    "Place",
    "PlaceTarget",
    "PlanningTwin",
    "PullH",
    "PullV",
    "Push",
    "Skill",
    "SkillParams",
    "SkillPlan",
    "Status",
    "flip_fingers",
    "handle_grasps",
    "held_grasp",
    "part_at",
    "place_target",
    "place_targets",
    "run_batch",
]
