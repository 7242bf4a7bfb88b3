"""Load real articulated objects and check they are simulable: load times (cold and
warm cache), 10 s standing still untouched, and the part description.

Usage::

    python tools/eval_objects.py --objects DIR [--json] [--seconds 10]

``DIR`` is a PartNet-Mobility object folder or a folder of them. Per object: the first
load with an empty decomposition cache (a fresh folder, so the figure is a first
load's whatever the user cache holds), a second load with it warm, the drift [m] and
tilt [rad] of the object's base and the largest part motion over ``--seconds`` of
simulation with nothing touching it (pass: under 2 mm, 0.01 rad, no MuJoCo warning),
and the described parts (kind, hinge, handle).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np

from strug_manip.objects import load_articulated_object
from strug_manip.objects.describe import describe_object
from strug_manip.objects.loader import object_folders

#: Standing still: the base may drift this much [m] and turn this much [rad].
MAX_DRIFT, MAX_TILT = 0.002, 0.01


def stand_still(obj, seconds: float) -> dict:
    """Drift [m], turn [rad], largest part motion and warnings over ``seconds``."""
    m = obj.mj_model
    data = mujoco.MjData(m)
    mujoco.mj_forward(m, data)
    root = m.body(obj.root).id
    p0, q0, parts0 = data.xpos[root].copy(), data.xquat[root].copy(), data.qpos[7:].copy()
    for _ in range(round(seconds / m.opt.timestep)):
        mujoco.mj_step(m, data)
    dot = min(1.0, abs(float(q0 @ data.xquat[root])))
    warnings = sum(int(data.warning[i].number) for i in range(len(data.warning)))
    return {
        "drift": float(np.linalg.norm(data.xpos[root] - p0)),
        "tilt": 2.0 * math.acos(dot),
        "part_motion": float(np.abs(data.qpos[7:] - parts0).max()) if len(parts0) else 0.0,
        "warnings": warnings,
    }


def _part_row(p) -> dict:
    return {
        "link": p.link,
        "kind": p.kind,
        "hinge": p.hinge,
        "handle": p.handle,
        "interior": p.interior_size is not None,
    }


def evaluate(folder: Path, seconds: float) -> dict:
    """Every figure of one object (module docstring)."""
    with tempfile.TemporaryDirectory() as cache:
        os.environ["STRUG_MANIP_CACHE"] = cache
        t0 = time.perf_counter()
        load_articulated_object(folder, progress=False)
        cold = time.perf_counter() - t0
        t0 = time.perf_counter()
        obj = load_articulated_object(folder, progress=False)
        warm = time.perf_counter() - t0
    spec = describe_object(obj)
    still = stand_still(obj, seconds)
    still["ok"] = bool(
        still["drift"] < MAX_DRIFT and still["tilt"] < MAX_TILT and still["warnings"] == 0
    )
    return {
        "object": folder.name,
        "load_cold_s": round(cold, 2),
        "load_warm_s": round(warm, 2),
        "scale": round(obj.scale, 3),
        "mass": round(obj.mass, 2),
        "size_xyz": [round(float(v), 3) for v in obj.bounds[1] - obj.bounds[0]],
        "stand_still": still,
        "parts": [_part_row(p) for p in spec.movable_parts],
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--objects", type=Path, required=True, help="object folder(s)")
    ap.add_argument("--seconds", type=float, default=10.0, help="standing time [s]")
    ap.add_argument("--json", action="store_true", help="one JSON object per object")
    args = ap.parse_args(argv)
    for folder in object_folders(args.objects):
        rec = evaluate(folder, args.seconds)
        if args.json:
            print(json.dumps(rec))
            continue
        s = rec["stand_still"]
        parts = ", ".join(
            f"{p['link']} {p['kind']}" + (f" ({p['hinge']})" if p["hinge"] else "")
            + f" {p['handle']}" for p in rec["parts"]
        )  # fmt: skip
        print(
            f"{rec['object']}: load {rec['load_cold_s']} s cold, {rec['load_warm_s']} s warm; "
            f"scale {rec['scale']}, {rec['mass']} kg, {rec['size_xyz']} m; "
            f"{args.seconds:g} s still: drift {s['drift'] * 1000:.2f} mm, tilt {s['tilt']:.4f} "
            f"rad, parts {s['part_motion']:.4f}, warnings {s['warnings']} -> "
            f"{'ok' if s['ok'] else 'FAIL'}; parts: {parts}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
