"""How the point-cloud likelihood separates right from wrong beliefs after a probe.

Usage::

    python tools/eval_likelihood.py --seeds 3000:3010
    python tools/eval_likelihood.py --seeds 3000:3010 --json

Per cabinet seed (all parts closed): perception from the standard head poses (the
trained network, or ``--oracle`` perfect maps), fusion, one belief particle. For every
real movable part that a particle part covers, the robot's probe moves the real part
(a drawer 12 cm out, a door 0.4 rad open) and the head camera sees the cabinet from the
first standard pose. Candidates: the true cabinet, and the particle with the probed
part believed a drawer, a door hinged on each of the four sides, or a fixed panel, each
predicting the probe by its own joint (12 cm, 0.4 rad, nothing). Printed: the quantile
Hausdorff distance H [m] of the right belief (the true kind and hinge) and of the best
wrong one, and how often the right belief ranks first among the particle's variants
(the true cabinet aside). These figures set ``perception.likelihood.SIGMA``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys

import numpy as np

from perception.fusion import FusedCabinet, fuse
from perception.inputs import check_view
from perception.likelihood import quantile_hausdorff
from perception.parts import Perceiver, extract
from strug_manip.domains.manipulation.belief import SIDE_AXES, BeliefConfig, sample_particles
from strug_manip.experiments.seeds import evaluation_seeds
from strug_manip.objects.assembly import FRONT, GAP, CabinetModel, PartModel, assemble
from strug_manip.world.perception_data import CabinetViewer, ViewRanges
from strug_manip.world.scene import SceneConfig, cabinet_pose
from strug_manip.world.sim import ManipulationWorld
from strug_manip.world.views import cabinet_cloud, look_poses, place_robot

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from eval_perception import oracle_output

#: The probe: a drawer pulled this far [m], a door opened this far [rad].
PROBE_DRAWER, PROBE_DOOR = 0.12, 0.4


def variants(model: CabinetModel, k: int) -> dict[str, CabinetModel]:
    """``model`` with part ``k`` believed each way: ``drawer``, ``door <side>``, ``panel``."""
    m = model.parts[k]
    y0, y1, z0, z1 = m.rect
    yc, zc = 0.5 * (y0 + y1), 0.5 * (z0 + z1)
    origins = {"left": [0, y0 + GAP, zc], "right": [0, y1 - GAP, zc],
               "bottom": [0, yc, z0 + GAP], "top": [-FRONT, yc, z1 - GAP]}  # fmt: skip
    axis_x = np.array([1.0, 0.0, 0.0])
    centre = np.array([0.0, yc, zc])
    kinds = {
        "drawer": PartModel("drawer", m.rect, axis_x, centre, None, 0.3),
        "panel": PartModel("panel", m.rect, np.zeros(3), np.zeros(3)),
    }
    for side, o in origins.items():
        kinds[f"door {side}"] = PartModel(
            "door", m.rect, SIDE_AXES[side], np.array(o, float), side, 1.5
        )
    return {
        name: dataclasses.replace(model, parts=(*model.parts[:k], part, *model.parts[k + 1 :]))
        for name, part in kinds.items()
    }


def _cloud(spec, q, pose) -> np.ndarray:
    w = ManipulationWorld.from_cabinet_spec(spec)
    try:
        w.reset(q)
        place_robot(w, pose)
        return cabinet_cloud(w, w.render())
    finally:
        w.close()


def probe_cabinet(seed: int, perceiver: Perceiver | None, rng: np.random.Generator) -> list[dict]:
    """Per probed part: ``{"seed", "part", "right", "H": {candidate: H [m]}}``."""
    world = ManipulationWorld(SceneConfig(cabinet_seed=seed))
    try:
        viewer = CabinetViewer(world, ViewRanges(open_prob=0.0))
        views = viewer.look_around(rng, 4)
        checked = [check_view(v.rgb, v.depth, v.T_world_camera, v.fovy) for v in views]
        vp = (
            [extract(c, oracle_output(v)) for c, v in zip(checked, views, strict=True)]
            if perceiver is None
            else [perceiver.perceive(c) for c in checked]
        )
        fused: FusedCabinet = fuse(vp)
        cfg = BeliefConfig(
            particles=1,
            existence_range=(1.0, 1.0),
            class_floor=0.0,
            split_base=0.0,
            split_merged=0.0,
        )
        (particle,) = sample_particles([fused], rng, cfg)
        parts = particle.model.parts
        order = sorted(range(len(parts)), key=lambda i: (-parts[i].rect[3], parts[i].rect[0]))
        T_wc = world.scene.T_world_cabinet
        pose = look_poses(world, 1)[0]
        out = []
        for part in world.scene.cabinet_spec.movable_parts:
            c = fused.front.to_front(T_wc[:3, :3] @ part.cell_center + T_wc[:3, 3])
            hit = [i for i, m in enumerate(parts)
                   if m.rect[0] < c[1] < m.rect[1] and m.rect[2] < c[2] < m.rect[3]]  # fmt: skip
            if not hit:
                continue
            probe = PROBE_DRAWER if part.joint_type == "prismatic" else PROBE_DOOR
            world.reset({part.joint: probe})
            place_robot(world, pose)
            observed = cabinet_cloud(world, world.render())
            names, clouds = ["true"], [observed]
            for name, model in variants(particle.model, hit[0]).items():
                spec, q = assemble(model, cabinet_pose(model.depth))
                probed = spec.parts[order.index(hit[0])]
                if probed.movable:
                    q[probed.joint] += (
                        PROBE_DRAWER if probed.joint_type == "prismatic" else PROBE_DOOR
                    )
                names.append(name)
                clouds.append(_cloud(spec, q, pose))
            H = quantile_hausdorff(observed, clouds)
            right = "drawer" if part.kind == "drawer" else f"door {part.hinge}"
            out.append(dict(seed=seed, part=part.joint, right=right,
                            H={n: float(h) for n, h in zip(names, H, strict=True)}))  # fmt: skip
    finally:
        world.close()
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=evaluation_seeds, required=True, help="START:STOP")
    ap.add_argument("--oracle", action="store_true")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    perceiver = None if args.oracle else Perceiver()
    rng = np.random.default_rng(0)
    rows = [r for s in args.seeds for r in probe_cabinet(s, perceiver, rng)]
    right = [r["H"][r["right"]] for r in rows]
    wrong = [min(v for k, v in r["H"].items() if k not in ("true", r["right"])) for r in rows]
    first = sum(h < w for h, w in zip(right, wrong, strict=True))
    # A probe the camera cannot see (the part out of view or hidden): every candidate
    # predicts the same cloud within 2 mm.
    blind = sum(max(r["H"].values()) - min(v for k, v in r["H"].items() if k != "true") < 0.002
                for r in rows)  # fmt: skip
    summary = {
        "probes": len(rows),
        "right_first": first,
        "unobservable": blind,
        "H_right_m": {"median": float(np.median(right)), "p90": float(np.percentile(right, 90))},
        "H_best_wrong_m": {
            "median": float(np.median(wrong)),
            "p10": float(np.percentile(wrong, 10)),
        },
    }
    if args.json:
        print(json.dumps(summary))
        return 0
    print(f"{len(rows)} probes: the right belief ranks first in {first} ({blind} unobservable)")
    r, w = summary["H_right_m"], summary["H_best_wrong_m"]
    print(f"H of the right belief [m]: median {r['median']:.4f}, p90 {r['p90']:.4f}")
    print(f"H of the best wrong belief [m]: median {w['median']:.4f}, p10 {w['p10']:.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
