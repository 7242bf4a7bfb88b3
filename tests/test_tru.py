"""Task-relevant uncertainty: the compatibility matrix, TRU and the search bonus."""

from __future__ import annotations

import numpy as np
import pytest

from planners.belief import ParticleBelief
from planners.determinized import determinized_plan
from planners.errors import BeliefError
from planners.solvers import STRUGConfig
from planners.solvers.belief_tree import belief_tree_search
from planners.tru import CompatibilityMatrix, compatibility_matrix, execute_plan
from strug_manip.domains import make_domain
from strug_manip.domains.tiger import LISTEN


def _matrix(values: np.ndarray) -> CompatibilityMatrix:
    m = len(values)
    return CompatibilityMatrix([None] * m, [[]] * m, values, 20.0, m * m, 0, 0.0)


def test_tru_is_zero_when_every_plan_has_the_same_value_everywhere() -> None:
    cm = _matrix(np.full((5, 5), 3.7))
    assert cm.tru(np.ones(5)) == pytest.approx(0.0, abs=1e-12)
    assert cm.tru(np.array([0.1, 0.5, 0.1, 0.2, 0.1])) == pytest.approx(0.0, abs=1e-12)


def test_tru_on_tiger_is_positive_then_zero_once_the_particles_agree() -> None:
    tiger = make_domain("tiger")
    states = [0] * 8 + [1] * 8
    cm = compatibility_matrix(tiger, states, 1, np.random.default_rng(0))
    uniform = np.ones(16)
    assert cm.tru(uniform) == pytest.approx(0.25)  # (+-10 / 20)^2: maximal conflict
    assert cm.tru(np.r_[np.ones(8), np.zeros(8)]) == pytest.approx(0.0, abs=1e-12)
    # Hearing "left" once (0.85) leaves less task-relevant uncertainty, twice less still.
    once = np.r_[np.full(8, 0.85), np.full(8, 0.15)]
    twice = np.r_[np.full(8, 0.85**2), np.full(8, 0.15**2)]
    assert 0.0 < cm.tru(twice) < cm.tru(once) < cm.tru(uniform)
    with pytest.raises(BeliefError):
        cm.tru(np.zeros(16))


def test_task_irrelevant_uncertainty_costs_no_tru() -> None:
    # LightDark2D: particles that differ only in y share a plan; in x they do not.
    ld = make_domain("lightdark2d")
    rng = np.random.default_rng(1)
    same_x = [(4.2, y) for y in np.linspace(0.5, 9.5, 12)]
    assert compatibility_matrix(ld, same_x, 1, rng).tru(np.ones(12)) == pytest.approx(0.0)
    spread_x = [(x, 4.0) for x in np.linspace(1.0, 9.0, 12)]
    assert compatibility_matrix(ld, spread_x, 1, rng).tru(np.ones(12)) > 0.01


def test_matrix_diagonal_is_each_particles_own_plan_value() -> None:
    ld = make_domain("lightdark1d")
    rng = np.random.default_rng(2)
    states = [ld.sample_initial_state(rng) for _ in range(10)]
    cm = compatibility_matrix(ld, states, 2, rng)
    for i, s in enumerate(states):
        own, _ = execute_plan(ld, s, cm.plans[i], rng, ld.discount)
        assert cm.values[i, i] == pytest.approx(own)
        assert own == pytest.approx(10.0 * ld.discount ** (len(cm.plans[i]) - 1))
    assert cm.executions == 10 * 10 * 2
    assert np.all(cm.values <= np.diag(cm.values)[:, None] + 1e-9)  # nobody beats its owner


def test_an_observation_separating_incompatible_particles_earns_a_bonus() -> None:
    tiger = make_domain("tiger")
    rng = np.random.default_rng(3)
    states = [0] * 16 + [1] * 16
    cm = compatibility_matrix(tiger, states, 1, rng)
    result = belief_tree_search(
        tiger, STRUGConfig(sims=300), states, np.ones(32), rng,
        node_value=lambda _s, w: cm.tru(w), beta=10.0,
    )  # fmt: skip
    bonus = dict(zip(result.actions, result.bonus, strict=True))
    assert bonus[LISTEN] > 0.5  # listening separates tiger-left from tiger-right
    assert all(v == 0.0 for a, v in bonus.items() if a != LISTEN)  # doors end the episode
    assert result.root_value == pytest.approx(0.25)


def test_determinized_fallback_finds_the_uncertainty_free_plans() -> None:
    rng = np.random.default_rng(4)
    tiger = make_domain("tiger")
    assert determinized_plan(tiger, 0, rng) == tiger.plan_for(0, rng)
    ld = make_domain("lightdark1d")
    plan = determinized_plan(ld, 2.4, rng)
    value, _ = execute_plan(ld, 2.4, plan, rng, ld.discount)
    assert value == pytest.approx(10.0 * ld.discount**2)  # two moves left, then declare


def test_strug_listens_until_confident_on_tiger() -> None:
    tiger = make_domain("tiger")
    rng = np.random.default_rng(5)
    planner = STRUGConfig(sims=1000).planner(tiger)
    a, info = planner.act(ParticleBelief.from_states([0, 1] * 200), rng)
    assert a == LISTEN
    assert info.extra["tru"] > 0.2
    assert info.extra["plan_executions"] == 32 * 32 * 3
