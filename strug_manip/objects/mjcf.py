"""Build an articulated object's MuJoCo bodies from a parsed URDF.

MuJoCo conversion (documented choices)
--------------------------------------
- One body per URDF link, named ``prefix + link``; joints ``prefix + joint``; the root
  link optionally gets a free joint ``prefix + "free"`` so the object can be dragged.
- Collision geometry collides (group 0 if an identical visual exists, else group 3);
  visual-only geometry is group 1 and never collides nor weighs. Handle geoms keep
  their URDF names (``.../handle_bar``), useful for segmentation.
- Masses: a link's ``<inertial>`` is used as given (inertia rotated into the link
  frame, made physically valid if needed). A link without one gets its mass from its
  collision geometry as hollow boards: shell inertia with surface density
  ``SHELL_DENSITY`` = 6 kg/m^2 (about a 10 mm board); a moving link with no mass of its
  own nor welded under it (a PartNet "helper" link) gets 1e-3 kg, as MuJoCo requires.
  ``total_mass`` rescales the whole object.
- Contacts: excluded between every body of the base group (the root and every link
  welded to it by fixed joints) and every other body of the object, and between every
  link and its ancestors. Parts that are siblings (two drawers, a door and a drawer)
  still collide with each other, and everything collides with the world.
- The base's collision geoms have sliding friction ``base_friction`` (default 0.5,
  wood/laminate on a hard floor) and ``priority=1`` so that value, not MuJoCo's
  max-of-pair rule, decides friction against the floor.
- Joint ``<dynamics damping friction>`` become MuJoCo ``damping`` and
  ``frictionloss`` (stiff, as the limits: a load below the friction does not make the
  joint creep); ``<limit>`` becomes ``range`` (``continuous``: unlimited). Limits
  are *hard stops* (:data:`LIMIT_SOLREF`, :data:`LIMIT_SOLIMP`: the stiffest constraint
  MuJoCo integrates stably at a 2 ms step): the parts' contacts with their own carcass
  are excluded (fronts sit in their openings with millimetre gaps), so the joint limit
  is what keeps a door from being pushed through its closed stop.
- Collision meshes are convex hulls in MuJoCo (a PartNet drawer mesh becomes a solid
  block: run a convex decomposition first if objects must go inside).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np

from planners.errors import ConfigError
from strug_manip.geometry import quat_of
from strug_manip.objects.finishes import GRAIN_METRES
from strug_manip.objects.urdf import GeometryInfo, LinkInfo, ParsedUrdf

SHELL_DENSITY = 6.0  # [kg/m^2] surface density of links without <inertial>
HELPER_MASS = 1e-3  # [kg] mass of a moving link without inertial nor geometry
HELPER_INERTIA = 1e-6  # [kg m^2]
BASE_FRICTION = 0.5  # sliding friction of the base against the floor
FLOOR_SIZE = 5.0  # [m] half-size of the standalone floor plane
#: Joint-limit constraint: time constant [s] (two 2 ms steps, MuJoCo's stability floor)
#: and damping ratio, so a stop yields a few millimetres under 100 N, not centimetres.
LIMIT_SOLREF = (0.004, 1.0)
#: Joint-limit impedance (d0, dwidth, width [m or rad], midpoint, power): near-rigid.
LIMIT_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)


def _valid_inertia(J: np.ndarray) -> np.ndarray:
    """Symmetric positive inertia satisfying the triangle inequality (MuJoCo's check)."""
    J = 0.5 * (J + J.T)
    w, V = np.linalg.eigh(J)
    w = np.maximum(w, 1e-9)
    for k in range(3):
        a, b, c = w[k], w[(k + 1) % 3], w[(k + 2) % 3]
        if a > b + c:
            extra = 0.5 * (a - b - c) + 1e-12
            w[(k + 1) % 3] += extra
            w[(k + 2) % 3] += extra
    return V @ np.diag(w) @ V.T


_GEOM_TYPES = {
    "box": mujoco.mjtGeom.mjGEOM_BOX,
    "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
    "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE,
    "sphere": mujoco.mjtGeom.mjGEOM_SPHERE,
    "mesh": mujoco.mjtGeom.mjGEOM_MESH,
}


def _mj_size(g: GeometryInfo) -> list[float]:
    if g.shape == "box":
        return [0.5 * s for s in g.size]
    if g.shape in ("cylinder", "capsule"):
        return [g.size[0], 0.5 * g.size[1], 0.0]
    if g.shape == "sphere":
        return [g.size[0], 0.0, 0.0]
    return [0.0, 0.0, 0.0]


def build_bodies(
    spec: mujoco.MjSpec,
    urdf: ParsedUrdf,
    *,
    pos: Sequence[float],
    yaw: float,
    free: bool,
    prefix: str,
    base_friction: float,
    mass_scale: float = 1.0,
) -> mujoco.MjsBody:
    """Add the object's bodies to ``spec.worldbody``; return the root body.

    ``mass_scale`` multiplies every mass and inertia (URDF, shell and helper ones).
    """
    hinge_scale = 180.0 / math.pi if spec.compiler.degree else 1.0
    meshes: dict[tuple, str] = {}
    materials: dict[tuple, str] = {}
    existing = {m.name for m in spec.meshes}
    # Base group: the root and every link welded to it by fixed joints.
    base_group = {urdf.root}
    for j in urdf.joints:
        if j.type == "fixed" and j.parent in base_group:
            base_group.add(j.child)

    def mesh_name(g: GeometryInfo) -> str:
        key = (str(g.mesh), g.scale) if g.vertices is None else ("mem", id(g.vertices))
        if key not in meshes:
            stem = f"{prefix}{g.mesh.stem if g.mesh is not None else g.name or 'mesh'}"
            name, k = stem, 0
            while name in existing:
                k += 1
                name = f"{stem}_{k}"
            existing.add(name)
            if g.vertices is None:
                m = spec.add_mesh(name=name, file=str(g.mesh), scale=list(g.scale))
            else:
                m = spec.add_mesh(name=name, uservert=g.vertices.ravel().tolist())
                if g.faces is not None:
                    m.userface = g.faces.ravel().tolist()
                if g.texture is not None:
                    m.usertexcoord = g.texcoords.ravel().tolist()  # type: ignore[union-attr]
                    m.userfacetexcoord = g.face_texcoords.ravel().tolist()  # type: ignore[union-attr]
            m.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
            meshes[key] = name
        return meshes[key]

    def material_name(g: GeometryInfo) -> str:
        """A material wearing ``g.texture`` (one per image and tint). A primitive has no
        texture coordinates: MuJoCo maps the image in metres (``texuniform``), one copy
        per :data:`~strug_manip.objects.finishes.GRAIN_METRES`."""
        key = (str(g.texture), g.rgba, g.shape == "mesh")
        if key not in materials:
            name = f"{prefix}material_{len(materials)}"
            spec.add_texture(name=name, type=mujoco.mjtTexture.mjTEXTURE_2D, file=str(g.texture))
            mat = spec.add_material(name=name, rgba=list(g.rgba or (1.0, 1.0, 1.0, 1.0)))
            mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = name
            if g.shape != "mesh":
                mat.texuniform = True
                mat.texrepeat = [1.0 / GRAIN_METRES, 1.0 / GRAIN_METRES]
            materials[key] = name
        return materials[key]

    def add_geoms(body: mujoco.MjsBody, link: LinkInfo) -> None:
        in_base = link.name in base_group
        explicit = link.mass is not None
        collision_keys = {c.key(): c for c in link.collisions}
        merged = {}
        names: set[str] = set()

        def unique(base: str) -> str:
            n, k = base, 0
            while n in names:
                k += 1
                n = f"{base}_{k}"
            names.add(n)
            return f"{prefix}{link.name}/{n}"

        for v in link.visuals:
            if v.key() in collision_keys and v.key() not in merged:
                merged[v.key()] = v
        for kind, items in (("collision", link.collisions), ("visual", link.visuals)):
            for i, g in enumerate(items):
                if kind == "visual" and g.key() in merged and merged[g.key()] is g:
                    continue
                vis = merged.get(g.key()) if kind == "collision" else None
                geom = body.add_geom(
                    name=unique(g.name or f"{kind}_{i}"),
                    type=_GEOM_TYPES[g.shape],
                    size=_mj_size(g),
                    pos=g.T_link_geom[:3, 3],
                    quat=quat_of(g.T_link_geom[:3, :3]),
                )
                if g.shape == "mesh":
                    geom.meshname = mesh_name(g)
                rgba = (vis.rgba if vis is not None else None) or g.rgba
                if vis is not None and vis.texture is not None:
                    geom.material = material_name(vis)
                if kind == "collision":
                    geom.group = 0 if vis is not None else 3
                    geom.rgba = rgba if rgba is not None else (0.6, 0.6, 0.6, 1.0 if vis else 0.4)
                    if g.shape != "mesh":  # meshes: set on the mesh asset
                        geom.typeinertia = mujoco.mjtGeomInertia.mjINERTIA_SHELL
                    geom.density = 0.0 if explicit else SHELL_DENSITY * mass_scale
                    if in_base:
                        geom.friction = [base_friction, 0.005, 0.0001]
                        geom.priority = 1
                else:
                    geom.group, geom.contype, geom.conaffinity = 1, 0, 0
                    geom.density = 0.0
                    geom.rgba = rgba if rgba is not None else (0.7, 0.7, 0.7, 1.0)
                    if g.texture is not None:
                        geom.material = material_name(g)

    def weighs(name: str) -> bool:
        """Whether a link, or a link welded under it by fixed joints, has mass."""
        link = urdf.links[name]
        if link.mass is not None or link.collisions:
            return True
        return any(weighs(j.child) for j in urdf.children[name] if j.type == "fixed")

    def set_inertial(body: mujoco.MjsBody, link: LinkInfo, moving: bool) -> None:
        if link.mass is not None:
            J = _valid_inertia(link.inertia) * mass_scale  # type: ignore[arg-type]
            body.mass = link.mass * mass_scale
            body.ipos = link.com
            body.fullinertia = [J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]]
            body.explicitinertial = True
        elif moving and not weighs(link.name):
            body.mass = HELPER_MASS * mass_scale
            body.inertia = [HELPER_INERTIA * mass_scale] * 3
            body.explicitinertial = True

    root_link = urdf.links[urdf.root]
    root = spec.worldbody.add_body(
        name=prefix + urdf.root, pos=list(pos), quat=[math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)]
    )
    if free:
        root.add_freejoint(name=prefix + "free")
    add_geoms(root, root_link)
    set_inertial(root, root_link, moving=free)
    bodies = {urdf.root: root}
    ancestors: dict[str, list[str]] = {urdf.root: []}
    for j in urdf.joints:  # depth-first: the parent body exists already
        link = urdf.links[j.child]
        body = bodies[j.parent].add_body(
            name=prefix + j.child, pos=j.origin[:3, 3], quat=quat_of(j.origin[:3, :3])
        )
        if j.movable:
            mj = body.add_joint(
                name=prefix + j.name,
                type=mujoco.mjtJoint.mjJNT_SLIDE
                if j.type == "prismatic"
                else mujoco.mjtJoint.mjJNT_HINGE,
                axis=j.axis,
                damping=j.damping,
                frictionloss=j.friction,
            )
            if j.type == "continuous":
                mj.limited = mujoco.mjtLimited.mjLIMITED_FALSE
            else:
                scale = hinge_scale if j.type == "revolute" else 1.0
                mj.limited = mujoco.mjtLimited.mjLIMITED_TRUE
                mj.range = [j.lower * scale, j.upper * scale]
                mj.solref_limit = list(LIMIT_SOLREF)
                mj.solimp_limit = list(LIMIT_SOLIMP)
            # Stiff dry friction too: a soft friction constraint lets a flap on its stay
            # creep shut (or a drawer roll) under a load below its friction.
            mj.solref_friction = list(LIMIT_SOLREF)
            mj.solimp_friction = list(LIMIT_SOLIMP)
        add_geoms(body, link)
        set_inertial(body, link, moving=j.movable)
        bodies[j.child] = body
        ancestors[j.child] = [*ancestors[j.parent], j.parent]
    pairs = set()
    for name in bodies:
        if name not in base_group:
            pairs.update((b, name) for b in base_group)
        pairs.update((a, name) for a in ancestors[name])
    for a, b in sorted(pairs):
        spec.add_exclude(bodyname1=prefix + a, bodyname2=prefix + b)
    return root


def compile_spec(spec: mujoco.MjSpec, path: Path) -> mujoco.MjModel:
    try:
        return spec.compile()
    except Exception as e:  # MuJoCo reports bad meshes, inertias, ... as ValueError
        raise ConfigError(f"cannot build a MuJoCo model from {path}: {e}") from None


def collision_bounds(model: mujoco.MjModel, body_ids: set[int]) -> np.ndarray:
    """AABB (2, 3) of the collision geoms of ``body_ids`` in the world frame [m]."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    pts = []
    colliding = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
    for g in range(model.ngeom):
        if model.geom_bodyid[g] not in body_ids or not colliding[g]:
            continue
        R, p = data.geom_xmat[g].reshape(3, 3), data.geom_xpos[g]
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            mid = model.geom_dataid[g]
            adr, n = model.mesh_vertadr[mid], model.mesh_vertnum[mid]
            local = model.mesh_vert[adr : adr + n].astype(float)
        else:
            c, h = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
            signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)])
            local = c + signs * h
        pts.append(local @ R.T + p)
    if not pts:
        return np.zeros((2, 3))
    allp = np.concatenate(pts)
    return np.stack([allp.min(axis=0), allp.max(axis=0)])
