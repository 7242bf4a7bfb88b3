"""What the closed fronts of handle-less cabinets are, in the training distribution.

Usage::

    python tools/unseen_front_prior.py --seeds 100000:100800

In a cabinet without handles a closed drawer front, a closed door and a fixed panel
look the same (:func:`eval_perception.type_unseen`), so perception can only type such
a front by the prior: how often a front like that is a drawer or a door in the scenes
perception is made for. This tool counts it on the training split (generator seeds
>= 100,000; the evaluation seeds are never used) the way ``tools/eval_perception.py``
counts parts: per head-camera view (``--views`` standard head poses, the cabinet in one
random state as in training), every part of a handle-less cabinet with at least 40
visible pixels at the network's resolution, panels and the movable fronts whose type
no view shows. It prints the counts per kind (flaps: top- and bottom-hinged doors) and
the drawer and door shares among the movable ones: the source of
:data:`perception.joint_cues.UNSEEN_SPLIT`.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from eval_perception import MIN_VIEW_PIXELS, type_unseen

from strug_manip.experiments.seeds import training_seeds
from strug_manip.objects.generator import generate_cabinet
from strug_manip.world.perception_data import render_episode


def count_cabinet(seed: int, views: int) -> Counter:
    """Per-view counts of panels and type-unseen movable fronts of cabinet ``seed``
    (empty when the cabinet has handles)."""
    spec = generate_cabinet(seed)
    c: Counter = Counter()
    if any(p.handle != "none" for p in spec.parts):
        return c
    for lv in render_episode(seed, views):
        pm = lv.part_map[::2, ::2]
        for k, part in enumerate(spec.parts):
            if (pm == k + 1).sum() < MIN_VIEW_PIXELS:
                continue
            if part.kind == "panel":
                c["panel"] += 1
            elif part.kind in ("drawer", "door") and type_unseen(part, lv.q[k]):
                c["flap" if part.hinge in ("top", "bottom") else part.kind] += 1
    return c


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=training_seeds, required=True, help="START:STOP training seeds")
    ap.add_argument("--views", type=int, default=4)
    args = ap.parse_args(argv)
    from tqdm import tqdm

    total: Counter = Counter()
    for s in tqdm(args.seeds, unit="cabinet"):
        total += count_cabinet(s, args.views)
    drawer, door = total["drawer"], total["door"] + total["flap"]
    print(f"seeds {args.seeds.start}:{args.seeds.stop}, {args.views} views, handle-less cabinets")
    print("views of: " + ", ".join(f"{k} {total[k]}" for k in ("panel", "drawer", "door", "flap")))
    if drawer + door:
        print(
            f"closed movable fronts: drawer {drawer / (drawer + door):.3f}, "
            f"door or flap {door / (drawer + door):.3f} (of {drawer + door})"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
