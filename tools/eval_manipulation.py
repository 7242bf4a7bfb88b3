"""The manipulation tasks on a range of episode seeds: success, failures by cause, time.

Usage::

    python tools/eval_manipulation.py --domains shelf --solvers strug,pomcpow \\
        --seeds 100:120 --out runs/eval_shelf --workers 2
    python tools/eval_manipulation.py --domains opendrawer --solvers strug --seeds 100:106 \\
        --out runs/eval_drawer --report-only

Runs the missing episodes of the range with ``strug bench`` (:func:`~strug_manip.
experiments.bench.run_bench`, resumable: episodes already in ``OUT/results.jsonl`` are
kept; ``--report-only`` runs none), then reports on the range's episodes only. Each
episode's real cabinet is a held-out generator seed (6,000-9,999) drawn from the
episode seed: tune on one range, report on another.

What it prints, per domain and solver: episodes that earned the task's +10; mean
return ± standard error; the median of the episodes' median planning time per step and
the median episode wall time. Per domain, the failures by cause, counted per episode
(per solver in brackets):

* ``dragged``: the episode ended at -10 (the cabinet more than 0.1 m from its start);
* ``placed elsewhere``: a real ``Place`` into a part ran ``ok`` and the episode earned
  nothing (the object in another part, or resting outside the target); records written
  before ``Place(table)`` was told apart count its ``ok`` here as well;
* ``out of steps after <skill> <status>``: the last real skill that ran and how it ended
  (``not_applicable`` steps, which run nothing, are left out);
* ``nothing ran``: no real skill ran at all.

Then the steps that ran nothing (the chosen action could not start under any of the
models the full robot plans in: ``not_applicable``; they spend the episode's steps and
no cause above names them), where the time went (summed over the episodes: the twin,
rendering predicted clouds, likelihoods, the full robot, perception, set-up) and the
outcome cache's median hit rate.

``oracle`` is a solver row like the others (STRUG knowing the cabinet: the bound the
skills set, :mod:`strug_manip.domains.manipulation.oracle`).
"""

from __future__ import annotations

import argparse
import collections
import json
import statistics
import sys
from pathlib import Path

from strug_manip.domains import MANIPULATION_DOMAINS
from strug_manip.experiments.bench import BenchSpec, load_results, run_bench, success_table
from strug_manip.experiments.seeds import seed_range

#: The report's time components, in the order printed.
TIME_PARTS = ("twin", "render", "likelihood", "real", "perception", "setup")


def cause(record: dict) -> str:
    """Why an episode failed (module docstring), or ``success``."""
    if record["success"]:
        return "success"
    if record["return"] < 0:
        return "dragged"
    real = record["report"].get("real", [])
    if any(r == "Place ok" for r in real):
        return "placed elsewhere"
    return f"out of steps after {real[-1]}" if real else "nothing ran"


def idle_steps(records: list[dict]) -> str:
    """How many of the episodes' steps ran no real skill, in all and per solver."""
    idle: collections.Counter[str] = collections.Counter()
    steps: collections.Counter[str] = collections.Counter()
    for r in records:
        idle[r["solver"]] += max(0, r["steps"] - len(r["report"].get("real", [])))
        steps[r["solver"]] += r["steps"]
    per = ", ".join(f"{s} {idle[s]} of {steps[s]}" for s in sorted(steps))
    return f"steps that ran nothing: {sum(idle.values())} of {sum(steps.values())} ({per})"


def report(records: list[dict]) -> str:
    """The text report of ``records`` (one domain or several)."""
    lines = [success_table(records)]
    groups: dict[tuple[str, str], list[dict]] = collections.defaultdict(list)
    for r in records:
        groups[(r["domain"], r["solver"])].append(r)
    lines.append("| domain | solver | mean return ± s.e. |")
    lines.append("|---|---|---|")
    for (d, s), rs in sorted(groups.items()):
        x = [r["return"] for r in rs]
        se = statistics.stdev(x) / len(x) ** 0.5 if len(x) > 1 else 0.0
        lines.append(f"| {d} | {s} | {statistics.mean(x):+.2f} ± {se:.2f} |")
    for d in sorted({r["domain"] for r in records}):
        rs = [r for r in records if r["domain"] == d]
        failed = [r for r in rs if not r["success"]]
        causes = collections.Counter(cause(r) for r in failed)
        lines.append(f"\n{d}: failures by cause ({sum(causes.values())} of {len(rs)} episodes)")
        by = collections.Counter((cause(r), r["solver"]) for r in failed)
        for c, n in causes.most_common():
            who = {s: k for (c2, s), k in by.items() if c2 == c}
            lines.append(f"  {n:4d}  {c} ({', '.join(f'{s} {k}' for s, k in sorted(who.items()))})")
        lines.append("  " + idle_steps(rs))
        total = {k: sum(r["report"]["time"].get(k, 0.0) for r in rs) for k in TIME_PARTS}
        t = sum(total.values()) or 1.0
        parts = ", ".join(f"{k} {v / t:.0%}" for k, v in total.items())
        hits = [r["report"]["outcome_cache"]["hit_rate"] for r in rs
                if "outcome_cache" in r["report"]]  # fmt: skip
        hit = f"{statistics.median(hits):.0%}" if hits else "n/a"
        lines.append(f"  time: {parts} (of {t:.0f} s); outcome cache hit rate median {hit}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--domains", default="shelf,opendrawer,opendoor")
    p.add_argument("--solvers", default="random,pomcp,pomcpow,entropy,active,strug,oracle")
    p.add_argument("--seeds", type=seed_range, required=True, help="episode seeds START:STOP")
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--report-only", action="store_true", help="run no episode")
    p.add_argument("--json", action="store_true", help="print the range's records as JSON")
    args = p.parse_args(argv)
    domains = tuple(x for x in args.domains.split(",") if x)
    for d in domains:
        if d not in MANIPULATION_DOMAINS:
            p.error(f"--domains: {d!r} is not one of {', '.join(MANIPULATION_DOMAINS)}")
    solvers = tuple(x for x in args.solvers.split(",") if x)
    seeds: range = args.seeds
    if not args.report_only:
        spec = BenchSpec(domains, solvers, len(seeds), first_seed=seeds.start)
        run_bench(spec, args.out, workers=args.workers, resume=True)
    records = [
        r
        for r in load_results(args.out)
        if r["domain"] in domains and r["solver"] in solvers and r["seed"] in seeds
    ]
    if not records:
        print(f"no episodes of {args.seeds} in {args.out}", file=sys.stderr)
        return 1
    print(json.dumps(records) if args.json else report(records))
    return 0


if __name__ == "__main__":
    sys.exit(main())
