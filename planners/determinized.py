"""A generic uncertainty-free planner: beam search on a determinised model.

STRUG needs a maximum-reward plan for one particle. Domains that know one provide
``plan_for(s, rng)``; for the others this fallback searches open-loop action
sequences over the domain's discretised actions. The model is *determinised* with
common random numbers: every candidate sequence is simulated from ``s`` with a
generator seeded identically, so sequences are compared on the same outcomes. The
beam keeps the ``beam`` best prefixes by discounted return so far (ties broken by the
shorter prefix, then at random so that a sparse-reward plateau is explored
broadly), and the best sequence (ended by a terminal step or by
``depth``) is returned.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any, Protocol

import numpy as np

from planners.errors import check_positive_int


class Simulable(Protocol):
    """What the beam search uses of a generative model (a
    :class:`~planners.pomdp.GenerativePOMDP` has it all; this module sits below it,
    since the model's default ``plan_for`` is this search)."""

    discount: float
    max_steps: int

    def action_space(self) -> Any: ...

    def step(self, s: Any, a: Hashable, rng: np.random.Generator) -> tuple: ...


def determinized_plan(
    pomdp: Simulable,
    s: Any,
    rng: np.random.Generator,
    *,
    depth: int | None = None,
    beam: int = 8,
) -> list[Hashable]:
    """The best open-loop action sequence found from ``s`` (length <= ``depth``).

    Args:
        pomdp: the generative model.
        s: the start state.
        rng: draws the determinisation seed.
        depth: maximum plan length (default: the domain's ``max_steps``).
        beam: prefixes kept per depth.
    """
    depth = check_positive_int("depth", depth if depth is not None else pomdp.max_steps)
    check_positive_int("beam", beam)
    seed = int(rng.integers(2**63))
    tie_break = np.random.default_rng(seed + 1)
    actions = list(pomdp.action_space().discretized)
    gamma = pomdp.discount

    def simulate(seq: tuple[Hashable, ...]) -> tuple[float, bool]:
        g = np.random.default_rng(seed)
        state, total, disc = s, 0.0, 1.0
        for a in seq:
            state, _, r, done = pomdp.step(state, a, g)
            total += disc * r
            disc *= gamma
            if done:
                return total, True
        return total, False

    frontier: list[tuple[Hashable, ...]] = [()]
    best_seq: tuple[Hashable, ...] = ()
    best_val = -np.inf
    for _ in range(depth):
        scored = []
        for prefix in frontier:
            for a in actions:
                seq = (*prefix, a)
                val, done = simulate(seq)
                if val > best_val or (val == best_val and len(seq) < len(best_seq)):
                    best_val, best_seq = val, seq
                if not done:
                    scored.append((val, -len(seq), float(tie_break.random()), seq))
        if not scored:
            break
        scored.sort(key=lambda t: t[:3], reverse=True)
        frontier = [t[3] for t in scored[:beam]]
    return list(best_seq)
