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

Storage is flat lists indexed by node id (:class:`POMCPOWTree`). Per belief node:
visits, the observation, and its particles (states, rewards, terminal flags,
cumulative weights for O(log n) sampling). Per action node, in the
:class:`ActionTree`: its statistics and the list of observation children generated,
with repeats, so that a uniform pick from it is a pick proportional to how often each
observation was generated. Observation children are keyed by
``pomdp.observation_key(o)``, so numpy observations are fine.
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
from planners.pomdp import GenerativePOMDP, check_pomdp
from planners.solvers.action_tree import (
    ActionTree,
    check_widening,
    history_offers,
    history_ranks,
    resolve_widening,
)
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

    def planner(self, pomdp: GenerativePOMDP) -> POMCPOWPlanner:
        return POMCPOWPlanner(self, pomdp)


class POMCPOWPlanner:
    """A POMCPOW search, rebuilt at every ``act`` call."""

    def __init__(self, config: POMCPOWConfig, pomdp: GenerativePOMDP) -> None:
        check_pomdp(pomdp)
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
        pomdp, space = self.pomdp, self.space
        step, loglik, obs_key = pomdp.step, pomdp.obs_loglik, pomdp.observation_key
        depth, gamma = cfg.search_depth(pomdp, self.steps_taken), self.gamma
        k_o, al_o = cfg.k_obs, cfg.alpha_obs
        u = UniformStream(rng)
        exp = math.exp
        actions = ActionTree(
            space, self.widening, cfg.k_action, cfg.alpha_action, self.c, rng, u, cfg.normalized
        )
        tree = POMCPOWTree(actions)
        select, backup, a_action, a_n = (
            actions.select,
            actions.update,
            actions.a_action,
            actions.a_n,
        )
        a_children, obs_child, add_node = actions.a_children, tree.obs_child, tree.add_node
        b_n, b_obs, b_states, b_rewards, b_done, b_cdf = (
            tree.visits,
            tree.obs,
            tree.states,
            tree.rewards,
            tree.done,
            tree.cdf,
        )
        rollout_actions = list(space.discretized) if self.widening == "all" else None
        rollout = make_rollout(pomdp, cfg.rollout, rollout_actions, space, depth, gamma, rng, u)

        offers = history_offers(pomdp, belief)  # None: every action, every node
        ranks = history_ranks(pomdp, belief)  # None: the list order

        def simulate(s: Any, h: int, d: int) -> float:
            nh = b_n[h]
            keep = None if offers is None else offers(h, s)
            anode, snode = select(h, nh, keep, None if ranks is None else ranks(h, s))
            a = a_action[anode]
            generated = a_children[anode]
            new_node = False
            if len(generated) <= k_o * a_n[anode] ** al_o:
                sp, o, r, done = step(s, a, rng)
                key = (anode, obs_key(o))
                hao = obs_child.get(key)
                if hao is None:
                    new_node = True
                    hao = obs_child[key] = add_node(o)
                generated.append(hao)
            else:
                sp, _, r, done = step(s, a, rng)
                hao = generated[int(u() * len(generated))]
            # Add (s', r) to the node's weighted particle set.
            cdf = b_cdf[hao]
            cdf.append((cdf[-1] if cdf else 0.0) + exp(loglik(b_obs[hao], sp, a)))
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

        add_node(None)
        sample_root = RootSampler(belief, rng)
        sims = 0
        while not budget.done(sims):
            simulate(sample_root(), 0, 0)
            sims += 1

        root_actions, q, visits = actions.root_stats()
        best = actions.best_root_action()
        info = SearchInfo(
            sims=sims,
            seconds=budget.elapsed(),
            tree_nodes=len(b_n) + actions.size(),
            actions=root_actions,
            q=q,
            visits=visits,
            tree=tree if cfg.keep_tree else None,
        )
        return (best if best is not None else space.sample(rng)), info


class POMCPOWTree:
    """A POMCPOW tree: the action nodes (:class:`ActionTree`, their observation children
    in ``actions.a_children``) and, per belief (observation) node, named lists.

    Attributes:
        actions: the action nodes, their statistics and widening.
        visits: N(h) per belief node (node 0 is the root).
        obs: the observation of each belief node (None at the root).
        states: its particles s'.
        rewards: the reward of the step that produced each particle.
        done: whether that step ended the episode, per particle.
        cdf: cumulative particle weights Z(o | s', a), for drawing by weight.
        obs_child: ``(action node, observation key) -> belief node``.
    """

    def __init__(self, actions: ActionTree) -> None:
        self.actions = actions
        self.visits: list[int] = []
        self.obs: list[Any] = []
        self.states: list[list[Any]] = []
        self.rewards: list[list[float]] = []
        self.done: list[list[bool]] = []
        self.cdf: list[list[float]] = []
        self.obs_child: dict[tuple[int, Hashable], int] = {}

    def add_node(self, o: Any) -> int:
        """Append an empty belief node for observation ``o``; returns its id."""
        for column, x in (
            (self.visits, 0), (self.obs, o), (self.states, []), (self.rewards, []),
            (self.done, []), (self.cdf, []),
        ):  # fmt: skip
            column.append(x)
        return self.actions.add_belief_node()

    def obs_children(self, anode: int) -> int:
        """Number of distinct observation children of action node ``anode``."""
        return len(set(self.actions.a_children[anode]))
