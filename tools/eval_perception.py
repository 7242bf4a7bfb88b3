"""Evaluate perception per real part and per cabinet on held-out generated cabinets.

Usage::

    python tools/eval_perception.py --seeds 1000:1030 --views 4
    python tools/eval_perception.py --seeds 2000:2030 --views 4 --json
    python tools/eval_perception.py --seeds 1000:1030 --style furniture  # furniture look
    python tools/eval_perception.py --seeds 3000:3010 --oracle        # geometry alone
    python tools/eval_perception.py --seeds 3000:3010 --dropout 0.11  # NaN depth dropouts
    python tools/eval_perception.py --objects ~/partnet --views 4       # real objects
    python tools/eval_perception.py --objects ~/partnet --states 10     # 10 states each

Per cabinet seed: the cabinet in one random state (each movable part opened with
probability 0.5, as in training), seen from the robot's ``--views`` standard head poses
(:func:`strug_manip.world.views.look_poses`); perception of every view, fusion, and
``--particles`` belief particles (:mod:`strug_manip.domains.manipulation.belief`).
Every figure is counted per real part (the generator's parts), never per predicted
region:

* ``parts_found``: per view, movable parts with at least 40 visible pixels (network
  resolution) that an instance matches with mask IoU >= 0.5; ``joint_type``: of those,
  the instance's most probable type is right;
* after fusion, a true movable part is *matched* by the fused hypothesis whose
  closed-state rectangle overlaps its front's most (IoU >= 0.5, existence >= 0.5);
  ``axis_error_deg_median`` (drawer, door = side-hinged, flap = top/bottom-hinged;
  signed axes, so a door believed hinged on the wrong side counts 180 deg) and
  ``hinge_error_m_median`` (distance from the true hinge point to the believed hinge
  line) over matched parts of the right type; ``cabinets_complete``: every movable part
  matched with the right type;
* ``true_in_support``: per movable part, some particle has a part of its true type whose
  axis is within 10 deg and whose hinge line (doors) or origin (drawers) is within 5 cm;
* ``handle_style``: per matched movable part with a handle, the fused hypothesis saw
  a handle and read its style (bar or knob) right, and a bar's direction on the front
  (:func:`perception.fusion.handle_shape`);
* ``spurious_per_cabinet``: fused movable hypotheses (existence >= 0.5) that match no
  real movable part;
* ``carcass_depth_beyond_seen_m``: over cabinets whose views see the carcass's depth,
  the true depth less the seen one (median, 10-90 %) and the share within the belief's
  draw (``BeliefConfig.depth_beyond_seen``);
* ``joint_type_unseen``: the part of ``joint_type`` over fronts whose type no view can
  show (:func:`type_unseen`: closed, in a cabinet without handles); the text output
  also gives the share right where the type shows, and what a perfect perceiver would
  get in expectation (right everywhere else, and on the unseen fronts as often as the
  training prior's larger share, :data:`perception.joint_cues.UNSEEN_SPLIT`);
* ``seconds_per_view`` (input checks, network, instances) and ``seconds_fusion``: wall
  time, torch on 1 thread; rendering is not counted.

With ``--json``, standard output is one JSON object with exactly these keys; the failure
causes (per part after fusion; ``per view:`` the found parts whose type was wrong, by
what they are) go to standard error.

Cabinets seen in training have seeds >= 100,000; tune on a range you do not report.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

from perception.articulation_net import (
    CENTRE_SCALE,
    N_OUT,
    SL_CENTRE,
    SL_CLASS,
    SL_HANDLE,
    SL_HINGE,
    view_targets,
)
from perception.fusion import SIDES, FusedCabinet, fuse, rect_iou
from perception.inputs import check_view
from perception.joint_cues import UNSEEN_SPLIT
from perception.parts import Perceiver, extract
from strug_manip.domains.manipulation.belief import (
    SIDE_AXES,
    BeliefConfig,
    noisy_view,
    sample_particles,
)
from strug_manip.experiments.seeds import evaluation_seeds
from strug_manip.objects import generate_cabinet, load_articulated_object
from strug_manip.objects.assembly import FRONT, GAP
from strug_manip.objects.describe import describe_object
from strug_manip.objects.generator import STYLES, CabinetSpec
from strug_manip.objects.hypotheses import BelievedJoint, same_joint
from strug_manip.objects.loader import object_folders
from strug_manip.world.perception_data import LabelledView, render_episode
from strug_manip.world.scene import SceneConfig, cabinet_pose

TYPES = ("fixed", "prismatic", "revolute")


def oracle_output(v: LabelledView, stride: int = 2) -> np.ndarray:
    """A perfect network output (N_OUT, h, w) from a view's labels (the geometry alone)."""
    cls, centre, hinge, handle = view_targets(
        v.part_map, v.joint_type, v.axis_cam, v.T_camera_cabinet, v.handle_map, stride
    )
    out = np.zeros((N_OUT, *cls.shape), dtype=np.float32)
    out[SL_CLASS] = -10.0
    np.put_along_axis(out[SL_CLASS], cls[None], 10.0, axis=0)
    out[SL_CENTRE] = centre
    out[SL_HINGE] = np.where(hinge[None] == np.arange(4)[:, None, None], 10.0, -10.0)
    out[SL_HANDLE] = np.where(handle > 0.5, 10.0, -10.0)[None]
    assert CENTRE_SCALE > 0
    return out


def _line_distance(p: np.ndarray, origin: np.ndarray, axis: np.ndarray) -> float:
    r = p - origin
    a = axis / np.linalg.norm(axis)
    return float(np.linalg.norm(r - (r @ a) * a))


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    c = float(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)))
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def true_parts(
    spec: CabinetSpec, T_world_cab: np.ndarray, fused: FusedCabinet | None
) -> list[dict]:
    """The true parts in the world (and their front rectangles in the fused front frame,
    if any): the generator's, or a real object's description."""
    R, t = T_world_cab[:3, :3], T_world_cab[:3, 3]
    out = []
    for p in spec.parts:
        c = R @ p.cell_center + t
        half = np.array([0.0, 0.5 * p.cell_size[0], 0.5 * p.cell_size[1]])
        rect = None
        if fused is not None:
            corners = fused.front.to_front(
                np.stack([c + R @ (half * s) for s in ((1, 1, 1), (1, -1, -1))])
            )
            rect = np.array(
                [corners[:, 1].min(), corners[:, 1].max(), corners[:, 2].min(), corners[:, 2].max()]
            )
        out.append(
            dict(
                joint=p.joint,
                kind=p.kind,
                type=p.joint_type,
                hinge=p.hinge,
                rect=rect,
                axis=R @ p.axis,
                # A movable part's origin as every comparison takes it (a drawer's: its
                # closed front's centre).
                origin=BelievedJoint.of_part(p, 0.0, T_world_cab).origin
                if p.movable
                else R @ p.origin + t,
                handle=p.handle,
                handle_axis=None if p.handle_axis is None else R @ p.handle_axis,
            )
        )
    return out


#: A part at most this far from closed [m or rad] counts as closed.
CLOSED = 0.02
#: A part counts in a view with at least this many visible pixels (network resolution).
MIN_VIEW_PIXELS = 40


def _front_kind(part, q: float) -> str:
    """A part as a failure cause names it: ``closed drawer with a bar`` ..."""
    kind = "flap" if part.hinge in ("top", "bottom") else part.kind
    state = "open" if q > CLOSED else "closed"
    handle = {"none": "without a handle", "bar": "with a bar", "knob": "with a knob"}[part.handle]
    return f"{state} {kind} {handle}"


def type_unseen(part, q: float) -> bool:
    """Whether a view cannot show ``part``'s joint type: a closed front (``q`` <=
    :data:`CLOSED`) in a cabinet without handles. The generator draws each cell's kind
    independently of its size and gives drawer fronts, doors and panels the same board,
    inset and gap, so nothing in the pixels tells them apart; only a probe does."""
    return q <= CLOSED and part.handle == "none"


def hypothesis_joint(h, front) -> tuple[str, np.ndarray, np.ndarray, np.ndarray]:
    """The point estimate of a fused hypothesis: (type, rect, world axis, world origin)."""
    t = h.joint_type
    if t == "revolute":
        k = int(np.argmax(h.hinge_prob))
        side = SIDES[k]
        y0, y1, z0, z1 = h.door_rect[k]
        o = {
            "left": [0, y0 + GAP, 0.5 * (z0 + z1)],
            "right": [0, y1 - GAP, 0.5 * (z0 + z1)],
            "bottom": [0, 0.5 * (y0 + y1), z0 + GAP],
            "top": [-FRONT, 0.5 * (y0 + y1), z1 - GAP],
        }[side]
        return (
            t,
            h.door_rect[k],
            front.dir_to_world(SIDE_AXES[side]),
            front.to_world(np.array(o, float)),
        )
    y0, y1, z0, z1 = h.rect
    return (
        t,
        h.rect,
        front.dir_to_world([1.0, 0, 0]),
        front.to_world(np.array([0.0, 0.5 * (y0 + y1), 0.5 * (z0 + z1)])),
    )


def evaluate_cabinet(
    seed: int | str,
    args,
    perceiver: Perceiver | None,
    rng: np.random.Generator,
    folder: Path | None = None,
    view_seed: int = 0,
) -> dict:
    """Every figure of one cabinet (module docstring): the generated cabinet ``seed``,
    or the real object in ``folder`` (``seed``: its name; the views drawn with the
    object's index in the evaluation, ``view_seed``)."""
    if folder is None:
        lvs = render_episode(int(seed), args.views, config=SceneConfig(cabinet_style=args.style))
        spec = generate_cabinet(int(seed), style=args.style)
    else:
        lvs = render_episode(view_seed, args.views, config=SceneConfig(cabinet_folder=folder))
        spec = describe_object(load_articulated_object(folder, progress=False))
    by_joint = {p.joint: p for p in spec.parts}
    T_world_cab = lvs[0].T_world_camera @ lvs[0].T_camera_cabinet
    rec = Counter()
    seconds = []
    vparts = []
    causes = Counter()
    checked = []  # the views as perception saw them (dropouts included)
    for lv in lvs:
        depth = lv.depth.copy()
        if args.dropout > 0:
            depth[rng.random(depth.shape) < args.dropout] = np.nan
        t0 = time.perf_counter()
        v = check_view(lv.rgb, depth, lv.T_world_camera, lv.fovy)
        checked.append(v)
        vp = extract(v, oracle_output(lv), 2, t0) if perceiver is None else perceiver.perceive(v)
        seconds.append(time.perf_counter() - t0)
        vparts.append(vp)
        pm = lv.part_map[::2, ::2]
        for k, jt in enumerate(lv.joint_type):
            mask = pm == k + 1
            part = by_joint.get(lv.joint_names[k])  # helper links and wheels are no part
            if jt == 0 or part is None or mask.sum() < MIN_VIEW_PIXELS:
                continue
            rec["view_parts"] += 1
            best, iou = None, 0.0
            for inst in vp.instances:
                inter = np.logical_and(inst.mask, mask).sum()
                u = inst.mask.sum() + mask.sum() - inter
                if inter / u > iou:
                    best, iou = inst, inter / u
            if best is not None and iou >= 0.5:
                rec["view_found"] += 1
                right = int(np.argmax(best.class_prob)) == int(jt)
                rec["view_type_ok"] += right
                if type_unseen(part, lv.q[k]):
                    rec["view_unseen"] += 1
                    rec["view_unseen_ok"] += right
                if not right:
                    causes[f"per view: {_front_kind(part, lv.q[k])} typed "
                           f"{TYPES[int(np.argmax(best.class_prob))]}"] += 1  # fmt: skip
    t0 = time.perf_counter()
    try:
        fused = fuse(vparts)
    except Exception as e:  # a cabinet not found counts every part as missed
        truth = true_parts(spec, T_world_cab, None)
        n = sum(p["type"] != "fixed" for p in truth)
        return dict(
            rec=rec,
            seconds=seconds,
            fusion=time.perf_counter() - t0,
            axis=[],
            hinge=[],
            complete=False,
            support=(n, 0),
            spurious=0,
            causes=Counter({f"no fusion: {e}": n}),
            seed=seed,
            depth_error=None,
        )
    t_fusion = time.perf_counter() - t0
    runs = [fused]
    for _ in range(args.noisy_runs if perceiver is not None else 0):
        cfg = BeliefConfig()
        noisy = [noisy_view(v, rng, cfg.depth_noise, cfg.rgb_noise) for v in checked]
        runs.append(fuse([perceiver.perceive(v) for v in noisy]))
    particles = sample_particles(
        runs, rng, BeliefConfig(particles=args.particles, noisy_runs=args.noisy_runs)
    )
    truth = true_parts(spec, T_world_cab, fused)
    est = [hypothesis_joint(h, fused.front) for h in fused.parts]
    used = set()
    axis_err, hinge_err, complete = [], [], True
    for tp in truth:
        if tp["type"] == "fixed":
            continue
        scores = [
            rect_iou(tp["rect"], e[1]) if h.existence >= 0.5 else 0.0
            for h, e in zip(fused.parts, est, strict=True)
        ]
        k = int(np.argmax(scores)) if scores else -1
        if k < 0 or scores[k] < 0.5:
            complete = False
            raw = [rect_iou(tp["rect"], e[1]) for e in est]
            if raw and max(raw) >= 0.5:
                causes["not matched after fusion: existence < 0.5"] += 1
            elif raw and max(raw) >= 0.2:
                causes["not matched after fusion: rectangle IoU in [0.2, 0.5)"] += 1
            else:
                causes["not matched after fusion: no hypothesis there"] += 1
            continue
        used.add(k)
        _count_handle(tp, fused.parts[k], fused.front, rec, causes)
        t, _, axis, origin = est[k]
        if t != tp["type"]:
            complete = False
            causes[f"type {tp['type']} believed {t}"] += 1
            continue
        cat = (
            "drawer"
            if t == "prismatic"
            else ("door" if tp["hinge"] in ("left", "right") else "flap")
        )
        err = _angle(axis, tp["axis"])
        axis_err.append((cat, err))
        if t == "revolute":
            hinge_err.append(_line_distance(tp["origin"], origin, axis))
            if err > 90:
                causes["door believed hinged on the wrong side"] += 1
    spurious = 0
    for k, (h, e) in enumerate(zip(fused.parts, est, strict=True)):
        if k in used or h.existence < 0.5 or e[0] == "fixed":
            continue
        if all(rect_iou(tp["rect"], e[1]) < 0.5 or tp["type"] == "fixed" for tp in truth):
            spurious += 1
    support_n = support_ok = 0
    believed = [  # every particle's movable joints in the world, once
        BelievedJoint.of_part(part, 0.0, cabinet_pose(p.spec.depth))
        for p in particles
        for part in p.spec.parts
        if part.movable
    ]
    for tp in truth:
        if tp["type"] == "fixed":
            continue
        support_n += 1
        true = BelievedJoint(tp["type"], tp["axis"], tp["origin"])
        ok = any(same_joint(b, true) for b in believed)
        support_ok += ok
        if not ok:
            causes["true model not in the particles' support"] += 1
    return dict(
        rec=rec,
        seconds=seconds,
        fusion=t_fusion,
        axis=axis_err,
        hinge=hinge_err,
        complete=complete,
        support=(support_n, support_ok),
        spurious=spurious,
        causes=causes,
        seed=seed,
        depth_error=spec.depth - fused.front.depth if fused.front.depth_seen else None,
    )


def _count_handle(tp: dict, h, front, rec: Counter, causes: Counter) -> None:
    """Count whether matched hypothesis ``h`` read true part ``tp``'s handle right."""
    if tp["handle"] == "none":
        return
    rec["handle_n"] += 1
    if h.handle is None:
        causes["handle: not seen"] += 1
        return
    along = None
    if tp["handle"] == "bar":
        d = front.T_world_front[:3, :3].T @ tp["handle_axis"]
        along = "z" if abs(d[2]) > abs(d[1]) else "y"
    if h.handle_style != tp["handle"]:
        causes[f"handle: {tp['handle']} read as {h.handle_style}"] += 1
    elif along is not None and h.handle_along not in (None, along):
        causes["handle: bar read along the wrong direction"] += 1
    else:
        rec["handle_ok"] += 1


def summarise(results: list[dict]) -> tuple[dict, dict[str, int]]:
    """The JSON object of the issue's acceptance, and the failure causes (per part)."""
    rec = sum((r["rec"] for r in results), Counter())
    axis = {
        c: [e for r in results for cc, e in r["axis"] if cc == c]
        for c in ("drawer", "door", "flap")
    }
    hinge = [e for r in results for e in r["hinge"]]
    med = lambda v: float(np.median(v)) if v else float("nan")  # noqa: E731
    depth = [r["depth_error"] for r in results if r.get("depth_error") is not None]
    lo, hi = BeliefConfig().depth_beyond_seen
    return {
        "parts_found": {"n": rec["view_parts"], "ok": rec["view_found"]},
        "joint_type": {"n": rec["view_found"], "ok": rec["view_type_ok"]},
        "joint_type_unseen": {"n": rec["view_unseen"], "ok": rec["view_unseen_ok"]},
        "axis_error_deg_median": {c: med(v) for c, v in axis.items()},
        "hinge_error_m_median": med(hinge),
        "cabinets_complete": {"n": len(results), "ok": sum(r["complete"] for r in results)},
        "true_in_support": {
            "n": sum(r["support"][0] for r in results),
            "ok": sum(r["support"][1] for r in results),
        },
        "handle_style": {"n": rec["handle_n"], "ok": rec["handle_ok"]},
        "spurious_per_cabinet": float(np.mean([r["spurious"] for r in results])),
        # How much deeper the carcass is than the views see it (where they see it):
        # BeliefConfig.depth_beyond_seen's provenance, and the share it covers.
        "carcass_depth_beyond_seen_m": {
            "n": len(depth),
            "median": med(depth),
            "p10_p90": [float(v) for v in np.percentile(depth, [10, 90])] if depth else [],
            "within_belief_range": float(np.mean([lo <= e <= hi for e in depth]))
            if depth
            else float("nan"),
        },
        "seconds_per_view": float(np.mean([s for r in results for s in r["seconds"]])),
        "seconds_fusion": float(np.mean([r["fusion"] for r in results])),
    }, dict(sum((r["causes"] for r in results), Counter()).most_common())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    which = ap.add_mutually_exclusive_group(required=True)
    which.add_argument(
        "--seeds", type=evaluation_seeds, help="START:STOP generator seeds (< 10,000)"
    )
    which.add_argument(
        "--objects",
        type=Path,
        help="a PartNet-Mobility object folder or a folder of them (truth: the object's "
        "own description, from its URDF, semantics and geometry)",
    )
    ap.add_argument(
        "--style",
        choices=STYLES,
        default="plain",
        help="the generated cabinets' style (plain: the tasks' cabinets; furniture: the look "
        "of real furniture)",
    )
    ap.add_argument(
        "--states",
        type=int,
        default=1,
        help="with --objects: random states per object (parts opened, robot placed); each "
        "counts as a cabinet",
    )
    ap.add_argument("--views", type=int, default=4)
    ap.add_argument("--particles", type=int, default=50)
    ap.add_argument("--noisy-runs", type=int, default=2)
    ap.add_argument("--dropout", type=float, default=0.0, help="share of depth pixels set to NaN")
    ap.add_argument("--oracle", action="store_true", help="perfect per-pixel maps (geometry alone)")
    ap.add_argument("--weights", type=Path, default=None)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    from tqdm import tqdm

    if args.states < 1:
        raise SystemExit(f"--states must be >= 1, got {args.states}")
    if not 0.0 <= args.dropout < 1.0:
        raise SystemExit(f"--dropout must be in [0, 1), got {args.dropout}")
    perceiver = None if args.oracle else Perceiver(args.weights)
    rng = np.random.default_rng(0)
    if args.objects is not None:
        folders = object_folders(args.objects)
        what = f"objects {args.objects} ({len(folders)} x {args.states} states)"
        runs = [(i, k, f) for k in range(args.states) for i, f in enumerate(folders)]
        results = [
            # State k of object i: view seed i + 1000 k (k = 0: the single state of before).
            evaluate_cabinet(folder.name, args, perceiver, rng, folder, i + 1000 * k)
            for i, k, folder in tqdm(runs, unit="object state", disable=args.json)
        ]
    else:
        seeds = args.seeds
        what = f"seeds {seeds.start}:{seeds.stop} ({args.style})"
        results = [
            evaluate_cabinet(s, args, perceiver, rng)
            for s in tqdm(seeds, unit="cabinet", disable=args.json)
        ]
    out, causes = summarise(results)
    if args.json:  # stdout: the issue's keys and joint_type_unseen; the causes go to stderr
        print(json.dumps(out))
        print(f"failure causes (per part): {json.dumps(causes)}", file=sys.stderr)
        return 0
    pct = lambda d: f"{d['ok']}/{d['n']} = {100 * d['ok'] / max(d['n'], 1):.1f}%"  # noqa: E731
    print(f"{what}, {args.views} views per cabinet" + (" (oracle maps)" if args.oracle else ""))
    print(f"parts found (per view, IoU >= 0.5): {pct(out['parts_found'])}")
    print(f"joint type right (found parts):    {pct(out['joint_type'])}")
    jt, un = out["joint_type"], out["joint_type_unseen"]
    seen = {"n": jt["n"] - un["n"], "ok": jt["ok"] - un["ok"]}
    ceiling = {"n": jt["n"], "ok": round(seen["n"] + max(UNSEEN_SPLIT) * un["n"])}
    print(f"  where the view shows the type:   {pct(seen)}")
    print(f"  closed fronts without handles:   {pct(un)} (the type is not in the pixels)")
    print(f"  expected of a perfect perceiver: {pct(ceiling)} (the prior's guess on those fronts)")
    a = out["axis_error_deg_median"]
    print(
        f"axis error median [deg]: drawer {a['drawer']:.2f}, door {a['door']:.2f}, "
        f"flap {a['flap']:.2f}"
    )
    print(f"hinge error median [m]:  {out['hinge_error_m_median']:.4f}")
    print(f"cabinets complete after fusion: {pct(out['cabinets_complete'])}")
    print(f"true model in the belief's support (per part): {pct(out['true_in_support'])}")
    print(f"handle style right (matched parts with a handle): {pct(out['handle_style'])}")
    print(f"spurious movable hypotheses per cabinet: {out['spurious_per_cabinet']:.2f}")
    dep = out["carcass_depth_beyond_seen_m"]
    if dep["n"]:
        print(
            f"carcass depth beyond the seen [m] ({dep['n']} seen): median {dep['median']:+.3f}, "
            f"10-90 % {dep['p10_p90'][0]:+.3f}..{dep['p10_p90'][1]:+.3f}; within the "
            f"belief's draw: {100 * dep['within_belief_range']:.0f} %"
        )
    total = args.views * out["seconds_per_view"] + out["seconds_fusion"]
    print(
        f"seconds per view {out['seconds_per_view']:.4f}, fusion {out['seconds_fusion']:.4f}, "
        f"{args.views} views + fusion {total:.3f}"
    )
    print("failure causes (per part):")
    for k, v in causes.items():
        print(f"  {v:4d}  {k}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
