"""tools/table1_options.py: paper rows on the option rows' own seeds, and the table layout."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[1] / "tools" / "table1_options.py"
_spec = importlib.util.spec_from_file_location("table1_options", _PATH)
assert _spec is not None and _spec.loader is not None
table1_options = importlib.util.module_from_spec(_spec)
sys.modules["table1_options"] = table1_options
_spec.loader.exec_module(table1_options)


def _baseline(tmp_path: Path, seeds: int) -> Path:
    lines = [
        {"domain": "tiger", "solver": "pomcp", "seed": k, "return": float(k), "steps": 1,
         "seconds": 0.0, "mean_sims": 1.0}
        for k in range(seeds)
    ]  # fmt: skip
    (tmp_path / "results.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
    return tmp_path


def test_paper_rows_use_only_the_option_rows_seeds(tmp_path: Path) -> None:
    base = _baseline(tmp_path, 10)
    [(solver, option, seeds, summary)] = table1_options.paper_rows(base, {("pomcp", 4)})
    assert (solver, option, seeds) == ("pomcp", "paper", 4)
    assert summary["tiger"]["pomcp"]["n"] == 4
    assert summary["tiger"]["pomcp"]["mean"] == pytest.approx(1.5)  # seeds 0..3
    # A baseline with fewer seeds than asked leaves the cell empty rather than short.
    [(_, _, _, short)] = table1_options.paper_rows(base, {("pomcp", 20)})
    assert short["tiger"] == {}
    assert table1_options.paper_rows(tmp_path / "missing", {("pomcp", 4)}) == []


def test_markdown_rows_name_options_and_seeds(tmp_path: Path) -> None:
    base = _baseline(tmp_path, 10)
    option_summary = {"tiger": {"pomcp": {"mean": 2.0, "stderr": 0.5, "n": 4}}}
    rows = [("pomcp", "normalized", 4, option_summary)]
    rows += table1_options.paper_rows(base, {("pomcp", 4)})
    text = table1_options.markdown(rows)
    lines = text.splitlines()
    assert lines[0].startswith("| solver | options | seeds | Tiger |")
    assert "| POMCP (Disc) | `exploration=normalized` | 0-3 | 2.00 ± 0.50 |" in text
    assert "| POMCP (Disc) | paper settings | 0-3 | 1.50 ± 0.65 |" in text


def test_seeds_for_is_validated() -> None:
    valid = list(table1_options.OPTIONS)
    assert table1_options._seeds_for(["episode=20"], 50, valid)["episode"] == 20
    assert table1_options._seeds_for([], 50, valid)["reuse"] == 50
    with pytest.raises(SystemExit, match="--seeds-for expects OPTION=N"):
        table1_options._seeds_for(["nothing=20"], 50, valid)
