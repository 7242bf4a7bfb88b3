"""Train and evaluate the per-pixel articulation network on rendered cabinet views.

Usage::

    python tools/render_perception_data.py --seeds 100000:100400 --out data/perception/train
    python tools/render_perception_data.py --seeds 0:60 --out data/perception/test
    python tools/train_perception.py --train data/perception/train --test data/perception/test

Writes ``models/perception/articulation_net.pt`` (weights and the settings they were
trained with) and ``models/perception/metrics.json`` (the held-out evaluation printed at
the end). Train and test cabinets come from disjoint generator seeds.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import torch
from torch import nn

from perception.articulation_net import (
    CLASSES,
    ArticulationNet,
    extract_parts,
    prepare_input,
    view_targets,
)
from strug_manip.world.perception_data import load_views

OUT_DIR = Path(__file__).resolve().parents[1] / "models" / "perception"
#: Loss weights: class cross-entropy, axis (1 - cos), hinge offset (smooth L1 [m]).
W_AXIS, W_OFFSET = 1.0, 5.0
#: Cross-entropy class weights (background is most pixels).
CLASS_WEIGHTS = (0.3, 1.0, 1.0, 1.5, 1.5)


def load_split(folder: Path, stride: int) -> dict[str, np.ndarray]:
    """Inputs and per-pixel targets of every shard in ``folder`` (N views)."""
    xs, cls, axes, offs, points, meta = [], [], [], [], [], []
    shards = sorted(Path(folder).glob("cabinet_*.npz"))
    if not shards:
        raise SystemExit(f"no cabinet_*.npz shards in {folder}")
    for path in shards:
        d = load_views(path)
        for i in range(len(d["rgb"])):
            xs.append(prepare_input(d["rgb"][i], d["depth"][i], stride))
            c, a, o, p = view_targets(
                d["part_map"][i], d["joint_type"][i], d["axis_cam"][i], d["origin_cam"][i],
                d["depth"][i], float(d["fovy"][i]), stride,
            )  # fmt: skip
            cls.append(c)
            axes.append(a)
            offs.append(o)
            points.append(p)
            meta.append((path.name, i))
    return {
        "x": np.stack(xs).astype(np.float32),
        "cls": np.stack(cls),
        "axis": np.stack(axes),
        "offset": np.stack(offs),
        "points": np.stack(points),
        "meta": meta,
    }


def losses(out: torch.Tensor, cls: torch.Tensor, axis: torch.Tensor, offset: torch.Tensor):
    """(total, class CE, axis, offset) losses of a batch."""
    k = len(CLASSES)
    ce = nn.functional.cross_entropy(out[:, :k], cls, weight=torch.tensor(CLASS_WEIGHTS))
    movable = (cls >= 3).float()
    pred_axis = nn.functional.normalize(out[:, k : k + 3], dim=1)
    cos = (pred_axis * axis).sum(dim=1)
    # Hinge axes are learnt as lines (sign-free): which way a door turns is not visible in
    # one pixel; extract_parts recovers the sign from the geometry (doors open outward).
    cos = torch.where(cls == 4, cos.abs(), cos)
    l_axis = ((1.0 - cos) * movable).sum() / movable.sum().clamp(min=1.0)
    door = (cls == 4).float()
    l_off = nn.functional.smooth_l1_loss(out[:, k + 3 :], offset, reduction="none", beta=0.05)
    l_off = (l_off.sum(dim=1) * door).sum() / door.sum().clamp(min=1.0)
    return ce + W_AXIS * l_axis + W_OFFSET * l_off, ce, l_axis, l_off


def flip(x, cls, axis, offset):
    """Mirror a batch left-right (image columns reversed; camera x -> -x).

    Offsets and drawer axes are ordinary vectors: their x component changes sign. A hinge
    axis is a pseudovector (its sign says which way positive q turns), and a mirror also
    swaps the turning sense: it maps to minus the mirrored vector, so its y and z change
    sign instead. (Mirroring hinge axes like drawer axes would teach that a left-hinged
    door and a right-hinged one share an axis.)
    """
    cls = cls.flip(-1)
    axis, offset = axis.flip(-1).clone(), offset.flip(-1).clone()
    door = (cls == 4).unsqueeze(1)
    mirrored_axis = axis * torch.tensor([-1.0, 1.0, 1.0]).view(1, 3, 1, 1)
    axis = torch.where(door, -mirrored_axis, mirrored_axis)
    offset[:, 0] *= -1
    return x.flip(-1), cls, axis, offset


def evaluate(model: ArticulationNet, split: dict, batch: int = 32) -> dict[str, float]:
    """Held-out figures: class IoU, and per ground-truth movable part (a connected region
    of >= 40 drawer or door pixels) the hypothesis with the best mask IoU (matched if
    >= 0.5): its joint type, axis angle error and hinge error (distance between the voted
    origin and the true hinge line), and for doors whether the recovered axis sign gives
    the true opening sense."""
    model.eval()
    outs = []
    with torch.no_grad():
        for i in range(0, len(split["x"]), batch):
            outs.append(model(torch.from_numpy(split["x"][i : i + batch])).numpy())
    out = np.concatenate(outs)
    k = len(CLASSES)
    pred = out[:, :k].argmax(axis=1)
    iou = {}
    for c, name in enumerate(CLASSES):
        inter = np.logical_and(pred == c, split["cls"] == c).sum()
        union = np.logical_or(pred == c, split["cls"] == c).sum()
        iou[name] = float(inter / union) if union else float("nan")
    type_ok, angles, hinge, door_sense, matched, total = 0, [], [], [], 0, 0
    for v in range(len(out)):
        hyps = extract_parts(out[v], split["points"][v])
        gt = split["cls"][v]
        for c in (3, 4):
            n, comp = cv2.connectedComponents((gt == c).astype(np.uint8), connectivity=4)
            for i in range(1, n):
                mask = comp == i
                if mask.sum() < 40:
                    continue
                total += 1
                best, best_iou = None, 0.0
                for h in hyps:
                    inter = np.logical_and(h.mask, mask).sum()
                    iou_h = inter / (h.mask.sum() + mask.sum() - inter)
                    if iou_h > best_iou:
                        best, best_iou = h, iou_h
                if best is None or best_iou < 0.5:  # matched: mask IoU >= 0.5
                    continue
                matched += 1
                type_ok += best.joint_type == CLASSES[c]
                true_axis = split["axis"][v][:, mask].mean(axis=1)
                if best.axis is not None:
                    cosang = float(best.axis @ true_axis)
                    angles.append(np.degrees(np.arccos(min(abs(cosang), 1.0))))
                    if c == 4:
                        door_sense.append(cosang > 0.0)
                if c == 4 and best.origin is not None:
                    o = (split["points"][v][mask] + split["offset"][v][:, mask].T).mean(axis=0)
                    r = best.origin - o
                    hinge.append(float(np.linalg.norm(r - (r @ true_axis) * true_axis)))
    return {
        "views": len(out),
        "pixel_accuracy": float((pred == split["cls"]).mean()),
        **{f"iou_{n}": v for n, v in iou.items()},
        "movable_parts": total,
        "matched": matched / max(total, 1),
        "joint_type_accuracy": type_ok / max(matched, 1),
        "axis_error_deg_median": float(np.median(angles)) if angles else float("nan"),
        "hinge_error_m_median": float(np.median(hinge)) if hinge else float("nan"),
        "door_opening_sense_accuracy": float(np.mean(door_sense)) if door_sense else float("nan"),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--train", type=Path, required=True)
    ap.add_argument("--test", type=Path, required=True)
    ap.add_argument("--epochs", type=int, default=12)
    ap.add_argument("--batch", type=int, default=16)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--width", type=int, default=16)
    ap.add_argument("--stride", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=OUT_DIR)
    args = ap.parse_args(argv)
    from tqdm import tqdm

    torch.manual_seed(args.seed)
    rng = np.random.default_rng(args.seed)
    t0 = time.perf_counter()
    train, test = load_split(args.train, args.stride), load_split(args.test, args.stride)
    print(
        f"{len(train['x'])} train / {len(test['x'])} test views ({time.perf_counter() - t0:.0f} s)"
    )
    model = ArticulationNet(args.width)
    n_params = sum(p.numel() for p in model.parameters())
    opt = torch.optim.AdamW(model.parameters(), lr=args.lr, weight_decay=1e-4)
    steps = args.epochs * (len(train["x"]) // args.batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=args.lr, total_steps=steps)
    tensors = {k: torch.from_numpy(train[k]) for k in ("x", "cls", "axis", "offset")}
    t0 = time.perf_counter()
    for epoch in range(args.epochs):
        model.train()
        order = rng.permutation(len(train["x"]))
        run = np.zeros(4)
        batches = range(0, len(order) - args.batch + 1, args.batch)
        for b in tqdm(batches, desc=f"epoch {epoch + 1}/{args.epochs}", leave=False):
            idx = torch.from_numpy(order[b : b + args.batch])
            x, cls, axis, off = (tensors[k][idx] for k in ("x", "cls", "axis", "offset"))
            if rng.random() < 0.5:
                x, cls, axis, off = flip(x, cls, axis, off)
            total, *parts = losses(model(x), cls, axis, off)
            opt.zero_grad()
            total.backward()
            opt.step()
            sched.step()
            run += [total.item(), *(p.item() for p in parts)]
        run /= max(len(batches), 1)
        print(
            f"epoch {epoch + 1}: loss {run[0]:.3f} (class {run[1]:.3f}, axis {run[2]:.3f}, "
            f"hinge {run[3]:.4f})  {time.perf_counter() - t0:.0f} s"
        )
    metrics = evaluate(model, test)
    metrics.update(
        train_views=len(train["x"]), epochs=args.epochs, parameters=n_params,
        train_seconds=round(time.perf_counter() - t0, 1),
    )  # fmt: skip
    args.out.mkdir(parents=True, exist_ok=True)
    torch.save(
        {"state_dict": model.state_dict(), "width": args.width, "stride": args.stride},
        args.out / "articulation_net.pt",
    )
    (args.out / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    for k, v in metrics.items():
        print(f"{k}: {v:.3f}" if isinstance(v, float) else f"{k}: {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
