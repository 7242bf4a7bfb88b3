"""PartNet-Mobility layout: write generated cabinets, load any articulated object.

A PartNet-Mobility object is a folder holding ``mobility.urdf`` (links ``base``,
``link_0``, ``link_1``, ...; joints ``joint_0``, ... of type ``prismatic``,
``revolute``, ``continuous`` or ``fixed``; geometry as primitives or meshes referenced
by paths relative to the folder, e.g. ``textured_objs/original-1.obj``) and
``semantics.txt`` (one line per link: ``link_i joint_word label``, e.g.
``link_1 slider drawer``, ``link_2 hinge door``, ``link_0 heavy furniture_body``).

- :func:`write_partnet` writes a :class:`~strug_manip.objects.generator.CabinetSpec`
  in that layout (plus ``spec.json``, the generator's ground truth).
- :func:`load_articulated_object` parses any such folder (ours or a downloaded
  PartNet-Mobility object) into an :class:`ArticulatedObject` holding a MuJoCo model
  (built with :class:`mujoco.MjSpec`, radians), a Pinocchio model
  (``pin.buildModelFromUrdf``) and per-joint metadata.
- :func:`add_to_spec` embeds the object into a larger ``MjSpec`` (a scene) at a pose.

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

import json
import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin

from planners.errors import ConfigError, UnknownNameError
from strug_manip.objects.generator import (
    JOINT_EFFORT,
    JOINT_VELOCITY,
    SEMANTICS,
    CabinetSpec,
    Geom,
    Inertial,
)

URDF_NAME = "mobility.urdf"
SEMANTICS_NAME = "semantics.txt"
SPEC_NAME = "spec.json"
JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")
UNSUPPORTED_JOINT_TYPES = ("floating", "planar")
MESH_EXTENSIONS = (".obj", ".stl", ".msh")
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


# ------------------------------------------------------------------------------------
# Writing
# ------------------------------------------------------------------------------------


def _f(x: float) -> str:
    """Format a float for URDF (9 significant digits, no '-0')."""
    s = f"{float(x):.9g}"
    return "0" if s == "-0" else s


def _v(xs: Sequence[float]) -> str:
    return " ".join(_f(x) for x in xs)


_CYL_RPY = {"x": (0.0, math.pi / 2, 0.0), "y": (math.pi / 2, 0.0, 0.0), "z": (0.0, 0.0, 0.0)}


def _geom_xml(g: Geom, material: str) -> str:
    if g.shape == "box":
        shape, rpy = f'<box size="{_v(g.size)}"/>', (0.0, 0.0, 0.0)
    elif g.shape == "sphere":
        shape, rpy = f'<sphere radius="{_f(g.size[0])}"/>', (0.0, 0.0, 0.0)
    else:
        shape = f'<cylinder radius="{_f(g.size[0])}" length="{_f(g.size[1])}"/>'
        rpy = _CYL_RPY[g.axis]
    origin = f'<origin xyz="{_v(g.pos)}" rpy="{_v(rpy)}"/>'
    geometry = f"<geometry>{shape}</geometry>"
    return (
        f'    <visual name="{g.name}">{origin}{geometry}<material name="{material}"/></visual>\n'
        f'    <collision name="{g.name}">{origin}{geometry}</collision>\n'
    )


def _link_xml(name: str, geoms: Sequence[Geom], inertial: Inertial, materials: dict) -> str:
    J = inertial.inertia
    out = [
        f'  <link name="{name}">\n',
        f'    <inertial><origin xyz="{_v(inertial.com)}" rpy="0 0 0"/>'
        f'<mass value="{_f(inertial.mass)}"/>'
        f'<inertia ixx="{_f(J[0, 0])}" ixy="{_f(J[0, 1])}" ixz="{_f(J[0, 2])}" '
        f'iyy="{_f(J[1, 1])}" iyz="{_f(J[1, 2])}" izz="{_f(J[2, 2])}"/></inertial>\n',
    ]
    out += [_geom_xml(g, materials[g.rgba]) for g in geoms]
    out.append("  </link>\n")
    return "".join(out)


def cabinet_urdf(spec: CabinetSpec) -> str:
    """The ``mobility.urdf`` text of a generated cabinet (PartNet-Mobility layout).

    ``base`` is an empty root; ``link_0`` (the carcass) hangs on it by the fixed
    ``joint_0``; each cell's part ``link_k`` hangs on ``link_0`` by ``joint_k``.
    """
    materials: dict[tuple[float, ...], str] = {}
    for key, rgba in spec.colors.items():
        materials.setdefault(tuple(rgba), key)
    for g in (*spec.body_geoms, *(g for p in spec.parts for g in p.geoms)):
        materials.setdefault(tuple(g.rgba), f"color_{len(materials)}")
    kinds = ",".join(spec.kinds)
    out = [
        '<?xml version="1.0" ?>\n',
        f'<robot name="{spec.name}">\n',
        f"  <!-- generated by strug_manip.objects.generator: seed {spec.seed}, kinds {kinds};"
        " MIT licence, strug-manip -->\n",
    ]
    out += [
        f'  <material name="{n}"><color rgba="{_v(c)}"/></material>\n' for c, n in materials.items()
    ]
    out.append('  <link name="base"/>\n')
    out.append(_link_xml("link_0", spec.body_geoms, spec.body_inertial, materials))
    out.append(
        '  <joint name="joint_0" type="fixed"><origin xyz="0 0 0" rpy="0 0 0"/>'
        '<parent link="base"/><child link="link_0"/></joint>\n'
    )
    for p in spec.parts:
        out.append(_link_xml(p.link, p.geoms, p.inertial, materials))
        body = [
            f'<origin xyz="{_v(p.origin)}" rpy="0 0 0"/>',
            '<parent link="link_0"/>',
            f'<child link="{p.link}"/>',
        ]
        if p.movable:
            body += [
                f'<axis xyz="{_v(p.axis)}"/>',
                f'<limit lower="{_f(p.lower)}" upper="{_f(p.upper)}" '
                f'effort="{_f(JOINT_EFFORT)}" velocity="{_f(JOINT_VELOCITY)}"/>',
                f'<dynamics damping="{_f(p.damping)}" friction="{_f(p.friction)}"/>',
            ]
        out.append(f'  <joint name="{p.joint}" type="{p.joint_type}">{"".join(body)}</joint>\n')
    out.append("</robot>\n")
    return "".join(out)


def cabinet_semantics(spec: CabinetSpec) -> str:
    """The ``semantics.txt`` text: ``link_i joint_word label`` per link."""
    lines = ["link_0 {} {}".format(*SEMANTICS["body"])]
    lines += [f"{p.link} {SEMANTICS[p.kind][0]} {SEMANTICS[p.kind][1]}" for p in spec.parts]
    return "\n".join(lines) + "\n"


def _arr(x: np.ndarray | None) -> list[float] | None:
    return None if x is None else [float(v) for v in x]


def cabinet_summary(spec: CabinetSpec) -> dict:
    """JSON-able ground truth of a generated cabinet (object frame, [m], [rad], [kg])."""
    return {
        "generator": "strug_manip.objects.generator",
        "seed": spec.seed,
        "kinds": list(spec.kinds),
        "size_xyz": [spec.depth, spec.width, spec.height],
        "wall": spec.wall,
        "plinth": spec.plinth,
        "grid": [spec.rows, spec.cols],
        "mass": spec.mass,
        "parts": [
            {
                "link": p.link,
                "joint": p.joint,
                "kind": p.kind,
                "semantic": p.semantic,
                "row": p.row,
                "col": p.col,
                "joint_type": p.joint_type,
                "axis": _arr(p.axis),
                "origin": _arr(p.origin),
                "limits": [p.lower, p.upper],
                "damping": p.damping,
                "friction": p.friction,
                "hinge": p.hinge,
                "handle": p.handle,
                "handle_pos": _arr(p.handle_pos),
                "handle_axis": _arr(p.handle_axis),
                "interior_center": _arr(p.interior_center),
                "interior_size": _arr(p.interior_size),
                "mass": p.inertial.mass,
            }
            for p in spec.parts
        ],
    }


def write_partnet(spec: CabinetSpec, folder: str | Path) -> Path:
    """Write ``spec`` as a PartNet-Mobility folder (created if needed).

    Writes ``mobility.urdf``, ``semantics.txt`` and ``spec.json``.

    Returns:
        The folder's path.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / URDF_NAME).write_text(cabinet_urdf(spec))
    (folder / SEMANTICS_NAME).write_text(cabinet_semantics(spec))
    (folder / SPEC_NAME).write_text(json.dumps(cabinet_summary(spec), indent=1) + "\n")
    return folder


# ------------------------------------------------------------------------------------
# Parsed URDF
# ------------------------------------------------------------------------------------


@dataclass(frozen=True)
class GeometryInfo:
    """One ``<visual>`` or ``<collision>`` element.

    Attributes:
        name: the element's ``name`` attribute (may be empty).
        shape: ``box``, ``cylinder``, ``sphere``, ``capsule`` or ``mesh``.
        size: box full extents (3,), cylinder/capsule ``(radius, length)``, sphere
            ``(radius,)`` [m]; empty for meshes.
        mesh: absolute path of the mesh file, or None.
        scale: mesh scale, (3,).
        T_link_geom: pose in the link frame, (4, 4).
        rgba: colour (4,) or None.
    """

    name: str
    shape: str
    size: tuple[float, ...]
    mesh: Path | None
    scale: tuple[float, float, float]
    T_link_geom: np.ndarray
    rgba: tuple[float, float, float, float] | None

    def key(self) -> tuple:
        """Identity of the geometry (shape, size, file, pose), to merge visual+collision."""
        return (
            self.shape,
            tuple(round(s, 9) for s in self.size),
            str(self.mesh),
            self.scale,
            tuple(np.round(self.T_link_geom[:3], 9).ravel()),
        )


@dataclass(frozen=True)
class LinkInfo:
    """One URDF link.

    Attributes:
        name: link name.
        visuals, collisions: its geometry.
        mass: [kg], or None if the link has no ``<inertial>``.
        com: centre of mass in the link frame (3,) [m], or None.
        inertia: inertia about the COM in the link frame (3, 3) [kg m^2], or None.
        semantic_type: semantics.txt joint word (``slider``, ``hinge``, ``static``,
            ``heavy``, ...), ``""`` if not listed.
        semantic: semantics.txt label (``drawer``, ``door``, ...), ``""`` if not listed.
    """

    name: str
    visuals: tuple[GeometryInfo, ...]
    collisions: tuple[GeometryInfo, ...]
    mass: float | None
    com: np.ndarray | None
    inertia: np.ndarray | None
    semantic_type: str = ""
    semantic: str = ""


@dataclass(frozen=True)
class JointInfo:
    """One URDF joint and where it is on the object.

    Attributes:
        name: joint name (``joint_3``).
        type: ``prismatic``, ``revolute``, ``continuous`` or ``fixed``.
        parent, child: link names.
        origin: ``T_parent_child`` at joint position 0, (4, 4) [m].
        axis: unit axis in the joint (= child link) frame, (3,).
        lower, upper: limits [m] or [rad] (``-inf``/``inf`` for continuous, 0 for fixed).
        damping: [N s/m] or [N m s/rad]; friction: [N] or [N m].
        semantic: label of the child link (``drawer``, ``door``, ...), ``""`` if unknown.
        semantic_type: joint word of the child link in semantics.txt.
        T_base_joint: pose of the joint frame in the root link frame with every joint
            at 0, (4, 4) [m].
        axis_base: the axis in the root link frame, (3,).
    """

    name: str
    type: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    lower: float
    upper: float
    damping: float
    friction: float
    semantic: str
    semantic_type: str
    T_base_joint: np.ndarray
    axis_base: np.ndarray

    @property
    def movable(self) -> bool:
        """True unless the joint is fixed."""
        return self.type != "fixed"


@dataclass
class ArticulatedObject:
    """An articulated object loaded from a PartNet-Mobility folder.

    Attributes:
        name: the URDF robot name.
        folder: the object folder; urdf_path: its ``mobility.urdf`` (both ``None`` for
            an object loaded in memory, :func:`load_cabinet_spec`).
        root: root link name (``base``).
        links: link name -> :class:`LinkInfo`, in tree order (root first).
        joints: every joint (fixed ones included), in tree order.
        mj_spec: the standalone MuJoCo spec (floor plane if ``floor``, then the object).
        mj_model: its compiled model.
        pin_model: the Pinocchio model (fixed base: the root link is Pinocchio's
            universe; continuous joints take two coordinates).
        free: whether the standalone model has a free joint on the root.
        bounds: axis-aligned bounds of the collision geometry in the root link frame
            with every joint at 0, rows (min, max), shape (2, 3) [m].
        mass: total mass in the MuJoCo model [kg].
        warnings: things skipped while loading (e.g. visual meshes of unsupported formats).
        urdf: the parsed URDF (what :func:`add_to_spec` builds from).
        base_friction: sliding friction of the base geoms.
        mass_scale: factor applied to every URDF/estimated mass (``total_mass``).
    """

    name: str
    folder: Path | None
    urdf_path: Path | None
    root: str
    links: dict[str, LinkInfo]
    joints: tuple[JointInfo, ...]
    mj_spec: mujoco.MjSpec
    mj_model: mujoco.MjModel
    pin_model: pin.Model
    free: bool
    bounds: np.ndarray
    mass: float
    warnings: tuple[str, ...]
    urdf: ParsedUrdf = field(repr=False)
    base_friction: float = BASE_FRICTION
    mass_scale: float = 1.0

    @property
    def movable_joints(self) -> tuple[JointInfo, ...]:
        """Prismatic, revolute and continuous joints, in tree order."""
        return tuple(j for j in self.joints if j.movable)

    def joint(self, name: str) -> JointInfo:
        """The joint called ``name``."""
        for j in self.joints:
            if j.name == name:
                return j
        raise UnknownNameError("joint", name, [j.name for j in self.joints])

    def random_configuration(self, rng: np.random.Generator) -> dict[str, float]:
        """Uniform joint positions within the limits ([-pi, pi] for continuous joints)."""
        out = {}
        for j in self.movable_joints:
            lo, hi = (j.lower, j.upper) if j.type != "continuous" else (-math.pi, math.pi)
            out[j.name] = float(rng.uniform(lo, hi))
        return out

    def pin_configuration(self, positions: Mapping[str, float]) -> np.ndarray:
        """Pinocchio ``q`` (nq,) from joint positions by name (missing joints at 0)."""
        q = pin.neutral(self.pin_model)
        for name, value in positions.items():
            if not self.pin_model.existJointName(name):
                raise UnknownNameError("joint", name, [j.name for j in self.movable_joints])
            jid = self.pin_model.getJointId(name)
            iq, nq = self.pin_model.idx_qs[jid], self.pin_model.nqs[jid]
            if nq == 2:  # continuous joint: (cos, sin)
                q[iq : iq + 2] = (math.cos(value), math.sin(value))
            else:
                q[iq] = value
        return q

    def mujoco_qpos_address(self, model: mujoco.MjModel, name: str, prefix: str = "") -> int:
        """Address in ``data.qpos`` of URDF joint ``name`` in ``model``: this object's
        standalone model, or a scene (pass the prefix used with :func:`add_to_spec`)."""
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, prefix + name)
        if jid < 0:
            raise UnknownNameError("joint", prefix + name, [j.name for j in self.movable_joints])
        return int(model.jnt_qposadr[jid])

    def to_mjcf(self) -> str:
        """The standalone model as MJCF XML (``<compiler angle="radian"/>``)."""
        return self.mj_spec.to_xml()


# ------------------------------------------------------------------------------------
# Parsing
# ------------------------------------------------------------------------------------


def _rpy_matrix(rpy: Sequence[float]) -> np.ndarray:
    """URDF fixed-axis roll-pitch-yaw [rad] -> rotation matrix Rz(y) Ry(p) Rx(r), (3, 3)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = (
        math.cos(r),
        math.sin(r),
        math.cos(p),
        math.sin(p),
        math.cos(y),
        math.sin(y),
    )
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _quat(R: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) -> MuJoCo quaternion (w, x, y, z), (4,)."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).ravel())
    return q


class _Parser:
    """Parses one URDF file; every problem becomes a ConfigError naming the file."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.folder = path.parent
        self.needs_sanitizing = False
        self.warnings: list[str] = []

    def fail(self, problem: str) -> ConfigError:
        return ConfigError(f"malformed URDF {self.path}: {problem}")

    def floats(self, text: str | None, n: int, what: str, default: Sequence[float]) -> tuple:
        if text is None:
            return tuple(float(v) for v in default)
        try:
            vals = tuple(float(v) for v in text.split())
        except ValueError:
            vals = ()
        if len(vals) != n or not all(math.isfinite(v) for v in vals):
            raise self.fail(f"{what} must be {n} finite number(s), got {text!r}")
        return vals

    def scalar(self, elem: ET.Element | None, attr: str, what: str, default: float = 0.0) -> float:
        text = elem.get(attr) if elem is not None else None
        return self.floats(text, 1, what, (default,))[0]

    def origin(self, elem: ET.Element | None, what: str) -> np.ndarray:
        T = np.eye(4)
        if elem is None:
            return T
        xyz = self.floats(elem.get("xyz"), 3, f"{what} <origin xyz>", (0, 0, 0))
        rpy = self.floats(elem.get("rpy"), 3, f"{what} <origin rpy>", (0, 0, 0))
        T[:3, :3] = _rpy_matrix(rpy)
        T[:3, 3] = xyz
        return T

    def materials(self, root: ET.Element) -> dict[str, tuple]:
        out = {}
        for m in root.findall("material"):
            color = m.find("color")
            if m.get("name") and color is not None:
                what = f"material {m.get('name')!r} <color rgba>"
                out[m.get("name")] = self.floats(color.get("rgba"), 4, what, (1, 1, 1, 1))
        return out

    def geometry(
        self, elem: ET.Element, link: str, kind: str, materials: dict
    ) -> GeometryInfo | None:
        what = f"link {link!r} <{kind}>"
        geo = elem.find("geometry")
        if geo is None or len(geo) == 0:
            raise self.fail(f"{what} has no <geometry>")
        shape_elem = geo[0]
        shape, size, mesh, scale = shape_elem.tag, (), None, (1.0, 1.0, 1.0)
        if shape == "box":
            size = self.floats(shape_elem.get("size"), 3, f"{what} <box size>", ())
        elif shape in ("cylinder", "capsule"):
            r = self.floats(shape_elem.get("radius"), 1, f"{what} <{shape} radius>", ())
            length = self.floats(shape_elem.get("length"), 1, f"{what} <{shape} length>", ())
            size = (r[0], length[0])
        elif shape == "sphere":
            size = self.floats(shape_elem.get("radius"), 1, f"{what} <sphere radius>", ())
        elif shape == "mesh":
            mesh = self.mesh_path(shape_elem.get("filename"), what)
            if mesh.suffix.lower() not in MESH_EXTENSIONS:
                if kind == "collision":
                    raise self.fail(
                        f"{what} mesh {mesh.name!r} has an unsupported format; MuJoCo reads "
                        f"{', '.join(MESH_EXTENSIONS)}"
                    )
                self.warnings.append(f"skipped visual mesh {mesh} (unsupported format)")
                return None
            scale = self.floats(shape_elem.get("scale"), 3, f"{what} <mesh scale>", (1, 1, 1))
        else:
            raise self.fail(f"{what} has unknown geometry <{shape}>")
        if any(s <= 0 for s in size) or any(s == 0 for s in scale):
            raise self.fail(f"{what} <{shape}> must have positive sizes, got {size or scale}")
        rgba = None
        mat = elem.find("material")
        if mat is not None:
            color = mat.find("color")
            if color is not None:
                rgba = self.floats(color.get("rgba"), 4, f"{what} <color rgba>", (1, 1, 1, 1))
            else:
                rgba = materials.get(mat.get("name", ""))
        return GeometryInfo(
            name=elem.get("name", ""),
            shape=shape,
            size=tuple(size),
            mesh=mesh,
            scale=tuple(scale),  # type: ignore[arg-type]
            T_link_geom=self.origin(elem.find("origin"), what),
            rgba=rgba,  # type: ignore[arg-type]
        )

    def mesh_path(self, filename: str | None, what: str) -> Path:
        if not filename:
            raise self.fail(f"{what} <mesh> has no filename")
        name = filename
        for scheme in ("file://", "package://"):
            if name.startswith(scheme):
                name = name[len(scheme) :]
        candidates = [self.folder / name]
        if filename.startswith("package://") and "/" in name:
            candidates.append(self.folder / name.split("/", 1)[1])
        if Path(name).is_absolute():
            candidates.insert(0, Path(name))
        for c in candidates:
            if c.is_file():
                return c.resolve()
        raise self.fail(f"{what} mesh file {filename!r} not found (looked in {self.folder})")

    def link(self, elem: ET.Element, materials: dict) -> LinkInfo:
        name = elem.get("name", "")
        visuals = [self.geometry(v, name, "visual", materials) for v in elem.findall("visual")]
        collisions = [
            self.geometry(c, name, "collision", materials) for c in elem.findall("collision")
        ]
        mass = com = inertia = None
        inertial = elem.find("inertial")
        if inertial is not None:
            what = f"link {name!r} <inertial>"
            m_elem, i_elem = inertial.find("mass"), inertial.find("inertia")
            m = self.scalar(m_elem, "value", f"{what} <mass value>")
            keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
            ixx, ixy, ixz, iyy, iyz, izz = (self.scalar(i_elem, k, f"{what} {k}") for k in keys)
            T = self.origin(inertial.find("origin"), what)
            if m < 0:
                raise self.fail(f"{what} mass must be >= 0, got {m}")
            if m > 0:
                I_frame = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
                mass, com = m, T[:3, 3].copy()
                inertia = T[:3, :3] @ I_frame @ T[:3, :3].T
        return LinkInfo(
            name=name,
            visuals=tuple(v for v in visuals if v is not None),
            collisions=tuple(c for c in collisions if c is not None),
            mass=mass,
            com=com,
            inertia=inertia,
        )

    def joint(self, elem: ET.Element, links: dict) -> dict:
        name = elem.get("name")
        if not name:
            raise self.fail("a <joint> has no name")
        jtype = elem.get("type", "")
        what = f"joint {name!r}"
        if jtype in UNSUPPORTED_JOINT_TYPES:
            raise self.fail(
                f"{what} has type {jtype!r}, which is not supported; "
                f"expected one of: {', '.join(JOINT_TYPES)}"
            )
        if jtype not in JOINT_TYPES:
            raise self.fail(
                f"{what} has unknown type {jtype!r}; expected one of: {', '.join(JOINT_TYPES)}"
            )
        ends = {}
        for tag in ("parent", "child"):
            e = elem.find(tag)
            link = e.get("link") if e is not None else None
            if not link:
                raise self.fail(f"{what} has no <{tag} link=...>")
            if link not in links:
                raise self.fail(f"{what} references {tag} link {link!r}, which is not defined")
            ends[tag] = link
        axis = np.zeros(3)
        lower = upper = 0.0
        damping = friction = 0.0
        if jtype != "fixed":
            a = elem.find("axis")
            axis = np.array(
                self.floats(
                    a.get("xyz") if a is not None else None, 3, f"{what} <axis xyz>", (1, 0, 0)
                )
            )
            norm = float(np.linalg.norm(axis))
            if norm < 1e-9:
                raise self.fail(
                    f"{what} <axis xyz> must be a non-zero vector, got {a.get('xyz')!r}"
                )
            axis = axis / norm
            lim = elem.find("limit")
            if jtype == "continuous":
                lower, upper = -math.inf, math.inf
            else:
                if lim is None:
                    raise self.fail(
                        f"{what} ({jtype}) has no <limit>; URDF requires lower/upper limits"
                    )
                lower = self.scalar(lim, "lower", f"{what} <limit lower>")
                upper = self.scalar(lim, "upper", f"{what} <limit upper>")
                if lower > upper:
                    raise self.fail(f"{what} <limit> lower {lower} > upper {upper}")
                if lim.get("effort") is None or lim.get("velocity") is None:
                    self.needs_sanitizing = True  # urdfdom (Pinocchio) requires both
            dyn = elem.find("dynamics")
            damping = self.scalar(dyn, "damping", f"{what} <dynamics damping>")
            friction = self.scalar(dyn, "friction", f"{what} <dynamics friction>")
            if damping < 0 or friction < 0:
                raise self.fail(f"{what} <dynamics> damping and friction must be >= 0")
        return {
            "name": name,
            "type": jtype,
            "parent": ends["parent"],
            "child": ends["child"],
            "origin": self.origin(elem.find("origin"), what),
            "axis": axis,
            "lower": lower,
            "upper": upper,
            "damping": damping,
            "friction": friction,
        }


def _read_semantics(folder: Path, links: Mapping[str, LinkInfo]) -> dict[str, tuple[str, str]]:
    path = folder / SEMANTICS_NAME
    if not path.is_file():
        return {}
    return _parse_semantics(path.read_text(), path, links)


def _parse_semantics(
    text: str, path: Path, links: Mapping[str, LinkInfo]
) -> dict[str, tuple[str, str]]:
    """``{link: (joint word, label)}`` of a semantics.txt's ``text`` (``path``: for
    messages)."""
    out = {}
    for i, line in enumerate(text.splitlines(), start=1):
        words = line.split()
        if not words:
            continue
        if len(words) != 3:
            raise ConfigError(
                f"malformed {path} line {i}: expected 'link_name joint_word label', got {line!r}"
            )
        if words[0] not in links:
            raise ConfigError(f"malformed {path} line {i}: link {words[0]!r} is not in the URDF")
        out[words[0]] = (words[1], words[2])
    return out


@dataclass(frozen=True)
class ParsedUrdf:
    """A validated URDF: links and joints in tree order (see :func:`parse_urdf`).

    Attributes:
        name: robot name; root: root link.
        links: link name -> :class:`LinkInfo`, root first.
        joints: every joint, depth first.
        children: link name -> the joints whose parent it is.
        needs_sanitizing: some ``<limit>`` lacks effort/velocity (urdfdom rejects it).
        tree: the XML tree; warnings: what was skipped.
    """

    name: str
    root: str
    links: dict[str, LinkInfo]
    joints: tuple[JointInfo, ...]
    children: dict[str, list[JointInfo]]
    needs_sanitizing: bool
    tree: ET.ElementTree
    warnings: tuple[str, ...]


def parse_urdf(urdf_path: Path) -> ParsedUrdf:
    """Parse and validate a URDF (and the ``semantics.txt`` next to it, if any).

    Raises:
        ConfigError: one message naming the file and the problem.
    """
    urdf_path = Path(urdf_path)
    if not urdf_path.is_file():
        raise ConfigError(f"URDF file {urdf_path} not found")
    p = _Parser(urdf_path)
    try:
        tree = ET.parse(urdf_path)
    except ET.ParseError as e:
        raise p.fail(f"not valid XML ({e})") from None
    return _parse_tree(p, tree, lambda links: _read_semantics(urdf_path.parent, links))


def parse_urdf_text(urdf: str, semantics: str = "", *, path: str | Path = URDF_NAME) -> ParsedUrdf:
    """Parse and validate a URDF given as text, with its ``semantics.txt`` text, in
    memory (no file is read or written; meshes are looked up relative to ``path``).

    Args:
        urdf: the URDF XML.
        semantics: the semantics.txt lines ("" for none).
        path: where the URDF would live, for messages and relative mesh paths.

    Raises:
        ConfigError: one message naming ``path`` and the problem.
    """
    path = Path(path)
    p = _Parser(path)
    try:
        tree = ET.ElementTree(ET.fromstring(urdf))
    except ET.ParseError as e:
        raise p.fail(f"not valid XML ({e})") from None
    return _parse_tree(p, tree, lambda links: _parse_semantics(semantics, path, links))


def _parse_tree(
    p: _Parser, tree: ET.ElementTree, read_semantics: Callable[[dict], dict]
) -> ParsedUrdf:
    urdf_path = p.path
    root_elem = tree.getroot()
    if root_elem.tag != "robot":
        raise p.fail(f"the root element is <{root_elem.tag}>, expected <robot>")
    materials = p.materials(root_elem)
    links: dict[str, LinkInfo] = {}
    for elem in root_elem.findall("link"):
        name = elem.get("name")
        if not name:
            raise p.fail("a <link> has no name")
        if name in links:
            raise p.fail(f"link {name!r} is defined twice")
        links[name] = p.link(elem, materials)
    if not links:
        raise p.fail("no <link> defined")
    raw = [p.joint(e, links) for e in root_elem.findall("joint")]
    seen, parent_of = set(), {}
    for j in raw:
        if j["name"] in seen:
            raise p.fail(f"joint {j['name']!r} is defined twice")
        seen.add(j["name"])
        if j["child"] in parent_of:
            raise p.fail(f"link {j['child']!r} is the child of two joints")
        parent_of[j["child"]] = j
    roots = [n for n in links if n not in parent_of]
    if len(roots) != 1:
        raise p.fail(f"expected exactly one root link, found {len(roots)}: {roots}")
    semantics = read_semantics(links)
    for n, (word, label) in semantics.items():
        links[n] = replace(links[n], semantic_type=word, semantic=label)
    # Tree order (depth first from the root), with each joint's pose in the root frame.
    by_parent: dict[str, list[dict]] = {}
    for j in raw:
        by_parent.setdefault(j["parent"], []).append(j)
    joints: list[JointInfo] = []
    children: dict[str, list[JointInfo]] = {n: [] for n in links}
    order = [roots[0]]

    def visit(link: str, T_base_link: np.ndarray) -> None:
        for j in by_parent.get(link, []):
            T = T_base_link @ j["origin"]
            sem_type, sem = semantics.get(j["child"], ("", ""))
            info = JointInfo(
                **j,
                semantic=sem,
                semantic_type=sem_type,
                T_base_joint=T,
                axis_base=T[:3, :3] @ j["axis"],
            )
            joints.append(info)
            children[link].append(info)
            order.append(j["child"])
            visit(j["child"], T)

    visit(roots[0], np.eye(4))
    if len(order) != len(links):
        loose = sorted(set(links) - set(order))
        raise p.fail(f"links {loose} are not connected to the root {roots[0]!r} (a cycle?)")
    return ParsedUrdf(
        name=root_elem.get("name", urdf_path.parent.name),
        root=roots[0],
        links={n: links[n] for n in order},
        joints=tuple(joints),
        children=children,
        needs_sanitizing=p.needs_sanitizing,
        tree=tree,
        warnings=tuple(p.warnings),
    )


# ------------------------------------------------------------------------------------
# MuJoCo
# ------------------------------------------------------------------------------------


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


def _build(
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
    existing = {m.name for m in spec.meshes}
    # Base group: the root and every link welded to it by fixed joints.
    base_group = {urdf.root}
    for j in urdf.joints:
        if j.type == "fixed" and j.parent in base_group:
            base_group.add(j.child)

    def mesh_name(g: GeometryInfo) -> str:
        key = (str(g.mesh), g.scale)
        if key not in meshes:
            stem, k = f"{prefix}{g.mesh.stem}", 0  # type: ignore[union-attr]
            name = stem
            while name in existing:
                k += 1
                name = f"{stem}_{k}"
            existing.add(name)
            m = spec.add_mesh(name=name, file=str(g.mesh), scale=list(g.scale))
            m.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
            meshes[key] = name
        return meshes[key]

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
                    quat=_quat(g.T_link_geom[:3, :3]),
                )
                if g.shape == "mesh":
                    geom.meshname = mesh_name(g)
                rgba = (vis.rgba if vis is not None else None) or g.rgba
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
            name=prefix + j.child, pos=j.origin[:3, 3], quat=_quat(j.origin[:3, :3])
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


def add_to_spec(
    spec: mujoco.MjSpec,
    obj: ArticulatedObject,
    pos: Sequence[float] = (0.0, 0.0, 0.0),
    yaw: float = 0.0,
    *,
    free: bool = True,
    prefix: str = "cabinet/",
    on_floor: bool = True,
    base_friction: float | None = None,
) -> mujoco.MjsBody:
    """Embed ``obj`` into ``spec`` (a scene) at a pose; return its root body.

    Names get ``prefix`` (bodies ``cabinet/link_1``, joints ``cabinet/joint_1``, the free
    joint ``cabinet/free``). Works with scenes compiled in degrees or radians.

    Args:
        spec: the scene spec, modified in place.
        obj: a loaded object.
        pos: where the root link frame goes in the world, (3,) [m]; with ``on_floor``
            the object is raised by ``-obj.bounds[0, 2]`` so its lowest collision point
            is at ``pos[2]`` (our cabinets: no change).
        yaw: rotation about the world z axis [rad].
        free: give the root a free joint (dragged by wrong pulls) or weld it to the world.
        prefix: name prefix, must be unique in the scene.
        on_floor: see ``pos``.
        base_friction: sliding friction of the base; default: the value used at loading.

    Returns:
        The root body (``prefix + obj.root``).
    """
    pos = np.asarray(pos, dtype=float)
    if pos.shape != (3,) or not np.all(np.isfinite(pos)) or not math.isfinite(yaw):
        raise ConfigError(f"pos must be 3 finite numbers and yaw finite, got {pos!r}, {yaw!r}")
    if spec.body(prefix + obj.root) is not None:
        raise ConfigError(
            f"the scene already has a body {prefix + obj.root!r}; give each object its own prefix"
        )
    if on_floor:
        pos = pos + np.array([0.0, 0.0, -obj.bounds[0, 2]])
    if base_friction is None:
        base_friction = obj.base_friction
    return _build(
        spec,
        obj.urdf,
        pos=pos,
        yaw=yaw,
        free=free,
        prefix=prefix,
        base_friction=base_friction,
        mass_scale=obj.mass_scale,
    )


def _compile(spec: mujoco.MjSpec, path: Path) -> mujoco.MjModel:
    try:
        return spec.compile()
    except Exception as e:  # MuJoCo reports bad meshes, inertias, ... as ValueError
        raise ConfigError(f"cannot build a MuJoCo model from {path}: {e}") from None


def _bounds(model: mujoco.MjModel, body_ids: set[int]) -> np.ndarray:
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


def _pinocchio(urdf: ParsedUrdf, path: Path) -> pin.Model:
    """Pinocchio's model of the parsed URDF (from its XML tree, in memory)."""
    root = urdf.tree.getroot()
    if urdf.needs_sanitizing:
        # urdfdom (Pinocchio's parser) requires effort and velocity in every <limit>;
        # PartNet-Mobility files omit them: fill them in on a copy.
        root = ET.fromstring(ET.tostring(root))
        for lim in root.iter("limit"):
            lim.set("effort", lim.get("effort", _f(JOINT_EFFORT)))
            lim.set("velocity", lim.get("velocity", _f(JOINT_VELOCITY)))
    try:
        return pin.buildModelFromXML(ET.tostring(root, encoding="unicode"))
    except Exception as e:  # urdfdom errors surface as ValueError/RuntimeError
        raise ConfigError(f"malformed URDF {path}: Pinocchio cannot parse it ({e})") from None


def load_cabinet_spec(
    spec: CabinetSpec,
    *,
    free: bool = True,
    floor: bool = True,
    base_friction: float = BASE_FRICTION,
) -> ArticulatedObject:
    """Load a generated (or believed) cabinet into MuJoCo and Pinocchio in memory: the
    same URDF and semantics :func:`write_partnet` would write, parsed from text, so a
    belief particle compiles without touching the disk. ``folder`` and ``urdf_path``
    of the result are ``None``. Options as :func:`load_articulated_object`.

    Raises:
        ConfigError: ``spec`` is not a :class:`CabinetSpec`, or a bad option.
    """
    if not isinstance(spec, CabinetSpec):
        raise ConfigError(f"spec must be a CabinetSpec, got {type(spec).__name__}")
    path = Path(spec.name) / URDF_NAME
    urdf = parse_urdf_text(cabinet_urdf(spec), cabinet_semantics(spec), path=path)
    return _load(urdf, path, None, free=free, floor=floor, base_friction=base_friction)


def load_articulated_object(
    folder: str | Path,
    *,
    free: bool = True,
    floor: bool = True,
    base_friction: float = BASE_FRICTION,
    total_mass: float | None = None,
) -> ArticulatedObject:
    """Load a PartNet-Mobility folder (or a ``.urdf`` path) into MuJoCo and Pinocchio.

    Args:
        folder: the object folder holding ``mobility.urdf`` (and optionally
            ``semantics.txt``), or the URDF file itself.
        free: give the root link a free joint in the standalone MuJoCo model.
        floor: add a floor plane at z = 0 and stand the object on it (lowest collision
            point at z = 0); otherwise the root frame is at the world origin.
        base_friction: sliding friction of the base against the floor.
        total_mass: if given, rescale every mass so the object weighs this [kg].

    Returns:
        The :class:`ArticulatedObject`.

    Raises:
        ConfigError: one message naming the file and the problem (missing file, bad
            XML, unknown joint type, undefined link, non-finite number, unreadable mesh).
    """
    path = Path(folder)
    urdf_path = path if path.suffix.lower() == ".urdf" else path / URDF_NAME
    if total_mass is not None and not (math.isfinite(total_mass) and total_mass > 0):
        raise ConfigError(f"total_mass must be a finite number > 0, got {total_mass!r}")
    urdf = parse_urdf(urdf_path)
    return _load(
        urdf,
        urdf_path,
        urdf_path.parent,
        free=free,
        floor=floor,
        base_friction=base_friction,
        total_mass=total_mass,
    )


def _load(
    urdf: ParsedUrdf,
    urdf_path: Path,
    folder: Path | None,
    *,
    free: bool,
    floor: bool,
    base_friction: float,
    total_mass: float | None = None,
) -> ArticulatedObject:
    """The :class:`ArticulatedObject` of a parsed URDF (``folder`` None: in memory)."""
    if not math.isfinite(base_friction) or base_friction < 0:
        raise ConfigError(f"base_friction must be a finite number >= 0, got {base_friction!r}")
    pin_model = _pinocchio(urdf, urdf_path)

    def make_spec(z: float, mass_scale: float) -> mujoco.MjSpec:
        spec = mujoco.MjSpec()
        spec.modelname = urdf.name
        spec.compiler.degree = False
        if floor:
            spec.worldbody.add_geom(
                name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[FLOOR_SIZE, FLOOR_SIZE, 0.1]
            )
        _build(
            spec,
            urdf,
            pos=(0.0, 0.0, z),
            yaw=0.0,
            free=free,
            prefix="",
            base_friction=base_friction,
            mass_scale=mass_scale,
        )
        return spec

    spec = make_spec(0.0, 1.0)
    model = _compile(spec, urdf_path)
    bounds = _bounds(model, set(range(1, model.nbody)))
    mass_scale = 1.0
    if total_mass is not None:
        mass_scale = total_mass / float(model.body_mass[1:].sum())
    if (floor and abs(bounds[0, 2]) > 1e-9) or mass_scale != 1.0:
        spec = make_spec(-bounds[0, 2] if floor else 0.0, mass_scale)
        model = _compile(spec, urdf_path)
    return ArticulatedObject(
        name=urdf.name,
        folder=folder,
        urdf_path=None if folder is None else urdf_path,
        root=urdf.root,
        links=urdf.links,
        joints=urdf.joints,
        mj_spec=spec,
        mj_model=model,
        pin_model=pin_model,
        free=free,
        bounds=bounds,
        mass=float(model.body_mass[1:].sum()),
        warnings=urdf.warnings,
        urdf=urdf,
        base_friction=base_friction,
        mass_scale=mass_scale,
    )
