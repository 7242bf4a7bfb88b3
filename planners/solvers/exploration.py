"""UCB at a belief node: the paper's fixed constant, or a scale-free normalised term.

Every tree solver picks the child to simulate with :func:`ucb_select`, and its decision
at the root with :func:`best_index`. Its
``exploration`` config field chooses the score of a visited child ``j`` of a node
visited ``N`` times:

* ``"fixed"`` (default; the published POMCP, POMCPOW and STRUG):
  ``Q_j + c * sqrt(ln N / n_j)``, with ``c`` in reward units (the ``c`` field; by
  default the domain's largest |reward|, as the STRUG paper sets it).
* ``"normalized"``: ``(Q_j - Q_min) / (Q_max - Q_min) + c_normalized * sqrt(ln N / n_j)``
  with ``Q_min``, ``Q_max`` the lowest and highest value among the node's *visited*
  children (MuZero's min-max normalisation, Schrittwieser et al. 2020, taken per node
  rather than over the whole tree). The value term lies in [0, 1] whatever the reward
  scale, so ``c_normalized`` (dimensionless, default 1) needs no guess about the spread
  of returns. When every visited child has the same value the value term is 0 for all
  of them and the exploration term alone decides.

Why it matters: on the classic Tiger (doors -100/+10), a random rollout that opens the
tiger's door can give ``listen`` a value near -330 after two visits; with ``c = 100`` the
fixed term then never returns to it (``-330 + 100 * sqrt(ln 10^4 / 2) < -34``), while
the normalised term does after a handful of simulations.

In both modes unvisited children are tried first, in the order of ``children`` (which
the action tree makes in the order of the domain's action prior, see
:mod:`planners.solvers.action_tree`), and a *solved* child (its
value known exactly, see :meth:`ActionTree.mark_solved`) scores its value term alone.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from planners.errors import ConfigError, check_positive_float

#: Valid values of the ``exploration`` config field.
EXPLORATION_MODES = ("fixed", "normalized")


def check_exploration(mode: str, c_normalized: float) -> None:
    """Validate an ``exploration`` mode and its ``c_normalized``."""
    if mode not in EXPLORATION_MODES:
        raise ConfigError(
            f"exploration must be one of {', '.join(EXPLORATION_MODES)}, got {mode!r}"
        )
    check_positive_float("c_normalized", c_normalized, allow_zero=True)


def ucb_select(
    children: Sequence[int],
    q: Sequence[float],
    n: Sequence[int],
    n_parent: int,
    c: float,
    normalized: bool,
    solved: Sequence[bool] | None = None,
) -> int:
    """The child of a node to simulate next (see the module docstring for the scores).

    Args:
        children: ids of the node's children, in creation order (a non-empty list or range).
        q: value estimate per id (indexed by the ids in ``children``).
        n: visit count per id.
        n_parent: the node's visit count ``N``.
        c: the exploration constant: ``c`` [reward units] when fixed, ``c_normalized``
            (dimensionless) when normalised.
        normalized: use the normalised value term.
        solved: per id, True when the child's value is exact (None: none is).

    Returns:
        The first unvisited child, else the highest score (ties: the first).
    """
    logn = math.log(n_parent) if n_parent > 0 else 0.0
    sqrt = math.sqrt
    lo, scale = 0.0, 1.0
    if normalized:
        values = []
        for j in children:
            if n[j] == 0:
                return j
            values.append(q[j])
        lo, hi = min(values), max(values)
        scale = 1.0 / (hi - lo) if hi > lo else 0.0
    best, best_v = children[0], -math.inf
    for j in children:
        nj = n[j]
        if nj == 0:
            return j
        x = (q[j] - lo) * scale if normalized else q[j]
        v = x if solved is not None and solved[j] else x + c * sqrt(logn / nj)
        if v > best_v:
            best_v, best = v, j
    return best


def puct_select(
    children: Sequence[int],
    q: Sequence[float],
    n: Sequence[int],
    n_parent: int,
    c: float,
    prior: Sequence[float],
) -> int:
    """The child to simulate next by PUCT (Silver et al. 2017): ``Q_j + c * P_j *
    sqrt(N) / (1 + n_j)``, an unvisited child's ``Q_j`` taken as 0. ``prior``: ``P_j``
    per position in ``children`` (summing to 1). Ties: the first. The prior decides
    where a few simulations go; a child's own returns take over as its visits grow."""
    root_n = math.sqrt(n_parent)
    best, best_v = children[0], -math.inf
    for j, p in zip(children, prior, strict=True):
        nj = n[j]
        v = (q[j] if nj else 0.0) + c * p * root_n / (1 + nj)
        if v > best_v:
            best_v, best = v, j
    return best


def most_visited_index(q: np.ndarray, visits: np.ndarray) -> int | None:
    """The root's decision after a PUCT search: the most visited child (ties: the
    higher value, then the first), or None when no child was visited. Shapes ``(A,)``."""
    if len(visits) == 0 or not np.any(visits > 0):
        return None
    top = visits == visits.max()
    return int(np.argmax(np.where(top, q, -np.inf)))


def best_index(q: np.ndarray, visits: np.ndarray) -> int | None:
    """The root's decision: the index of the visited child with the highest value
    (ties: the first), or None when no child was visited. Shapes ``(A,)``."""
    if len(visits) == 0 or not np.any(visits > 0):
        return None
    return int(np.argmax(np.where(visits > 0, q, -np.inf)))
