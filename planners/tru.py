"""Task-relevant uncertainty (TRU): the plan compatibility matrix and TRU of a belief.

STRUG paper, Section IV and Algorithm 1. For M particles ``x_0 .. x_{M-1}`` drawn
from the belief, each particle gets an uncertainty-free plan (an open-loop action
sequence: the domain's ``plan_for``, whose default is
:func:`planners.determinized.determinized_plan`).
Executing plan i K times from particle j gives the compatibility matrix

    S[i, j] = 1/K sum_k sum_t gamma^t r_t        (discounted return of plan i on particle j)

so ``S[i, i]`` is particle i's own plan value. For a belief with weights ``w`` over the
M particles (shape ``(M,)``, summing to 1):

    TRU(w) = sum_i w_i sum_j w_j (S[i, j] - sum_j' w_j' S[i, j'])^2

Two points the paper leaves loose, settled here:

(a) Both sums are weighted by the belief: TRU(b) = E_{s1~b}[Var_{s2~b}[V_{pi*_{s1}}(s2)]]
    as the paper defines it. Plans of particles the belief has ruled out no longer
    count, so TRU falls to 0 once the particles left agree on a plan (the paper's
    matrix formula sums plans i unweighted, which never reaches 0 while any ruled-out
    particle's plan disagrees).
(b) The search bonus rewards a *reduction*: ``beta * (TRU(b) - TRU(b'))`` (the paper
    writes E[TRU(b') - TRU(b)], which would pay for *gaining* uncertainty).

Scale: S is divided by the domain's reward range ``2 * max_abs_reward`` before the
variance, so TRU is dimensionless (at most 1/4) and ``beta = 10`` means the same on
every domain: on Tiger, one informative listen from a uniform belief earns ~1.2, a
little more than its cost of 1. (The paper applies beta = 10 to TRU in squared reward
units, where one listen would earn ~490 and no door would ever be opened.)
"""

from __future__ import annotations

import time
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from planners.errors import BeliefError, ConfigError, check_positive_int

if TYPE_CHECKING:
    from planners.pomdp import GenerativePOMDP

Plan = Sequence[Hashable]


@dataclass(frozen=True)
class CompatibilityMatrix:
    """The M x M plan compatibility matrix of M particles.

    Attributes:
        states: the M particles.
        plans: plan i (an action sequence) for particle i.
        values: S, shape ``(M, M)``: mean discounted return of plan i from particle j.
        scale: the reward range that normalises S for TRU.
        executions: plan executions run (M * M * K).
        steps: generative-model steps run while executing plans.
        seconds: wall time spent planning and executing [s].
    """

    states: list[Any]
    plans: list[Plan]
    values: np.ndarray
    scale: float
    executions: int
    steps: int
    seconds: float

    def __post_init__(self) -> None:
        m = len(self.states)
        if self.values.shape != (m, m):
            raise ConfigError(f"values must have shape ({m}, {m}), got {self.values.shape}")
        normalised = self.values / self.scale
        object.__setattr__(self, "_s", normalised)
        object.__setattr__(self, "_s2", normalised * normalised)

    @property
    def size(self) -> int:
        """M."""
        return len(self.states)

    def tru(self, w: np.ndarray) -> float:
        """TRU of the belief with weights ``w`` (shape ``(M,)``, any positive scale)."""
        total = float(w.sum())
        if not total > 0.0:
            raise BeliefError("TRU needs weights with positive mass")
        w = w / total
        mean = self._s @ w  # (M,): value of plan i under the belief
        var = self._s2 @ w - mean * mean
        return max(float(w @ var), 0.0)


def execute_plan(
    pomdp: GenerativePOMDP, s: Any, plan: Plan, rng: np.random.Generator, discount: float
) -> tuple[float, int]:
    """Discounted return of the open-loop ``plan`` from ``s``, and the steps it took."""
    total, disc, steps = 0.0, 1.0, 0
    step = pomdp.step
    for a in plan:
        s, _, r, done = step(s, a, rng)
        total += disc * r
        disc *= discount
        steps += 1
        if done:
            break
    return total, steps


def compatibility_matrix(
    pomdp: GenerativePOMDP,
    states: Sequence[Any],
    repeats: int,
    rng: np.random.Generator,
    *,
    discount: float | None = None,
    plan_fn: Callable[[Any, np.random.Generator], Plan] | None = None,
) -> CompatibilityMatrix:
    """Algorithm 1: plan for every particle, execute every plan on every particle.

    Args:
        pomdp: the generative model.
        states: the M particles.
        repeats: K, executions of each plan on each particle (K = 1 suffices when the
            domain's transitions and rewards are deterministic given the actions).
        rng: randomness for planning and execution.
        discount: return discount (default: the domain's).
        plan_fn: ``plan(s, rng) -> actions``; default ``pomdp.plan_for`` (whose own
            default is the determinised forward search).
    """
    check_positive_int("repeats (K)", repeats)
    if len(states) == 0:
        raise ConfigError("the compatibility matrix needs at least one particle")
    t0 = time.perf_counter()
    gamma = pomdp.discount if discount is None else discount
    if plan_fn is None:
        plan_fn = pomdp.plan_for
    plans = [list(plan_fn(s, rng)) for s in states]
    m = len(states)
    values = np.zeros((m, m))
    steps = 0
    for i, plan in enumerate(plans):
        for j, s in enumerate(states):
            acc = 0.0
            for _ in range(repeats):
                ret, n = execute_plan(pomdp, s, plan, rng, gamma)
                acc += ret
                steps += n
            values[i, j] = acc / repeats
    scale = 2.0 * float(pomdp.max_abs_reward)
    return CompatibilityMatrix(
        list(states), plans, values, scale, m * m * repeats, steps, time.perf_counter() - t0
    )
