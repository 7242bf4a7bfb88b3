"""URDF and semantics.txt parsing for articulated objects (PartNet-Mobility layout).

A PartNet-Mobility object is a folder holding ``mobility.urdf`` (links ``base``,
``link_0``, ``link_1``, ...; joints ``joint_0``, ... of type ``prismatic``,
``revolute``, ``continuous`` or ``fixed``; geometry as primitives or meshes referenced
by paths relative to the folder, e.g. ``textured_objs/original-1.obj``) and
``semantics.txt`` (one line per link: ``link_i joint_word label``, e.g.
``link_1 slider drawer``, ``link_2 hinge door``, ``link_0 heavy furniture_body``).

:func:`parse_urdf` validates a file into a :class:`ParsedUrdf`: every problem found
(a missing mesh, an unsupported joint, an undefined link, ...) is reported at once,
in one :class:`~planners.errors.ConfigError` line naming the file.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TypeVar

import numpy as np

from planners.errors import ConfigError
from strug_manip.geometry import rpy_matrix

URDF_NAME = "mobility.urdf"
SEMANTICS_NAME = "semantics.txt"
JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")
UNSUPPORTED_JOINT_TYPES = ("floating", "planar")
MESH_EXTENSIONS = (".obj", ".stl", ".msh")


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
        vertices: a mesh given in memory instead of a file (the loader's collision
            pieces and visual meshes, :mod:`strug_manip.objects.conform`): vertices in
            the geom frame, scale applied, shape (n, 3) [m]; ``None`` for files.
        faces: its triangles, shape (m, 3) int, or ``None`` (a convex piece: MuJoCo
            takes the hull of the vertices).
        texture: a PNG image the geometry wears, or ``None``: a visual mesh's (then
            ``texcoords`` (k, 2) and ``face_texcoords`` (m, 3) int map it), or a
            primitive's material texture (a generated finish, mapped in metres).
    """

    name: str
    shape: str
    size: tuple[float, ...]
    mesh: Path | None
    scale: tuple[float, float, float]
    T_link_geom: np.ndarray
    rgba: tuple[float, float, float, float] | None
    vertices: np.ndarray | None = field(default=None, repr=False, compare=False)
    faces: np.ndarray | None = field(default=None, repr=False, compare=False)
    texture: Path | None = None
    texcoords: np.ndarray | None = field(default=None, repr=False, compare=False)
    face_texcoords: np.ndarray | None = field(default=None, repr=False, compare=False)

    def key(self) -> tuple:
        """Identity of the geometry (shape, size, file, pose), to merge visual+collision."""
        return (
            self.shape,
            tuple(round(s, 9) for s in self.size),
            str(self.mesh) if self.vertices is None else id(self.vertices),
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


T = TypeVar("T")


class _ProblemError(Exception):
    """One problem of a URDF element (collected by :class:`_Parser`)."""


class _Parser:
    """Parses one URDF file; every problem becomes a ConfigError naming the file."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.folder = path.parent
        self.warnings: list[str] = []
        #: Every problem found so far: the parse goes on past a bad element, so that
        #: one message lists them all.
        self.problems: list[str] = []

    def fail(self, problem: str) -> _ProblemError:
        return _ProblemError(problem)

    def collect(self, parse: Callable[..., T], *args: object) -> T | None:
        """``parse(*args)``, or ``None`` with its problem recorded."""
        try:
            return parse(*args)
        except (_ProblemError, ConfigError) as e:
            self.problems.append(str(e))
            return None

    def check(self) -> None:
        """Raise the problems found, all in one line naming the file."""
        if self.problems:
            raise ConfigError(f"malformed URDF {self.path}: {'; '.join(self.problems)}")

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
        T[:3, :3] = rpy_matrix(rpy)
        T[:3, 3] = xyz
        return T

    def materials(self, root: ET.Element) -> dict[str, tuple]:
        """Named materials: ``name -> (rgba or None, texture path or None)``."""
        out = {}
        for m in root.findall("material"):
            if m.get("name"):
                out[m.get("name")] = self.material(m, f"material {m.get('name')!r}")
        return out

    def material(self, m: ET.Element, what: str) -> tuple:
        """One ``<material>``: its colour and the PNG its ``<texture filename>`` names
        (other image formats are skipped with a warning: MuJoCo reads PNG)."""
        color, tex = m.find("color"), m.find("texture")
        rgba = None
        if color is not None:
            rgba = self.floats(color.get("rgba"), 4, f"{what} <color rgba>", (1, 1, 1, 1))
        texture = None
        name = tex.get("filename", "") if tex is not None else ""
        if name:
            path = Path(name) if Path(name).is_absolute() else self.folder / name
            if not path.is_file() or path.suffix.lower() != ".png":
                self.warnings.append(f"skipped {what} texture {name!r} (not a PNG file)")
            else:
                texture = path.resolve()
        return rgba, texture

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
        rgba = texture = None
        mat = elem.find("material")
        if mat is not None:
            rgba, texture = self.material(mat, what)
            if rgba is None and texture is None:
                rgba, texture = materials.get(mat.get("name", ""), (None, None))
        return GeometryInfo(
            name=elem.get("name", ""),
            shape=shape,
            size=tuple(size),
            mesh=mesh,
            scale=tuple(scale),  # type: ignore[arg-type]
            T_link_geom=self.origin(elem.find("origin"), what),
            rgba=rgba,  # type: ignore[arg-type]
            texture=texture if shape != "mesh" else None,
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
        visuals = [
            self.collect(self.geometry, v, name, "visual", materials)
            for v in elem.findall("visual")
        ]
        collisions = [
            self.collect(self.geometry, c, name, "collision", materials)
            for c in elem.findall("collision")
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
        warnings: what was skipped.
    """

    name: str
    root: str
    links: dict[str, LinkInfo]
    joints: tuple[JointInfo, ...]
    children: dict[str, list[JointInfo]]
    warnings: tuple[str, ...]


def parse_urdf(urdf_path: Path, *, require_movable: bool = False) -> ParsedUrdf:
    """Parse and validate a URDF (and the ``semantics.txt`` next to it, if any).

    Args:
        urdf_path: the file.
        require_movable: an object without a movable joint is a problem too.

    Raises:
        ConfigError: one line naming the file and every problem found.
    """
    urdf_path = Path(urdf_path)
    if not urdf_path.is_file():
        raise ConfigError(f"URDF file {urdf_path} not found")
    p = _Parser(urdf_path)
    try:
        tree = ET.parse(urdf_path)
    except ET.ParseError as e:
        raise ConfigError(f"malformed URDF {urdf_path}: not valid XML ({e})") from None
    return _parse_tree(
        p, tree, lambda links: _read_semantics(urdf_path.parent, links), require_movable
    )


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
        raise ConfigError(f"malformed URDF {path}: not valid XML ({e})") from None
    return _parse_tree(p, tree, lambda links: _parse_semantics(semantics, path, links))


def _parse_tree(
    p: _Parser,
    tree: ET.ElementTree,
    read_semantics: Callable[[dict], dict],
    require_movable: bool = False,
) -> ParsedUrdf:
    root_elem = tree.getroot()
    if root_elem.tag != "robot":
        raise ConfigError(
            f"malformed URDF {p.path}: the root element is <{root_elem.tag}>, expected <robot>"
        )
    materials = p.collect(p.materials, root_elem) or {}
    links: dict[str, LinkInfo] = {}
    for elem in root_elem.findall("link"):
        name = elem.get("name")
        if not name:
            p.problems.append("a <link> has no name")
        elif name in links:
            p.problems.append(f"link {name!r} is defined twice")
        else:
            link = p.collect(p.link, elem, materials)
            if link is not None:
                links[name] = link
    if not links:
        p.problems.append("no <link> defined")
        p.check()
    raw = [p.collect(p.joint, e, links) for e in root_elem.findall("joint")]
    seen, parent_of = set(), {}
    for j in raw:
        if j is None:
            continue
        if j["name"] in seen:
            p.problems.append(f"joint {j['name']!r} is defined twice")
        elif j["child"] in parent_of:
            p.problems.append(f"link {j['child']!r} is the child of two joints")
        else:
            parent_of[j["child"]] = j
        seen.add(j["name"])
    roots = [n for n in links if n not in parent_of]
    if len(roots) != 1:
        p.problems.append(f"expected exactly one root link, found {len(roots)}: {roots}")
    if require_movable and not any(j is not None and j["type"] != "fixed" for j in raw):
        p.problems.append("no movable part (every joint is fixed)")
    semantics = p.collect(read_semantics, links) or {}
    p.check()
    for n, (word, label) in semantics.items():
        links[n] = replace(links[n], semantic_type=word, semantic=label)
    for j in parent_of.values():
        j["semantic_type"], j["semantic"] = semantics.get(j["child"], ("", ""))
    joints, children = joint_tree(roots[0], list(parent_of.values()))
    order = [roots[0], *(j.child for j in joints)]
    if len(order) != len(links):
        loose = sorted(set(links) - set(order))
        p.problems.append(f"links {loose} are not connected to the root {roots[0]!r} (a cycle?)")
        p.check()
    return ParsedUrdf(
        name=root_elem.get("name", p.path.parent.name),
        root=roots[0],
        links={n: links[n] for n in order},
        joints=joints,
        children=children,
        warnings=tuple(p.warnings),
    )


def joint_tree(
    root: str, raw: Sequence[Mapping]
) -> tuple[tuple[JointInfo, ...], dict[str, list[JointInfo]]]:
    """Joints in tree order (depth first from ``root``) with their poses in the root
    frame, and each link's child joints.

    Args:
        root: the root link.
        raw: one mapping per joint with :class:`JointInfo`'s fields but the last two
            (``T_base_joint``, ``axis_base``, computed here).
    """
    by_parent: dict[str, list[Mapping]] = {}
    for j in raw:
        by_parent.setdefault(j["parent"], []).append(j)
    joints: list[JointInfo] = []
    children: dict[str, list[JointInfo]] = {root: []}

    def visit(link: str, T_base_link: np.ndarray) -> None:
        for j in by_parent.get(link, []):
            T = T_base_link @ j["origin"]
            info = JointInfo(**j, T_base_joint=T, axis_base=T[:3, :3] @ j["axis"])
            joints.append(info)
            children[link].append(info)
            children[j["child"]] = []
            visit(j["child"], T)

    visit(root, np.eye(4))
    return tuple(joints), children
