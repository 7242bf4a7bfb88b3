"""Per-pixel articulation network: RGB-D in, part classes and joint parameters out.

A small U-Net (torch, CPU-sized) reads one head-camera view (RGB and depth) and predicts,
for every pixel,

* its class (:data:`CLASSES`): not the cabinet, the carcass, a fixed front (panel or
  shelf), a drawer (prismatic joint) or a door (revolute joint);
* for drawer and door pixels, the unit joint axis in the camera frame (3 channels;
  for doors a line, trained sign-free: the sign that opens the door is recovered from
  the geometry by :func:`extract_parts`);
* for door pixels, the offset from the pixel's 3D point to the hinge origin [m]
  (3 channels): every pixel votes for its hinge, as in per-pixel articulation
  estimators (e.g. ANCSH, Li et al. 2020).

:func:`extract_parts` turns these maps into part hypotheses: connected regions of one
class, each with a class confidence, the mean predicted axis and the median voted hinge
origin. Turning hypotheses into belief particles (with noise on inputs, classes and
parameters, as the paper does) is the job of the belief builder.

Input convention (:func:`prepare_input`): images are downsampled by ``stride`` (default
2: 240x320 -> 120x160); RGB scaled to [0, 1]; depth clipped to ``MAX_DEPTH`` and divided
by it. Everything is in the camera frame of :mod:`strug_manip.world.sim` (looking along
-z, +x right, +y up).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
import torch
from torch import nn

#: Pixel classes, in output-channel order.
CLASSES = ("background", "carcass", "fixed", "prismatic", "revolute")
#: Depth beyond which a pixel is treated as far background [m].
MAX_DEPTH = 4.0
#: Output channels: class logits, joint axis (3), hinge offset (3).
N_OUT = len(CLASSES) + 6


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


def view_targets(
    part_map: np.ndarray,
    joint_type: np.ndarray,
    axis_cam: np.ndarray,
    origin_cam: np.ndarray,
    depth: np.ndarray,
    fovy: float,
    stride: int = 2,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Training targets of one labelled view at the network's resolution.

    Args:
        part_map: (H, W) part index per pixel (-1 background, 0 carcass, k part k).
        joint_type: (P,) 0 fixed, 1 prismatic, 2 revolute.
        axis_cam, origin_cam: (P, 3) joint axes and origins, camera frame [m].
        depth: (H, W) depth [m]; fovy: vertical field of view [rad].
        stride: subsampling, as in :func:`prepare_input`.

    Returns:
        ``(classes (h, w) int64, axis (3, h, w), hinge offset (3, h, w) [m],
        points (h, w, 3) [m])``, float32 where not integer; axis and offset are only
        meaningful on drawer and door pixels.
    """
    pm = part_map[::stride, ::stride].astype(np.int64)
    points = pixel_points(depth, fovy)[::stride, ::stride]
    part = np.clip(pm - 1, 0, None)
    axis = axis_cam[part].transpose(2, 0, 1)
    offset = (origin_cam[part] - points).transpose(2, 0, 1)
    return (
        class_targets(pm, joint_type),
        axis.astype(np.float32),
        offset.astype(np.float32),
        points.astype(np.float32),
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


@dataclass(frozen=True)
class PartHypothesis:
    """One predicted part.

    Attributes:
        joint_type: ``fixed``, ``prismatic`` or ``revolute``.
        confidence: mean softmax probability of that class over the part's pixels.
        pixels: pixel count (at the network's resolution).
        mask: boolean mask (H, W) at the network's resolution.
        axis: unit joint axis in the camera frame (3,), or None for fixed parts.
        origin: voted hinge origin in the camera frame (3,) [m], or None unless revolute.
        centroid: mean 3D point of the part (3,) [m].
    """

    joint_type: str
    confidence: float
    pixels: int
    mask: np.ndarray
    axis: np.ndarray | None
    origin: np.ndarray | None
    centroid: np.ndarray


def _door_axis(votes: np.ndarray, origin: np.ndarray, centroid: np.ndarray) -> np.ndarray:
    """A hinge axis from per-pixel line votes (3, N): the principal direction of their
    outer products (sign-free), signed so that a small positive turn about it moves the
    door's centroid towards the camera (doors open outward, towards the robot)."""
    v = votes / np.maximum(np.linalg.norm(votes, axis=0), 1e-9)
    _, vecs = np.linalg.eigh(v @ v.T)
    axis = vecs[:, -1]
    velocity = np.cross(axis, centroid - origin)
    return axis if velocity @ (-centroid) >= 0.0 else -axis


def extract_parts(
    output: np.ndarray, points: np.ndarray, min_pixels: int = 40
) -> list[PartHypothesis]:
    """Part hypotheses from one network output.

    Args:
        output: (N_OUT, H, W) network output for one view.
        points: (H, W, 3) camera-frame points at the same resolution [m].
        min_pixels: smaller regions are dropped.
    """
    logits = output[: len(CLASSES)]
    prob = np.exp(logits - logits.max(axis=0))
    prob /= prob.sum(axis=0)
    label = prob.argmax(axis=0)
    axis_map, offset_map = output[len(CLASSES) : len(CLASSES) + 3], output[len(CLASSES) + 3 :]
    parts = []
    for cls in (2, 3, 4):
        n, comp = cv2.connectedComponents((label == cls).astype(np.uint8), connectivity=4)
        for i in range(1, n):
            mask = comp == i
            count = int(mask.sum())
            if count < min_pixels:
                continue
            kind = CLASSES[cls]
            axis = origin = None
            centroid = points[mask].mean(axis=0)
            if cls == 3:
                a = axis_map[:, mask].mean(axis=1)
                axis = a / max(float(np.linalg.norm(a)), 1e-9)
            if cls == 4:
                origin = np.median(points[mask] + offset_map[:, mask].T, axis=0)
                axis = _door_axis(axis_map[:, mask], origin, centroid)
            parts.append(
                PartHypothesis(
                    joint_type=kind,
                    confidence=float(prob[cls][mask].mean()),
                    pixels=count,
                    mask=mask,
                    axis=axis,
                    origin=origin,
                    centroid=centroid,
                )
            )
    return parts
