"""POMCP (Silver & Veness 2010): UCT over action-observation histories.

Discrete actions and observations. On a continuous domain it runs as the POMCPOW
paper's baseline does: actions come from the domain's documented discretisation
(``ActionSpace.discretized``) and observations are binned on a grid of width
``obs_bin`` per dimension, so that repeated histories share a node.

The tree is flat arrays indexed by node id: per belief node its visit count and the
id of its first action node (the node's actions are contiguous); per action node its
visit count and value. Children of an action node are found in one dict keyed by
``(action node, observation key)``. Nodes are expanded lazily: a history seen for
the first time gets a node and a random rollout; its action slots are allocated on
its second visit. Root states are drawn from the runner's particle belief; the tree
is not reused between decisions (the belief update lives in the runner).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from planners.belief import ParticleBelief
from planners.errors import check_positive_float
from planners.solvers.base import (
    Budget,
    RootSampler,
    SearchInfo,
    TreeSearchConfig,
    UniformStream,
)


@dataclass(frozen=True)
class POMCPConfig(TreeSearchConfig):
    """POMCP hyper-parameters.

    Attributes:
        sims: simulations per decision (default 3000).
        time_limit: wall time per decision [s] (default None).
        depth: maximum search depth incl. rollout (default: the domain's ``max_steps``).
        c: UCB exploration constant (default: the domain's largest |reward|).
        discount: search discount (default: the domain's).
        obs_bin: width of the observation grid on continuous-observation domains, in
            the observation's units (default 1.0); ignored for discrete observations.
    """

    name: ClassVar[str] = "pomcp"

    obs_bin: float = 1.0

    def __post_init__(self) -> None:
        super().__post_init__()
        check_positive_float("obs_bin", self.obs_bin)

    def planner(self, pomdp: Any) -> POMCPPlanner:
        return POMCPPlanner(self, pomdp)


def observation_key(pomdp: Any, obs_bin: float) -> Callable[[Any], Hashable] | None:
    """The function mapping observations to tree keys (None: use them as they are)."""
    if pomdp.discrete_observations:
        return None
    inv = 1.0 / obs_bin

    def key(o: Any) -> Hashable:
        if isinstance(o, tuple | list | np.ndarray):
            return tuple(math.floor(x * inv) for x in o)
        return math.floor(o * inv)

    return key


class POMCPPlanner:
    """A POMCP search, rebuilt at every ``act`` call."""

    def __init__(self, config: POMCPConfig, pomdp: Any) -> None:
        self.config = config
        self.pomdp = pomdp
        self.actions = list(pomdp.action_space().discretized)
        self.depth, self.c, self.gamma = config.resolved(pomdp)
        self.obs_key = observation_key(pomdp, config.obs_bin)

    def act(self, belief: ParticleBelief, rng: np.random.Generator) -> tuple[Hashable, SearchInfo]:
        cfg = self.config
        budget = Budget(cfg.sims, cfg.time_limit)
        actions = self.actions
        n_actions = len(actions)
        depth, c, gamma = self.depth, self.c, self.gamma
        step = self.pomdp.step
        obs_key = self.obs_key
        u = UniformStream(rng)
        log, sqrt = math.log, math.sqrt

        # Belief nodes: visit count, first action node (-1 until expanded).
        b_n: list[int] = [0]
        b_first: list[int] = [0]
        # Action nodes: visit count and value.
        a_n: list[int] = [0] * n_actions
        a_q: list[float] = [0.0] * n_actions
        children: dict[tuple[int, Hashable], int] = {}
        zeros_i = [0] * n_actions
        zeros_f = [0.0] * n_actions

        def rollout(s: Any, d: int) -> float:
            total = 0.0
            disc = 1.0
            while d < depth:
                s, _, r, done = step(s, actions[int(u() * n_actions)], rng)
                total += disc * r
                if done:
                    break
                disc *= gamma
                d += 1
            return total

        def simulate(s: Any, h: int, d: int) -> float:
            first = b_first[h]
            if first < 0:
                first = b_first[h] = len(a_n)
                a_n.extend(zeros_i)
                a_q.extend(zeros_f)
            nh = b_n[h]
            if nh < n_actions:
                # Unvisited actions first, in order: after nh visits exactly 0..nh-1 are tried.
                ai = first + nh
            else:
                logn = log(nh)
                ai = first
                best = -math.inf
                for j in range(first, first + n_actions):
                    v = a_q[j] + c * sqrt(logn / a_n[j])
                    if v > best:
                        best = v
                        ai = j
            s2, o, r, done = step(s, actions[ai - first], rng)
            if done or d + 1 >= depth:
                total = r
            else:
                key = (ai, o if obs_key is None else obs_key(o))
                h2 = children.get(key)
                if h2 is None:
                    children[key] = len(b_n)
                    b_n.append(0)
                    b_first.append(-1)
                    total = r + gamma * rollout(s2, d + 1)
                else:
                    total = r + gamma * simulate(s2, h2, d + 1)
            b_n[h] = nh + 1
            n = a_n[ai] + 1
            a_n[ai] = n
            a_q[ai] += (total - a_q[ai]) / n
            return total

        sample_root = RootSampler(belief, rng)
        sims = 0
        while not budget.done(sims):
            simulate(sample_root(), 0, 0)
            sims += 1

        q = np.array(a_q[:n_actions])
        visits = np.array(a_n[:n_actions], dtype=np.int64)
        best = _best_root_action(q, visits)
        info = SearchInfo(
            sims=sims,
            seconds=budget.elapsed(),
            tree_nodes=len(b_n) + len(a_n),
            actions=list(actions),
            q=q,
            visits=visits,
        )
        return actions[best], info


def _best_root_action(q: np.ndarray, visits: np.ndarray) -> int:
    """Index of the visited root action with the highest value (ties: the first)."""
    if not np.any(visits > 0):
        return 0
    return int(np.argmax(np.where(visits > 0, q, -np.inf)))
