"""Online POMDP solvers: each a frozen config dataclass that builds a planner.

``SOLVERS`` maps the canonical solver names to their config classes;
``make_solver(name, overrides)`` builds a validated config.
"""

from __future__ import annotations

from typing import Any

from planners.errors import UnknownNameError
from planners.solvers.active_learning import ActiveLearningConfig, ActiveLearningPlanner
from planners.solvers.base import SearchInfo, SolverConfig, TreeSearchConfig
from planners.solvers.belief_tree import BeliefTreeConfig
from planners.solvers.entropy_regularized import EntropyConfig, EntropyPlanner
from planners.solvers.pomcp import POMCPConfig, POMCPPlanner
from planners.solvers.pomcpow import POMCPOWConfig, POMCPOWPlanner
from planners.solvers.random_solver import RandomConfig, RandomPlanner
from planners.solvers.strug import STRUGConfig, STRUGPlanner

#: Canonical solver name -> config class, in the row order of the paper's Table I.
SOLVERS: dict[str, type[SolverConfig]] = {
    "random": RandomConfig,
    "pomcp": POMCPConfig,
    "pomcpow": POMCPOWConfig,
    "entropy": EntropyConfig,
    "active": ActiveLearningConfig,
    "strug": STRUGConfig,
}


def make_solver(name: str, overrides: dict[str, Any] | None = None) -> SolverConfig:
    """The config of solver ``name`` with ``overrides`` applied and validated."""
    try:
        cls = SOLVERS[name]
    except KeyError:
        raise UnknownNameError("solver", name, list(SOLVERS)) from None
    config = cls()
    return config.with_overrides(overrides) if overrides else config


__all__ = [
    "SOLVERS",
    "ActiveLearningConfig",
    "ActiveLearningPlanner",
    "BeliefTreeConfig",
    "EntropyConfig",
    "EntropyPlanner",
    "POMCPConfig",
    "POMCPOWConfig",
    "POMCPOWPlanner",
    "POMCPPlanner",
    "RandomConfig",
    "RandomPlanner",
    "STRUGConfig",
    "STRUGPlanner",
    "SearchInfo",
    "SolverConfig",
    "TreeSearchConfig",
    "make_solver",
]
