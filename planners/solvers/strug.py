"""STRUG: Search with Task-Relevant Uncertainty Guidance (the paper's Algorithm 2).

At every decision: draw M particles from the belief, build their plan compatibility
matrix (Algorithm 1, :mod:`planners.tru`), then run the belief-tree search of
:mod:`planners.solvers.belief_tree` with the reward ``R + beta * (TRU(b) - TRU(b'))``,
TRU computed from the cached matrix and each node's weights over the M particles
(the paper's approximate incremental TRU). Hybrid action spaces use HPW (Algorithm 3).
On a domain with an action prior, the root's actions are ordered by the weight of the
particles whose plan begins with them, then by the domain's prior (``root_plans`` of
:class:`~planners.solvers.belief_tree.BeliefTreeSearch`), and the root chooses among them
by PUCT over that weight (``root_selection``), stopping once no simulation left could
change its decision (``stop_decided``).
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from planners.belief import ParticleBelief
from planners.errors import check_positive_int
from planners.pomdp import GenerativePOMDP, check_pomdp
from planners.solvers.base import SearchInfo
from planners.solvers.belief_tree import (
    BeliefTreeConfig,
    EpisodeSteps,
    belief_tree_search,
    root_particles,
)
from planners.tru import compatibility_matrix


@dataclass(frozen=True)
class STRUGConfig(BeliefTreeConfig):
    """STRUG hyper-parameters (the paper's names in brackets).

    Attributes:
        sims: tree simulations per decision [tree samples] (default 3000).
        time_limit: wall time per decision [s] (default None).
        depth: maximum search depth incl. rollout (default: the domain's ``max_steps``).
        c: UCB constant (default: the largest |reward|, as the paper sets it).
        discount: search discount [gamma] (default: the domain's).
        particles: particles of the compatibility matrix and of every node [M] (default 32).
        plan_repeats: executions of each plan on each particle [K] (default 3).
        beta: weight of the TRU reduction [beta] (default 10, the paper's).
        k_action, alpha_action: HPW widening over each schema's parameters [k, alpha]
            (defaults 10, 1/30).
        k_obs, alpha_obs: observation widening (defaults 5, 1/15).
        widening: ``"auto"`` (HPW on hybrid spaces), ``"all"``, ``"dpw"`` or ``"hpw"``.
        rollout: leaf estimate, ``"auto"`` (default: ``"plan"`` on a domain with its own
            ``plan_for``, else ``"random"``), ``"plan"`` (a particle's uncertainty-free
            plan executed from another particle, both drawn from the node's belief) or
            ``"random"`` (the paper's Algorithm 2 as written).
        stop_decided: a PUCT root (the manipulation tasks) stops once no simulation
            left could change its decision (:class:`BeliefTreeConfig`; default True).
    """

    name: ClassVar[str] = "strug"

    plan_repeats: int = 3
    rollout: str = "auto"

    def __post_init__(self) -> None:
        super().__post_init__()
        check_positive_int("plan_repeats", self.plan_repeats)

    def planner(self, pomdp: GenerativePOMDP) -> STRUGPlanner:
        return STRUGPlanner(self, pomdp)


class STRUGPlanner(EpisodeSteps):
    """Compatibility matrix + TRU-guided belief-tree search, rebuilt at every decision."""

    def __init__(self, config: STRUGConfig, pomdp: GenerativePOMDP) -> None:
        check_pomdp(pomdp)
        self.config = config
        self.pomdp = pomdp

    def act(self, belief: ParticleBelief, rng: np.random.Generator) -> tuple[Hashable, SearchInfo]:
        cfg = self.config
        states, weights = root_particles(self.pomdp, belief, cfg.particles, rng)
        _, _, gamma = cfg.resolved(self.pomdp)
        matrix = compatibility_matrix(self.pomdp, states, cfg.plan_repeats, rng, discount=gamma)
        result = belief_tree_search(
            self.pomdp,
            cfg,
            states,
            weights,
            rng,
            node_value=lambda _states, w: matrix.tru(w),
            beta=cfg.beta,
            steps_taken=self.steps_taken,
            root_plans=matrix.plans,
        )
        action = result.best if result.best is not None else self.pomdp.action_space().sample(rng)
        info = result.search_info(
            matrix.seconds,
            tru=result.root_value,
            matrix_seconds=matrix.seconds,
            plan_executions=matrix.executions,
        )
        return action, info
