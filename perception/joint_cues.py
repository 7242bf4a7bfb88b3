"""Joint-type evidence from one view's geometry: what the network's class head cannot
be trusted with on its own.

The network reads a front's joint type from its looks; its mistakes on the tuning
cabinets have geometric causes (figures: the README's perception section):

* an open bottom-hinged flap (a board turned down in front of its cell) is taken for
  an open drawer;
* a closed flap with its handle by the top or bottom edge is taken for a drawer;
* a closed front without a handle is taken for a fixed panel, even when the cabinet has
  no handles at all (then panels, drawers and doors look the same).

:func:`apply_joint_cues` fits the front plane from the one view
(:func:`perception.fusion.front_frame`), reads each instance on it
(:func:`perception.fusion.read_instance`) and multiplies the network's class
probabilities by likelihoods of (fixed, prismatic, revolute) from what the depth and the
pull-affordance map show. Each cue leaves the types it rules out with
:data:`CUE_EVIDENCE` (not zero: the network and the cue may both be wrong):

* **an open front.** A face parallel to the front plane, at least
  :data:`FACE_MIN` x :data:`FACE_MIN` and moved out by more than :data:`FACE_OUT`,
  flat within 1 cm in depth: a drawer's front, pulled out. Most of its surface
  (:data:`TILTED_SHARE`) turned more than :data:`AXIS_TOL` from every axis of the front
  frame: a panel turned about a hinge, a door (drawer boxes are axis-aligned boards).
  The reading's own geometry counts too (:class:`perception.fusion.Reading`'s
  ``moved_out`` and ``turned_out``).
* **a closed front with a handle** (:data:`MIN_HANDLE_PIXELS` pull pixels inside its
  face). The handle's centre, in units of the face's half-extents from its centre:
  within :data:`CENTRED` a drawer's (the generator centres them), beyond
  :data:`OFF_CENTRE` a door's (door handles sit 3-6 cm in from the free edge: at least
  half-way out); a vertical bar is a side door's (drawer and flap bars are horizontal).
* **a closed front without a handle.** If the view shows handles on other fronts, the
  cabinet has handles and this is probably a fixed panel (:data:`PANEL_EVIDENCE` on
  drawer and door, mild: a handle can be missed). If the view shows none, the cabinet
  has no handles: panel, drawer and door are told apart by nothing, so fixed keeps
  :data:`CUE_EVIDENCE` (the generator's panels are 0.15 of the cells against 0.70 for
  drawers and doors) and drawer and door share the rest as such fronts are drawers
  and doors in the training distribution (:data:`UNSEEN_SPLIT`): the network's split
  between them is noise there, and the prior's larger share is the best guess.

The evidence uses one view only, so the per-view type is this view's
(:class:`perception.parts.Instance`'s ``class_prob``; ``net_class_prob`` keeps the
network's); fusion averages the views' probabilities.
"""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np

from perception.errors import NoCabinetError
from perception.fusion import FrontFrame, Reading, front_frame, read_instance
from perception.instances import ViewParts

#: Likelihood left to the joint types a cue rules out.
CUE_EVIDENCE = 0.1
#: Likelihood of drawer and door for a closed front without a handle in a view that
#: shows handles elsewhere.
PANEL_EVIDENCE = 0.5
#: (drawer, door) shares of a closed movable front in a cabinet without handles, where
#: nothing in the pixels tells them apart. Counted per view on the training split,
#: ``python tools/unseen_front_prior.py --seeds 100000:100800``: 420 views of such
#: drawers against 529 of doors and flaps.
UNSEEN_SPLIT = (0.44, 0.56)
#: A drawer's moved-out face: at least this wide and high [m] ...
FACE_MIN = 0.05
#: ... more than this in front of the front plane [m] ...
FACE_OUT = 0.02
#: ... and at least this many pixels (network resolution) with normals within
#: :data:`AXIS_TOL` of the front's normal.
FACE_PIXELS = 20
#: A surface normal within this of an axis of the front frame is axis-aligned [rad].
AXIS_TOL = math.radians(15.0)
#: Share of an instance's surface turned away from every axis that makes it a door.
TILTED_SHARE = 0.5
#: Handle pixels (pull probability > 0.5) inside a face that make it a handled front.
MIN_HANDLE_PIXELS = 3
#: Handle centre offsets (in half-extents of the face) of a drawer's and a door's handle.
CENTRED, OFF_CENTRE = 0.3, 0.4
#: A front flat on the front plane lies within this of it [m] (median depth).
FLAT = 0.02
#: A front *reads as furniture* (:func:`reads_as_furniture`) when more than
#: :data:`TEXTURED_SHARE` of its inner pixels have a luminance gradient above
#: :data:`TEXTURE_EDGE` grey levels (3x3 Sobel). On the tuning cabinets' fronts
#: (3000:3008 plain, 3100:3108 furniture, 117 and 116 instances) the share was 0 on
#: half the plain ones and at most 0.13 on 90%, against a median of 0.30 on furniture
#: fronts, whose lowest 10% are painted slabs (those never carry a raised pull).
TEXTURE_EDGE, TEXTURED_SHARE = 20.0, 0.15
#: Inner pixels needed to judge a front's look (network resolution).
LOOK_PIXELS = 30


@dataclasses.dataclass(frozen=True)
class HandleSeen:
    """A handle on a front, in the front frame.

    Attributes:
        u, v: its centre's offset from the face's centre, in half-widths and
            half-heights (-1..1 inside the face).
        width, height: extent of its pixels along y and z [m].
        pixels: handle pixels.
    """

    u: float
    v: float
    width: float
    height: float
    pixels: int

    @property
    def vertical_bar(self) -> bool:
        """A bar standing upright (a side door's)."""
        return self.height > 2.0 * self.width and self.height > 0.04


def handle_on_face(points: np.ndarray, face: np.ndarray) -> HandleSeen | None:
    """The handle whose pixels' front-frame points (N, 3) [m] lie on the face
    ``(y0, y1, z0, z1)`` [m], or None (too few pixels, or their centre is off the face:
    a neighbour's handle)."""
    if len(points) < MIN_HANDLE_PIXELS:
        return None
    c = np.median(points, axis=0)
    u = (c[1] - 0.5 * (face[0] + face[1])) / max(0.5 * (face[1] - face[0]), 1e-3)
    v = (c[2] - 0.5 * (face[2] + face[3])) / max(0.5 * (face[3] - face[2]), 1e-3)
    if max(abs(u), abs(v)) > 0.95:
        return None
    return HandleSeen(
        float(u), float(v), float(np.ptp(points[:, 1])), float(np.ptp(points[:, 2])), len(points)
    )


def open_front_evidence(r: Reading, P: np.ndarray, N: np.ndarray) -> np.ndarray:
    """Likelihoods (3,) of fixed, prismatic, revolute from an instance's front-frame
    points P (K, 3) [m] and unit normals N (K, 3) (module docstring, "an open front")."""
    g = CUE_EVIDENCE
    c = math.cos(AXIS_TOL)
    a = np.abs(N)
    along_x = a[:, 0] > c
    tilted = ~(along_x | (a[:, 1] > c) | (a[:, 2] > c))
    face = along_x & (P[:, 0] > FACE_OUT)
    drawer, door = r.moved_out, r.turned_out
    if face.sum() >= FACE_PIXELS:
        Q = P[face]
        drawer |= bool(
            np.ptp(Q[:, 1]) >= FACE_MIN and np.ptp(Q[:, 2]) >= FACE_MIN and Q[:, 0].std() < 0.01
        )
    door |= bool(len(N) > 0 and tilted.mean() >= TILTED_SHARE)
    if drawer == door:
        return np.ones(3)
    return np.array([g, 1.0, g]) if drawer else np.array([g, g, 1.0])


def reads_as_furniture(vp: ViewParts, mask: np.ndarray) -> bool | None:
    """Whether the front under ``mask`` (h, w) shows wood grain or a framed front's
    rails (:data:`TEXTURED_SHARE`), what no plain-style front has; None if the view has
    no texture map or too little of the front is clear of its edges and handle."""
    if vp.texture is None:
        return None
    kernel = np.ones((5, 5), np.uint8)
    inner = cv2.erode(mask.astype(np.uint8), kernel) > 0
    inner &= ~(cv2.dilate((vp.handle_prob > 0.3).astype(np.uint8), kernel) > 0)
    if inner.sum() < LOOK_PIXELS:
        return None
    return bool(np.mean(vp.texture[inner] > TEXTURE_EDGE) > TEXTURED_SHARE)


def closed_front_evidence(
    handle: HandleSeen | None, handles_elsewhere: bool, furniture: bool | None = None
) -> np.ndarray:
    """Likelihoods (3,) of fixed, prismatic, revolute of a closed front (module
    docstring); ``furniture``: the front reads as furniture (:func:`reads_as_furniture`;
    None: unknown). For a handle-less front in a handle-less view
    :func:`apply_joint_cues` sets the drawer and door shares to :data:`UNSEEN_SPLIT`."""
    g = CUE_EVIDENCE
    if handle is None:
        if handles_elsewhere:
            return np.array([1.0, PANEL_EVIDENCE, PANEL_EVIDENCE])
        return np.array([g, 1.0, 1.0])
    off = max(abs(handle.u), abs(handle.v))
    ev = np.array([g, 1.0, g]) if off < CENTRED else np.array([g, g, 1.0])
    if CENTRED <= off <= OFF_CENTRE:
        ev = np.array([g, 1.0, 1.0])
    elif off > OFF_CENTRE and abs(handle.u) < CENTRED and not handle.vertical_bar:
        # Centred across, by the top or bottom edge: a flap's on a plain front, but
        # furniture puts drawer pulls there too (41083): on a front that reads as
        # furniture (or whose look is unknown) no type is ruled out.
        ev = np.array([g, 1.0 if furniture is not False else g, 1.0])
    if handle.vertical_bar:
        ev[1] *= g
    return ev


def apply_joint_cues(vp: ViewParts, front: FrontFrame | None = None) -> ViewParts:
    """``vp`` with each instance's ``class_prob`` times its geometric evidence (module
    docstring), on ``front`` or (default) the front fitted from this view alone.
    A view without a cabinet front is returned as it is."""
    if not vp.instances or not vp.sees_cabinet:
        return vp
    if front is None:
        try:
            # One view may not see the carcass's back: no depth bound on its front.
            front = front_frame([vp], max_depth=None)
        except NoCabinetError:
            return vp
    R = front.T_world_front[:3, :3]
    kernel = np.ones((5, 5), np.uint8)
    seen = []
    for inst in vp.instances:
        r = read_instance(0, inst, front)
        near = cv2.dilate(inst.mask.astype(np.uint8), kernel) > 0
        hm = near & (vp.handle_prob > 0.5) & vp.valid
        seen.append((r, handle_on_face(front.to_front(vp.points[hm]), r.face_rect)))
    handled = sum(h is not None for _, h in seen)
    out = []
    for inst, (r, handle) in zip(vp.instances, seen, strict=True):
        p = inst.net_class_prob.copy()
        if r.closed_door and abs(r.depth_x) < FLAT:
            elsewhere = handled - (handle is not None) > 0
            ev = closed_front_evidence(handle, elsewhere, reads_as_furniture(vp, inst.mask))
            if handle is None and handled == 0:
                # A handle-less cabinet: drawer and door alike, the training prior decides.
                p[1:] = p[1:].sum() * np.asarray(UNSEEN_SPLIT)
        else:
            mv = inst.mask & vp.valid
            N = vp.normals[mv] @ R
            ok = np.linalg.norm(N, axis=1) > 0.5
            ev = open_front_evidence(r, front.to_front(vp.points[mv][ok]), N[ok])
        p = p * ev
        out.append(dataclasses.replace(inst, class_prob=p / p.sum()))
    return dataclasses.replace(vp, instances=out)
