"""The solvers and caches the skills share, owned by one explicit object.

A :class:`ControlContext` holds what is expensive to build and holds no per-run state:
the arm's and the whole body's IK (mink, on the robot-only model), an OMPL planner and
a contact checker per scene model, and a cache of base placements (a placement depends
only on the plan, where the base starts and the planning world's model). Build one and
pass it to every skill run (``ctx=...``); a run without one uses a context of its own.
Tests inject a context with other solvers or options instead of patching modules.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Hashable
from typing import TYPE_CHECKING, Any

import mujoco

from strug_manip.cache import LRU
from strug_manip.control.contacts import ContactChecker
from strug_manip.control.ik import FetchIK
from strug_manip.control.motion import ArmMotionPlanner
from strug_manip.control.outcome import SkillStop
from strug_manip.control.placement import BASE_COST, Placement, PlacementHints
from strug_manip.robot.fetch import ARM_TORSO_JOINTS, BASE_JOINTS

if TYPE_CHECKING:
    from strug_manip.world.sim import ManipulationWorld

#: Per scene model: the model, its planners (first, fallback) and its contact checker.
_Entry = tuple[mujoco.MjModel, tuple[ArmMotionPlanner, ArmMotionPlanner], ContactChecker]
#: The OMPL planners tried in turn: RRTConnect (fast where the space is open), then
#: LBKPIECE1 (finds the narrow passages out of the carry posture where RRTConnect,
#: with an object in the hand, often does not).
PLANNERS = ("RRTConnect", "LBKPIECE1")


class ControlContext:
    """Shared solvers and caches of the skills.

    Args:
        ik: the arm's key-pose and line IK (default: torso + arm, 3 restarts, seed 0).
        wb_ik: the whole-body IK (default: base + torso + arm, base motion
            :data:`~strug_manip.control.placement.BASE_COST` times dearer).
        max_models: scene models whose planner and checker are kept (least recently
            used ones are dropped: e.g. the worlds of discarded belief particles).
        max_placements: placements kept.
    """

    def __init__(
        self,
        ik: FetchIK | None = None,
        wb_ik: FetchIK | None = None,
        max_models: int = 16,
        max_placements: int = 4096,
    ) -> None:
        self.ik = ik or FetchIK(restarts=3, seed=0)
        self.wb_ik = wb_ik or FetchIK(include_base=True, base_cost=BASE_COST, restarts=0)
        self.max_models = max_models
        self.max_placements = max_placements
        self._per_model = LRU(max_models)
        self._placements = LRU(max_placements)
        #: Candidates that worked for recent plans (the planning twins' searches).
        self.hints = PlacementHints()
        # One token per planning world (placement keys), and what is derived from a
        # placement in a planning world alone (the stow's plan), shared by every twin
        # and dropped with the world or the placement.
        self._tokens: weakref.WeakKeyDictionary[ManipulationWorld, object] = (
            weakref.WeakKeyDictionary()
        )
        self._derived: weakref.WeakKeyDictionary[Placement, dict] = weakref.WeakKeyDictionary()

    def world_token(self, world: ManipulationWorld) -> object:
        """A key for ``world`` in the placement cache: an object made for it (not its
        id, which a later world may reuse once it is gone); the same for every twin
        that plans in ``world``."""
        return self._tokens.setdefault(world, object())

    def derived(self, placement: Placement, key: Hashable, compute: Callable[[], Any]) -> Any:
        """What ``compute()`` gave for ``placement`` and ``key`` before, else its result,
        kept as long as the placement lives (keyed by the object: one the placement
        cache lets go takes what was derived from it along)."""
        table = self._derived.setdefault(placement, {})
        if key not in table:
            table[key] = compute()
        return table[key]

    def _entry(
        self, model: mujoco.MjModel
    ) -> tuple[mujoco.MjModel, ArmMotionPlanner, ContactChecker]:
        key = id(model)
        entry = self._per_model.lookup(key)
        if entry is None or entry[0] is not model:
            entry = (
                model,
                tuple(ArmMotionPlanner(model, planner=name) for name in PLANNERS),
                ContactChecker(model, (*BASE_JOINTS, *ARM_TORSO_JOINTS)),
            )
            self._per_model.store(key, entry)
        return entry

    def planners(self, model: mujoco.MjModel) -> tuple[ArmMotionPlanner, ...]:
        """The OMPL planners of torso + arm in ``model``, to try in turn
        (:data:`PLANNERS`)."""
        return self._entry(model)[1]

    def checker(self, model: mujoco.MjModel) -> ContactChecker:
        """The contact checker of ``model`` over base + torso + arm (its scratch state is
        whatever the last user loaded: load it before use)."""
        return self._entry(model)[2]

    @property
    def placement_hits(self) -> int:
        """Placement lookups served from the cache."""
        return self._placements.hits

    @property
    def placement_misses(self) -> int:
        """Placement lookups that found nothing."""
        return self._placements.misses

    def cached_placement(self, key: Hashable) -> Placement | SkillStop | None:
        """A placement found before for ``key`` (or the ``ik_infeasible`` stop of a
        search that found none), or None."""
        return self._placements.lookup(key)

    def store_placement(self, key: Hashable, placement: Placement | SkillStop) -> None:
        """Keep ``placement`` (or the stop of a failed search) for ``key`` (oldest
        dropped beyond ``max_placements``)."""
        self._placements.store(key, placement)

    def placement(self, key: Hashable, search: Callable[[], Placement]) -> Placement:
        """The placement cached for ``key``, else ``search()``'s (cached, as is the
        :class:`SkillStop` it raises when it finds none, which is raised again)."""
        found = self.cached_placement(key)
        if found is None:
            try:
                found = search()
            except SkillStop as stop:
                found = stop
            self.store_placement(key, found)
        if isinstance(found, SkillStop):
            raise found
        return found
