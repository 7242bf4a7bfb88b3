"""The oracle solver choice (STRUG on the true cabinet as its only particle) and the
true-hypothesis criterion it shares with the evaluations."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.parts import Perceiver
from planners.errors import ConfigError, UnknownNameError
from planners.solvers import STRUGConfig
from strug_manip.cli import main
from strug_manip.domains import make_domain
from strug_manip.domains.manipulation.actions import ManipAction
from strug_manip.experiments.bench import BenchSpec
from strug_manip.experiments.episode import run_episode
from strug_manip.experiments.table import to_markdown
from strug_manip.experiments.task import (
    SOLVER_NAMES,
    budget_for,
    check_solver,
    domain_params,
    solver_config,
)
from strug_manip.objects.hypotheses import BelievedJoint, same_joint

#: A drawers-only cabinet whose top drawer the robot opens (``tools/eval_skills.py``).
SEED = 11


def _turned(axis: np.ndarray, deg: float) -> np.ndarray:
    """``axis`` (a unit z axis here) turned by ``deg`` degrees about x."""
    a = math.radians(deg)
    return np.array([0.0, -math.sin(a), math.cos(a)]) * axis[2]


def test_same_joint_is_the_type_the_axis_within_10_deg_and_the_hinge_within_5_cm():
    true = BelievedJoint("revolute", [0.0, 0.0, 1.0], [1.0, 0.2, 0.8])
    z = np.array([0.0, 0.0, 1.0])
    assert same_joint(BelievedJoint("revolute", _turned(z, 9.0), true.origin), true)
    assert not same_joint(BelievedJoint("revolute", _turned(z, 11.0), true.origin), true)
    assert not same_joint(BelievedJoint("revolute", -z, true.origin), true)  # other side
    # Along the hinge line is the same hinge; across it, 4 cm is, 6 cm is not.
    assert same_joint(BelievedJoint("revolute", z, np.add(true.origin, [0.0, 0.0, 0.3])), true)
    assert same_joint(BelievedJoint("revolute", z, np.add(true.origin, [0.04, 0.0, 0.0])), true)
    assert not same_joint(BelievedJoint("revolute", z, np.add(true.origin, [0.0, 0.06, 0.0])), true)
    drawer = BelievedJoint("prismatic", [-1.0, 0.0, 0.0], [1.0, 0.0, 0.8])
    assert not same_joint(BelievedJoint("revolute", [-1.0, 0.0, 0.0], drawer.origin), drawer)
    assert same_joint(BelievedJoint("prismatic", [-1.0, 0.0, 0.0], [1.0, 0.0, 0.84]), drawer)
    assert not same_joint(BelievedJoint("prismatic", [-1.0, 0.0, 0.0], [1.3, 0.0, 0.8]), drawer)


def test_the_oracle_is_strug_on_the_manipulation_tasks_only(capsys):
    assert SOLVER_NAMES[-1] == "oracle"
    config = solver_config("oracle", budget_for("opendoor", {}))
    assert config == solver_config("strug", budget_for("opendoor", {}))
    assert isinstance(config, STRUGConfig)
    assert domain_params("opendoor", "oracle") == {"belief": "true"}
    assert domain_params("opendoor", "strug") == {}
    for domain in ("tiger", "lightdark2d", "my_module:MyPOMDP"):
        with pytest.raises(ConfigError, match=r"manipulation domains \(shelf, opendrawer"):
            check_solver(domain, "oracle")
    with pytest.raises(ConfigError, match="not 'tiger'"):
        BenchSpec(("opendrawer", "tiger"), ("strug", "oracle"), 1)
    with pytest.raises(UnknownNameError, match="oracle"):
        BenchSpec(("tiger",), ("orcale",), 1)
    assert main(["run", "--domain", "lightdark1d", "--solver", "oracle", "--seed", "0"]) == 2
    err = capsys.readouterr().err
    assert "strug: error: solver 'oracle'" in err and "opendoor), not 'lightdark1d'" in err
    with pytest.raises(UnknownNameError, match="belief"):
        make_domain("opendrawer", belief="oracle")


def test_the_oracle_row_is_a_bound_never_bold():
    cell = {"stderr": 0.1, "n": 3}
    table = to_markdown(
        {"opendoor": {"strug": {"mean": 3.0, **cell}, "oracle": {"mean": 9.0, **cell}}},
        with_paper=False,
    )
    assert "| STRUG | **3.00 ± 0.10** |" in table
    assert "| Oracle (STRUG, true model) | 9.00 ± 0.10 |" in table


def test_the_oracle_believes_the_real_cabinet_and_takes_over_its_state(monkeypatch):
    def no_network(*_args, **_kwargs):
        raise AssertionError("the oracle ran the perception network")

    # The oracle takes views but believes the true cabinet: the network never runs
    # (checked directly, not by a wall time that a loaded machine exceeds).
    monkeypatch.setattr(Perceiver, "perceive", no_network)
    d = make_domain("opendrawer", cabinet_seed=SEED, target_link="link_1", belief="true",
                    max_steps=1)  # fmt: skip
    env = d.environment
    try:
        env.reset(np.random.default_rng(0))
        belief = env.condition(d.initial_belief(np.random.default_rng(1), 24))
        real = d.real.world
        assert len(belief) == 1 and d.worlds.particles[0].spec is real.scene.cabinet_spec
        assert d.cat.targets == ("link_1",)
        obs, _, _ = env.execute(ManipAction("Pick", grasp="top"), np.random.default_rng(2))
        # As if the real robot had nudged the cabinet and a drawer: the particle's twin
        # takes the real state over, whatever it predicted.
        shift = np.eye(4)
        shift[:3, 3] = [0.02, -0.01, 0.0]
        real.set_cabinet_pose(shift @ real.cabinet_pose())
        real.set_parts({"joint_2": 0.07})
        s = d.step(belief.states[0], ManipAction("Pick", grasp="top"), np.random.default_rng(3))
        took = env.condition(type(belief)([s.state], belief.weights, belief.origin))
        tw = d.worlds.twins[0]
        tw.restore(took.states[0].sim)
        assert np.allclose(tw.world.cabinet_pose(), real.cabinet_pose(), atol=1e-9)
        assert tw.world.part_positions() == pytest.approx(real.part_positions(), abs=1e-9)
        assert took.states[0].last == s.state.last  # the twin's own key is kept
        assert env.health is not None and env.health.steps[0].target_before == 1.0
        if not obs.key[1]:  # the hand is empty: the object is where the real one is
            assert np.allclose(tw.world.object_pose(), real.object_pose(), atol=1e-9)
    finally:
        d.close()


def test_an_oracle_episode_runs_with_one_particle():
    d = make_domain(
        "opendrawer", cabinet_seed=SEED, target_link="link_1", **domain_params("opendrawer",
        "oracle"), max_steps=1,
    )  # fmt: skip
    try:
        res = run_episode(d, solver_config("oracle", {"sims": 2, "particles": 4}), 0)
        report = d.report()
    finally:
        d.close()
    assert len(res.steps) == 1
    assert report["health"]["initial"] == {"weight": 1.0, "models": 1, "catalogued": 1}
    assert [s["planned_true"] for s in report["health"]["steps"]] == [True]
