"""POMCP (Silver & Veness 2010): UCT over action-observation histories.

Discrete actions and observations. On a continuous domain it runs as the POMCPOW
paper's baseline does: actions come from the domain's documented discretisation
(``ActionSpace.discretized``) and observations are binned on a grid of width
``obs_bin`` per dimension, so that repeated histories share a node.

The tree is flat arrays indexed by node id (:class:`POMCPTree`): per belief node its
visit count and the id of its first action node (the node's actions are contiguous);
per action node its visit count and value. Children of an action node are found in
one dict keyed by ``(action node, observation key)``. Nodes are expanded lazily: a
history seen for the first time gets a node and a rollout; its action slots are
allocated on its second visit. Root states are drawn from the runner's particle
belief. By default the tree is rebuilt at every decision (the published algorithm as
Table I runs it); ``reuse_tree`` keeps the subtree under the executed action and the
real observation (:mod:`planners.solvers.reuse`). ``exploration`` chooses the UCB
score (:mod:`planners.solvers.exploration`) and ``rollout`` the leaf estimate
(:mod:`planners.solvers.rollout`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from planners.belief import ParticleBelief
from planners.errors import check_positive_float
from planners.pomdp import GenerativePOMDP, check_pomdp
from planners.solvers.base import (
    Budget,
    RootSampler,
    SearchInfo,
    TreeSearchConfig,
    UniformStream,
)
from planners.solvers.exploration import best_index, ucb_select
from planners.solvers.reuse import check_reuse, particle_disagreement
from planners.solvers.rollout import check_rollout, domain_policy, make_rollout


@dataclass(frozen=True)
class POMCPConfig(TreeSearchConfig):
    """POMCP hyper-parameters.

    Attributes:
        sims: simulations per decision (default 3000).
        time_limit: wall time per decision [s] (default None).
        depth: maximum search depth incl. rollout (default: the domain's ``max_steps``).
        c: UCB exploration constant (default: the domain's largest |reward|).
        discount: search discount (default: the domain's).
        exploration: ``"fixed"`` (default) or ``"normalized"`` UCB (see
            :class:`TreeSearchConfig`); ``c_normalized`` its constant (default 1.0).
        horizon: ``"receding"`` (default) or ``"episode"`` (see :class:`TreeSearchConfig`).
        obs_bin: width of the observation grid on continuous-observation domains, in
            the observation's units (default 1.0); ignored for discrete observations.
        rollout: ``"random"`` (default: uniform actions from the discretised set) or
            ``"heuristic"`` (the domain's :meth:`rollout_policy`).
        reuse_tree: keep the subtree under the executed action and observation for the
            next decision (default False: a fresh tree every decision).
        reuse_tolerance: drop the kept subtree when the states its simulations brought
            to it differ from the runner's belief by more than this total-variation
            distance (default 0.25; 1.0 never drops).
    """

    name: ClassVar[str] = "pomcp"

    obs_bin: float = 1.0
    rollout: str = "random"
    reuse_tree: bool = False
    reuse_tolerance: float = 0.25

    def __post_init__(self) -> None:
        super().__post_init__()
        check_positive_float("obs_bin", self.obs_bin)
        check_rollout(self.rollout)
        check_reuse(self.reuse_tree, self.reuse_tolerance)

    def planner(self, pomdp: GenerativePOMDP) -> POMCPPlanner:
        return POMCPPlanner(self, pomdp)


def observation_bins(pomdp: GenerativePOMDP, obs_bin: float) -> Callable[[Any], Hashable]:
    """The function mapping observations to tree keys: the domain's
    ``observation_key`` with discrete observations, else that key binned on a grid of
    width ``obs_bin`` per dimension (the key must then be a number or a flat tuple of
    numbers, as the default key of a 1-d numpy array is after its shape)."""
    key_of = pomdp.observation_key
    if pomdp.discrete_observations:
        return key_of
    inv = 1.0 / obs_bin

    def binned(o: Any) -> Hashable:
        k = key_of(o)
        if isinstance(o, np.ndarray):  # the default key: (shape, values)
            k = k[1]  # type: ignore[index]
        if isinstance(k, tuple):
            return tuple(math.floor(x * inv) for x in k)
        return math.floor(k * inv)  # type: ignore[operator]

    return binned


@dataclass
class POMCPTree:
    """A POMCP tree as flat lists; belief node 0 is the root.

    Attributes:
        b_n: visits per belief node.
        b_first: first action node per belief node (-1 until its second visit).
        a_n: visits per action node.
        a_q: value per action node.
        children: ``(action node, observation key) -> belief node``.
        particles: for the root's grandchildren (the belief nodes one step down), the
            next states the simulations brought there (filled only with ``reuse_tree``).
    """

    b_n: list[int]
    b_first: list[int]
    a_n: list[int]
    a_q: list[float]
    children: dict[tuple[int, Hashable], int] = field(default_factory=dict)
    particles: dict[int, list[Any]] = field(default_factory=dict)

    @classmethod
    def fresh(cls, n_actions: int) -> POMCPTree:
        """A root whose action slots are allocated."""
        return cls([0], [0], [0] * n_actions, [0.0] * n_actions)

    @property
    def size(self) -> int:
        """Belief nodes + action nodes."""
        return len(self.b_n) + len(self.a_n)

    def child(self, action_index: int, obs_key: Hashable) -> int | None:
        """The root's belief child under (action index, observation key), if any."""
        first = self.b_first[0]
        if first < 0:
            return None
        return self.children.get((first + action_index, obs_key))

    def subtree(self, h: int, n_actions: int) -> POMCPTree:
        """A copy of the subtree under belief node ``h``, renumbered breadth-first."""
        below: dict[int, list[tuple[Hashable, int]]] = {}
        for (ai, key), child in self.children.items():
            below.setdefault(ai, []).append((key, child))
        out = POMCPTree([], [], [], [])
        queue, head = [h], 0
        while head < len(queue):
            old = queue[head]
            head += 1
            out.b_n.append(self.b_n[old])
            first = self.b_first[old]
            if first < 0:
                out.b_first.append(-1)
                continue
            new_first = len(out.a_n)
            out.b_first.append(new_first)
            out.a_n.extend(self.a_n[first : first + n_actions])
            out.a_q.extend(self.a_q[first : first + n_actions])
            for j in range(n_actions):
                for key, child in below.get(first + j, ()):
                    out.children[(new_first + j, key)] = len(queue)
                    queue.append(child)
        return out


class POMCPPlanner:
    """A POMCP search; with ``reuse_tree`` it keeps its tree between decisions."""

    def __init__(self, config: POMCPConfig, pomdp: GenerativePOMDP) -> None:
        check_pomdp(pomdp)
        self.config = config
        self.pomdp = pomdp
        self.actions = list(pomdp.action_space().discretized)
        self.depth, self.c, self.gamma = config.resolved(pomdp)
        self.obs_key = observation_bins(pomdp, config.obs_bin)
        if config.rollout == "heuristic":
            domain_policy(pomdp)  # a domain without one fails here, not mid-episode
        self._tree: POMCPTree | None = None
        self._executed: tuple[int, Hashable] | None = None
        self.steps_taken = 0

    def observe(self, action: Hashable, observation: Any) -> None:
        """Record the executed action and the real observation (``reuse_tree``, ``horizon``)."""
        self.steps_taken += 1
        if self.config.reuse_tree and action in self.actions:
            key = self.obs_key(observation)
            self._executed = (self.actions.index(action), key)

    def _start_tree(self, belief: ParticleBelief) -> tuple[POMCPTree, float]:
        """The tree to search from, and the disagreement of a kept subtree (NaN if none)."""
        old, executed = self._tree, self._executed
        self._tree, self._executed = None, None
        if old is None or executed is None:
            return POMCPTree.fresh(len(self.actions)), math.nan
        h = old.child(*executed)
        if h is None:
            return POMCPTree.fresh(len(self.actions)), math.nan
        gap = particle_disagreement(self.pomdp, old.particles.get(h, []), belief)
        if gap > self.config.reuse_tolerance:
            return POMCPTree.fresh(len(self.actions)), gap
        return old.subtree(h, len(self.actions)), gap

    def act(self, belief: ParticleBelief, rng: np.random.Generator) -> tuple[Hashable, SearchInfo]:
        cfg = self.config
        budget = Budget(cfg.sims, cfg.time_limit)
        tree, gap = self._start_tree(belief)
        reused = tree.b_n[0]
        actions = self.actions
        n_actions = len(actions)
        depth, c, gamma = cfg.search_depth(self.pomdp, self.steps_taken), self.c, self.gamma
        normalized = cfg.normalized
        step = self.pomdp.step
        obs_key = self.obs_key
        u = UniformStream(rng)
        rollout = make_rollout(
            self.pomdp, cfg.rollout, actions, self.pomdp.action_space(), depth, gamma, rng, u
        )
        b_n, b_first, a_n, a_q, children = tree.b_n, tree.b_first, tree.a_n, tree.a_q, tree.children
        particles = tree.particles if cfg.reuse_tree else None
        zeros_i = [0] * n_actions
        zeros_f = [0.0] * n_actions

        def simulate(s: Any, h: int, d: int) -> float:
            first = b_first[h]
            if first < 0:
                first = b_first[h] = len(a_n)
                a_n.extend(zeros_i)
                a_q.extend(zeros_f)
            nh = b_n[h]
            ai = ucb_select(range(first, first + n_actions), a_q, a_n, nh, c, normalized)
            s2, o, r, done = step(s, actions[ai - first], rng)
            if done or d + 1 >= depth:
                total = r
            else:
                key = (ai, obs_key(o))
                h2 = children.get(key)
                if particles is not None and d == 0:
                    particles.setdefault(len(b_n) if h2 is None else h2, []).append(s2)
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

        first = b_first[0]
        if first < 0:  # a kept root that was reached once and no time was left to expand it
            q, visits = np.zeros(n_actions), np.zeros(n_actions, dtype=np.int64)
        else:
            q = np.array(a_q[first : first + n_actions])
            visits = np.array(a_n[first : first + n_actions], dtype=np.int64)
        best = best_index(q, visits) or 0
        if cfg.reuse_tree:
            self._tree = tree
        info = SearchInfo(
            sims=sims,
            seconds=budget.elapsed(),
            tree_nodes=tree.size,
            actions=list(actions),
            q=q,
            visits=visits,
            extra={"reused_visits": reused, "reuse_disagreement": gap} if cfg.reuse_tree else {},
            tree=tree if cfg.keep_tree else None,
        )
        return actions[best], info
