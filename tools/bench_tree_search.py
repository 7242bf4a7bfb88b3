"""Tree-search speed: our POMCP against pomdp_py's POMCP on the classic Tiger problem.

Usage::

    make bench                                   # installs pomdp-py==1.3.5.1, then runs this
    python tools/bench_tree_search.py [--depths 3,10] [--seconds 1.0] [--repeats 5]
                                      [--c 100] [--seed 0] [--json]

Both planners get the same problem, belief size, exploration constant, discount and
wall-time budget per decision, and build a fresh tree for every decision:

* **Problem.** Ours: ``make_domain("tigerclassic")``. pomdp_py: its shipped
  ``pomdp_py.problems.tiger`` models (pure Python, like ours): listen -1, tiger -100,
  treasure +10, listening accuracy 0.85, opening a door resets the tiger uniformly
  and gives a uniformly random observation. Neither problem has terminal states.
* **Belief.** 1000 unweighted particles drawn from the uniform prior (ours a
  ``ParticleBelief``, pomdp_py a ``Particles``).
* **Search.** ``c`` (default 100, the reward range of the -100/+10 doors) and
  discount 0.95 for both; rollouts pick actions uniformly at random (ours:
  ``UniformStream``; pomdp_py: the tiger ``PolicyModel``, ``random.sample``).
  pomdp_py's ``agent.tree`` is reset to ``None`` before every decision, so neither
  side reuses a tree.
* **Timing.** Each decision is timed with ``time.perf_counter`` around
  ``planner.act`` / ``planner.plan``; the rate is simulations / that wall time
  (simulations from ``info.sims`` and ``planner.last_num_sims``). Decisions of the
  two libraries alternate (and alternate which goes first), so machine load hits
  both alike; the table reports the median over ``--repeats`` decisions.

How the depth is matched
------------------------
Our ``depth = D`` is the maximum number of steps simulated from the root, counting
tree and rollout steps alike: ``simulate`` at depth ``d`` stops after its step when
``d + 1 >= D``, and a rollout started at depth ``d`` runs steps ``d .. D-1``. Every
simulation on Tiger (no terminal states) is therefore exactly ``D`` steps.

pomdp_py 1.3.5.1 (``po_uct.pyx``, ``POUCT._simulate`` / ``_rollout``) counts
differently. ``_simulate(depth)`` returns 0 when ``depth > max_depth``; a new node
reached at ``depth`` starts a rollout that runs ``while depth < max_depth``. So

* a simulation that ends in a rollout simulates exactly ``max_depth`` steps, but
* a simulation that stays in the tree takes tree steps at depths ``0 .. max_depth``,
  i.e. ``max_depth + 1`` steps (a node at depth ``max_depth`` still selects an action
  and samples one more step before ``depth > max_depth`` cuts it off).

No ``max_depth`` makes both kinds equal to ours. The script sets
``max_depth = D - 1``, so both planners share the same *maximum* total depth ``D``:
pomdp_py's tree-only simulations take ``D`` steps like ours, its rollout-ending ones
``D - 1``, one fewer than ours. Each pomdp_py simulation is thus at most as long as
ours, which can only favour pomdp_py. To show how much, the script also counts the
steps each planner really simulates (untimed runs with counting transition
functions, a fixed budget equal to that library's median number of simulations, so
the trees are at the same stage of growth) and reports steps per simulation and the
ratio of simulated steps per second. (Measured with the defaults: at depth 3 every
pomdp_py simulation stays in its small tree, 3.00 steps per simulation, as ours; at
depth 10 about 9.6 against our 10.0. ``max_depth = D`` would instead give pomdp_py
4.00 steps per simulation at depth 3, a third more work than ours.)

Remaining differences
---------------------
* pomdp_py's POMCP keeps particles in the tree: in 1.3.5.1 ``POMCP._simulate`` adds
  the sampled state to the belief of every *depth-1* node it passes through again
  (``if depth == 1 and root is not None``), not to every node; and creating the root
  deep-copies the agent's 1000-particle belief inside the timed search. Ours keeps no
  particles in the tree (the belief update lives in the runner) and does not reuse
  trees between decisions.
* pomdp_py creates all action children of a node when the node is created, stores
  the full history tuple along each path, and uses ``log(N + 1)`` in UCB1; ours
  allocates a node's action slots on its second visit and uses ``log N`` (both try
  every action once before applying UCB1).
* pomdp_py draws its randomness from Python's ``random`` (seeded here per decision);
  its action list comes from a ``set`` of strings, so its action order (and with it
  the exact search) depends on ``PYTHONHASHSEED``. Ours uses only the
  ``np.random.Generator`` passed to ``act``.
* With a wall-time budget neither side is deterministic: the figures are rates.
"""

from __future__ import annotations

import argparse
import json
import platform
import random
import statistics
import sys
import time
from dataclasses import asdict, dataclass, field
from importlib import metadata
from types import ModuleType
from typing import Any

import numpy as np

from planners.solvers.pomcp import POMCPConfig
from strug_manip.domains import make_domain
from strug_manip.domains.tiger import TigerClassic

N_PARTICLES = 1000
DISCOUNT = 0.95
LISTEN_NOISE = 0.15
POMDP_PY_VERSION = "1.3.5.1"
WARMUP_SECONDS = 0.2


@dataclass
class DepthResult:
    """Figures of one search depth.

    Attributes:
        depth: our ``depth`` (maximum steps simulated from the root).
        pomdp_py_max_depth: the ``max_depth`` given to pomdp_py (``depth - 1``).
        ours_sims_per_s: median simulations per second, ours.
        pomdp_py_sims_per_s: median simulations per second, pomdp_py.
        ratio: ``ours_sims_per_s / pomdp_py_sims_per_s``.
        ours_steps_per_sim: mean simulated steps per simulation, ours.
        pomdp_py_steps_per_sim: mean simulated steps per simulation, pomdp_py.
        steps_ratio: ratio of simulated steps per second, ours / pomdp_py.
        ours_samples: simulations per second of each decision, ours.
        pomdp_py_samples: simulations per second of each decision, pomdp_py.
        ours_sims: simulations of each decision, ours.
        pomdp_py_sims: simulations of each decision, pomdp_py.
    """

    depth: int
    pomdp_py_max_depth: int
    ours_sims_per_s: float = 0.0
    pomdp_py_sims_per_s: float = 0.0
    ratio: float = 0.0
    ours_steps_per_sim: float = 0.0
    pomdp_py_steps_per_sim: float = 0.0
    steps_ratio: float = 0.0
    ours_samples: list[float] = field(default_factory=list)
    pomdp_py_samples: list[float] = field(default_factory=list)
    ours_sims: list[int] = field(default_factory=list)
    pomdp_py_sims: list[int] = field(default_factory=list)


class _CountingTigerClassic(TigerClassic):
    """Our TigerClassic counting the steps the planner simulates (untimed runs only)."""

    def __init__(self) -> None:
        super().__init__()
        self.steps = 0

    def step(self, s: int, a: Any, rng: np.random.Generator) -> Any:
        self.steps += 1
        return super().step(s, a, rng)


# --------------------------------------------------------------------------- ours


def ours_decision(
    depth: int, c: float, seconds: float | None, sims: int | None, seed: list[int], counting: bool
) -> tuple[int, float, int]:
    """One decision of our POMCP from a fresh 1000-particle belief.

    Args:
        depth: maximum steps simulated from the root.
        c: UCB exploration constant.
        seconds: wall-time budget (None: use ``sims``).
        sims: simulation budget (None: use ``seconds``).
        seed: entropy for the decision's ``np.random.Generator``.
        counting: count simulated steps (slower; for the untimed calibration).

    Returns:
        ``(simulations, wall seconds, simulated steps or 0 when not counting)``.
    """
    pomdp = _CountingTigerClassic() if counting else make_domain("tigerclassic")
    rng = np.random.default_rng(seed)
    belief = pomdp.initial_belief(rng, N_PARTICLES)
    config = POMCPConfig(sims=sims, time_limit=seconds, depth=depth, c=c, discount=DISCOUNT)
    planner = config.planner(pomdp)
    start = time.perf_counter()
    _, info = planner.act(belief, rng)
    elapsed = time.perf_counter() - start
    steps = pomdp.steps if isinstance(pomdp, _CountingTigerClassic) else 0
    return info.sims, elapsed, steps


# ----------------------------------------------------------------------- pomdp_py


def load_pomdp_py() -> tuple[ModuleType, ModuleType]:
    """``(pomdp_py, pomdp_py.problems.tiger.tiger_problem)``; exit 2 when not installed."""
    try:
        import pomdp_py
        from pomdp_py.problems.tiger import tiger_problem
    except ImportError as exc:
        print(
            f"pomdp_py is not installed ({exc}). It is a benchmark-only dependency: "
            f"`make bench` installs it (pip install pomdp-py=={POMDP_PY_VERSION}) and runs "
            "this script.",
            file=sys.stderr,
        )
        sys.exit(2)
    return pomdp_py, tiger_problem


def _counting_transition_model(tiger_problem: ModuleType) -> Any:
    """pomdp_py's tiger TransitionModel counting its samples (one per simulated step)."""

    class CountingTransitionModel(tiger_problem.TransitionModel):
        def __init__(self) -> None:
            super().__init__()
            self.steps = 0

        def sample(self, state: Any, action: Any) -> Any:
            self.steps += 1
            return super().sample(state, action)

    return CountingTransitionModel()


def pomdp_py_decision(
    pomdp_py: ModuleType,
    tiger_problem: ModuleType,
    max_depth: int,
    c: float,
    seconds: float | None,
    sims: int | None,
    seed: str,
    counting: bool,
) -> tuple[int, float, int]:
    """One decision of pomdp_py's POMCP from a fresh 1000-particle belief.

    Args:
        pomdp_py: the pomdp_py module.
        tiger_problem: ``pomdp_py.problems.tiger.tiger_problem``.
        max_depth: pomdp_py's ``max_depth``.
        c: UCB exploration constant.
        seconds: wall-time budget (None: use ``sims``).
        sims: simulation budget (None: use ``seconds``).
        seed: seed for Python's ``random`` (pomdp_py's only source of randomness).
        counting: count simulated steps (slower; for the untimed calibration).

    Returns:
        ``(simulations, wall seconds, simulated steps or 0 when not counting)``.
    """
    random.seed(seed)
    prior = pomdp_py.Histogram(
        {
            tiger_problem.TigerState("tiger-left"): 0.5,
            tiger_problem.TigerState("tiger-right"): 0.5,
        }
    )
    particles = pomdp_py.Particles.from_histogram(prior, num_particles=N_PARTICLES)
    transition = (
        _counting_transition_model(tiger_problem) if counting else tiger_problem.TransitionModel()
    )
    policy = tiger_problem.PolicyModel()
    agent = pomdp_py.Agent(
        particles,
        policy,
        transition,
        tiger_problem.ObservationModel(LISTEN_NOISE),
        tiger_problem.RewardModel(),
    )
    planner = pomdp_py.POMCP(
        max_depth=max_depth,
        discount_factor=DISCOUNT,
        planning_time=seconds if seconds is not None else -1.0,
        num_sims=sims if sims is not None else -1,
        exploration_const=c,
        rollout_policy=policy,
    )
    agent.tree = None  # no tree reuse (a fresh agent has none; explicit for clarity)
    start = time.perf_counter()
    planner.plan(agent)
    elapsed = time.perf_counter() - start
    steps = getattr(transition, "steps", 0)
    return int(planner.last_num_sims), elapsed, steps


# ---------------------------------------------------------------------- benchmark


def run_depth(
    pomdp_py: ModuleType, tiger_problem: ModuleType, depth: int, args: argparse.Namespace
) -> DepthResult:
    """Timed decisions of both libraries at one depth, interleaved, then the step counts."""
    result = DepthResult(depth=depth, pomdp_py_max_depth=depth - 1)
    for rep in range(args.repeats):
        order = ["ours", "pomdp_py"] if rep % 2 == 0 else ["pomdp_py", "ours"]
        for lib in order:
            if lib == "ours":
                n, secs, _ = ours_decision(
                    depth, args.c, args.seconds, None, [args.seed, 1, depth, rep], counting=False
                )
                result.ours_sims.append(n)
                result.ours_samples.append(n / secs)
            else:
                n, secs, _ = pomdp_py_decision(
                    pomdp_py,
                    tiger_problem,
                    result.pomdp_py_max_depth,
                    args.c,
                    args.seconds,
                    None,
                    f"{args.seed}-{depth}-{rep}",
                    counting=False,
                )
                result.pomdp_py_sims.append(n)
                result.pomdp_py_samples.append(n / secs)
        _progress(f"depth {depth}: decision {rep + 1}/{args.repeats} done")
    result.ours_sims_per_s = statistics.median(result.ours_samples)
    result.pomdp_py_sims_per_s = statistics.median(result.pomdp_py_samples)
    result.ratio = result.ours_sims_per_s / result.pomdp_py_sims_per_s

    # Untimed calibration: steps per simulation at each library's median tree size.
    ours_n = round(statistics.median(result.ours_sims))
    n, _, steps = ours_decision(depth, args.c, None, ours_n, [args.seed, 2, depth], counting=True)
    result.ours_steps_per_sim = steps / n
    py_n = round(statistics.median(result.pomdp_py_sims))
    n, _, steps = pomdp_py_decision(
        pomdp_py,
        tiger_problem,
        result.pomdp_py_max_depth,
        args.c,
        None,
        py_n,
        f"{args.seed}-{depth}-calibration",
        counting=True,
    )
    result.pomdp_py_steps_per_sim = steps / n
    result.steps_ratio = (result.ours_sims_per_s * result.ours_steps_per_sim) / (
        result.pomdp_py_sims_per_s * result.pomdp_py_steps_per_sim
    )
    return result


def warm_up(
    pomdp_py: ModuleType, tiger_problem: ModuleType, depth: int, c: float, seed: int
) -> None:
    """A short untimed decision per library (imports, caches, allocator)."""
    ours_decision(depth, c, WARMUP_SECONDS, None, [seed, 0], counting=False)
    pomdp_py_decision(
        pomdp_py, tiger_problem, depth - 1, c, WARMUP_SECONDS, None, f"{seed}-warm-up", False
    )


def format_table(results: list[DepthResult], args: argparse.Namespace, version: str) -> str:
    """The human-readable report."""
    lines = [
        f"POMCP tree search on classic Tiger: ours vs pomdp_py {version} "
        f"(Python {platform.python_version()})",
        f"{N_PARTICLES} particles, c={args.c:g}, discount {DISCOUNT}, "
        f"{args.seconds:g} s per decision, median of {args.repeats} decisions, seed {args.seed}",
        "",
        f"{'depth':>5}  {'pomdp_py':>9}  {'ours':>10}  {'pomdp_py':>10}  {'ratio':>6}  "
        f"{'ours':>9}  {'pomdp_py':>9}  {'ratio':>7}",
        f"{'':>5}  {'max_depth':>9}  {'sims/s':>10}  {'sims/s':>10}  {'sims':>6}  "
        f"{'steps/sim':>9}  {'steps/sim':>9}  {'steps/s':>7}",
    ]
    for r in results:
        lines.append(
            f"{r.depth:>5}  {r.pomdp_py_max_depth:>9}  {r.ours_sims_per_s:>10,.0f}  "
            f"{r.pomdp_py_sims_per_s:>10,.0f}  {r.ratio:>5.2f}x  "
            f"{r.ours_steps_per_sim:>9.2f}  {r.pomdp_py_steps_per_sim:>9.2f}  "
            f"{r.steps_ratio:>6.2f}x"
        )
    lines += [
        "",
        "ratio sims = ours sims/s / pomdp_py sims/s (medians). steps/sim = mean steps simulated",
        "per simulation (untimed counting run); ratio steps/s = the ratio in simulated steps/s.",
        "pomdp_py max_depth = depth - 1: both search at most `depth` steps from the root",
        "(see this script's docstring).",
    ]
    return "\n".join(lines)


def _progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _depths(text: str) -> list[int]:
    try:
        depths = [int(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected integers like 3,10, got {text!r}") from None
    if not depths or any(d < 1 for d in depths):
        raise argparse.ArgumentTypeError(f"depths must be integers >= 1, got {text!r}")
    return depths


def _positive_float(text: str) -> float:
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return value


def _non_negative_float(text: str) -> float:
    value = float(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text!r}")
    return value


def _non_negative_int(text: str) -> int:
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text!r}")
    return value


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {text!r}")
    return value


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line."""
    parser = argparse.ArgumentParser(
        description="Compare POMCP simulations/second: ours vs pomdp_py on classic Tiger.",
    )
    parser.add_argument(
        "--depths",
        type=_depths,
        default=[3, 10],
        help="comma-separated search depths (max steps from the root); default 3,10",
    )
    parser.add_argument(
        "--seconds", type=_positive_float, default=1.0, help="wall time per decision [s]"
    )
    parser.add_argument(
        "--repeats", type=_positive_int, default=5, help="decisions per (library, depth)"
    )
    parser.add_argument(
        "--c", type=_non_negative_float, default=100.0, help="UCB exploration constant"
    )
    parser.add_argument("--seed", type=_non_negative_int, default=0, help="base seed (>= 0)")
    parser.add_argument("--json", action="store_true", help="print the figures as one JSON object")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the table (or JSON)."""
    args = parse_args(argv)
    pomdp_py, tiger_problem = load_pomdp_py()
    version = metadata.version("pomdp-py")
    warm_up(pomdp_py, tiger_problem, args.depths[0], args.c, args.seed)
    results = [run_depth(pomdp_py, tiger_problem, d, args) for d in args.depths]
    if args.json:
        report = {
            "problem": "tigerclassic",
            "pomdp_py_version": version,
            "python": platform.python_version(),
            "particles": N_PARTICLES,
            "discount": DISCOUNT,
            "c": args.c,
            "seconds": args.seconds,
            "repeats": args.repeats,
            "seed": args.seed,
            "results": [asdict(r) for r in results],
        }
        print(json.dumps(report))
    else:
        print(format_table(results, args, version))
    return 0


if __name__ == "__main__":
    sys.exit(main())
