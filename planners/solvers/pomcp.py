"""POMCP (Silver & Veness 2010): UCT over action-observation histories.

Discrete actions and observations. On a continuous domain it runs as the POMCPOW
paper's baseline does: actions come from the domain's documented discretisation
(``ActionSpace.discretized``) and observations are binned on a grid of width
``obs_bin`` per dimension, so that repeated histories share a node.

The tree is flat arrays indexed by node id (:class:`POMCPTree`): the action nodes,
their visit counts and values on the :class:`ActionTree` every tree solver shares
(``"all"``: every action of the finite set, UCB by
:func:`planners.solvers.exploration.ucb_select`), per belief node its visit count.
Children of an action node are found in one dict keyed by ``(action node,
observation key)`` (``pomdp.observation_key``, binned on continuous domains). Nodes
are expanded lazily: a history seen for the first time gets a node and a rollout; its
action nodes are created on its second visit. Root states are drawn from the runner's particle
belief. By default the tree is rebuilt at every decision (the published algorithm as
Table I runs it); ``reuse_tree`` keeps the subtree under the executed action and the
real observation (:mod:`planners.solvers.reuse`). ``exploration`` chooses the UCB
score (:mod:`planners.solvers.exploration`) and ``rollout`` the leaf estimate
(:mod:`planners.solvers.rollout`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from planners.belief import ParticleBelief
from planners.errors import check_positive_float
from planners.pomdp import GenerativePOMDP, check_pomdp
from planners.solvers.action_tree import ActionTree, history_offers, history_ranks
from planners.solvers.base import (
    Budget,
    RootSampler,
    SearchInfo,
    TreeSearchConfig,
    UniformStream,
)
from planners.solvers.exploration import best_index
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
    numbers, as the default key of a 1-d numpy array is)."""
    key_of = pomdp.observation_key
    if pomdp.discrete_observations:
        return key_of
    inv = 1.0 / obs_bin

    def binned(o: Any) -> Hashable:
        k = key_of(o)
        if isinstance(k, tuple):
            return tuple(math.floor(x * inv) for x in k)
        return math.floor(k * inv)  # type: ignore[operator]

    return binned


class POMCPTree:
    """A POMCP tree: action nodes on the shared :class:`ActionTree` (every action of the
    finite set expanded at a node's first selection), belief nodes as named lists;
    belief node 0 is the root.

    Attributes:
        actions: the action nodes and their statistics.
        visits: visits per belief node.
        children: ``(action node, observation key) -> belief node``.
        particles: for the root's grandchildren (the belief nodes one step down), the
            next states the simulations brought there (filled only with ``reuse_tree``).
    """

    def __init__(self, actions: ActionTree) -> None:
        self.actions = actions
        self.visits: list[int] = []
        self.children: dict[tuple[int, Hashable], int] = {}
        self.particles: dict[int, list[Any]] = {}

    def add_node(self) -> int:
        """Append a belief node; returns its id."""
        self.visits.append(0)
        return self.actions.add_belief_node()

    @property
    def size(self) -> int:
        """Belief nodes + action nodes."""
        return len(self.visits) + self.actions.size()

    def child(self, action: Hashable, obs_key: Hashable) -> int | None:
        """The root's belief child under (action, observation key), if any."""
        tree = self.actions
        for anode in tree.b_children[0] if tree.b_children else ():
            if tree.a_action[anode] == action:
                return self.children.get((anode, obs_key))
        return None

    def subtree(self, h: int) -> POMCPTree:
        """A copy of the subtree under belief node ``h``, renumbered breadth-first."""
        old = self.actions
        below: dict[int, list[tuple[Hashable, int]]] = {}
        for (anode, key), child in self.children.items():
            below.setdefault(anode, []).append((key, child))
        out = POMCPTree(old.empty_like())
        new = out.actions
        queue, head = [h], 0
        while head < len(queue):
            src = queue[head]
            head += 1
            dst = out.add_node()
            out.visits[dst] = self.visits[src]
            if not old.b_children[src]:
                continue
            kept = [old.a_action[anode] for anode in old.b_children[src]]
            for j, anode in zip(new.add_children(dst, kept), old.b_children[src], strict=True):
                new.a_n[j], new.a_q[j] = old.a_n[anode], old.a_q[anode]
                for key, child in below.get(anode, ()):
                    out.children[(j, key)] = len(queue)
                    queue.append(child)
        return out


class POMCPPlanner:
    """A POMCP search; with ``reuse_tree`` it keeps its tree between decisions."""

    def __init__(self, config: POMCPConfig, pomdp: GenerativePOMDP) -> None:
        check_pomdp(pomdp)
        self.config = config
        self.pomdp = pomdp
        self.actions = list(pomdp.action_space().discretized)
        self._index = {a: i for i, a in enumerate(self.actions)}
        self.depth, self.c, self.gamma = config.resolved(pomdp)
        self.obs_key = observation_bins(pomdp, config.obs_bin)
        if config.rollout == "heuristic":
            domain_policy(pomdp)  # a domain without one fails here, not mid-episode
        self._tree: POMCPTree | None = None
        self._executed: tuple[Hashable, Hashable] | None = None
        self.steps_taken = 0

    def observe(self, action: Hashable, observation: Any) -> None:
        """Record the executed action and the real observation (``reuse_tree``, ``horizon``)."""
        self.steps_taken += 1
        if self.config.reuse_tree and action in self.actions:
            key = self.obs_key(observation)
            self._executed = (action, key)

    def _fresh(self, rng: np.random.Generator, u: UniformStream) -> POMCPTree:
        cfg, space = self.config, self.pomdp.action_space()
        # "all": every action of the discretised set; k and alpha are unused there.
        tree = POMCPTree(ActionTree(space, "all", 1.0, 0.0, self.c, rng, u, cfg.normalized))
        tree.add_node()
        return tree

    def _start_tree(
        self, belief: ParticleBelief, rng: np.random.Generator, u: UniformStream
    ) -> tuple[POMCPTree, float]:
        """The tree to search from, and the disagreement of a kept subtree (NaN if none)."""
        old, executed = self._tree, self._executed
        self._tree, self._executed = None, None
        if old is None or executed is None:
            return self._fresh(rng, u), math.nan
        h = old.child(*executed)
        if h is None:
            return self._fresh(rng, u), math.nan
        gap = particle_disagreement(self.pomdp, old.particles.get(h, []), belief)
        if gap > self.config.reuse_tolerance:
            return self._fresh(rng, u), gap
        return old.subtree(h), gap

    def act(self, belief: ParticleBelief, rng: np.random.Generator) -> tuple[Hashable, SearchInfo]:
        cfg, pomdp = self.config, self.pomdp
        budget = Budget(cfg.sims, cfg.time_limit)
        u = UniformStream(rng)
        tree, gap = self._start_tree(belief, rng, u)
        reused = tree.visits[0]
        depth, gamma = cfg.search_depth(pomdp, self.steps_taken), self.gamma
        step, obs_key = pomdp.step, self.obs_key
        space = pomdp.action_space()
        rollout = make_rollout(pomdp, cfg.rollout, self.actions, space, depth, gamma, rng, u)
        nodes = tree.actions
        select, backup, a_action = nodes.select, nodes.update, nodes.a_action
        b_n, children, add_belief = tree.visits, tree.children, nodes.add_belief_node
        particles = tree.particles if cfg.reuse_tree else None

        offers = history_offers(pomdp, belief)  # None: every action, every node
        ranks = history_ranks(pomdp, belief)  # None: the list order

        def simulate(s: Any, h: int, d: int) -> float:
            nh = b_n[h]
            keep = None if offers is None else offers(h, s)
            anode, _ = select(h, nh, keep, None if ranks is None else ranks(h, s))
            s2, o, r, done = step(s, a_action[anode], rng)
            if done or d + 1 >= depth:
                total = r
            else:
                key = (anode, obs_key(o))
                h2 = children.get(key)
                if particles is not None and d == 0:
                    particles.setdefault(len(b_n) if h2 is None else h2, []).append(s2)
                if h2 is None:
                    b_n.append(0)  # POMCPTree.add_node, inlined on this hot path
                    children[key] = add_belief()
                    total = r + gamma * rollout(s2, d + 1)
                else:
                    total = r + gamma * simulate(s2, h2, d + 1)
            b_n[h] = nh + 1
            backup(anode, -1, total)
            return total

        sample_root = RootSampler(belief, rng)
        sims = 0
        while not budget.done(sims):
            simulate(sample_root(), 0, 0)
            sims += 1

        # Per action of the finite set, in order (a root without children: a kept root
        # reached once with no time left to expand it; actions the root does not offer
        # stay unvisited).
        q, visits = np.zeros(len(self.actions)), np.zeros(len(self.actions), dtype=np.int64)
        for anode in nodes.b_children[0]:
            i = self._index[nodes.a_action[anode]]
            q[i], visits[i] = nodes.a_q[anode], nodes.a_n[anode]
        best = best_index(q, visits) or 0
        if cfg.reuse_tree:
            self._tree = tree
        info = SearchInfo(
            sims=sims,
            seconds=budget.elapsed(),
            tree_nodes=tree.size,
            actions=list(self.actions),
            q=q,
            visits=visits,
            extra={"reused_visits": reused, "reuse_disagreement": gap} if cfg.reuse_tree else {},
            tree=tree if cfg.keep_tree else None,
        )
        return self.actions[best], info
