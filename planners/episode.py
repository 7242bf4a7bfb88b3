"""One episode of any :class:`GenerativePOMDP` planned in a model and executed in an
:class:`~planners.environment.Environment` (:func:`run_episode`).

The loop: reset the environment (the true initial state) and draw an ``n_particles``
belief from the model's b0, conditioned by the environment; then, per step,
``planner.act(belief, rng)``, ``environment.execute`` the chosen action, update the
belief with the observation (:func:`planners.belief.update_belief`), condition it on
what the environment knows for certain (``environment.condition``) and report the step
to the planner (``observe``), until ``done`` or the model's ``max_steps``.

Randomness: ``seed`` feeds one ``SeedSequence`` split into three independent
generators (the world: the environment's reset and execution; the belief updates; the
planner), so different solvers with the same seed face the same true initial state
and the same initial belief. With a simulation budget the same seed gives the same
episode bit for bit; a wall-time budget (``time_limit``) does not.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from planners.belief import update_belief
from planners.environment import Environment, environment_for
from planners.errors import check_positive_int
from planners.pomdp import GenerativePOMDP, check_pomdp
from planners.solvers.base import SolverConfig

#: Particles in the runner's belief (the planners' root belief).
DEFAULT_PARTICLES = 1000


@dataclass
class StepRecord:
    """One real step of an episode (the fields of ``strug run --json``).

    Attributes:
        step: index from 0.
        action: the action, formatted.
        observation: the observation, formatted.
        reward: the reward received.
        sims: simulations the planner ran.
        plan_seconds: planner wall time [s].
        tree_nodes: nodes in the planner's tree.
        belief: summary of the belief *after* the update.
        q: root value per action name (tree solvers).
        visits: root visits per action name (tree solvers).
        bonus: mean belief-dependent bonus per root action name (STRUG: beta times the
            TRU reduction; Entropy Regularized, Active Learning: beta times the entropy
            reduction).
        tru: TRU of the root belief (STRUG), else None.
        entropy: entropy of the root belief [nats] (Entropy, Active Learning), else None.
        phase: Active Learning's phase, ``"learn"`` or ``"exploit"``, else None.
        state: the true state before the step (formatted).
    """

    step: int
    action: str
    observation: str
    reward: float
    sims: int
    plan_seconds: float
    tree_nodes: int
    belief: str
    q: dict[str, float] = field(default_factory=dict)
    visits: dict[str, int] = field(default_factory=dict)
    bonus: dict[str, float] = field(default_factory=dict)
    tru: float | None = None
    entropy: float | None = None
    phase: str | None = None
    state: str = ""

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


@dataclass
class EpisodeResult:
    """A finished episode.

    Attributes:
        discounted_return: sum_t gamma^t r_t with the domain's discount.
        steps: the step records.
        seconds: wall time of the whole episode [s].
        true_initial_state: the drawn true state (repr).
        trajectory: the true states, the initial one first, then after every step.
    """

    discounted_return: float
    steps: list[StepRecord]
    seconds: float
    true_initial_state: str
    trajectory: list[Any] = field(default_factory=list)

    @property
    def mean_sims(self) -> float:
        """Mean simulations per decision."""
        return float(np.mean([s.sims for s in self.steps])) if self.steps else 0.0


def episode_generators(seed: int) -> tuple[np.random.Generator, ...]:
    """The (world, belief, planner) generators of episode ``seed``."""
    seq = np.random.SeedSequence(check_positive_int("seed", seed, allow_zero=True))
    return tuple(np.random.default_rng(s) for s in seq.spawn(3))


def run_episode(
    model: GenerativePOMDP,
    environment: Environment | Any,
    solver: SolverConfig | int | None = None,
    seed: int | None = None,
    *,
    n_particles: int = DEFAULT_PARTICLES,
    on_step: Callable[[StepRecord], None] | None = None,
    recorder: Callable[[StepRecord, Any, Any], None] | None = None,
) -> EpisodeResult:
    """Run one episode of ``solver`` planning in ``model`` while ``environment`` acts,
    until ``done`` or the model's ``max_steps``: act -> execute -> update the belief ->
    condition it.

    The convenience form ``run_episode(model, solver, seed)`` (no environment) runs in
    the environment the model comes with (:func:`planners.environment.environment_for`:
    a :class:`~planners.environment.SimulatedEnvironment` of the model, or the
    manipulation tasks' real robot).

    Args:
        model: the domain the planner simulates (validated with
            :func:`planners.pomdp.check_pomdp`).
        environment: what executes the actions (:class:`~planners.environment.Environment`).
        solver: the solver config (built into a planner here).
        seed: the episode seed (>= 0).
        n_particles: belief size.
        on_step: called with every step record as soon as it exists.
        recorder: called as ``recorder(record, belief after the update or None, true
            state after the step)``, e.g. a rerun recorder.

    Returns:
        The :class:`EpisodeResult`: discounted return (the model's discount), the step
        records and the true trajectory (the environment's ``state`` after every step).

    Raises:
        ModelError: ``model`` lacks a class attribute or returns a malformed action space.
        ConfigError: ``seed`` or ``n_particles`` is not a valid count.
    """
    if not isinstance(environment, Environment):  # run_episode(model, solver, seed)
        solver, seed = environment, seed if seed is not None else solver
        environment = environment_for(model)
    check_positive_int("n_particles", n_particles)
    check_pomdp(model)
    world_rng, belief_rng, plan_rng = episode_generators(seed)  # type: ignore[arg-type]
    t0 = time.perf_counter()
    environment.reset(world_rng)
    state = environment.state
    belief = environment.condition(model.initial_belief(belief_rng, n_particles))
    planner = solver.planner(model)  # type: ignore[union-attr]
    observe = getattr(planner, "observe", None)
    names = model.action_space().name
    total, disc = 0.0, 1.0
    records: list[StepRecord] = []
    trajectory = [state]
    initial = repr(state)
    for t in range(model.max_steps):
        action, info = planner.act(belief, plan_rng)
        obs, reward, done = environment.execute(action, world_rng)
        state_next = environment.state
        total += disc * reward
        disc *= model.discount
        if not done:
            belief, _ = update_belief(
                model, belief, action, obs, belief_rng, resample_ess=model.resample_ess
            )
            belief = environment.condition(belief)
            if observe is not None:
                observe(action, obs)  # lets a planner keep its tree (reuse_tree)
        rec = StepRecord(
            step=t,
            action=names(action),
            observation=model.format_obs(obs),
            reward=float(reward),
            sims=info.sims,
            plan_seconds=info.seconds,
            tree_nodes=info.tree_nodes,
            belief="(episode over)" if done else model.summarize_belief(belief),
            q={names(a): float(v) for a, v in zip(info.actions, info.q, strict=True)},
            visits={names(a): int(v) for a, v in zip(info.actions, info.visits, strict=True)},
            bonus={
                names(a): float(v)
                for a, v in zip(info.actions, info.extra.get("bonus", ()), strict=False)
            },
            tru=_optional_float(info.extra.get("tru")),
            entropy=_optional_float(info.extra.get("entropy")),
            phase=info.extra.get("phase"),
            state=model.format_state(state),
        )
        records.append(rec)
        trajectory.append(state_next)
        if on_step is not None:
            on_step(rec)
        if recorder is not None:
            recorder(rec, None if done else belief, state_next)
        if done:
            break
        state = state_next
    return EpisodeResult(total, records, time.perf_counter() - t0, initial, trajectory)


def _optional_float(x: Any) -> float | None:
    return None if x is None else float(x)
