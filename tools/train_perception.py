"""Train the per-pixel articulation network on rendered cabinet views (resumable).

Usage::

    python tools/render_perception_data.py --seeds 100000:100600 --out data/perception/train \
        --empty-prob 0.05 --furniture 0.5
    python tools/render_perception_data.py --seeds 3000:3030 --out data/perception/tune
    python tools/train_perception.py --train data/perception/train --test data/perception/tune

Writes ``models/perception/articulation_net.pt`` (weights and the settings they were
trained with), ``models/perception/metrics.json`` (the pixel-level figures on the
``--test`` views printed at the end; the per-part evaluation is
``tools/eval_perception.py``) and the training curve, ``training_curve.json`` and
``training_curve.png`` (losses per epoch, held-out pixel figures after each epoch).
After every epoch the full training state (weights, optimiser, schedule, random
generators, curve) goes to ``<out>/checkpoint.pt``; ``--resume`` continues from it, so
a killed run loses at most one epoch. Train and test cabinets
come from disjoint generator seeds. torch uses one thread by default (``--threads``, at
most 2): on the project's shared 2-core machines two threads ran ten times slower than
one whenever other jobs held the cores (README, "Perception network").
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import torch
from torch import nn

from perception.articulation_net import (
    CLASSES,
    HINGE_SIDES,
    SL_CENTRE,
    SL_CLASS,
    SL_HANDLE,
    SL_HINGE,
    ArticulationNet,
    prepare_input,
    view_targets,
)
from strug_manip.world.perception_data import load_views

OUT_DIR = Path(__file__).resolve().parents[1] / "models" / "perception"
#: Loss weights: class cross-entropy, centre offsets (smooth L1), hinge side
#: cross-entropy, handle binary cross-entropy.
W_CENTRE, W_HINGE, W_HANDLE = 1.0, 0.5, 1.0
#: Cross-entropy class weights (background is most pixels).
CLASS_WEIGHTS = (0.3, 1.0, 1.0, 1.5, 1.5)
#: Positive weight of handle pixels (about 1% of the cabinet's pixels).
HANDLE_POS_WEIGHT = 5.0
TARGETS = ("cls", "centre", "hinge", "handle")
#: The per-epoch losses of the training curve, and the held-out figures beside them.
LOSS_NAMES = ("loss", "class", "centre", "hinge", "handle")
CURVE_METRICS = ("pixel_accuracy", "iou_prismatic", "iou_revolute", "hinge_side_pixel_accuracy")
#: Options that change how a run goes, not what it computes (free to change on resume).
RUN_ONLY = ("resume", "threads")


def load_split(folder: Path, stride: int) -> dict:
    """Inputs and per-pixel targets of every shard in ``folder`` (N views)."""
    xs, meta = [], []
    targets: dict[str, list] = {k: [] for k in TARGETS}
    shards = sorted(Path(folder).glob("cabinet_*.npz"))
    if not shards:
        raise SystemExit(f"no cabinet_*.npz shards in {folder}")
    for path in shards:
        d = load_views(path)
        if "handle_map" not in d:
            raise SystemExit(f"{path} has no handle_map: re-render it with this version")
        for i in range(len(d["rgb"])):
            xs.append(prepare_input(d["rgb"][i], d["depth"][i], stride))
            t = view_targets(
                d["part_map"][i], d["joint_type"][i], d["axis_cam"][i],
                d["T_camera_cabinet"][i], d["handle_map"][i], stride,
            )  # fmt: skip
            for k, v in zip(TARGETS, t, strict=True):
                targets[k].append(v)
            meta.append((path.name, i))
    out = {k: np.stack(v) for k, v in targets.items()}
    out["x"] = np.stack(xs).astype(np.float32)
    out["meta"] = meta
    return out


def losses(out: torch.Tensor, cls, centre, hinge, handle):
    """(total, class CE, centre, hinge CE, handle BCE) losses of a batch."""
    ce = nn.functional.cross_entropy(out[:, SL_CLASS], cls, weight=torch.tensor(CLASS_WEIGHTS))
    part = (cls >= 2).float()
    l_c = nn.functional.smooth_l1_loss(out[:, SL_CENTRE], centre, reduction="none", beta=0.1)
    l_c = (l_c.sum(dim=1) * part).sum() / part.sum().clamp(min=1.0)
    door = hinge >= 0
    if door.any():
        l_h = nn.functional.cross_entropy(out[:, SL_HINGE].permute(0, 2, 3, 1)[door], hinge[door])
    else:
        l_h = out.sum() * 0.0
    l_a = nn.functional.binary_cross_entropy_with_logits(
        out[:, SL_HANDLE][:, 0], handle, pos_weight=torch.tensor(HANDLE_POS_WEIGHT)
    )
    total = ce + W_CENTRE * l_c + W_HINGE * l_h + W_HANDLE * l_a
    return total, ce, l_c, l_h, l_a


def flip(x, cls, centre, hinge, handle):
    """Mirror a batch left-right: image columns reversed, column offsets negated, left
    and right hinges swapped (a mirrored left-hinged door is a right-hinged one)."""
    centre = centre.flip(-1).clone()
    centre[:, 0] *= -1
    hinge = hinge.flip(-1)
    swap = torch.tensor([1, 0, 2, 3])
    hinge = torch.where(hinge >= 0, swap[hinge.clamp(min=0)], hinge)
    return x.flip(-1), cls.flip(-1), centre, hinge, handle.flip(-1)


def evaluate(model: ArticulationNet, split: dict, batch: int = 32) -> dict[str, float]:
    """Pixel-level held-out figures: accuracy and IoU per class, hinge side accuracy on
    door pixels, handle precision and recall at probability 0.5."""
    model.eval()
    k = len(CLASSES)
    inter, union = np.zeros(k), np.zeros(k)
    correct = pixels = hinge_ok = hinge_n = 0
    tp = fp = fn = 0
    with torch.no_grad():
        for i in range(0, len(split["x"]), batch):
            out = model(torch.from_numpy(split["x"][i : i + batch])).numpy()
            pred, cls = out[:, SL_CLASS].argmax(axis=1), split["cls"][i : i + batch]
            correct += int((pred == cls).sum())
            pixels += cls.size
            for c in range(k):
                inter[c] += np.logical_and(pred == c, cls == c).sum()
                union[c] += np.logical_or(pred == c, cls == c).sum()
            hinge = split["hinge"][i : i + batch]
            door = hinge >= 0
            hinge_ok += int((out[:, SL_HINGE].argmax(axis=1)[door] == hinge[door]).sum())
            hinge_n += int(door.sum())
            ph, th = out[:, SL_HANDLE][:, 0] > 0.0, split["handle"][i : i + batch] > 0.5
            tp += int((ph & th).sum())
            fp += int((ph & ~th).sum())
            fn += int((~ph & th).sum())
    return {
        "views": len(split["x"]),
        "pixel_accuracy": correct / max(pixels, 1),
        **{f"iou_{n}": float(inter[c] / max(union[c], 1)) for c, n in enumerate(CLASSES)},
        "hinge_side_pixel_accuracy": hinge_ok / max(hinge_n, 1),
        "handle_precision": tp / max(tp + fp, 1),
        "handle_recall": tp / max(tp + fn, 1),
    }


def plot_curve(history: list[dict], path: Path) -> None:
    """The training curve: the losses per epoch (left) and the held-out pixel figures
    after each epoch (right), as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    epochs = [h["epoch"] for h in history]
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.6))
    for k in LOSS_NAMES:
        a.plot(epochs, [h[k] for h in history], marker="o", ms=3, label=k)
    a.set(xlabel="epoch", ylabel="training loss", yscale="log", title="losses")
    a.legend(fontsize=8)
    for k in CURVE_METRICS:
        b.plot(epochs, [h[f"test_{k}"] for h in history], marker="o", ms=3, label=k)
    b.set(xlabel="epoch", ylim=(0, 1), title="held-out views (pixels)")
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _save(path: Path, obj: dict) -> None:
    tmp = path.with_name(path.name + ".tmp")
    torch.save(obj, tmp)
    tmp.replace(path)


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
    ap.add_argument("--resume", action="store_true", help="continue from <out>/checkpoint.pt")
    ap.add_argument("--threads", type=int, default=1, help="torch threads (1 or 2)")
    args = ap.parse_args(argv)
    from tqdm import tqdm

    torch.set_num_threads(max(1, min(args.threads, 2)))
    torch.manual_seed(args.seed)
    rng = np.random.default_rng(args.seed)
    t_load = time.perf_counter()
    train, test = load_split(args.train, args.stride), load_split(args.test, args.stride)
    print(f"{len(train['x'])} train / {len(test['x'])} test views "
          f"({time.perf_counter() - t_load:.0f} s)")  # fmt: skip
    model = ArticulationNet(args.width)
    n_params = sum(p.numel() for p in model.parameters())
    opt = torch.optim.AdamW(model.parameters(), lr=args.lr, weight_decay=1e-4)
    per_epoch = len(train["x"]) // args.batch
    sched = torch.optim.lr_scheduler.OneCycleLR(
        opt, max_lr=args.lr, total_steps=args.epochs * per_epoch
    )
    args.out.mkdir(parents=True, exist_ok=True)
    ckpt_path, start, seconds = args.out / "checkpoint.pt", 0, 0.0
    if args.resume and ckpt_path.exists():
        ck = torch.load(ckpt_path, weights_only=False)
        if ck["args"] != {k: v for k, v in vars(args).items() if k not in RUN_ONLY}:
            raise SystemExit(f"{ckpt_path} was made with other settings: {ck['args']}")
        model.load_state_dict(ck["model"])
        opt.load_state_dict(ck["opt"])
        sched.load_state_dict(ck["sched"])
        rng.bit_generator.state = ck["rng"]
        torch.set_rng_state(ck["torch_rng"])
        start, seconds = ck["epoch"], ck["seconds"]
        print(f"resuming after epoch {start} ({seconds:.0f} s so far)")
    history: list[dict] = ck.get("history", []) if args.resume and ckpt_path.exists() else []
    tensors = {k: torch.from_numpy(train[k]) for k in ("x", *TARGETS)}
    for epoch in range(start, args.epochs):
        t0 = time.perf_counter()
        model.train()
        order = rng.permutation(len(train["x"]))
        run = np.zeros(5)
        batches = range(0, per_epoch * args.batch, args.batch)
        for b in tqdm(batches, desc=f"epoch {epoch + 1}/{args.epochs}", leave=False):
            idx = torch.from_numpy(order[b : b + args.batch])
            batch = [tensors[k][idx] for k in ("x", *TARGETS)]
            if rng.random() < 0.5:
                batch = flip(*batch)
            total, *parts = losses(model(batch[0]), *batch[1:])
            opt.zero_grad()
            total.backward()
            opt.step()
            sched.step()
            run += [total.item(), *(p.item() for p in parts)]
        run /= max(len(batches), 1)
        seconds += time.perf_counter() - t0
        held_out = evaluate(model, test)  # not counted in the training time
        history.append({
            "epoch": epoch + 1, "seconds": round(seconds, 1),
            **dict(zip(LOSS_NAMES, (round(float(v), 4) for v in run), strict=True)),
            **{f"test_{k}": round(held_out[k], 4) for k in CURVE_METRICS},
        })  # fmt: skip
        print(
            f"epoch {epoch + 1}: loss {run[0]:.3f} (class {run[1]:.3f}, centre {run[2]:.3f}, "
            f"hinge {run[3]:.3f}, handle {run[4]:.3f}); held-out pixel accuracy "
            f"{held_out['pixel_accuracy']:.3f}  {seconds:.0f} s"
        )
        _save(ckpt_path, {
            "model": model.state_dict(), "opt": opt.state_dict(), "sched": sched.state_dict(),
            "rng": rng.bit_generator.state, "torch_rng": torch.get_rng_state(),
            "epoch": epoch + 1, "seconds": seconds, "history": history,
            "args": {k: v for k, v in vars(args).items() if k not in RUN_ONLY},
        })  # fmt: skip
    metrics = evaluate(model, test)
    metrics.update(
        train_views=len(train["x"]), epochs=args.epochs, parameters=n_params,
        train_seconds=round(seconds, 1), hinge_sides=list(HINGE_SIDES),
    )  # fmt: skip
    _save(
        args.out / "articulation_net.pt",
        {"state_dict": model.state_dict(), "width": args.width, "stride": args.stride},
    )
    (args.out / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    (args.out / "training_curve.json").write_text(json.dumps(history, indent=1) + "\n")
    plot_curve(history, args.out / "training_curve.png")
    for k, v in metrics.items():
        print(f"{k}: {v:.3f}" if isinstance(v, float) else f"{k}: {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
