"""Where bench episodes run: local workers end with their parent; Ray gives the same rows;
a user's own domain by ``package.module:Class``."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from strug_manip.experiments.bench import TIMING_FIELDS, BenchSpec, load_results, run_bench


def _children(pid: int) -> list[int]:
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                out.append(int(entry.name))
    return out


def _alive(pid: int) -> bool:
    """True while ``pid`` runs (a zombie waiting for its reaper counts as dead)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state not in ("Z", "X")


@pytest.mark.skipif(not Path("/proc").exists(), reason="reads /proc")
def test_workers_end_when_the_parent_is_killed(tmp_path: Path) -> None:
    cmd = [sys.executable, "-m", "strug_manip", "bench", "--domains", "lightdark1d",
           "--solvers", "pomcpow", "--seeds", "50", "--sims", "3000", "--out", str(tmp_path),
           "--workers", "2", "--no-progress"]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    workers: list[int] = []
    while time.time() < deadline and len(workers) < 2:
        time.sleep(0.2)
        workers = _children(proc.pid)
    assert len(workers) == 2, "the bench should have started two workers"
    time.sleep(1.0)  # the workers are inside their first episodes
    os.kill(proc.pid, signal.SIGKILL)  # the parent only, not its process group
    proc.wait()
    deadline = time.time() + 5
    while time.time() < deadline and any(_alive(w) for w in workers):
        time.sleep(0.1)
    assert not any(_alive(w) for w in workers), "a worker outlived its parent"
    err = proc.stderr.read()
    assert "leaked" not in err and "Traceback" not in err, err


def _rows(out: Path) -> list[str]:
    """The records without their wall times, sorted (the order of finishing varies)."""
    return sorted(
        json.dumps({k: v for k, v in r.items() if k not in TIMING_FIELDS}, sort_keys=True)
        for r in load_results(out)
    )


def test_ray_runs_the_same_sweep_as_local_processes(tmp_path: Path) -> None:
    pytest.importorskip("ray")
    spec = BenchSpec(("tiger", "lightdark1d"), ("random", "pomcp"), 3, {"sims": 50}, 100)
    run_bench(spec, tmp_path / "local", workers=2, progress=False)
    # Ray, interrupted after 4 episodes (by a resume of a partial copy) must give the same.
    ray_out = tmp_path / "ray"
    ray_out.mkdir()
    partial = (tmp_path / "local" / "results.jsonl").read_text().splitlines()[:4]
    (ray_out / "results.jsonl").write_text("\n".join(partial) + "\n")
    run_bench(spec, ray_out, workers=2, progress=False, executor="ray", resume=True)
    assert len(load_results(ray_out)) == 12
    assert _rows(ray_out) == _rows(tmp_path / "local")
    assert load_results(ray_out)[:4] == [json.loads(x) for x in partial]  # kept as they were


def test_ray_missing_is_one_clear_error(tmp_path: Path, monkeypatch) -> None:
    import builtins

    from planners.errors import ConfigError

    real_import = builtins.__import__

    def no_ray(name, *args, **kwargs):
        if name == "ray":
            raise ImportError("No module named 'ray'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_ray)
    spec = BenchSpec(("tiger",), ("random",), 1, {}, 50)
    with pytest.raises(ConfigError, match=r"--executor ray needs Ray: pip install"):
        run_bench(spec, tmp_path, progress=False, executor="ray")


USER_DOMAIN = '''
from strug_manip.domains.tiger import Tiger


class SmallTiger(Tiger):
    """The paper's Tiger under another name: a domain outside strug_manip."""

    name = "smalltiger"
'''


def test_a_user_domain_by_module_and_class(tmp_path: Path) -> None:
    (tmp_path / "my_domains.py").write_text(USER_DOMAIN)
    base = [sys.executable, "-m", "strug_manip"]
    run = subprocess.run(
        [*base, "run", "--domain", "my_domains:SmallTiger", "--solver", "pomcp", "--sims", "50",
         "--json"], cwd=tmp_path, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "return" in json.loads(run.stdout.splitlines()[-1])
    out = tmp_path / "runs"
    bench = subprocess.run(
        [*base, "bench", "--domains", "my_domains:SmallTiger,tiger", "--solvers", "random",
         "--seeds", "3", "--out", str(out), "--workers", "2", "--no-progress", "--json"],
        cwd=tmp_path, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert bench.returncode == 0, bench.stderr
    summary = json.loads(bench.stdout)
    # Same seeds, same dynamics: the renamed Tiger plays exactly the Tiger's episodes.
    assert summary["my_domains:SmallTiger"] == summary["tiger"]


@pytest.mark.skipif(not Path("/proc").exists(), reason="reads /proc")
def test_ctrl_c_stops_bench_and_its_workers_with_one_line(tmp_path: Path) -> None:
    """SIGINT to the whole process group, as a terminal's Ctrl-C sends it. The bench
    starts with SIGINT's default action, as a terminal's foreground job does: a test
    suite run as a background job of a script (``make test &``) inherits SIGINT
    ignored, and the bench would then run to its end."""
    cmd = [sys.executable, "-m", "strug_manip", "bench", "--domains", "lightdark1d",
           "--solvers", "pomcpow", "--seeds", "50", "--sims", "3000", "--out", str(tmp_path),
           "--workers", "2", "--no-progress"]  # fmt: skip
    proc = subprocess.Popen(
        cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
        start_new_session=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    results = tmp_path / "results.jsonl"
    deadline = time.time() + 60
    while time.time() < deadline and not (results.exists() and results.read_text()):
        time.sleep(0.1)
    workers = _children(proc.pid)
    os.killpg(proc.pid, signal.SIGINT)
    assert proc.wait(timeout=20) == 130
    err = proc.stderr.read()
    kept = len(load_results(tmp_path))
    assert kept >= 1
    assert err.strip().splitlines() == [
        f"strug: interrupted: {kept} finished episodes are kept in {results}; "
        "rerun the same command with --resume to run only the rest"
    ], err
    assert not any(_alive(w) for w in workers)
