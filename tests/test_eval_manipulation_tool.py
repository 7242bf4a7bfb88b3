"""``tools/eval_manipulation.py`` without episodes: failure causes, the report, options."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import eval_manipulation as E  # noqa: E402, N812


def _record(seed: int, ret: float, real: list[str], solver: str = "strug") -> dict:
    return {
        "domain": "shelf", "solver": solver, "seed": seed, "return": ret, "steps": 3,
        "seconds": 60.0 + seed, "mean_sims": 20.0, "plan_seconds_median": 2.0,
        "success": ret > 0, "report": {
            "time": {"twin": 30.0, "render": 10.0, "real": 10.0},
            "real": real, "outcome_cache": {"hit_rate": 0.5 + 0.1 * (seed % 3)},
        },
    }  # fmt: skip


def test_every_failure_gets_the_cause_that_ended_it() -> None:
    assert E.cause(_record(0, 9.5, ["Pick ok", "Place ok"])) == "success"
    assert E.cause(_record(0, -9.0, ["OpenDrawer ok"])) == "dragged"
    assert E.cause(_record(0, 0.0, ["Pick ok", "Place ok"])) == "placed elsewhere"
    last = _record(0, 0.0, ["Pick ok", "Pick ik_infeasible"])
    assert E.cause(last) == "out of steps after Pick ik_infeasible"
    assert E.cause(_record(0, 0.0, [])) == "nothing ran"


def test_the_report_counts_successes_causes_and_time(tmp_path: Path, capsys) -> None:
    recs = [_record(100, 9.5, ["Pick ok", "Place ok"]), _record(101, 0.0, []),
            _record(102, -9.0, ["Place ok"]), _record(7, 9.5, ["Place ok"])]  # fmt: skip
    (tmp_path / "results.jsonl").write_text("".join(json.dumps(r) + "\n" for r in recs))
    assert E.main(["--domains", "shelf", "--solvers", "strug", "--seeds", "100:103",
                   "--out", str(tmp_path), "--report-only"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "| shelf | strug | 1/3 (33%) | 2.00 | 161.0 | 20.0 |" in out  # seed 7 is not in
    assert "failures by cause (2 of 3 episodes)" in out
    assert "1  dragged (strug 1)" in out and "1  nothing ran (strug 1)" in out
    assert "twin 60%, render 20%, likelihood 0%, real 20%" in out
    # Three steps each, two, none and one of them a real skill.
    assert "steps that ran nothing: 6 of 9 (strug 6 of 9)" in out


def test_a_domain_that_is_no_manipulation_task_is_refused(tmp_path: Path) -> None:
    with pytest.raises(SystemExit):
        E.main(["--domains", "tiger", "--seeds", "0:2", "--out", str(tmp_path)])
