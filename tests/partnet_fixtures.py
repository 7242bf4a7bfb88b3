"""PartNet-Mobility look-alike storage cabinets, written at test time.

Real PartNet-Mobility objects cannot be committed (licence), so tests write small
cabinets that look exactly like ``StorageFurniture`` downloads, quirks included:

* ``mobility.urdf`` as PartNet writes it (minidom, tab indents, ``<?xml version="1.0" ?>``):
  ``<robot name="partnet_<32 hex>">``, an empty ``<link name="base"/>``, parts
  ``link_0``, ``link_1``, ... each followed by its ``joint_i``, the carcass last, fixed
  to ``base`` with ``<origin rpy="1.570796326794897 0 -1.570796326794897" xyz="0 0 0"/>``
  (PartNet's y-up mesh frame to z-up). No ``<inertial>``, no ``<dynamics>``, no
  effort/velocity in ``<limit>``; continuous joints have no ``<limit>``.
* Every link frame sits on its joint axis: the joint ``xyz`` is the child's axis point
  minus the parent's (both in the mesh frame) and every visual and collision of the link
  is offset by minus its own axis point. Links without an axis (the carcass, ``static``
  helpers, drawers annotated with their axis through the origin) have their frame at the
  mesh origin.
* One ``<visual name="<part>-<id>">`` and one unnamed ``<collision>`` per OBJ file
  ``textured_objs/original-K.obj``; several OBJ files may share a visual name (one
  PartNet part split in several meshes).
* OBJ meshes in the y-up mesh frame, in the object's absolute coordinates (SSTK
  header, ``mtllib``, ``o``, ``v``/``vt``/``vn``, ``usemtl material_0_0``): closed
  8-vertex boards, zero-thickness double-sided quads (the back side under
  ``usemtl material_1_0`` with ``f v//vn`` faces), concave multi-board meshes and
  octagonal wheels. Each OBJ has its own ``.mtl`` with both materials, ``Kd`` colours
  and, for textured ones, ``map_Kd ../images/texture_0.png`` (a small PNG).
* ``semantics.txt`` (``link_i <joint word> <label>``), ``meta.json``
  (``"model_cat": "StorageFurniture"``) and ``bounding_box.json`` (mesh frame).

The mesh frame: ``+x`` is the right of a person standing in front of the cabinet,
``+y`` is up, ``+z`` points out of the front. After the base joint's rotation the base
frame has ``x_base = -z_mesh`` (the front faces ``-x``: drawers slide toward ``-x``),
``y_base = -x_mesh`` and ``z_base = y_mesh``. Both real objects studied (PartNet ids
40147 and 41083) follow this convention.

Good fixtures (:data:`FIXTURES`), sizes in PartNet units (metres before the loader
scales them down):

* ``drawers``: a 0.72 m rolling pedestal, a column of three drawers (each drawer box
  ONE concave open-top OBJ of five boards, a U-pull handle), four wheels on
  ``continuous`` joints (``hinge wheel``).
* ``doors``: a 1.1 m cupboard, two overlay doors: ``link_0`` hinged on the left
  (axis ``0 -1 0``, ``lower="-0.0"``), ``link_1`` hinged on the right (axis ``0 1 0``)
  whose whole geometry (door board and a handle split in two OBJs) hangs on the
  ``static`` helper ``link_2``, fixed to ``link_1``.
* ``mixed``: 0.85 m, laid out like PartNet 40147: a drawer on top (separate side,
  back and zero-thickness bottom boards, a textured front, its axis through the mesh
  origin) over a right-hinged door made of six zero-thickness surfaces.
* ``flap``: a 0.6 m bureau with a bottom-hinged drop-down door (axis ``1 0 0``) whose
  centre of mass is in front of the hinge: without joint friction the closed flap falls
  open. Two knobs; the carcass is ``free furniture_body``.

Broken fixtures (:data:`BROKEN`) are good ones with one (or several) defects.
"""

from __future__ import annotations

import hashlib
import json
import math
import shutil
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from xml.dom import minidom

import cv2
import numpy as np

#: Names of the good fixtures.
FIXTURES: tuple[str, ...] = ("drawers", "doors", "mixed", "flap")

#: PartNet's base joint rotation (y-up mesh frame to z-up), as written in its URDFs.
BASE_RPY = "1.570796326794897 0 -1.570796326794897"

#: Upper limit of PartNet's 90 degree hinges, as written in its URDFs.
_QUARTER_TURN = "1.5707963267948966"

#: Board thickness and the gap between a part and the carcass [PartNet units].
_T = 0.018
_GAP = 0.003

_CARCASS_KD = (0.9, 0.89, 0.86)
_FRONT_KD = (0.72, 0.55, 0.36)
_METAL_KD = (0.2, 0.2, 0.2)
_WHEEL_KD = (0.1, 0.1, 0.1)
_TEXTURED_KD = (1.0, 1.0, 1.0)
_TEXTURE = "texture_0.png"

Vec = tuple[float, float, float]


# --------------------------------------------------------------------------- meshes


@dataclass(frozen=True)
class _Tri:
    """One triangle: vertex indices (in its primitive), outward normal, back side?"""

    idx: tuple[int, int, int]
    normal: Vec
    back: bool = False


@dataclass(frozen=True)
class _Prim:
    """A primitive of an OBJ file: vertices (n, 3) in the mesh frame and triangles."""

    verts: np.ndarray
    tris: tuple[_Tri, ...]


def _quad(corners: list[int], pts: np.ndarray, normal: Vec, back: bool = False) -> list[_Tri]:
    """Two triangles covering the cyclic quad ``corners``, wound counter-clockwise as
    seen from the side ``normal`` points to."""
    a, b, c, _ = (pts[i] for i in corners)
    if np.dot(np.cross(b - a, c - a), normal) < 0:
        corners = corners[::-1]
    i0, i1, i2, i3 = corners
    return [_Tri((i0, i1, i2), normal, back), _Tri((i0, i2, i3), normal, back)]


def _box(lo: Vec, hi: Vec) -> _Prim:
    """A closed axis-aligned board: 8 vertices, 12 outward triangles."""
    lo_a, hi_a = np.asarray(lo, float), np.asarray(hi, float)
    assert np.all(hi_a > lo_a), (lo, hi)
    pts = np.array([[(hi_a if (i >> a) & 1 else lo_a)[a] for a in range(3)] for i in range(8)])
    tris: list[_Tri] = []
    for a in range(3):
        b, c = [k for k in range(3) if k != a]
        for side in (0, 1):
            cyc = [(0, 0), (1, 0), (1, 1), (0, 1)]
            corners = [(side << a) | (u << b) | (v << c) for u, v in cyc]
            n = [0.0, 0.0, 0.0]
            n[a] = 1.0 if side else -1.0
            tris += _quad(corners, pts, (n[0], n[1], n[2]))
    return _Prim(pts, tuple(tris))


def _flat(lo: Vec, hi: Vec, facing: int) -> _Prim:
    """A zero-thickness double-sided rectangle (exactly one extent of ``lo``/``hi`` is
    zero): its front faces ``facing`` (+1/-1) along that axis, its back side has the
    opposite normal (PartNet writes both sides)."""
    lo_a, hi_a = np.asarray(lo, float), np.asarray(hi, float)
    (a,) = np.flatnonzero(hi_a == lo_a)
    b, c = [k for k in range(3) if k != a]
    pts = []
    for u, v in [(0, 0), (1, 0), (1, 1), (0, 1)]:
        p = lo_a.copy()
        p[b] = hi_a[b] if u else lo_a[b]
        p[c] = hi_a[c] if v else lo_a[c]
        pts.append(p)
    arr = np.array(pts)
    n = [0.0, 0.0, 0.0]
    n[a] = float(facing)
    front = (n[0], n[1], n[2])
    back = (-front[0], -front[1], -front[2])
    return _Prim(arr, tuple(_quad([0, 1, 2, 3], arr, front) + _quad([0, 1, 2, 3], arr, back, True)))


def _wheel(centre: Vec, radius: float, width: float, sides: int = 8) -> _Prim:
    """A wheel turning about the mesh x axis: a closed prism of ``sides`` flat faces
    tangent to the circle of ``radius`` (the bottom face touches ``cy - radius``)."""
    cx, cy, cz = centre
    ang = [2 * math.pi * (k + 0.5) / sides for k in range(sides)]
    corner = radius / math.cos(math.pi / sides)
    ring = [(cy + corner * math.cos(t), cz + corner * math.sin(t)) for t in ang]
    pts = np.array([(cx + s * width / 2, y, z) for s in (-1, 1) for y, z in ring])
    tris: list[_Tri] = []
    for k in range(sides):
        k1 = (k + 1) % sides
        mid = 0.5 * (ang[k] + ang[k1]) if k1 else 0.5 * (ang[k] + ang[k1] + 2 * math.pi)
        tris += _quad([k, k1, sides + k1, sides + k], pts, (0.0, math.cos(mid), math.sin(mid)))
    for s, off in ((-1.0, 0), (1.0, sides)):
        for k in range(1, sides - 1):
            tri = [off, off + k, off + k + 1]
            a, b, c = pts[tri]
            if np.dot(np.cross(b - a, c - a), (s, 0, 0)) < 0:
                tri = tri[::-1]
            tris.append(_Tri((tri[0], tri[1], tri[2]), (s, 0.0, 0.0)))
    return _Prim(pts, tuple(tris))


def _open_box(lo: Vec, hi: Vec, t: float = 0.012) -> list[_Prim]:
    """A drawer box open at the top: bottom, left, right, back and front boards."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    return [
        _box((x0, y0, z0), (x1, y0 + t, z1)),
        _box((x0, y0 + t, z0), (x0 + t, y1, z1)),
        _box((x1 - t, y0 + t, z0), (x1, y1, z1)),
        _box((x0 + t, y0 + t, z0), (x1 - t, y1, z0 + t)),
        _box((x0 + t, y0 + t, z1 - t), (x1 - t, y1, z1)),
    ]


def _pull(centre: Vec, along: int, length: float, z_face: float) -> list[_Prim]:
    """A U-shaped pull handle (bar and two posts) on a front face at ``z_face``: the bar
    runs along mesh axis ``along`` (0: horizontal, 1: vertical), centred at ``centre``."""
    r, standoff = 0.006, 0.03
    lo = [centre[0] - r, centre[1] - r, z_face + standoff - r]
    hi = [centre[0] + r, centre[1] + r, z_face + standoff + r]
    lo[along] -= length / 2
    hi[along] += length / 2
    prims = [_box((lo[0], lo[1], lo[2]), (hi[0], hi[1], hi[2]))]
    for end in (lo[along], hi[along] - 2 * r):
        plo = [centre[0] - r, centre[1] - r, z_face]
        phi = [centre[0] + r, centre[1] + r, lo[2]]
        plo[along], phi[along] = end, end + 2 * r
        prims.append(_box((plo[0], plo[1], plo[2]), (phi[0], phi[1], phi[2])))
    return prims


def _knob(centre: Vec, z_face: float, size: float = 0.03) -> list[_Prim]:
    """A knob: a small block on a short stem."""
    cx, cy, _ = centre
    s, h = size / 2, 0.006
    return [
        _box((cx - h, cy - h, z_face), (cx + h, cy + h, z_face + 0.015)),
        _box((cx - s, cy - s, z_face + 0.015), (cx + s, cy + s, z_face + 0.035)),
    ]


# --------------------------------------------------------------------------- spec


@dataclass(frozen=True)
class _Piece:
    """One OBJ file: a visual named ``label`` (``<part name>-<part id>``)."""

    label: str
    prims: tuple[_Prim, ...]
    kd: Vec
    textured: bool = False


@dataclass
class _Part:
    """One link ``link_<index>`` and the joint to its parent.

    ``axis_point``: the joint axis' point in the (unshifted) mesh frame, where the link
    frame sits; ``None`` puts the frame at the mesh origin (carcass, static helpers,
    drawers annotated with an axis through the origin).
    """

    index: int
    words: tuple[str, str]
    pieces: list[_Piece]
    joint: str = "fixed"
    parent: int | None = None
    axis_point: Vec | None = None
    axis: Vec | None = None
    limit: tuple[str, str] | None = None


@dataclass
class _Spec:
    """A whole object: its parts, the shift added to every mesh coordinate, the truth."""

    name: str
    parts: list[_Part]
    shift: Vec
    truth: dict
    anno_id: str


class _Ids:
    """PartNet part ids for visual names (not contiguous, as in real annotations)."""

    def __init__(self, start: int) -> None:
        self._next = start

    def __call__(self, part: str) -> str:
        label = f"{part}-{self._next}"
        self._next += 1 if self._next % 5 else 2
        return label


def _carcass(
    ids: _Ids,
    w: float,
    d: float,
    y_bottom: float,
    y_top: float,
    y_sides: float,
    *,
    flat_back: bool,
    flat_bottom: bool,
) -> list[_Piece]:
    """Top, bottom, both sides and back of a carcass ``w`` wide and ``d`` deep (x, z
    centred on 0), its bottom board from ``y_bottom``, its top board up to ``y_top``, the
    sides down to ``y_sides``."""
    x0, x1, z0, z1 = -w / 2, w / 2, -d / 2, d / 2
    yb = y_bottom + _T
    bottom = (
        _flat((x0 + _T, yb, z0), (x1 - _T, yb, z1), +1)
        if flat_bottom
        else _box((x0 + _T, y_bottom, z0), (x1 - _T, yb, z1))
    )
    back = (
        _flat((x0 + _T, yb, z0), (x1 - _T, y_top - _T, z0), +1)
        if flat_back
        else _box((x0 + _T, yb, z0), (x1 - _T, y_top - _T, z0 + 0.008))
    )
    return [
        _Piece(ids("top_panel"), (_box((x0, y_top - _T, z0), (x1, y_top, z1)),), _CARCASS_KD),
        _Piece(ids("bottom_panel"), (bottom,), _CARCASS_KD),
        _Piece(
            ids("vertical_side_panel"),
            (_box((x0, y_sides, z0), (x0 + _T, y_top - _T, z1)),),
            _CARCASS_KD,
        ),
        _Piece(
            ids("vertical_side_panel"),
            (_box((x1 - _T, y_sides, z0), (x1, y_top - _T, z1)),),
            _CARCASS_KD,
        ),
        _Piece(ids("back_panel"), (back,), _CARCASS_KD),
    ]


def _truth(carcass: int, height: float, parts: dict, **extra: object) -> dict:
    truth = {
        "model_cat": "StorageFurniture",
        "carcass": f"link_{carcass}",
        "height": height,
        "parts": parts,
        "helpers": {},
        "continuous": (),
    }
    truth.update(extra)
    return truth


def _drawers() -> _Spec:
    """A rolling pedestal: three drawers (concave one-mesh boxes) and four wheels."""
    ids = _Ids(4)
    w, d, h, r = 0.5, 0.55, 0.72, 0.035
    y_floor = -h / 2
    y_bot, y_top = y_floor + 2 * r + 0.01, h / 2
    zf, zb = d / 2, -d / 2
    carcass = _carcass(ids, w, d, y_bot, y_top, y_bot, flat_back=True, flat_bottom=False)
    # three equal cells between the bottom and top boards, two rails between them
    inner0, inner1 = y_bot + _T, y_top - _T
    cell = (inner1 - inner0 - 2 * _T) / 3
    cells = [(inner0 + k * (cell + _T), inner0 + k * (cell + _T) + cell) for k in range(3)]
    for k in (1, 2):
        y = cells[k][0]
        carcass.append(
            _Piece(
                ids("frame_horizontal_bar"),
                (_box((-w / 2 + _T, y - _T, zb + 0.02), (w / 2 - _T, y, zf)),),
                _CARCASS_KD,
            )
        )
    parts: list[_Part] = []
    # drawers top to bottom are link_0..link_2; fronts overlay the carcass edges
    for i, (c0, c1) in enumerate(reversed(cells)):
        f0, f1 = c0 - _T / 2 + _GAP, c1 + _T / 2 - _GAP
        box_lo = (-w / 2 + _T + 0.01, c0 + 0.005, zb + 0.03)
        box_hi = (w / 2 - _T - 0.01, c1 - 0.025, zf)
        front_z = zf + _GAP + _T
        pieces = [
            _Piece(
                ids("drawer_front"),
                (_box((-w / 2 + _GAP, f0, zf + _GAP), (w / 2 - _GAP, f1, front_z)),),
                _FRONT_KD,
            ),
            _Piece(ids("drawer_box"), tuple(_open_box(box_lo, box_hi)), _FRONT_KD),
            _Piece(
                ids("handle"),
                tuple(_pull((0.0, 0.5 * (f0 + f1), 0.0), 0, 0.14, front_z)),
                _METAL_KD,
            ),
        ]
        # drawer 0: axis through the mesh origin (as 40147); the others on the front
        # centre and on a back corner of the box (as 41083: any point of the axis line)
        point = [None, (0.0, 0.5 * (f0 + f1), front_z), (box_lo[0], box_lo[1], box_lo[2])][i]
        parts.append(
            _Part(
                i,
                ("slider", "drawer"),
                pieces,
                "prismatic",
                7,
                point,
                (0, 0, 1),
                ("0", repr(round(0.8 * d, 2))),
            )
        )
    wheels = []
    for j, (sx, sz) in enumerate([(-1, 1), (1, 1), (-1, -1), (1, -1)]):
        centre = (sx * (w / 2 - 0.05), y_floor + r, sz * (d / 2 - 0.06))
        piece = _Piece(ids("wheel"), (_wheel(centre, r, 0.025),), _WHEEL_KD)
        parts.append(_Part(3 + j, ("hinge", "wheel"), [piece], "continuous", 7, centre, (1, 0, 0)))
        wheels.append(f"link_{3 + j}")
    parts.append(_Part(7, ("heavy", "furniture_body"), carcass))
    truth = _truth(
        7,
        h,
        {f"link_{i}": {"kind": "drawer", "joint": f"joint_{i}", "handles": 1} for i in range(3)},
        continuous=tuple(wheels),
    )
    return _Spec(
        "drawers", parts, (0.012337461820135, -0.007094418826871, 0.004617309255034), truth, "90101"
    )


def _doors() -> _Spec:
    """A cupboard with two overlay doors; the right one's geometry on a helper link."""
    ids = _Ids(6)
    w, d, h, plinth = 0.9, 0.45, 1.1, 0.08
    y_floor, y_top = -h / 2, h / 2
    y_bot = y_floor + plinth
    zf, zb = d / 2, -d / 2
    carcass = _carcass(ids, w, d, y_bot, y_top, y_floor, flat_back=True, flat_bottom=False)
    y_mid = 0.5 * (y_bot + y_top)
    carcass += [
        _Piece(
            ids("shelf"),
            (_box((-w / 2 + _T, y_mid - _T / 2, zb), (w / 2 - _T, y_mid + _T / 2, zf - 0.02)),),
            _CARCASS_KD,
        ),
        _Piece(
            ids("base_side_panel"),
            (_box((-w / 2 + _T, y_floor, zf - 0.04 - _T), (w / 2 - _T, y_bot, zf - 0.04)),),
            _CARCASS_KD,
        ),
    ]
    y0, y1 = y_bot + _GAP, y_top - _GAP
    z0, z1 = zf + _GAP, zf + _GAP + _T
    # left door: hinge on the left edge, axis -y (PartNet: lower="-0.0")
    left = [
        _Piece(ids("cabinet_door_surface"), (_box((-w / 2, y0, z0), (-_GAP, y1, z1)),), _FRONT_KD),
        _Piece(
            ids("handle"), tuple(_pull((-_GAP - 0.05, y_mid + 0.1, 0.0), 1, 0.2, z1)), _METAL_KD
        ),
    ]
    # right door: hinge on the right edge, axis +y; board and handle (split in two
    # OBJs sharing one name) on the static helper link_2
    bar, post_a, post_b = _pull((_GAP + 0.05, y_mid + 0.1, 0.0), 1, 0.2, z1)
    handle = ids("handle")
    right = [
        _Piece(ids("cabinet_door_surface"), (_box((_GAP, y0, z0), (w / 2, y1, z1)),), _FRONT_KD),
        _Piece(handle, (bar,), _METAL_KD),
        _Piece(handle, (post_a, post_b), _METAL_KD),
    ]
    parts = [
        _Part(
            0,
            ("hinge", "rotation_door"),
            left,
            "revolute",
            3,
            (-w / 2, y1, z0),
            (0, -1, 0),
            ("-0.0", _QUARTER_TURN),
        ),
        _Part(
            1,
            ("hinge", "rotation_door"),
            [],
            "revolute",
            3,
            (w / 2, y1, z0),
            (0, 1, 0),
            ("0.0", _QUARTER_TURN),
        ),
        _Part(2, ("static", "cabinet_door"), right, "fixed", 1),
        _Part(3, ("heavy", "furniture_body"), carcass),
    ]
    truth = _truth(
        3,
        h,
        {
            "link_0": {
                "kind": "door",
                "joint": "joint_0",
                "hinge": "left",
                "handles": 1,
                "falls_open": False,
            },
            "link_1": {
                "kind": "door",
                "joint": "joint_1",
                "hinge": "right",
                "handles": 1,
                "falls_open": False,
            },
        },
        helpers={"link_2": "link_1"},
    )
    return _Spec(
        "doors", parts, (-0.021748630915207, 0.013902276541183, -0.008215937460291), truth, "90102"
    )


def _mixed() -> _Spec:
    """A drawer over a right-hinged door, laid out like PartNet 40147."""
    ids = _Ids(2)
    w, d, h, plinth = 0.7, 0.5, 0.85, 0.07
    y_floor, y_top = -h / 2, h / 2
    y_bot = y_floor + plinth
    zf, zb = d / 2, -d / 2
    carcass = _carcass(ids, w, d, y_bot, y_top, y_bot, flat_back=False, flat_bottom=True)
    y_div = y_top - 0.22
    x0, x1 = -w / 2 + _T, w / 2 - _T
    carcass.append(
        _Piece(ids("shelf"), (_box((x0, y_div - _T, zb + 0.008), (x1, y_div, zf)),), _CARCASS_KD)
    )
    # plinth: four base side panels under the bottom board
    for lo, hi in [
        ((-w / 2, y_floor, zf - 0.05 - _T), (w / 2, y_bot, zf - 0.05)),
        ((-w / 2, y_floor, zb), (w / 2, y_bot, zb + _T)),
        ((-w / 2, y_floor, zb + _T), (-w / 2 + _T, y_bot, zf - 0.05 - _T)),
        ((w / 2 - _T, y_floor, zb + _T), (w / 2, y_bot, zf - 0.05 - _T)),
    ]:
        carcass.append(_Piece(ids("base_side_panel"), (_box(lo, hi),), _CARCASS_KD))
    # drawer link_1 in the top cell: separate boards, textured front, zero-thickness bottom
    c0, c1 = y_div, y_top - _T
    f0, f1 = c0 - _T / 2 + _GAP, y_top - _GAP
    front_z = zf + _GAP + _T
    bx0, bx1, by0, by1, bz0 = x0 + 0.012, x1 - 0.012, c0 + 0.006, c1 - 0.03, zb + 0.04
    t = 0.012
    drawer = [
        _Piece(
            ids("drawer_front"),
            (_box((-w / 2 + _GAP, f0, zf + _GAP), (w / 2 - _GAP, f1, front_z)),),
            _TEXTURED_KD,
            textured=True,
        ),
        _Piece(ids("drawer_side"), (_box((bx0, by0, bz0), (bx0 + t, by1, zf)),), _FRONT_KD),
        _Piece(ids("drawer_side"), (_box((bx1 - t, by0, bz0), (bx1, by1, zf)),), _FRONT_KD),
        _Piece(
            ids("drawer_back"), (_box((bx0 + t, by0, bz0), (bx1 - t, by1, bz0 + t)),), _FRONT_KD
        ),
        _Piece(
            ids("drawer_bottom"),
            (_flat((bx0 + t, by0, bz0 + t), (bx1 - t, by0, zf), 1),),
            _FRONT_KD,
        ),
        _Piece(
            ids("handle"), tuple(_pull((0.0, 0.5 * (f0 + f1), 0.0), 0, 0.16, front_z)), _METAL_KD
        ),
    ]
    # door link_0 below: six zero-thickness surfaces (front, back, four edges) as 40147
    dx0, dx1, dy0, dy1 = -w / 2 + _GAP, w / 2 - _GAP, y_bot + _GAP, y_div - _T / 2 - _GAP
    z0, z1 = zf + _GAP, zf + _GAP + _T
    surface = ids("cabinet_door_surface")
    surfaces = [
        _flat((dx0, dy0, z1), (dx1, dy1, z1), +1),
        _flat((dx0, dy0, z0), (dx1, dy1, z0), -1),
        _flat((dx0, dy0, z0), (dx0, dy1, z1), -1),
        _flat((dx1, dy0, z0), (dx1, dy1, z1), +1),
        _flat((dx0, dy0, z0), (dx1, dy0, z1), -1),
        _flat((dx0, dy1, z0), (dx1, dy1, z1), +1),
    ]
    door = [_Piece(surface, (s,), _FRONT_KD) for s in surfaces]
    door.append(
        _Piece(ids("handle"), tuple(_pull((dx0 + 0.05, dy1 - 0.12, 0.0), 1, 0.16, z1)), _METAL_KD)
    )
    parts = [
        _Part(
            0,
            ("hinge", "rotation_door"),
            door,
            "revolute",
            2,
            (dx1, 0.0, z0),
            (0, 1, 0),
            ("0.0", _QUARTER_TURN),
        ),
        _Part(1, ("slider", "drawer"), drawer, "prismatic", 2, None, (0, 0, 1), ("0", "0.4")),
        _Part(2, ("heavy", "furniture_body"), carcass),
    ]
    truth = _truth(
        2,
        h,
        {
            "link_0": {
                "kind": "door",
                "joint": "joint_0",
                "hinge": "right",
                "handles": 1,
                "falls_open": False,
            },
            "link_1": {"kind": "drawer", "joint": "joint_1", "handles": 1},
        },
    )
    return _Spec(
        "mixed", parts, (0.039126684307719, -0.011347015928846, 0.020815529643102), truth, "90103"
    )


def _flap() -> _Spec:
    """A bureau whose bottom-hinged flap falls open without joint friction."""
    ids = _Ids(3)
    w, d, h, plinth = 0.8, 0.4, 0.6, 0.06
    y_floor, y_top = -h / 2, h / 2
    y_bot = y_floor + plinth
    zf, zb = d / 2, -d / 2
    carcass = _carcass(ids, w, d, y_bot, y_top, y_floor, flat_back=True, flat_bottom=False)
    y_mid = 0.5 * (y_bot + y_top)
    carcass += [
        _Piece(
            ids("shelf"),
            (_box((-w / 2 + _T, y_mid, zb), (w / 2 - _T, y_mid + _T, zf - 0.03)),),
            _CARCASS_KD,
        ),
        _Piece(
            ids("base_side_panel"),
            (_box((-w / 2 + _T, y_floor, zf - 0.03 - _T), (w / 2 - _T, y_bot, zf - 0.03)),),
            _CARCASS_KD,
        ),
    ]
    # the flap overlays the front; its hinge runs along its bottom back edge, so the
    # board and the knobs (its centre of mass) are in front of the axis
    x0, x1, y0, y1 = -w / 2 + _GAP, w / 2 - _GAP, y_bot + _GAP, y_top - _GAP
    z0, z1 = zf + _GAP, zf + _GAP + 0.022
    flap = [
        _Piece(ids("cabinet_door_surface"), (_box((x0, y0, z0), (x1, y1, z1)),), _FRONT_KD),
        _Piece(ids("handle"), tuple(_knob((-0.25, y1 - 0.05, 0.0), z1)), _METAL_KD),
        _Piece(ids("handle"), tuple(_knob((0.25, y1 - 0.05, 0.0), z1)), _METAL_KD),
    ]
    parts = [
        _Part(
            0,
            ("hinge", "door"),
            flap,
            "revolute",
            1,
            (0.0, y0, z0),
            (1, 0, 0),
            ("0.0", _QUARTER_TURN),
        ),
        _Part(1, ("free", "furniture_body"), carcass),
    ]
    truth = _truth(
        1,
        h,
        {
            "link_0": {
                "kind": "door",
                "joint": "joint_0",
                "hinge": "bottom",
                "handles": 2,
                "falls_open": True,
            }
        },
    )
    return _Spec(
        "flap", parts, (-0.006428817350964, 0.018661350472519, -0.013069274185537), truth, "90104"
    )


_BUILDERS: dict[str, Callable[[], _Spec]] = {
    "drawers": _drawers,
    "doors": _doors,
    "mixed": _mixed,
    "flap": _flap,
}


# --------------------------------------------------------------------------- writing


def _num(x: float) -> str:
    """A number as PartNet writes it: ``0`` for zero, integers bare, else ``repr``."""
    x = float(x)
    if x == 0:
        return "0"
    if x.is_integer():
        return str(int(x))
    return repr(x)


def _obj_numbers(spec: _Spec) -> Iterator[tuple[_Part, _Piece, int]]:
    """Every piece with its OBJ number ``K`` (carcass first, numbers with gaps)."""
    order = sorted(spec.parts, key=lambda p: (p.parent is not None, p.index))
    k = 2
    for part in order:
        for piece in part.pieces:
            yield part, piece, k
            k += 2 if k % 9 == 0 else 1


def _obj_text(k: int, prims: tuple[_Prim, ...], shift: np.ndarray) -> str:
    """An OBJ file as SSTK writes it (PartNet's ``textured_objs/original-K.obj``)."""
    lines = [
        "# SSTK version 0.8.0",
        f"# {k}",
        f"mtllib original-{k}.mtl",
        f"o mesh{k - 1}/mesh{k - 1}-geometry#mesh{k - 1}-geometry",
    ]
    vts: dict[tuple[float, float], int] = {}
    vns: dict[Vec, int] = {}
    front: list[str] = []
    back: list[str] = []
    base = 0
    verts = []
    for prim in prims:
        pts = prim.verts + shift
        verts.append(pts)
        for tri in prim.tris:
            n = tuple(0.0 if abs(c) < 1e-12 else round(c, 12) for c in tri.normal)
            ni = vns.setdefault((n[0], n[1], n[2]), len(vns) + 1)
            idx = [base + i + 1 for i in tri.idx]
            if tri.back:
                back.append("f " + " ".join(f"{i}//{ni}" for i in idx))
                continue
            # planar texture coordinates in the plane of the face
            a = int(np.argmax(np.abs(tri.normal)))
            b, c = [m for m in range(3) if m != a]
            corners = []
            for i in tri.idx:
                uv = (round(2.0 * float(pts[i, b]), 6), round(2.0 * float(pts[i, c]), 6))
                corners.append(vts.setdefault(uv, len(vts) + 1))
            front.append(
                "f " + " ".join(f"{i}/{t}/{ni}" for i, t in zip(idx, corners, strict=True))
            )
        base += len(prim.verts)
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in np.vstack(verts)]
    lines += [f"vt {_num(u)} {_num(v)}" for u, v in vts]
    lines += ["vn " + " ".join(_num(c) for c in n) for n in vns]
    lines += ["usemtl material_0_0", *front]
    if back:
        lines += ["usemtl material_1_0", *back]
    return "\n".join(lines) + "\n"


def _mtl_text(piece: _Piece) -> str:
    """The ``.mtl`` next to an OBJ: ``material_0_0`` (front) and ``material_1_0``."""
    kd = " ".join(_num(c) for c in piece.kd)
    ks = " ".join([repr(1 / 15)] * 3)
    out = []
    for m in range(2):
        out += [f"newmtl material_{m}_0", "illum 3", "d 1", "Ns 30", f"Kd {kd} ", f"Ks {ks} "]
        if m == 0 and piece.textured:
            out.append(f"map_Kd ../images/{_TEXTURE}")
        out.append("")
    return "\n".join(out) + "\n"


def _texture() -> np.ndarray:
    """A small wood-grain texture (BGR, 32x32): deterministic, no randomness."""
    u, v = np.meshgrid(np.arange(32), np.arange(32))
    grain = 0.5 + 0.5 * np.sin(0.9 * u + 0.15 * v + 0.8 * np.sin(0.4 * v))
    bgr = np.stack([60 + 30 * grain, 110 + 40 * grain, 160 + 50 * grain], axis=-1)
    return bgr.astype(np.uint8)


def _frame(part: _Part, shift: np.ndarray) -> np.ndarray:
    """The link frame's position in the (shifted) mesh frame."""
    if part.axis_point is None:
        return np.zeros(3)
    return np.asarray(part.axis_point, float) + shift


def _xyz(v: np.ndarray) -> str:
    return " ".join(_num(c) for c in v)


def _element(parent: minidom.Element, tag: str, **attrs: str) -> minidom.Element:
    doc = parent.ownerDocument
    assert doc is not None
    el = doc.createElement(tag)
    for key, value in attrs.items():
        el.setAttribute(key, value)
    parent.appendChild(el)
    return el


def _urdf_text(spec: _Spec, files: dict[int, list[tuple[_Piece, str]]]) -> str:
    shift = np.asarray(spec.shift, float)
    doc = minidom.Document()
    robot = doc.createElement("robot")
    robot.setAttribute("name", f"partnet_{_model_id(spec.name)}")
    doc.appendChild(robot)
    _element(robot, "link", name="base")
    frames = {p.index: _frame(p, shift) for p in spec.parts}
    for part in sorted(spec.parts, key=lambda p: p.index):
        link = _element(robot, "link", name=f"link_{part.index}")
        offset = _xyz(-frames[part.index])
        for tag in ("visual", "collision"):
            for piece, filename in files[part.index]:
                el = _element(link, tag, name=piece.label) if tag == "visual" else None
                el = el if el is not None else _element(link, tag)
                _element(el, "origin", xyz=offset)
                _element(_element(el, "geometry"), "mesh", filename=filename)
        joint = _element(robot, "joint", name=f"joint_{part.index}", type=part.joint)
        if part.parent is None:
            _element(joint, "origin", rpy=BASE_RPY, xyz="0 0 0")
        else:
            # an undefined parent (a broken fixture) counts as sitting at the origin
            parent_frame = frames.get(part.parent, np.zeros(3))
            _element(joint, "origin", xyz=_xyz(frames[part.index] - parent_frame))
        if part.axis is not None:
            _element(joint, "axis", xyz=" ".join(_num(c) for c in part.axis))
        _element(joint, "child", link=f"link_{part.index}")
        _element(joint, "parent", link="base" if part.parent is None else f"link_{part.parent}")
        if part.limit is not None:
            _element(joint, "limit", lower=part.limit[0], upper=part.limit[1])
    return doc.toprettyxml(indent="\t")


def _model_id(name: str) -> str:
    return hashlib.md5(f"strug-manip fixture {name}".encode()).hexdigest()


def _write(spec: _Spec, out: Path) -> Path:
    """Write ``spec`` into the object folder ``out`` (replaced if it exists)."""
    if out.exists():
        shutil.rmtree(out)
    objs = out / "textured_objs"
    objs.mkdir(parents=True)
    shift = np.asarray(spec.shift, float)
    files: dict[int, list[tuple[_Piece, str]]] = {p.index: [] for p in spec.parts}
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    textured = False
    for part, piece, k in _obj_numbers(spec):
        (objs / f"original-{k}.obj").write_text(_obj_text(k, piece.prims, shift))
        (objs / f"original-{k}.mtl").write_text(_mtl_text(piece))
        files[part.index].append((piece, f"textured_objs/original-{k}.obj"))
        textured |= piece.textured
        for prim in piece.prims:
            lo = np.minimum(lo, (prim.verts + shift).min(axis=0))
            hi = np.maximum(hi, (prim.verts + shift).max(axis=0))
    if textured:
        (out / "images").mkdir()
        cv2.imwrite(str(out / "images" / _TEXTURE), _texture())
    (out / "mobility.urdf").write_text(_urdf_text(spec, files))
    semantics = [f"link_{p.index} {p.words[0]} {p.words[1]}" for p in spec.parts]
    (out / "semantics.txt").write_text("\n".join(sorted(semantics, key=_link_key)) + "\n")
    meta = {
        "model_id": _model_id(spec.name),
        "anno_id": spec.anno_id,
        "user_id": "strug-manip-fixture",
        "time_in_sec": "600",
        "version": "2",
        "model_cat": "StorageFurniture",
    }
    (out / "meta.json").write_text(json.dumps(meta))
    box = {"min": [round(float(v), 6) for v in lo], "max": [round(float(v), 6) for v in hi]}
    (out / "bounding_box.json").write_text(json.dumps(box))
    return out


def _link_key(line: str) -> int:
    return int(line.split()[0].removeprefix("link_"))


def write_fixture(folder: Path, name: str) -> Path:
    """Write the good fixture ``name`` (one of :data:`FIXTURES`) as ``folder/<name>/``.

    Args:
        folder: where to create the object folder (created if missing).
        name: the fixture.

    Returns:
        The object folder (holding ``mobility.urdf``, ``semantics.txt``, ...).

    Raises:
        KeyError: ``name`` is not a good fixture.
    """
    if name not in _BUILDERS:
        raise KeyError(f"unknown PartNet fixture {name!r}; expected one of {FIXTURES}")
    return _write(_BUILDERS[name](), Path(folder) / name)


def fixture_truth(name: str) -> dict:
    """What a loader should find in the good fixture ``name``.

    Returns:
        ``{"model_cat", "carcass": link, "height": float (PartNet units, before any
        scaling), "parts": {link: {"kind": "drawer" | "door", "joint": joint name,
        "handles": int (distinct ``handle-<id>`` visual names on the part and its
        helpers), and for doors "hinge": "left" | "right" | "top" | "bottom" (as seen by
        a person standing in front of the cabinet) and "falls_open": bool (the closed
        door opens under gravity without joint friction)}}, "helpers": {helper link:
        the part it belongs to (joined by a fixed joint)}, "continuous": links on
        continuous joints (wheels or knobs: neither drawers nor doors)}``. A fresh copy.

    Raises:
        KeyError: ``name`` is not a good fixture.
    """
    if name not in _BUILDERS:
        raise KeyError(f"unknown PartNet fixture {name!r}; expected one of {FIXTURES}")
    return json.loads(json.dumps(_BUILDERS[name]().truth), object_hook=_tuples)


def _tuples(d: dict) -> dict:
    return {k: tuple(v) if isinstance(v, list) else v for k, v in d.items()}


# --------------------------------------------------------------------------- broken


def _obj_name(spec: _Spec, link: int, label_prefix: str) -> str:
    """The OBJ file name of the first piece of ``link`` whose label starts with
    ``label_prefix``."""
    for part, piece, k in _obj_numbers(spec):
        if part.index == link and piece.label.startswith(label_prefix):
            return f"original-{k}.obj"
    raise KeyError((link, label_prefix))


def _with_joint(spec: _Spec, index: int, **changes: object) -> _Spec:
    parts = [replace(p, **changes) if p.index == index else p for p in spec.parts]
    return replace(spec, parts=parts)


@dataclass(frozen=True)
class _Broken:
    """How to break a good fixture: the base, a spec change, files to delete, and what
    every problem line must mention."""

    base: str
    change: Callable[[_Spec], _Spec] = lambda s: s
    delete: tuple[str, ...] = ()
    truncate: bool = False
    mentions: tuple[str, ...] = ()


def _all_fixed(spec: _Spec) -> _Spec:
    parts = [
        replace(p, joint="fixed", axis=None, limit=None, words=("static", p.words[1]))
        if p.parent is not None
        else p
        for p in spec.parts
    ]
    return replace(spec, parts=parts)


def _broken_table() -> dict[str, _Broken]:
    mixed = _mixed()
    drawer_handle = _obj_name(mixed, 1, "handle")
    door_handle = _obj_name(mixed, 0, "handle")
    return {
        # the drawer's handle mesh is missing from textured_objs/
        "missing_mesh": _Broken("mixed", delete=(drawer_handle,), mentions=(drawer_handle,)),
        # a download cut short: the URDF ends in the middle of an element
        "malformed_urdf": _Broken("doors", truncate=True, mentions=("mobility.urdf",)),
        # the drawer hangs on a floating joint
        "unsupported_joint": _Broken(
            "mixed",
            change=lambda s: _with_joint(s, 1, joint="floating", axis=None, limit=None),
            mentions=("floating",),
        ),
        # every joint is fixed
        "no_movable_part": _Broken("doors", change=_all_fixed, mentions=("movable",)),
        # a missing mesh, a planar joint and a joint naming an undefined parent link
        "several_problems": _Broken(
            "mixed",
            change=lambda s: _with_joint(_with_joint(s, 0, joint="planar"), 1, parent=7),
            delete=(door_handle,),
            mentions=(door_handle, "planar", "link_7"),
        ),
    }


_BROKEN_TABLE = _broken_table()

#: Broken fixture name -> a substring every problem line the loader reports must contain
#: (a line also names the file). ``several_problems`` must be reported in ONE line that
#: mentions every item of :data:`BROKEN_MENTIONS`.
BROKEN: dict[str, str] = {k: b.mentions[0] for k, b in _BROKEN_TABLE.items()}

#: Broken fixture name -> every substring its one problem line must contain.
BROKEN_MENTIONS: dict[str, tuple[str, ...]] = {k: b.mentions for k, b in _BROKEN_TABLE.items()}


def write_broken(folder: Path, name: str) -> Path:
    """Write the broken fixture ``name`` (one of :data:`BROKEN`) as ``folder/<name>/``.

    Args:
        folder: where to create the object folder (created if missing).
        name: the broken fixture.

    Returns:
        The object folder.

    Raises:
        KeyError: ``name`` is not a broken fixture.
    """
    if name not in _BROKEN_TABLE:
        raise KeyError(f"unknown broken PartNet fixture {name!r}; expected one of {list(BROKEN)}")
    b = _BROKEN_TABLE[name]
    spec = b.change(replace(_BUILDERS[b.base](), name=name))
    out = _write(spec, Path(folder) / name)
    for filename in b.delete:
        (out / "textured_objs" / filename).unlink()
    if b.truncate:
        urdf = out / "mobility.urdf"
        text = urdf.read_text()
        urdf.write_text(text[: int(0.6 * len(text))])
    return out
