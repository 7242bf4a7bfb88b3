"""The Random baseline: a uniform action every step (no search)."""

from __future__ import annotations

import time
from collections.abc import Hashable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from planners.belief import ParticleBelief
from planners.pomdp import GenerativePOMDP, check_pomdp
from planners.solvers.base import SearchInfo, SolverConfig


@dataclass(frozen=True)
class RandomConfig(SolverConfig):
    """Uniformly random actions: a uniform schema, then uniform parameters in its box.

    The budget fields are accepted (so one command line fits every solver) and unused.
    """

    name: ClassVar[str] = "random"

    def planner(self, pomdp: GenerativePOMDP) -> RandomPlanner:
        return RandomPlanner(pomdp)


class RandomPlanner:
    """Draws a uniform action from the domain's action space."""

    def __init__(self, pomdp: GenerativePOMDP) -> None:
        check_pomdp(pomdp)
        self.space = pomdp.action_space()

    def act(self, belief: ParticleBelief, rng: np.random.Generator) -> tuple[Hashable, SearchInfo]:
        t0 = time.perf_counter()
        a = self.space.sample(rng)
        return a, SearchInfo(seconds=time.perf_counter() - t0)
