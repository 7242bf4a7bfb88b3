"""Share of affordance-sampled grasps that the full robot grasps successfully.

Usage::

    python tools/eval_grasps.py --seeds 1000:1010 --grasps 2
    python tools/eval_grasps.py --seeds 1000:1010 --grasps 2 --json --out /tmp/grasps

Per cabinet seed (the generator's full cabinet, every part closed, the robot at home):
perception of the 4 standard head views (:func:`strug_manip.world.views.take_views`),
fusion, then for every real movable part *with a handle* (a flat front cannot be
grasped by a parallel gripper) that a fused hypothesis matches (closed-state rectangle
IoU >= 0.5), ``--grasps`` grasp poses drawn by :func:`perception.affordance.
sample_grasps` (biased by the pull-affordance map) and as many drawn uniformly over
the part's pixels (the peer: no affordance), alternately, so machine load hits both
alike.

Each grasp is executed on the full robot (:mod:`strug_manip.control`: base placement,
mink IK, OMPL, MuJoCo physics) from a fresh reset, with the opening skill under the
part's *true* joint (:class:`OpenDrawer` for a drawer, :class:`OpenDoor` for a door or
flap), so that only the grasp decides. As with the skills library's own handle grasps
(:func:`strug_manip.control.handle_grasps`), a grasp whose level approach no base pose
reaches (``ik_infeasible``, or its goal touches the cabinet:
:attr:`~strug_manip.control.Outcome.cannot_reach`) is tried pitched by
:data:`~strug_manip.control.grasps.PITCHES` about the horizontal axis of the front.
Outcomes:

* ``ok``: the skill ran to its end and the part moved at least :data:`MOVED_SHARE` of
  the commanded travel (the part followed the gripper: the grasp held);
* ``too_little``: it ran to its end but the part did not follow (the fingers slipped
  off without noticing, or pushed the whole cabinet);
* the skill's status otherwise (``grasp_lost``, ``ik_infeasible``, ``collision``,
  ``no_motion_plan``, ``timeout``);
* ``no_handle_there``: no handle within the skills' :data:`~strug_manip.control.skills.
  HANDLE_RADIUS` of the grasp point (the skill refuses before anything moves);
* ``other_part``: the nearest handle is another part's.

Results are appended per seed to ``OUT/results.jsonl`` as they finish; a rerun with the
same ``--out`` skips the seeds already there.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

from perception.affordance import SHARPNESS, sample_grasps
from perception.fusion import fuse, rect_iou
from perception.inputs import check_view
from perception.parts import Perceiver
from planners.errors import UnknownNameError
from strug_manip.control import ControlContext, OpenDoor, OpenDrawer, part_at
from strug_manip.control.grasps import PITCHES
from strug_manip.control.params import DEFAULT_PARAMS
from strug_manip.experiments.seeds import evaluation_seeds
from strug_manip.geometry import axis_angle
from strug_manip.objects.hypotheses import BelievedJoint
from strug_manip.world import ManipulationWorld, SceneConfig
from strug_manip.world.views import take_views

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_perception import hypothesis_joint, true_parts

#: Share of the commanded travel the part must follow for a grasp to count as held.
MOVED_SHARE = 0.5
#: The samplers compared: name -> ``sharpness`` of :func:`sample_grasps`.
SAMPLERS = {"affordance": SHARPNESS, "uniform": 0.0}


def pitched(g: np.ndarray, pitch: float) -> np.ndarray:
    """``g`` (4, 4) with its approach tilted down by ``pitch`` [rad] about the
    horizontal axis perpendicular to it (as :func:`handle_grasps` pitches)."""
    a = g[:3, 0]
    side = np.cross([0.0, 0.0, 1.0], a)
    out = g.copy()
    if np.linalg.norm(side) < 1e-6:
        return out
    out[:3, :3] = axis_angle(side / np.linalg.norm(side), pitch) @ g[:3, :3]
    return out


def run_grasp(world, g, part, joint, ctx, start) -> tuple[str, float]:
    """One sampled grasp (module docstring): ``(outcome, part motion [m or rad])``."""
    world.restore(start)
    try:
        link, joint_name, _ = part_at(world, g)
    except UnknownNameError:
        return "no_handle_there", 0.0
    if link != part.link:
        return "other_part", 0.0
    out = None
    for pitch in (0.0, *PITCHES):
        world.restore(start)
        gp = pitched(g, pitch)
        skill = OpenDrawer(gp, joint) if joint.type == "prismatic" else OpenDoor(gp, joint)
        out = skill.run(world, ctx=ctx)
        if not out.cannot_reach:
            break
    moved = abs(out.motion_of(joint_name))
    p = DEFAULT_PARAMS
    margin = p.limit_margin_m if joint.type == "prismatic" else p.limit_margin_rad
    want = min(skill.default_amount(p), joint.limit - margin)
    if not out.ok:
        return str(out.status), moved
    return ("ok" if moved >= MOVED_SHARE * want else "too_little"), moved


def run_cabinet(seed: int, n: int, perceiver: Perceiver, ctx: ControlContext) -> dict:
    """Every grasp of one cabinet: ``{"seed", "runs": [{"sampler", "kind", "outcome",
    "motion", "pull"}], "unmatched", "no_handle", "seconds"}``."""
    t0 = time.perf_counter()
    rng = np.random.default_rng([seed, 0x6A5B])
    world = ManipulationWorld(SceneConfig(cabinet_seed=seed))
    runs, unmatched, no_handle = [], 0, 0
    try:
        frames = take_views(world, 4)
        views = [check_view(f.rgb, f.depth, f.T_world_camera, f.fovy) for f in frames]
        fused = fuse([perceiver.perceive(v) for v in views])
        T = world.scene.T_world_cabinet
        truth = true_parts(seed, T, fused)
        start = world.snapshot()
        for tp, part in zip(truth, world.scene.cabinet_spec.parts, strict=True):
            if tp["type"] == "fixed":
                continue
            if part.handle == "none" or part.handle_pos is None:
                no_handle += 1
                continue
            scores = [
                rect_iou(tp["rect"], hypothesis_joint(h, fused.front)[1]) for h in fused.parts
            ]
            if not scores or max(scores) < 0.5:
                unmatched += 1
                continue
            k = int(np.argmax(scores))
            joint = BelievedJoint.of_part(part, 0.0, T)
            drawn = {
                name: sample_grasps(fused, k, n, rng, tp["type"], sharpness=s)
                for name, s in SAMPLERS.items()
            }
            for i in range(n):
                for name, (gs, pull) in drawn.items():
                    outcome, moved = run_grasp(world, gs[i], part, joint, ctx, start)
                    runs.append(
                        dict(sampler=name, kind=part.kind, outcome=outcome,
                             motion=round(moved, 4), pull=round(float(pull[i]), 3))
                    )  # fmt: skip
    finally:
        world.close()
    return dict(
        seed=seed, runs=runs, unmatched=unmatched, no_handle=no_handle,
        seconds=round(time.perf_counter() - t0, 1),
    )  # fmt: skip


def summary(records: list[dict]) -> dict:
    """Per sampler ``{"n", "ok", "outcomes"}``; ``parts_unmatched`` (movable handled
    parts no fused hypothesis matched), ``parts_without_handle``, ``seconds``."""
    runs = [r for rec in records for r in rec["runs"]]
    out: dict = {}
    for name in SAMPLERS:
        mine = [r for r in runs if r["sampler"] == name]
        out[name] = {
            "n": len(mine),
            "ok": sum(r["outcome"] == "ok" for r in mine),
            "outcomes": dict(Counter(r["outcome"] for r in mine).most_common()),
        }
    out["parts_unmatched"] = sum(r["unmatched"] for r in records)
    out["parts_without_handle"] = sum(r["no_handle"] for r in records)
    out["seconds"] = round(sum(r["seconds"] for r in records), 1)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--seeds",
        type=evaluation_seeds,
        required=True,
        help="START:STOP generator seeds (< 10,000)",
    )
    ap.add_argument("--grasps", type=int, default=2, help="grasps per part and sampler")
    ap.add_argument("--out", type=Path, default=None, help="folder of results.jsonl (resume)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    if args.grasps < 1:
        raise SystemExit(f"--grasps must be >= 1, got {args.grasps}")
    from tqdm import tqdm

    seeds = args.seeds
    records: list[dict] = []
    path = None
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        path = args.out / "results.jsonl"
        if path.exists():
            records = [json.loads(line) for line in path.read_text().splitlines() if line]
    done = {r["seed"] for r in records}
    perceiver, ctx = Perceiver(), ControlContext()
    for s in tqdm([s for s in seeds if s not in done], unit="cabinet", disable=args.json):
        rec = run_cabinet(s, args.grasps, perceiver, ctx)
        records.append(rec)
        if path is not None:
            with path.open("a") as f:
                f.write(json.dumps(rec) + "\n")
    out = summary([r for r in records if r["seed"] in set(seeds)])
    if args.json:
        print(json.dumps(out))
        return 0
    for name in SAMPLERS:
        d = out[name]
        pct = 100 * d["ok"] / max(d["n"], 1)
        print(f"{name}: {d['ok']}/{d['n']} = {pct:.1f}% grasped; outcomes {d['outcomes']}")
    print(f"handled parts not matched by fusion: {out['parts_unmatched']}; "
          f"movable parts without a handle: {out['parts_without_handle']}")  # fmt: skip
    print(f"seconds: {out['seconds']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
