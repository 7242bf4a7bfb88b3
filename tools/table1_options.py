"""Table I's toy columns with the search options of issue 13, one row per (solver, option).

Usage::

    python tools/table1_options.py [--seeds 100] [--seeds-for OPTION=N ...]
                                   [--baseline runs/table1] [--out runs/table1_options]
                                   [--workers 2] [--resume] [--options NAME,...]

The paper's settings (``strug bench`` defaults: 3000 simulations per decision, fixed c,
random rollouts, no tree reuse, receding horizon) are Table I itself; this script runs
the same domains and seeds with one option set at a time, so each row shows what that
option does to that solver:

* ``normalized``: ``exploration=normalized`` (every tree solver);
* ``reuse``: ``reuse_tree=true`` (POMCP);
* ``episode``: ``horizon=episode`` (every tree solver);
* ``all``: the three together (POMCP).

Each option set is one resumable ``strug bench`` run in ``OUT/<option>/`` (its own
``results.jsonl``, fsync'ed per episode) over seeds ``0..N-1``: ``N`` is ``--seeds``, or
``--seeds-for OPTION=N`` for one set (the expensive ``episode`` set may get fewer;
``strug bench`` plays seed by seed, so a killed run's finished seeds are a prefix).
``OUT/table.md`` is rewritten at the end with every row. Beside them, ``paper`` rows
give the same solvers with the paper's settings on the *same* seeds, read from the
Table I run in ``--baseline`` (default ``runs/table1``, skipped when it is absent), so
each option row is compared with its own seeds. Rollout heuristics are left out: only
the Tiger domains have one.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from strug_manip.experiments.bench import BenchSpec, load_results, run_bench
from strug_manip.experiments.table import DOMAIN_TITLES, SOLVER_TITLES, summarize

DOMAINS = ("tiger", "extendedtiger", "lightdark1d", "lightdark2d")
TREE_SOLVERS = ("pomcp", "pomcpow", "entropy", "active", "strug")

#: Option set name -> (solvers, config overrides).
OPTIONS: dict[str, tuple[tuple[str, ...], dict[str, Any]]] = {
    "normalized": (TREE_SOLVERS, {"exploration": "normalized"}),
    "reuse": (("pomcp",), {"reuse_tree": True}),
    "episode": (TREE_SOLVERS, {"horizon": "episode"}),
    "all": (("pomcp",), {"exploration": "normalized", "reuse_tree": True, "horizon": "episode"}),
}


#: A table row: (solver, option set or ``PAPER``, seeds, {domain: {solver: cell}}).
Row = tuple[str, str, int, dict[str, dict[str, dict[str, float]]]]

#: The option name of the rows with the paper's settings (the Table I run).
PAPER = "paper"


def markdown(rows: list[Row]) -> str:
    """One table: a row per (solver, option set, seeds), the toy domains as columns."""
    titles = " | ".join(DOMAIN_TITLES[d] for d in DOMAINS)
    lines = [f"| solver | options | seeds | {titles} |", "|" + "---|" * (len(DOMAINS) + 3)]
    for solver, option, seeds, summary in rows:
        if option == PAPER:
            flags = "paper settings"
        else:
            flags = "`" + " ".join(f"{k}={str(v).lower()}" for k, v in OPTIONS[option][1].items())
            flags += "`"
        cells = []
        for d in DOMAINS:
            c = summary.get(d, {}).get(solver)
            cells.append(f"{c['mean']:.2f} ± {c['stderr']:.2f}" if c else "")
        lines.append(
            f"| {SOLVER_TITLES[solver]} | {flags} | 0-{seeds - 1} | " + " | ".join(cells) + " |"
        )
    return "\n".join(lines) + "\n"


def paper_rows(baseline: Path, wanted: set[tuple[str, int]]) -> list[Row]:
    """The Table I run's rows for each (solver, seeds) in ``wanted`` (seeds ``0..N-1``).

    A cell the baseline does not hold for all ``N`` seeds stays empty.
    """
    if not (baseline / "results.jsonl").exists():
        return []
    records = load_results(baseline)
    rows = []
    for solver, seeds in sorted(wanted):
        mine = [r for r in records if r["solver"] == solver and r["seed"] < seeds]
        summary = {
            d: {s: c for s, c in cells.items() if c["n"] == seeds}
            for d, cells in summarize(mine).items()
        }
        rows.append((solver, PAPER, seeds, summary))
    return rows


def _seeds_for(items: list[str], default: int, valid: list[str]) -> dict[str, int]:
    """``--seeds-for OPTION=N`` flags as ``{option: N}`` over every option set."""
    out = dict.fromkeys(valid, default)
    for item in items:
        name, _, n = item.partition("=")
        if name not in OPTIONS or not n.isdigit() or int(n) < 2:
            raise SystemExit(
                f"table1_options: --seeds-for expects OPTION=N with N >= 2 and OPTION one of "
                f"{', '.join(OPTIONS)}, got {item!r}"
            )
        out[name] = int(n)
    return out


def main(argv: list[str] | None = None) -> int:
    """Run every option set (resumably) and write ``OUT/table.md``."""
    parser = argparse.ArgumentParser(description="Table I toy columns with issue 13's options.")
    parser.add_argument("--seeds", type=int, default=100, help="seeds 0..N-1 per cell")
    parser.add_argument(
        "--seeds-for", action="append", default=[], metavar="OPTION=N", help="seeds of one set"
    )
    parser.add_argument("--baseline", type=Path, default=Path("runs/table1"))
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
    seeds = _seeds_for(args.seeds_for, args.seeds, chosen)
    rows: list[Row] = []
    for option in chosen:
        solvers, overrides = OPTIONS[option]
        print(f"{option}: {', '.join(solvers)} with {overrides}", file=sys.stderr)
        spec = BenchSpec(DOMAINS, solvers, seeds[option], overrides)
        summary = run_bench(spec, args.out / option, workers=args.workers, resume=args.resume)
        rows += [(s, option, seeds[option], summary) for s in solvers]
    rows += paper_rows(args.baseline, {(r[0], r[2]) for r in rows})
    order = [PAPER, *OPTIONS]
    rows.sort(key=lambda r: (TREE_SOLVERS.index(r[0]), -r[2], order.index(r[1])))
    table = markdown(rows)
    (args.out / "table.md").write_text(table)
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
