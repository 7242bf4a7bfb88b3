"""Scale-free (normalised) exploration obeys its definition; fixed UCB is unchanged."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.errors import ConfigError
from planners.solvers import make_solver
from planners.solvers.action_tree import ActionTree
from planners.solvers.base import UniformStream
from planners.solvers.exploration import ucb_select
from strug_manip.domains import make_domain


def _normalized_scores(q, n, n_parent, c):
    """The definition, written out: (Q - min Q) / (max Q - min Q) + c sqrt(ln N / n)."""
    lo, hi = min(q), max(q)
    return [
        (qj - lo) / (hi - lo) + c * math.sqrt(math.log(n_parent) / nj)
        for qj, nj in zip(q, n, strict=True)
    ]


def test_the_tiger_node_of_the_issue() -> None:
    """listen -330 after 2 visits, open-left -33.9 after 9993, open-right -40 after 5."""
    q, n, big_n = [-330.0, -33.9, -40.0], [2, 9993, 5], 10_000
    # By hand: normalised values 0, 1, 290/296.1 = 0.9794; bonuses sqrt(ln 1e4 / n) =
    # 2.1460, 0.0304, 1.3572, so the scores are 2.1460, 1.0304, 2.3366: open-right.
    scores = _normalized_scores(q, n, big_n, 1.0)
    assert scores == pytest.approx([2.1460, 1.0304, 2.3366], abs=1e-4)
    assert ucb_select(range(3), q, n, big_n, 1.0, normalized=True) == 2
    # c = 0.5: scores 1.0730, 1.0152, 1.6580: still open-right.
    assert ucb_select(range(3), q, n, big_n, 0.5, normalized=True) == 2
    assert ucb_select(range(2), [-330.0, -33.9], [2, 9993], 9995, 1.0, normalized=True) == 0
    # Fixed c = 100 never goes back to listen: -330 + 100 * 2.146 = -115.4 < -33.9 + 3.04.
    assert ucb_select(range(2), [-330.0, -33.9], [2, 9993], 9995, 100.0, normalized=False) == 1


@pytest.mark.parametrize("seed", range(20))
def test_normalized_choice_is_the_argmax_of_the_definition(seed: int) -> None:
    rng = np.random.default_rng(seed)
    k = int(rng.integers(2, 7))
    q = (rng.normal(0.0, 1.0, k) * 10.0 ** rng.uniform(-2, 3)).tolist()
    n = rng.integers(1, 500, k).tolist()
    big_n = sum(n)
    c = float(rng.uniform(0.1, 3.0))
    expected = int(np.argmax(_normalized_scores(q, n, big_n, c)))
    assert ucb_select(range(k), q, n, big_n, c, normalized=True) == expected
    # Scale-free: an affine change of the reward units (positive scale) changes nothing.
    scale, shift = float(10.0 ** rng.uniform(-3, 3)), float(rng.normal(0.0, 1000.0))
    moved = [scale * x + shift for x in q]
    assert ucb_select(range(k), moved, n, big_n, c, normalized=True) == expected


def test_fixed_mode_is_q_plus_c_sqrt_log_n_over_n() -> None:
    q, n, big_n, c = [1.0, 2.0, 0.5], [10, 40, 3], 53, 2.0
    scores = [qj + c * math.sqrt(math.log(big_n) / nj) for qj, nj in zip(q, n, strict=True)]
    assert ucb_select(range(3), q, n, big_n, c, normalized=False) == int(np.argmax(scores))


def test_unvisited_first_equal_values_and_solved_children() -> None:
    assert ucb_select([4, 7, 9], {4: 1.0, 7: 0.0, 9: 5.0}, {4: 3, 7: 0, 9: 0}, 3, 1.0, True) == 7
    # All values equal: the value term is 0, the least visited child wins.
    assert ucb_select(range(3), [2.0, 2.0, 2.0], [5, 2, 9], 16, 1.0, normalized=True) == 1
    # A solved child scores its normalised value alone (no exploration term).
    q, n, solved = [0.0, 1.0, 0.5], [1, 50, 40], [False, True, False]
    # child 0: 0 + sqrt(ln 91) = 2.124; child 1: 1; child 2: 0.5 + 0.336 = 0.836.
    assert ucb_select(range(3), q, n, 91, 1.0, normalized=True, solved=solved) == 0
    n = [90, 50, 40]  # child 0: 0.240, child 2: 0.860; the solved best value now wins
    assert ucb_select(range(3), q, n, 180, 1.0, normalized=True, solved=solved) == 1


def test_the_action_tree_uses_the_normalized_score() -> None:
    """A hand-built belief node in the tree every POMCPOW and belief-tree search uses."""
    tiger = make_domain("tigerclassic")
    rng = np.random.default_rng(0)
    for normalized, expected in ((True, 0), (False, 2)):
        tree = ActionTree(
            tiger.action_space(), "all", 1.0, 0.0, 100.0 if not normalized else 1.0,
            rng, UniformStream(rng), normalized,
        )  # fmt: skip
        tree.add_belief_node()
        tree.select(0, 0)  # creates listen, open-left, open-right
        for node, returns in ((0, [-330.0] * 2), (1, [-33.9] * 9993), (2, [-120.0] * 5)):
            for r in returns:
                tree.update(node, -1, r)
        # normalised: listen 0 + 2.146, open-left 1 + 0.030, open-right 0.709 + 1.357 = 2.066;
        # fixed c = 100: -330 + 214.6, -33.9 + 3.0, -120 + 135.7: open-right.
        assert tree.select(0, 10_000)[0] == expected


def test_exploration_is_validated_and_offered_by_every_tree_solver() -> None:
    for solver in ("pomcp", "pomcpow", "entropy", "active", "strug"):
        cfg = make_solver(solver, {"exploration": "normalized", "c_normalized": 0.5})
        assert cfg.resolved(make_domain("tigerclassic"))[1] == 0.5  # c is the normalised one
        assert make_solver(solver).resolved(make_domain("tigerclassic"))[1] == 100.0
    with pytest.raises(ConfigError, match="exploration must be one of fixed, normalized"):
        make_solver("pomcp", {"exploration": "muzero"})
    with pytest.raises(ConfigError, match="c_normalized must be >= 0"):
        make_solver("strug", {"c_normalized": -1.0})
