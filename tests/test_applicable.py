"""Actions a domain declares not applicable are not offered by any solver."""

from __future__ import annotations

import numpy as np
import pytest

from planners.pomdp import legal_in, provides_applicable
from planners.solvers import SOLVERS, make_solver
from strug_manip.domains.tiger import LISTEN, OPEN_LEFT, OPEN_RIGHT, Tiger


class LockedLeftTiger(Tiger):
    """Tiger whose left door is locked while the tiger is behind the right one (state
    1): opening it then does nothing (for the test; the reward model is Tiger's)."""

    def applicable(self, s, a) -> bool:
        return not (a == OPEN_LEFT and s == 1)


def _belief(pomdp, states):
    from planners.belief import ParticleBelief

    return ParticleBelief.from_states(list(states))


def test_legal_in_asks_the_weighted_particles_only():
    pomdp = LockedLeftTiger()
    assert provides_applicable(pomdp) and not provides_applicable(Tiger())
    assert not legal_in(pomdp, [1, 1])(OPEN_LEFT)
    assert legal_in(pomdp, [1, 0])(OPEN_LEFT)
    assert not legal_in(pomdp, [1, 0], [1.0, 0.0])(OPEN_LEFT)
    assert legal_in(pomdp, [1, 1])(LISTEN) and legal_in(pomdp, [1])(OPEN_RIGHT)


@pytest.mark.parametrize("solver", list(SOLVERS))
def test_no_solver_offers_an_action_no_particle_can_start(solver: str) -> None:
    """Every particle puts the tiger right: the locked door is never chosen nor
    searched at the root; with one particle on the left it is offered again."""
    pomdp = LockedLeftTiger()
    for seed in range(5):
        rng = np.random.default_rng(seed)
        planner = make_solver(solver, {"sims": 60}).planner(pomdp)
        a, info = planner.act(_belief(pomdp, [1] * 20), rng)
        assert a != OPEN_LEFT
        visited = {b for b, n in zip(info.actions, info.visits, strict=True) if n > 0}
        assert OPEN_LEFT not in visited
    if solver == "random":
        picks = {
            make_solver(solver, {})
            .planner(pomdp)
            .act(_belief(pomdp, [1] * 19 + [0]), np.random.default_rng(s))[0]
            for s in range(40)
        }
        assert picks == {LISTEN, OPEN_LEFT, OPEN_RIGHT}
        return
    # Half the particles on the left (Active Learning plans on the mode when sure).
    planner = make_solver(solver, {"sims": 60}).planner(pomdp)
    _, info = planner.act(_belief(pomdp, [1] * 10 + [0] * 10), np.random.default_rng(0))
    assert OPEN_LEFT in info.actions
