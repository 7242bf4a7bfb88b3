"""Make a downloaded articulated object simulable and stand it like a generated cabinet.

A PartNet-Mobility object as downloaded is not ready for physics: its collision meshes
are zero-thickness panels (MuJoCo refuses them) or whole concave boxes (MuJoCo would
fill them), it faces away from the robot, it is furniture-sized (1.1-1.7 m, hundreds of
kilograms by board area), its joints have no damping or friction, and some of its
doors are closed at their *upper* limit. :func:`conform` rewrites a
:class:`~strug_manip.objects.urdf.ParsedUrdf` into the generator's conventions
(:mod:`strug_manip.objects.generator`, "Object frame"):

- **Collision pieces**: each collision mesh becomes its convex pieces
  (:func:`strug_manip.objects.meshes.convex_pieces`: a panel given a board's thickness,
  a near-convex mesh its hull, a concave one its CoACD decomposition, cached on disk),
  named after the visual that shows the same mesh (``handle-15``), so interiors stay
  hollow and handle geoms keep their names. Visual meshes are read once
  (:func:`~strug_manip.objects.meshes.read_obj`) with their material colour.
- **Front**: the side the drawers slide out of and the doors swing to (the mean of
  the parts' horizontal opening directions, snapped to the nearest side of the
  object's box) is turned to ``+x``; ``+z`` stays up (PartNet's base joint already
  turns its y-up meshes z-up).
- **Scale**: uniform, the scale nearest 1 at which the object's depth, width and
  height lie inside the generator's ranges (:data:`~strug_manip.objects.generator.
  DEPTH_RANGE`, ``WIDTH_RANGE``, ``HEIGHT_RANGE``), or, if no scale fits them all, the
  largest at which none exceeds its maximum: the object then stands on the cabinet
  table within the Fetch's reach, as every generated cabinet does. ``scale=``
  overrides it.
- **Origin**: on the carcass's bottom at the centre of its footprint (a file already
  so, within :data:`ORIGIN_SLACK`, keeps its own).
- **Joints**: positive positions open (a joint closed at its upper limit gets its axis
  and limits negated); where the URDF gives no ``<dynamics>``, the middle of the
  generator's ranges (:data:`DRAWER_DAMPING_DEFAULT` ...; a flap's friction stay is
  set by the loader once masses are known, :func:`flap_stay`).

The mass policy (total mass inside the generator's :data:`~strug_manip.objects.
generator.TOTAL_MASS`) is applied by the loader, which compiles the pieces' masses.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from strug_manip.objects.generator import (
    DEPTH_RANGE,
    DOOR_DAMPING,
    DOOR_FRICTION,
    DRAWER_DAMPING,
    DRAWER_FRICTION,
    FLAP_STAY_HOLD,
    GRAVITY,
    HEIGHT_RANGE,
    WIDTH_RANGE,
)
from strug_manip.objects.meshes import ObjMesh, convex_pieces, png_texture, read_obj
from strug_manip.objects.urdf import GeometryInfo, JointInfo, LinkInfo, ParsedUrdf, joint_tree

#: Damping [N s/m] and Coulomb friction [N] of a drawer whose URDF gives none: the middle
#: of the generator's ranges (ball-bearing runners), so a drawer stays where it is left.
DRAWER_DAMPING_DEFAULT = 0.5 * sum(DRAWER_DAMPING)
DRAWER_FRICTION_DEFAULT = 0.5 * sum(DRAWER_FRICTION)
#: Damping [N m s/rad] and friction [N m] of a side-hinged door (or a continuous joint)
#: whose URDF gives none: the middle of the generator's ranges (cup hinges).
DOOR_DAMPING_DEFAULT = 0.5 * sum(DOOR_DAMPING)
DOOR_FRICTION_DEFAULT = 0.5 * sum(DOOR_FRICTION)
#: A flap's friction stay holds this many times its horizontal gravity torque (the
#: middle of the generator's :data:`FLAP_STAY_HOLD`): without it a drop-down door falls
#: open and a lift-up one falls shut as soon as it is let go.
FLAP_HOLD_DEFAULT = 0.5 * sum(FLAP_STAY_HOLD)
#: A hinge whose axis leans more than this from vertical is a flap (top/bottom hinge).
FLAP_AXIS_COS = math.cos(math.radians(45.0))
#: Scales the automatic policy never goes beyond: a PartNet object is metres, not
#: millimetres (a scale outside means a unit error in the file, not furniture).
SCALE_BOUNDS = (0.05, 5.0)
#: The generator's size ranges [m] in object-frame order (x: depth, y: width, z: height).
SIZE_RANGES = np.array([DEPTH_RANGE, WIDTH_RANGE, HEIGHT_RANGE])
#: Relative slack on those ranges: a carcass within 5 % of them (glides, mouldings, a
#: generated cabinet's own feet) is left at its size.
SIZE_SLACK = 0.05
#: A file whose carcass is already centred on its origin and stands on it within this
#: [m] keeps its origin (a generated cabinet's glides reach 6 mm below its frame).
ORIGIN_SLACK = 0.01


@dataclass(frozen=True)
class Conformed:
    """A conformed object and what was done to it.

    Attributes:
        urdf: the rewritten URDF (object frame: front ``+x``, origin on the floor at the
            footprint's centre, scaled, every joint opening toward positive positions).
        scale: the uniform scale applied [-].
        yaw: the rotation about ``z`` that turned the front to ``+x`` [rad].
        flipped: joints whose axis and limits were negated.
        defaulted: joints that got the default damping and friction.
    """

    urdf: ParsedUrdf
    scale: float
    yaw: float
    flipped: tuple[str, ...]
    defaulted: tuple[str, ...]


def _transform(T: np.ndarray, pts: np.ndarray) -> np.ndarray:
    return pts @ T[:3, :3].T + T[:3, 3]


def _with_pieces(
    link: LinkInfo,
    cache_dir: Path | None,
    progress: bool,
    textures: dict[Path, np.ndarray | None],
) -> LinkInfo:
    """``link`` with every collision mesh replaced by its convex pieces and every visual
    mesh read into memory (with its material colour; ``textures``: the texture colours
    read so far, shared across the object's links)."""
    names = {(str(v.mesh), v.scale, v.T_link_geom.tobytes()): v.name for v in link.visuals}
    collisions = []
    for g in link.collisions:
        if g.shape != "mesh":
            collisions.append(g)
            continue
        name = names.get((str(g.mesh), g.scale, g.T_link_geom.tobytes()), g.name) or "piece"
        for piece in convex_pieces(g.mesh, g.scale, cache_dir=cache_dir, progress=progress):
            collisions.append(replace(g, name=name, vertices=piece, faces=None, mesh=None))
    visuals = []
    for g in link.visuals:
        if g.shape != "mesh" or g.mesh.suffix.lower() != ".obj":  # type: ignore[union-attr]
            visuals.append(g)
            continue
        visuals += _visual_parts(g, read_obj(g.mesh, textures), cache_dir)  # type: ignore[arg-type]
    return replace(link, collisions=tuple(collisions), visuals=tuple(visuals))


def geom_points(g: GeometryInfo) -> np.ndarray:
    """Points spanning a collision geom in its own frame, (n, 3) [m]: a piece's vertices,
    a primitive's bounding-box corners."""
    if g.vertices is not None:
        return g.vertices
    if g.shape == "box":
        h = np.asarray(g.size, dtype=float) / 2
    elif g.shape in ("cylinder", "capsule"):
        h = np.array([g.size[0], g.size[0], g.size[1] / 2])
    else:
        h = np.full(3, g.size[0]) if g.size else np.zeros(3)
    return np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]) * h


def _visual_parts(g: GeometryInfo, mesh: ObjMesh, cache_dir: Path | None) -> list[GeometryInfo]:
    """A visual OBJ as one geom per material (MuJoCo gives a geom one material): its
    faces, their own vertices (scaled), and the material's texture (as a PNG) where the
    faces have texture coordinates, else its colour."""
    out = []
    for k, mat in enumerate(mesh.materials):
        faces = mesh.faces[mesh.face_material == k]
        if len(faces) == 0:
            continue
        used, local = np.unique(faces, return_inverse=True)
        png = None
        if mat.texture is not None and mesh.face_texcoords is not None:
            png = png_texture(mat.texture, cache_dir)
        uv = {}
        if png is not None:
            uv = {
                "texture": png,
                "texcoords": mesh.texcoords,
                "face_texcoords": mesh.face_texcoords[mesh.face_material == k],
            }
        rgba = g.rgba or (mat.tint if png is not None else mat.rgba)
        verts = mesh.vertices[used] * np.asarray(g.scale)
        out.append(
            replace(g, vertices=verts, faces=local.reshape(-1, 3), rgba=rgba, mesh=None, **uv)
        )
    return out


def link_points(urdf: ParsedUrdf, link: str, T_base_link: np.ndarray) -> np.ndarray:
    """The collision points of ``link`` in the root frame (:func:`geom_points` of each
    geom), shape (n, 3) [m]."""
    pts = [
        _transform(T_base_link @ g.T_link_geom, geom_points(g)) for g in urdf.links[link].collisions
    ]
    return np.concatenate(pts) if pts else np.zeros((0, 3))


def link_poses(urdf: ParsedUrdf) -> dict[str, np.ndarray]:
    """Every link's pose in the root frame with the joints at 0, (4, 4) each."""
    poses = {urdf.root: np.eye(4)}
    for j in urdf.joints:
        poses[j.child] = j.T_base_joint
    return poses


def moving_subtree(urdf: ParsedUrdf, joint: JointInfo) -> list[str]:
    """The links a movable joint moves: its child and every link welded under it."""
    out, stack = [], [joint.child]
    while stack:
        link = stack.pop()
        out.append(link)
        stack += [j.child for j in urdf.children[link] if not j.movable]
    return out


def _opening_sign(j: JointInfo) -> float:
    """+1 if the part opens toward positive positions (the closed pose is position 0 at
    the lower end of its range), -1 if toward negative ones."""
    if j.type == "continuous":
        return 1.0
    return 1.0 if abs(j.upper) >= abs(j.lower) else -1.0


def opening_direction(urdf: ParsedUrdf, j: JointInfo) -> np.ndarray:
    """Where the part moves as it starts to open, in the root frame, (3,) (not unit)."""
    sign = _opening_sign(j)
    if j.type == "prismatic":
        return sign * j.axis_base
    poses = link_poses(urdf)
    pts = np.concatenate([link_points(urdf, n, poses[n]) for n in moving_subtree(urdf, j)])
    if len(pts) == 0:
        return np.zeros(3)
    lever = pts.mean(axis=0) - j.T_base_joint[:3, 3]
    return sign * np.cross(j.axis_base, lever)


def front_yaw(urdf: ParsedUrdf) -> float:
    """The rotation about ``z`` [rad] that turns the object's front to ``+x``: the front
    is the mean horizontal opening direction of its movable parts, snapped to the
    nearest of ``+-x``, ``+-y``; PartNet's ``-x`` if nothing moves horizontally."""
    total = np.zeros(2)
    for j in urdf.joints:
        if j.movable:
            d = opening_direction(urdf, j)[:2]
            n = float(np.linalg.norm(d))
            if n > 1e-9:
                total += d / n
    if np.linalg.norm(total) < 1e-9:
        total = np.array([-1.0, 0.0])
    heading = math.atan2(total[1], total[0])
    snapped = round(heading / (math.pi / 2)) * (math.pi / 2)
    return -snapped


def policy_scale(size_xyz: np.ndarray) -> float:
    """The automatic scale (module docstring) of an object whose carcass has extents
    ``size_xyz`` = (depth, width, height) [m] in the object frame (within
    :data:`SIZE_SLACK` of the ranges counts as inside)."""
    size = np.maximum(np.asarray(size_xyz, dtype=float), 1e-6)
    s_min = float(np.max((1.0 - SIZE_SLACK) * SIZE_RANGES[:, 0] / size))
    s_max = float(np.min((1.0 + SIZE_SLACK) * SIZE_RANGES[:, 1] / size))
    s = min(max(1.0, s_min), s_max) if s_min <= s_max else s_max
    return float(np.clip(s, *SCALE_BOUNDS))


def _scaled_geom(g: GeometryInfo, T: np.ndarray, s: float) -> GeometryInfo:
    """``g`` posed by ``T`` (a rigid change of its link frame) and scaled by ``s``."""
    T_new = T @ g.T_link_geom
    T_new[:3, 3] *= s
    if g.vertices is not None:
        return replace(g, T_link_geom=T_new, vertices=g.vertices * s)
    if g.shape == "mesh":
        return replace(g, T_link_geom=T_new, scale=tuple(v * s for v in g.scale))
    return replace(g, T_link_geom=T_new, size=tuple(v * s for v in g.size))


def _scaled_link(link: LinkInfo, T: np.ndarray, s: float) -> LinkInfo:
    inertial = {}
    if link.mass is not None:
        inertial = {
            "mass": link.mass * s**3,
            "com": s * _transform(T, link.com[None])[0],  # type: ignore[index]
            "inertia": s**5 * T[:3, :3] @ link.inertia @ T[:3, :3].T,
        }
    return replace(
        link,
        visuals=tuple(_scaled_geom(g, T, s) for g in link.visuals),
        collisions=tuple(_scaled_geom(g, T, s) for g in link.collisions),
        **inertial,
    )


def _default_dynamics(j: JointInfo, axis_object: np.ndarray) -> tuple[float, float]:
    if j.type == "prismatic":
        return DRAWER_DAMPING_DEFAULT, DRAWER_FRICTION_DEFAULT
    if j.type == "revolute" and abs(axis_object[2]) < FLAP_AXIS_COS:
        return DOOR_DAMPING_DEFAULT, 0.0  # a flap: its stay is set once masses are known
    return DOOR_DAMPING_DEFAULT, DOOR_FRICTION_DEFAULT


def is_flap(j: JointInfo) -> bool:
    """A revolute joint whose axis is nearer horizontal than vertical (object frame)."""
    return j.type == "revolute" and abs(float(j.axis_base[2])) < FLAP_AXIS_COS


def flap_stay(mass: float, lever: float) -> float:
    """Friction [N m] of a flap's stay: :data:`FLAP_HOLD_DEFAULT` times the gravity
    torque of ``mass`` [kg] at ``lever`` [m] from the hinge (the flap horizontal)."""
    return FLAP_HOLD_DEFAULT * mass * GRAVITY * lever


def conform(
    urdf: ParsedUrdf,
    *,
    scale: float | None = None,
    cache_dir: Path | None = None,
    progress: bool = True,
) -> Conformed:
    """Rewrite ``urdf`` into the generator's conventions (module docstring).

    Args:
        urdf: a parsed URDF whose meshes exist.
        scale: uniform scale; ``None``: the automatic policy (:func:`policy_scale`).
        cache_dir: where convex decompositions are cached (default: the user cache).
        progress: show a progress bar while decomposing concave meshes.

    Returns:
        The :class:`Conformed` object.
    """
    textures: dict[Path, np.ndarray | None] = {}
    links = {n: _with_pieces(link, cache_dir, progress, textures) for n, link in urdf.links.items()}
    pieced = replace(urdf, links=links)
    yaw = front_yaw(pieced)
    T_root, s = _root_frame(pieced, yaw, scale)
    new_links = {
        n: _scaled_link(link, T_root if n == urdf.root else np.eye(4), s)
        for n, link in links.items()
    }
    rows = [_joint_row(pieced, j, T_root, s) for j in pieced.joints]
    joints, children = joint_tree(urdf.root, [r for r, _, _ in rows])
    out = replace(pieced, links=new_links, joints=joints, children=children)
    flipped = tuple(r["name"] for r, f, _ in rows if f)
    defaulted = tuple(r["name"] for r, _, d in rows if d)
    return Conformed(out, s, yaw, flipped, defaulted)


def _root_frame(urdf: ParsedUrdf, yaw: float, scale: float | None) -> tuple[np.ndarray, float]:
    """The root link's new pose (turned by ``yaw``, then moved so the carcass's scaled
    footprint is centred on the origin and its bottom on z = 0; translation in unscaled
    metres), (4, 4), and the scale."""
    R = np.eye(4)
    R[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
    poses = link_poses(urdf)
    moving = {n for j in urdf.joints if j.movable for n in moving_subtree(urdf, j)}
    # The carcass decides scale and origin (handles and fronts standing proud do not).
    carcass = [n for n in urdf.links if n not in moving] or list(urdf.links)
    pts = np.concatenate([_transform(R, link_points(urdf, n, poses[n])) for n in carcass])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    s = policy_scale(hi - lo) if scale is None else float(scale)
    offset = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
    if np.all(np.abs(offset) <= ORIGIN_SLACK):
        offset[:] = 0.0  # already in the object frame (e.g. a generated cabinet's folder)
    T_root = R.copy()
    T_root[:3, 3] = -offset
    return T_root, s


def _joint_row(
    urdf: ParsedUrdf, j: JointInfo, T_root: np.ndarray, s: float
) -> tuple[dict, bool, bool]:
    """Joint ``j`` rewritten (its fields but the root-frame pose, for
    :func:`~strug_manip.objects.urdf.joint_tree`), whether its sign was flipped, and
    whether it got the default dynamics."""
    origin = (T_root @ j.origin) if j.parent == urdf.root else j.origin.copy()
    origin[:3, 3] *= s
    axis, lower, upper = j.axis.copy(), j.lower, j.upper
    flip = j.movable and _opening_sign(j) < 0
    if flip:
        axis, lower, upper = -axis, -upper, -lower
    if j.type == "prismatic":
        lower, upper = lower * s, upper * s
    damping, friction = j.damping, j.friction
    default = j.movable and damping == 0.0 and friction == 0.0
    if default:
        damping, friction = _default_dynamics(j, T_root[:3, :3] @ j.axis_base)
    row = {
        "name": j.name,
        "type": j.type,
        "parent": j.parent,
        "child": j.child,
        "origin": origin,
        "axis": axis,
        "lower": lower + 0.0,  # no "-0.0"
        "upper": upper + 0.0,
        "damping": damping,
        "friction": friction,
        "semantic": j.semantic,
        "semantic_type": j.semantic_type,
    }
    return row, flip, default


__all__: Sequence[str] = (
    "Conformed",
    "conform",
    "flap_stay",
    "front_yaw",
    "geom_points",
    "is_flap",
    "link_points",
    "link_poses",
    "moving_subtree",
    "opening_direction",
    "policy_scale",
)
