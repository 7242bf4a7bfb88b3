"""Record the planning-twin runs of one decision's search, or replay them: how long the
twins take and whether a change to them alters any outcome.

Usage::

    # with the code before a change (e.g. a worktree of main):
    python tools/replay_twin_runs.py record --domain opendrawer --seed 9100 --sims 100 \\
        --file runs/twin_runs.pkl
    # with the code after it (the same file):
    python tools/replay_twin_runs.py replay --domain opendrawer --seed 9100 \\
        --file runs/twin_runs.pkl

``record`` builds the episode of ``--seed`` (its real cabinet, perception's belief,
the belief conditioned as the runner does), runs STRUG's first decision with ``--sims``
simulations and saves every twin run the search made (particle, start state, action,
outcome, wall time [s]), then prints how many there were, by where the search asked for
them (expansions of a node, a particle's forward plan ``plan_for``, a plan executed from
another particle ``plan_return``), and their time. ``replay`` builds the same episode
with the code at hand, runs the saved runs again in their order (the caches fill as
they did) and prints the CPU and wall time [s] and how many outcomes differ from the
recorded ones (next state, observation key, reward, terminal and summary). Timings on a
loaded machine vary; compare CPU times of runs made back to back.
"""

from __future__ import annotations

import argparse
import collections
import pickle
import sys
import time
import traceback
from pathlib import Path
from typing import Any

import numpy as np

from planners.episode import episode_generators
from strug_manip.domains import make_domain
from strug_manip.experiments.task import budget_for, solver_config

#: Where the search asked for a twin run, by the first of these on the call stack.
ORIGINS = ("plan_for", "plan_return", "expand", "compatibility_matrix")


def episode(domain: str, seed: int) -> tuple[Any, Any, np.random.Generator]:
    """The task of ``domain`` at episode ``seed`` after its reset: (task, the
    conditioned initial belief, the planner's generator), as ``run_episode`` makes them."""
    task = make_domain(domain)
    world_rng, belief_rng, plan_rng = episode_generators(seed)
    task.environment.reset(world_rng)
    belief = task.environment.condition(task.initial_belief(belief_rng, 1000))
    return task, belief, plan_rng


def record(args: argparse.Namespace) -> None:
    """Run the first decision and save its twin runs (module docstring)."""
    task, belief, rng = episode(args.domain, args.seed)
    runs: list[tuple] = []
    origins: list[str] = []
    simulate = task._simulate

    def recorded(i: int, sim: Any, a: Any) -> Any:
        t = time.perf_counter()
        out = simulate(i, sim, a)
        runs.append((i, sim, a, out, time.perf_counter() - t))
        names = {f.name for f in traceback.extract_stack(limit=16)}
        origins.append(next((o for o in ORIGINS if o in names), "other"))
        return out

    task._simulate = recorded
    planner = solver_config("strug", budget_for(args.domain, {"sims": args.sims})).planner(task)
    t = time.perf_counter()
    planner.act(belief, rng)
    print(f"decision {time.perf_counter() - t:.2f} s; twin runs {len(runs)}, "
          f"{sum(r[4] for r in runs):.2f} s")  # fmt: skip
    seconds: dict[str, float] = collections.defaultdict(float)
    for o, r in zip(origins, runs, strict=True):
        seconds[o] += r[4]
    for o, n in collections.Counter(origins).most_common():
        print(f"  {o}: {n} runs, {seconds[o]:.2f} s")
    args.file.parent.mkdir(parents=True, exist_ok=True)
    args.file.write_bytes(pickle.dumps(runs))


def same(a: tuple, b: tuple) -> bool:
    """Whether two outcomes ``(next state, key, reward, terminal, summary)`` agree (the
    states to 1e-9 in every coordinate)."""
    return a[1:] == b[1:] and np.allclose(a[0].physics, b[0].physics, rtol=0.0, atol=1e-9)


def replay(args: argparse.Namespace) -> None:
    """Run the saved twin runs again and compare (module docstring)."""
    runs = pickle.loads(args.file.read_bytes())
    task, _, _ = episode(args.domain, args.seed)
    differ = 0
    cpu, wall = time.process_time(), time.perf_counter()
    for i, sim, a, out, _ in runs:
        if not same(task._simulate(i, sim, a), out):
            differ += 1
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    recorded = sum(r[4] for r in runs)
    print(f"runs {len(runs)}, outcomes that differ {differ}; CPU {cpu:.2f} s, wall "
          f"{wall:.2f} s (recorded in the search: {recorded:.2f} s)")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("mode", choices=("record", "replay"))
    p.add_argument("--domain", default="opendrawer")
    p.add_argument("--seed", type=int, default=9100, help="episode seed (a tuning seed)")
    p.add_argument("--sims", type=int, default=100, help="simulations of the decision")
    p.add_argument("--file", type=Path, required=True, help="the runs' file (pickle)")
    args = p.parse_args(argv)
    (record if args.mode == "record" else replay)(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
