"""Belief-tree search with belief-dependent rewards: the engine of STRUG and its baselines.

STRUG's Algorithm 2 steps a *belief*: ``b', o, r <- G(b, a)``. Here every tree node
holds a weighted set of the same M particles (the root's M draws from the runner's
belief, particle i of every node descending from root particle i), as in PFT-DPW
(Sunberg & Kochenderfer 2018). Expanding ``(b, a)``:

1. draw one particle j by weight and step it: its observation ``o`` names the child;
2. for a child not seen before, step every other particle with positive weight, and
   reweight each by ``Z(o | s'_i, a)`` (``obs_loglik``): the child is the exact
   particle-filter posterior ``b'``, so a belief-dependent value of it (TRU over the
   M root particles, or entropy) is meaningful from its first visit;
3. the transition's reward is the belief-expected reward ``sum_i w_i r_i``.

The value backed up through a child is ``reward_weight * r + bonus + gamma * V(b')``
with ``bonus = beta * (value(b) - value(b'))``: a reduction of TRU (STRUG) or of
entropy (Entropy Regularized) pays. A new child gets a rollout (``rollout``: random,
as in the paper's Algorithm 2, a plan, or the domain's heuristic) from one of its
particles (drawn by weight), without bonus.

Actions come from :class:`planners.solvers.action_tree.ActionTree` (HPW by default on
hybrid action spaces); a node tries its untried actions in the order of the domain's
:meth:`~planners.pomdp.GenerativePOMDP.action_prior` over its particles (where the domain
has one; STRUG's particle plans come first at the root, ``root_plans``); observations
are progressively widened (``k_obs * N(ha) ^ alpha_obs`` children; a discrete
observation seen again reuses its child).

Particles that reached a terminal state stay in the child they reached it in and drop
out (weight 0) below it; a node whose particles are all terminal ends the simulation.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from planners.errors import ConfigError, check_positive_float, check_positive_int
from planners.pomdp import (
    GenerativePOMDP,
    legal_in,
    prior_order,
    provides_applicable,
    provides_prior,
)
from planners.solvers.action_tree import (
    ActionTree,
    Keep,
    Rank,
    check_widening,
    resolve_widening,
)
from planners.solvers.base import Budget, SearchInfo, TreeSearchConfig, UniformStream
from planners.solvers.exploration import best_index, most_visited_index, puct_select
from planners.solvers.rollout import check_rollout, make_rollout, plan_return, resolve_rollout

#: Leaf estimators of a new belief node.
ROLLOUTS = ("random", "plan", "heuristic", "auto")

#: Where terminal actions are solved (see ``BeliefTreeConfig.solve_terminal``).
SOLVE_TERMINAL = ("auto", "always", "never")

#: How the root chooses its next action (see ``BeliefTreeConfig.root_selection``).
ROOT_SELECTION = ("auto", "ucb", "puct")

#: Share of the root's PUCT prior spread evenly over its actions, the rest on the first
#: actions of the particles' plans by weight: an action no plan begins with (a probe, a
#: part no particle plans for) still gets a visit once the plans' first actions return
#: little (of 13 actions, an unvisited one outscores the plans' one, worth 0, after its
#: 14th visit, whatever c).
PRIOR_SPREAD = 0.5

#: A belief-dependent node value: ``value(states, weights)`` with weights shape ``(M,)``.
NodeValue = Callable[[list[Any], np.ndarray], float]


@dataclass(frozen=True)
class BeliefTreeConfig(TreeSearchConfig):
    """Hyper-parameters shared by the belief-tree solvers (STRUG, Entropy, Active).

    Attributes:
        sims: simulations per decision (default 3000).
        time_limit: wall time per decision [s] (default None).
        depth: maximum search depth incl. rollout (default: the domain's ``max_steps``).
        c: UCB exploration constant (default: the domain's largest |reward|).
        discount: search discount (default: the domain's).
        particles: M, particles per belief node, drawn from the runner's belief at
            every decision (default 32).
        beta: weight of the belief-dependent bonus (default 10, the paper's).
        k_action: action widening coefficient k (default 10).
        alpha_action: action widening exponent alpha in [0, 1] (default 1/30).
        k_obs: observation widening coefficient (default 5).
        alpha_obs: observation widening exponent in [0, 1] (default 1/15).
        widening: ``"auto"`` (default: HPW on hybrid action spaces, every action on
            finite ones), ``"all"``, ``"dpw"`` or ``"hpw"``.
        solve_terminal: when to mark an action *solved* once it has ended the episode for
            every particle of its node. Its value, the belief-expected reward over the
            node's M particles, is then final: with discrete observations a revisit returns
            the very child it created, whose stored reward cannot change. So UCB gives it
            no exploration term and the budget goes to the actions still uncertain
            (MCTS-Solver, Winands et al. 2008). ``"auto"`` (default): on domains with
            discrete observations; ``"always"``; ``"never"`` (plain UCB everywhere). With
            continuous observations a revisit makes a new child from a fresh propagation,
            so ``"auto"`` keeps exploring there. Measured (100 seeds, README): solving is
            what lets the search find ExtendedTiger's chain of paid, uninformative listens,
            since exploring the exactly known doors at every level dilutes the chain's
            mean backups; ``"always"`` lowered STRUG on LightDark2D from 3.57 to 1.99.
            With stochastic rewards the first M-particle estimate is kept.
        rollout: leaf estimate of a new node: ``"random"`` (uniform random actions from
            one particle drawn by weight) or ``"plan"`` (draw two particles i, j by
            weight and execute i's uncertainty-free plan, ``pomdp.plan_for``, from j:
            its expectation is the value of committing to a plan under the node's
            belief, high where the belief is concentrated), or ``"heuristic"`` (the
            domain's :meth:`rollout_policy` from one particle drawn by weight), or
            ``"auto"`` (``"plan"`` when the domain defines its own ``plan_for``, else
            ``"random"``: the default ``plan_for`` is a beam search, too slow to run
            once per rollout). Default ``"random"``; STRUG, which owns the
            uncertainty-free planner, defaults to ``"auto"``.
        exploration: ``"fixed"`` (default) or ``"normalized"`` UCB (see
            :class:`TreeSearchConfig`); ``c_normalized`` its constant (default 1.0).
        horizon: ``"receding"`` (default) or ``"episode"`` (see :class:`TreeSearchConfig`).
        root_selection: how the root picks the action to simulate: ``"ucb"`` (the
            paper's) or ``"puct"`` (``Q + c P sqrt(N) / (1 + n)``, P the weight of the
            particles whose plan begins with the action, :data:`PRIOR_SPREAD` of it
            spread evenly; the decision is the most visited action); ``"auto"``
            (default): ``"puct"`` where the domain has an action prior and the solver
            has its particles' plans (STRUG on the manipulation tasks), else ``"ucb"``.
        stop_decided: a PUCT root's search under a simulation budget (no
            ``time_limit``) stops once its decision is settled: the most visited root
            action leads every other by more than the simulations left, so none of
            them could change the decision (visit-count pruning, as in Leela Chess
            Zero's "smart pruning"). The decision is the one the whole budget gives;
            ``sims`` reports the simulations run. Default True; a UCB root, whose
            decision is by value, always runs its whole budget.
    """

    particles: int = 32
    beta: float = 10.0
    k_action: float = 10.0
    alpha_action: float = 1.0 / 30.0
    k_obs: float = 5.0
    alpha_obs: float = 1.0 / 15.0
    widening: str = "auto"
    rollout: str = "random"
    solve_terminal: str = "auto"
    root_selection: str = "auto"
    stop_decided: bool = True

    def __post_init__(self) -> None:
        super().__post_init__()
        check_positive_int("particles", self.particles)
        if self.root_selection not in ROOT_SELECTION:
            raise ConfigError(
                f"root_selection must be one of {', '.join(ROOT_SELECTION)}, "
                f"got {self.root_selection!r}"
            )
        if self.solve_terminal not in SOLVE_TERMINAL:
            raise ConfigError(
                f"solve_terminal must be one of {', '.join(SOLVE_TERMINAL)}, "
                f"got {self.solve_terminal!r}"
            )
        if not isinstance(self.stop_decided, bool):
            raise ConfigError(f"stop_decided must be true or false, got {self.stop_decided!r}")
        check_rollout(self.rollout, ROLLOUTS)
        check_positive_float("beta", self.beta, allow_zero=True)
        check_widening(self.widening, self.k_action, self.alpha_action)
        check_positive_float("k_obs", self.k_obs)
        check_positive_float("alpha_obs", self.alpha_obs, allow_zero=True, upper=1.0)


class EpisodeSteps:
    """The real steps of the episode a belief-tree planner serves (``horizon="episode"``)."""

    steps_taken: int = 0

    def observe(self, action: Hashable, observation: Any) -> None:
        """Count one real step (the runner calls this after every step)."""
        self.steps_taken += 1


def root_particles(
    pomdp: GenerativePOMDP, belief: Any, m: int, rng: np.random.Generator
) -> tuple[list[Any], np.ndarray]:
    """M root particles drawn from ``belief`` by weight, and their weights ``(M,)``.

    With discrete states (``pomdp.discrete_states``) the draw is importance-corrected:
    a state drawn ``n`` times out of M gets weight ``b(state) / n`` per copy, so the
    root's mass on every state equals the runner's belief exactly. Without it a Tiger
    belief of 0.5 would sample as, say, 19 vs 13 particles, making a door look worth
    +/-1.9 at the root before any search. Continuous states keep equal weights.
    """
    idx = belief.sample_indices(rng, m).tolist()
    states = [belief.states[i] for i in idx]
    if not pomdp.discrete_states(states):
        return states, np.ones(m)
    mass: dict[Any, float] = {}
    for s, w in zip(belief.states, belief.weights.tolist(), strict=True):
        mass[s] = mass.get(s, 0.0) + w
    copies: dict[Any, int] = {}
    for s in states:
        copies[s] = copies.get(s, 0) + 1
    return states, np.array([mass[s] / copies[s] for s in states])


@dataclass
class TreeResult:
    """What one belief-tree search found.

    Attributes:
        actions: root action children; ``q`` and ``visits`` per child.
        q: value per root action, shape ``(A,)``.
        visits: visits per root action, shape ``(A,)``.
        bonus: mean bonus earned by the root action's observation children, ``(A,)``.
        best: the root's decision (:meth:`BeliefTreeSearch.decision`; None if none visited).
        root_value: the belief-dependent value of the root (TRU or entropy), or NaN.
        sims: simulations run.
        belief_nodes: belief nodes created.
        action_nodes: action nodes created.
        seconds: search wall time [s].
        tree: the action tree (its statistics and observation children).
        search: the whole search, belief nodes included (``SearchInfo.tree`` with
            ``keep_tree``).
    """

    actions: list[Hashable]
    q: np.ndarray
    visits: np.ndarray
    bonus: np.ndarray
    best: Hashable | None
    root_value: float
    sims: int
    belief_nodes: int
    action_nodes: int
    seconds: float
    tree: ActionTree = field(repr=False)
    search: BeliefTreeSearch = field(repr=False)

    def search_info(self, extra_seconds: float = 0.0, **extra: Any) -> SearchInfo:
        """The :class:`SearchInfo` of this search, with solver-specific ``extra`` figures
        (the tree, ``search``, only with the config's ``keep_tree``)."""
        return SearchInfo(
            sims=self.sims,
            seconds=self.seconds + extra_seconds,
            tree_nodes=self.belief_nodes + self.action_nodes,
            actions=self.actions,
            q=self.q,
            visits=self.visits,
            extra={"bonus": self.bonus, **extra},
            tree=self.search if self.search.config.keep_tree else None,
        )


class BeliefTreeSearch:
    """One belief-tree search (see the module docstring), its tree as named arrays.

    Per belief node ``h`` (node 0 is the root): ``visits[h]``, the M particle
    ``states[h]`` and their weights ``weights[h]`` (shape ``(M,)``), ``alive[h]`` (False
    for particles that reached a terminal state), ``cdf[h]`` (cumulative live weight,
    for drawing by weight), ``terminal[h]`` (no live weight left), and the transition
    into it: the belief-expected ``reward[h]``, the ``bonus[h]`` it earned and the node
    value ``value[h]`` (TRU, entropy, or NaN without a bonus). Action nodes, their
    statistics and their observation children live in ``tree``
    (:class:`ActionTree`); ``obs_child`` maps ``(action node, observation key)`` to a
    child when observations are discrete.

    Args:
        pomdp: the generative model.
        config: budgets and widening (its ``beta`` is ignored in favour of ``beta``).
        rng: all randomness of the search.
        node_value: belief-dependent value whose reduction earns ``beta`` per unit; None
            for no bonus.
        beta: bonus weight.
        reward_weight: weight of the task reward (0 for pure information gathering).
        c: UCB constant of ``exploration="fixed"`` (default: the config's, else the
            domain's largest |reward|); normalised exploration uses ``c_normalized``.
        terminal_bonus: bonus of a transition that ends the episode, as a function of
            the parent's value (default: none).
        steps_taken: real steps of the episode so far (``horizon="episode"``).
        root_plans: per root particle ``i``, its uncertainty-free plan (STRUG's matrix
            plans): on a domain with an :meth:`~planners.pomdp.GenerativePOMDP.action_prior`,
            the root tries first the actions that begin the plans of the most weight
            (then the domain's order). None (default): the domain's order alone; a
            domain without a prior keeps the list order either way.
    """

    def __init__(
        self,
        pomdp: GenerativePOMDP,
        config: BeliefTreeConfig,
        rng: np.random.Generator,
        *,
        node_value: NodeValue | None,
        beta: float,
        reward_weight: float = 1.0,
        c: float | None = None,
        terminal_bonus: Callable[[float], float] | None = None,
        steps_taken: int = 0,
        root_plans: Sequence[Sequence[Hashable]] | None = None,
    ) -> None:
        self.pomdp, self.config, self.rng = pomdp, config, rng
        _, c_default, self.gamma = config.resolved(pomdp)
        self.depth = config.search_depth(pomdp, steps_taken)
        c = c_default if c is None or config.normalized else c
        space = pomdp.action_space()
        widening = resolve_widening(config.widening, space, "hpw")
        self.u = UniformStream(rng)
        self.tree = ActionTree(
            space, widening, config.k_action, config.alpha_action, c, rng, self.u,
            config.normalized,
        )  # fmt: skip
        rollout = resolve_rollout(config.rollout, pomdp)
        self.plan_rollout = rollout == "plan"
        finite = list(space.discretized) if widening == "all" else None
        leaf = "random" if self.plan_rollout else rollout
        self.run_from = make_rollout(
            pomdp, leaf, finite, space, self.depth, self.gamma, rng, self.u
        )
        self.filter = provides_applicable(pomdp)
        self.prior = provides_prior(pomdp)
        self.root_plans = root_plans
        if config.root_selection == "puct" and widening != "all":
            raise ConfigError(
                "root_selection='puct' needs a finite action list (widening 'all'), "
                f"got widening {widening!r}"
            )
        guided = self.prior and root_plans is not None and widening == "all"
        self.puct = config.root_selection == "puct" or (config.root_selection == "auto" and guided)
        self.root_prior: list[float] | None = None
        self.node_value, self.beta, self.reward_weight = node_value, beta, reward_weight
        self.terminal_bonus = terminal_bonus
        self.with_bonus = node_value is not None and beta > 0.0
        self.discrete_obs = pomdp.discrete_observations
        self.solve_terminal = config.solve_terminal == "always" or (
            config.solve_terminal == "auto" and self.discrete_obs
        )
        self.visits: list[int] = []
        self.states: list[list[Any]] = []
        self.weights: list[np.ndarray] = []
        self.cdf: list[list[float]] = []
        self.alive: list[list[bool]] = []
        self.terminal: list[bool] = []
        self.reward: list[float] = []
        self.bonus: list[float] = []
        self.value: list[float] = []
        self.obs_child: dict[tuple[int, Hashable], int] = {}

    def add_node(
        self, states: list[Any], w: np.ndarray, alive: list[bool], r: float, parent: int
    ) -> int:
        """Append a belief node reached from ``parent`` (-1 for the root) with reward ``r``."""
        cdf, acc = [], 0.0
        for wi, ok in zip(w.tolist(), alive, strict=True):
            acc += wi if ok else 0.0
            cdf.append(acc)
        terminal = acc <= 0.0
        # Information that arrives with the episode's end cannot be used: no bonus.
        with_bonus = self.with_bonus
        value = self.node_value(states, w) if with_bonus and not terminal else math.nan
        if parent < 0 or not with_bonus:
            bonus = 0.0
        elif terminal:
            tb = self.terminal_bonus
            bonus = tb(self.value[parent]) if tb is not None else 0.0
        else:
            bonus = self.beta * (self.value[parent] - value)
        for column, x in (
            (self.visits, 0), (self.states, states), (self.weights, w), (self.cdf, cdf),
            (self.alive, alive), (self.terminal, terminal), (self.reward, r),
            (self.bonus, bonus), (self.value, value),
        ):  # fmt: skip
            column.append(x)
        return self.tree.add_belief_node()

    def draw(self, h: int) -> int:
        """A live particle index of node ``h``, drawn by weight."""
        cdf = self.cdf[h]
        return min(bisect_right(cdf, self.u() * cdf[-1]), len(cdf) - 1)

    def expand(self, h: int, anode: int) -> tuple[int, bool, bool]:
        """The child of ``(h, a)`` reached by one observation; True if it is new; True if
        the action ended the episode for every particle it propagated."""
        pomdp, a, rng = self.pomdp, self.tree.a_action[anode], self.rng
        states, w, alive_h = self.states[h], self.weights[h], self.alive[h]
        j = self.draw(h)
        sj, o, rj, done_j = pomdp.step(states[j], a, rng)
        key = (anode, pomdp.observation_key(o)) if self.discrete_obs else None
        if key is not None and key in self.obs_child:
            return self.obs_child[key], False, False
        # Propagate the other live, weighted particles (weightless or terminal ones stay).
        idx = [i for i, wi in enumerate(w.tolist()) if wi > 0.0 and alive_h[i] and i != j]
        nxt, rew, done = pomdp.transition_many([states[i] for i in idx], a, rng)
        idx.append(j)
        nxt.append(sj)
        rew, done = np.append(rew, rj), np.append(done, done_j)
        new_states, alive = list(states), [False] * len(states)
        for i, s, d_i in zip(idx, nxt, done.tolist(), strict=True):
            new_states[i], alive[i] = s, not d_i
        w_prior = w[idx]
        logw = np.full(len(states), -np.inf)
        logw[idx] = np.log(w_prior) + pomdp.obs_loglik_many(o, nxt, a)
        top = logw.max()
        w_new = np.exp(logw - top) if np.isfinite(top) else w.copy()
        w_new /= w_new.sum()
        reward = float(w_prior @ rew / w_prior.sum())
        child = self.add_node(new_states, w_new, alive, reward, h)
        if key is not None:
            self.obs_child[key] = child
        return child, True, bool(done.all())

    def rollout(self, h: int, d: int) -> float:
        """Leaf estimate of the new node ``h`` at depth ``d``, from a particle drawn by
        weight: a random (or heuristic) rollout, or the plan of another particle."""
        s = self.states[h][self.draw(h)]
        if not self.plan_rollout:
            return self.run_from(s, d)
        plan = self.pomdp.plan_for(self.states[h][self.draw(h)], self.rng)
        return plan_return(self.pomdp, s, plan, d, self.depth, self.gamma, self.rng)

    def offered(self, h: int) -> Keep:
        """The actions node ``h`` offers: those applicable in one of its live,
        weighted particles."""
        return legal_in(self.pomdp, self.states[h], self.weights[h], self.alive[h])

    def ranked(self, h: int) -> Rank:
        """The order in which node ``h`` tries its untried actions: by the domain's
        prior over its live, weighted particles (:func:`planners.pomdp.prior_order`);
        at the root, first by the weight of the particles whose plan (``root_plans``)
        begins with the action."""
        pomdp, states, w, alive = self.pomdp, self.states[h], self.weights[h], self.alive[h]

        def rank(actions: list[Hashable]) -> list[Hashable]:
            live = [i for i, wi in enumerate(w.tolist()) if wi > 0.0 and alive[i]]
            ls, lw = [states[i] for i in live], [float(w[i]) for i in live]
            first = self.plans_first() if h == 0 else {}
            planned = (lambda a: first.get(a, 0.0)) if first else None
            return prior_order(pomdp, ls, lw, actions, planned)

        return rank

    def plans_first(self) -> dict[Hashable, float]:
        """Per action, the weight of the root's live particles whose plan
        (``root_plans``) begins with it (empty without plans)."""
        first: dict[Hashable, float] = {}
        if self.root_plans is None:
            return first
        for i, wi in enumerate(self.weights[0].tolist()):
            plan = self.root_plans[i]
            if plan and wi > 0.0 and self.alive[0][i]:
                first[plan[0]] = first.get(plan[0], 0.0) + wi
        return first

    def select_root(self, n: int, keep: Keep | None, rank: Rank | None) -> int:
        """The root's action node to simulate by PUCT (:func:`puct_select`), its prior
        made with its children: the weight of the root particles whose plan
        (``root_plans``) begins with each action, :data:`PRIOR_SPREAD` spread evenly."""
        tree = self.tree
        kids = tree.b_children[0] or tree.expand_all(0, keep, rank)
        if self.root_prior is None:
            first = self.plans_first()
            mass = [first.get(tree.a_action[j], 0.0) for j in kids]
            total = sum(mass)
            spread = PRIOR_SPREAD if total > 0.0 else 1.0
            even = spread / len(kids)
            self.root_prior = [(1.0 - spread) * m / (total or 1.0) + even for m in mass]
        return puct_select(kids, tree.a_q, tree.a_n, n, tree.c, self.root_prior)

    def simulate(self, h: int, d: int) -> float:
        """One descent from belief node ``h`` at depth ``d``; returns its return."""
        tree, nh = self.tree, self.visits[h]
        keep = self.offered(h) if self.filter else None
        rank = self.ranked(h) if self.prior else None
        if h == 0 and self.puct:
            anode, snode = self.select_root(nh, keep, rank), -1
        else:
            anode, snode = tree.select(h, nh, keep, rank)
        generated = tree.a_children[anode]
        cfg = self.config
        if len(generated) <= cfg.k_obs * tree.a_n[anode] ** cfg.alpha_obs:
            child, new, ends_all = self.expand(h, anode)
            generated.append(child)
            if ends_all and self.solve_terminal:
                tree.mark_solved(anode, snode)
        else:
            child, new = generated[int(self.u() * len(generated))], False
        total = self.reward_weight * self.reward[child] + self.bonus[child]
        if not self.terminal[child] and d + 1 < self.depth:
            future = self.rollout(child, d + 1) if new else self.simulate(child, d + 1)
            total += self.gamma * future
        self.visits[h] = nh + 1
        tree.update(anode, snode, total)
        return total

    def settled(self, left: int) -> bool:
        """Whether ``left`` more simulations cannot change a PUCT root's decision (the
        most visited action): its visits exceed every other action's by more than
        ``left``, so no other can reach them."""
        visits = sorted((self.tree.a_n[j] for j in self.tree.b_children[0]), reverse=True)
        return len(visits) > 0 and visits[0] - (visits[1] if len(visits) > 1 else 0) > left

    def decision(self) -> Hashable | None:
        """The root's action: after a PUCT search the most visited, else the visited
        one of the highest value (None if nothing was visited)."""
        actions, q, visits = self.tree.root_stats()
        i = most_visited_index(q, visits) if self.puct else best_index(q, visits)
        return None if i is None else actions[i]

    def run(self, root_states: Sequence[Any], root_weights: np.ndarray) -> TreeResult:
        """Search from the belief ``(root_states, root_weights)`` (weights ``(M,)``)."""
        cfg = self.config
        budget = Budget(cfg.sims, cfg.time_limit)
        w0 = np.asarray(root_weights, dtype=float)
        self.add_node(list(root_states), w0 / w0.sum(), [True] * len(w0), 0.0, -1)
        sims = 0
        # The stop needs the simulations left, known only under a simulation budget.
        stop = self.puct and cfg.stop_decided and cfg.time_limit is None and cfg.sims is not None
        while not budget.done(sims) and not (stop and self.settled(cfg.sims - sims)):
            self.simulate(0, 0)
            sims += 1
        tree = self.tree
        actions, q, visits = tree.root_stats()
        bonus = np.array(
            [
                float(np.mean([self.bonus[ch] for ch in tree.a_children[j]]))
                if tree.a_children[j]
                else 0.0
                for j in tree.b_children[0]
            ]
        )
        return TreeResult(
            actions=actions,
            q=q,
            visits=visits,
            bonus=bonus,
            best=self.decision(),
            root_value=self.value[0] if self.with_bonus else math.nan,
            sims=sims,
            belief_nodes=len(self.visits),
            action_nodes=tree.size(),
            seconds=budget.elapsed(),
            tree=tree,
            search=self,
        )


def belief_tree_search(
    pomdp: GenerativePOMDP,
    config: BeliefTreeConfig,
    root_states: Sequence[Any],
    root_weights: np.ndarray,
    rng: np.random.Generator,
    **options: Any,
) -> TreeResult:
    """``BeliefTreeSearch(pomdp, config, rng, **options).run(root_states, root_weights)``."""
    return BeliefTreeSearch(pomdp, config, rng, **options).run(root_states, root_weights)
