"""A loaded object's part description: the same :class:`CabinetSpec` a generated
cabinet has, derived from the object itself (URDF, semantics and geometry).

Whatever the skills, the belief, the rules and the tasks read of a part (its kind,
joint type, axis, origin and limits, handle pose and style, the interior where an
object can be put) comes from :func:`describe_object`, for a downloaded
PartNet-Mobility object as for a generated cabinet loaded from its folder; only the
generator reads the generator's ground truth. The object must be conformed
(:mod:`strug_manip.objects.conform`: front ``+x``, origin on the floor at the
footprint's centre, positive joint positions open), as the loader leaves it.

How each field is found (object frame, parts closed):

- **kind**: the semantics label (``drawer``, ``*door*``), else the joint type
  (prismatic: drawer, revolute: door); continuous joints (knobs, wheels) are not parts.
- **geometry**: the collision pieces of the part's links (its child link and the links
  welded under it), each as its axis-aligned box; the carcass is every other link.
- **front**: the part's box without its handles; ``cell_center`` on the carcass's
  front plane at the front's centre, ``cell_size`` its width and height.
- **handle**: the pieces named ``handle*`` (PartNet names them in ``<visual>``; a
  door's: the one farthest from the hinge); a bar if its face extent is
  :data:`BAR_ASPECT` times longer than wide (its axis the long side, the grasp point
  the bar's centre a radius behind its foremost point), else a knob (grasped
  :data:`~strug_manip.objects.generator.KNOB_GRASP_INSET` behind its tip), described
  by the generator's parametric ``bar_handle``/``knob_handle`` fitted to its extents
  (what the grasps read); no handle: ``none``, the grasp point on the front face (a
  drawer's centre, a door's free edge side).
- **hinge**: for doors, the side of the front the hinge line is on.
- **interior**: the free box measured by casting rays (``mujoco.mj_ray``, collision
  geoms only) from inside the drawer box (its top: the drawer's sides) or from the
  cell behind the door.
- **grid**: rows and columns by clustering the fronts' centres.
- **mass**: boxes' mass properties at one density, scaled to the loaded model's mass.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import mujoco
import numpy as np

from planners.errors import ConfigError
from strug_manip.objects.conform import geom_points, link_poses, moving_subtree
from strug_manip.objects.generator import (
    KNOB_GRASP_INSET,
    WALL_RANGE,
    CabinetSpec,
    Geom,
    PartSpec,
    bar_handle,
    box,
    knob_handle,
    mass_properties,
)
from strug_manip.objects.loader import ArticulatedObject
from strug_manip.objects.urdf import JointInfo

#: A handle is a bar when its longer face extent is this many times its shorter one.
BAR_ASPECT = 2.5
#: A door without a handle is grasped this far in from its free edge [m] (the middle
#: of the generator's :data:`~strug_manip.objects.generator.DOOR_HANDLE_INSET`).
EDGE_INSET = 0.045
#: Fronts whose centres are nearer than this share a row or a column [m].
GRID_TOLERANCE = 0.05
#: A measured interior narrower than this along any axis holds nothing [m].
MIN_INTERIOR = 0.03
#: Pieces thinner than this along every axis are dropped from the boxes [m].
MIN_PIECE = 1e-4
_COLLISION_GROUPS = np.array([1, 0, 0, 1, 0, 0], dtype=np.uint8)  # groups 0 and 3


def _kind(j: JointInfo) -> str | None:
    label = j.semantic.lower()
    if j.type == "continuous":
        return None
    if "drawer" in label:
        return "drawer"
    if "door" in label:
        return "door"
    return "drawer" if j.type == "prismatic" else "door"


def _piece_boxes(
    obj: ArticulatedObject, links: Sequence[str]
) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(name, lo, hi) of every collision piece of ``links``: its axis-aligned box in the
    object frame with the parts closed [m]."""
    poses = link_poses(obj.urdf)
    out = []
    for name in links:
        for g in obj.urdf.links[name].collisions:
            T = poses[name] @ g.T_link_geom
            pts = geom_points(g) @ T[:3, :3].T + T[:3, 3]
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            if np.all(hi - lo >= MIN_PIECE):
                out.append((g.name, lo, hi))
    return out


def _is_handle(name: str) -> bool:
    return name.lower().startswith("handle") or "/handle" in name.lower()


def _handle(
    boxes: list[tuple[str, np.ndarray, np.ndarray]],
    j: JointInfo,
    kind: str,
    rgba: tuple[float, float, float, float],
) -> tuple[str, np.ndarray | None, np.ndarray | None, list[Geom]]:
    """Style, grasp point (3,), bar axis (3,) and geoms of a part's handle (object
    frame): the generator's parametric bar or knob fitted to the handle's pieces."""
    groups: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for name, lo, hi in boxes:
        if _is_handle(name):
            groups.setdefault(name, []).append((lo, hi))
    if not groups:
        return "none", None, None, []
    spans = {
        n: (np.min([a for a, _ in v], axis=0), np.max([b for _, b in v], axis=0))
        for n, v in groups.items()
    }
    if kind == "door":  # the handle farthest from the hinge line
        o, a = j.T_base_joint[:3, 3], j.axis_base

        def dist(n: str) -> float:
            c = 0.5 * (spans[n][0] + spans[n][1]) - o
            return float(np.linalg.norm(c - (c @ a) * a))

        best = max(spans, key=dist)
    else:  # the largest
        best = max(spans, key=lambda n: float(np.prod(spans[n][1] - spans[n][0] + 1e-3)))
    lo, hi = spans[best]
    c = 0.5 * (lo + hi)
    face = hi[1:] - lo[1:]  # (y, z) extents
    long, short = float(face.max()), float(face.min())
    depth = max(float(hi[0] - lo[0]), 2 * KNOB_GRASP_INSET)
    radius = max(0.5 * min(short, depth), 0.004)
    if long > BAR_ASPECT * max(short, 1e-3):
        along = "y" if face[0] >= face[1] else "z"
        grasp = np.array([hi[0] - radius, c[1], c[2]])
        geoms = bar_handle(grasp, along, radius, long, max(grasp[0] - lo[0], radius), rgba)
        axis = np.array([0.0, 1.0, 0.0]) if along == "y" else np.array([0.0, 0.0, 1.0])
        return "bar", grasp, axis, geoms
    geoms, grasp = knob_handle(np.array([lo[0], c[1], c[2]]), 0.5 * long, depth, rgba)
    return "knob", grasp, np.array([1.0, 0.0, 0.0]), geoms


def _hinge(j: JointInfo, lo: np.ndarray, hi: np.ndarray) -> str:
    o, c = j.T_base_joint[:3, 3], 0.5 * (lo + hi)
    if abs(j.axis_base[2]) >= math.cos(math.radians(45.0)):
        return "left" if o[1] < c[1] else "right"  # the viewer's left is -y
    return "top" if o[2] > c[2] else "bottom"


def _ray(model: mujoco.MjModel, data: mujoco.MjData, p: np.ndarray, d: np.ndarray) -> float:
    geom = np.zeros(1, dtype=np.int32)
    dist = mujoco.mj_ray(model, data, p, d, _COLLISION_GROUPS, 1, -1, geom)
    return math.inf if dist < 0 else float(dist)


def _interior(
    obj: ArticulatedObject, start: np.ndarray, top: float | None
) -> tuple[np.ndarray, np.ndarray] | None:
    """The free box around ``start`` (object frame) bounded by the collision geometry
    (the parts closed), its top at most ``top``: centre (3,) and size (3,) [m]."""
    model = obj.mj_model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    T = np.eye(4)
    root = model.body(obj.root).id
    T[:3, :3], T[:3, 3] = data.xmat[root].reshape(3, 3), data.xpos[root]
    p = T[:3, :3] @ start + T[:3, 3]
    lo, hi = np.empty(3), np.empty(3)
    for k in range(3):
        e = T[:3, k]
        lo[k] = start[k] - _ray(model, data, p, -e)
        hi[k] = start[k] + _ray(model, data, p, e)
    if top is not None:
        hi[2] = min(hi[2], top)
    size = hi - lo
    if not np.all(np.isfinite(size)) or np.any(size < MIN_INTERIOR):
        return None
    return 0.5 * (lo + hi), size


def _grid(values: np.ndarray, descending: bool) -> np.ndarray:
    """Index of each value's cluster (clusters of values nearer than the tolerance)."""
    order = np.argsort(-values if descending else values)
    idx = np.empty(len(values), dtype=int)
    k, last = -1, None
    for i in order:
        if last is None or abs(values[i] - last) > GRID_TOLERANCE:
            k += 1
        idx[i], last = k, values[i]
    return idx


def _part_interior(
    obj: ArticulatedObject,
    boxes: list[tuple[str, np.ndarray, np.ndarray]],
    kind: str,
    lo: np.ndarray,
    hi: np.ndarray,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Centre (3,) and size (3,) [m] of where an object goes in a part (its front's box
    ``lo``, ``hi``): a drawer's box, or the cell behind a door."""
    if kind == "drawer":  # from the middle of the box behind the front, up to its sides
        behind = [(a, b) for n, a, b in boxes if not _is_handle(n) and a[0] < hi[0] - 0.03]
        blo = np.min([a for a, _ in behind], axis=0) if behind else lo
        bhi = np.max([b for _, b in behind], axis=0) if behind else hi
        inside = _interior(obj, 0.5 * (blo + bhi), top=float(bhi[2]))
    else:  # the largest cell behind the door (a shelf may divide it)
        cells = [
            _interior(obj, np.array([lo[0] - 0.05, 0.5 * (lo[1] + hi[1]), z]), top=None)
            for z in lo[2] + (hi[2] - lo[2]) * np.array([0.5, 0.25, 0.75])
        ]
        found = [c for c in cells if c is not None]
        inside = max(found, key=lambda c: float(np.prod(c[1]))) if found else None
        if inside is not None:  # the part of the cell behind this door's opening
            c_lo = np.maximum(inside[0] - inside[1] / 2, np.r_[-np.inf, lo[1:]])
            c_hi = np.minimum(inside[0] + inside[1] / 2, np.r_[np.inf, hi[1:]])
            ok = np.all(c_hi - c_lo >= MIN_INTERIOR)
            inside = (0.5 * (c_lo + c_hi), c_hi - c_lo) if ok else None
    return inside


def _part(obj: ArticulatedObject, j: JointInfo, kind: str, x_front: float, rgba: dict) -> dict:
    links = moving_subtree(obj.urdf, j)
    origin = j.T_base_joint[:3, 3].copy()
    boxes = _piece_boxes(obj, links)
    if not boxes:
        raise ConfigError(f"{obj.name}: part {j.child!r} has no collision geometry")
    front = [(lo, hi) for n, lo, hi in boxes if not _is_handle(n)] or [b[1:] for b in boxes]
    lo = np.min([a for a, _ in front], axis=0)
    hi = np.max([b for _, b in front], axis=0)
    handle, grasp, handle_axis, handle_geoms = _handle(boxes, j, kind, rgba["handle"])
    if grasp is None:
        grasp = np.array([hi[0], 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])])
        if kind == "door":
            c = 0.5 * (lo + hi)
            side = np.sign(c - origin) * (np.abs(c - origin) > 1e-6)
            side[0] = 0.0
            grasp[1:] = c[1:] + side[1:] * (0.5 * (hi[1:] - lo[1:]) - EDGE_INSET)
            if _hinge(j, lo, hi) in ("left", "right"):
                grasp[2] = c[2]
            else:
                grasp[1] = c[1]
    inside = _part_interior(obj, boxes, kind, lo, hi)
    boards = [
        box(f"board_{i}", a - origin, b - origin, rgba["front"])
        for i, (n, a, b) in enumerate(boxes)
        if not _is_handle(n)
    ]
    # The handle as the generator's parametric one, in the link frame.
    moved = [
        replace(g, pos=tuple(float(v) for v in np.asarray(g.pos) - origin)) for g in handle_geoms
    ]
    geoms = tuple(boards + moved)
    return {
        "link": j.child,
        "joint": j.name,
        "kind": kind,
        "semantic": j.semantic or kind,
        "cell_center": np.array([x_front, 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])]),
        "cell_size": np.array([hi[1] - lo[1], hi[2] - lo[2]]),
        "joint_type": j.type,
        "axis": j.axis_base.copy(),
        "origin": origin,
        "lower": j.lower,
        "upper": j.upper,
        "damping": j.damping,
        "friction": j.friction,
        "hinge": _hinge(j, lo, hi) if kind == "door" else None,
        "handle": handle,
        "handle_pos": grasp,
        "handle_axis": handle_axis if handle_axis is not None else np.array([1.0, 0.0, 0.0]),
        "interior_center": None if inside is None else inside[0],
        "interior_size": None if inside is None else inside[1],
        "geoms": geoms,
    }


def _colors(obj: ArticulatedObject, carcass: Sequence[str], parts: Sequence[str]) -> dict:
    def mean(links: Sequence[str], handles: bool) -> tuple[float, float, float, float]:
        cols = [
            v.rgba
            for n in links
            for v in obj.urdf.links[n].visuals
            if v.rgba is not None and _is_handle(v.name) == handles
        ]
        if not cols:
            return (0.7, 0.7, 0.7, 1.0)
        return tuple(float(x) for x in np.mean(cols, axis=0))  # type: ignore[return-value]

    return {
        "body": mean(carcass, False),
        "front": mean(parts, False),
        "handle": mean(parts, True),
    }


def describe_object(obj: ArticulatedObject) -> CabinetSpec:
    """The part description of a loaded, conformed object (module docstring).

    Raises:
        ConfigError: the object has no drawer or door, or a part has no geometry.
    """
    movable = [(j, _kind(j)) for j in obj.urdf.joints if j.movable]
    movable = [(j, k) for j, k in movable if k is not None]
    if not movable:
        raise ConfigError(f"{obj.name}: no drawer or door to describe")
    in_parts = {n for j, _ in movable for n in moving_subtree(obj.urdf, j)}
    carcass_links = [n for n in obj.urdf.links if n not in in_parts]
    carcass_boxes = _piece_boxes(obj, carcass_links)
    x_front = max(b[2][0] for b in carcass_boxes) if carcass_boxes else 0.0
    rgba = _colors(obj, carcass_links, sorted(in_parts))
    raw = [_part(obj, j, k, x_front, rgba) for j, k in movable]
    centers = np.array([r["cell_center"] for r in raw])
    rows, cols = _grid(centers[:, 2], True), _grid(centers[:, 1], False)
    body_geoms = tuple(
        box(f"board_{i}", lo, hi, rgba["body"]) for i, (_, lo, hi) in enumerate(carcass_boxes)
    )
    everything = [*body_geoms, *(g for r in raw for g in r["geoms"])]
    total = mass_properties(everything, {"wood": 1.0, "metal": 1.0}).mass
    density = obj.mass / total
    dens = {"wood": density, "metal": density}
    parts = []
    for r, row, col in zip(raw, rows, cols, strict=True):
        parts.append(
            PartSpec(row=int(row), col=int(col), inertial=mass_properties(r["geoms"], dens), **r)
        )
    thin = sorted(float(np.min(hi - lo)) for _, lo, hi in carcass_boxes)
    wall = float(np.clip(np.median(thin), *WALL_RANGE)) if thin else WALL_RANGE[0]
    heights = [max(p.cell_size[1] for p in parts if p.row == r) for r in range(rows.max() + 1)]
    widths = [max(p.cell_size[0] for p in parts if p.col == c) for c in range(cols.max() + 1)]
    carcass = _carcass(obj, carcass_links)
    size = obj.bounds[1] - obj.bounds[0]
    return CabinetSpec(
        seed=-1,
        kinds=tuple(sorted({p.kind for p in parts})),
        width=float(size[1]),
        depth=float(size[0]),
        height=float(size[2]),
        wall=wall,
        back=wall,
        plinth=0.0,
        rows=int(rows.max() + 1),
        cols=int(cols.max() + 1),
        row_heights=np.array(heights),
        col_widths=np.array(widths),
        body_geoms=body_geoms,
        body_inertial=mass_properties(body_geoms, dens),
        parts=tuple(parts),
        colors=rgba,
        carcass=carcass[0],
        carcass_joint=carcass[1],
        label=obj.folder.name if obj.folder is not None else obj.name,
    )


def _carcass(obj: ArticulatedObject, links: Sequence[str]) -> tuple[str, str]:
    """The carcass link (the one labelled a body in semantics, else the largest welded
    to the root) and the joint that holds it."""
    welded = [j for j in obj.urdf.joints if j.child in links]
    if not welded:
        return obj.root, "joint_root"
    labelled = [j for j in welded if "body" in j.semantic or j.semantic_type == "heavy"]
    best = labelled[0] if labelled else welded[0]
    return best.child, best.name
