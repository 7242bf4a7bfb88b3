"""One view to part instances: run the network, split parts into instances, lift them
to the world frame.

:class:`Perceiver` holds the trained :class:`~perception.articulation_net.ArticulationNet`
and turns a checked :class:`~perception.inputs.View` into a :class:`ViewParts`: the
cabinet's pixels as world points and a list of :class:`Instance` (one per visible
part: its pixels, world points, class probabilities, hinge-side probabilities and its
best pull point). Joint parameters are not decided here: they need the cabinet's front
plane, which :mod:`perception.fusion` fits from every view at once.

Instances (centre voting): pixels whose most likely class is a part class (fixed,
drawer, door) form connected regions; each pixel votes for its part's centre (the
network's centre offsets); the votes of a region are accumulated on the image grid,
smoothed, and every local maximum with at least :data:`MIN_VOTES` votes is an instance
centre; each pixel joins the centre nearest to its vote. Regions are taken across
classes, so a front whose pixels the network splits between "drawer" and "door" stays
one instance with mixed class probabilities (the belief's class flip), and two touching
fronts of one class are split by their centres (the issue of merged drawer stacks).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import cv2
import numpy as np
import torch
from scipy import ndimage

from perception.articulation_net import (
    CENTRE_SCALE,
    SL_CENTRE,
    SL_CLASS,
    SL_HANDLE,
    SL_HINGE,
    ArticulationNet,
    load_network,
    pixel_points,
    prepare_input,
)
from perception.errors import BadInputError
from perception.inputs import View
from perception.instances import Instance, ViewParts
from perception.joint_cues import apply_joint_cues

#: The shipped weights.
DEFAULT_WEIGHTS = (
    Path(__file__).resolve().parents[1] / "models" / "perception" / "articulation_net.pt"
)
#: Part classes, as indices into ``CLASSES`` (fixed, prismatic, revolute).
PART_CLASSES = (2, 3, 4)
#: Smallest instance kept [pixels at the network's resolution].
MIN_PIXELS = 30
#: Smallest accumulated vote count of an instance centre.
MIN_VOTES = 20.0
#: Smoothing of the vote image [pixels] and the window of its local maxima [pixels].
VOTE_SIGMA, PEAK_WINDOW = 2.5, 11


def _softmax(x: np.ndarray, axis: int = 0) -> np.ndarray:
    e = np.exp(x - x.max(axis=axis, keepdims=True))
    return e / e.sum(axis=axis, keepdims=True)


def surface_normals(points: np.ndarray, eye: np.ndarray, max_step: float = 0.03) -> np.ndarray:
    """Unit normals (h, w, 3) of a grid of points (h, w, 3) [m] from central
    differences, turned towards ``eye`` (3,); zero at the border and where a neighbour
    is more than ``max_step`` [m] away (a depth edge)."""
    n = np.zeros_like(points)
    du = points[1:-1, 2:] - points[1:-1, :-2]
    dv = points[2:, 1:-1] - points[:-2, 1:-1]
    c = np.cross(du, dv)
    norm = np.linalg.norm(c, axis=-1, keepdims=True)
    ok = (np.linalg.norm(du, axis=-1) < 2 * max_step) & (np.linalg.norm(dv, axis=-1) < 2 * max_step)
    c = np.where(ok[..., None] & (norm > 1e-12), c / np.maximum(norm, 1e-12), 0.0)
    flip = ((eye - points[1:-1, 1:-1]) * c).sum(axis=-1) < 0
    n[1:-1, 1:-1] = np.where(flip[..., None], -c, c)
    return n


def split_instances(
    part: np.ndarray, centre: np.ndarray, min_pixels: int = MIN_PIXELS
) -> list[np.ndarray]:
    """Instance masks from a part mask (h, w) bool and centre offsets (2, h, w) [pixels].

    Returns the masks (each (h, w) bool), largest first (module docstring).
    """
    h, w = part.shape
    n, comp = cv2.connectedComponents(part.astype(np.uint8), connectivity=4)
    vv, uu = np.mgrid[0:h, 0:w]
    vote_u, vote_v = uu + centre[0], vv + centre[1]
    masks = []
    for i in range(1, n):
        region = comp == i
        if region.sum() < min_pixels:
            continue
        ui = np.clip(np.rint(vote_u[region]), 0, w - 1).astype(int)
        vi = np.clip(np.rint(vote_v[region]), 0, h - 1).astype(int)
        acc = np.zeros((h, w))
        np.add.at(acc, (vi, ui), 1.0)
        acc = ndimage.gaussian_filter(acc, VOTE_SIGMA) * (2 * np.pi * VOTE_SIGMA**2)
        peaks = (acc == ndimage.maximum_filter(acc, PEAK_WINDOW)) & (acc >= MIN_VOTES)
        pv, pu = np.nonzero(peaks)
        if len(pu) <= 1:
            masks.append(region)
            continue
        d2 = (vote_u[region][:, None] - pu[None]) ** 2 + (vote_v[region][:, None] - pv[None]) ** 2
        owner = d2.argmin(axis=1)
        rv, ru = np.nonzero(region)
        for k in range(len(pu)):
            m = np.zeros_like(region)
            m[rv[owner == k], ru[owner == k]] = True
            if m.sum() >= min_pixels:
                masks.append(m)
    return sorted(masks, key=lambda m: -int(m.sum()))


class Perceiver:
    """The network and the per-view extraction.

    Args:
        weights: a checkpoint of ``tools/train_perception.py`` (default: the shipped one).
        threads: torch threads (default 1: on a shared 2-core machine two threads wait
            on each other whenever another job holds a core).
    """

    def __init__(self, weights: str | Path | None = None, threads: int = 1) -> None:
        path = Path(weights) if weights is not None else DEFAULT_WEIGHTS
        if not path.exists():
            raise BadInputError(f"no perception weights at {path}")
        torch.set_num_threads(max(1, min(int(threads), 2)))
        self.net, self.stride = load_network(path)

    @classmethod
    def from_network(cls, net: ArticulationNet, stride: int = 2) -> Perceiver:
        """A perceiver around an already built network (tests, training)."""
        self = cls.__new__(cls)
        self.net, self.stride = net.eval(), int(stride)
        return self

    def network_output(self, view: View) -> np.ndarray:
        """The raw output (N_OUT, h, w) of one view."""
        x = torch.from_numpy(prepare_input(view.rgb, view.depth, self.stride))[None]
        with torch.no_grad():
            return self.net(x)[0].numpy()

    def perceive(self, view: View) -> ViewParts:
        """Network, instances and world points of one checked view."""
        t0 = time.perf_counter()
        return extract(view, self.network_output(view), self.stride, t0)


def texture_map(rgb: np.ndarray, stride: int, shape: tuple[int, int]) -> np.ndarray:
    """(h, w) = ``shape``: the (H, W, 3) uint8 image's luminance gradient magnitude
    (3x3 Sobel, grey levels), the largest over each pixel's ``stride`` x ``stride``
    block (a max, so that a one-pixel grain line survives the network's resolution)."""
    g = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY).astype(np.float32)
    mag = np.hypot(cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3), cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3))
    h, w = shape
    return mag[: h * stride, : w * stride].reshape(h, stride, w, stride).max(axis=(1, 3))


def extract(view: View, out: np.ndarray, stride: int = 2, t0: float | None = None) -> ViewParts:
    """Instances and world points of one view from a network output (N_OUT, h, w),
    with this view's joint-type cues (:func:`perception.joint_cues.apply_joint_cues`)
    (``t0``: the :func:`time.perf_counter` the view's processing started at)."""
    t0 = time.perf_counter() if t0 is None else t0
    s = stride
    prob = _softmax(out[SL_CLASS])
    label = prob.argmax(axis=0)
    valid = view.valid[::s, ::s]
    T = view.T_world_camera
    pts = pixel_points(view.depth, view.fovy)[::s, ::s] @ T[:3, :3].T + T[:3, 3]
    cab = (label >= 1) & valid
    hinge = _softmax(out[SL_HINGE])
    handle = 1.0 / (1.0 + np.exp(-out[SL_HANDLE][0]))
    part = label >= 2
    instances = []
    for mask in split_instances(part, out[SL_CENTRE] * CENTRE_SCALE):
        mv = mask & valid
        if mv.sum() < MIN_PIXELS // 2:
            continue
        cp = prob[2:5][:, mask].mean(axis=1)
        hs = np.where(mv, handle, 0.0)
        best = np.unravel_index(int(hs.argmax()), hs.shape)
        score = float(hs[best])
        instances.append(
            Instance(
                mask=mask,
                points=pts[mv],
                class_prob=cp / cp.sum(),
                part_prob=float(prob[2:5][:, mask].sum(axis=0).mean()),
                hinge_prob=hinge[:, mask].mean(axis=1),
                handle=pts[best] if score > 0.5 else None,
                handle_score=score,
                pull=handle[mv],
                net_class_prob=cp / cp.sum(),
                handle_points=pts[mv & (handle > 0.5)],
            )
        )
    normals = surface_normals(pts, T[:3, 3])
    vp = ViewParts(
        T_world_camera=T,
        fovy=view.fovy,
        shape=label.shape,
        cabinet_points=pts[cab],
        cabinet_class=label[cab],
        cabinet_normals=normals[cab],
        instances=instances,
        handle_prob=handle,
        points=pts,
        valid=valid,
        normals=normals,
        seconds=0.0,
        texture=texture_map(view.rgb, stride, label.shape),
    )
    vp = apply_joint_cues(vp)
    return dataclasses.replace(vp, seconds=time.perf_counter() - t0)
