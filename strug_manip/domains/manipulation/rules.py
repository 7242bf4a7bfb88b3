"""What the manipulation tasks count as success and failure, from a skill's facts.

The skills report facts (:class:`~strug_manip.control.outcome.Outcome`); the tasks
judge them here, in the units of each part:

- a part is **open enough** when the object can be put into it as it now stands: an
  open drawer's box far enough out of the carcass, a door or flap far enough out of
  its cell's opening (:func:`~strug_manip.control.targets.place_target` finds room for
  the object and the fingers);
- the object is **inside** a part when its centre lies in the part's interior box (a
  drawer's moves with it) and it rests there (not held);
- the cabinet is **dragged** when its base has moved more than :data:`DRAG_LIMIT` from
  where it stood at the start of the episode (the paper's -10, cumulative over the
  skills of an episode).
"""

from __future__ import annotations

import numpy as np

from planners.errors import ConfigError
from strug_manip.control import Status, place_target
from strug_manip.domains.manipulation.state import NOT_APPLICABLE, STATUS_CODES
from strug_manip.objects.generator import CabinetSpec

#: The cabinet base moved more than this from where it stood [m]: the paper's failure.
DRAG_LIMIT = 0.1
#: The outcomes of an action that could not start (nothing moved): no base and arm
#: reach it, or its plan cannot be made in the model.
CANNOT_START = (str(Status.IK_INFEASIBLE), NOT_APPLICABLE)
#: The outcomes of an action that, tried again from nearly the same state against the
#: same model, ends the same way: it could not start; its grasp slipped off a handle
#: that does not turn about the joint it followed; it stopped because it slid the
#: cabinet (again, the slides add up to a drag). A ``collision`` or a missing motion
#: plan is not among them: the next attempt plans a new path.
REPEATS_ITSELF = (*CANNOT_START, str(Status.GRASP_LOST), str(Status.CABINET_MOVED))
#: The cabinet counts as changed past this, in any coordinate [m or rad] (its base's
#: pose, its parts'): more than a part drifts while the robot works elsewhere, or a
#: cabinet settles on its stand in a simulation (fractions of a millimetre). A refusal
#: stands while the cabinet is unchanged (:attr:`.real.RealEpisode.refused`), and an
#: opening's grasps follow a cabinet that has moved (:func:`.grounding.cabinet_frame`).
UNCHANGED = 0.01
#: The outcomes the full robot reaches before anything moves: every IK solution, route
#: and arm motion of a skill (the stow after it included) is found before it moves, in
#: the model it plans against (:meth:`.real.RealEnvironment.plan_models`), not in the
#: real cabinet. Such an outcome is a function of that model and of the planners'
#: budgets alone, so the real belief weighs it as no evidence and keeps its states as
#: they were: after a Place whose stow found no plan in time, the particles whose twins
#: placed the object would otherwise lose to those without the target part (their
#: twins could not start either), and an episode gave up on the right model.
BEFORE_MOTION = (*CANNOT_START, str(Status.NO_MOTION_PLAN))
#: Their status codes, as observation keys carry them.
BEFORE_MOTION_CODES = frozenset(STATUS_CODES[x] for x in BEFORE_MOTION)


def dragged(displacement: float) -> bool:
    """The cabinet's base is more than :data:`DRAG_LIMIT` from its start [m]."""
    return float(displacement) > DRAG_LIMIT


def open_enough(spec: CabinetSpec, link: str, q: float, T_world_object: np.ndarray) -> bool:
    """Whether the object fits into part ``link`` at joint position ``q`` [m or rad]
    (the cabinet frame at ``T_world_object``, (4, 4))."""
    try:
        place_target(spec, link, q, T_world_object)
    except ConfigError:
        return False
    return True


def inside(
    spec: CabinetSpec, link: str, q: float, T_world_object: np.ndarray, T_world_item: np.ndarray
) -> bool:
    """Whether the item at ``T_world_item`` (4, 4) has its centre in part ``link``'s
    interior (a drawer's at joint position ``q``), the cabinet frame at
    ``T_world_object``."""
    part = spec.part(link)
    if part.interior_center is None or part.interior_size is None:
        return False
    c = (np.linalg.inv(np.asarray(T_world_object)) @ np.r_[np.asarray(T_world_item)[:3, 3], 1.0])[
        :3
    ]
    center = (
        part.point_at(part.interior_center, q)
        if part.joint_type == "prismatic"
        else part.interior_center
    )
    return bool(np.all(np.abs(c - center) <= np.asarray(part.interior_size) / 2 + 1e-3))
