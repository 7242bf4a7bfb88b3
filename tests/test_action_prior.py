"""The order in which a tree node tries its untried actions: the domain's action prior
(issue 37, "a budget that decides"), one mechanism for every tree solver; the toy
domains, which have no prior, keep the list order."""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from typing import Any

import numpy as np
import pytest

from planners.belief import ParticleBelief
from planners.errors import ConfigError, ModelError
from planners.pomdp import legal_in, prior_order, provides_prior
from planners.solvers import STRUGConfig, make_solver
from planners.solvers.action_tree import ActionTree, history_ranks
from planners.solvers.base import UniformStream
from planners.solvers.exploration import most_visited_index, puct_select
from strug_manip.domains import TOY_DOMAINS, make_domain
from strug_manip.domains.manipulation.actions import TABLE, ManipAction
from strug_manip.domains.tiger import LISTEN, OPEN_LEFT, OPEN_RIGHT, Tiger

#: The tree solvers (every solver but Random).
TREE_SOLVERS = ("pomcp", "pomcpow", "entropy", "active", "strug")
#: A drawers-only cabinet with 12 drawers with handles, 3 x 4 (cabinet seeds below 1,000:
#: the episodes' own seeds are held out).
TWELVE_DRAWERS = 9


class DoorsFirstTiger(Tiger):
    """Tiger whose prior ranks the left door, then the right one, then listening (the
    reverse of nothing: the list is listen, left, right)."""

    def action_prior(
        self, states: Sequence[Any], weights: Sequence[float], actions: Sequence[Hashable]
    ) -> list[float]:
        rank = {OPEN_LEFT: 2.0, OPEN_RIGHT: 1.0, LISTEN: 0.0}
        return [rank[a] for a in actions]


class BadPriorTiger(Tiger):
    def action_prior(self, states, weights, actions):
        return [1.0]


def test_the_toy_domains_have_no_prior_and_keep_the_list_order() -> None:
    """No toy domain ranks: every tree solver's search there is the one Table I ran."""
    for name in TOY_DOMAINS:
        pomdp = make_domain(name)
        assert not provides_prior(pomdp), name
        assert pomdp.action_prior([None], [1.0], list(pomdp.action_space().discretized)) is None
        belief = pomdp.initial_belief(np.random.default_rng(0), 10)
        assert history_ranks(pomdp, belief) is None, name
        space = pomdp.action_space()
        rng = np.random.default_rng(0)
        tree = ActionTree(space, "all", 1.0, 0.0, 1.0, rng, UniformStream(rng))
        tree.add_belief_node()
        kids = tree.expand_all(0)
        assert [tree.a_action[j] for j in kids] == list(space.discretized), name


def test_prior_order_is_stable_and_puts_the_solvers_preference_first() -> None:
    pomdp = DoorsFirstTiger()
    actions = [LISTEN, OPEN_LEFT, OPEN_RIGHT]
    assert provides_prior(pomdp)
    assert prior_order(pomdp, [0], [1.0], actions) == [OPEN_LEFT, OPEN_RIGHT, LISTEN]
    assert prior_order(Tiger(), [0], [1.0], actions) == actions  # ties: the list's
    preferred = prior_order(pomdp, [0], [1.0], actions, lambda a: float(a == LISTEN))
    assert preferred == [LISTEN, OPEN_LEFT, OPEN_RIGHT]
    with pytest.raises(ModelError, match="one score per action"):
        prior_order(BadPriorTiger(), [0], [1.0], actions)


@pytest.mark.parametrize("solver", TREE_SOLVERS)
def test_every_tree_solver_tries_its_untried_root_actions_in_the_prior_order(
    solver: str,
) -> None:
    """One simulation visits one root action: the prior's first, where Tiger's list order
    visits listen. (STRUG's: the first action of one of its particles' plans, a door
    either way: the two plans weigh 1/2 each, up to rounding.)"""
    belief = ParticleBelief.from_states([0, 1] * 10)  # tiger left or right, 50/50
    for pomdp, first in ((Tiger(), {LISTEN}), (DoorsFirstTiger(), {OPEN_LEFT})):
        if solver == "strug" and provides_prior(pomdp):
            first = {OPEN_LEFT, OPEN_RIGHT}
        planner = make_solver(solver, {"sims": 1}).planner(pomdp)
        _, info = planner.act(belief, np.random.default_rng(0))
        visited = [a for a, n in zip(info.actions, info.visits, strict=True) if n > 0]
        assert len(visited) == 1 and visited[0] in first, (solver, type(pomdp).__name__)


def test_strug_tries_the_first_action_of_its_particles_plans_first() -> None:
    """On a domain with a prior, STRUG's root puts its particles' plans first: every
    particle puts the tiger left, so every plan opens the right door, whatever the
    prior prefers."""
    sure = ParticleBelief.from_states([0] * 20)
    _, info = STRUGConfig(sims=1).planner(DoorsFirstTiger()).act(sure, np.random.default_rng(0))
    visited = [a for a, n in zip(info.actions, info.visits, strict=True) if n > 0]
    assert visited == [OPEN_RIGHT] and info.actions[0] == OPEN_RIGHT


def test_on_a_12_drawer_cabinet_the_target_pick_and_place_come_first() -> None:
    """The list puts Pick after the 12 drawers' openings and probes; the prior tries the
    target drawer's opening and probe first; once the drawer is open, Pick; once the
    object is held, the Place into the drawer (held with the drawer closed: the Place
    back onto the table). Two simulations of STRUG visit the target's opening (in list
    order they would visit the first drawer's opening and probe)."""
    d = make_domain("opendrawer", cabinet_seed=TWELVE_DRAWERS, target_link="link_8",
                    belief="true", max_steps=4)  # fmt: skip
    try:
        d.environment.reset(np.random.default_rng(0))
        belief = d.environment.condition(d.initial_belief(np.random.default_rng(1), 1))
        actions = list(d.action_space().discretized)
        k = d.cat.target_index(0)
        assert len(d.parts) == 12 and k is not None
        opening, probe = ManipAction("OpenDrawer", k, 0), ManipAction("PullH", k)
        pick, place = ManipAction("Pick", grasp="top"), ManipAction("Place", k)
        back = ManipAction("Place", TABLE)
        assert actions.index(pick) == 24 and actions.index(opening) == 2 * k > 0

        def order(s: Any) -> list[Hashable]:
            offered = [a for a in actions if legal_in(d, [s])(a)]
            return prior_order(d, [s], [1.0], offered)

        s = belief.states[0]
        assert order(s)[:2] == [opening, probe]
        rng = np.random.default_rng(2)
        early = d.step(s, pick, rng)
        assert d._holding(early.state) and order(early.state)[0] == back
        opened = d.step(s, opening, rng)
        assert d._open_enough(opened.state, k), opened.obs.summary
        assert order(opened.state)[0] == pick
        held = d.step(opened.state, pick, rng)
        assert d._holding(held.state), held.obs.summary
        assert order(held.state)[0] == place

        _, info = STRUGConfig(sims=2, particles=1).planner(d).act(belief, rng)
        visited = {a for a, n in zip(info.actions, info.visits, strict=True) if n > 0}
        assert opening in visited and info.actions[0] == opening
    finally:
        d.close()


def test_strug_puts_its_root_visits_where_its_particles_plans_begin() -> None:
    """With an action prior, STRUG's root is PUCT over the weight of the plans' first
    actions (``root_selection="auto"``): on a certain Tiger belief (tiger left), every
    plan opens the right door, which then gets most of the visits and is the decision;
    the same search by UCB tries all three actions first. (The whole budget runs:
    ``stop_decided`` would end it once the door's lead is settled.)"""
    sure = ParticleBelief.from_states([0] * 20)
    rng = np.random.default_rng(0)
    whole = STRUGConfig(sims=9, stop_decided=False)
    _, info = whole.planner(DoorsFirstTiger()).act(sure, rng)
    visits = dict(zip(info.actions, info.visits.tolist(), strict=True))
    assert max(visits, key=visits.__getitem__) == OPEN_RIGHT and visits[OPEN_RIGHT] >= 7
    ucb = STRUGConfig(sims=9, root_selection="ucb").planner(DoorsFirstTiger())
    _, info = ucb.act(sure, np.random.default_rng(0))
    assert all(info.visits > 0)
    with pytest.raises(ConfigError, match="root_selection must be one of auto, ucb, puct"):
        STRUGConfig(root_selection="pucb")
    lightdark = make_domain("lightdark2d")  # continuous actions: HPW, no list to rank
    planner = STRUGConfig(sims=2, root_selection="puct").planner(lightdark)
    with pytest.raises(ConfigError, match="needs a finite action list"):
        planner.act(lightdark.initial_belief(rng, 10), rng)


def test_puct_scores_and_decides_by_visits() -> None:
    q, n = [5.0, 0.0, 2.0], [4, 0, 1]
    # Visited: Q + c P sqrt(N) / (1 + n); unvisited: c P sqrt(N).
    assert puct_select([0, 1, 2], q, n, 5, 1.0, [0.8, 0.1, 0.1]) == 0
    assert puct_select([0, 1, 2], q, n, 5, 100.0, [0.1, 0.8, 0.1]) == 1
    assert most_visited_index(np.array([1.0, 3.0, 2.0]), np.array([4, 4, 1])) == 1
    assert most_visited_index(np.array([1.0]), np.array([0])) is None


@pytest.mark.parametrize(
    ("states", "settles"),
    [([0] * 20, True), ([0] * 15 + [1] * 5, True), ([0, 1] * 10, False)],
)
def test_a_puct_search_stops_once_its_decision_is_settled_and_decides_as_the_whole_budget(
    states: list[int], settles: bool
) -> None:
    """``stop_decided`` ends a PUCT root's search when the most visited action leads
    every other by more than the simulations left: the decision is the whole budget's,
    in fewer simulations. A 50/50 tiger never settles: both doors keep even visits,
    and the whole budget runs."""
    belief = ParticleBelief.from_states(states)
    runs = {}
    for stop in (True, False):
        rng = np.random.default_rng(3)
        cfg = STRUGConfig(sims=60, stop_decided=stop)
        action, info = cfg.planner(DoorsFirstTiger()).act(belief, rng)
        runs[stop] = (action, info)
    (a_stop, i_stop), (a_all, i_all) = runs[True], runs[False]
    assert a_stop == a_all and i_all.sims == 60
    if not settles:
        assert i_stop.sims == 60 and np.array_equal(i_stop.visits, i_all.visits)
        return
    assert i_stop.sims < 60
    lead, *rest = sorted(i_stop.visits.tolist(), reverse=True)
    assert lead - max(rest) > 60 - i_stop.sims


def test_a_search_that_decides_by_value_or_by_time_runs_its_whole_budget() -> None:
    """A UCB root decides by value, which any simulation may change, and a time budget
    leaves the simulations left unknown: neither stops early."""
    sure = ParticleBelief.from_states([0] * 20)
    for cfg, pomdp in (
        (STRUGConfig(sims=40), Tiger()),  # no prior: UCB (Table I's search)
        (STRUGConfig(sims=40, root_selection="ucb"), DoorsFirstTiger()),
    ):
        _, info = cfg.planner(pomdp).act(sure, np.random.default_rng(0))
        assert info.sims == 40
    timed = STRUGConfig(sims=None, time_limit=0.2).planner(DoorsFirstTiger())
    _, info = timed.act(sure, np.random.default_rng(0))
    assert info.sims > 40  # a sure belief's door would have settled within 40
    with pytest.raises(ConfigError, match="stop_decided must be true or false"):
        STRUGConfig(stop_decided="yes")  # type: ignore[arg-type]
