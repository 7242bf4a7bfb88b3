"""Per-pixel articulation network: RGB-D in, part classes, instances, hinge sides and
pull affordances out.

A small U-Net (torch, CPU-sized) reads one head-camera view (RGB and depth) and predicts,
for every pixel (output channels in this order, :data:`N_OUT` in all):

* its class (:data:`CLASSES`, 5 logits): not the cabinet, the carcass, a fixed front
  (panel or shelf), a drawer (prismatic joint) or a door (revolute joint);
* the offset from the pixel to the centre of its part's visible region (2 channels,
  image columns and rows at the network's resolution divided by :data:`CENTRE_SCALE`):
  every pixel of a part votes for one centre, so adjacent fronts of one class (a drawer
  stack) come out as separate instances (centre voting, as in Panoptic-DeepLab);
* for door pixels, the hinge side (:data:`HINGE_SIDES`, 4 logits) as a person in front
  of the cabinet names it: which edge the door turns about;
* the pull affordance (1 logit): the pixel is on a handle (bar, post or knob), where a
  pull grasps.

Joint axes and hinge lines are *not* regressed: they follow from the depth geometry
(:mod:`perception.parts`), which is exact to a few millimetres where a learnt
regression was off by 15 degrees. The network decides what geometry cannot see:
classes, instances, and which edge of a closed door is the hinge.

Input convention (:func:`prepare_input`): images are downsampled by ``stride`` (default
2: 240x320 -> 120x160); RGB scaled to [0, 1]; depth clipped to ``MAX_DEPTH`` and divided
by it. Everything is in the camera frame of :mod:`strug_manip.world.sim` (looking along
-z, +x right, +y up). This module does not check its inputs; :func:`perception.views
.check_view` does.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import torch
from torch import nn

#: Pixel classes, in output-channel order.
CLASSES = ("background", "carcass", "fixed", "prismatic", "revolute")
#: Door hinge sides, in output-channel order (the generator's names).
HINGE_SIDES = ("left", "right", "top", "bottom")
#: Depth beyond which a pixel is treated as far background [m].
MAX_DEPTH = 4.0
#: Centre offsets are predicted in units of this many pixels (network resolution).
CENTRE_SCALE = 20.0
#: Channel slices of the output.
SL_CLASS = slice(0, 5)
SL_CENTRE = slice(5, 7)
SL_HINGE = slice(7, 11)
SL_HANDLE = slice(11, 12)
N_OUT = 12


def class_targets(part_map: np.ndarray, joint_type: np.ndarray) -> np.ndarray:
    """Per-pixel class index (H, W) int64 from a part map and per-part joint types."""
    lut = np.concatenate([[0, 1], 2 + np.asarray(joint_type, dtype=np.int64)])
    return lut[part_map.astype(np.int64) + 1]


def pixel_points(depth: np.ndarray, fovy: float) -> np.ndarray:
    """Camera-frame 3D point of every pixel, (H, W, 3) [m] (MuJoCo's camera convention)."""
    h, w = depth.shape
    f = 0.5 * h / math.tan(0.5 * fovy)
    u = np.arange(w)[None, :] + 0.5 - 0.5 * w
    v = np.arange(h)[:, None] + 0.5 - 0.5 * h
    d = depth.astype(np.float64)
    return np.stack([u * d / f, -v * d / f, -d], axis=-1)


def hinge_side_of(axis_cabinet: np.ndarray) -> int:
    """Index into :data:`HINGE_SIDES` of a door whose (signed, opening) axis in the
    cabinet frame is ``axis_cabinet`` (3,): the generator's axis is ``e x n`` with ``e``
    from the hinge to the free edge and ``n = +x``, so left -> -z, right -> +z,
    top -> -y, bottom -> +y."""
    a = np.asarray(axis_cabinet, dtype=float)
    k = int(np.argmax(np.abs(a[1:]))) + 1
    if k == 2:
        return 0 if a[2] < 0 else 1
    return 2 if a[1] < 0 else 3


def view_targets(
    part_map: np.ndarray,
    joint_type: np.ndarray,
    axis_cam: np.ndarray,
    T_camera_cabinet: np.ndarray,
    handle_map: np.ndarray,
    stride: int = 2,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Training targets of one labelled view at the network's resolution.

    Args:
        part_map: (H, W) part index per pixel (-1 background, 0 carcass, k part k).
        joint_type: (P,) 0 fixed, 1 prismatic, 2 revolute.
        axis_cam: (P, 3) joint axes, camera frame.
        T_camera_cabinet: (4, 4) the cabinet frame in the camera frame.
        handle_map: (H, W) bool, handle pixels.
        stride: subsampling, as in :func:`prepare_input`.

    Returns:
        ``(classes (h, w) int64, centre offsets (2, h, w) float32 in CENTRE_SCALE
        pixels (meaningful on part pixels), hinge side (h, w) int64 (-1 off doors),
        handle (h, w) float32)``.
    """
    pm = part_map[::stride, ::stride].astype(np.int64)
    h, w = pm.shape
    n = len(joint_type) + 2
    flat = (pm + 1).reshape(-1)
    count = np.bincount(flat, minlength=n).astype(np.float64)
    vv, uu = np.mgrid[0:h, 0:w]
    cu = np.bincount(flat, weights=uu.reshape(-1), minlength=n) / np.maximum(count, 1)
    cv = np.bincount(flat, weights=vv.reshape(-1), minlength=n) / np.maximum(count, 1)
    centre = np.stack([cu[pm + 1] - uu, cv[pm + 1] - vv]) / CENTRE_SCALE
    R = np.asarray(T_camera_cabinet)[:3, :3]
    sides = np.full(n, -1, dtype=np.int64)
    for k, jt in enumerate(joint_type):
        if jt == 2:
            sides[k + 2] = hinge_side_of(R.T @ axis_cam[k])
    return (
        class_targets(pm, joint_type),
        centre.astype(np.float32),
        sides[pm + 1],
        handle_map[::stride, ::stride].astype(np.float32),
    )


def prepare_input(rgb: np.ndarray, depth: np.ndarray, stride: int = 2) -> np.ndarray:
    """Network input (4, H/stride, W/stride) float32 from RGB (H, W, 3) uint8 and depth [m].

    Labels and 3D points go with it as ``array[::stride, ::stride]``.
    """
    h, w = depth.shape
    size = (w // stride, h // stride)
    rgb_s = cv2.resize(rgb, size, interpolation=cv2.INTER_AREA).astype(np.float32) / 255.0
    d = np.clip(np.nan_to_num(depth, nan=MAX_DEPTH), 0.0, MAX_DEPTH).astype(np.float32)
    d_s = d[::stride, ::stride] / MAX_DEPTH  # the same pixels as the subsampled labels
    return np.concatenate([rgb_s.transpose(2, 0, 1), d_s[None]], axis=0)


def _block(c_in: int, c_out: int) -> nn.Sequential:
    return nn.Sequential(
        nn.Conv2d(c_in, c_out, 3, padding=1),
        nn.BatchNorm2d(c_out),
        nn.ReLU(inplace=True),
        nn.Conv2d(c_out, c_out, 3, padding=1),
        nn.BatchNorm2d(c_out),
        nn.ReLU(inplace=True),
    )


class ArticulationNet(nn.Module):
    """U-Net with ``width * (1, 2, 4, 8)`` channels over four scales.

    Args:
        width: channels of the first scale (default 16: about 0.5 M parameters).
    """

    def __init__(self, width: int = 16) -> None:
        super().__init__()
        if not isinstance(width, int) or width < 4:
            raise ValueError(f"width must be an integer >= 4, got {width!r}")
        c = [width, 2 * width, 4 * width, 8 * width]
        self.enc = nn.ModuleList([_block(4, c[0]), _block(c[0], c[1]), _block(c[1], c[2])])
        self.mid = _block(c[2], c[3])
        self.up = nn.ModuleList(
            [nn.ConvTranspose2d(c[i + 1], c[i], 2, stride=2) for i in (2, 1, 0)]
        )
        self.dec = nn.ModuleList([_block(2 * c[i], c[i]) for i in (2, 1, 0)])
        self.head = nn.Conv2d(c[0], N_OUT, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """(B, 4, H, W) -> (B, N_OUT, H, W); H and W must be multiples of 8."""
        skips = []
        for enc in self.enc:
            x = enc(x)
            skips.append(x)
            x = nn.functional.max_pool2d(x, 2)
        x = self.mid(x)
        for up, dec, skip in zip(self.up, self.dec, reversed(skips), strict=True):
            x = dec(torch.cat([up(x), skip], dim=1))
        return self.head(x)


def load_network(path) -> tuple[ArticulationNet, int]:
    """The network saved by ``tools/train_perception.py`` at ``path``, in eval mode, and
    its input stride."""
    ckpt = torch.load(path, weights_only=True, map_location="cpu")
    net = ArticulationNet(int(ckpt["width"]))
    net.load_state_dict(ckpt["state_dict"])
    return net.eval(), int(ckpt["stride"])
