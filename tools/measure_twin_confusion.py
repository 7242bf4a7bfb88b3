"""Measure how the planning twin's status confuses with the full robot's, on tuning seeds,
and write the data the real belief update weighs real keys by
(:mod:`strug_manip.domains.manipulation.twin_keys`).

Usage::

    python tools/measure_twin_confusion.py --seeds 9100:9112
    python tools/measure_twin_confusion.py --seeds 9100:9112 --out /tmp/conf.json \\
        --runs runs/twin_confusion_9100_9112
    python tools/measure_twin_confusion.py --seeds 9100:9112 --runs runs/eval_x \\
        --solver strug --report-only        # tally another run's pairs, write nothing

The pairs come from real episodes of the **oracle** (``strug bench``'s ``oracle`` row:
STRUG's planner whose only particle is the true cabinet, which takes over the real
cabinet's state after every real step, :mod:`strug_manip.domains.manipulation.oracle`).
Each episode's belief health (:mod:`strug_manip.domains.manipulation.health`) records,
per real step, the key the twin of the best particle holding the true hypothesis
predicted, against the real key; in the oracle's episodes that particle is the true
cabinet itself, standing as the real one stood when the step began, so each step is a
pair (twin of the true cabinet, full robot) from the same starting state. Every step
with a twin key counts (before-motion stops included: the likelihood is conditioned on
the twin's status, not on the real one having moved); a step whose twin key was never
computed (the episode ended before the update, and the search never simulated the
action) is counted apart.

Episodes run through the bench (:func:`~strug_manip.experiments.bench.run_bench`, one
at a time, a progress bar on stderr), their records appended to ``RUNS/results.jsonl``
as each finishes; a rerun with the same ``--runs`` keeps them and runs the rest. The data
(``--out``, default the package's ``twin_confusion.json``) is written at the end with its
provenance: the git commit, whether the tree was dirty, the seeds, domains, episodes and
pairs, the command, the date.

Only tuning seeds: episode seeds from :data:`HELD_OUT` up are kept for final reports,
and the tool refuses them.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import subprocess
import sys
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from strug_manip.domains import MANIPULATION_DOMAINS
from strug_manip.domains.manipulation import twin_keys
from strug_manip.domains.manipulation.model import MISMATCH
from strug_manip.experiments.bench import BenchSpec, load_results, run_bench
from strug_manip.experiments.seeds import seed_range

#: Episode seeds from here up are held out for final reports: never measured on.
HELD_OUT = 9200
#: The smoothing the shipped data states (:func:`twin_keys.smoothed`): pseudo-pairs per
#: row spread as the exact-match rule (about one episode's steps on one status), that
#: rule's weight of another status (:data:`.model.MISMATCH`, a log), and the least
#: probability of any pair.
PRIOR_STRENGTH = 5.0
PRIOR_MISMATCH = round(math.exp(MISMATCH), 12)
FLOOR = 0.01
#: The package's data file.
DEFAULT_OUT = Path(twin_keys.__file__).with_name(twin_keys.DATA_FILE)


def pairs_of(records: Iterable[dict]) -> tuple[list[tuple[str, str]], int]:
    """The (twin status, real status) pairs of the records' belief health, and how many
    steps had no twin key."""
    pairs, missing = [], 0
    for r in records:
        for s in r["report"].get("health", {}).get("steps", []):
            if s["twin_status"] is None:
                missing += 1
            else:
                pairs.append((s["twin_status"], s["real_status"]))
    return pairs, missing


def git(*args: str) -> str:
    """The output of ``git args`` in this repository ('' if git fails)."""
    root = Path(__file__).resolve().parent.parent
    try:
        out = subprocess.run(["git", *args], cwd=root, capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        return ""
    return out.stdout.strip()


def confusion_of(records: list[dict], seeds: range, domains: tuple[str, ...], solver: str,
                 argv: list[str]) -> twin_keys.TwinConfusion:  # fmt: skip
    """The confusion counted from ``records``, with its provenance."""
    pairs, missing = pairs_of(records)
    counts = twin_keys.count_pairs(pairs)
    provenance = {
        "commit": git("rev-parse", "HEAD"),
        "dirty": bool(git("status", "--porcelain", "--untracked-files=no")),
        "seeds": f"{seeds.start}:{seeds.stop}",
        "domains": list(domains),
        "solver": solver,
        "source": "belief health of the oracle's real episodes: the twin of the true "
        "cabinet, standing as the real one stood at the step's start, against the full "
        "robot's real key",
        "episodes": len(records),
        "pairs": len(pairs),
        "steps_without_twin_key": missing,
        "command": "python tools/measure_twin_confusion.py " + " ".join(argv),
        "date": datetime.date.today().isoformat(),
    }
    return twin_keys.TwinConfusion(twin_keys.STATUSES, counts, PRIOR_STRENGTH,
                                   PRIOR_MISMATCH, FLOOR, provenance)  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=seed_range, required=True, help="episode seeds START:STOP")
    p.add_argument("--domains", default="opendrawer,opendoor")
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help="the data file to write")
    p.add_argument("--runs", type=Path, help="episode records (default runs/twin_confusion_A_B)")
    p.add_argument("--solver", default="oracle", help="whose episodes (only oracle writes data)")
    p.add_argument("--report-only", action="store_true", help="run no episode, write nothing")
    args = p.parse_args(argv)
    seeds: range = args.seeds
    if seeds.stop > HELD_OUT:
        p.error(f"--seeds: episode seeds from {HELD_OUT} up are held out; measure below it")
    domains = tuple(x for x in args.domains.split(",") if x)
    for d in domains:
        if d not in MANIPULATION_DOMAINS:
            p.error(f"--domains: {d!r} is not one of {', '.join(MANIPULATION_DOMAINS)}")
    runs = args.runs or Path(f"runs/twin_confusion_{seeds.start}_{seeds.stop}")
    if not args.report_only:
        # The oracle's belief is one particle: the key rule cannot change its episodes,
        # and the exact match needs no data (the data may not exist yet).
        os.environ[twin_keys.TWIN_KEYS_ENV] = "match"
        spec = BenchSpec(domains, (args.solver,), len(seeds), first_seed=seeds.start)
        run_bench(spec, runs, workers=1, resume=True)
    records = [r for r in load_results(runs) if r["domain"] in domains
               and r["solver"] == args.solver and r["seed"] in seeds]  # fmt: skip
    if not records:
        print(f"no episodes of {seeds} in {runs}", file=sys.stderr)
        return 1
    conf = confusion_of(records, seeds, domains, args.solver, argv)
    print(twin_keys.table(conf.counts, conf.p))
    prov = conf.provenance
    print(f"{prov['pairs']} pairs from {prov['episodes']} episodes "
          f"({prov['steps_without_twin_key']} steps without a twin key); agreement "
          f"{np.trace(conf.counts) / max(conf.counts.sum(), 1):.0%}")  # fmt: skip
    if args.report_only or args.solver != "oracle":
        return 0
    args.out.write_text(json.dumps(conf.as_dict(), indent=1) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
