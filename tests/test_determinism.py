"""The same seed gives the same episode, bit for bit."""

from __future__ import annotations

import pytest

from planners.solvers import make_solver
from strug_manip.domains import make_domain
from strug_manip.experiments.episode import run_episode


def _trace(result):
    return (
        [
            (s.action, s.observation, s.reward, s.sims, s.tree_nodes, s.belief, s.q, s.visits)
            for s in result.steps
        ],
        result.discounted_return,
        result.true_initial_state,
    )


@pytest.mark.parametrize("domain", ["tiger", "extendedtiger", "lightdark1d", "lightdark2d"])
@pytest.mark.parametrize("solver", ["random", "pomcp", "pomcpow"])
def test_same_seed_same_episode(domain: str, solver: str) -> None:
    pomdp = make_domain(domain)
    config = make_solver(solver, {"sims": 200})
    a = run_episode(pomdp, config, 11, n_particles=300)
    b = run_episode(make_domain(domain), config, 11, n_particles=300)
    assert _trace(a) == _trace(b)


def test_different_seeds_differ() -> None:
    pomdp = make_domain("lightdark1d")
    config = make_solver("pomcpow", {"sims": 100})
    runs = {repr(_trace(run_episode(pomdp, config, s, n_particles=100))) for s in range(4)}
    assert len(runs) > 1


NEW_OPTIONS = [
    ("pomcp", {"exploration": "normalized", "reuse_tree": True}),
    ("pomcpow", {"exploration": "normalized"}),
    ("strug", {"exploration": "normalized", "horizon": "episode"}),
]
HEURISTIC = {
    "exploration": "normalized",
    "reuse_tree": True,
    "rollout": "heuristic",
    "horizon": "episode",
}


@pytest.mark.parametrize(
    ("domain", "solver", "options"),
    [(d, s, o) for d in ("tigerclassic", "extendedtiger", "lightdark1d") for s, o in NEW_OPTIONS]
    + [(d, "pomcp", HEURISTIC) for d in ("tigerclassic", "extendedtiger")],
)
def test_same_seed_same_episode_with_the_new_options(domain: str, solver: str, options) -> None:
    """Tree reuse and normalised exploration keep episodes a function of the seed."""
    config = make_solver(solver, {"sims": 150, **options})
    a = run_episode(make_domain(domain), config, 13, n_particles=200)
    b = run_episode(make_domain(domain), config, 13, n_particles=200)
    assert _trace(a) == _trace(b)
    default = make_solver(solver, {"sims": 150})
    assert _trace(a) != _trace(run_episode(make_domain(domain), default, 13, n_particles=200))
