"""The ``strug`` command line: list, run (text and JSON)."""

from __future__ import annotations

import json

from planners.solvers import SOLVERS
from strug_manip.cli import main
from strug_manip.domains import DOMAINS


def test_list_names_every_domain_and_solver(capsys) -> None:
    assert main(["list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    firsts = {line.split()[0] for line in lines if line.startswith("  ")}
    assert set(DOMAINS) | set(SOLVERS) <= firsts


def test_run_json_lines(capsys) -> None:
    argv = [
        "run",
        "--domain",
        "tigerclassic",
        "--solver",
        "pomcp",
        "--seed",
        "2",
        "--sims",
        "200",
        "--set",
        "depth=4",
        "--set",
        "c=50",
        "--json",
    ]
    assert main(argv) == 0
    rows = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    steps, final = rows[:-1], rows[-1]
    assert len(steps) == 10  # TigerClassic never ends early
    for i, row in enumerate(steps):
        assert row["step"] == i
        assert {"action", "observation", "reward", "sims", "plan_seconds"} <= set(row)
        assert row["sims"] == 200
    assert "return" in final
    gamma = 0.95
    assert abs(final["return"] - sum(r["reward"] * gamma**i for i, r in enumerate(steps))) < 1e-9


def test_run_text_shows_steps_and_return(capsys) -> None:
    assert main(["run", "--domain", "lightdark1d", "--solver", "pomcpow", "--sims", "100"]) == 0
    out = capsys.readouterr().out
    assert "step 0:" in out and "discounted return:" in out and "Q/N at root" in out


def test_run_writes_a_rerun_recording(tmp_path, capfd) -> None:
    for domain in ("tiger", "lightdark2d"):
        out = tmp_path / f"{domain}.rrd"
        assert main(["run", "--domain", domain, "--solver", "strug", "--sims", "100",
                     "--rerun", str(out)]) == 0  # fmt: skip
        assert out.stat().st_size > 1000
    err = capfd.readouterr().err  # rerun logs from native code: capture the file descriptor
    assert "WARN" not in err  # entity paths are valid


def test_bench_accepts_the_search_options(tmp_path, capsys) -> None:
    """The --set overrides that tools/bench_returns.py prints as its best configuration."""
    argv = ["bench", "--domains", "tigerclassic", "--solvers", "pomcp", "--time", "0.005",
            "--seeds", "2", "--out", str(tmp_path), "--json", "--no-progress", "--workers", "1",
            "--set", "exploration=normalized", "--set", "reuse_tree=true",
            "--set", "rollout=heuristic", "--set", "horizon=episode", "--set", "c_normalized=1.5",
            "--set", "reuse_tolerance=0.3"]  # fmt: skip
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["tigerclassic"]["pomcp"]["n"] == 2
    settings = json.loads((tmp_path / "run.json").read_text())
    assert settings["overrides"]["reuse_tree"] is True
    assert settings["overrides"]["exploration"] == "normalized"
