"""Domain-agnostic online POMDP solvers (numpy only).

Plan in any generative POMDP: implement :class:`planners.pomdp.GenerativePOMDP`
(``step(s, a, rng)``, ``obs_loglik``, ``action_space``, ``sample_initial_state``),
build a solver config (``POMCPOWConfig(sims=2000)``), then
``config.planner(pomdp).act(belief, rng) -> (action, SearchInfo)``.
This package never imports mujoco, torch or ``strug_manip``.
"""

from planners.belief import ParticleBelief, UpdateInfo, update_belief
from planners.errors import (
    BeliefError,
    ConfigError,
    ObservationError,
    StrugError,
    UnknownNameError,
)
from planners.pomdp import ActionSchema, ActionSpace, GenerativePOMDP, HybridAction, Step
from planners.solvers import (
    SOLVER_SUMMARIES,
    SOLVERS,
    POMCPConfig,
    POMCPOWConfig,
    RandomConfig,
    SearchInfo,
    SolverConfig,
    make_solver,
)

__all__ = [
    "SOLVERS",
    "SOLVER_SUMMARIES",
    "ActionSchema",
    "ActionSpace",
    "BeliefError",
    "ConfigError",
    "GenerativePOMDP",
    "HybridAction",
    "ObservationError",
    "POMCPConfig",
    "POMCPOWConfig",
    "ParticleBelief",
    "RandomConfig",
    "SearchInfo",
    "SolverConfig",
    "Step",
    "StrugError",
    "UnknownNameError",
    "UpdateInfo",
    "make_solver",
    "update_belief",
]
