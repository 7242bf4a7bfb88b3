"""Render labelled RGB-D views of generated cabinets: perception's training/test data.

Usage::

    python tools/render_perception_data.py --seeds 100000:100500 --out data/perception/train \
        --empty-prob 0.05
    python tools/render_perception_data.py --seeds 0:100 --out data/perception/test \
        --picture docs/perception_data.png

One ``cabinet_<seed>.npz`` shard per cabinet (see
:mod:`strug_manip.world.perception_data` for the arrays). Shards already in ``--out`` are
skipped, so a killed run resumes where it stopped. Training seeds start at
``TRAIN_SEED_START`` (100,000); seeds below 10,000 are the evaluation split.
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
    render_cabinet,
    save_views,
    shard_path,
)


def _render_one(seed: int, views: int, out: str, empty_prob: float) -> int:
    ranges = ViewRanges(empty_prob=empty_prob)
    save_views(shard_path(Path(out), seed), render_cabinet(seed, views, ranges))
    return seed


def _picture(out: Path, seed: int, path: Path) -> None:
    import cv2

    from strug_manip.world.perception_data import load_views

    data = load_views(shard_path(out, seed))
    rows = []
    palette = np.array(
        [[0, 0, 0], [90, 90, 90], [230, 159, 0], [86, 180, 233], [0, 158, 115], [240, 228, 66],
         [0, 114, 178], [213, 94, 0], [204, 121, 167], [150, 150, 250]], dtype=np.uint8,
    )  # fmt: skip
    for i in range(min(3, len(data["rgb"]))):
        depth = data["depth"][i]
        near, far = np.percentile(depth, 1), np.percentile(depth, 60)
        d8 = (255 * np.clip((depth - near) / max(far - near, 1e-6), 0, 1)).astype(np.uint8)
        parts = palette[(data["part_map"][i].astype(int) + 1) % len(palette)]
        rows.append(np.concatenate([data["rgb"][i], np.stack([d8] * 3, -1), parts], axis=1))
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), np.concatenate(rows, axis=0)[:, :, ::-1])
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
    ap.add_argument("--picture", type=Path, help="also write RGB | depth | parts of one shard")
    args = ap.parse_args(argv)
    from tqdm import tqdm

    seeds = args.seeds
    todo = [s for s in seeds if not shard_path(args.out, s).exists()]
    print(f"{len(seeds) - len(todo)} of {len(seeds)} cabinets already in {args.out}")
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers, mp_context=get_context("spawn")) as pool:
        futures = [
            pool.submit(_render_one, s, args.views, str(args.out), args.empty_prob) for s in todo
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
