"""Weighted particle beliefs and their Bayes updates.

A :class:`~planners.particles.ParticleBelief` (defined in :mod:`planners.particles`,
re-exported here) is a set of weighted states that remember their initial particle.

Two updates (:func:`update_belief` picks by ``pomdp.discrete_observations``):

* **Discrete observations, exact match** (POMCP's rejection update): propagate every
  particle once through G(s, a) and keep, with its weight, each whose simulated
  observation equals the real one; when fewer than ``min_match_fraction * n`` match,
  keep drawing particles by weight and propagating them (rejection sampling) until
  enough match or ``max_tries_per_particle * n`` draws were spent; resample
  (systematic) back to ``n`` particles when the count or the ESS fell. *Fallback*
  when still too few matched: weight every propagated particle by ``exp(obs_loglik)``
  instead (exact for models whose observation depends on ``(s', a)`` only). Zero
  total likelihood falls through to reinvigoration, below.
* **Continuous observations, likelihood weighting**: propagate every particle once,
  multiply its weight by ``Z(o | s', a)`` (computed in log space, shifted by the max
  so that tiny likelihoods do not underflow), normalise, and resample
  (systematic) when the effective sample size falls below ``resample_ess * N``.

*Reinvigoration* when every weight vanishes (the observation is impossible under
every particle): the domain's ``reinvigorate(o, a, n, rng)`` proposes states
consistent with ``o``; they get equal weights and origin ``-1`` (no known ancestor).
A domain that cannot propose any gets a :class:`BeliefError` naming the observation.
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np

from planners.errors import BeliefError, check_positive_float, check_positive_int
from planners.particles import NO_ORIGIN, ParticleBelief
from planners.pomdp import GenerativePOMDP


@dataclass(frozen=True)
class UpdateInfo:
    """What happened in one belief update.

    Attributes:
        method: ``"match"``, ``"likelihood"`` or ``"reinvigorated"``.
        matched: particles whose simulated observation matched (exact-match update only).
        draws: particles propagated.
        ess: effective sample size of the result.
    """

    method: str
    matched: int
    draws: int
    ess: float


def update_belief(
    pomdp: GenerativePOMDP,
    belief: ParticleBelief,
    a: Hashable,
    o: Any,
    rng: np.random.Generator,
    *,
    n_particles: int | None = None,
    resample_ess: float = 0.5,
    max_tries_per_particle: int = 20,
    min_match_fraction: float = 0.1,
) -> tuple[ParticleBelief, UpdateInfo]:
    """Bayes update of ``belief`` after action ``a`` and observation ``o``.

    Args:
        pomdp: the generative model (``step``, ``obs_loglik``, ``discrete_observations``).
        belief: the prior particle belief.
        a: the action taken.
        o: the observation received (validated by ``pomdp.check_observation``).
        rng: randomness for propagation and resampling.
        n_particles: size of the posterior (default: the prior's size).
        resample_ess: resample when ESS < ``resample_ess * N`` (continuous updates), in (0, 1].
        max_tries_per_particle: exact-match budget, in draws per wanted particle.
        min_match_fraction: below this fraction of matches, fall back to likelihood weighting.

    Returns:
        The posterior and an :class:`UpdateInfo`.

    Raises:
        ObservationError: ``o`` is malformed (NaN).
        BeliefError: no particle explains ``o`` and the domain cannot reinvigorate.
    """
    pomdp.check_observation(o)
    n = len(belief) if n_particles is None else check_positive_int("n_particles", n_particles)
    check_positive_float("resample_ess", resample_ess, upper=1.0)
    if pomdp.discrete_observations:
        return _update_exact_match(
            pomdp, belief, a, o, rng, n, max_tries_per_particle, min_match_fraction, resample_ess
        )
    return _update_likelihood(pomdp, belief, a, o, rng, n, resample_ess)


def _update_exact_match(
    pomdp: GenerativePOMDP,
    belief: ParticleBelief,
    a: Hashable,
    o: Any,
    rng: np.random.Generator,
    n: int,
    max_tries_per_particle: int,
    min_match_fraction: float,
    resample_ess: float,
) -> tuple[ParticleBelief, UpdateInfo]:
    step, key_of = pomdp.step, pomdp.observation_key
    key = key_of(o)
    # Pass 1: every particle once, in order, keeping its weight. An observation every
    # particle explains (Tiger's "nothing") then leaves the belief exactly as it was,
    # instead of adding multinomial resampling noise at every step.
    kept, kept_w, kept_origin = [], [], []
    proposed, proposed_origin = [], []
    for s, w, org in zip(
        belief.states, belief.weights.tolist(), belief.origin.tolist(), strict=True
    ):
        s_next, o_sim, _, _ = step(s, a, rng)
        proposed.append(s_next)
        proposed_origin.append(org)
        if key_of(o_sim) == key:
            kept.append(s_next)
            kept_w.append(w)
            kept_origin.append(org)
    draws = len(belief)
    # Pass 2: too few matches; keep drawing particles by weight (rejection sampling).
    budget = max_tries_per_particle * n
    extra, extra_origin = [], []
    while len(kept) + len(extra) < min_match_fraction * n and draws < budget:
        for i in belief.sample_indices(rng, min(budget - draws, n)).tolist():
            s_next, o_sim, _, _ = step(belief.states[i], a, rng)
            draws += 1
            if key_of(o_sim) == key:
                extra.append(s_next)
                extra_origin.append(int(belief.origin[i]))
    matched = len(kept) + len(extra)
    if matched >= max(1, min_match_fraction * n):
        # Pass-1 matches are a weighted posterior sample, pass-2 ones an unweighted one;
        # each set gets mass in proportion to its size.
        w1 = np.asarray(kept_w, dtype=float)
        w1 = w1 / w1.sum() * len(kept) if len(kept) else w1
        weights = np.concatenate([w1, np.ones(len(extra))])
        post = ParticleBelief(
            kept + extra, weights, np.asarray(kept_origin + extra_origin, dtype=np.int64)
        )
        if len(post) != n or post.ess() < resample_ess * n:
            post = post.resampled(rng, n)
        return post, UpdateInfo("match", matched, draws, post.ess())
    # Fallback: too few exact matches; weight the propagated particles by Z(o | s', a).
    logw = np.log(np.maximum(belief.weights, 1e-300)) + np.array(
        [pomdp.obs_loglik(o, s, a) for s in proposed], dtype=float
    )
    post, method = _weighted(
        pomdp, proposed, np.asarray(proposed_origin), logw, o, a, rng, n, resample_ess
    )
    return post, UpdateInfo(method, matched, draws, post.ess())


def _update_likelihood(
    pomdp: GenerativePOMDP,
    belief: ParticleBelief,
    a: Hashable,
    o: Any,
    rng: np.random.Generator,
    n: int,
    resample_ess: float,
) -> tuple[ParticleBelief, UpdateInfo]:
    src = belief if len(belief) == n else belief.resampled(rng, n)
    step = pomdp.step
    nxt = [step(s, a, rng)[0] for s in src.states]
    loglik = np.array([pomdp.obs_loglik(o, s, a) for s in nxt], dtype=float)
    logw = np.log(np.maximum(src.weights, 1e-300)) + loglik
    post, method = _weighted(pomdp, nxt, src.origin, logw, o, a, rng, n, resample_ess)
    return post, UpdateInfo(method, 0, len(nxt), post.ess())


def _weighted(
    pomdp: GenerativePOMDP,
    states: list[Any],
    origin: np.ndarray,
    logw: np.ndarray,
    o: Any,
    a: Hashable,
    rng: np.random.Generator,
    n: int,
    resample_ess: float,
) -> tuple[ParticleBelief, str]:
    if np.any(np.isnan(logw)):
        raise BeliefError(f"{pomdp.name}: obs_loglik returned NaN for observation {o!r}")
    top = logw.max() if len(logw) else -np.inf
    if not np.isfinite(top):
        fresh = pomdp.reinvigorate(o, a, n, rng)
        if not fresh:
            raise BeliefError(
                f"{pomdp.name}: observation {o!r} after action {a!r} has zero likelihood "
                "under every particle and the domain cannot reinvigorate its belief"
            )
        return (
            ParticleBelief(
                list(fresh), np.full(len(fresh), 1.0 / len(fresh)), np.full(len(fresh), NO_ORIGIN)
            ),
            "reinvigorated",
        )
    w = np.exp(logw - top)
    post = ParticleBelief(states, w, origin)
    if post.ess() < resample_ess * len(post) or len(post) != n:
        post = post.resampled(rng, n)
    return post, "likelihood"
