"""The ``strug`` command line: list, run, bench, demo.

Examples::

    strug list
    strug run --domain tiger --solver pomcpow --seed 3
    strug run --domain tigerclassic --solver pomcp --set depth=10 --set c=50 --json
    strug bench --domains tiger,lightdark1d --solvers random,pomcp,pomcpow --seeds 100 \\
        --out runs/table1 --workers 2
    strug demo
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any

from planners.errors import ConfigError, StrugError
from planners.solvers import SOLVER_SUMMARIES, SOLVERS
from planners.solvers.base import parse_value
from strug_manip.domains import DOMAIN_SUMMARIES, DOMAINS, make_domain
from strug_manip.experiments.bench import BenchSpec, run_bench, solver_config
from strug_manip.experiments.episode import DEFAULT_PARTICLES, StepRecord, run_episode
from strug_manip.experiments.table import to_markdown

#: The demo: a short Table I run of the toy domains.
DEMO_DOMAINS = ("tiger", "extendedtiger", "lightdark1d", "lightdark2d")
DEMO_SOLVERS = ("random", "pomcp", "pomcpow", "entropy", "active", "strug")
DEMO_SEEDS = 20
DEMO_SIMS = 1000


def _overrides(args: argparse.Namespace) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in args.set or []:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise ConfigError(f"--set expects NAME=VALUE, got {item!r}")
        out[name.strip()] = parse_value(value)
    if args.sims is not None:
        out["sims"] = args.sims
    if args.time is not None:
        out["time_limit"] = args.time
        if args.sims is None:
            out["sims"] = None  # a time budget alone
    return out


def _split(text: str) -> tuple[str, ...]:
    return tuple(x.strip() for x in text.split(",") if x.strip())


def _add_budget(p: argparse.ArgumentParser) -> None:
    p.add_argument("--sims", type=int, help="simulations per decision (default: solver's, 3000)")
    p.add_argument("--time", type=float, help="wall time per decision [s] (not reproducible)")
    p.add_argument(
        "--set",
        action="append",
        metavar="NAME=VALUE",
        help="override a solver config field, e.g. --set depth=10 --set c=50",
    )
    p.add_argument(
        "--particles",
        type=int,
        default=DEFAULT_PARTICLES,
        help=f"belief particles (default {DEFAULT_PARTICLES})",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="strug", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)

    sub.add_parser("list", help="list domains and solvers")

    run = sub.add_parser("run", help="run one episode and print every step")
    run.add_argument("--domain", required=True, help=f"one of {', '.join(DOMAINS)}")
    run.add_argument("--solver", required=True, help=f"one of {', '.join(SOLVERS)}")
    run.add_argument("--seed", type=int, default=0)
    run.add_argument("--json", action="store_true", help="one JSON object per line per step")
    run.add_argument(
        "--rerun",
        type=Path,
        metavar="FILE.rrd",
        help="log the episode (belief, search statistics) to a rerun recording",
    )
    _add_budget(run)

    bench = sub.add_parser("bench", help="run a Table I grid of episodes")
    bench.add_argument("--domains", required=True, help="comma-separated domain names")
    bench.add_argument("--solvers", required=True, help="comma-separated solver names")
    bench.add_argument("--seeds", type=int, required=True, help="seeds 0..N-1 per cell")
    bench.add_argument("--out", type=Path, required=True, help="output directory")
    bench.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    bench.add_argument("--resume", action="store_true", help="skip finished episodes in --out")
    bench.add_argument("--json", action="store_true", help="print the summary as JSON")
    bench.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    _add_budget(bench)

    scene = sub.add_parser("scene", help="picture Fetch in front of a generated cabinet")
    scene.add_argument("--seed", type=int, default=3, help="cabinet generator seed")
    scene.add_argument(
        "--kinds", default="drawer,door,shelf,panel", help="part kinds the generator may use"
    )
    scene.add_argument("--out", type=Path, default=Path("scene.png"))
    scene.add_argument("--camera", default="overview", help="overview or head_camera")
    scene.add_argument("--width", type=int, default=960)
    scene.add_argument("--height", type=int, default=720)

    demo = sub.add_parser("demo", help="a short Table I run of the toy domains")
    demo.add_argument("--out", type=Path, default=Path("runs/demo"))
    demo.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    return parser


def cmd_list() -> int:
    print("domains:")
    for name in DOMAINS:
        print(f"  {name:<14} {DOMAIN_SUMMARIES[name]}")
    print("solvers:")
    for name in SOLVERS:
        print(f"  {name:<14} {SOLVER_SUMMARIES[name]}")
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    pomdp = make_domain(args.domain)
    overrides = _overrides(args)
    BenchSpec((args.domain,), (args.solver,), 1, overrides, args.particles)  # validates
    config = solver_config(args.solver, overrides)

    def show(rec: StepRecord) -> None:
        if args.json:
            print(json.dumps(rec.to_json()), flush=True)
            return
        q = "  ".join(f"{a}:{v:+.2f}/{rec.visits[a]}" for a, v in rec.q.items())
        print(
            f"step {rec.step}: {rec.action} -> {rec.observation}  r={rec.reward:+.2f}  "
            f"sims={rec.sims} ({rec.plan_seconds:.3f} s)  belief: {rec.belief}"
        )
        if q:
            print(f"    Q/N at root: {q}")
        if rec.tru is not None or rec.entropy is not None:
            what = f"TRU={rec.tru:.4f}" if rec.tru is not None else f"H={rec.entropy:.3f} nats"
            phase = f" phase={rec.phase}" if rec.phase else ""
            bonus = "  ".join(f"{a}:{v:+.3f}" for a, v in rec.bonus.items())
            print(f"    root {what}{phase}; bonus per action: {bonus}")

    if not args.json:
        print(f"{args.domain} / {args.solver} / seed {args.seed}: {config}")
    recorder = None
    if args.rerun is not None:
        from strug_manip.experiments.rerun_log import RerunRecorder

        args.rerun.parent.mkdir(parents=True, exist_ok=True)
        recorder = RerunRecorder(args.rerun, pomdp)
    result = run_episode(
        pomdp, config, args.seed, n_particles=args.particles, on_step=show, recorder=recorder
    )
    if recorder is not None:
        recorder.close()
        print(f"wrote {args.rerun} (open with: rerun {args.rerun})", file=sys.stderr)
    if args.json:
        print(
            json.dumps(
                {
                    "return": result.discounted_return,
                    "steps": len(result.steps),
                    "seconds": result.seconds,
                }
            )
        )
    else:
        print(
            f"discounted return: {result.discounted_return:+.3f} "
            f"({len(result.steps)} steps, {result.seconds:.2f} s)"
        )
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    spec = BenchSpec(
        _split(args.domains), _split(args.solvers), args.seeds, _overrides(args), args.particles
    )
    summary = run_bench(
        spec, args.out, workers=args.workers, resume=args.resume, progress=not args.no_progress
    )
    if args.json:
        print(json.dumps(summary))
    else:
        print(to_markdown(summary))
        print(f"wrote {args.out}/results.jsonl, table.md, table.csv, table.png")
    return 0


def cmd_scene(args: argparse.Namespace) -> int:
    import cv2

    from strug_manip.world import ManipulationWorld, SceneConfig

    world = ManipulationWorld(SceneConfig(cabinet_seed=args.seed, cabinet_kinds=_split(args.kinds)))
    world.step(0.5)  # let everything settle
    rgb = world.render_rgb(args.camera, args.width, args.height)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(args.out), rgb[:, :, ::-1]):
        raise ConfigError(f"could not write an image to {args.out}")
    spec = world.scene.cabinet_spec
    parts = (
        ", ".join(
            f"{p.link} {p.kind}" + (f" ({p.hinge} hinge)" if p.hinge else "") for p in spec.parts
        )
        if spec
        else f"loaded from {world.config.cabinet_folder}"
    )
    print(f"cabinet seed {args.seed} ({spec.mass:.1f} kg): {parts}" if spec else parts)
    print(f"wrote {args.out}")
    world.close()
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    spec = BenchSpec(DEMO_DOMAINS, DEMO_SOLVERS, DEMO_SEEDS, {"sims": DEMO_SIMS})
    print(
        f"demo: {len(spec.tasks())} episodes ({', '.join(DEMO_SOLVERS)} on "
        f"{', '.join(DEMO_DOMAINS)}; {DEMO_SEEDS} seeds, {DEMO_SIMS} sims per step) -> {args.out}"
    )
    summary = run_bench(spec, args.out, workers=args.workers, resume=True)
    print(to_markdown(summary))
    print(
        f"wrote {args.out}/table.md, table.csv, table.png; "
        "the full table: strug bench --seeds 100 (see README)"
    )
    return 0


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        if args.command == "list":
            return cmd_list()
        if args.command == "run":
            return cmd_run(args)
        if args.command == "bench":
            return cmd_bench(args)
        if args.command == "scene":
            return cmd_scene(args)
        return cmd_demo(args)
    except StrugError as exc:
        print(f"strug: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(
            "strug: interrupted (finished episodes are saved; rerun with --resume)", file=sys.stderr
        )
        return 130
