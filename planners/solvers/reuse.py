"""Tree reuse between decisions: what is kept, and when it is dropped.

With ``reuse_tree=True`` (POMCP; default False, the published algorithm as Table I
runs it) a planner keeps its tree after ``act``. The runner then reports the executed
action and the real observation with ``planner.observe(a, o)``, and the next ``act``
starts from the subtree under that (action, observation), the way POMCP (Silver &
Veness 2010) and pomdp_py's POUCT carry their search forward: its visit counts and
values count as prior simulations and the new budget adds to them.

*Particles.* POMCP would take the new root's belief from the states its simulations
left in that node, and reinvigorate it with fresh particles when too few arrived.
Here the root states of every search are drawn from the runner's belief (exact-match
or likelihood-weighted Bayes, :mod:`planners.belief`), so the root is always fully
reinvigorated from the better belief. What the subtree brings is its statistics. They
were gathered from the states that reached the node in the earlier search (recorded
during that search); when those disagree with the runner's belief by more than
``reuse_tolerance`` in :func:`particle_disagreement`, the statistics describe another
belief and the subtree is dropped: the search starts fresh. The subtree is also
dropped when the tree never simulated the real (action, observation); on continuous
domains POMCP's observation bins (``obs_bin``) let the real observation find its child.

Kept subtrees are copied into fresh arrays (nodes renumbered breadth-first) at the
start of the next ``act``, inside its time budget, so a reused tree holds only the
nodes still reachable.

Not offered by the other solvers: POMCPOW's observation children are the sampled
observation values themselves, which a continuous real observation never equals, and
every belief-tree node holds the decision's M root particles reweighted (STRUG's
compatibility matrix is built over them), which the runner's next belief resamples.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from planners.belief import ParticleBelief
from planners.errors import ConfigError, check_positive_float

if TYPE_CHECKING:
    from planners.pomdp import GenerativePOMDP

#: Bins per dimension when continuous states are compared (quartiles of the belief).
CONTINUOUS_BINS = 4


def check_reuse(reuse_tree: object, reuse_tolerance: float) -> None:
    """Validate the ``reuse_tree`` and ``reuse_tolerance`` fields."""
    if not isinstance(reuse_tree, bool):
        raise ConfigError(f"reuse_tree must be true or false, got {reuse_tree!r}")
    check_positive_float("reuse_tolerance", reuse_tolerance, allow_zero=True, upper=1.0)


def particle_disagreement(
    pomdp: GenerativePOMDP, states: Sequence[Any], belief: ParticleBelief
) -> float:
    """Total-variation distance in [0, 1] between equally weighted ``states`` and ``belief``.

    Discrete states (``pomdp.discrete_states``) are compared state by state.
    Continuous ones are compared per feature on the quartile bins of the belief's
    marginal (:data:`CONTINUOUS_BINS` bins), the largest distance over the features
    counting. With few ``states`` the distance carries sampling noise (about
    ``0.4 / sqrt(len(states))`` for two equally likely states).
    """
    if not states:
        return 1.0
    w = belief.weights
    if pomdp.discrete_states(list(states)):
        mass: dict[Hashable, float] = {}
        for s, wi in zip(belief.states, w.tolist(), strict=True):
            mass[s] = mass.get(s, 0.0) + wi
        share = 1.0 / len(states)
        for s in states:
            mass[s] = mass.get(s, 0.0) - share
        return 0.5 * float(sum(abs(v) for v in mass.values()))
    ours = np.asarray(pomdp.entropy_features(list(states)), dtype=float)
    theirs = np.asarray(pomdp.entropy_features(belief.states), dtype=float)
    worst = 0.0
    for k in range(theirs.shape[1]):
        order = np.argsort(theirs[:, k], kind="stable")
        cdf = np.cumsum(w[order])
        cuts = np.interp(np.arange(1, CONTINUOUS_BINS) / CONTINUOUS_BINS, cdf, theirs[order, k])
        p = np.bincount(np.searchsorted(cuts, theirs[:, k]), w, CONTINUOUS_BINS)
        q = np.bincount(np.searchsorted(cuts, ours[:, k]), minlength=CONTINUOUS_BINS) / len(ours)
        worst = max(worst, 0.5 * float(np.abs(p - q).sum()))
    return worst
