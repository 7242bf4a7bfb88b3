"""Entropy Regularized: belief-tree search whose reward pays for entropy reduction.

The paper's baseline (its eq. 3) augments the reward with ``beta * E[log b]``. Paid at
every step, that term is negative and would reward ending the episode early, so the
search here pays its potential-based form, ``beta * (H(b) - H(b'))``: the same
information incentive without a per-step penalty, on the same belief tree as STRUG
(the two differ only in what uncertainty they count). Entropies are estimated as in
:mod:`planners.entropy` (categorical for discrete states, a Gaussian fit for
continuous ones).
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from planners.belief import ParticleBelief
from planners.entropy import state_entropy
from planners.pomdp import GenerativePOMDP, check_pomdp
from planners.solvers.base import SearchInfo
from planners.solvers.belief_tree import (
    BeliefTreeConfig,
    EpisodeSteps,
    NodeValue,
    belief_tree_search,
    root_particles,
)


def entropy_value(pomdp: GenerativePOMDP) -> NodeValue:
    """The node value ``H(b)`` [nats] for ``pomdp``'s states."""

    def value(states: list[Any], w: np.ndarray) -> float:
        return state_entropy(pomdp, states, w)

    return value


@dataclass(frozen=True)
class EntropyConfig(BeliefTreeConfig):
    """Entropy Regularized hyper-parameters: those of :class:`BeliefTreeConfig`.

    ``beta`` (default 10) weighs one nat of entropy reduction against one unit of reward.
    """

    name: ClassVar[str] = "entropy"

    def planner(self, pomdp: GenerativePOMDP) -> EntropyPlanner:
        return EntropyPlanner(self, pomdp)


class EntropyPlanner(EpisodeSteps):
    """Belief-tree search with reward ``R + beta * (H(b) - H(b'))``."""

    def __init__(self, config: EntropyConfig, pomdp: GenerativePOMDP) -> None:
        check_pomdp(pomdp)
        self.config = config
        self.pomdp = pomdp
        self.value = entropy_value(pomdp)

    def act(self, belief: ParticleBelief, rng: np.random.Generator) -> tuple[Hashable, SearchInfo]:
        cfg = self.config
        states, weights = root_particles(self.pomdp, belief, cfg.particles, rng)
        result = belief_tree_search(
            self.pomdp, cfg, states, weights, rng,
            node_value=self.value, beta=cfg.beta, steps_taken=self.steps_taken,
        )  # fmt: skip
        action = result.best if result.best is not None else self.pomdp.action_space().sample(rng)
        info = result.search_info(entropy=result.root_value)
        return action, info
