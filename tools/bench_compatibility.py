"""Cost of STRUG's plan compatibility matrix (Algorithm 1) as M grows.

Usage::

    python tools/bench_compatibility.py [--domain lightdark2d] [--sizes 16,32,64]
                                        [--repeats 3] [--trials 5] [--seed 0] [--json]

For each M: M particles from the domain's initial belief, one uncertainty-free plan
each (``plan_for``), every plan executed K = ``--repeats`` times from every particle.
Prints the median wall time over ``--trials`` matrices, the plan executions
(M * M * K), the generative-model steps, and both normalised by M^2: constant
per-M^2 figures mean the cost grows as M^2, not worse.
"""

from __future__ import annotations

import argparse
import json
import statistics

import numpy as np

from planners.tru import compatibility_matrix
from strug_manip.domains import make_domain


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--domain", default="lightdark2d")
    parser.add_argument("--sizes", default="16,32,64")
    parser.add_argument("--repeats", type=int, default=3, help="K, executions per plan/particle")
    parser.add_argument("--trials", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    pomdp = make_domain(args.domain)
    rng = np.random.default_rng(args.seed)
    rows = []
    for m in (int(x) for x in args.sizes.split(",")):
        times, execs, steps = [], 0, 0
        for _ in range(args.trials):
            states = [pomdp.sample_initial_state(rng) for _ in range(m)]
            cm = compatibility_matrix(pomdp, states, args.repeats, rng)
            times.append(cm.seconds)
            execs, steps = cm.executions, cm.steps
        t = statistics.median(times)
        rows.append(
            {
                "M": m,
                "seconds": t,
                "plan_executions": execs,
                "steps": steps,
                "us_per_execution": 1e6 * t / execs,
                "ms_per_M2": 1e3 * t / m**2,
            }
        )
    if args.json:
        print(json.dumps(rows))
        return
    print(f"compatibility matrix on {args.domain}, K={args.repeats}, median of {args.trials}")
    print(f"{'M':>4} {'seconds':>9} {'executions':>11} {'steps':>9} {'us/exec':>8} {'ms/M^2':>8}")
    for r in rows:
        print(
            f"{r['M']:>4} {r['seconds']:>9.4f} {r['plan_executions']:>11,} {r['steps']:>9,} "
            f"{r['us_per_execution']:>8.2f} {r['ms_per_M2']:>8.4f}"
        )
    first, last = rows[0], rows[-1]
    growth = last["seconds"] / first["seconds"]
    print(
        f"M x{last['M'] / first['M']:.0f}: time x{growth:.1f} "
        f"(M^2 predicts x{(last['M'] / first['M']) ** 2:.0f})"
    )


if __name__ == "__main__":
    main()
