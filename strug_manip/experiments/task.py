"""One bench task: a (domain, solver, seed) episode run to its result record.

What the driver (:mod:`strug_manip.experiments.bench`) and its workers
(:mod:`strug_manip.experiments.executors`) both call: the solver's config with the
run's overrides, the manipulation tasks' default budget, and the episode itself.

The solver names the runner takes (:data:`SOLVER_NAMES`) are the planners'
(:data:`planners.solvers.SOLVERS`) and :data:`ORACLE`, a choice of *belief* with
STRUG's planner: the manipulation task is built with the true cabinet as its only
particle (``belief="true"``, :mod:`strug_manip.domains.manipulation.oracle`), while the
solver config, its overrides and the budget are STRUG's own. The toy domains have no
perception to replace, and a user's own domain no true model to hand over: the runner
refuses the oracle there (:func:`check_solver`).
"""

from __future__ import annotations

import statistics
from typing import Any

from planners.errors import ConfigError, UnknownNameError
from planners.solvers import SOLVERS, make_solver
from strug_manip.domains import (
    MANIPULATION_DOMAINS,
    MANIPULATION_PARTICLES,
    MANIPULATION_SIMS,
    make_domain,
)
from strug_manip.experiments.episode import EpisodeResult, run_episode

#: The oracle: STRUG's planner on the true model (module docstring).
ORACLE = "oracle"
#: The planner the oracle runs.
ORACLE_PLANNER = "strug"
#: Every solver name the runner takes, in the rows' order: the planners', then the oracle.
SOLVER_NAMES: tuple[str, ...] = (*SOLVERS, ORACLE)


def planner_of(solver: str) -> str:
    """The planner (a key of :data:`~planners.solvers.SOLVERS`) that ``solver`` runs.

    Raises:
        UnknownNameError: ``solver`` is none of :data:`SOLVER_NAMES`.
    """
    if solver == ORACLE:
        return ORACLE_PLANNER
    if solver not in SOLVERS:
        raise UnknownNameError("solver", solver, list(SOLVER_NAMES))
    return solver


def check_solver(domain: str, solver: str) -> None:
    """Refuse a solver the domain cannot run: the oracle outside the manipulation tasks.

    Raises:
        UnknownNameError: ``solver`` is none of :data:`SOLVER_NAMES`.
        ConfigError: the oracle on a domain that is no manipulation task.
    """
    planner_of(solver)
    if solver == ORACLE and domain not in MANIPULATION_DOMAINS:
        raise ConfigError(
            f"solver {ORACLE!r} (STRUG given the true cabinet as its only particle) applies "
            f"to the manipulation domains ({', '.join(MANIPULATION_DOMAINS)}), not {domain!r}"
        )


def domain_params(domain: str, solver: str) -> dict[str, Any]:
    """The domain parameters ``solver`` asks for: the oracle's ``belief="true"``."""
    check_solver(domain, solver)
    return {"belief": "true"} if solver == ORACLE else {}


def solver_config(solver: str, overrides: dict[str, Any]) -> Any:
    """The config of ``solver`` (the oracle: STRUG's) with the overrides it has a field
    for."""
    planner = planner_of(solver)
    fields = SOLVERS[planner].field_names()
    return make_solver(planner, {k: v for k, v in overrides.items() if k in fields})


def budget_for(domain: str, overrides: dict[str, Any]) -> dict[str, Any]:
    """``overrides`` with the manipulation tasks' default budget where they set none:
    :data:`~strug_manip.domains.MANIPULATION_SIMS` simulations per decision (the
    solvers' 3000 are sized for the toy domains, whose steps cost microseconds, not the
    tens of milliseconds of a twin's skill) and
    :data:`~strug_manip.domains.MANIPULATION_PARTICLES` root particles."""
    if domain not in MANIPULATION_DOMAINS:
        return overrides
    out = {"particles": MANIPULATION_PARTICLES, **overrides}
    if "sims" not in overrides and "time_limit" not in overrides:
        out["sims"] = MANIPULATION_SIMS
    return out


def run_task(
    task: tuple[str, str, int],
    overrides: dict[str, Any],
    n_particles: int,
    objects: tuple[str, ...] = (),
) -> dict:
    """Run one episode and return its result record (executed in a worker).

    Every record has the return, the steps, the wall time, the mean simulations and the
    median planning time per step [s]; a manipulation episode's also ``success`` (the
    +10: the object rests in the target part) and the domain's report (where the time
    went, the outcome cache's hit rate). ``objects``: real object folders the
    manipulation tasks act on (:attr:`~strug_manip.experiments.bench.BenchSpec.objects`)."""
    domain, solver, seed = task
    on_objects = bool(objects) and domain in MANIPULATION_DOMAINS
    params = {"objects": objects} if on_objects else {}
    pomdp = make_domain(domain, **params, **domain_params(domain, solver))
    result = run_episode(
        pomdp, solver_config(solver, budget_for(domain, overrides)), seed, n_particles=n_particles
    )
    return episode_record(task, pomdp, result)


def episode_record(task: tuple[str, str, int], pomdp: Any, result: EpisodeResult) -> dict:
    """The result record of ``task``'s finished episode ``result`` in ``pomdp``
    (:func:`run_task`'s); a manipulation task's report is taken and its worlds freed."""
    domain, solver, seed = task
    plan = [s.plan_seconds for s in result.steps]
    rec = {
        "domain": domain,
        "solver": solver,
        "seed": seed,
        "return": result.discounted_return,
        "steps": len(result.steps),
        "seconds": round(result.seconds, 4),
        "mean_sims": result.mean_sims,
        "plan_seconds_median": round(statistics.median(plan), 4) if plan else 0.0,
    }
    report = getattr(pomdp, "report", None)
    if report is not None:
        rec["success"] = any(s.reward > 0 for s in result.steps)
        rec["report"] = report()
        pomdp.close()
    return rec
