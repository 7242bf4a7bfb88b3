"""Tree reuse: the kept subtree is the right one, gives the fresh tree's decision, and is
dropped when its particles disagree with the runner's belief."""

from __future__ import annotations

import math
from collections.abc import Hashable
from typing import Any

import numpy as np
import pytest

from planners.belief import ParticleBelief
from planners.errors import ConfigError
from planners.pomdp import ActionSpace, GenerativePOMDP, Step
from planners.solvers import POMCPConfig, make_solver
from planners.solvers.pomcp import POMCPTree
from planners.solvers.reuse import particle_disagreement
from strug_manip.domains import make_domain
from strug_manip.domains.tiger import LISTEN, OPEN_LEFT, OPEN_RIGHT
from strug_manip.experiments.episode import run_episode


class RevealTiger(GenerativePOMDP):
    """A deterministic Tiger: listening reveals the tiger's side exactly.

    State 0 (tiger left) or 1; actions listen (-1, observation = the state), open-left /
    open-right (+10 on the treasure, -10 on the tiger, episode over, observation 2).
    Given the state every step is deterministic, so two searches of the same belief
    agree on every value once they have visited it.
    """

    name = "revealtiger"
    discount = 0.95
    max_steps = 10
    max_abs_reward = 10.0
    discrete_observations = True

    def action_space(self) -> ActionSpace:
        return make_domain("tiger").action_space()

    def sample_initial_state(self, rng: np.random.Generator) -> int:
        return int(rng.random() < 0.5)

    def step(self, s: int, a: Hashable, rng: np.random.Generator) -> Step:
        if a == LISTEN:
            return Step(s, s, -1.0, False)
        return Step(s, 2, -10.0 if a - 1 == s else 10.0, True)

    def obs_loglik(self, o: Any, s_next: int, a: Hashable) -> float:
        if a == LISTEN:
            return 0.0 if o == s_next else -math.inf
        return 0.0 if o == 2 else -math.inf


UNIFORM = ParticleBelief.from_states([0, 1] * 100)
LEFT = ParticleBelief.from_states([0] * 200)
RIGHT = ParticleBelief.from_states([1] * 200)


def test_reused_tree_gives_the_fresh_trees_decision() -> None:
    pomdp = RevealTiger()
    reuse = POMCPConfig(sims=300, reuse_tree=True).planner(pomdp)
    a0, info0 = reuse.act(UNIFORM, np.random.default_rng(1))
    assert a0 == LISTEN and info0.extra["reused_visits"] == 0
    reuse.observe(LISTEN, 0)  # heard the tiger on the left: it is there
    a1, info1 = reuse.act(LEFT, np.random.default_rng(2))
    fresh_action, fresh = POMCPConfig(sims=300).planner(pomdp).act(LEFT, np.random.default_rng(2))
    assert a1 == fresh_action == OPEN_RIGHT
    # The reused root really carried the earlier simulations through (listen, left).
    assert info1.extra["reused_visits"] > 50
    assert info1.extra["reuse_disagreement"] == pytest.approx(0.0, abs=1e-12)
    assert info1.visits.sum() == info1.extra["reused_visits"] + 300 > fresh.visits.sum()


def _same_subtree(old: POMCPTree, h: int, new: POMCPTree, g: int) -> int:
    """Walk both trees in step; return the number of belief nodes compared."""
    assert old.visits[h] == new.visits[g]
    ko, kn = old.actions.b_children[h], new.actions.b_children[g]
    assert len(ko) == len(kn)
    assert [old.actions.a_action[j] for j in ko] == [new.actions.a_action[j] for j in kn]
    assert [old.actions.a_n[j] for j in ko] == [new.actions.a_n[j] for j in kn]
    assert [old.actions.a_q[j] for j in ko] == [new.actions.a_q[j] for j in kn]
    count = 1
    for (anode, key), child in old.children.items():
        if anode in ko:
            twin = new.children[(kn[ko.index(anode)], key)]
            count += _same_subtree(old, child, new, twin)
    return count


def test_subtree_copies_exactly_the_nodes_below_the_child() -> None:
    pomdp = make_domain("tigerclassic")
    planner = POMCPConfig(sims=2000, reuse_tree=True).planner(pomdp)
    planner.act(UNIFORM, np.random.default_rng(3))
    old = planner._tree
    assert old is not None
    h = old.child(LISTEN, 0)  # (listen, hear-left)
    sub = old.subtree(h)
    compared = _same_subtree(old, h, sub, 0)
    assert compared == len(sub.visits) > 10  # every copied node is reachable, none is missing
    assert len(sub.visits) < len(old.visits)
    assert sub.actions.size() == 3 * sum(1 for k in sub.actions.b_children if k)


def test_disagreeing_particles_drop_the_subtree() -> None:
    pomdp = RevealTiger()
    planner = POMCPConfig(sims=300, reuse_tree=True).planner(pomdp)
    planner.act(UNIFORM, np.random.default_rng(1))
    planner.observe(LISTEN, 0)  # the subtree's particles are all "tiger left" ...
    action, info = planner.act(RIGHT, np.random.default_rng(2))  # ... the belief says right
    assert info.extra["reuse_disagreement"] == pytest.approx(1.0)
    assert info.extra["reused_visits"] == 0 and info.visits.sum() == 300
    assert action == OPEN_LEFT
    # An (action, observation) the tree never simulated starts fresh as well: from
    # "tiger right" listening never says left.
    planner.observe(LISTEN, 0)
    _, info = planner.act(RIGHT, np.random.default_rng(4))
    assert info.extra["reused_visits"] == 0 and math.isnan(info.extra["reuse_disagreement"])


def test_without_reuse_observe_changes_nothing() -> None:
    pomdp = make_domain("tigerclassic")
    a = POMCPConfig(sims=500).planner(pomdp)
    b = POMCPConfig(sims=500).planner(pomdp)
    a.act(UNIFORM, np.random.default_rng(0))
    b.act(UNIFORM, np.random.default_rng(0))
    a.observe(LISTEN, 0)
    ra, ia = a.act(LEFT, np.random.default_rng(1))
    rb, ib = b.act(LEFT, np.random.default_rng(1))
    assert ra == rb and np.array_equal(ia.q, ib.q) and np.array_equal(ia.visits, ib.visits)


def test_particle_disagreement() -> None:
    tiger = make_domain("tiger")
    assert particle_disagreement(tiger, [0] * 10, UNIFORM) == pytest.approx(0.5)
    assert particle_disagreement(tiger, [0, 1] * 5, UNIFORM) == pytest.approx(0.0)
    assert particle_disagreement(tiger, [], UNIFORM) == 1.0
    ld = make_domain("lightdark1d")
    rng = np.random.default_rng(0)
    belief = ld.initial_belief(rng, 2000)
    same = belief.states[:400]
    assert particle_disagreement(ld, same, belief) < 0.1
    shifted = [s + 9.0 for s in same]  # three standard deviations away
    assert particle_disagreement(ld, shifted, belief) > 0.7
    ld2 = make_domain("lightdark2d")
    b2 = ld2.initial_belief(rng, 1000)
    moved_y = [(x, min(y + 4.0, 10.0)) for x, y in b2.states[:300]]  # only y differs
    assert particle_disagreement(ld2, moved_y, b2) > 0.5


def test_reuse_fields_are_validated() -> None:
    with pytest.raises(ConfigError, match="reuse_tree must be true or false, got 'yes'"):
        make_solver("pomcp", {"reuse_tree": "yes"})
    with pytest.raises(ConfigError, match=r"reuse_tolerance must be <= 1\.0"):
        make_solver("pomcp", {"reuse_tolerance": 2.0})


def test_episodes_with_reuse_are_bounded_and_reuse_happens() -> None:
    """The runner reports every step to the planner, so later decisions start warm."""
    pomdp = make_domain("tigerclassic")
    seen: list[int] = []
    config = make_solver("pomcp", {"sims": 300, "reuse_tree": True})
    real_planner = config.planner

    class Spy:
        def __init__(self) -> None:
            self.inner = real_planner(pomdp)

        def act(self, belief, rng):
            action, info = self.inner.act(belief, rng)
            seen.append(info.extra["reused_visits"])
            return action, info

        def observe(self, action, obs) -> None:
            self.inner.observe(action, obs)

    class SpyConfig:
        def planner(self, _pomdp):
            return Spy()

    result = run_episode(pomdp, SpyConfig(), 5, n_particles=300)  # type: ignore[arg-type]
    assert len(result.steps) == 10 and seen[0] == 0
    assert sum(v > 0 for v in seen[1:]) >= 7  # nearly every later decision reused a subtree


def test_episode_horizon_searches_only_the_steps_left() -> None:
    pomdp = make_domain("tigerclassic")
    config = POMCPConfig(sims=3000, horizon="episode")
    assert config.search_depth(pomdp, 0) == 10 and config.search_depth(pomdp, 9) == 1
    assert POMCPConfig().search_depth(pomdp, 9) == 10  # receding: always depth steps
    planner = config.planner(pomdp)
    for _ in range(9):
        planner.observe(LISTEN, 0)
    # The last step at P(left) = 0.85: a door is worth 0.85 * 10 - 0.15 * 100 = -6.5 there,
    # less than the -1 of listening, although listening can no longer be used.
    likely_left = ParticleBelief.from_states([0] * 170 + [1] * 30)
    action, info = planner.act(likely_left, np.random.default_rng(0))
    assert action == LISTEN
    assert info.q[0] == pytest.approx(-1.0) and info.q[2] == pytest.approx(-6.5, abs=1.5)
    with pytest.raises(ConfigError, match="horizon must be one of receding, episode"):
        make_solver("strug", {"horizon": "forever"})
