"""Action children of belief nodes: full expansion, DPW, or HPW (STRUG's Algorithm 3).

Every tree solver asks the same question at a belief node: which action to simulate
next. Three answers, chosen by a config's ``widening`` field:

* ``"all"``: every action of the (finite or discretised) action set is a child from
  the first visit; UCB picks among them.
* ``"dpw"``: progressive widening over the whole action space (POMCPOW's): while the
  node has at most ``k * N(h)^alpha`` children, a new action is drawn uniformly from
  the action space (a uniform schema, then uniform parameters).
* ``"hpw"``: hierarchical progressive widening (the STRUG paper's Algorithm 3): UCB
  first picks a *schema* (a controller kind) from per-(node, schema) statistics; then,
  within that schema, while it has at most ``k * N(h, schema)^alpha`` parameter
  children a new parameter vector is drawn from the schema's box, and UCB picks among
  them. A schema without parameters has exactly one child. Promising controllers get
  their parameters explored without paying for the parameters of the others.
* ``"auto"``: ``"all"`` on a finite action space, else the solver's default.

Untried actions are tried first (UCB gives them no score), in the order the node's
``rank`` puts them when its children are made: the domain's
:meth:`~planners.pomdp.GenerativePOMDP.action_prior` over the node's particles
(:func:`planners.pomdp.prior_order`; STRUG puts its particles' plans first at the root),
else the action list's order. With a budget of a few simulations per action this decides
which actions get a visit at all: on a manipulation task the list puts ``Pick`` after
every part's openings and probes. (DPW and HPW draw new actions one at a time, so there
is nothing to order; a domain without a prior keeps the list order bit for bit.)

A node offers only the actions its solver's ``keep`` accepts (the domain's
:meth:`~planners.pomdp.GenerativePOMDP.applicable` in the node's particles): a no-op
costs a step and is worth the discounted value of its own node, so with a handful of
visits per action it would win the root by noise alone.

UCB is :func:`planners.solvers.exploration.ucb_select`: ``Q + c sqrt(log N / n)``
(``normalized=False``, POMCPOW.jl's ``MaxUCB``) or its scale-free form with Q min-max
normalised over the node's visited children; unvisited children are tried first, in
the order they were made. A child marked *solved* (:meth:`ActionTree.mark_solved`)
competes with its value alone, without the exploration term: its value is known
exactly, so visiting it again cannot teach anything (MCTS-Solver, Winands, Bjornsson &
Saito 2008). Storage is flat lists indexed by node id; every action node also holds the
list of observation children (belief-node ids, with repeats) its solver generated under
it, so a search keeps no per-node list of its own parallel to the tree's.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any

import numpy as np

from planners.belief import ParticleBelief
from planners.errors import ConfigError, check_positive_float
from planners.pomdp import (
    ActionSpace,
    GenerativePOMDP,
    legal_in,
    prior_order,
    provides_applicable,
    provides_prior,
)
from planners.solvers.exploration import best_index, ucb_select

WIDENING_MODES = ("auto", "all", "dpw", "hpw")

#: Which actions a node offers: ``keep(a)`` is True for an action applicable there.
Keep = Callable[[Hashable], bool]

#: Draws of a widening step before it takes an action ``keep`` refuses (a schema whose
#: every parameter is refused still gets a child, as with ``keep`` None).
KEEP_TRIES = 20

#: ``offers(h, s)``: the actions history node ``h`` offers, reached by state ``s``.
Offers = Callable[[int, Any], Keep]

#: The order in which a node tries its untried actions: ``rank(actions)`` returns them
#: reordered (:func:`planners.pomdp.prior_order`).
Rank = Callable[[list[Hashable]], list[Hashable]]

#: ``ranks(h, s)``: the :data:`Rank` of history node ``h``, reached by state ``s``.
Ranks = Callable[[int, Any], Rank]


def history_offers(pomdp: GenerativePOMDP, belief: ParticleBelief) -> Offers | None:
    """For the solvers whose nodes are histories (POMCP, POMCPOW): ``offers(h, s)``,
    the actions node ``h`` offers when state ``s`` reaches it (at the root, those
    applicable in a weighted particle of ``belief``; deeper, those applicable in the
    state that reaches the node first, since "all" widening reads ``keep`` once: a
    history holds the states of one action-observation sequence, which agree on it
    mostly); None on a domain without its own ``applicable``."""
    if not provides_applicable(pomdp):
        return None
    root = legal_in(pomdp, belief.states, belief.weights)
    applicable = pomdp.applicable
    return lambda h, s: root if h == 0 else (lambda a: applicable(s, a))


def history_ranks(pomdp: GenerativePOMDP, belief: ParticleBelief) -> Ranks | None:
    """For the solvers whose nodes are histories (POMCP, POMCPOW): ``ranks(h, s)``, the
    order in which node ``h`` tries its untried actions (the domain's
    :meth:`~planners.pomdp.GenerativePOMDP.action_prior` over the weighted particles of
    ``belief`` at the root; deeper, over the state that reaches the node first, as
    :func:`history_offers` reads it); None on a domain without its own prior (the list
    order)."""
    if not provides_prior(pomdp):
        return None
    live = [(s, w) for s, w in zip(belief.states, belief.weights.tolist(), strict=True) if w > 0]
    root_states, root_weights = [s for s, _ in live], [w for _, w in live]

    def ranks(h: int, s: Any) -> Rank:
        if h == 0:
            return lambda actions: prior_order(pomdp, root_states, root_weights, actions)
        return lambda actions: prior_order(pomdp, [s], [1.0], actions)

    return ranks


def check_widening(mode: str, k: float, alpha: float) -> None:
    """Validate a ``widening`` mode and its ``k``, ``alpha``."""
    if mode not in WIDENING_MODES:
        raise ConfigError(f"widening must be one of {', '.join(WIDENING_MODES)}, got {mode!r}")
    check_positive_float("k_action", k)
    check_positive_float("alpha_action", alpha, allow_zero=True, upper=1.0)


def resolve_widening(mode: str, space: ActionSpace, continuous_default: str) -> str:
    """The concrete mode (``all``, ``dpw`` or ``hpw``) for ``space``."""
    if mode == "auto":
        return "all" if space.is_discrete else continuous_default
    return mode


class ActionTree:
    """Action nodes hanging off belief nodes, with UCB selection and widening.

    Attributes:
        a_n: visits per action node.
        a_q: value estimate per action node.
        a_action: the action of each action node.
        a_solved: per action node, True once its value is known exactly.
        a_children: per action node, the belief-node ids of the observation children
            generated under it, in order and with repeats (filled by the solver: a
            uniform pick from it is a pick in proportion to how often each came up).
        b_children: action-node ids per belief node (all schemas).
        b_schema_first: HPW only: the first schema node of each belief node (-1 until
            its first selection).
    """

    def __init__(
        self,
        space: ActionSpace,
        mode: str,
        k: float,
        alpha: float,
        c: float,
        rng: np.random.Generator,
        uniform: Callable[[], float],
        normalized: bool = False,
    ) -> None:
        if mode not in ("all", "dpw", "hpw"):
            raise ConfigError(f"ActionTree mode must be all, dpw or hpw, got {mode!r}")
        self.space, self.mode, self.k, self.alpha, self.c = space, mode, k, alpha, c
        self.normalized = normalized
        self.rng, self.u = rng, uniform
        self.actions = list(space.discretized)
        self.n_schemas = len(space.schemas)
        self.a_n: list[int] = []
        self.a_q: list[float] = []
        self.a_action: list[Hashable] = []
        self.a_solved: list[bool] = []
        self.a_children: list[list[int]] = []
        self.b_children: list[list[int]] = []
        # What UCB reads as "solved": None until a node is solved (no per-child test).
        self._solved: list[bool] | None = None
        self._lookup: dict[tuple[int, Hashable], int] = {}
        # HPW: schema nodes (one per belief node and schema), contiguous per belief node.
        self.s_n: list[int] = []
        self.s_q: list[float] = []
        self.s_children: list[list[int]] = []
        self.s_solved: list[bool] = []
        self.s_owner: list[int] = []
        self.b_schema_first: list[int] = []

    def empty_like(self) -> ActionTree:
        """A tree without nodes and with this one's settings (a kept subtree's new home)."""
        return ActionTree(
            self.space, self.mode, self.k, self.alpha, self.c, self.rng, self.u, self.normalized
        )

    def expand_all(self, h: int, keep: Keep | None = None, rank: Rank | None = None) -> list[int]:
        """Make every action of the finite action set that ``keep`` accepts (all when
        ``keep`` is None or accepts none) a child of ``h`` (which has none yet), in the
        order ``rank`` puts them (None: the list's); returns its children."""
        actions = self.actions
        if keep is not None:
            actions = [a for a in actions if keep(a)] or actions
        if rank is not None:
            actions = rank(list(actions))
        return self.add_children(h, actions)

    def add_children(self, h: int, actions: list[Hashable]) -> list[int]:
        """Make ``actions`` (distinct, so no lookup is needed) the children of ``h``
        (which has none yet); returns its children."""
        n, k = len(self.a_n), len(actions)
        self.b_children[h].extend(range(n, n + k))
        self.a_n.extend([0] * k)
        self.a_q.extend([0.0] * k)
        self.a_action.extend(actions)
        self.a_solved.extend([False] * k)
        self.a_children.extend([[] for _ in range(k)])
        return self.b_children[h]

    def _draw(self, draw: Callable[[], Hashable], keep: Keep | None) -> Hashable:
        """``draw()`` until ``keep`` accepts it (at most :data:`KEEP_TRIES` draws; the
        last one is taken regardless)."""
        a = draw()
        for _ in range(KEEP_TRIES - 1):
            if keep is None or keep(a):
                break
            a = draw()
        return a

    def add_belief_node(self) -> int:
        """Register the next belief node (call once per belief node); returns its id."""
        self.b_children.append([])
        if self.mode == "hpw":
            self.b_schema_first.append(-1)
        return len(self.b_children) - 1

    def _add_action(self, h: int, a: Hashable) -> int:
        key = (h, a)
        node = self._lookup.get(key)
        if node is None:
            node = self._lookup[key] = len(self.a_n)
            self.b_children[h].append(node)
            self.a_n.append(0)
            self.a_q.append(0.0)
            self.a_action.append(a)
            self.a_solved.append(False)
            self.a_children.append([])
        return node

    def mark_solved(self, anode: int, snode: int = -1) -> None:
        """Declare the value of ``anode`` exact: UCB stops adding exploration to it.

        A schema node (HPW) is solved with it when the schema has no parameters, since
        that action node is then the schema's only child.
        """
        self.a_solved[anode] = True
        self._solved = self.a_solved
        if snode >= 0:
            first = self.b_schema_first[self.s_owner[snode]]
            if self.space.schemas[snode - first].dim == 0:
                self.s_solved[snode] = True

    def _ucb(self, children: list[int], n_parent: int) -> int:
        return ucb_select(
            children, self.a_q, self.a_n, n_parent, self.c, self.normalized, self._solved
        )

    def select(
        self, h: int, n_h: int, keep: Keep | None = None, rank: Rank | None = None
    ) -> tuple[int, int]:
        """``(action node, schema node or -1)`` to simulate from belief node ``h``.

        Args:
            h: the belief node.
            n_h: its visit count N(h) before this simulation.
            keep: which actions the node offers (``keep(a)``: applicable in its
                particles, :func:`planners.pomdp.legal_in`); None offers every action.
                Read when children are made: the first expansion ("all"), each new
                draw ("dpw", "hpw": a refused draw is redrawn).
            rank: the order of the node's untried actions ("all": read once, when its
                children are made; None: the list's). DPW and HPW draw their actions one
                at a time and ignore it.
        """
        children = self.b_children[h]
        if self.mode == "all":  # the hot path of POMCP: one call, no detour
            if not children:
                self.expand_all(h, keep, rank)
            return ucb_select(
                children, self.a_q, self.a_n, n_h, self.c, self.normalized, self._solved
            ), -1
        if self.mode == "dpw":
            if len(children) <= self.k * n_h**self.alpha:
                self._add_action(h, self._draw(lambda: self.space.sample(self.rng), keep))
            return self._ucb(children, n_h), -1
        return self._select_hpw(h, n_h, keep)

    def _select_hpw(self, h: int, n_h: int, keep: Keep | None = None) -> tuple[int, int]:
        first = self.b_schema_first[h]
        if first < 0:
            first = self.b_schema_first[h] = len(self.s_n)
            for _ in range(self.n_schemas):
                self.s_n.append(0)
                self.s_q.append(0.0)
                self.s_children.append([])
                self.s_solved.append(False)
                self.s_owner.append(h)
        # 1) UCB over the discrete schema choice.
        s_n = self.s_n
        snode = ucb_select(
            range(first, first + self.n_schemas),
            self.s_q,
            s_n,
            n_h,
            self.c,
            self.normalized,
            self.s_solved,
        )
        schema = snode - first
        # 2) Progressive widening over that schema's continuous parameters.
        kids = self.s_children[snode]
        dim = self.space.schemas[schema].dim
        if (not kids) or (dim > 0 and len(kids) <= self.k * s_n[snode] ** self.alpha):
            space, rng = self.space, self.rng
            a = self._draw(lambda: space.build(schema, space.sample_params(schema, rng)), keep)
            node = self._add_action(h, a)
            if node not in kids:
                kids.append(node)
        return self._ucb(kids, s_n[snode]), snode

    def update(self, anode: int, snode: int, total: float) -> None:
        """Back up the return ``total`` of a simulation through ``anode`` (and ``snode``)."""
        n = self.a_n[anode] + 1
        self.a_n[anode] = n
        self.a_q[anode] += (total - self.a_q[anode]) / n
        if snode >= 0:
            n = self.s_n[snode] + 1
            self.s_n[snode] = n
            self.s_q[snode] += (total - self.s_q[snode]) / n

    def root_stats(self) -> tuple[list[Hashable], np.ndarray, np.ndarray]:
        """Actions, values and visits of the root's children."""
        root = self.b_children[0] if self.b_children else []
        return (
            [self.a_action[j] for j in root],
            np.array([self.a_q[j] for j in root]),
            np.array([self.a_n[j] for j in root], dtype=np.int64),
        )

    def best_root_action(self) -> Hashable | None:
        """The visited root action with the highest value (None if nothing was visited)."""
        actions, q, visits = self.root_stats()
        i = best_index(q, visits)
        return None if i is None else actions[i]

    def size(self) -> int:
        """Number of action nodes."""
        return len(self.a_n)
