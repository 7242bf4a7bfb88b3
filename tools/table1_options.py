"""Table I's toy columns with the search options of issue 13, one row per (solver, option).

Usage::

    python tools/table1_options.py [--seeds 100] [--out runs/table1_options] [--workers 2]
                                   [--resume]

The paper's settings (``strug bench`` defaults: 3000 simulations per decision, fixed c,
random rollouts, no tree reuse, receding horizon) are Table I itself; this script runs
the same domains and seeds with one option set at a time, so each row shows what that
option does to that solver:

* ``normalized``: ``exploration=normalized`` (every tree solver);
* ``reuse``: ``reuse_tree=true`` (POMCP);
* ``episode``: ``horizon=episode`` (every tree solver);
* ``all``: the three together (POMCP).

Each option set is one resumable ``strug bench`` run in ``OUT/<option>/`` (its own
``results.jsonl``, fsync'ed per episode); ``OUT/table.md`` is rewritten at the end with
every row. Rollout heuristics are left out: only the Tiger domains have one.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from strug_manip.experiments.bench import BenchSpec, run_bench
from strug_manip.experiments.table import DOMAIN_TITLES, SOLVER_TITLES

DOMAINS = ("tiger", "extendedtiger", "lightdark1d", "lightdark2d")
TREE_SOLVERS = ("pomcp", "pomcpow", "entropy", "active", "strug")

#: Option set name -> (solvers, config overrides).
OPTIONS: dict[str, tuple[tuple[str, ...], dict[str, Any]]] = {
    "normalized": (TREE_SOLVERS, {"exploration": "normalized"}),
    "reuse": (("pomcp",), {"reuse_tree": True}),
    "episode": (TREE_SOLVERS, {"horizon": "episode"}),
    "all": (("pomcp",), {"exploration": "normalized", "reuse_tree": True, "horizon": "episode"}),
}


def markdown(rows: list[tuple[str, str, dict[str, dict[str, dict[str, float]]]]]) -> str:
    """One table: a row per (solver, option set), the toy domains as columns."""
    head = "| solver | options | " + " | ".join(DOMAIN_TITLES[d] for d in DOMAINS) + " |"
    lines = [head, "|" + "---|" * (len(DOMAINS) + 2)]
    for solver, option, summary in rows:
        flags = " ".join(f"{k}={str(v).lower()}" for k, v in OPTIONS[option][1].items())
        cells = []
        for d in DOMAINS:
            c = summary.get(d, {}).get(solver)
            cells.append(f"{c['mean']:.2f} ± {c['stderr']:.2f}" if c else "")
        lines.append(f"| {SOLVER_TITLES[solver]} | `{flags}` | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """Run every option set (resumably) and write ``OUT/table.md``."""
    parser = argparse.ArgumentParser(description="Table I toy columns with issue 13's options.")
    parser.add_argument("--seeds", type=int, default=100, help="seeds 0..N-1 per cell")
    parser.add_argument("--out", type=Path, default=Path("runs/table1_options"))
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--resume", action="store_true", help="continue the runs in --out")
    parser.add_argument(
        "--options", default=",".join(OPTIONS), help=f"comma-separated, of {', '.join(OPTIONS)}"
    )
    args = parser.parse_args(argv)
    chosen = [x.strip() for x in args.options.split(",") if x.strip()]
    bad = [x for x in chosen if x not in OPTIONS]
    if bad:
        parser.error(f"unknown option set {', '.join(bad)}; expected some of {', '.join(OPTIONS)}")
    rows = []
    for option in chosen:
        solvers, overrides = OPTIONS[option]
        print(f"{option}: {', '.join(solvers)} with {overrides}", file=sys.stderr)
        spec = BenchSpec(DOMAINS, solvers, args.seeds, overrides)
        summary = run_bench(spec, args.out / option, workers=args.workers, resume=args.resume)
        rows += [(s, option, summary) for s in solvers]
    rows.sort(key=lambda r: (TREE_SOLVERS.index(r[0]), list(OPTIONS).index(r[1])))
    table = markdown(rows)
    (args.out / "table.md").write_text(table)
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
