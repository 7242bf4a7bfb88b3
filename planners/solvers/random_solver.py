"""The Random baseline: a uniform action every step (no search)."""

from __future__ import annotations

import time
from collections.abc import Hashable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from planners.belief import ParticleBelief
from planners.pomdp import GenerativePOMDP, check_pomdp, legal_in, provides_applicable
from planners.solvers.base import SearchInfo, SolverConfig


@dataclass(frozen=True)
class RandomConfig(SolverConfig):
    """Uniformly random actions: a uniform schema, then uniform parameters in its box
    (a finite space: a uniform action among those the belief finds applicable).

    The budget fields are accepted (so one command line fits every solver) and unused.
    """

    name: ClassVar[str] = "random"

    def planner(self, pomdp: GenerativePOMDP) -> RandomPlanner:
        return RandomPlanner(pomdp)


class RandomPlanner:
    """Draws a uniform action from the domain's action space; on a finite space of a
    domain with its own ``applicable``, from the actions applicable in a weighted
    particle of the belief (all of them when none is)."""

    def __init__(self, pomdp: GenerativePOMDP) -> None:
        check_pomdp(pomdp)
        self.pomdp = pomdp
        self.space = pomdp.action_space()
        self.filter = provides_applicable(pomdp) and self.space.is_discrete

    def act(self, belief: ParticleBelief, rng: np.random.Generator) -> tuple[Hashable, SearchInfo]:
        t0 = time.perf_counter()
        if self.filter:
            keep = legal_in(self.pomdp, belief.states, belief.weights)
            actions = list(self.space.discretized)
            actions = [a for a in actions if keep(a)] or actions
            a = actions[int(rng.integers(len(actions)))]
        else:
            a = self.space.sample(rng)
        return a, SearchInfo(seconds=time.perf_counter() - t0)
