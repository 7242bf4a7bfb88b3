"""POMCPOW (Sunberg & Kochenderfer 2018): POMCP with observation widening.

Double progressive widening: a belief node gets a new action child while it has at
most ``k_action * N(h)^alpha_action`` of them, and an action node a new observation
child while it has at most ``k_obs * N(ha)^alpha_obs``. Every observation node holds
a *weighted* particle set: each simulation through it adds its next state ``s'``
with weight ``Z(o | s', a)`` (the domain's ``obs_loglik``), and the descent continues
from a particle drawn by weight, so deeper nodes hold properly weighted beliefs even
with continuous observations. This is POMCPOW.jl's algorithm with ``check_repeat_obs``
and ``check_repeat_act`` on and the ``MaxUCB`` criterion.

Action selection comes from :class:`planners.solvers.action_tree.ActionTree`:
``widening="auto"`` (default) is the published algorithm, DPW over the whole action
space when it has continuous parameters and every action on a finite space;
``"hpw"`` swaps in STRUG's hierarchical widening so its effect alone can be measured.
Rollouts are uniformly random unless ``rollout="heuristic"``.

Storage is flat lists indexed by node id. Per belief node: visits, the observation,
and its particles (states, rewards, terminal flags, cumulative weights for O(log n)
sampling). Per action node (beside the ActionTree's statistics): the list of
observation children generated, with repeats, so that a uniform pick from it is a
pick proportional to how often each observation was generated.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from planners.belief import ParticleBelief
from planners.errors import check_positive_float
from planners.solvers.action_tree import ActionTree, check_widening, resolve_widening
from planners.solvers.base import (
    Budget,
    RootSampler,
    SearchInfo,
    TreeSearchConfig,
    UniformStream,
)
from planners.solvers.rollout import check_rollout, domain_policy, make_rollout


@dataclass(frozen=True)
class POMCPOWConfig(TreeSearchConfig):
    """POMCPOW hyper-parameters.

    Attributes:
        sims: simulations per decision (default 3000).
        time_limit: wall time per decision [s] (default None).
        depth: maximum search depth incl. rollout (default: the domain's ``max_steps``).
        c: UCB exploration constant (default: the domain's largest |reward|).
        discount: search discount (default: the domain's).
        k_action: action widening coefficient k_a (default 10, POMCPOW.jl's default).
        alpha_action: action widening exponent alpha_a in [0, 1] (default 1/30, as the
            POMCPOW paper's continuous-action VDP Tag; keeps ~k_a children).
        k_obs: observation widening coefficient k_o (default 5, the paper's LightDark).
        alpha_obs: observation widening exponent alpha_o in [0, 1] (default 1/15, the
            paper's LightDark).
        widening: action selection, ``"auto"`` (default: DPW on continuous action
            spaces, every action on finite ones), ``"all"``, ``"dpw"`` or ``"hpw"``.
        exploration: ``"fixed"`` (default) or ``"normalized"`` UCB (see
            :class:`TreeSearchConfig`); ``c_normalized`` its constant (default 1.0).
        horizon: ``"receding"`` (default) or ``"episode"`` (see :class:`TreeSearchConfig`).
        rollout: ``"random"`` (default: uniform actions, from the discretised set when
            every action is a child, else from the whole space) or ``"heuristic"`` (the
            domain's :meth:`rollout_policy`).
    """

    name: ClassVar[str] = "pomcpow"

    k_action: float = 10.0
    alpha_action: float = 1.0 / 30.0
    k_obs: float = 5.0
    alpha_obs: float = 1.0 / 15.0
    widening: str = "auto"
    rollout: str = "random"

    def __post_init__(self) -> None:
        super().__post_init__()
        check_widening(self.widening, self.k_action, self.alpha_action)
        check_rollout(self.rollout)
        check_positive_float("k_obs", self.k_obs)
        check_positive_float("alpha_obs", self.alpha_obs, allow_zero=True, upper=1.0)

    def planner(self, pomdp: Any) -> POMCPOWPlanner:
        return POMCPOWPlanner(self, pomdp)


class POMCPOWPlanner:
    """A POMCPOW search, rebuilt at every ``act`` call."""

    def __init__(self, config: POMCPOWConfig, pomdp: Any) -> None:
        self.config = config
        self.pomdp = pomdp
        self.space = pomdp.action_space()
        self.depth, self.c, self.gamma = config.resolved(pomdp)
        self.widening = resolve_widening(config.widening, self.space, "dpw")
        if config.rollout == "heuristic":
            domain_policy(pomdp)  # a domain without one fails here, not mid-episode
        self.steps_taken = 0

    def observe(self, action: Hashable, observation: Any) -> None:
        """Count the real steps of the episode (for ``horizon="episode"``)."""
        self.steps_taken += 1

    def act(self, belief: ParticleBelief, rng: np.random.Generator) -> tuple[Hashable, SearchInfo]:
        cfg = self.config
        budget = Budget(cfg.sims, cfg.time_limit)
        step, loglik = self.pomdp.step, self.pomdp.obs_loglik
        space = self.space
        depth, gamma = cfg.search_depth(self.pomdp, self.steps_taken), self.gamma
        k_o, al_o = cfg.k_obs, cfg.alpha_obs
        u = UniformStream(rng)
        exp = math.exp
        tree = ActionTree(
            space, self.widening, cfg.k_action, cfg.alpha_action, self.c, rng, u, cfg.normalized
        )
        select, backup, a_action, a_n = tree.select, tree.update, tree.a_action, tree.a_n
        rollout_actions = list(space.discretized) if self.widening == "all" else None
        rollout = make_rollout(
            self.pomdp, cfg.rollout, rollout_actions, space, depth, gamma, rng, u
        )

        # Belief (observation) nodes.
        b_n: list[int] = []
        b_obs: list[Any] = []
        b_states: list[list[Any]] = []
        b_rewards: list[list[float]] = []
        b_done: list[list[bool]] = []
        b_cdf: list[list[float]] = []
        a_generated: list[list[int]] = []
        obs_lookup: dict[tuple[int, Any], int] = {}

        def new_belief_node(o: Any) -> int:
            b_n.append(0)
            b_obs.append(o)
            b_states.append([])
            b_rewards.append([])
            b_done.append([])
            b_cdf.append([])
            tree.add_belief_node()
            return len(b_n) - 1

        def simulate(s: Any, h: int, d: int) -> float:
            nh = b_n[h]
            anode, snode = select(h, nh)
            while len(a_generated) < len(a_n):
                a_generated.append([])
            a = a_action[anode]
            generated = a_generated[anode]
            new_node = False
            if len(generated) <= k_o * a_n[anode] ** al_o:
                sp, o, r, done = step(s, a, rng)
                key = (anode, o)
                hao = obs_lookup.get(key)
                if hao is None:
                    new_node = True
                    hao = obs_lookup[key] = new_belief_node(o)
                generated.append(hao)
            else:
                sp, _, r, done = step(s, a, rng)
                hao = generated[int(u() * len(generated))]
            # Add (s', r) to the node's weighted particle set.
            w = exp(loglik(b_obs[hao], sp, a))
            cdf = b_cdf[hao]
            cdf.append((cdf[-1] if cdf else 0.0) + w)
            b_states[hao].append(sp)
            b_rewards[hao].append(r)
            b_done[hao].append(done)
            if new_node:
                total = r if done or d + 1 >= depth else r + gamma * rollout(sp, d + 1)
            else:
                # Continue from a particle drawn by weight (uniformly if all weights are 0).
                if cdf[-1] > 0.0:
                    i = min(bisect_right(cdf, u() * cdf[-1]), len(cdf) - 1)
                else:
                    i = int(u() * len(cdf))
                sp, r, done = b_states[hao][i], b_rewards[hao][i], b_done[hao][i]
                total = r if done or d + 1 >= depth else r + gamma * simulate(sp, hao, d + 1)
            b_n[h] = nh + 1
            backup(anode, snode, total)
            return total

        new_belief_node(None)
        sample_root = RootSampler(belief, rng)
        sims = 0
        while not budget.done(sims):
            simulate(sample_root(), 0, 0)
            sims += 1

        actions, q, visits = tree.root_stats()
        best = tree.best_root_action()
        info = SearchInfo(
            sims=sims,
            seconds=budget.elapsed(),
            tree_nodes=len(b_n) + tree.size(),
            actions=actions,
            q=q,
            visits=visits,
            extra={"tree": TreeCounts(b_n, tree.b_children, a_n, a_generated)},
        )
        return (best if best is not None else space.sample(rng)), info


@dataclass(frozen=True)
class TreeCounts:
    """Read-only counts of a finished tree (for tests and diagnostics).

    Attributes:
        belief_visits: N(h) per belief node.
        belief_children: action-node ids per belief node.
        action_visits: N(ha) per action node.
        action_generated: observation-node ids generated per action node (with repeats).
    """

    belief_visits: list[int]
    belief_children: list[list[int]]
    action_visits: list[int]
    action_generated: list[list[int]]

    def obs_children(self, anode: int) -> int:
        """Number of distinct observation children of action node ``anode``."""
        return len(set(self.action_generated[anode])) if anode < len(self.action_generated) else 0
