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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin

from planners.errors import ConfigError, UnknownNameError
from strug_manip.objects.conform import conform, flap_stay, is_flap
from strug_manip.objects.generator import JOINT_EFFORT, JOINT_VELOCITY, TOTAL_MASS, CabinetSpec
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
    joint_tree,
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
        scale: the uniform scale the loader applied to the file's geometry [-].
        yaw: the turn about ``z`` that brought the file's front to ``+x`` [rad].
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
    scale: float = 1.0
    yaw: float = 0.0

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


def kinematic_urdf(urdf: ParsedUrdf) -> str:
    """The kinematic tree of ``urdf`` as URDF text (links without geometry; every
    ``<limit>`` with the effort and velocity urdfdom requires)."""
    out = [f'<robot name="{urdf.name}">']
    out += [f'<link name="{n}"/>' for n in urdf.links]
    for j in urdf.joints:
        T = j.origin
        rpy = pin.rpy.matrixToRpy(T[:3, :3])
        body = [
            f'<origin xyz="{" ".join(fmt_float(v) for v in T[:3, 3])}" '
            f'rpy="{" ".join(fmt_float(v) for v in rpy)}"/>',
            f'<parent link="{j.parent}"/><child link="{j.child}"/>',
        ]
        if j.movable:
            body.append(f'<axis xyz="{" ".join(fmt_float(v) for v in j.axis)}"/>')
        if j.type in ("prismatic", "revolute"):
            body.append(
                f'<limit lower="{fmt_float(j.lower)}" upper="{fmt_float(j.upper)}" '
                f'effort="{fmt_float(JOINT_EFFORT)}" velocity="{fmt_float(JOINT_VELOCITY)}"/>'
            )
        out.append(f'<joint name="{j.name}" type="{j.type}">{"".join(body)}</joint>')
    out.append("</robot>")
    return "\n".join(out)


def _pinocchio(urdf: ParsedUrdf, path: Path) -> pin.Model:
    """Pinocchio's model of the (conformed) kinematic tree, built in memory."""
    try:
        return pin.buildModelFromXML(kinematic_urdf(urdf))
    except Exception as e:  # urdfdom errors surface as ValueError/RuntimeError
        raise ConfigError(f"malformed URDF {path}: Pinocchio cannot parse it ({e})") from None


def object_folders(path: str | Path) -> tuple[Path, ...]:
    """The object folders at ``path``: itself if it holds a ``mobility.urdf``, else its
    subfolders that do (sorted by name), e.g. a folder of downloaded objects.

    Raises:
        ConfigError: ``path`` is not a folder, or holds no object.
    """
    path = Path(path)
    if not path.is_dir():
        raise ConfigError(f"object folder {path} not found")
    if (path / URDF_NAME).is_file():
        return (path,)
    found = tuple(sorted(p for p in path.iterdir() if (p / URDF_NAME).is_file()))
    if not found:
        raise ConfigError(f"{path} holds no object: no {URDF_NAME} in it or its subfolders")
    return found


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
    scale: float | None = None,
    cache_dir: Path | None = None,
    progress: bool = True,
) -> ArticulatedObject:
    """Load a PartNet-Mobility folder (or a ``.urdf`` path) into MuJoCo and Pinocchio,
    conformed to the generator's conventions (:mod:`strug_manip.objects.conform`:
    collision pieces, front to ``+x``, scale, origin, joint signs and dynamics).

    Args:
        folder: the object folder holding ``mobility.urdf`` (and optionally
            ``semantics.txt``), or the URDF file itself.
        free: give the root link a free joint in the standalone MuJoCo model.
        floor: add a floor plane at z = 0 and stand the object on it (lowest collision
            point at z = 0); otherwise the root frame is at the world origin.
        base_friction: sliding friction of the base against the floor.
        total_mass: the object's mass [kg]; default: the mass policy (the boards'
            mass at :data:`~strug_manip.objects.mjcf.SHELL_DENSITY`, brought into the
            generator's :data:`~strug_manip.objects.generator.TOTAL_MASS` range; a
            URDF that gives every moving link an ``<inertial>`` keeps its masses).
        scale: uniform scale; default: the policy of
            :func:`~strug_manip.objects.conform.policy_scale`.
        cache_dir: where convex decompositions are cached (default: the user cache).
        progress: show a progress bar while decomposing concave meshes.

    Returns:
        The :class:`ArticulatedObject`.

    Raises:
        ConfigError: one line naming the file and every problem found (missing file,
            bad XML, unsupported joint type, undefined link, non-finite number,
            missing mesh, no movable part), or a bad option.
    """
    path = Path(folder)
    urdf_path = path if path.suffix.lower() == ".urdf" else path / URDF_NAME
    if total_mass is not None and not (math.isfinite(total_mass) and total_mass > 0):
        raise ConfigError(f"total_mass must be a finite number > 0, got {total_mass!r}")
    if scale is not None and not (math.isfinite(scale) and scale > 0):
        raise ConfigError(f"scale must be a finite number > 0, got {scale!r}")
    raw = parse_urdf(urdf_path, require_movable=True)
    conformed = conform(raw, scale=scale, cache_dir=cache_dir, progress=progress)
    urdf = conformed.urdf
    model, data = _standalone(urdf, base_friction, urdf_path)
    mass = float(model.body_mass.sum())
    if total_mass is None and not all(
        urdf.links[j.child].mass is not None for j in urdf.joints if j.movable
    ):
        total_mass = float(np.clip(mass, *TOTAL_MASS))
    scaled = 1.0 if total_mass is None else total_mass / mass
    urdf = _with_flap_stays(urdf, conformed.defaulted, model, data, scaled)
    return _load(
        urdf,
        urdf_path,
        urdf_path.parent,
        free=free,
        floor=floor,
        base_friction=base_friction,
        total_mass=total_mass,
        scale=conformed.scale,
        yaw=conformed.yaw,
    )


def _standalone(
    urdf: ParsedUrdf, base_friction: float, path: Path
) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The object alone, fixed, joints at 0, kinematics and masses computed (``path``:
    the URDF, for messages)."""
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    build_bodies(
        spec, urdf, pos=(0, 0, 0), yaw=0.0, free=False, prefix="", base_friction=base_friction
    )
    model = compile_spec(spec, path)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def _with_flap_stays(
    urdf: ParsedUrdf,
    defaulted: Sequence[str],
    model: mujoco.MjModel,
    data: mujoco.MjData,
    mass_scale: float,
) -> ParsedUrdf:
    """``urdf`` with a friction stay on every flap whose dynamics were defaulted
    (:func:`~strug_manip.objects.conform.flap_stay`; ``model``/``data``: the object
    alone, :func:`_standalone`, whose masses are then scaled by ``mass_scale``)."""
    flaps = [j for j in urdf.joints if j.name in defaulted and is_flap(j)]
    if not flaps:
        return urdf
    friction = {}
    for j in flaps:
        b = model.body(j.child).id
        jid = model.joint(j.name).id
        lever = data.subtree_com[b] - data.xanchor[jid]
        lever -= (lever @ data.xaxis[jid]) * data.xaxis[jid]
        mass = mass_scale * float(model.body_subtreemass[b])
        friction[j.name] = flap_stay(mass, float(np.linalg.norm(lever)))
    raw = [
        {
            f.name: friction.get(j.name, j.friction) if f.name == "friction" else getattr(j, f.name)
            for f in fields(JointInfo)
            if f.name not in ("T_base_joint", "axis_base")
        }
        for j in urdf.joints
    ]
    joints, children = joint_tree(urdf.root, raw)
    return replace(urdf, joints=joints, children=children)


def _load(
    urdf: ParsedUrdf,
    urdf_path: Path,
    folder: Path | None,
    *,
    free: bool,
    floor: bool,
    base_friction: float,
    total_mass: float | None = None,
    scale: float = 1.0,
    yaw: float = 0.0,
) -> ArticulatedObject:
    """The :class:`ArticulatedObject` of a parsed URDF (``folder`` None: in memory;
    ``scale``, ``yaw``: what conforming it did, recorded)."""
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
        scale=scale,
        yaw=yaw,
    )
