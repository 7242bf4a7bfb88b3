"""Toy domains: documented constants, and obs_loglik agreeing with the sampled observations."""

from __future__ import annotations

import math

import numpy as np
import pytest

from strug_manip.domains import make_domain
from strug_manip.domains.tiger import (
    HEAR_LEFT,
    HEAR_NOTHING,
    HEAR_RIGHT,
    LISTEN,
    OPEN_LEFT,
    OPEN_RIGHT,
    Tiger,
)


def test_tiger_constants() -> None:
    t = make_domain("tiger")
    rng = np.random.default_rng(0)
    assert (t.discount, t.max_steps) == (0.95, 10)
    assert t.step(0, LISTEN, rng).reward == -1
    assert t.step(0, OPEN_LEFT, rng) == (0, HEAR_NOTHING, -10, True)
    assert t.step(0, OPEN_RIGHT, rng) == (0, HEAR_NOTHING, 10, True)
    hits = sum(t.step(1, LISTEN, rng).obs == 1 for _ in range(20_000))
    assert abs(hits / 20_000 - 0.85) < 0.01


def test_tigerclassic_resets_and_continues() -> None:
    t = make_domain("tigerclassic")
    rng = np.random.default_rng(0)
    steps = [t.step(0, OPEN_LEFT, rng) for _ in range(4000)]
    assert {s.reward for s in steps} == {-100}
    assert not any(s.done for s in steps)
    assert abs(np.mean([s.state for s in steps]) - 0.5) < 0.03
    assert abs(np.mean([s.obs for s in steps]) - 0.5) < 0.03
    # obs and the new state are independent
    both = np.mean([s.state == 1 and s.obs == 1 for s in steps])
    assert abs(both - 0.25) < 0.03


def test_extendedtiger_listening_informs_after_three() -> None:
    t = make_domain("extendedtiger")
    rng = np.random.default_rng(0)
    s = (0, 0)
    for _ in range(3):
        s, o, r, done = t.step(s, LISTEN, rng)
        assert o == HEAR_NOTHING and r == -1 and not done
    informed = [t.step(s, LISTEN, rng).obs for _ in range(2000)]
    assert abs(np.mean(np.array(informed) == 0) - 0.85) < 0.03


def test_lightdark1d_as_pomdpmodels() -> None:
    ld = make_domain("lightdark1d")
    rng = np.random.default_rng(0)
    assert ld.discount == 0.9
    assert ld.sigma(5.0) == pytest.approx(0.01)
    assert ld.sigma(0.0) == pytest.approx(5 / math.sqrt(2) + 0.01)
    assert ld.step(0.5, 1, rng)[2:] == (10.0, True)
    assert ld.step(1.5, 1, rng)[2:] == (-10.0, True)
    assert ld.step(2.0, 2, rng).state == 3.0
    y0 = [ld.sample_initial_state(rng) for _ in range(20_000)]
    assert abs(np.mean(y0) - 2.0) < 0.1 and abs(np.std(y0) - 3.0) < 0.1


def test_lightdark2d_room_goal_and_noise() -> None:
    from planners.pomdp import HybridAction

    ld = make_domain("lightdark2d")
    rng = np.random.default_rng(0)
    stop, move = HybridAction(1, ()), HybridAction(0, (1.0, 0.5))
    assert ld.step((5.2, 9.0), stop, rng)[2:] == (10.0, True)
    assert ld.step((5.6, 9.0), stop, rng)[2:] == (-10.0, True)
    assert ld.step((9.5, 9.8), move, rng).state == (10.0, 10.0)  # clipped to the room
    near_right = np.array([ld.step((9.0, 1.0), move, rng).obs for _ in range(4000)])
    assert np.std(near_right[:, 0]) == pytest.approx(0.1, rel=0.1)  # sx(10) = 0.1
    assert np.std(near_right[:, 1]) == pytest.approx(0.1 + 0.5 * 8.5, rel=0.1)
    assert len(ld.action_space().discretized) == 9


@pytest.mark.parametrize("name", ["tiger", "tigerclassic", "extendedtiger"])
def test_discrete_obs_loglik_matches_sampling(name: str) -> None:
    pomdp = make_domain(name)
    rng = np.random.default_rng(1)
    for _ in range(5):
        s = pomdp.sample_initial_state(rng)
        for a in pomdp.action_space().discretized:
            draws = [pomdp.step(s, a, rng) for _ in range(4000)]
            for o in (0, 1, 2):
                # Z(o | s', a) averaged over s' must match the empirical frequency of o.
                expected = np.mean([math.exp(pomdp.obs_loglik(o, d.state, a)) for d in draws])
                freq = np.mean([d.obs == o for d in draws])
                assert abs(expected - freq) < 0.03, (name, s, a, o)
            s = draws[0].state if not draws[0].done else s


@pytest.mark.parametrize("name", ["lightdark1d", "lightdark2d"])
def test_continuous_obs_loglik_is_the_sampling_density(name: str) -> None:
    pomdp = make_domain(name)
    rng = np.random.default_rng(2)
    s = pomdp.sample_initial_state(rng)
    a = pomdp.action_space().discretized[0]
    draws = [pomdp.step(s, a, rng) for _ in range(20_000)]
    s_next = draws[0].state
    obs = np.array([d.obs for d in draws], dtype=float).reshape(len(draws), -1)
    # The mean log density of samples is minus the entropy; compare to the Gaussian's.
    mean_ll = np.mean([pomdp.obs_loglik(d.obs, s_next, a) for d in draws])
    std = obs.std(axis=0)
    entropy = float(np.sum(0.5 * np.log(2 * math.pi * math.e * std**2)))
    assert abs(mean_ll + entropy) < 0.05


def test_tiger_optimal_values_by_backward_induction() -> None:
    tiger, extended = make_domain("tiger"), make_domain("extendedtiger")
    assert tiger.optimal_value() == pytest.approx(5.673, abs=1e-3)  # the belief-grid value
    assert tiger.optimal_value(1.0) == 10.0 and tiger.optimal_value(0.0) == 10.0
    # ExtendedTiger: three paid listens first, then at best Tiger with 7 steps left.
    g = extended.discount
    short = Tiger()
    short.max_steps = 7
    upper = -(1 + g + g * g) + g**3 * short.optimal_value()
    assert extended.optimal_value() == pytest.approx(upper)  # listening first is optimal here
    assert extended.optimal_value() == pytest.approx(2.010, abs=1e-3)
    # No policy does better: "listen 5 times, open the door the majority says is safe".
    rng = np.random.default_rng(0)
    returns = []
    for _ in range(20_000):
        s, total, disc, votes = extended.sample_initial_state(rng), 0.0, 1.0, 0
        for _ in range(5):
            s, o, r, _ = extended.step(s, LISTEN, rng)
            total, disc = total + disc * r, disc * g
            votes += {HEAR_LEFT: 1, HEAR_RIGHT: -1}.get(o, 0)
        total += disc * extended.step(s, OPEN_RIGHT if votes > 0 else OPEN_LEFT, rng).reward
        returns.append(total)
    assert np.mean(returns) < extended.optimal_value() + 3 * np.std(returns) / np.sqrt(20_000)
    assert make_domain("tigerclassic").optimal_value() > 0.0
