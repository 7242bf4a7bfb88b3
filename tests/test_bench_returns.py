"""tools/bench_returns.py: its report keys, its best configuration and its --set flags."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from planners.solvers import make_solver
from strug_manip.cli_args import parse_value

_PATH = Path(__file__).resolve().parents[1] / "tools" / "bench_returns.py"
_spec = importlib.util.spec_from_file_location("bench_returns", _PATH)
assert _spec is not None and _spec.loader is not None
bench_returns = importlib.util.module_from_spec(_spec)
sys.modules["bench_returns"] = bench_returns
_spec.loader.exec_module(bench_returns)


def _records(budget: str, config: str, returns: list[float]) -> list[dict]:
    return [
        {"budget": budget, "config": config, "seed": i, "return": r, "sims": 100.0,
         "seconds": 0.02, "load1": 1.0}
        for i, r in enumerate(returns)
    ]  # fmt: skip


def test_set_flags_rebuild_every_configuration() -> None:
    """``strug bench --set NAME=VALUE`` with the printed flags gives the same config."""
    for name, overrides in bench_returns.OURS.items():
        parsed = {}
        for flag in bench_returns.set_flags(name):
            key, _, value = flag.partition("=")
            parsed[key] = parse_value(value)
        assert parsed == overrides
        assert make_solver("pomcp", parsed) == make_solver("pomcp", overrides)


def test_json_report_has_exactly_the_documented_keys() -> None:
    records = (
        _records("20ms", "pomdp_py", [1.0, 3.0, 2.0])
        + _records("20ms", "pomcp", [0.0, 1.0, -1.0])
        + _records("20ms", "pomcp+normalized+reuse", [5.0, 7.0, 6.0])
        + _records("200ms", "pomcp", [4.0, 5.0])
    )
    summary = bench_returns.summarize(records)
    report = bench_returns.json_report(summary, ["20ms", "200ms", "1000sims"])
    assert set(report) == {"20ms", "200ms", "best"}
    assert set(report["20ms"]) == {"pomdp_py", "pomcp", "pomcp+normalized+reuse"}
    for cell in report["20ms"].values():
        assert set(cell) == {"mean", "stderr", "n"}
    assert report["20ms"]["pomcp+normalized+reuse"] == {"mean": 6.0, "stderr": 1.0 / 3**0.5, "n": 3}
    # The best is ours with the highest mean at 20 ms; a peer never is.
    assert report["best"] == ["exploration=normalized", "reuse_tree=true"]
    text = bench_returns.text_report(summary, ["20ms", "200ms"], ["header"])
    assert "exact optimum 6.69" in text and "--set exploration=normalized" in text
