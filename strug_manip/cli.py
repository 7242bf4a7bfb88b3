"""The strug command line: list, run, bench, scene, demo.

Examples:

    strug list
    strug run --domain tiger --solver pomcpow --seed 3
    strug run --domain tigerclassic --solver pomcp --sims 3000 --set depth=3
    strug bench --domains tiger,lightdark1d --solvers random,pomcp,pomcpow --seeds 100 \\
        --out runs/table1 --workers 2
    strug bench ... --executor ray                 # the same sweep as Ray tasks
    strug run --domain my_module:MyPOMDP --solver pomcpow   # your own GenerativePOMDP
    strug run --domain opendoor --solver oracle --seed 9100  # STRUG knowing the cabinet
    strug scene --seed 3 --out scene.png
    strug demo

Errors on bad input are one line, "strug: error: ...", with exit status 2.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import textwrap
from collections.abc import Callable
from pathlib import Path
from typing import Any

from planners.errors import ConfigError, PlannersError, UnknownNameError
from strug_manip.cli_args import (
    Parser,
    nonnegative_int,
    output_dir,
    output_file,
    parse_overrides,
    positive_int,
    positive_seconds,
)
from strug_manip.domains import DOMAIN_SUMMARIES, DOMAINS, MANIPULATION_DOMAINS, make_domain
from strug_manip.experiments.bench import RESULTS, BenchSpec, load_results, run_bench
from strug_manip.experiments.episode import DEFAULT_PARTICLES, StepRecord, run_episode
from strug_manip.experiments.executors import EXECUTORS
from strug_manip.experiments.table import to_markdown
from strug_manip.experiments.task import SOLVER_NAMES, budget_for, domain_params, solver_config
from strug_manip.objects.loader import object_folders

#: The demo: a short Table I run of the toy domains.
DEMO_DOMAINS = ("tiger", "extendedtiger", "lightdark1d", "lightdark2d")
DEMO_SOLVERS = ("random", "pomcp", "pomcpow", "entropy", "active", "strug")
DEMO_SEEDS = 20
DEMO_SIMS = 1000
#: The full toy Table I, the demo's closing hint (runnable as printed).
FULL_TABLE_COMMAND = (
    "strug bench --domains tiger,extendedtiger,lightdark1d,lightdark2d "
    "--solvers random,pomcp,pomcpow,entropy,active,strug --seeds 100 --out runs/table1"
)

#: One-line descriptions of the solvers for ``strug list``.
SOLVER_SUMMARIES: dict[str, str] = {
    "random": "uniformly random actions (no search)",
    "pomcp": "POMCP (Silver & Veness 2010); continuous domains discretised",
    "pomcpow": "POMCPOW (Sunberg & Kochenderfer 2018): double progressive widening",
    "entropy": "Entropy Regularized: belief-tree search paying beta per nat of entropy reduced",
    "active": "Active Learning: reduce entropy below a threshold, then plan in the MAP model",
    "strug": "STRUG: belief-tree search paying beta per unit of task-relevant uncertainty reduced",
    "oracle": "STRUG given the true cabinet as its only particle (manipulation tasks; a bound)",
}


def _overrides(args: argparse.Namespace) -> dict[str, Any]:
    out = parse_overrides(args.set)
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
    p.add_argument(
        "--sims",
        type=positive_int,
        help="simulations per decision (default: the solver's, 3000); reproducible per seed",
    )
    p.add_argument(
        "--time",
        type=positive_seconds,
        help="wall time per decision [s], instead of --sims; with both, a decision stops at "
        "whichever comes first (not reproducible)",
    )
    p.add_argument(
        "--set",
        action="append",
        metavar="NAME=VALUE",
        help="override a solver config field, e.g. --set depth=10 --set c=50 (see README)",
    )
    p.add_argument(
        "--particles",
        type=positive_int,
        default=DEFAULT_PARTICLES,
        help=f"belief particles (default {DEFAULT_PARTICLES})",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="strug",
        description=__doc__.strip(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    domains = f"one of {', '.join(DOMAINS)}, or package.module:Class (your own GenerativePOMDP)"

    sub.add_parser("list", help="list domains and solvers")

    run = sub.add_parser("run", help="run one episode and print every step")
    run.add_argument("--domain", required=True, help=domains)
    run.add_argument("--solver", required=True, help=f"one of {', '.join(SOLVER_NAMES)}")
    run.add_argument("--seed", type=nonnegative_int, default=0, help="episode seed (default 0)")
    run.add_argument("--json", action="store_true", help="one JSON object per line per step")
    run.add_argument(
        "--object",
        type=Path,
        default=None,
        help="a PartNet-Mobility object folder to act on (manipulation tasks; default: a "
        "generated cabinet)",
    )
    run.add_argument(
        "--target", default=None, help="the target part's link (e.g. link_1), with --object"
    )
    run.add_argument(
        "--rerun",
        type=Path,
        metavar="FILE.rrd",
        help="log the episode (world, belief, search statistics) to a rerun recording",
    )
    _add_budget(run)

    bench = sub.add_parser("bench", help="run a Table I grid of episodes, resumable")
    bench.add_argument("--domains", required=True, help=f"comma-separated: {domains}")
    bench.add_argument(
        "--solvers", required=True, help=f"comma-separated: {', '.join(SOLVER_NAMES)}"
    )
    bench.add_argument("--seeds", type=positive_int, required=True, help="N seeds per cell")
    bench.add_argument(
        "--first-seed",
        type=int,
        default=0,
        help="seeds are FIRST..FIRST+N-1 (default 0): report on a range no tuning used",
    )
    bench.add_argument("--out", type=Path, required=True, help="output directory")
    bench.add_argument(
        "--objects",
        type=Path,
        default=None,
        help="a folder of PartNet-Mobility object folders: the manipulation tasks act on "
        "them (each episode's seed draws one and its target)",
    )
    bench.add_argument(
        "--workers",
        type=positive_int,
        default=os.cpu_count() or 1,
        help="episodes at once (default: the CPU count; 1 runs them in this process)",
    )
    bench.add_argument(
        "--executor",
        choices=EXECUTORS,
        default="local",
        help="local worker processes (default) or Ray tasks (pip install 'strug-manip[ray]')",
    )
    bench.add_argument(
        "--address",
        help="with --executor ray: the Ray cluster to join (default: start Ray locally)",
    )
    bench.add_argument("--resume", action="store_true", help="skip finished episodes in --out")
    bench.add_argument("--json", action="store_true", help="print the summary as JSON")
    bench.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    _add_budget(bench)

    scene = sub.add_parser("scene", help="picture Fetch in front of a cabinet")
    scene.add_argument("--seed", type=nonnegative_int, default=3, help="cabinet generator seed")
    scene.add_argument(
        "--object", type=Path, default=None, help="a PartNet-Mobility object folder instead"
    )
    scene.add_argument(
        "--kinds", default="drawer,door,shelf,panel", help="part kinds the generator may use"
    )
    scene.add_argument("--out", type=Path, default=Path("scene.png"), help="PNG or JPEG file")
    scene.add_argument("--camera", default="overview", help="overview (default) or head_camera")
    scene.add_argument("--width", type=positive_int, default=960, help="image width [px]")
    scene.add_argument("--height", type=positive_int, default=720, help="image height [px]")

    demo = sub.add_parser("demo", help="a short Table I run of the toy domains (resumes)")
    demo.add_argument(
        "--out", type=Path, default=Path("runs/demo"),
        help="runs/demo: the episode's runs/demo.rrd and runs/demo.png (--toy: a directory)",
    )  # fmt: skip
    demo.add_argument(
        "--toy", action="store_true", help="a short Table I of the toy domains instead"
    )
    demo.add_argument(
        "--workers", type=positive_int, default=os.cpu_count() or 1, help="episodes at once"
    )
    parser.epilog = "commands and their options:\n" + "\n".join(
        "  " + p.format_usage().removeprefix("usage: ").strip().replace("\n", "\n  ")
        for p in sub.choices.values()
    )
    return parser


def cmd_list(args: argparse.Namespace) -> int:
    print("domains:")
    for name in DOMAINS:
        print(f"  {name:<14} {DOMAIN_SUMMARIES[name]}")
    print("  package.module:Class  your own GenerativePOMDP subclass, built without arguments")
    print("solvers:")
    for name in SOLVER_NAMES:
        print(f"  {name:<14} {SOLVER_SUMMARIES[name]}")
    return 0


def describe_config(config: Any, pomdp: Any) -> str:
    """``config`` as ``Name(field=value, ...)`` with the domain's defaults filled in:
    ``depth`` (the domain's ``max_steps``), ``c`` (its ``max_abs_reward``, unused with
    ``exploration=normalized``) and ``discount`` (its own) instead of ``None``."""
    values = {f.name: getattr(config, f.name) for f in dataclasses.fields(config)}
    defaults = {
        "depth": int(pomdp.max_steps),
        "c": float(pomdp.max_abs_reward),
        "discount": float(pomdp.discount),
    }
    parts = []
    for name, value in values.items():
        if name in defaults and value is None:
            unused = name == "c" and values.get("exploration") == "normalized"
            value = "unused" if unused else f"{defaults[name]:g} (domain's)"
        parts.append(f"{name}={value}")
    return f"{type(config).__name__}({', '.join(parts)})"


def _show_step(rec: StepRecord, as_json: bool) -> None:
    if as_json:
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


def cmd_run(args: argparse.Namespace) -> int:
    if args.rerun is not None:
        output_file(args.rerun, "--rerun", (".rrd",))
    overrides = _overrides(args)
    BenchSpec((args.domain,), (args.solver,), 1, overrides, args.particles)  # validates
    pomdp = make_domain(
        args.domain, **_object_params(args), **domain_params(args.domain, args.solver)
    )
    config = solver_config(args.solver, budget_for(args.domain, overrides))
    if not args.json:
        print(f"{args.domain} / {args.solver} / seed {args.seed}: {describe_config(config, pomdp)}")
    recorder = None
    if args.rerun is not None:
        from strug_manip.experiments.rerun_log import RerunRecorder

        recorder = RerunRecorder(args.rerun, pomdp)
    try:
        result = run_episode(
            pomdp,
            config,
            args.seed,
            n_particles=args.particles,
            on_step=lambda rec: _show_step(rec, args.json),
            recorder=recorder,
        )
    finally:
        if recorder is not None:
            recorder.close()
    if recorder is not None:
        print(f"wrote {args.rerun} (open with: rerun {args.rerun})", file=sys.stderr)
    if args.json:
        summary = {"return": result.discounted_return, "steps": len(result.steps)}
        print(json.dumps({**summary, "seconds": result.seconds}))
    else:
        print(
            f"discounted return: {result.discounted_return:+.3f} "
            f"({len(result.steps)} steps, {result.seconds:.2f} s)"
        )
    return 0


def _object_params(args: argparse.Namespace) -> dict[str, Any]:
    """The domain parameters of ``--object`` and ``--target`` (manipulation tasks)."""
    if args.object is None:
        if args.target is not None:
            raise ConfigError("--target names a part of --object; add --object DIR")
        return {}
    if args.domain not in MANIPULATION_DOMAINS:
        raise ConfigError(
            f"--object is for the manipulation tasks ({', '.join(MANIPULATION_DOMAINS)}), "
            f"not {args.domain!r}"
        )
    return {"objects": (args.object,), "target_link": args.target}


def cmd_bench(args: argparse.Namespace) -> int:
    if args.address is not None and args.executor != "ray":
        raise ConfigError("--address is for --executor ray; add --executor ray")
    spec = BenchSpec(
        _split(args.domains),
        _split(args.solvers),
        args.seeds,
        _overrides(args),
        args.particles,
        args.first_seed,
        () if args.objects is None else tuple(str(p) for p in object_folders(args.objects)),
    )
    output_dir(args.out, "--out")
    summary = run_bench(
        spec,
        args.out,
        workers=args.workers,
        resume=args.resume,
        progress=not args.no_progress,
        executor=args.executor,
        address=args.address,
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

    output_file(args.out, "--out", (".png", ".jpg", ".jpeg"))
    if args.object is not None:
        world = ManipulationWorld(SceneConfig(cabinet_folder=object_folders(args.object)[0]))
    else:
        config = SceneConfig(cabinet_seed=args.seed, cabinet_kinds=_split(args.kinds))
        world = ManipulationWorld(config)
    try:
        try:
            world.camera_pose(args.camera)
        except UnknownNameError as exc:
            raise ConfigError(f"--camera: {exc}") from None
        world.step(0.5)  # let everything settle
        rgb = world.render_rgb(args.camera, args.width, args.height)
        if not cv2.imwrite(str(args.out), rgb[:, :, ::-1]):
            raise ConfigError(f"--out {args.out}: could not write the image")
        spec = world.scene.cabinet_spec
        parts = ", ".join(
            f"{p.link} {p.kind}" + (f" ({p.hinge} hinge)" if p.hinge else "") for p in spec.parts
        )
        what = f"cabinet seed {args.seed}" if args.object is None else f"object {spec.name}"
        size = f"{spec.depth:.2f} x {spec.width:.2f} x {spec.height:.2f} m"
        print(f"{what} ({size}, {spec.mass:.1f} kg): {parts}")
        print(f"wrote {args.out}")
    finally:
        world.close()
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    """The main job (one OpenDrawer episode with STRUG) or, with ``--toy``, a short
    Table I of the toy domains."""
    return _toy_demo(args) if args.toy else _manipulation_demo(args)


def _manipulation_demo(args: argparse.Namespace) -> int:
    from strug_manip.experiments.rerun_log import RerunRecorder
    from strug_manip.experiments.rerun_manip import episode_strip

    rrd, png = args.out.with_suffix(".rrd"), args.out.with_suffix(".png")
    output_file(rrd, "--out", (".rrd",))
    pomdp = make_domain("opendrawer")
    config = solver_config("strug", budget_for("opendrawer", {}))
    print(f"demo: opendrawer / strug / seed 0: {describe_config(config, pomdp)}")
    recorder = RerunRecorder(rrd, pomdp)
    truth: list = []  # the real state after every step

    def record(rec, belief, state) -> None:
        recorder(rec, belief, state)
        truth.append(state)

    try:
        result = run_episode(
            pomdp, config, 0, n_particles=DEFAULT_PARTICLES,
            on_step=lambda rec: _show_step(rec, False), recorder=record,
        )  # fmt: skip
    finally:
        recorder.close()
    real = pomdp.real
    labels = ["start", *(f"{r.step}: {r.action}" for r in result.steps)]
    frames = [real.frames[0], *real.frames[pomdp.views :]]
    short = [textwrap.shorten(x, 38) for x in labels]
    episode_strip([f.rgb for f in frames], png, short)
    # The same steps from the overview camera: the robot and the cabinet, as the
    # recording's 3D view shows them.
    overview = png.with_name(png.stem + "_overview.png")
    world = real.world
    shots = []
    for state in truth:
        world.restore(state.sim)
        shots.append(world.render_rgb("overview"))
    episode_strip(shots, overview, short[1:])
    print(f"cabinet seed {real.seed}, target {real.target}: {pomdp.report()}")
    pomdp.close()
    print(
        f"discounted return: {result.discounted_return:+.3f} ({len(result.steps)} steps, "
        f"{result.seconds:.1f} s); wrote {rrd} (open with: rerun {rrd}), {png} and "
        f"{overview}.\n"
        "The toy columns of Table I in a few minutes: strug demo --toy"
    )
    return 0


def _toy_demo(args: argparse.Namespace) -> int:
    spec = BenchSpec(DEMO_DOMAINS, DEMO_SOLVERS, DEMO_SEEDS, {"sims": DEMO_SIMS})
    print(
        f"demo: {len(spec.tasks())} episodes ({', '.join(DEMO_SOLVERS)} on "
        f"{', '.join(DEMO_DOMAINS)}; {DEMO_SEEDS} seeds, {DEMO_SIMS} sims per step) -> {args.out}"
    )
    output_dir(args.out, "--out")
    summary = run_bench(spec, args.out, workers=args.workers, resume=True)
    print(to_markdown(summary))
    print(
        f"wrote {args.out}/table.md, table.csv, table.png. {DEMO_SEEDS} seeds are a quick "
        "look: cells move by a point or two from seed set to seed set (a Tiger cell above "
        "the exact optimum 5.67 is such noise; see README). The full table (100 seeds, "
        f"3000 simulations per decision, about 20 minutes on 2 cores):\n  {FULL_TABLE_COMMAND}"
    )
    return 0


def _interrupted(args: argparse.Namespace) -> str:
    """What a Ctrl-C kept, per command."""
    if args.command == "run":
        kept = f"; {args.rerun} holds the steps logged so far" if args.rerun else ""
        return f"interrupted: the episode did not finish (nothing else is saved){kept}"
    if args.command in ("bench", "demo"):
        try:
            n = len(load_results(args.out))
        except (PlannersError, OSError):
            n = 0
        again = (
            "rerun the same command with --resume"
            if args.command == "bench"
            else "run strug demo again"
        )
        return (
            f"interrupted: {n} finished episodes are kept in {args.out / RESULTS}; "
            f"{again} to run only the rest"
        )
    if args.command == "scene":
        return "interrupted: no image was written"
    return "interrupted"


COMMANDS: dict[str, Callable[[argparse.Namespace], int]] = {
    "list": cmd_list,
    "run": cmd_run,
    "bench": cmd_bench,
    "scene": cmd_scene,
    "demo": cmd_demo,
}


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return COMMANDS[args.command](args)
    except PlannersError as exc:
        print(f"strug: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"strug: {_interrupted(args)}", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. strug run ... | head: the reader is gone, so stop quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
