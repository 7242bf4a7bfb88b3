"""`planners` as a library: any GenerativePOMDP, numpy observations included, runs every solver.

The toy domains here are defined the way a user would define one (nothing from
``strug_manip``): a Tiger whose observations are numpy arrays, and a corridor with a
hybrid action space and continuous numpy observations. Neither defines ``plan_for``,
so STRUG runs on the default (determinised) one.
"""

from __future__ import annotations

import importlib.util
import math
import subprocess
import sys
from collections.abc import Hashable
from typing import Any

import numpy as np
import pytest

import planners
from planners import (
    SOLVERS,
    ActionSchema,
    ActionSpace,
    GenerativePOMDP,
    HybridAction,
    ModelError,
    PlannersError,
    SearchInfo,
    Step,
    check_pomdp,
    make_solver,
    run_episode,
)
from planners.determinized import determinized_plan
from planners.pomdp import REQUIRED_ATTRIBUTES, provides_plan
from planners.solvers.belief_tree import BeliefTreeSearch
from planners.solvers.pomcp import observation_bins
from planners.solvers.rollout import resolve_rollout
from planners.tru import compatibility_matrix

LISTEN, OPEN_LEFT, OPEN_RIGHT = 0, 1, 2
TIGER_SPACE = ActionSpace(
    (ActionSchema("listen"), ActionSchema("open-left"), ActionSchema("open-right")),
    (LISTEN, OPEN_LEFT, OPEN_RIGHT),
)


TIGER_ATTRIBUTES = {
    "name": "arraytiger",
    "discount": 0.95,
    "max_steps": 8,
    "max_abs_reward": 10.0,
    "discrete_observations": True,
}


class TigerModel(GenerativePOMDP):
    """Tiger (rewards -1 / -10 / +10) whose observations are numpy arrays of shape (1,):
    ``[0]`` heard left, ``[1]`` heard right, ``[-1]`` a door opened (no class attributes)."""

    def sample_initial_state(self, rng: np.random.Generator) -> int:
        return int(rng.integers(2))

    def step(self, s: int, a: Hashable, rng: np.random.Generator) -> Step:
        if a == LISTEN:
            heard = s if rng.random() < 0.85 else 1 - s
            return Step(s, np.array([heard]), -1.0, False)
        return Step(s, np.array([-1]), -10.0 if a - 1 == s else 10.0, True)

    def obs_loglik(self, o: Any, s_next: int, a: Hashable) -> float:
        if a != LISTEN:
            return 0.0 if o[0] == -1 else -math.inf
        return math.log(0.85 if o[0] == s_next else 0.15)

    def action_space(self) -> ActionSpace:
        return TIGER_SPACE


ArrayTiger = type("ArrayTiger", (TigerModel,), dict(TIGER_ATTRIBUTES))


MOVE, STOP = 0, 1
CORRIDOR_SPACE = ActionSpace(
    (ActionSchema("move", (-1.0,), (1.0,)), ActionSchema("stop")),
    (HybridAction(MOVE, (-1.0,)), HybridAction(MOVE, (1.0,)), HybridAction(STOP, ())),
)


class ArrayCorridor(GenerativePOMDP):
    """Stop within 0.5 of x = 5 (+10, else -10); observations: ``np.array([x + noise])``."""

    name = "arraycorridor"
    discount = 0.95
    max_steps = 6
    max_abs_reward = 10.0
    discrete_observations = False

    def sample_initial_state(self, rng: np.random.Generator) -> float:
        return float(rng.uniform(2.0, 8.0))

    def step(self, s: float, a: Hashable, rng: np.random.Generator) -> Step:
        schema, params = a  # type: ignore[misc]
        if schema == STOP:
            return Step(s, np.array([s]), 10.0 if abs(s - 5.0) < 0.5 else -10.0, True)
        x = min(max(s + params[0], 0.0), 10.0)
        return Step(x, np.array([x + 0.5 * rng.standard_normal()]), 0.0, False)

    def obs_loglik(self, o: Any, s_next: float, a: Hashable) -> float:
        if a[0] == STOP:  # type: ignore[index]
            return 0.0
        z = (o[0] - s_next) / 0.5
        return -0.5 * z * z

    def action_space(self) -> ActionSpace:
        return CORRIDOR_SPACE


TOYS = [ArrayTiger, ArrayCorridor]
BUDGET = 60


def _valid(space: ActionSpace, a: Hashable) -> bool:
    if space.is_discrete:
        return a in space.discretized
    return isinstance(a, HybridAction) and len(a.params) == space.schemas[a.schema].dim


@pytest.mark.parametrize("toy", TOYS, ids=lambda c: c.name)
@pytest.mark.parametrize("solver", list(SOLVERS))
def test_every_solver_plans_with_numpy_observations(toy: type, solver: str) -> None:
    pomdp = toy()
    rng = np.random.default_rng(0)
    planner = make_solver(solver, {"sims": BUDGET}).planner(pomdp)
    a, info = planner.act(pomdp.initial_belief(rng, 100), rng)
    assert _valid(pomdp.action_space(), a) and isinstance(info, SearchInfo)
    if solver != "random":
        assert info.sims == BUDGET and a in info.actions
        assert np.all(np.isfinite(info.q))
    first = run_episode(pomdp, make_solver(solver, {"sims": BUDGET}), 3, n_particles=100)
    again = run_episode(pomdp, make_solver(solver, {"sims": BUDGET}), 3, n_particles=100)
    assert 1 <= len(first.steps) <= pomdp.max_steps
    assert abs(first.discounted_return) <= 10.0 * pomdp.max_steps
    assert [s.action for s in first.steps] == [s.action for s in again.steps]  # same seed
    assert first.discounted_return == again.discounted_return


def test_an_episode_runs_in_any_environment() -> None:
    """``run_episode(model, environment, solver, seed)``: a simulated environment gives
    the convenience form's episode; a user's own environment executes every action the
    planner chose, and its ``condition`` sees the initial belief and every update."""
    from planners import Environment, Executed, SimulatedEnvironment

    pomdp = ArrayTiger()
    config = make_solver("pomcp", {"sims": BUDGET})
    named = run_episode(pomdp, SimulatedEnvironment(pomdp), config, 3, n_particles=100)
    short = run_episode(pomdp, config, 3, n_particles=100)
    assert [s.action for s in named.steps] == [s.action for s in short.steps]
    assert named.discounted_return == short.discounted_return

    class Robot:  # a tiger always behind the left door, and a log of what it did
        def __init__(self) -> None:
            self.state, self.done, self.conditioned = None, [], 0

        def reset(self, rng: np.random.Generator) -> None:
            self.state = 0

        def execute(self, action: Any, rng: np.random.Generator) -> Executed:
            _, o, r, done = pomdp.step(self.state, action, rng)
            self.done.append(action)
            return Executed(o, r, done)

        def condition(self, belief: Any) -> Any:
            self.conditioned += 1
            return belief

    robot = Robot()
    assert isinstance(robot, Environment)
    result = run_episode(pomdp, robot, config, 3, n_particles=100)
    assert len(robot.done) == len(result.steps)
    assert robot.conditioned == len(result.steps) + (0 if result.steps[-1].belief.startswith(
        "(episode over)") else 1)  # fmt: skip


def test_observation_keys() -> None:
    pomdp = ArrayTiger()
    assert pomdp.observation_key(np.array([1.5, -2.0])) == (1.5, -2.0)
    assert pomdp.observation_key(np.zeros((2, 1))) == ((2, 1), (0.0, 0.0))
    assert pomdp.observation_key([1, 2]) == (1, 2)
    assert pomdp.observation_key(3) == 3 and pomdp.observation_key((0, 1)) == (0, 1)
    assert observation_bins(ArrayCorridor(), 1.0)(np.array([1.2])) == (1,)
    assert observation_bins(pomdp, 1.0)(np.array([1])) == (1,)  # discrete: the key itself


def test_a_domains_observation_key_files_the_tree_children() -> None:
    class OneKey(ArrayCorridor):
        def observation_key(self, o: Any) -> Hashable:
            return "same"  # every observation counts as one

    for pomdp, most in ((ArrayCorridor(), 10), (OneKey(), 1)):
        rng = np.random.default_rng(1)
        cfg = make_solver("pomcpow", {"sims": 400, "keep_tree": True, "k_obs": 50.0})
        _, info = cfg.planner(pomdp).act(pomdp.initial_belief(rng, 100), rng)
        root = info.tree.actions.b_children[0]
        distinct = max(info.tree.obs_children(j) for j in root)
        assert distinct == 1 if most == 1 else distinct > most


def test_the_default_plan_for_is_the_one_fallback() -> None:
    pomdp = ArrayTiger()
    assert not provides_plan(pomdp)
    a = pomdp.plan_for(0, np.random.default_rng(5))
    assert a == determinized_plan(pomdp, 0, np.random.default_rng(5)) == [OPEN_RIGHT]
    matrix = compatibility_matrix(pomdp, [0, 1], 1, np.random.default_rng(0))
    assert matrix.plans == [[OPEN_RIGHT], [OPEN_LEFT]]  # TRU plans through pomdp.plan_for
    assert resolve_rollout("auto", pomdp) == "random"  # a beam search per rollout: too slow

    class Planned(ArrayTiger):
        calls = 0

        def plan_for(self, s: int, rng: np.random.Generator) -> list[Hashable]:
            Planned.calls += 1
            return [OPEN_RIGHT if s == 0 else OPEN_LEFT]

    planned = Planned()
    assert provides_plan(planned) and resolve_rollout("auto", planned) == "plan"
    cfg = make_solver("strug", {"sims": 200, "particles": 8})
    cfg.planner(planned).act(
        planned.initial_belief(np.random.default_rng(0), 50), np.random.default_rng(0)
    )
    assert Planned.calls > 8  # the matrix's 8 plans, then the plan rollouts: one lookup


def test_required_attributes_are_checked_by_name() -> None:
    for attr in REQUIRED_ATTRIBUTES:
        attrs = {k: v for k, v in TIGER_ATTRIBUTES.items() if k != attr}
        broken = type("Broken", (TigerModel,), attrs)
        with pytest.raises(ModelError, match=f"Broken must set the class attribute {attr}"):
            make_solver("pomcp").planner(broken())
        with pytest.raises(ModelError, match=attr):
            run_episode(broken(), make_solver("random"), 0)
    bad = type("Bad", (ArrayTiger,), {"discount": 1.5})
    with pytest.raises(ModelError, match=r"Bad.discount must be the discount factor.*got 1.5"):
        check_pomdp(bad())
    with pytest.raises(ModelError, match=r"expected a planners\.GenerativePOMDP instance, got int"):
        check_pomdp(3)
    assert issubclass(ModelError, PlannersError) and issubclass(ModelError, ValueError)


def test_hybrid_spaces_give_hybrid_actions_even_without_parameters() -> None:
    assert CORRIDOR_SPACE.build(STOP, ()) == HybridAction(STOP, ())
    assert TIGER_SPACE.build(OPEN_LEFT, ()) == OPEN_LEFT  # a discrete space: ints
    draws = {CORRIDOR_SPACE.sample(np.random.default_rng(k)) for k in range(40)}
    assert HybridAction(STOP, ()) in draws and all(isinstance(a, HybridAction) for a in draws)
    assert CORRIDOR_SPACE.name(HybridAction(STOP, ())) == "stop"


@pytest.mark.parametrize("solver", ["pomcp", "pomcpow", "strug", "entropy", "active"])
def test_the_tree_is_returned_on_request(solver: str) -> None:
    pomdp = ArrayTiger()
    rng = np.random.default_rng(2)
    belief = pomdp.initial_belief(rng, 100)
    _, plain = make_solver(solver, {"sims": 50}).planner(pomdp).act(belief, rng)
    _, kept = make_solver(solver, {"sims": 50, "keep_tree": True}).planner(pomdp).act(belief, rng)
    assert plain.tree is None and kept.tree is not None
    if solver in ("strug", "entropy", "active"):
        assert isinstance(kept.tree, BeliefTreeSearch)
        assert len(kept.tree.visits) + kept.tree.tree.size() == kept.tree_nodes
    else:
        assert kept.tree.actions.size() > 0 and kept.tree.visits[0] == 50
    with pytest.raises(PlannersError, match="keep_tree must be true or false"):
        make_solver(solver, {"keep_tree": "yes"})


def test_every_solver_config_is_exported_from_planners() -> None:
    from planners import STRUGConfig  # the import the issue found failing

    assert STRUGConfig is SOLVERS["strug"]
    for cls in SOLVERS.values():
        assert getattr(planners, cls.__name__) is cls and cls.__name__ in planners.__all__
    assert all(hasattr(planners, name) for name in planners.__all__)


def test_one_error_hierarchy() -> None:
    for name in ("ConfigError", "UnknownNameError", "BeliefError", "ObservationError"):
        assert issubclass(getattr(planners, name), PlannersError)
    assert importlib.util.find_spec("strug_manip.errors") is None


def test_planners_imports_no_product_code() -> None:
    code = (
        "import sys, pkgutil, importlib, planners\n"
        "for m in pkgutil.walk_packages(planners.__path__, 'planners.'):\n"
        "    importlib.import_module(m.name)\n"
        "bad = [m for m in sys.modules if m.split('.')[0] in ('mujoco', 'torch', 'strug_manip')]\n"
        "print(bad)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
