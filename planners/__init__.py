"""Domain-agnostic online POMDP solvers (numpy only).

Plan in any generative POMDP: subclass :class:`planners.pomdp.GenerativePOMDP` (five
class attributes; ``step(s, a, rng)``, ``obs_loglik``, ``action_space``,
``sample_initial_state``), build a solver config (``POMCPOWConfig(sims=2000)``), then
either ``config.planner(pomdp).act(belief, rng) -> (action, SearchInfo)`` per decision
or ``run_episode(model, environment, config, seed) -> EpisodeResult`` for a whole
episode (``run_episode(pomdp, config, seed)`` simulates the true state with the
model). Every error raised on bad input is a :class:`PlannersError`.
This package never imports mujoco, torch or ``strug_manip``.
"""

from planners.belief import ParticleBelief, UpdateInfo, update_belief
from planners.environment import Environment, Executed, SimulatedEnvironment
from planners.episode import (
    DEFAULT_PARTICLES,
    EpisodeResult,
    StepRecord,
    episode_generators,
    run_episode,
)
from planners.errors import (
    BeliefError,
    ConfigError,
    ModelError,
    ObservationError,
    PlannersError,
    UnknownNameError,
)
from planners.pomdp import (
    ActionSchema,
    ActionSpace,
    GenerativePOMDP,
    HybridAction,
    RolloutPolicy,
    Step,
    check_pomdp,
)
from planners.solvers import (
    SOLVERS,
    ActiveLearningConfig,
    BeliefTreeConfig,
    EntropyConfig,
    POMCPConfig,
    POMCPOWConfig,
    RandomConfig,
    SearchInfo,
    SolverConfig,
    STRUGConfig,
    TreeSearchConfig,
    make_solver,
)

__all__ = [
    "DEFAULT_PARTICLES",
    "SOLVERS",
    "ActionSchema",
    "ActionSpace",
    "ActiveLearningConfig",
    "BeliefError",
    "BeliefTreeConfig",
    "ConfigError",
    "EntropyConfig",
    "Environment",
    "EpisodeResult",
    "Executed",
    "GenerativePOMDP",
    "HybridAction",
    "ModelError",
    "ObservationError",
    "POMCPConfig",
    "POMCPOWConfig",
    "ParticleBelief",
    "PlannersError",
    "RandomConfig",
    "RolloutPolicy",
    "STRUGConfig",
    "SearchInfo",
    "SimulatedEnvironment",
    "SolverConfig",
    "Step",
    "StepRecord",
    "TreeSearchConfig",
    "UnknownNameError",
    "UpdateInfo",
    "check_pomdp",
    "episode_generators",
    "make_solver",
    "run_episode",
    "update_belief",
]
