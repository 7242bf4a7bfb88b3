"""Render labelled RGB-D views of generated cabinets: perception's training/test data.

Usage::

    python tools/render_perception_data.py --seeds 100000:100600 --out data/perception/train \
        --empty-prob 0.05 --furniture 0.5
    python tools/render_perception_data.py --seeds 0:100 --out data/perception/test \
        --picture docs/perception_data.png

One ``cabinet_<seed>.npz`` shard per cabinet (see
:mod:`strug_manip.world.perception_data` for the arrays). Shards already in ``--out`` are
skipped, so a killed run resumes where it stopped. ``--furniture P``: each cabinet is
drawn in the generator's furniture style with probability ``P``
(:func:`~strug_manip.world.perception_data.cabinet_style`, fixed by the seed).
Training seeds start at ``TRAIN_SEED_START`` (100,000); seeds below 10,000 are the
evaluation split.
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from strug_manip.experiments.seeds import seed_range
from strug_manip.world.perception_data import (
    DEFAULT_VIEWS,
    ViewRanges,
    cabinet_style,
    render_cabinet,
    save_views,
    shard_path,
)
from strug_manip.world.scene import SceneConfig


def _render_one(seed: int, views: int, out: str, empty_prob: float, furniture: float) -> int:
    ranges = ViewRanges(empty_prob=empty_prob)
    config = SceneConfig(cabinet_style=cabinet_style(seed, furniture))
    save_views(shard_path(Path(out), seed), render_cabinet(seed, views, ranges, config))
    return seed


#: Colours of the part map: not the cabinet, the carcass, then parts 1, 2, ... (cycled).
PALETTE = np.array(
    [[0, 0, 0], [90, 90, 90], [230, 159, 0], [86, 180, 233], [0, 158, 115], [240, 228, 66],
     [0, 114, 178], [213, 94, 0], [204, 121, 167], [150, 150, 250]], dtype=np.uint8,
)  # fmt: skip
JOINT_NAMES = ("fixed", "prismatic", "revolute")


def _picture(out: Path, seed: int, path: Path) -> None:
    """RGB | depth | part map of the first three views of one shard, with column titles,
    a depth colour bar [m] and a key of the part colours (semantic label, joint type)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    from strug_manip.world.perception_data import load_views

    data = load_views(shard_path(out, seed))
    n = min(3, len(data["rgb"]))
    fig, axes = plt.subplots(n, 3, figsize=(10.5, 2.75 * n + 1.0), squeeze=False)
    titles = ("RGB (head camera)", "depth [m]", "part map (colour key below)")
    for col, title in enumerate(titles):
        axes[0][col].set_title(title, fontsize=10)
    for i in range(n):
        depth = data["depth"][i]
        near, far = np.percentile(depth, 1), np.percentile(depth, 60)
        axes[i][0].imshow(data["rgb"][i])
        im = axes[i][1].imshow(depth, cmap="gray", vmin=near, vmax=far)
        fig.colorbar(im, ax=axes[i][1], fraction=0.035, pad=0.02)
        axes[i][2].imshow(PALETTE[(data["part_map"][i].astype(int) + 1) % len(PALETTE)])
        axes[i][0].set_ylabel(f"view {i}", fontsize=9)
        for ax in axes[i]:
            ax.set_xticks([])
            ax.set_yticks([])
    key = [Patch(color=PALETTE[0] / 255, label="not the cabinet"),
           Patch(color=PALETTE[1] / 255, label="carcass")]  # fmt: skip
    for k, (label, jtype) in enumerate(zip(data["semantic"], data["joint_type"][0], strict=True)):
        color = PALETTE[(k + 2) % len(PALETTE)] / 255
        key.append(Patch(color=color, label=f"part {k + 1}: {label}, {JOINT_NAMES[int(jtype)]}"))
    fig.legend(handles=key, loc="lower center", ncol=4, fontsize=8, frameon=False)
    fig.suptitle(f"evaluation cabinet {seed}: labelled views", fontsize=11)
    fig.tight_layout(rect=(0, 0.09, 1, 0.97))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=seed_range, required=True, help="START:STOP generator seeds")
    ap.add_argument("--views", type=int, default=DEFAULT_VIEWS, help="views per cabinet")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument(
        "--empty-prob", type=float, default=0.0, help="share of views without the cabinet"
    )
    ap.add_argument(
        "--furniture",
        type=float,
        default=0.0,
        help="share of cabinets in the generator's furniture style (drawn per seed)",
    )
    ap.add_argument("--picture", type=Path, help="also write RGB | depth | parts of one shard")
    args = ap.parse_args(argv)
    from tqdm import tqdm

    seeds = args.seeds
    todo = [s for s in seeds if not shard_path(args.out, s).exists()]
    print(f"{len(seeds) - len(todo)} of {len(seeds)} cabinets already in {args.out}")
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers, mp_context=get_context("spawn")) as pool:
        futures = [
            pool.submit(_render_one, s, args.views, str(args.out), args.empty_prob, args.furniture)
            for s in todo
        ]
        for f in tqdm(as_completed(futures), total=len(futures), unit="cabinet"):
            f.result()
    seconds = time.perf_counter() - t0
    if todo:
        print(
            f"rendered {len(todo)} cabinets x {args.views} views in {seconds:.1f} s "
            f"({seconds / (len(todo) * args.views):.3f} s per view, {args.workers} workers)"
        )
    if args.picture is not None:
        _picture(args.out, seeds[0], args.picture)
    return 0


if __name__ == "__main__":
    sys.exit(main())
