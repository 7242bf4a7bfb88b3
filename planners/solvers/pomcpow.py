"""POMCPOW (Sunberg & Kochenderfer 2018): POMCP with observation widening.

Double progressive widening: a belief node gets a new action child while it has at
most ``k_action * N(h)^alpha_action`` of them, and an action node a new observation
child while it has at most ``k_obs * N(ha)^alpha_obs``. Every observation node holds
a *weighted* particle set: each simulation through it adds its next state ``s'``
with weight ``Z(o | s', a)`` (the domain's ``obs_loglik``), and the descent continues
from a particle drawn by weight, so deeper nodes hold properly weighted beliefs even
with continuous observations. This is POMCPOW.jl's algorithm with ``check_repeat_obs``
and ``check_repeat_act`` on and the ``MaxUCB`` criterion.

Action widening is on by default only when the action space has continuous
parameters; on a finite action space every action is a child from the start
(``action_widening`` forces either). New actions are drawn uniformly from the
action space; rollouts are uniformly random.

Storage is flat lists indexed by node id. Per belief node: visits, child action ids,
the observation, and its particles (states, rewards, terminal flags, cumulative
weights for O(log n) sampling). Per action node: visits, value, the action, and the
list of observation children generated (with repeats, so that a uniform pick from
it is a pick proportional to how often each observation was generated).
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from planners.belief import ParticleBelief
from planners.errors import ConfigError, check_positive_float
from planners.solvers.base import (
    Budget,
    RootSampler,
    SearchInfo,
    TreeSearchConfig,
    UniformStream,
)


@dataclass(frozen=True)
class POMCPOWConfig(TreeSearchConfig):
    """POMCPOW hyper-parameters.

    Attributes:
        sims: simulations per decision (default 1000).
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
        action_widening: ``None`` (default) widens actions only on continuous action
            spaces; ``True``/``False`` force it on or off.
    """

    name: ClassVar[str] = "pomcpow"

    k_action: float = 10.0
    alpha_action: float = 1.0 / 30.0
    k_obs: float = 5.0
    alpha_obs: float = 1.0 / 15.0
    action_widening: bool | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        check_positive_float("k_action", self.k_action)
        check_positive_float("k_obs", self.k_obs)
        check_positive_float("alpha_action", self.alpha_action, allow_zero=True, upper=1.0)
        check_positive_float("alpha_obs", self.alpha_obs, allow_zero=True, upper=1.0)
        if self.action_widening not in (None, True, False):
            raise ConfigError(
                f"action_widening must be None, True or False, got {self.action_widening!r}"
            )

    def planner(self, pomdp: Any) -> POMCPOWPlanner:
        return POMCPOWPlanner(self, pomdp)


class POMCPOWPlanner:
    """A POMCPOW search, rebuilt at every ``act`` call."""

    def __init__(self, config: POMCPOWConfig, pomdp: Any) -> None:
        self.config = config
        self.pomdp = pomdp
        self.space = pomdp.action_space()
        self.depth, self.c, self.gamma = config.resolved(pomdp)
        widen = config.action_widening
        self.action_widening = (not self.space.is_discrete) if widen is None else widen

    def act(self, belief: ParticleBelief, rng: np.random.Generator) -> tuple[Hashable, SearchInfo]:
        cfg = self.config
        budget = Budget(cfg.sims, cfg.time_limit)
        pomdp = self.pomdp
        step, loglik = pomdp.step, pomdp.obs_loglik
        space = self.space
        depth, c, gamma = self.depth, self.c, self.gamma
        k_a, al_a, k_o, al_o = cfg.k_action, cfg.alpha_action, cfg.k_obs, cfg.alpha_obs
        widen_actions = self.action_widening
        all_actions = list(space.discretized)
        n_all = len(all_actions)
        u = UniformStream(rng)
        log, sqrt, exp = math.log, math.sqrt, math.exp

        # Belief (observation) nodes.
        b_n: list[int] = [0]
        b_children: list[list[int]] = [[]]
        b_obs: list[Any] = [None]
        b_states: list[list[Any]] = [[]]
        b_rewards: list[list[float]] = [[]]
        b_done: list[list[bool]] = [[]]
        b_cdf: list[list[float]] = [[]]
        # Action nodes.
        a_n: list[int] = []
        a_q: list[float] = []
        a_action: list[Hashable] = []
        a_generated: list[list[int]] = []
        act_lookup: dict[tuple[int, Hashable], int] = {}
        obs_lookup: dict[tuple[int, Any], int] = {}

        def add_action(h: int, a: Hashable) -> None:
            key = (h, a)
            if key in act_lookup:
                return
            act_lookup[key] = len(a_n)
            b_children[h].append(len(a_n))
            a_n.append(0)
            a_q.append(0.0)
            a_action.append(a)
            a_generated.append([])

        def rollout(s: Any, d: int) -> float:
            total = 0.0
            disc = 1.0
            while d < depth:
                a = all_actions[int(u() * n_all)] if not widen_actions else space.sample(rng)
                s, _, r, done = step(s, a, rng)
                total += disc * r
                if done:
                    break
                disc *= gamma
                d += 1
            return total

        def simulate(s: Any, h: int, d: int) -> float:
            children = b_children[h]
            nh = b_n[h]
            if widen_actions:
                if len(children) <= k_a * nh**al_a:
                    add_action(h, space.sample(rng))
            elif not children:
                for a in all_actions:
                    add_action(h, a)
            # MaxUCB: the first unvisited child, else the highest UCB.
            best = -1
            best_v = -math.inf
            logn = log(nh) if nh > 0 else 0.0
            for j in children:
                n = a_n[j]
                if n == 0:
                    best = j
                    break
                v = a_q[j] + c * sqrt(logn / n)
                if v > best_v:
                    best_v = v
                    best = j
            a = a_action[best]
            generated = a_generated[best]
            new_node = False
            if len(generated) <= k_o * a_n[best] ** al_o:
                sp, o, r, done = step(s, a, rng)
                key = (best, o)
                hao = obs_lookup.get(key)
                if hao is None:
                    new_node = True
                    hao = obs_lookup[key] = len(b_n)
                    b_n.append(0)
                    b_children.append([])
                    b_obs.append(o)
                    b_states.append([])
                    b_rewards.append([])
                    b_done.append([])
                    b_cdf.append([])
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
                    i = bisect_right(cdf, u() * cdf[-1])
                    i = min(i, len(cdf) - 1)
                else:
                    i = int(u() * len(cdf))
                sp, r, done = b_states[hao][i], b_rewards[hao][i], b_done[hao][i]
                total = r if done or d + 1 >= depth else r + gamma * simulate(sp, hao, d + 1)
            b_n[h] = nh + 1
            n = a_n[best] + 1
            a_n[best] = n
            a_q[best] += (total - a_q[best]) / n
            return total

        sample_root = RootSampler(belief, rng)
        sims = 0
        while not budget.done(sims):
            simulate(sample_root(), 0, 0)
            sims += 1

        root = b_children[0]
        q = np.array([a_q[j] for j in root])
        visits = np.array([a_n[j] for j in root], dtype=np.int64)
        if len(root) and np.any(visits > 0):
            best = int(np.argmax(np.where(visits > 0, q, -np.inf)))
        else:
            best = 0
        info = SearchInfo(
            sims=sims,
            seconds=budget.elapsed(),
            tree_nodes=len(b_n) + len(a_n),
            actions=[a_action[j] for j in root],
            q=q,
            visits=visits,
            extra={"tree": _TreeView(b_n, b_children, a_n, a_generated)},
        )
        action = a_action[root[best]] if root else space.sample(rng)
        return action, info


@dataclass(frozen=True)
class _TreeView:
    """Read-only counts of a finished POMCPOW tree (for tests and diagnostics).

    Attributes:
        belief_visits: N(h) per belief node.
        belief_children: action-node ids per belief node.
        action_visits: N(ha) per action node.
        action_obs_children: distinct observation-node ids per action node.
    """

    belief_visits: list[int]
    belief_children: list[list[int]]
    action_visits: list[int]
    action_generated: list[list[int]]

    def obs_children(self, anode: int) -> int:
        """Number of distinct observation children of action node ``anode``."""
        return len(set(self.action_generated[anode]))
