"""Bad input gets one clear PlannersError-family message naming the value."""

from __future__ import annotations

import subprocess
import sys

import pytest

from planners.errors import ConfigError, PlannersError, UnknownNameError
from planners.solvers import POMCPConfig, POMCPOWConfig, RandomConfig, make_solver
from strug_manip.domains import make_domain
from strug_manip.domains.tiger import ExtendedTiger
from strug_manip.experiments.bench import BenchSpec
from strug_manip.experiments.episode import run_episode


def test_unknown_names_list_the_choices() -> None:
    with pytest.raises(UnknownNameError, match=r"unknown domain 'tigre'; expected one of: tiger"):
        make_domain("tigre")
    with pytest.raises(UnknownNameError, match=r"unknown solver 'pomcpp'.*pomcpow"):
        make_solver("pomcpp")
    with pytest.raises(UnknownNameError, match=r"'dpeth'.*depth"):
        make_solver("pomcp", {"dpeth": 3})


@pytest.mark.parametrize(
    ("build", "text"),
    [
        (lambda: POMCPConfig(sims=-5), "sims must be an integer >= 1, got -5"),
        (lambda: POMCPConfig(sims=2.5), "sims must be an integer >= 1, got 2.5"),
        (lambda: POMCPConfig(depth=0), "depth must be an integer >= 1, got 0"),
        (lambda: POMCPConfig(c=float("nan")), "c must be finite"),
        (lambda: POMCPConfig(discount=1.5), "discount must be <= 1.0, got 1.5"),
        (lambda: POMCPConfig(obs_bin=0), "obs_bin must be > 0"),
        (lambda: POMCPOWConfig(alpha_obs=2.0), "alpha_obs must be <= 1.0"),
        (lambda: POMCPOWConfig(k_action=-1), "k_action must be > 0"),
        (lambda: RandomConfig(sims=None, time_limit=None), "set a budget"),
        (lambda: POMCPConfig(time_limit=-1.0), "time_limit must be > 0"),
        (lambda: ExtendedTiger(listens_required=0), "listens_required must be an integer >= 1"),
        (lambda: ExtendedTiger(listens_required=12), "listens_required must be < 9"),
        (lambda: BenchSpec(("tiger",), ("pomcp",), -3), "seeds must be an integer >= 1, got -3"),
        (lambda: BenchSpec(("tiger",), ("pomcp",), 2, {}, 0), "n_particles must be"),
        (lambda: BenchSpec((), ("pomcp",), 2), "at least one domain"),
    ],
)
def test_impossible_hyper_parameters(build, text: str) -> None:
    with pytest.raises(ConfigError, match=text.replace("(", r"\(").replace(")", r"\)")):
        build()


def test_negative_seed_and_particles() -> None:
    pomdp = make_domain("tiger")
    with pytest.raises(ConfigError, match="seed must be an integer >= 0, got -1"):
        run_episode(pomdp, make_solver("random"), -1)
    with pytest.raises(ConfigError, match="n_particles must be an integer >= 1, got -10"):
        run_episode(pomdp, make_solver("random"), 0, n_particles=-10)


def test_errors_share_one_family() -> None:
    for exc in (ConfigError, UnknownNameError):
        assert issubclass(exc, PlannersError)


@pytest.mark.parametrize(
    ("argv", "text"),
    [
        (["run", "--domain", "tigre", "--solver", "pomcp"], "unknown domain 'tigre'"),
        (["run", "--domain", "tiger", "--solver", "x"], "unknown solver 'x'"),
        (
            ["run", "--domain", "tiger", "--solver", "pomcp", "--sims", "-2"],
            "argument --sims: expected an integer >= 1",
        ),
        (["run", "--domain", "tiger", "--solver", "pomcp", "--set", "c"], "--set expects"),
        (
            ["run", "--domain", "lightdark1d", "--solver", "pomcp", "--set", "rollout=heuristic"],
            "rollout='heuristic' needs a domain rollout policy, but lightdark1d has none",
        ),
        (
            ["run", "--domain", "tiger", "--solver", "strug", "--set", "exploration=muzero"],
            "exploration must be one of fixed, normalized, got 'muzero'",
        ),
        (
            ["bench", "--domains", "tiger", "--solvers", "random", "--seeds", "0", "--out", "x"],
            "argument --seeds: expected an integer >= 1",
        ),
    ],
)
def test_cli_prints_one_line_and_exits_2(argv: list[str], text: str) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "strug_manip", *argv], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 2
    assert text in proc.stderr
    assert "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
