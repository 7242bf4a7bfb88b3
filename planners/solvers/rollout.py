"""Rollouts: the leaf value estimate of a new tree node, shared by every tree solver.

A rollout simulates from a state ``s`` at depth ``d`` until the search depth or a
terminal step and returns the discounted return. Which actions it takes is the
solver's ``rollout`` config field:

* ``"random"`` (default): uniform actions (a uniform pick from the discretised set
  when the solver searches a finite one, else ``ActionSpace.sample``), as POMCP,
  POMCPOW and STRUG's Algorithm 2 publish them;
* ``"heuristic"``: the domain's own :class:`planners.pomdp.RolloutPolicy`
  (``pomdp.rollout_policy()``), which picks actions from the rollout's own actions and
  observations; a domain without one is a :class:`ConfigError`.

The belief-tree solvers add ``"plan"`` (:func:`plan_return`, called by
:mod:`planners.solvers.belief_tree`): a particle's uncertainty-free plan
(``pomdp.plan_for``) executed from another particle, both drawn from the node's
belief; it needs the particle sets those nodes hold. Their ``"auto"`` is ``"plan"``
when the domain defines its own ``plan_for`` and ``"random"`` otherwise
(:func:`resolve_rollout`): the default ``plan_for`` is a beam search, affordable for
the M plans of STRUG's matrix but not once per rollout.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence
from typing import Any

import numpy as np

from planners.errors import ConfigError
from planners.pomdp import ActionSpace, GenerativePOMDP, RolloutPolicy, provides_plan
from planners.tru import execute_plan

#: Rollout kinds every tree solver offers.
ROLLOUTS = ("random", "heuristic")

#: ``rollout(s, d) -> discounted return of the steps d .. depth-1 from state s``.
Rollout = Callable[[Any, int], float]


def check_rollout(kind: str, choices: Sequence[str] = ROLLOUTS) -> None:
    """Validate a ``rollout`` config value against ``choices``."""
    if kind not in choices:
        raise ConfigError(f"rollout must be one of {', '.join(choices)}, got {kind!r}")


def resolve_rollout(kind: str, pomdp: GenerativePOMDP) -> str:
    """The concrete rollout of ``kind``: ``"auto"`` is ``"plan"`` when ``pomdp`` defines
    its own ``plan_for``, else ``"random"``; other kinds are returned as they are."""
    if kind == "auto":
        return "plan" if provides_plan(pomdp) else "random"
    return kind


def plan_return(
    pomdp: GenerativePOMDP,
    s: Any,
    plan: Sequence[Hashable],
    d: int,
    depth: int,
    gamma: float,
    rng: np.random.Generator,
) -> float:
    """Discounted return of the open-loop ``plan`` executed from ``s`` over the steps
    ``d .. depth-1`` (the plan is cut there), stopping at a terminal step
    (:func:`planners.tru.execute_plan`, the loop TRU's matrix runs too)."""
    return execute_plan(pomdp, s, plan[: depth - d], rng, gamma)[0]


def domain_policy(pomdp: GenerativePOMDP) -> RolloutPolicy:
    """``pomdp``'s rollout heuristic, or a :class:`ConfigError` naming the domain."""
    policy = pomdp.rollout_policy()
    if policy is None:
        raise ConfigError(
            f"rollout='heuristic' needs a domain rollout policy, but {pomdp.name} has none "
            "(rollout_policy() returned None); use rollout='random'"
        )
    return policy


def make_rollout(
    pomdp: GenerativePOMDP,
    kind: str,
    actions: Sequence[Hashable] | None,
    space: ActionSpace,
    depth: int,
    gamma: float,
    rng: np.random.Generator,
    uniform: Callable[[], float],
) -> Rollout:
    """The rollout function of kind ``kind`` (``"random"`` or ``"heuristic"``).

    Args:
        pomdp: the generative model.
        kind: ``"random"`` or ``"heuristic"``.
        actions: the finite action set random rollouts draw from (uniformly, with
            ``uniform``), or None to draw with ``space.sample(rng)``.
        space: the domain's action space.
        depth: the search depth (steps from the root, tree and rollout alike).
        gamma: the search discount.
        rng: randomness of the steps (and of ``space.sample``).
        uniform: the search's uniform [0, 1) stream.
    """
    check_rollout(kind)
    step = pomdp.step
    if kind == "heuristic":
        policy = domain_policy(pomdp)
        start, choose, update = policy.start, policy.action, policy.update

        def heuristic(s: Any, d: int) -> float:
            total, disc, memory = 0.0, 1.0, start()
            while d < depth:
                a = choose(memory, rng)
                s, o, r, done = step(s, a, rng)
                total += disc * r
                if done:
                    break
                memory = update(memory, a, o)
                disc *= gamma
                d += 1
            return total

        return heuristic

    finite = list(actions) if actions is not None else None
    n_finite = len(finite) if finite is not None else 0

    def random_rollout(s: Any, d: int) -> float:
        total, disc = 0.0, 1.0
        while d < depth:
            a = finite[int(uniform() * n_finite)] if finite is not None else space.sample(rng)
            s, _, r, done = step(s, a, rng)
            total += disc * r
            if done:
                break
            disc *= gamma
            d += 1
        return total

    return random_rollout
