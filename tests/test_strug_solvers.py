"""HPW, entropy estimates and the information-gathering solvers."""

from __future__ import annotations

import math
from collections.abc import Hashable

import numpy as np
import pytest

from planners.belief import ParticleBelief
from planners.entropy import MIN_VARIANCE, particle_entropy
from planners.solvers import ActiveLearningConfig, POMCPOWConfig, STRUGConfig
from planners.solvers.active_learning import most_likely_state
from planners.solvers.belief_tree import belief_tree_search
from strug_manip.domains import make_domain
from strug_manip.domains.tiger import LISTEN, OPEN_LEFT


def _check_hpw(tree, k: float, alpha: float) -> int:
    checked = 0
    for h, first in enumerate(tree.b_schema_first):
        if first < 0:
            continue
        for j in range(first, first + tree.n_schemas):
            kids = tree.s_children[j]
            dim = tree.space.schemas[j - first].dim
            limit = 1 if dim == 0 else k * tree.s_n[j] ** alpha + 1
            assert len(kids) <= limit, (h, j, len(kids), tree.s_n[j])
            checked += 1
        assert sum(len(tree.s_children[j]) for j in range(first, first + tree.n_schemas)) == len(
            tree.b_children[h]
        )
    return checked


@pytest.mark.parametrize(("k", "alpha"), [(10.0, 1 / 30), (1.0, 0.5), (2.0, 0.3)])
def test_hpw_never_holds_more_continuous_children_than_k_n_alpha(k: float, alpha: float) -> None:
    ld = make_domain("lightdark2d")
    rng = np.random.default_rng(0)
    states = [ld.sample_initial_state(rng) for _ in range(16)]
    cfg = STRUGConfig(sims=1500, k_action=k, alpha_action=alpha, widening="hpw")
    result = belief_tree_search(ld, cfg, states, np.ones(16), rng, node_value=None, beta=0.0)
    assert _check_hpw(result.tree, k, alpha) > 20
    root_moves = result.tree.s_children[result.tree.b_schema_first[0]]
    assert len(root_moves) >= int(k * (result.tree.s_n[0] - 1) ** alpha)  # it did widen


def test_pomcpow_can_switch_to_hpw() -> None:
    ld = make_domain("lightdark2d")
    rng = np.random.default_rng(1)
    planner = POMCPOWConfig(sims=800, widening="hpw").planner(ld)
    _, info = planner.act(ld.initial_belief(rng, 200), rng)
    assert planner.widening == "hpw"
    assert {a.schema for a in info.actions} == {0, 1}  # both schemas, stop exactly once
    assert sum(a.schema == 1 for a in info.actions) == 1


def test_categorical_entropy() -> None:
    h = particle_entropy([0, 1, 1, 0], np.array([0.1, 0.3, 0.2, 0.4]), None)
    assert h == pytest.approx(-2 * 0.5 * math.log(0.5))


def test_gaussian_entropy_matches_the_analytic_value() -> None:
    rng = np.random.default_rng(2)
    x = rng.normal([0.0, 3.0], [2.0, 0.5], size=(20_000, 2))
    h = particle_entropy(list(x), np.ones(len(x)), x)
    exact = 0.5 * math.log(
        (2 * math.pi * math.e) ** 2 * (4.0 + MIN_VARIANCE) * (0.25 + MIN_VARIANCE)
    )
    assert h == pytest.approx(exact, abs=0.02)


def test_active_learning_learns_then_exploits_on_tiger() -> None:
    tiger = make_domain("tiger")
    rng = np.random.default_rng(3)
    planner = ActiveLearningConfig(sims=500).planner(tiger)
    a, info = planner.act(ParticleBelief.from_states([0, 1] * 100), rng)
    assert (a, info.extra["phase"]) == (LISTEN, "learn")
    sure_right = ParticleBelief.from_states([1] * 99 + [0])
    a, info = planner.act(sure_right, rng)
    assert (a, info.extra["phase"]) == (OPEN_LEFT, "exploit")


def test_most_likely_state() -> None:
    tiger = make_domain("tiger")
    assert most_likely_state(tiger, ParticleBelief.from_states([0, 1, 1])) == 1
    ld = make_domain("lightdark1d")
    b = ParticleBelief.from_states([0.0, 1.0, 2.0, 10.0], [0.3, 0.3, 0.3, 0.1])
    assert most_likely_state(ld, b) == 2.0  # nearest to the weighted mean 1.9


def test_a_domains_entropy_key_decides_what_the_entropy_and_the_mode_tell_apart() -> None:
    """States that differ only in detail the domain's ``entropy_key`` drops (here the
    tens digit) count as one class: the entropy is the classes', and the most likely
    state is the heaviest state of the heaviest class."""
    from planners.entropy import state_entropy

    class Classed(type(make_domain("tiger"))):
        def entropy_key(self, s):
            return s % 10

    domain = Classed()
    states, w = [0, 10, 1, 21, 31], np.array([0.2, 0.2, 0.1, 0.3, 0.2])
    h = -(0.4 * math.log(0.4) + 0.6 * math.log(0.6))
    assert state_entropy(domain, states, w) == pytest.approx(h)
    assert state_entropy(make_domain("tiger"), [0, 1], np.ones(2)) == pytest.approx(math.log(2))
    b = ParticleBelief.from_states(states, w)
    assert most_likely_state(domain, b) == 21  # class 1 (0.6), its heaviest state


def test_a_solved_child_competes_without_exploration() -> None:
    from planners.solvers.action_tree import ActionTree
    from planners.solvers.base import UniformStream

    tiger = make_domain("tiger")
    rng = np.random.default_rng(0)
    tree = ActionTree(tiger.action_space(), "all", 1.0, 0.0, 10.0, rng, UniformStream(rng))
    tree.add_belief_node()
    assert tree.select(0, 0)[0] == 0  # first call creates the three children
    listen, left, right = 0, 1, 2
    for node, q in ((listen, -1.0), (left, 1.0), (right, 0.0)):
        tree.update(node, -1, q)
    # Unsolved, the rarely tried doors would win on exploration; solved, only their value counts.
    for _ in range(50):
        tree.update(listen, -1, -1.0)
    assert tree.select(0, 53)[0] in (left, right)
    tree.mark_solved(left)
    tree.mark_solved(right)
    assert tree.select(0, 53)[0] == listen  # -1 + 10 sqrt(ln 53 / 51) = 1.79 > 1
    for _ in range(10_000):
        tree.update(listen, -1, -1.0)
    assert tree.select(0, 10_053)[0] == left  # the best solved value, once listening is known bad


def test_terminal_actions_are_solved_and_the_budget_goes_to_listening() -> None:
    """ExtendedTiger's doors end the episode: after one visit each their value is exact."""
    et = make_domain("extendedtiger")
    belief = et.initial_belief(np.random.default_rng(4), 1000)

    def door_visits(mode: str) -> tuple[Hashable, int]:
        planner = STRUGConfig(sims=2000, solve_terminal=mode).planner(et)
        action, info = planner.act(belief, np.random.default_rng(5))
        assert sum(info.visits) == 2000
        return action, sum(v for a, v in zip(info.actions, info.visits, strict=True) if a != LISTEN)

    action, visits = door_visits("auto")  # the default: discrete observations are solved
    assert action == LISTEN and visits <= 20  # one visit per door, the rest to listening
    assert door_visits("never")[1] > 100  # plain UCB keeps trying the doors


def test_solve_terminal_is_validated() -> None:
    from planners.errors import ConfigError

    with pytest.raises(ConfigError, match="solve_terminal must be one of auto, always, never"):
        STRUGConfig(solve_terminal="yes")


def test_hpw_solves_a_parameterless_terminal_schema() -> None:
    ld = make_domain("lightdark2d")
    rng = np.random.default_rng(5)
    states = [ld.sample_initial_state(rng) for _ in range(16)]
    result = belief_tree_search(
        ld,
        STRUGConfig(sims=800, solve_terminal="always"),
        states,
        np.ones(16),
        rng,
        node_value=None,
        beta=0.0,
    )
    tree, first = result.tree, result.tree.b_schema_first[0]
    schemas = range(first, first + tree.n_schemas)
    stop = next(j for j in schemas if tree.space.schemas[j - first].dim == 0)
    move = next(j for j in schemas if j != stop)
    assert tree.s_solved[stop] and not tree.s_solved[move]
    assert tree.a_solved[tree.s_children[stop][0]]
    assert tree.s_n[stop] < tree.s_n[move]
