"""Table I runs: tables, resume after a kill, settings checks."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from planners.errors import ConfigError
from strug_manip.experiments.bench import BenchSpec, load_results, run_bench
from strug_manip.experiments.table import summarize, to_markdown


def _triples(path: Path) -> list[tuple[str, str, int]]:
    return [(r["domain"], r["solver"], r["seed"]) for r in load_results(path)]


def test_bench_writes_tables_and_json_summary(tmp_path: Path) -> None:
    spec = BenchSpec(("tiger", "lightdark1d"), ("random", "pomcp"), 3, {"sims": 50}, 100)
    summary = run_bench(spec, tmp_path, workers=2, progress=False)
    for name in ("results.jsonl", "table.md", "table.csv", "table.png", "run.json"):
        assert (tmp_path / name).stat().st_size > 0
    assert summary["tiger"]["random"]["n"] == 3
    assert set(summary) == {"tiger", "lightdark1d"}
    assert len(_triples(tmp_path)) == 12
    md = (tmp_path / "table.md").read_text()
    assert "| Random |" in md and "Tiger" in md and "LightDark 1D" in md
    # A second run over a full directory needs --resume and then does nothing new.
    with pytest.raises(ConfigError, match="pass --resume"):
        run_bench(spec, tmp_path, progress=False)
    run_bench(spec, tmp_path, resume=True, progress=False)
    assert len(_triples(tmp_path)) == 12


def test_resume_refuses_other_settings(tmp_path: Path) -> None:
    run_bench(BenchSpec(("tiger",), ("random",), 2, {"sims": 50}, 50), tmp_path, progress=False)
    with pytest.raises(ConfigError, match="settings"):
        run_bench(
            BenchSpec(("tiger",), ("random",), 2, {"sims": 60}, 50),
            tmp_path,
            resume=True,
            progress=False,
        )


def test_torn_last_line_is_dropped(tmp_path: Path) -> None:
    spec = BenchSpec(("tiger",), ("random",), 4, {}, 50)
    run_bench(spec, tmp_path, progress=False)
    path = tmp_path / "results.jsonl"
    lines = path.read_text().splitlines()
    path.write_text("\n".join(lines[:2]) + "\n" + lines[2][:15])  # killed mid-write
    run_bench(spec, tmp_path, resume=True, progress=False)
    triples = _triples(tmp_path)
    assert sorted(triples) == sorted(set(triples)) and len(triples) == 4


def test_kill_then_resume_loses_and_repeats_nothing(tmp_path: Path) -> None:
    out = tmp_path / "run"
    cmd = [
        sys.executable,
        "-m",
        "strug_manip",
        "bench",
        "--domains",
        "tiger,lightdark1d",
        "--solvers",
        "random,pomcp,pomcpow",
        "--seeds",
        "6",
        "--sims",
        "300",
        "--particles",
        "200",
        "--out",
        str(out),
        "--workers",
        "2",
        "--no-progress",
    ]
    proc = subprocess.Popen(
        cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True
    )
    results = out / "results.jsonl"
    deadline = time.time() + 120
    while time.time() < deadline:
        if results.exists() and len(results.read_text().splitlines()) >= 5:
            break
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)  # the whole group: main process and workers
    proc.wait()
    before = load_results(out)
    assert 5 <= len(before) < 36, "the kill should land mid-run"
    done = subprocess.run([*cmd, "--resume"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    after = load_results(out)
    triples = [(r["domain"], r["solver"], r["seed"]) for r in after]
    assert len(triples) == len(set(triples)) == 36  # nothing repeated, nothing missing
    assert after[: len(before)] == before  # finished episodes kept as they were


def test_summary_and_bold_cells() -> None:
    recs = [
        {"domain": "tiger", "solver": s, "return": v}
        for s, vals in {"random": [-2.0, 0.0], "pomcp": [6.0, 8.0], "strug": [5.0, 6.0]}.items()
        for v in vals
    ]
    summary = summarize(recs)
    assert summary["tiger"]["pomcp"] == {"mean": 7.0, "stderr": 1.0, "n": 2}
    md = to_markdown(summary, with_paper=False)
    assert "**7.00 ± 1.00**" in md and "**5.50 ± 0.50**" in md  # 5.5 is within 2 of 7
    assert "| Random | -1.00 ± 1.00 |" in md  # not bold
    assert md.index("Random") < md.index("POMCP") < md.index("STRUG")


def test_bench_json_output(tmp_path: Path) -> None:
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "strug_manip",
            "bench",
            "--domains",
            "tiger",
            "--solvers",
            "random",
            "--seeds",
            "3",
            "--out",
            str(tmp_path),
            "--json",
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert set(data["tiger"]["random"]) == {"mean", "stderr", "n"}
    assert data["tiger"]["random"]["n"] == 3
