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

Then the **belief health** (recorded during each episode against the true cabinet, the
report's ``health``: :mod:`strug_manip.domains.manipulation.health`): how often the
initial belief held the true hypothesis of the target part and lost it, and the failures
decomposed into causes a user can act on, per episode the first of (:func:`health_flags`):

* ``true hypothesis missing from the initial belief``: no particle's target part has the
  real target's joint (type, axis within 10 deg, hinge or origin within 5 cm);
* ``no action on the target part: no model shows its handle``: no particle's target part
  is catalogued (perception gave it no handle in any model, so no opening, probe or
  ``Place`` names it), whatever its joint (OpenDoor episode 9963: a lift-up flap with a
  knob, the true hinge in half the models; the robot could only pick the object and put
  it back);
* ``belief dropped the true hypothesis``: after a step its weight fell below 1 %
  (:data:`~strug_manip.domains.manipulation.health.LOST_WEIGHT`), named by the skill and
  the key that did it: the real status against the one the twin of the best true
  particle predicted, the motion where only it differed, or the cloud where the keys
  agreed (each such step is listed with both keys);
* ``skill failed under the right hypothesis``: a real skill planned in a model holding
  the true hypothesis of the part it acted on ended other than ``ok``, or dragged;
* ``same action repeated without news``: an action chosen again right after it ended
  with the same key and the cabinet unchanged;
* ``out of steps``: none of these, the episode used all its steps;
* ``other: <cause>``: none of these either (the cause above).

``--twin-keys confusion|match`` chooses how the real belief update weighs the real
key's status against each twin's (:mod:`strug_manip.domains.manipulation.twin_keys`;
default the task's), for every episode this run starts; each record's report names the
rule it ran with (``twin_keys``). Keep one ``--out`` per rule.

``--sims N`` sets the simulations per decision of the episodes this run starts (default
the tasks' :data:`~strug_manip.domains.MANIPULATION_SIMS`); keep one ``--out`` per budget.

``oracle`` is a solver row like the others (STRUG knowing the cabinet: the bound the
skills set, :mod:`strug_manip.domains.manipulation.oracle`).
"""

from __future__ import annotations

import argparse
import collections
import itertools
import json
import os
import statistics
import sys
from collections.abc import Callable
from pathlib import Path

from strug_manip.domains import MANIPULATION_DOMAINS
from strug_manip.domains.manipulation import health, twin_keys
from strug_manip.experiments.bench import BenchSpec, load_results, run_bench, success_table
from strug_manip.experiments.seeds import seed_range

#: The report's time components, in the order printed.
TIME_PARTS = ("twin", "render", "likelihood", "real", "perception", "setup")
#: The belief-health causes, in the order an episode's is looked for.
MISSING = "true hypothesis missing from the initial belief"
NO_ACTION = "no action on the target part: no model shows its handle"
DROPPED = "belief dropped the true hypothesis"
SKILL_FAILED = "skill failed under the right hypothesis"
REPEATED = "same action repeated without news"
OUT_OF_STEPS = "out of steps"


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


def _skill(action: str) -> str:
    """The skill of a step's action name (``Place(table)`` kept whole)."""
    return action if action == "Place(table)" else action.split("(")[0]


def _key(key: list[float] | None) -> str:
    """An observation key for people: ``ok, held, (+1, +0, -2)`` (motion in 5 cm bins)."""
    if key is None:
        return "none"
    motion = ", ".join(f"{int(v):+d}" for v in key[2:])
    return f"{health.status_of(key)}, {'held' if key[1] else 'empty'}, ({motion})"


def drop_key(step: dict) -> str:
    """Which key dropped the true hypothesis at ``step`` (a health step record): the
    real status against the twin's, the motion or the grip where only it differed, or
    the cloud where the keys agreed."""
    real, twin = step["real_key"], step["twin_key"]
    if twin is None:
        return f"real {step['real_status']}, no twin key"
    if step["real_status"] != step["twin_status"]:
        return f"real {step['real_status']} vs twin {step['twin_status']}"
    if real[1] != twin[1]:
        return f"{step['real_status']}, the grip differs from the twin's"
    if list(real[2:]) != list(twin[2:]):
        return f"{step['real_status']}, the motion differs from the twin's"
    return f"{step['real_status']}, the cloud (keys agreed)"


def health_flags(record: dict) -> list[str]:
    """Every belief-health cause (module docstring) that a failed episode shows, in
    order; [] for a success or a record without health."""
    h = record["report"].get("health")
    if record["success"] or h is None:
        return []
    steps, out = h["steps"], []
    if h["initial"]["models"] == 0:
        out.append(MISSING)
    if h["initial"].get("catalogued", 1) == 0:  # records before 2026-12-06 lack it
        out.append(NO_ACTION)
    lost = next((s for s in steps if s["step"] == h["lost_at"]), None)
    if lost is not None:
        out.append(f"{DROPPED}: {_skill(lost['action'])} {drop_key(lost)}")
    failed = [s for s in steps if s["planned_true"]
              and (s["real_status"] != "ok" or s["reward"] < 0)]  # fmt: skip
    if failed:
        s = failed[0]
        out.append(f"{SKILL_FAILED}: {_skill(s['action'])} "
                   f"{'dragged' if s['reward'] < 0 else s['real_status']}")  # fmt: skip
    again = [b for a, b in itertools.pairwise(steps) if a["action"] == b["action"]
             and not a["news"] and a["real_key"] == b["real_key"]]  # fmt: skip
    if again:
        out.append(f"{REPEATED}: {_skill(again[0]['action'])}")
    if len(steps) >= h["max_steps"]:
        out.append(OUT_OF_STEPS)
    return out


def health_cause(record: dict) -> str:
    """The belief-health cause of an episode's failure (the first of
    :func:`health_flags`; ``success``; ``no belief health recorded``)."""
    if record["success"]:
        return "success"
    if "health" not in record["report"]:
        return "no belief health recorded"
    flags = health_flags(record)
    return flags[0] if flags else f"other: {cause(record)}"


def _by_cause(failed: list[dict], why: Callable[[dict], str]) -> list[str]:
    """Count lines, most common first: ``   n  cause (solver k, ...)``."""
    causes = collections.Counter(why(r) for r in failed)
    by = collections.Counter((why(r), r["solver"]) for r in failed)
    lines = []
    for c, n in causes.most_common():
        who = {s: k for (c2, s), k in by.items() if c2 == c}
        lines.append(f"  {n:4d}  {c} ({', '.join(f'{s} {k}' for s, k in sorted(who.items()))})")
    return lines


def health_report(records: list[dict]) -> list[str]:
    """The belief-health lines of one domain's records (module docstring)."""
    rs = [r for r in records if "health" in r["report"]]
    if not rs:
        return ["  belief health: not recorded (records written before it was)"]
    hs = [r["report"]["health"] for r in rs]
    held = sum(h["initial"]["models"] > 0 for h in hs)
    lost = sum(h["lost_at"] is not None for h in hs)
    failed = [r for r in rs if not r["success"]]
    lines = [
        f"  belief health: the true target hypothesis was in the initial belief in "
        f"{held} of {len(rs)} episodes, lost after a step in {lost}",
        f"  failures by belief-health cause ({len(failed)} of {len(rs)} episodes)",
    ]
    lines += _by_cause(failed, health_cause)
    shown = collections.Counter(f.split(":")[0] for r in failed for f in health_flags(r))
    if shown:
        lines.append("  shown by failed episodes (not exclusive): "
                     + ", ".join(f"{c} {n}" for c, n in shown.most_common()))  # fmt: skip
    for r in failed:
        h = r["report"]["health"]
        step = next((s for s in h["steps"] if s["step"] == h["lost_at"]), None)
        if step is not None:
            lines.append(f"    dropped: seed {r['seed']} {r['solver']} step {step['step']} "
                         f"{step['action']}: real {_key(step['real_key'])}; "
                         f"twin {_key(step['twin_key'])}")  # fmt: skip
    return lines


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
    rules = collections.Counter(r.get("report", {}).get("twin_keys", "not recorded")
                                for r in records)  # fmt: skip
    lines.append("real key rule (twin_keys): " + ", ".join(f"{k} {n}" for k, n in rules.items()))
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
        lines.append(f"\n{d}: failures by cause ({len(failed)} of {len(rs)} episodes)")
        lines += _by_cause(failed, cause)
        lines.append("  " + idle_steps(rs))
        total = {k: sum(r["report"]["time"].get(k, 0.0) for r in rs) for k in TIME_PARTS}
        t = sum(total.values()) or 1.0
        parts = ", ".join(f"{k} {v / t:.0%}" for k, v in total.items())
        hits = [r["report"]["outcome_cache"]["hit_rate"] for r in rs
                if "outcome_cache" in r["report"]]  # fmt: skip
        hit = f"{statistics.median(hits):.0%}" if hits else "n/a"
        lines.append(f"  time: {parts} (of {t:.0f} s); outcome cache hit rate median {hit}")
        lines += health_report(rs)
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
    p.add_argument("--twin-keys", choices=twin_keys.TWIN_KEYS, help="the real key rule")
    p.add_argument(
        "--sims",
        type=int,
        help="simulations per decision (default: the tasks' budget, MANIPULATION_SIMS)",
    )
    args = p.parse_args(argv)
    if args.twin_keys:  # the bench builds the tasks (in this process or in workers)
        os.environ[twin_keys.TWIN_KEYS_ENV] = args.twin_keys
    domains = tuple(x for x in args.domains.split(",") if x)
    for d in domains:
        if d not in MANIPULATION_DOMAINS:
            p.error(f"--domains: {d!r} is not one of {', '.join(MANIPULATION_DOMAINS)}")
    solvers = tuple(x for x in args.solvers.split(",") if x)
    seeds: range = args.seeds
    if not args.report_only:
        overrides = {} if args.sims is None else {"sims": args.sims}
        spec = BenchSpec(domains, solvers, len(seeds), overrides, first_seed=seeds.start)
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
