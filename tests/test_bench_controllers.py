"""``tools/bench_controllers.py``: the OpenDrawer wall time on one core, against the twin.

Runs the tool on one cabinet (seed 11, three drawers), one run each: its JSON holds the
figures the README quotes, consistent with each other (the target itself is measured by
the tool on an idle core, not asserted here: the test machine's cores are shared).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

TOOL = Path(__file__).resolve().parent.parent / "tools" / "bench_controllers.py"


def test_bench_reports_open_drawer_wall_time_and_the_twin_ratio() -> None:
    cmd = [sys.executable, str(TOOL), "--seeds", "11", "--runs", "1", "--skills", "none"]
    proc = subprocess.run([*cmd, "--json"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    r = json.loads(proc.stdout)
    od = r["open_drawer"]
    assert od["drawers"] == 3 and od["n"] == 3 and od["seeds"] == [11]
    assert 0 < od["median_s"] <= od["p90_s"] <= od["max_s"]
    assert od["cpu_median_s"] > 0 and 0 < od["twin_median_s"] < od["median_s"]
    assert od["speedup_median"] > 1
    shares = [od[k] for k in ("ik_share", "planning_share", "physics_share", "other_share")]
    assert all(0 <= s <= 1 for s in shares) and abs(sum(shares) - 1) < 1e-9
    assert od["statuses"] == {"ok": 3}
    assert r["met"] == (od["median_s"] <= r["target_s"]) and r["target_s"] == 0.5
    assert "skills" not in r
    bad = subprocess.run([*cmd[:2], "--seeds", "x"], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and "'x'" in bad.stderr
