"""``tools/eval_skills.py`` without physics: its options, its resumable records and the
twin's figures per physics step; and the planning twin's step, validated."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pytest

from planners.errors import ConfigError
from strug_manip.control import PlanningTwin
from strug_manip.objects.generator import generate_cabinet

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import eval_skills as E  # noqa: E402, N812


def row(agree: bool, full: str = "ok", twin: str = "ok", full_wall=1.0, twin_wall=0.1) -> dict:
    """One comparison row as :func:`eval_skills.compare` writes it."""
    return {"full": full, "twin": twin, "motion_error": 0.0, "dragged": False, "agree": agree,
            "agree_strict": agree, "full_wall": full_wall, "twin_wall": twin_wall,
            "twin_cold_wall": 10 * twin_wall}  # fmt: skip


def twin_record(seed: int, rows_by_step: dict[str, list[dict]]) -> dict:
    """A ``--only twin`` record of one part with the given rows per step."""
    first = next(iter(rows_by_step))
    part = {"part": "link_1", "model": "drawer", "category": "open_drawer", "unit": "m",
            "scene": "drawer", "twin": rows_by_step[first], "twin_steps": rows_by_step}  # fmt: skip
    return {"seed": seed, "parts": [part], "seconds": 1.0, "only": "twin"}


def test_twin_steps_option_parses_and_rejects_bad_steps() -> None:
    assert E.twin_steps("0.005,0.002") == (0.005, 0.002)
    for bad in ("", "fast", "0", "0.02", "0.005,-1"):
        with pytest.raises(argparse.ArgumentTypeError, match=r"0\.01"):
            E.twin_steps(bad)


def test_only_twin_records_give_the_twin_figures_per_step() -> None:
    recs = [
        twin_record(1, {"0.005": [row(True), row(False, twin="grasp_lost")],
                        "0.002": [row(True, twin_wall=0.25), row(True, twin_wall=0.25)]}),
        twin_record(2, {"0.005": [row(True)], "0.002": [row(True, twin_wall=0.25)]}),
    ]  # fmt: skip
    fig = E.summary(recs)
    assert set(fig) == {"twin", "twin_steps"}
    assert fig["twin"]["agreement"] == {"n": 3, "ok": 2}
    assert fig["twin"]["disagreements"] == {"ok vs grasp_lost": 1}
    assert list(fig["twin_steps"]) == ["0.005", "0.002"]  # coarsest first
    assert fig["twin_steps"]["0.002"]["agreement"] == {"n": 3, "ok": 3}
    assert fig["twin_steps"]["0.005"]["speedup"] == pytest.approx(10.0)
    assert fig["twin_steps"]["0.002"]["speedup"] == pytest.approx(4.0)
    text = E.report(fig, "1:3")
    assert "twin  5.0 ms agreement 2/3" in text and "twin  2.0 ms agreement 3/3" in text


def test_a_resumed_run_reuses_only_records_that_answer_it() -> None:
    rec = twin_record(1, {"0.005": [row(True)]})
    assert E.usable(rec, ["0.005"], only_twin=True)
    assert not E.usable(rec, ["0.005", "0.002"], only_twin=True)  # a step is missing
    assert not E.usable(rec, ["0.005"], only_twin=False)  # a full run needs the rest
    full = {k: v for k, v in rec.items() if k != "only"}
    full["parts"] = [{k: v for k, v in full["parts"][0].items() if k != "twin_steps"}]
    assert E.usable(full, [E.TWIN_KEY], only_twin=True)  # older records: the default twin
    assert E.usable(full, [E.TWIN_KEY], only_twin=False)


def test_the_twins_step_is_validated() -> None:
    spec = generate_cabinet(3)
    for bad in (0.0, -0.001, 0.02, float("nan")):
        with pytest.raises(ConfigError, match="timestep"):
            PlanningTwin(spec, timestep=bad)
