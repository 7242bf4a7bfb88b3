"""Particle belief updates against exact Bayes posteriors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.belief import NO_ORIGIN, ParticleBelief, update_belief
from planners.errors import BeliefError, ObservationError
from strug_manip.domains import make_domain
from strug_manip.domains.tiger import HEAR_LEFT, HEAR_NOTHING, HEAR_RIGHT, LISTEN, OPEN_LEFT


def _p_left(belief: ParticleBelief) -> float:
    return float(belief.weights[np.asarray(belief.states) == 0].sum())


def test_tigerclassic_exact_match_matches_bayes() -> None:
    pomdp = make_domain("tigerclassic")
    rng = np.random.default_rng(3)
    initial = pomdp.initial_belief(rng, 20_000)
    belief = initial
    history = [
        (LISTEN, HEAR_LEFT),
        (LISTEN, HEAR_LEFT),
        (LISTEN, HEAR_RIGHT),
        (LISTEN, HEAR_LEFT),
        (LISTEN, HEAR_LEFT),
    ]
    p = 0.5
    for a, o in history:
        belief, info = update_belief(pomdp, belief, a, o, rng)
        like_left = 0.85 if o == HEAR_LEFT else 0.15
        p = like_left * p / (like_left * p + (1 - like_left) * (1 - p))
        assert info.method == "match"
        assert abs(_p_left(belief) - p) < 0.02, (a, o, _p_left(belief), p)
    assert p > 0.99
    # Listening never moves the tiger: every particle still equals its ancestor.
    assert all(initial.states[k] == s for k, s in zip(belief.origin, belief.states, strict=True))
    # Opening a door resets the tiger: the posterior is uniform again.
    belief, _ = update_belief(pomdp, belief, OPEN_LEFT, HEAR_RIGHT, rng)
    assert abs(_p_left(belief) - 0.5) < 0.02


def test_an_observation_every_particle_explains_leaves_the_belief_unchanged() -> None:
    pomdp = make_domain("extendedtiger")
    rng = np.random.default_rng(1)
    belief = pomdp.initial_belief(rng, 500)
    post, info = update_belief(pomdp, belief, LISTEN, HEAR_NOTHING, rng)
    assert info.matched == 500 and info.draws == 500
    assert [s[0] for s in post.states] == [s[0] for s in belief.states]
    assert np.allclose(post.weights, belief.weights, rtol=1e-12)
    assert np.array_equal(post.origin, belief.origin)


def test_exact_match_falls_back_to_likelihood_weighting() -> None:
    pomdp = make_domain("tigerclassic")
    rng = np.random.default_rng(0)
    # Nearly all mass on "left": hearing "right" matches ~15% of draws; with one draw per
    # wanted particle and 90% required, the exact-match passes give up.
    belief = ParticleBelief.from_states([0] * 999 + [1])
    post, info = update_belief(
        pomdp, belief, LISTEN, HEAR_RIGHT, rng, max_tries_per_particle=1, min_match_fraction=0.9
    )
    assert info.method == "likelihood"
    assert info.matched < 900 and info.draws == 1000
    exact = 0.15 * 0.999 / (0.15 * 0.999 + 0.85 * 0.001)  # P(left | hear right) = 0.9943
    assert abs(_p_left(post) - exact) < 0.01


def test_lightdark1d_likelihood_weighting_matches_grid_posterior() -> None:
    pomdp = make_domain("lightdark1d")
    rng = np.random.default_rng(5)
    belief = pomdp.initial_belief(rng, 20_000)
    o = 3.4
    post, info = update_belief(pomdp, belief, 2, o, rng)  # move +1, then observe
    assert info.method == "likelihood"
    grid = np.linspace(-15, 20, 20_001)
    prior = np.exp(-0.5 * ((grid - 3.0) / 3.0) ** 2)  # y' = y + 1 ~ N(3, 3^2)
    sig = np.abs(grid - 5) / math.sqrt(2) + 0.01
    like = np.exp(-0.5 * ((o - grid) / sig) ** 2) / sig
    w = prior * like
    w /= w.sum()
    mean = float(w @ grid)
    std = math.sqrt(float(w @ (grid - mean) ** 2))
    y = np.asarray(post.states)
    pm = float(post.weights @ y)
    ps = math.sqrt(float(post.weights @ (y - pm) ** 2))
    assert abs(pm - mean) < 0.05
    assert abs(ps - std) < 0.05


def test_zero_weights_are_rejected() -> None:
    with pytest.raises(BeliefError, match="weights are zero"):
        ParticleBelief([0, 1], np.zeros(2), np.arange(2))
    with pytest.raises(BeliefError, match="finite"):
        ParticleBelief([0, 1], np.array([np.nan, 1.0]), np.arange(2))
    with pytest.raises(BeliefError, match="at least one particle"):
        ParticleBelief.from_states([])


def test_nan_observation_is_rejected(rng) -> None:
    for name, o in [("lightdark1d", math.nan), ("lightdark2d", (1.0, math.nan))]:
        pomdp = make_domain(name)
        belief = pomdp.initial_belief(rng, 10)
        a = pomdp.action_space().discretized[0]
        with pytest.raises(ObservationError, match="finite"):
            update_belief(pomdp, belief, a, o, rng)
    tiger = make_domain("tiger")
    with pytest.raises(ObservationError, match="hear-left"):
        update_belief(tiger, tiger.initial_belief(rng, 10), LISTEN, 7, rng)


def test_impossible_observation_without_reinvigoration_is_a_clear_error(rng) -> None:
    tiger = make_domain("tiger")
    with pytest.raises(BeliefError, match="zero likelihood under every particle"):
        update_belief(tiger, tiger.initial_belief(rng, 50), LISTEN, HEAR_NOTHING, rng)


def test_reinvigoration_when_every_weight_vanishes(rng, monkeypatch) -> None:
    pomdp = make_domain("lightdark1d")
    belief = pomdp.initial_belief(rng, 500)
    monkeypatch.setattr(pomdp, "obs_loglik", lambda o, s, a: -math.inf)
    post, info = update_belief(pomdp, belief, 2, 5.0, rng)
    assert info.method == "reinvigorated"
    assert len(post) == 500
    assert np.all(post.origin == NO_ORIGIN)
    assert abs(float(np.mean(post.states)) - 5.0) < 0.01  # sigma(5) = 0.01


def test_resampling_keeps_origins_and_size(rng) -> None:
    belief = ParticleBelief.from_states(list(range(10)), [0, 0, 0, 1, 0, 0, 0, 0, 0, 3])
    post = belief.resampled(rng, 400)
    assert len(post) == 400
    assert set(post.origin.tolist()) <= {3, 9}
    assert all(post.states[i] == post.origin[i] for i in range(400))
    assert abs(post.origin_weights(10)[9] - 0.75) < 0.01


def test_a_domain_that_never_resamples_keeps_every_particle():
    """``resample_ess`` near 0 (a domain of distinct deterministic models) leaves an
    unlikely particle in the posterior with its small weight instead of resampling it
    away, so later evidence can bring it back."""
    pomdp = make_domain("lightdark1d")
    rng = np.random.default_rng(0)
    belief = pomdp.initial_belief(rng, 50)
    o = 5.0
    post, info = update_belief(pomdp, belief, 2, o, rng, resample_ess=1e-9)
    assert info.method == "likelihood" and len(post) == 50
    assert len(set(post.origin.tolist())) == 50
    assert post.ess() < 25  # the default 0.5 would have resampled
    again, _ = update_belief(pomdp, belief, 2, o, np.random.default_rng(0))
    assert len(set(again.origin.tolist())) < 50
