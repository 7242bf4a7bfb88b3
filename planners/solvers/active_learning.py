"""Active Learning: first reduce belief entropy, then plan under the most likely model.

Two phases, decided afresh at every step from the runner's belief:

1. **Learn** while ``H(b) > entropy_threshold`` [nats]: belief-tree search that pays
   only for entropy reduction (``beta * (H(b) - H(b'))``, task reward weight 0), so
   the agent takes the most informative actions whatever the task. Ending the
   episode while learning forfeits the entropy still above the threshold
   (``-beta * (H - threshold)``), so learning never stops by ending the episode.
2. **Exploit** once ``H(b) <= entropy_threshold``: Monte-Carlo tree search from the
   most likely state alone, as if the model were known: the mode for discrete
   states, for continuous ones the particle nearest the belief's weighted mean.

The threshold default, 0.2 nats, is P(tiger) >= 0.95 on Tiger, a 0.3 m standard
deviation on LightDark1D, and sigma_x * sigma_y <= 0.07 m^2 on LightDark2D (see
:mod:`planners.entropy` for the estimators). The learn phase uses UCB constant
``beta`` (its returns are ``beta`` per nat).
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from planners.belief import ParticleBelief
from planners.entropy import state_entropy
from planners.errors import check_positive_float
from planners.pomdp import GenerativePOMDP, check_pomdp
from planners.solvers.base import SearchInfo
from planners.solvers.belief_tree import (
    BeliefTreeConfig,
    EpisodeSteps,
    belief_tree_search,
    root_particles,
)
from planners.solvers.entropy_regularized import entropy_value


@dataclass(frozen=True)
class ActiveLearningConfig(BeliefTreeConfig):
    """Active Learning hyper-parameters: :class:`BeliefTreeConfig`'s, plus

    Attributes:
        entropy_threshold: belief entropy [nats] below which the agent exploits
            (default 0.2).
    """

    name: ClassVar[str] = "active"

    entropy_threshold: float = 0.2

    def __post_init__(self) -> None:
        super().__post_init__()
        if not np.isfinite(self.entropy_threshold):
            check_positive_float("entropy_threshold", self.entropy_threshold)

    def planner(self, pomdp: GenerativePOMDP) -> ActiveLearningPlanner:
        return ActiveLearningPlanner(self, pomdp)


def most_likely_state(pomdp: GenerativePOMDP, belief: ParticleBelief) -> Any:
    """Discrete states: the heaviest particle of the heaviest ``entropy_key`` class (by
    default: the mode); continuous: the particle nearest the weighted mean."""
    if pomdp.discrete_states(belief.states):
        mass: dict[Any, float] = {}
        keys = [pomdp.entropy_key(s) for s in belief.states]
        for k, w in zip(keys, belief.weights.tolist(), strict=True):
            mass[k] = mass.get(k, 0.0) + w
        best = max(mass, key=mass.__getitem__)
        heaviest: dict[Any, float] = {}  # equal states pool their weight, as in the mode
        for s, k, w in zip(belief.states, keys, belief.weights.tolist(), strict=True):
            if k == best:
                heaviest[s] = heaviest.get(s, 0.0) + w
        return max(heaviest, key=heaviest.__getitem__)
    features = pomdp.entropy_features(belief.states)
    mean = belief.weights @ features
    return belief.states[int(np.argmin(((features - mean) ** 2).sum(axis=1)))]


class ActiveLearningPlanner(EpisodeSteps):
    """Learn (entropy reduction only) until confident, then exploit the MAP model."""

    def __init__(self, config: ActiveLearningConfig, pomdp: GenerativePOMDP) -> None:
        check_pomdp(pomdp)
        self.config = config
        self.pomdp = pomdp
        self.value = entropy_value(pomdp)

    def act(self, belief: ParticleBelief, rng: np.random.Generator) -> tuple[Hashable, SearchInfo]:
        cfg = self.config
        pomdp = self.pomdp
        h = state_entropy(pomdp, belief.states, belief.weights)
        threshold = cfg.entropy_threshold
        if h > threshold:
            states, weights = root_particles(pomdp, belief, cfg.particles, rng)
            result = belief_tree_search(
                pomdp, cfg, states, weights, rng,
                node_value=self.value, beta=cfg.beta, reward_weight=0.0, c=cfg.beta,
                terminal_bonus=lambda h_left: -cfg.beta * max(h_left - threshold, 0.0),
                steps_taken=self.steps_taken,
            )  # fmt: skip
            phase = "learn"
        else:
            state = most_likely_state(pomdp, belief)
            result = belief_tree_search(
                pomdp,
                cfg,
                [state],
                np.ones(1),
                rng,
                node_value=None,
                beta=0.0,
                steps_taken=self.steps_taken,
            )
            phase = "exploit"
        action = result.best if result.best is not None else pomdp.action_space().sample(rng)
        info = result.search_info(entropy=h, phase=phase)
        return action, info
