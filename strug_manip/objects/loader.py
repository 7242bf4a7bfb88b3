"""Load articulated objects: a PartNet-Mobility folder or a generated cabinet.

- :func:`load_articulated_object` parses any PartNet-Mobility folder (ours or a
  downloaded object) into an :class:`ArticulatedObject` holding a MuJoCo model (built
  with :class:`mujoco.MjSpec`, radians), a Pinocchio model and per-joint metadata.
- :func:`load_cabinet_spec` does the same for a generated (or believed) cabinet, in
  memory.
- :func:`add_to_spec` embeds the object into a larger ``MjSpec`` (a scene) at a pose.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin

from planners.errors import ConfigError, UnknownNameError
from strug_manip.objects.generator import JOINT_EFFORT, JOINT_VELOCITY, CabinetSpec
from strug_manip.objects.mjcf import (
    BASE_FRICTION,
    FLOOR_SIZE,
    build_bodies,
    collision_bounds,
    compile_spec,
)
from strug_manip.objects.partnet import cabinet_semantics, cabinet_urdf, fmt_float
from strug_manip.objects.urdf import (
    URDF_NAME,
    JointInfo,
    LinkInfo,
    ParsedUrdf,
    parse_urdf,
    parse_urdf_text,
)


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
    return build_bodies(
        spec,
        obj.urdf,
        pos=pos,
        yaw=yaw,
        free=free,
        prefix=prefix,
        base_friction=base_friction,
        mass_scale=obj.mass_scale,
    )


def _pinocchio(urdf: ParsedUrdf, path: Path) -> pin.Model:
    """Pinocchio's model of the parsed URDF (from its XML tree, in memory)."""
    root = urdf.tree.getroot()
    if urdf.needs_sanitizing:
        # urdfdom (Pinocchio's parser) requires effort and velocity in every <limit>;
        # PartNet-Mobility files omit them: fill them in on a copy.
        root = ET.fromstring(ET.tostring(root))
        for lim in root.iter("limit"):
            lim.set("effort", lim.get("effort", fmt_float(JOINT_EFFORT)))
            lim.set("velocity", lim.get("velocity", fmt_float(JOINT_VELOCITY)))
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
        build_bodies(
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
    model = compile_spec(spec, urdf_path)
    bounds = collision_bounds(model, set(range(1, model.nbody)))
    mass_scale = 1.0
    if total_mass is not None:
        mass_scale = total_mass / float(model.body_mass[1:].sum())
    if (floor and abs(bounds[0, 2]) > 1e-9) or mass_scale != 1.0:
        spec = make_spec(-bounds[0, 2] if floor else 0.0, mass_scale)
        model = compile_spec(spec, urdf_path)
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
