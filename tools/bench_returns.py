"""Returns per second of thinking: our POMCP options against pomdp_py's POUCT on the classic Tiger.

Usage::

    make bench-returns                        # installs pomdp-py==1.3.5.1, then runs this
    python tools/bench_returns.py [--seeds 0:300] [--budgets 20ms,200ms,1000sims]
                                  [--configs NAME,...] [--out runs/bench_returns]
                                  [--resume] [--json] [--no-progress]

A user compares planners by the return they earn for the time they think, so this
benchmark plays whole episodes of the classic Tiger (``tigerclassic``: listen -1, tiger
-100, treasure +10, accuracy 0.85, discount 0.95, 10 steps; exact optimum 6.69 from
``TigerClassic.optimal_value()``) under three budgets per decision: 20 ms and 200 ms
of wall time, and 1000 simulations. Every configuration plays the same seeds.

Ours (:data:`OURS`): POMCP as ``strug bench --domains tigerclassic --solvers pomcp``
runs it (``run_episode``: a 1000-particle belief in the runner, depth 10 = the
domain's ``max_steps``, c = 100 = its largest |reward|), with the options of issue 13
switched on one at a time and together: ``exploration=normalized``, ``reuse_tree=true``,
``rollout=heuristic`` (the domain's :class:`ListenUntilSure`) and ``horizon=episode``
(search only the steps left in the 10-step episode).

pomdp_py's (:data:`PEERS`): ``pomdp_py.POUCT`` 1.3.5.1 on its shipped
``problems.tiger`` models, planning on the *exact* belief (a ``Histogram`` updated
with ``update_histogram_belief``) and keeping its tree between decisions
(``planner.update``), as its own Tiger example does; c = 100, discount 0.95 and
``max_depth = 9`` (pomdp_py's tree steps run at depths 0..max_depth, so 9 bounds both
planners at 10 steps from the root; ``tools/bench_tree_search.py`` explains the
off-by-one). ``pomdp_py+heuristic`` gives it the same listen-until-sure rollout, which
there sees the whole history since the last door (real steps, tree path and rollout),
at least what ours sees. The true world is always our ``TigerClassic`` drawn from the
episode seed's world generator, so both libraries face the same tiger at the start.

Fairness on a shared machine: episodes are interleaved (for every seed and budget,
every configuration plays once, in an order rotated per seed), so load changes hit all
alike; the 1-minute load average is stored with every episode and printed. Time is
spent inside each library's own ``act`` / ``plan`` call; belief updates are outside
it on both sides. Results are appended to ``OUT/results.jsonl`` as each episode ends
(``--resume`` continues a killed run without repeating an episode).

Output: per budget and configuration the mean discounted return ± its standard error,
the episodes, the simulations and seconds per decision, the difference to pomdp_py's
POUCT in combined standard errors (``(m - m_py) / sqrt(se^2 + se_py^2)``) and to the
optimum in standard errors (``(m - 6.69) / se``). ``best`` is our configuration with the
highest mean at 20 ms (or the first budget run), as ``--set NAME=VALUE`` overrides:
``strug bench --domains tigerclassic --solvers pomcp --time 0.02 --set ...`` plays it.
``--json`` prints exactly ``{"20ms": {config: {"mean", "stderr", "n"}}, "200ms": ...,
"1000sims": ..., "best": ["NAME=VALUE", ...]}``.

Remaining differences: pomdp_py draws from Python's ``random`` (seeded per episode),
and its action order comes from a ``set``, so its exact search depends on
``PYTHONHASHSEED``; a wall-time budget is never reproducible bit for bit.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from strug_manip.domains import make_domain
from strug_manip.domains.tiger import LISTEN, OPEN_LEFT, OPEN_RIGHT, ListenUntilSure
from strug_manip.experiments.bench import load_results
from strug_manip.experiments.episode import episode_generators, run_episode
from strug_manip.experiments.seeds import seed_range
from strug_manip.experiments.task import solver_config

POMDP_PY_VERSION = "1.3.5.1"
DOMAIN = "tigerclassic"
DEPTH = 10  # the domain's max_steps: our default depth
C = 100.0  # the domain's largest |reward|: our default c
DISCOUNT = 0.95

#: Budget name -> (wall time per decision [s] or None, simulations per decision or None).
BUDGETS: dict[str, tuple[float | None, int | None]] = {
    "20ms": (0.02, None),
    "200ms": (0.2, None),
    "1000sims": (None, 1000),
}

#: Our configurations: POMCP config overrides (the ``--set`` fields). ``pomcp`` is the
#: published algorithm as Table I runs it; the others add issue 13's options.
_ALL = {"exploration": "normalized", "reuse_tree": True, "rollout": "heuristic"}
OURS: dict[str, dict[str, Any]] = {
    "pomcp": {},
    "pomcp+normalized": {"exploration": "normalized"},
    "pomcp+reuse": {"reuse_tree": True},
    "pomcp+normalized+reuse": {"exploration": "normalized", "reuse_tree": True},
    "pomcp+heuristic": {"rollout": "heuristic"},
    "pomcp+normalized+reuse+heuristic": _ALL,
    "pomcp+normalized+reuse+heuristic+episode": {**_ALL, "horizon": "episode"},
}

#: pomdp_py configurations: the rollout policy of its POUCT.
PEERS: dict[str, str] = {"pomdp_py": "random", "pomdp_py+heuristic": "heuristic"}

#: The peer the differences are measured against.
REFERENCE = "pomdp_py"


@dataclass(frozen=True)
class Episode:
    """One finished episode (one line of ``results.jsonl``)."""

    budget: str
    config: str
    seed: int
    ret: float
    sims: float
    seconds: float
    load1: float

    def record(self) -> dict[str, Any]:
        return {
            "budget": self.budget,
            "config": self.config,
            "seed": self.seed,
            "return": self.ret,
            "sims": self.sims,
            "seconds": self.seconds,
            "load1": self.load1,
        }


# --------------------------------------------------------------------------- ours


def ours_episode(config: str, budget: str, seed: int) -> tuple[float, float, float]:
    """One episode of our POMCP: ``(discounted return, sims/decision, s/decision)``."""
    time_limit, sims = BUDGETS[budget]
    overrides = {**OURS[config], "sims": sims, "time_limit": time_limit}
    result = run_episode(make_domain(DOMAIN), solver_config("pomcp", overrides), seed)
    seconds = float(np.mean([s.plan_seconds for s in result.steps]))
    return result.discounted_return, result.mean_sims, seconds


# ----------------------------------------------------------------------- pomdp_py


def load_pomdp_py() -> tuple[ModuleType, ModuleType]:
    """``(pomdp_py, pomdp_py.problems.tiger.tiger_problem)``; exit 2 when not installed."""
    try:
        import pomdp_py
        from pomdp_py.problems.tiger import tiger_problem
    except ImportError as exc:
        print(
            f"pomdp_py is not installed ({exc}). It is a benchmark-only dependency: "
            f"`make bench-returns` installs it (pip install pomdp-py=={POMDP_PY_VERSION}) "
            "and runs this script.",
            file=sys.stderr,
        )
        sys.exit(2)
    return pomdp_py, tiger_problem


def pomdp_py_heuristic(pomdp_py: ModuleType) -> Any:
    """Our :class:`ListenUntilSure` as a pomdp_py rollout policy, reading its history."""
    margin = ListenUntilSure().margin

    class ListenUntilSurePolicy(pomdp_py.RolloutPolicy):
        def __init__(self, actions: list[Any]) -> None:
            self.by_name = {a.name: a for a in actions}

        def rollout(self, state: Any, history: Any = None) -> Any:
            lead = 0
            for a, o in reversed(history or ()):  # since the last door was opened
                if a.name != "listen":
                    break
                lead += 1 if o.name == "tiger-left" else -1
            if lead >= margin:
                return self.by_name["open-right"]
            if lead <= -margin:
                return self.by_name["open-left"]
            return self.by_name["listen"]

    return ListenUntilSurePolicy


def pomdp_py_episode(
    pomdp_py: ModuleType, tp: ModuleType, rollout: str, budget: str, seed: int
) -> tuple[float, float, float]:
    """One pomdp_py POUCT episode in our world: ``(return, sims/decision, s/decision)``."""
    time_limit, sims = BUDGETS[budget]
    world = make_domain(DOMAIN)
    world_rng = episode_generators(seed)[0]
    state = world.sample_initial_state(world_rng)
    random.seed(f"pomdp_py-{seed}")
    policy_model = tp.PolicyModel()
    prior = pomdp_py.Histogram(
        {tp.TigerState("tiger-left"): 0.5, tp.TigerState("tiger-right"): 0.5}
    )
    agent = pomdp_py.Agent(
        prior, policy_model, tp.TransitionModel(), tp.ObservationModel(0.15), tp.RewardModel()
    )
    rollout_policy = (
        pomdp_py_heuristic(pomdp_py)(policy_model.get_all_actions())
        if rollout == "heuristic"
        else policy_model
    )
    planner = pomdp_py.POUCT(
        max_depth=DEPTH - 1,
        discount_factor=DISCOUNT,
        planning_time=time_limit if time_limit is not None else -1.0,
        num_sims=sims if sims is not None else -1,
        exploration_const=C,
        rollout_policy=rollout_policy,
    )
    ours = {"listen": LISTEN, "open-left": OPEN_LEFT, "open-right": OPEN_RIGHT}
    total, disc, n_sims, seconds = 0.0, 1.0, [], []
    for _ in range(world.max_steps):
        start = time.perf_counter()
        action = planner.plan(agent)
        seconds.append(time.perf_counter() - start)
        n_sims.append(planner.last_num_sims)
        state, obs, reward, _ = world.step(state, ours[action.name], world_rng)
        total += disc * reward
        disc *= world.discount
        heard = tp.TigerObservation("tiger-left" if obs == 0 else "tiger-right")
        agent.update_history(action, heard)
        planner.update(agent, action, heard)  # keeps the subtree (agent.tree)
        agent.set_belief(
            pomdp_py.update_histogram_belief(
                agent.cur_belief, action, heard, agent.observation_model, agent.transition_model
            )
        )
    return total, float(np.mean(n_sims)), float(np.mean(seconds))


# ---------------------------------------------------------------------- benchmark


def summarize(records: list[dict[str, Any]]) -> dict[str, dict[str, dict[str, float]]]:
    """``{budget: {config: {"mean", "stderr", "n", "sims", "seconds"}}}``."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in records:
        groups.setdefault((r["budget"], r["config"]), []).append(r)
    out: dict[str, dict[str, dict[str, float]]] = {}
    for (budget, config), rows in groups.items():
        x = np.array([r["return"] for r in rows], dtype=float)
        se = float(x.std(ddof=1) / math.sqrt(len(x))) if len(x) > 1 else math.nan
        out.setdefault(budget, {})[config] = {
            "mean": float(x.mean()),
            "stderr": se,
            "n": len(x),
            "sims": float(np.mean([r["sims"] for r in rows])),
            "seconds": float(np.mean([r["seconds"] for r in rows])),
            "load1": float(np.mean([r["load1"] for r in rows])),
        }
    return out


def best_config(summary: dict[str, dict[str, dict[str, float]]], budgets: list[str]) -> str:
    """Our configuration with the highest mean at 20 ms (else at the first budget run)."""
    budget = "20ms" if "20ms" in summary else budgets[0]
    cells = {k: v for k, v in summary.get(budget, {}).items() if k in OURS}
    return max(cells, key=lambda k: cells[k]["mean"])


def set_flags(config: str) -> list[str]:
    """The ``--set NAME=VALUE`` overrides of our configuration ``config``."""
    text = {True: "true", False: "false"}
    return [f"{k}={text.get(v, v) if isinstance(v, bool) else v}" for k, v in OURS[config].items()]


def json_report(summary: dict[str, Any], budgets: list[str]) -> dict[str, Any]:
    """The ``--json`` object: per budget and configuration mean, stderr, n; and ``best``."""
    report: dict[str, Any] = {
        b: {c: {k: cell[k] for k in ("mean", "stderr", "n")} for c, cell in summary[b].items()}
        for b in budgets
        if b in summary
    }
    report["best"] = set_flags(best_config(summary, budgets))
    return report


def text_report(summary: dict[str, Any], budgets: list[str], header: list[str]) -> str:
    """The human-readable tables."""
    optimum = make_domain(DOMAIN).optimal_value()
    lines = [*header, f"exact optimum {optimum:.2f}", ""]
    for b in budgets:
        cells = summary.get(b, {})
        ref = cells.get(REFERENCE)
        lines += [
            f"budget {b}",
            f"  {'configuration':<42} {'mean ± s.e.':>15} {'n':>4} {'sims/dec':>9} "
            f"{'s/dec':>7} {'vs ' + REFERENCE + ' [s.e.]':>20} {'vs optimum [s.e.]':>18}",
        ]
        for name in [*PEERS, *OURS]:
            if name not in cells:
                continue
            c = cells[name]
            vs_ref = (
                (c["mean"] - ref["mean"]) / math.hypot(c["stderr"], ref["stderr"])
                if ref is not None and name != REFERENCE
                else math.nan
            )
            vs_opt = (c["mean"] - optimum) / c["stderr"]
            lines.append(
                f"  {name:<42} {c['mean']:>7.2f} ± {c['stderr']:<5.2f} {c['n']:>4} "
                f"{c['sims']:>9.0f} {c['seconds']:>7.4f} {vs_ref:>+20.1f} {vs_opt:>+18.1f}"
            )
        lines.append("")
    best = best_config(summary, budgets)
    flags = " ".join(f"--set {f}" for f in set_flags(best)) or "(no overrides)"
    lines += [
        f"best (highest mean at {'20ms' if '20ms' in summary else budgets[0]}): {best}",
        f"  reproduce: strug bench --domains {DOMAIN} --solvers pomcp --time 0.02 {flags} "
        "--seeds N --out DIR",
    ]
    return "\n".join(lines)


def _prepare(out: Path, settings: dict[str, Any], resume: bool) -> list[dict[str, Any]]:
    """The finished records in ``out`` (checking the settings), ready for appending."""
    out.mkdir(parents=True, exist_ok=True)
    records = load_results(out)
    if records and not resume:
        raise SystemExit(
            f"bench_returns: {out}/results.jsonl already holds {len(records)} episodes; "
            "pass --resume or choose another --out"
        )
    path = out / "run.json"
    if resume and path.exists() and json.loads(path.read_text()) != settings:
        raise SystemExit(f"bench_returns: --resume: {path} was written with other settings")
    path.write_text(json.dumps(settings, indent=1) + "\n")
    tmp = out / "results.tmp"
    tmp.write_text("".join(json.dumps(r) + "\n" for r in records))
    os.replace(tmp, out / "results.jsonl")
    return records


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Play every missing episode, interleaved; return the summary."""
    pomdp_py, tp = load_pomdp_py()
    settings = {
        "ours": {k: OURS[k] for k in args.configs if k in OURS},
        "peers": {k: PEERS[k] for k in args.configs if k in PEERS},
        "budgets": {b: list(BUDGETS[b]) for b in args.budgets},
        "pomdp_py": metadata.version("pomdp-py"),
    }
    records = _prepare(args.out, settings, args.resume)
    done = {(r["budget"], r["config"], r["seed"]) for r in records}
    play: dict[str, Callable[[str, int], tuple[float, float, float]]] = {}
    for name in args.configs:
        if name in OURS:
            play[name] = lambda b, s, name=name: ours_episode(name, b, s)
        else:
            play[name] = lambda b, s, name=name: pomdp_py_episode(pomdp_py, tp, PEERS[name], b, s)
    todo = []
    for i, seed in enumerate(args.seeds):
        k = i % len(args.configs)
        order = args.configs[k:] + args.configs[:k]  # who goes first rotates per seed
        todo += [(b, c, seed) for b in args.budgets for c in order if (b, c, seed) not in done]
    ours_episode(next(iter(OURS)), "1000sims", 10**6)  # warm-up, untimed
    pomdp_py_episode(pomdp_py, tp, "random", "1000sims", 10**6)
    bar = _progress(len(todo), not args.no_progress)
    with (args.out / "results.jsonl").open("a") as sink:
        for budget, config, seed in todo:
            ret, sims, seconds = play[config](budget, seed)
            ep = Episode(budget, config, seed, ret, sims, seconds, os.getloadavg()[0])
            sink.write(json.dumps(ep.record()) + "\n")
            sink.flush()
            os.fsync(sink.fileno())
            records.append(ep.record())
            bar.update(1)
    bar.close()
    wanted = set(args.seeds)
    return summarize([r for r in records if r["seed"] in wanted and r["config"] in play])


def _progress(total: int, enabled: bool) -> Any:
    from tqdm import tqdm

    return tqdm(total=total, unit="episode", file=sys.stderr, disable=not enabled, smoothing=0.05)


def _names(valid: list[str], what: str) -> Callable[[str], list[str]]:
    def parse(text: str) -> list[str]:
        names = [x.strip() for x in text.split(",") if x.strip()]
        bad = [x for x in names if x not in valid]
        if bad or not names:
            raise argparse.ArgumentTypeError(
                f"unknown {what} {', '.join(bad) or '(none)'}; expected some of: {', '.join(valid)}"
            )
        return names

    return parse


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line."""
    parser = argparse.ArgumentParser(
        description="Returns at equal budgets: our POMCP options vs pomdp_py POUCT, classic Tiger."
    )
    parser.add_argument("--seeds", type=seed_range, default=range(300), help="START:END")
    parser.add_argument(
        "--budgets",
        type=_names(list(BUDGETS), "budget"),
        default=list(BUDGETS),
        help=f"comma-separated, of {', '.join(BUDGETS)} (default: all)",
    )
    every = [*PEERS, *OURS]
    parser.add_argument(
        "--configs",
        type=_names(every, "configuration"),
        default=every,
        help=f"comma-separated, of {', '.join(every)} (default: all)",
    )
    parser.add_argument("--out", type=Path, default=Path("runs/bench_returns"))
    parser.add_argument("--resume", action="store_true", help="continue the run in --out")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    args = parser.parse_args(argv)
    if not any(c in OURS for c in args.configs):
        parser.error("--configs needs at least one of ours: " + ", ".join(OURS))
    return args


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the tables (or the JSON object)."""
    args = parse_args(argv)
    load_start = os.getloadavg()
    started = time.strftime("%Y-%m-%d %H:%M")
    summary = run(args)
    load_end = os.getloadavg()
    if args.json:
        print(json.dumps(json_report(summary, args.budgets)))
        return 0
    header = [
        f"classic Tiger ({DOMAIN}), depth {DEPTH}, c = {C:g}, discount {DISCOUNT}; "
        f"ours vs pomdp_py {metadata.version('pomdp-py')} POUCT; seeds "
        f"{args.seeds[0]}:{args.seeds[-1] + 1}",
        f"started {started}; load average (1/5/15 min) at start "
        f"{'/'.join(f'{x:.2f}' for x in load_start)}, at end "
        f"{'/'.join(f'{x:.2f}' for x in load_end)}; {os.cpu_count()} CPUs",
    ]
    print(text_report(summary, args.budgets, header))
    return 0


if __name__ == "__main__":
    sys.exit(main())
