"""Multi-view fusion: the views' part instances to one set of part hypotheses per
cabinet, in the world frame.

Steps (:func:`fuse`):

1. **The front plane**, from the cabinet points of every view at once (the cabinet
   stands upright on its table, so its front is a vertical plane; :func:`fit_front`).
   It fixes the *front frame* ``F``: ``x`` the outward normal, ``z`` world up, ``y = z x x`` (the
   generator's object axes), origin on the plane below the front's centre at the
   carcass's lowest point. A drawer's axis is this normal; a door's hinge is an edge of
   its panel; so joint axes come from hundreds of depth points instead of a learnt
   per-pixel regression.
2. **Per instance and view**, its *closed-state rectangle* on the front plane (``y0,
   y1, z0, z1`` in ``F`` [m]) and its joint parameters under each interpretation: as a
   drawer, its opening [m] (the front face's distance from the plane); as a door, the
   hinge side and opening angle [rad]. An open door's hinge is the panel edge nearest
   the front plane (geometry); a closed door's is the side the network votes for, times
   the handle's cue (a handle sits near the free edge). A side door open by theta looks
   exactly like the opposite-hinged door open by pi - theta; both are kept when
   pi - theta is within :data:`SIDE_DOOR_MAX` (the larger generator limit), weighted by
   the network. A reading also says whether its front moved out parallel to the plane
   (``moved_out``: only drawers do that) or turned out about an edge on it
   (``turned_out``: doors), which :mod:`perception.joint_cues` weighs per view.
3. **Association**: instances of all views, smallest first, join the fused part whose
   largest reading's closed-state rectangle overlaps theirs most (IoU >=
   :data:`ASSOC_IOU`, the best pair of interpretations: as seen, or as a door hinged on
   a side the geometry allows; one instance per view and part); an instance holding
   most of two or more fused parts that lie apart (a divider between them) is a merged
   region: it counts as evidence that the
   region holds several parts (``merged``) and adds to none. Each fused part gets class
   probabilities (pixel-weighted mean over its views of the instances' probabilities,
   which hold each view's geometric evidence), hinge-side probabilities, an
   existence probability (confidence-weighted share of the views that could see it
   that did) and the spread of its rectangle and opening over the views. Pieces of one
   open drawer (pulled out by the same centimetre, side by side) are joined.

All lengths [m], angles [rad], frames ``T_world_frame`` (4, 4).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import Counter, deque
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from perception.errors import NoCabinetError
from perception.instances import Instance, ViewParts

#: Distance of a point on the front plane from it [m].
PLANE_TOL = 0.006
#: How far overlay fronts stand in front of the carcass's front plane [m]: real
#: furniture's doors and drawer fronts often sit on a face frame instead of inset in it
#: (SAPIEN's 40147: 15 mm); they belong to the front's extent.
OVERLAY = 0.025
#: A door panel tilted by more than this from the front plane is open [rad].
DOOR_OPEN_TILT = math.radians(12.0)
#: Largest side-door opening the generator makes (2.10 rad) plus a margin [rad].
SIDE_DOOR_MAX = 2.2
#: Instances whose closed-state rectangles overlap at least this much (IoU, best pair
#: of interpretations) are one part.
ASSOC_IOU = 0.3
#: A reading takes its view's place in a group from one that matches the group's
#: reference worse by this much (IoU) ...
SWAP_MARGIN = 0.2
#: ... and a reading is displaced at most this often (the association ends).
MAX_EVICTIONS = 2
#: Groups whose largest reading's seen face is narrower or lower than this [m] (a strip
#: of an open cell's floor, read as a flap turned down) do not make a reading that
#: covers them a merged region (the generator's cells are at least 0.12 x 0.20 m).
MIN_PART = 0.06
#: Parts a merged region covers lie this far apart at least [m]: a divider (the
#: generator's boards are 0.015-0.020 m) less the rectangles' noise. Pieces of one
#: front touch or overlap: a reading that covers those is that front.
MERGE_GAP = 0.007
#: Match score of two open panels turned about one hinge line, within this [m] and
#: with openings within this [rad] of each other.
HINGE_MATCH, HINGE_TOL, OPENING_TOL = 0.6, 0.03, 0.3
#: A front narrower or lower than this is a measurement failure [m] (the generator's
#: smallest cabinet is 0.35 x 0.30 m).
MIN_FRONT = 0.2
#: Depth of the carcass when its top and sides are not seen: the middle of the
#: generator's 0.30-0.45 m range [m].
DEFAULT_DEPTH = 0.375
#: Deepest carcass behind its front the fit accepts: the generator's 0.45 m plus a margin.
MAX_DEPTH = 0.52
#: The gap between a front and its cell [m] and a front's thickness [m] (the middle of
#: the generator's 0.002-0.004 and 0.015-0.022 m).
FRONT_GAP, FRONT_THICKNESS = 0.003, 0.018
#: A closed-looking front this far in front of the front plane has moved out [m].
MOVED_OUT = 0.025
#: An open panel's seen end nearest the front plane further out than this has its hinge
#: hidden [m]; the hinge is then extrapolated along the panel, at most this far [m].
HIDDEN_HINGE, MAX_HIDDEN = 0.03, 0.3
#: Sharpness of the handle's hinge-side cue (:func:`_handle_cue`).
HANDLE_CUE = 6.0
#: Hinge sides, as :data:`perception.articulation_net.HINGE_SIDES`.
SIDES = ("left", "right", "top", "bottom")
#: A view's handle pixels (pull affordance > 0.5) read as a bar when they stretch at
#: least this far along their longest direction [m] and this many times further than
#: across it: the generator's bars are 8-20 cm long, its knobs 2-3.6 cm across, and the
#: affordance spreads a few centimetres around a knob (4.7-6.5 cm in the worst views).
BAR_MIN_LENGTH, BAR_MIN_ELONGATION = 0.05, 2.5
#: Fewer handle pixels than this in a view say nothing of the handle's shape.
MIN_HANDLE_PIXELS = 5
#: Joint types of a fused part's class probabilities.
TYPES = ("fixed", "prismatic", "revolute")
#: An instance with at least this many mask pixels on an image border (network
#: resolution) runs off the image there: the side of its rectangle facing that border
#: is a bound, not an edge. Two, not one: a part whose edge ends a pixel short of the
#: border may bleed one pixel onto it. (A tall cabinet's top drawer ran off the top of
#: three of the four standard views; their medians put its front 3 cm low, and a Place
#: carried the object into its real front's top edge, issue 39.)
CUT_PIXELS = 2


@dataclass(frozen=True)
class FrontFrame:
    """The cabinet's front, as seen.

    Attributes:
        T_world_front: (4, 4): x outward normal, z up, origin on the front plane at the
            front's lateral centre and the carcass's lowest point.
        width, height: extents of the front [m] (y and z in the front frame).
        depth: the carcass depth behind the front [m]; ``depth_seen``: whether it was
            measured (else :data:`DEFAULT_DEPTH`).
        inliers: front-plane points found.
    """

    T_world_front: np.ndarray
    width: float
    height: float
    depth: float
    depth_seen: bool
    inliers: int

    def to_front(self, p: np.ndarray) -> np.ndarray:
        """World points (..., 3) in the front frame."""
        T = self.T_world_front
        return (np.asarray(p) - T[:3, 3]) @ T[:3, :3]

    def to_world(self, p: np.ndarray) -> np.ndarray:
        """Front-frame points (..., 3) in the world."""
        T = self.T_world_front
        return np.asarray(p) @ T[:3, :3].T + T[:3, 3]

    def dir_to_world(self, v: np.ndarray) -> np.ndarray:
        """A front-frame direction (3,) in the world."""
        return self.T_world_front[:3, :3] @ np.asarray(v, dtype=float)


@dataclass(frozen=True)
class Reading:
    """One instance of one view, interpreted (front frame).

    Attributes:
        rect: (4,) the closed-state rectangle ``y0, y1, z0, z1`` [m] it is associated
            by (as an open door if it is one and the network says door, else as seen).
        face_rect: (4,) the rectangle as a drawer or panel (the seen front) [m].
        q_drawer: its opening if a drawer [m].
        door_rect: (4, 4) closed rectangle per hinge side; door_q: (4,) opening per side
            [rad]; door_ok: (4,) which sides are geometrically possible.
        closed_door: the panel lies in the front plane.
        depth_x: median front-frame x of its points [m] (shelves lie deep inside).
        moved_out: its front lies parallel to the front plane, more than
            :data:`MOVED_OUT` in front of it (only a drawer does that).
        turned_out: it is a panel turned out of the front plane about an edge on it
            (a door).
        cut: (4,) bool, which sides of ``face_rect`` (``y0, y1, z0, z1``) lie on the
            image's border: the part may go on beyond them, so they are a bound, not
            an edge (:func:`cut_sides`).
    """

    view: int
    instance: Instance
    rect: np.ndarray
    face_rect: np.ndarray
    q_drawer: float
    door_rect: np.ndarray
    door_q: np.ndarray
    door_ok: np.ndarray
    closed_door: bool
    depth_x: float
    moved_out: bool = False
    turned_out: bool = False
    cut: np.ndarray = field(default_factory=lambda: np.zeros(4, dtype=bool))

    @property
    def door_cut(self) -> np.ndarray:
        """(4, 4) bool: :attr:`cut` for each row of ``door_rect``; an open panel's
        sides across its hinge come from the hinge and its width, and are edges."""
        out = np.tile(self.cut, (4, 1))
        if not self.closed_door:
            out[:2, :2] = False  # side doors: their y sides
            out[2:, 2:] = False  # flaps: their z sides
        return out


@dataclass
class PartHypothesis:
    """One fused part (front frame; see the module docstring).

    Attributes:
        rect: (4,) closed-state rectangle as a drawer or panel [m]; rect_std: its
            spread over the views [m].
        class_prob: (3,) fixed, prismatic, revolute.
        existence: probability that the part exists.
        hinge_prob: (4,) over :data:`SIDES`, geometry and network combined.
        door_rect: (4, 4) closed rectangle per side; door_q: (4,) opening per side [rad].
        q_drawer: opening as a drawer [m]; q_std: its spread [m].
        handle: (3,) front-frame grasp point, or None; handle_score: its affordance.
        handle_style: ``bar`` or ``knob``, as the handle's seen shape says
            (:func:`handle_shape`); handle_along: a bar's direction on the front,
            ``y`` or ``z`` (None: a knob, or not seen).
        views: views it was seen in; visible: views that could see it; merged: views in
            which it was part of a larger merged region.
        shelf: a fixed part lying deep in its cell (an open shelf board, not a panel).
    """

    rect: np.ndarray
    rect_std: np.ndarray
    class_prob: np.ndarray
    existence: float
    hinge_prob: np.ndarray
    door_rect: np.ndarray
    door_q: np.ndarray
    q_drawer: float
    q_std: float
    handle: np.ndarray | None
    handle_score: float
    views: int
    visible: int
    merged: int
    shelf: bool
    readings: list[Reading] = field(default_factory=list, repr=False)
    handle_style: str = "bar"
    handle_along: str | None = None

    @property
    def joint_type(self) -> str:
        """The most probable joint type."""
        return TYPES[int(np.argmax(self.class_prob))]

    @property
    def side(self) -> str:
        """The most probable hinge side."""
        return SIDES[int(np.argmax(self.hinge_prob))]


@dataclass(frozen=True)
class FusedCabinet:
    """The fusion's result: the front and the part hypotheses (largest first)."""

    front: FrontFrame
    parts: list[PartHypothesis]
    seconds: float


# --- the front plane ------------------------------------------------------------------
def fit_front(
    points: np.ndarray,
    normals: np.ndarray,
    carcass: np.ndarray,
    cameras: np.ndarray,
    max_depth: float | None = MAX_DEPTH,
) -> tuple[np.ndarray, float, np.ndarray]:
    """The cabinet's front: a vertical plane facing the cameras.

    The normal: drawer fronts, closed doors, panels and the carcass's front edges all
    share it, so it is the peak of the histogram (1 deg bins) of the horizontal
    directions of the points' surface normals that face the cameras within 60 deg,
    refined by the mean of the normals within 4 deg of the peak. The offset: the points'
    offsets along the normal (4 mm bins) have peaks at the front, at open drawers' fronts
    (in front of it, no carcass), at the back panel seen through open cells (behind it)
    and at thin carcass-looking strips (an open door's edge); the front is the peak with
    the most carcass points on it less twice the carcass points 2 cm or more in front of
    it (the carcass lies behind its front), among the peaks with at most ``max_depth``
    of carcass behind them (None: any).

    Args:
        points: (N, 3) world points of the cabinet [m]; normals: (N, 3) their unit
            normals (zero if unknown).
        carcass: (N,) bool, the points classed carcass.
        cameras: (K, 3) camera positions [m].

    Returns:
        ``(unit horizontal normal (3,), offset d with n . p = d on the plane [m],
        inlier mask (N,))``.
    """
    eye = cameras.mean(axis=0)
    to_eye = eye[:2] - points[:, :2]
    to_eye /= np.maximum(np.linalg.norm(to_eye, axis=1, keepdims=True), 1e-9)
    h = normals[:, :2]
    hn = np.linalg.norm(h, axis=1)
    use = (np.abs(normals[:, 2]) < 0.5) & (hn > 0.5)
    use &= (h * to_eye).sum(axis=1) > 0.5 * np.maximum(hn, 1e-9)
    if use.sum() < 20:
        raise NoCabinetError("no vertical cabinet front facing the camera was found")
    yaw = np.degrees(np.arctan2(h[use, 1], h[use, 0]))
    hist = np.bincount(np.floor(yaw + 180.0).astype(int) % 360, minlength=360)
    smooth = hist + np.roll(hist, 1) + np.roll(hist, -1)
    peak = np.radians(int(np.argmax(smooth)) + 0.5 - 180.0)
    near = np.abs((yaw - np.degrees(peak) + 180.0) % 360.0 - 180.0) < 4.0
    m = h[use][near].mean(axis=0)
    n = np.array([m[0], m[1], 0.0]) / np.linalg.norm(m)
    off = points @ n
    lo = off.min()
    idx = ((off - lo) / 0.004).astype(int)
    hist = np.bincount(idx)
    hist_c = np.bincount(idx[carcass], minlength=len(hist))
    smooth = np.convolve(hist, np.ones(3), "same")
    smooth_c = np.convolve(hist_c, np.ones(3), "same")
    peaks = [
        k for k in range(len(smooth))
        if smooth[k] == smooth[max(0, k - 2) : k + 3].max() and smooth[k] >= 0.05 * smooth.max()
    ]  # fmt: skip
    # Carcass on the plane, minus twice the carcass in front of it (2 cm and more).
    ahead = np.cumsum(hist_c[::-1])[::-1]  # carcass points in bin k and beyond
    score = [smooth_c[k] - 2.0 * (ahead[k + 5] if k + 5 < len(ahead) else 0) for k in peaks]
    # No carcass is deeper than the generator's 0.45 m: a plane with carcass further
    # behind it is an open drawer's front.
    if max_depth is not None and carcass.sum() >= 20:
        back = float(np.percentile(off[carcass], 2.0))
        score = [
            sc if lo + (k + 0.5) * 0.004 - back <= max_depth else -np.inf
            for k, sc in zip(peaks, score, strict=True)
        ]
    k = peaks[int(np.argmax(score))] if peaks and max(score) > -np.inf else int(np.argmax(smooth))
    d = float(lo + (k + 0.5) * 0.004)
    inl = np.abs(off - d) < PLANE_TOL
    d = float(np.median(off[inl]))
    return n, d, np.abs(off - d) < PLANE_TOL


def _run(v: np.ndarray, bin_size: float = 0.01, max_gap: int = 8) -> tuple[float, float]:
    """The extent of the contiguous run (gaps of at most ``max_gap`` empty bins) of the
    values ``v`` [m] that holds their median: stray points (a table pixel called
    carcass) outside the cabinet do not widen it."""
    lo = float(v.min())
    idx = ((v - lo) / bin_size).astype(int)
    occupied = np.bincount(idx) > 0
    # Start at the occupied bin nearest the median (the median may fall in a gap).
    filled = np.flatnonzero(occupied)
    k0 = k1 = int(filled[np.argmin(np.abs(filled - int((np.median(v) - lo) / bin_size)))])
    gap = 0
    while k1 + 1 < len(occupied) and gap <= max_gap:
        k1 += 1
        gap = 0 if occupied[k1] else gap + 1
    k1 -= gap
    gap = 0
    while k0 > 0 and gap <= max_gap:
        k0 -= 1
        gap = 0 if occupied[k0] else gap + 1
    k0 += gap
    inside = v[(idx >= k0) & (idx <= k1)]
    return float(inside.min()), float(inside.max())


def front_frame(views: Sequence[ViewParts], max_depth: float | None = MAX_DEPTH) -> FrontFrame:
    """The :class:`FrontFrame` from the cabinet points of every view (``max_depth``:
    :func:`fit_front`'s)."""
    seen = [v for v in views if v.sees_cabinet]
    if not seen:
        raise NoCabinetError(
            f"no cabinet in view: at most {max((len(v.cabinet_points) for v in views), default=0)} "
            "cabinet pixels in any of the views"
        )
    pts = np.concatenate([v.cabinet_points for v in seen])
    cams = np.stack([v.T_world_camera[:3, 3] for v in seen])
    carcass = np.concatenate([v.cabinet_class == 1 for v in seen])
    normals = np.concatenate([v.cabinet_normals for v in seen])
    n, d, inl = fit_front(pts, normals, carcass, cams, max_depth)
    z = np.array([0.0, 0.0, 1.0])
    y = np.cross(z, n)
    R = np.stack([n, y, z], axis=1)
    local_y = pts @ y
    local_z = pts[:, 2]
    ahead = pts @ n - d
    # The front's extent: the plane's points and those up to OVERLAY in front of it
    # (overlay fronts, and the face frame they sit on, may cover most of a real front
    # whose largest plane is a blind panel behind the frame).
    ext = (ahead > -PLANE_TOL) & (ahead < OVERLAY)  # holds the plane's inliers
    y0, y1 = _run(local_y[ext])
    if y1 - y0 < MIN_FRONT:  # a broken run: fall back to the inliers' percentiles
        y0, y1 = (float(v) for v in np.percentile(local_y[ext], [1.0, 99.0]))
    z0, z_top = _run(local_z[ext])
    if z_top - z0 < MIN_FRONT:
        z0, z_top = (float(v) for v in np.percentile(local_z[ext], [1.0, 99.0]))
    behind = d - pts @ n
    body = (local_y > y0 - 0.02) & (local_y < y1 + 0.02) & (behind > -0.02) & (behind < 0.7)
    body &= local_z < z_top + 0.02
    # The carcass bottom lies at most a plinth and a board (10 cm) below the front's
    # lowest point; below that, points called cabinet are the table or its legs.
    body &= local_z > z0 - 0.1
    z_bot = min(_run(local_z[body])[0], z0) if body.sum() > 20 else z0
    depth_seen = float(np.percentile(behind[body], 99.0)) if body.sum() > 20 else 0.0
    seen_ok = depth_seen > 0.25
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = n * d + y * (0.5 * (y0 + y1)) + z * z_bot  # n and y are horizontal
    return FrontFrame(
        T_world_front=T,
        width=float(y1 - y0),
        height=z_top - z_bot,
        depth=float(np.clip(depth_seen, 0.25, 0.6)) if seen_ok else DEFAULT_DEPTH,
        depth_seen=bool(seen_ok),
        inliers=int(inl.sum()),
    )


# --- one instance ---------------------------------------------------------------------
def _extent(v: np.ndarray) -> tuple[float, float]:
    lo, hi = np.percentile(v, [1.0, 99.0])
    return float(lo), float(hi)


def _panel_plane(P: np.ndarray, iterations: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A panel's plane from its points (N, 3), refitted on the points near it (within 1 cm
    or twice the median residual): ``(centroid, unit normal with x >= 0, inliers)``.
    Pixels of something else in the instance (the cell's inside seen past an open
    door) would otherwise tilt the plane and widen the panel."""
    pts = P
    for _ in range(iterations):
        c = pts.mean(axis=0)
        _, _, vt = np.linalg.svd(pts - c, full_matrices=False)
        res = np.abs((P - c) @ vt[2])
        keep = res < max(0.01, 2.0 * float(np.median(res)))
        if keep.sum() < 10:
            break
        pts = P[keep]
    c = pts.mean(axis=0)
    _, _, vt = np.linalg.svd(pts - c, full_matrices=False)
    m = vt[2] if vt[2][0] >= 0 else -vt[2]
    return c, m, pts


def read_instance(
    view: int, inst: Instance, front: FrontFrame, seen_in: ViewParts | None = None
) -> Reading:
    """Interpret one instance under every joint type (module docstring, step 2).

    Rectangles are cells: the seen front's extents widened by :data:`FRONT_GAP`.
    ``seen_in`` is the view the instance is from (its camera and image size): with it,
    the sides that run off the image are marked (``Reading.cut``); without it none are.
    """
    P = front.to_front(inst.points)
    x = P[:, 0]
    depth_x = float(np.median(x))
    face = np.abs(x - depth_x) < 0.015
    face = face if face.sum() >= 10 else np.ones_like(face)
    ylo, yhi = _extent(P[face, 1])
    zlo, zhi = _extent(P[face, 2])
    g = FRONT_GAP
    face_rect = np.array([ylo - g, yhi + g, zlo - g, zhi + g])
    door_rect = np.tile(face_rect, (4, 1))
    door_q = np.zeros(4)
    ok = np.ones(4, dtype=bool)
    c, m, P = _panel_plane(P)
    tilt = math.acos(min(1.0, abs(float(m[0]))))
    closed = tilt < DOOR_OPEN_TILT
    primary = None
    moved_out = closed and depth_x > MOVED_OUT  # still parallel: only a drawer does that
    turned_out = False
    if not closed:
        ok[:] = False
        side_door = abs(float(m[1])) > abs(float(m[2]))  # turned about a vertical line
        e = np.array([-m[1], m[0], 0.0]) if side_door else np.cross(m, [0.0, 1.0, 0.0])
        e /= max(np.linalg.norm(e), 1e-9)  # in the panel, across the hinge
        s_lo, s_hi = _extent((P - c) @ e)
        ends = (c + s_lo * e, c + s_hi * e)
        hinge, free = ends if ends[0][0] <= ends[1][0] else ends[::-1]  # hinge: nearer the front
        w = s_hi - s_lo
        dirn = free - hinge
        turned_out = abs(hinge[0]) < 0.04 and free[0] > 0.05  # about an edge on the front
        u = dirn / max(float(np.linalg.norm(dirn)), 1e-9)
        # The hinge end hidden (a flap open above shades it): the hinge is where the
        # panel's plane meets the front plane, on the seen (outer) face of a side door
        # or a lifted top flap.
        back = float(hinge[0]) / u[0] if u[0] > 0.1 else math.inf
        hidden = hinge[0] > HIDDEN_HINGE and (side_door or u[2] < 0) and back < MAX_HIDDEN
        if hidden:
            hinge = hinge - back * u
            w += back
        if side_door:
            theta = math.atan2(max(dirn[0], 0.0), abs(dirn[1]))
            first, second = (0, 1) if dirn[1] > 0 else (1, 0)  # left if the free edge is to +y
            y_h = float(hinge[1])
            spans = {0: (y_h - g, y_h + w + g), 1: (y_h - w - g, y_h + g)}
            for side, q in ((first, theta), (second, math.pi - theta)):
                if q <= SIDE_DOOR_MAX:
                    ok[side] = True
                    door_q[side] = q
                    door_rect[side] = [*spans[side], zlo - g, zhi + g]
            primary = first
        else:
            theta = math.atan2(max(dirn[0], 0.0), abs(dirn[2]))
            side = 2 if dirn[2] < 0 else 3  # top hinge if the free edge hangs below
            # A top hinge sits on the panel's back face: the seen edge rose by about
            # FRONT_THICKNESS * sin(theta) as it turned.
            # (On the front plane, extrapolated: FRONT_THICKNESS * tan(theta / 2).)
            rise = math.tan(0.5 * theta) if hidden else math.sin(theta)
            z_h = float(hinge[2]) - (FRONT_THICKNESS * rise if side == 2 else 0.0)
            ylo2, yhi2 = _extent(P[:, 1])
            span = (z_h - w - g, z_h + g) if side == 2 else (z_h - g, z_h + w + g)
            ok[side] = True
            door_q[side] = theta
            door_rect[side] = [ylo2 - g, yhi2 + g, *span]
            primary = side
    as_door = primary is not None and inst.class_prob[2] >= inst.class_prob[1]
    rect = door_rect[primary].copy() if as_door else face_rect
    cut = np.zeros(4, dtype=bool)
    if seen_in is not None:
        cut = cut_sides(inst.mask, face_rect, depth_x, front, seen_in)
    return Reading(
        view, inst, rect, face_rect, max(depth_x, 0.0), door_rect, door_q, ok, closed, depth_x,
        bool(moved_out), bool(turned_out), cut,
    )  # fmt: skip


def _project(p: np.ndarray, view: ViewParts) -> np.ndarray | None:
    """Pixel ``(u, v)`` (network resolution; ``v`` down from the top row) of world
    point ``p`` (3,) in ``view``, or None behind (or within 5 cm of) the camera."""
    T = view.T_world_camera
    pc = T[:3, :3].T @ (np.asarray(p, dtype=float) - T[:3, 3])
    if pc[2] >= -0.05:
        return None
    h, w = view.shape
    f = 0.5 * h / math.tan(0.5 * view.fovy)
    return np.array([pc[0] / -pc[2] * f + 0.5 * w, -pc[1] / -pc[2] * f + 0.5 * h])


def cut_sides(
    mask: np.ndarray, rect: np.ndarray, depth_x: float, front: FrontFrame, view: ViewParts
) -> np.ndarray:
    """Which sides ``(y0, y1, z0, z1)`` of ``rect`` (front frame [m], at front-frame
    ``x = depth_x``) run off ``view``'s image: (4,) bool, True where the image border
    that the side faces (its outward direction projected at the rectangle's centre)
    holds at least :data:`CUT_PIXELS` of the instance's ``mask`` (h, w)."""
    borders = {
        "top": int(mask[0].sum()), "bottom": int(mask[-1].sum()),
        "left": int(mask[:, 0].sum()), "right": int(mask[:, -1].sum()),
    }  # fmt: skip
    centre = np.array([depth_x, 0.5 * (rect[0] + rect[1]), 0.5 * (rect[2] + rect[3])])
    cut = np.zeros(4, dtype=bool)
    uv0 = _project(front.to_world(centre), view)
    if uv0 is None:
        return cut
    for k, (axis, sign) in enumerate(((1, -1.0), (1, 1.0), (2, -1.0), (2, 1.0))):
        step = np.zeros(3)
        step[axis] = 0.05 * sign
        uv = _project(front.to_world(centre + step), view)
        if uv is None:
            continue
        du, dv = uv - uv0
        if abs(dv) >= abs(du):
            border = "bottom" if dv > 0 else "top"
        else:
            border = "right" if du > 0 else "left"
        cut[k] = borders[border] >= CUT_PIXELS
    return cut


# --- association ----------------------------------------------------------------------
def rect_iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two rectangles ``(y0, y1, z0, z1)``."""
    iy = max(0.0, min(a[1], b[1]) - max(a[0], b[0]))
    iz = max(0.0, min(a[3], b[3]) - max(a[2], b[2]))
    inter = iy * iz
    union = (a[1] - a[0]) * (a[3] - a[2]) + (b[1] - b[0]) * (b[3] - b[2]) - inter
    return inter / union if union > 0 else 0.0


def _covered(inner: np.ndarray, outer: np.ndarray) -> float:
    """Share of ``inner``'s area inside ``outer``."""
    iy = max(0.0, min(inner[1], outer[1]) - max(inner[0], outer[0]))
    iz = max(0.0, min(inner[3], outer[3]) - max(inner[2], outer[2]))
    area = (inner[1] - inner[0]) * (inner[3] - inner[2])
    return iy * iz / area if area > 0 else 0.0


def _visible(rect: np.ndarray, front: FrontFrame, view: ViewParts) -> bool:
    """Whether the rectangle's centre projects into ``view``'s image."""
    p = front.to_world(np.array([0.0, 0.5 * (rect[0] + rect[1]), 0.5 * (rect[2] + rect[3])]))
    uv = _project(p, view)
    if uv is None:
        return False
    h, w = view.shape
    return bool(0 <= uv[0] < w and 0 <= uv[1] < h)


def fuse_sides(rects: np.ndarray, cut: np.ndarray, weights: np.ndarray | None) -> np.ndarray:
    """One rectangle ``(y0, y1, z0, z1)`` from the readings' ``rects`` (N, 4) [m], side
    by side from the readings that see the side end (``cut`` (N, 4) False): their
    median, or with ``weights`` (N,) and at most two of them their weighted mean.
    Where every reading runs off its image on a side, the farthest of them: each is a
    bound the part reaches at least."""
    out = np.empty(4)
    for k in range(4):
        ends = ~cut[:, k]
        if not ends.any():
            out[k] = rects[:, k].min() if k % 2 == 0 else rects[:, k].max()
            continue
        v = rects[ends, k]
        if weights is None or len(v) > 2:
            out[k] = float(np.median(v))
        else:
            w = weights[ends]
            out[k] = float((w * v).sum() / w.sum())
    return out


def _handle_cue(handle: np.ndarray, rect: np.ndarray) -> np.ndarray:
    """Hinge-side likelihoods (4,) from where a closed door's handle sits: handles are
    near the free edge (the generator puts them 3-6 cm in from it), so a handle right of
    the centre (+y) means a left hinge, one below the centre a top hinge."""
    u = (handle[1] - 0.5 * (rect[0] + rect[1])) / max(0.5 * (rect[1] - rect[0]), 1e-3)
    v = (handle[2] - 0.5 * (rect[2] + rect[3])) / max(0.5 * (rect[3] - rect[2]), 1e-3)
    e = np.exp(HANDLE_CUE * np.array([u, -u, -v, v]))
    return e / e.sum()


def _weighted_median(v: np.ndarray, w: np.ndarray) -> float:
    """The median of values ``v`` (N,) under weights ``w`` (N,): a fragment seen in
    one view does not pull a drawer's opening to its own."""
    order = np.argsort(v, kind="stable")
    c = np.cumsum(w[order])
    return float(v[order][np.searchsorted(c, 0.5 * c[-1])])


def _existence(group: list[Reading], *visible: int) -> float:
    """Confidence-weighted share of the views that could see a part that did: per view
    its most confident reading (pieces of one front count once), over the most views
    that could see it (``visible``), with a prior of 0.1 in 0.2."""
    conf: dict[int, float] = {}
    for r in group:
        conf[r.view] = max(conf.get(r.view, 0.0), r.instance.part_prob)
    return float(min((sum(conf.values()) + 0.1) / (max(*visible, len(conf)) + 0.2), 1.0))


def _summarise(
    group: list[Reading], merged: int, visible: int, front: FrontFrame
) -> PartHypothesis:
    wts = np.array([r.instance.pixels for r in group], dtype=float)
    wts /= wts.sum()
    rects = np.stack([r.face_rect for r in group])
    rect = fuse_sides(rects, np.stack([r.cut for r in group]), wts)
    # Each view's probabilities already hold its geometric evidence (joint_cues).
    cls = (wts[:, None] * np.stack([r.instance.class_prob for r in group])).sum(axis=0) + 1e-9
    net = (wts[:, None] * np.stack([r.instance.hinge_prob for r in group])).sum(axis=0)
    # Geometry: an open panel allows only the sides it can be hinged on.
    ok = np.all(np.stack([r.door_ok for r in group]), axis=0)
    if not ok.any():
        ok = np.stack([r.door_ok for r in group]).any(axis=0)
    hinge = np.where(ok, net, 0.0) + 1e-6
    door_q = np.zeros(4)
    door_rect = np.tile(rect, (4, 1))
    for k in range(4):
        rows = [r for r in group if r.door_ok[k]]
        if rows:
            door_q[k] = float(np.median([r.door_q[k] for r in rows]))
            door_rect[k] = fuse_sides(
                np.stack([r.door_rect[k] for r in rows]),
                np.stack([r.door_cut[k] for r in rows]),
                None,
            )
    existence = _existence(group, visible)
    handles = [
        (r.instance.handle, r.instance.handle_score) for r in group if r.instance.handle is not None
    ]
    handle = (
        front.to_front(np.median(np.stack([h for h, _ in handles]), axis=0)) if handles else None
    )
    middle = handle_middle(np.concatenate([r.instance.handle_points for r in group]), front)
    if handle is not None and middle is not None:
        # On the front, the handle's middle; off it, the peak's standoff: the affordance
        # spreads onto the face around a handle (see BAR_MIN_LENGTH): a median sinks.
        handle = np.array([handle[0], *middle])
    if handle is not None and all(r.closed_door for r in group):
        hinge = hinge * _handle_cue(handle, rect)
    style, along = handle_shape([r.instance.handle_points for r in group], front)
    return PartHypothesis(
        rect=rect,
        rect_std=rects.std(axis=0),
        class_prob=cls / cls.sum(),
        existence=existence,
        hinge_prob=hinge / hinge.sum(),
        door_rect=door_rect,
        door_q=door_q,
        q_drawer=_weighted_median(np.array([r.q_drawer for r in group]), wts),
        q_std=float(np.std([r.q_drawer for r in group])),
        handle=handle,
        handle_score=float(max((s for _, s in handles), default=0.0)),
        views=len({r.view for r in group}),
        visible=visible,
        merged=merged,
        shelf=float(np.median([r.depth_x for r in group])) < -0.04,
        readings=group,
        handle_style=style,
        handle_along=along,
    )


def handle_middle(points: np.ndarray, front: FrontFrame) -> np.ndarray | None:
    """The middle of a part's handle on its front: the median front-frame (y, z) (2,)
    [m] of its handle pixels' world points ``points`` (K, 3), all views together (a
    bar's middle, a knob's centre); None with fewer than :data:`MIN_HANDLE_PIXELS`.

    A view's grasp point is its pixel of highest pull affordance, which on a bar may
    lie anywhere along it (OpenDoor episode 10206's models grasped a 16 cm upright bar
    5.6 cm below its middle, 1.4 cm above its lower post). On the episodes 10130-10159
    the target's grasp point, weighted over the models, stood from the true middle along
    the bar by a median 1.8 cm on a door (10 of 30 over 3 cm) and 2.2 cm on a drawer
    (11 of 30); from this middle, 0.4 cm and 0.4 cm (none over 3 cm). The fused grasp
    point is moved to this middle (:func:`_summarise`), and the affordance grasps are
    drawn near it (:mod:`perception.affordance`)."""
    if len(points) < MIN_HANDLE_PIXELS:
        return None
    return np.median(front.to_front(points)[:, 1:], axis=0)


def handle_shape(views: Sequence[np.ndarray], front: FrontFrame) -> tuple[str, str | None]:
    """A handle's style and (a bar's) direction from its pixels in each view.

    ``views``: per view, the (K, 3) world points whose pull affordance exceeds 0.5.
    Each view with at least :data:`MIN_HANDLE_PIXELS` votes, weighted by its pixel
    count: a bar if the points stretch :data:`BAR_MIN_LENGTH` along their principal
    direction on the front plane and :data:`BAR_MIN_ELONGATION` times their spread
    across it there (how far the handle stands out is no part of its length), else a
    knob.
    The handle's shape stays as it is when its part turns or slides (a side door's bar
    is vertical, a flap's horizontal, open or not), so the direction is read in the
    front frame. No view with enough pixels: a bar, the generator's likelier style, its
    direction left to the part's kind (None).

    Returns:
        (``"bar"`` or ``"knob"``, ``"y"``, ``"z"`` or None).
    """
    bar = knob = 0.0
    along = np.zeros(2)  # votes for y, z
    for pts in views:
        if len(pts) < MIN_HANDLE_PIXELS:
            continue
        c = front.to_front(pts)[:, 1:]  # on the front: a bar's standoff is not its length
        c = c - c.mean(axis=0)
        _, _, vt = np.linalg.svd(c, full_matrices=False)
        long = float(np.ptp(c @ vt[0]))
        across = float(np.ptp(c @ vt[1]))
        if long >= BAR_MIN_LENGTH and long >= BAR_MIN_ELONGATION * across:
            bar += len(pts)
            along[int(abs(vt[0][1]) > abs(vt[0][0]))] += len(pts)
        else:
            knob += len(pts)
    if bar == knob == 0.0:
        return "bar", None
    if knob > bar:
        return "knob", None
    return "bar", "yz"[int(np.argmax(along))]


def _candidates(r: Reading) -> list[np.ndarray]:
    """The closed-state rectangles a reading may stand for: as seen, as associated, and
    as a door hinged on each side its geometry allows."""
    return [r.rect, r.face_rect, *(r.door_rect[k] for k in range(4) if r.door_ok[k])]


def _match(r: Reading, ref: Reading) -> float:
    """How well reading ``r`` matches a group's reference reading: the best IoU over
    their pairs of candidate rectangles, or :data:`HINGE_MATCH` for two open panels
    turned about one hinge line (:func:`_same_hinge`), whose rectangles differ with
    how much of the panel each view saw."""
    iou = max(rect_iou(a, b) for a in _candidates(r) for b in _candidates(ref))
    return max(iou, HINGE_MATCH) if _same_hinge(r, ref) else iou


def _same_hinge(a: Reading, b: Reading) -> bool:
    """Two open panels with a hinge side both allow, their hinge lines within
    :data:`HINGE_TOL` of each other, their openings within :data:`OPENING_TOL`, and
    overlapping along the hinge by half the shorter one."""
    if a.closed_door or b.closed_door:
        return False
    for k in range(4):
        if not (a.door_ok[k] and b.door_ok[k]):
            continue
        edge = (0, 1, 3, 2)[k]  # the rectangle's coordinate on the hinge line
        ra, rb = a.door_rect[k], b.door_rect[k]
        lo, hi = (2, 3) if k < 2 else (0, 1)  # along the hinge
        overlap = min(ra[hi], rb[hi]) - max(ra[lo], rb[lo])
        shorter = min(ra[hi] - ra[lo], rb[hi] - rb[lo])
        if (
            abs(ra[edge] - rb[edge]) < HINGE_TOL
            and abs(a.door_q[k] - b.door_q[k]) < OPENING_TOL
            and overlap > 0.5 * shorter
        ):
            return True
    return False


def _apart(a: np.ndarray, b: np.ndarray) -> bool:
    """Two closed-state rectangles lie apart by at least :data:`MERGE_GAP` (a divider
    between two cells), in y or in z."""
    return max(max(a[0], b[0]) - min(a[1], b[1]), max(a[2], b[2]) - min(a[3], b[3])) >= MERGE_GAP


def _associate(readings: list[Reading]) -> tuple[list[list[Reading]], list[int]]:
    """Readings (smallest first) into groups of one part each, and per group the views
    in which it was part of a merged region (module docstring, step 3).

    A reading whose best group already holds a reading of its view takes that place if
    it matches the group's reference (its largest reading) better by
    :data:`SWAP_MARGIN`; the reading it displaces is placed again (at most
    :data:`MAX_EVICTIONS` times). Small fragments (a strip of an open cell) otherwise
    keep the view's slot of a part whose whole front that view saw, and the front
    starts a second hypothesis of the same part."""
    queue = deque(readings)
    groups: list[list[Reading]] = []
    refs: list[Reading] = []  # each group's largest reading
    merged: list[int] = []
    evicted: Counter[int] = Counter()
    while queue:
        r = queue.popleft()
        # A merged region: it covers two or more parts that each fill little of it.
        covered = [
            k for k, g in enumerate(refs)
            if _covered(g.rect, r.rect) > 0.7 and rect_iou(g.rect, r.rect) < 0.6
            and min(g.face_rect[1] - g.face_rect[0], g.face_rect[3] - g.face_rect[2]) >= MIN_PART
        ]  # fmt: skip
        if any(_apart(refs[i].rect, refs[j].rect) for i in covered for j in covered):
            for k in covered:
                merged[k] += 1
            continue
        scores = [_match(r, g) for g in refs]
        placed = False
        for k in np.argsort(scores, kind="stable")[::-1]:
            if scores[k] < ASSOC_IOU:
                break
            occupant = next((g for g in groups[k] if g.view == r.view), None)
            if occupant is not None:
                if evicted[id(occupant)] >= MAX_EVICTIONS or occupant is refs[k]:
                    continue
                if scores[k] < _match(occupant, refs[k]) + SWAP_MARGIN:
                    continue
                groups[k] = [g for g in groups[k] if g is not occupant]
                evicted[id(occupant)] += 1
                queue.appendleft(occupant)
            groups[k].append(r)
            refs[k] = max(groups[k], key=lambda g: (g.instance.pixels, -g.view))
            placed = True
            break
        if not placed:
            groups.append([r])
            refs.append(r)
            merged.append(0)
    return groups, merged


def fuse(views: Sequence[ViewParts]) -> FusedCabinet:
    """Fuse the views of one cabinet (module docstring).

    Raises:
        NoCabinetError: no view shows a cabinet.
    """
    t0 = time.perf_counter()
    front = front_frame(views)
    readings = [
        read_instance(i, inst, front, v)
        for i, v in enumerate(views)
        if v.sees_cabinet
        for inst in v.instances
    ]
    # A part lies on the cabinet's front: a reading mostly outside it is no part.
    box = np.array(
        [-0.5 * front.width - 0.05, 0.5 * front.width + 0.05, -0.05, front.height + 0.05]
    )
    readings = [r for r in readings if _covered(r.rect, box) > 0.8]
    readings.sort(key=lambda r: (r.instance.pixels, r.view))
    groups, merged = _associate(readings)
    parts = []
    for grp, mg in zip(groups, merged, strict=True):
        rect = np.median(np.stack([g.rect for g in grp]), axis=0)
        visible = sum(_visible(rect, front, v) for v in views if v.sees_cabinet)
        parts.append(_summarise(grp, mg, visible, front))
    parts = _join_open_fragments(parts)
    parts.sort(key=lambda p: -(p.rect[1] - p.rect[0]) * (p.rect[3] - p.rect[2]))
    return FusedCabinet(front, parts, time.perf_counter() - t0)


def _join_open_fragments(parts: list[PartHypothesis]) -> list[PartHypothesis]:
    """Join drawer hypotheses that are pieces of one open drawer front: both pulled out
    (more than 2 cm) by the same amount (within 1 cm), side by side or one above the
    other within 8 cm, spanning the same rows or columns. Two real drawers are rarely
    pulled out by the same centimetre; when they are, a divider separates them, so two
    hypotheses seen in three views or more join only if they lie closer than
    :data:`MERGE_GAP`."""
    out = list(parts)
    joined = True
    while joined:
        joined = False
        for i in range(len(out)):
            for j in range(i + 1, len(out)):
                a, b = out[i], out[j]
                if a.joint_type != "prismatic" or b.joint_type != "prismatic":
                    continue
                if min(a.q_drawer, b.q_drawer) < 0.02 or abs(a.q_drawer - b.q_drawer) > 0.01:
                    continue
                ra, rb = a.rect, b.rect
                gap_y = max(ra[0], rb[0]) - min(ra[1], rb[1])
                gap_z = max(ra[2], rb[2]) - min(ra[3], rb[3])
                span_z = min(ra[3], rb[3]) - max(ra[2], rb[2])
                span_y = min(ra[1], rb[1]) - max(ra[0], rb[0])
                # Two fronts each seen whole from most views, a divider apart: two drawers.
                reach = MERGE_GAP if min(a.views, b.views) >= 3 else 0.08
                side = gap_y < reach and span_z > 0.8 * min(ra[3] - ra[2], rb[3] - rb[2])
                stack = gap_z < reach and span_y > 0.8 * min(ra[1] - ra[0], rb[1] - rb[0])
                if not (side or stack):
                    continue
                rect = np.array([min(ra[0], rb[0]), max(ra[1], rb[1]),
                                 min(ra[2], rb[2]), max(ra[3], rb[3])])  # fmt: skip
                big, small = (a, b) if a.views * a.existence >= b.views * b.existence else (b, a)
                readings = big.readings + small.readings
                seen = big if big.handle is not None else small  # whose handle it keeps
                out[i] = dataclasses.replace(
                    big,
                    rect=rect,
                    door_rect=np.tile(rect, (4, 1)),
                    existence=max(a.existence, b.existence, _existence(readings, a.visible,
                                                                       b.visible)),
                    views=len({r.view for r in readings}),
                    handle=seen.handle,
                    handle_style=seen.handle_style,
                    handle_along=seen.handle_along,
                    readings=readings,
                )  # fmt: skip
                del out[j]
                joined = True
                break
            if joined:
                break
    return out
