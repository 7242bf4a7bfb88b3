"""Share of affordance-sampled grasps that the full robot grasps successfully.

Usage::

    python tools/eval_grasps.py --seeds 1000:1010 --grasps 3
    python tools/eval_grasps.py --seeds 1000:1010 --grasps 3 --json

Per cabinet seed (all parts closed, the robot at home): perception from the standard
head poses, fusion, then for every real movable part that a fused hypothesis matches
(closed-state rectangle IoU >= 0.5), ``--grasps`` grasp poses drawn by
:func:`perception.affordance.sample_grasps` (biased by the pull-affordance map) and as
many drawn uniformly over the part's pixels (the peer: no affordance). Each grasp is
executed by the full robot (:mod:`strug_manip.control`: mink IK, OMPL, MuJoCo physics)
with the opening skill of the part's *true* joint (``OpenDrawer`` or ``OpenDoor``), so
that only the grasp decides: a grasp succeeds when the skill reports success (the part
followed the gripper). Failures are counted by the skill's reason. Runs are
interleaved (biased, uniform, biased, ...) so machine load hits both alike.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter

import numpy as np

from perception.affordance import sample_grasps
from perception.fusion import fuse, rect_iou
from perception.inputs import check_view
from perception.parts import Perceiver
from strug_manip.world.perception_data import CabinetViewer, ViewRanges
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from eval_perception import hypothesis_joint, parse_seeds, true_parts


def run_cabinet(seed: int, n: int, perceiver: Perceiver, rng: np.random.Generator) -> list[dict]:
    """Every grasp run on one cabinet: ``{"sampler", "kind", "success", "reason"}``."""
    from strug_manip.control.controllers import OpenDoor, OpenDrawer, true_joint

    world = ManipulationWorld(SceneConfig(cabinet_seed=seed))
    out = []
    try:
        viewer = CabinetViewer(world, ViewRanges(open_prob=0.0))
        views = viewer.look_around(rng, 4)
        fused = fuse(
            [
                perceiver.perceive(check_view(v.rgb, v.depth, v.T_world_camera, v.fovy))
                for v in views
            ]
        )
        T_wc = world.scene.T_world_cabinet
        truth = true_parts(seed, T_wc, fused)
        spec = world.scene.cabinet_spec
        start = world.snapshot()
        for tp, part in zip(truth, spec.parts, strict=True):
            if tp["type"] == "fixed":
                continue
            scores = [
                rect_iou(tp["rect"], hypothesis_joint(h, fused.front)[1]) for h in fused.parts
            ]
            if not scores or max(scores) < 0.5:
                continue
            k = int(np.argmax(scores))
            biased, _ = sample_grasps(fused, k, n, rng, tp["type"])
            uniform, _ = sample_grasps(fused, k, n, rng, tp["type"], sharpness=0.0)
            joint = true_joint(world, part.link)
            for i in range(n):
                for name, g in (("affordance", biased[i]), ("uniform", uniform[i])):
                    world.restore(start)
                    skill = (
                        OpenDrawer(g, joint, travel=0.08)
                        if tp["type"] == "prismatic"
                        else OpenDoor(g, joint, angle=0.3)
                    )
                    o = skill.run(world, seed=i)
                    out.append(dict(sampler=name, kind=part.kind, success=bool(o.success),
                                    reason=o.reason))  # fmt: skip
    finally:
        world.close()
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", required=True)
    ap.add_argument("--grasps", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    seeds = parse_seeds(args.seeds)
    perceiver = Perceiver()
    rng = np.random.default_rng(0)
    t0 = time.perf_counter()
    runs = []
    for s in seeds:
        runs += run_cabinet(s, args.grasps, perceiver, rng)
        if not args.json:
            print(f"cabinet {s}: {len(runs)} grasps so far", flush=True)
    summary = {}
    for name in ("affordance", "uniform"):
        mine = [r for r in runs if r["sampler"] == name]
        summary[name] = {
            "n": len(mine),
            "ok": sum(r["success"] for r in mine),
            "reasons": dict(Counter(r["reason"] for r in mine if not r["success"])),
        }
    summary["seconds"] = round(time.perf_counter() - t0, 1)
    if args.json:
        print(json.dumps(summary))
    else:
        for name in ("affordance", "uniform"):
            d = summary[name]
            print(f"{name}: {d['ok']}/{d['n']} grasps succeeded; failures {d['reasons']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
