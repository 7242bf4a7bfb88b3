"""Weighted particle beliefs: a set of states, their weights and their origins.

A :class:`ParticleBelief` is three parallel arrays: the states (a Python list, since a
state may be any object), their normalised weights ``(N,)`` and the index of the
*initial* particle each one descends from ``(N,)``. The origin index survives
propagation and resampling, so any belief met later can be read as a weight vector
over the initial particles: STRUG's TRU is computed from exactly that. The Bayes
updates are in :mod:`planners.belief`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from planners.errors import BeliefError

#: Origin index of a particle that has no initial ancestor (created by reinvigoration).
NO_ORIGIN = -1


@dataclass(frozen=True)
class ParticleBelief:
    """A weighted particle set.

    Attributes:
        states: the particles, length N (any state objects).
        weights: normalised weights, shape ``(N,)``, non-negative, summing to 1.
        origin: index of the initial particle each particle descends from, shape ``(N,)``
            (``-1`` for reinvigorated particles).
    """

    states: list[Any]
    weights: np.ndarray
    origin: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.states)
        if n == 0:
            raise BeliefError("a belief needs at least one particle, got 0")
        w = np.asarray(self.weights, dtype=float)
        if w.shape != (n,) or np.asarray(self.origin).shape != (n,):
            raise BeliefError(
                f"weights {w.shape} and origin {np.asarray(self.origin).shape} must both "
                f"have shape ({n},) to match the {n} states"
            )
        if not np.all(np.isfinite(w)) or np.any(w < 0):
            raise BeliefError("particle weights must be finite and >= 0")
        total = w.sum()
        if total <= 0:
            raise BeliefError(f"all {n} particle weights are zero; a belief needs positive mass")
        object.__setattr__(self, "weights", w / total)
        object.__setattr__(self, "origin", np.asarray(self.origin, dtype=np.int64))

    @classmethod
    def from_states(
        cls, states: Sequence[Any], weights: Sequence[float] | None = None
    ) -> ParticleBelief:
        """A belief over ``states`` (uniform unless ``weights`` given); particle i is origin i."""
        n = len(states)
        w = np.full(n, 1.0 / max(n, 1)) if weights is None else np.asarray(weights, float)
        return cls(list(states), w, np.arange(n, dtype=np.int64))

    def __len__(self) -> int:
        return len(self.states)

    def ess(self) -> float:
        """Effective sample size 1 / sum(w^2), in [1, N]."""
        return float(1.0 / np.dot(self.weights, self.weights))

    def sample_indices(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` particle indices drawn i.i.d. by weight, shape ``(n,)``."""
        cdf = np.cumsum(self.weights)
        idx = np.searchsorted(cdf, rng.random(n) * cdf[-1], side="right")
        return np.minimum(idx, len(self.states) - 1)

    def sample(self, rng: np.random.Generator) -> Any:
        """One state drawn by weight."""
        return self.states[int(self.sample_indices(rng, 1)[0])]

    def origin_weights(self, n_origins: int) -> np.ndarray:
        """Belief mass on each initial particle, shape ``(n_origins,)``, summing to <= 1.

        Mass of reinvigorated particles (origin -1) is not attributed to any origin.
        """
        keep = (self.origin >= 0) & (self.origin < n_origins)
        return np.bincount(self.origin[keep], weights=self.weights[keep], minlength=n_origins)

    def resampled(self, rng: np.random.Generator, n: int | None = None) -> ParticleBelief:
        """Systematic resampling to ``n`` (default N) equally weighted particles."""
        n = len(self.states) if n is None else n
        cdf = np.cumsum(self.weights)
        positions = (rng.random() + np.arange(n)) / n
        idx = np.minimum(np.searchsorted(cdf, positions * cdf[-1], side="right"), len(cdf) - 1)
        return ParticleBelief(
            [self.states[i] for i in idx], np.full(n, 1.0 / n), self.origin[idx].copy()
        )

    def expectation(self, f: Any) -> float:
        """E_b[f(s)] for a scalar function ``f`` of the state."""
        return float(sum(w * f(s) for s, w in zip(self.states, self.weights, strict=True)))
