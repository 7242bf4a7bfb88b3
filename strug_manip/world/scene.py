"""Compose the manipulation scene: Fetch + floor + two tables + object + one free cabinet.

World frame: the robot's base starts at the origin facing +x. In front of it stands the
*cabinet table* (a low sideboard, top :data:`STAND_HEIGHT` high, its front edge
``cabinet_distance`` ahead), and on it the cabinet, its open front (+x of the cabinet
frame) facing the robot :data:`STAND_SETBACK` behind the table's edge, on a free joint:
a wrong pull drags it across the table top, or off it. This is the paper's setting (a
small storage cabinet standing on a table; see the generator's docstring for the
cabinets drawn). ``stand_height=0`` puts the cabinet on the floor instead.

A second table stands to the robot's right (-y), a little behind it, with a
spam-can-sized box on it (YCB's
potted meat can, 0.10 x 0.06 x 0.085 m, 0.37 kg). An ``overview`` camera looks at the
whole scene; the robot's ``head_camera`` is its RGB-D sensor. Shadows are off (the floor
light casts none) for speed.

Friction of the cabinet on its table: :data:`CABINET_FRICTION` = 0.4, dry wood (or
laminate) on wood, whose measured static coefficients lie in 0.25-0.5 (Engineering
ToolBox, "Friction and Friction Coefficients for various Materials"); MuJoCo's Coulomb
model uses one coefficient for sticking and sliding.

Contacts: the cabinet base is excluded against its own moving parts (by the loader);
the robot base against the world (its wheels only touch the floor visually).
"""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from planners.errors import ConfigError, UnknownNameError, check_positive_float
from strug_manip.objects import (
    ArticulatedObject,
    CabinetSpec,
    add_to_spec,
    generate_cabinet,
    load_articulated_object,
    load_cabinet_spec,
)
from strug_manip.objects.describe import describe_object
from strug_manip.objects.generator import STYLES
from strug_manip.robot.fetch import FETCH_SCENE_XML, GRIPPER_JOINTS, HOME_KEYFRAME
from strug_manip.world.floating_gripper import add_floating_gripper

#: Half sizes of the graspable object [m] (YCB potted meat can: 0.10 x 0.06 x 0.085 m).
OBJECT_HALF_SIZE = (0.05, 0.03, 0.0425)
#: Its mass [kg].
OBJECT_MASS = 0.37
#: Where it stands on the table, from the table's centre [m]: near the corner the
#: robot comes to, 0.1 m in from both edges, so it can be taken from above or, level,
#: from the side.
OBJECT_ON_TABLE = (0.2, 0.25)
#: Table top height [m], half extents of the top [m].
TABLE_HEIGHT = 0.72
TABLE_HALF = (0.30, 0.40, 0.02)
#: Height of the cabinet table's top [m]: a low sideboard, so that every handle of the
#: generated cabinets (0.30-0.85 m tall) lies 0.55-1.30 m above the floor, where the
#: Fetch grasps with a level or slightly pitched gripper.
STAND_HEIGHT = 0.50
#: Smallest top of the cabinet table (depth along x, width along y) [m]; larger
#: cabinets get a top 0.15 m deeper and 0.2 m wider than their footprint.
STAND_TOP = (0.60, 1.10)
#: Thickness of the cabinet table's top [m].
STAND_THICKNESS = 0.03
#: Distance of the cabinet's front plane behind the table's front edge [m].
STAND_SETBACK = 0.02
#: Sliding friction of the cabinet on its table (dry wood on wood: 0.25-0.5) [-].
CABINET_FRICTION = 0.4
#: What can stand in front of the cabinet: the Fetch, or its floating hand (the twin).
ROBOTS: tuple[str, ...] = ("fetch", "gripper")
#: Collision bit of the Fetch's geoms. They collide with the world (conaffinity 1) but
#: not with each other: the robot's motions are planned free of self-contact (the
#: contact checker turns self-contacts back on: :mod:`strug_manip.control.contacts`),
#: and leaving the mesh-mesh pairs of neighbouring links out of the simulation's
#: collision detection makes a physics step much cheaper (README: performance).
ROBOT_CONTYPE = 2


@dataclass(frozen=True)
class SceneConfig:
    """What the scene holds and where.

    Attributes:
        cabinet_seed: seed of the generated cabinet (ignored if ``cabinet_folder`` or
            ``cabinet_spec``).
        cabinet_kinds: part kinds the generator may use (``drawer``, ``door``,
            ``shelf``, ``panel``).
        cabinet_folder: a PartNet-Mobility folder to load instead of generating one.
        cabinet_distance: distance of the cabinet table's front edge (with
            ``stand_height=0``: of the cabinet's foremost point) from the robot's
            origin [m].
        cabinet_lateral: lateral offset of the cabinet (+y) [m].
        stand_height: height of the cabinet table's top [m]; 0 stands the cabinet on
            the floor (no table; floor friction: the loader's, 0.5).
        table_xy: position of the (object) table's centre [m]: to the robot's right and
            a little behind it, clear of the floor in front of the cabinet where the
            robot stands to open doors that swing toward it.
        timestep: physics step [s].
        width, height: camera image size [px].
        cabinet_spec: a cabinet to build instead of generating one from
            ``cabinet_seed`` (e.g. a belief particle: the generator's spec with some
            parts' joints replaced, see
            :func:`strug_manip.objects.hypotheses.believed_spec`); excludes
            ``cabinet_folder``. Not compared or hashed.
        robot: ``fetch`` (the robot) or ``gripper`` (its floating hand alone: the
            skills' planning twin, :mod:`strug_manip.world.floating_gripper`).
        cabinet_style: the generator's style for ``cabinet_seed`` (``plain`` or
            ``furniture``, :data:`strug_manip.objects.generator.STYLES`).
    """

    cabinet_seed: int = 3
    cabinet_kinds: tuple[str, ...] = ("drawer", "door", "shelf", "panel")
    cabinet_folder: Path | None = None
    cabinet_distance: float = 1.0
    cabinet_lateral: float = 0.0
    stand_height: float = STAND_HEIGHT
    table_xy: tuple[float, float] = (-0.15, -1.05)
    timestep: float = 0.002
    width: int = 320
    height: int = 240
    cabinet_spec: CabinetSpec | None = field(default=None, compare=False)
    robot: str = "fetch"
    cabinet_style: str = "plain"

    def __post_init__(self) -> None:
        if self.robot not in ROBOTS:
            raise UnknownNameError("robot", self.robot, ROBOTS)
        if self.cabinet_style not in STYLES:
            raise UnknownNameError("cabinet style", self.cabinet_style, STYLES)
        if self.cabinet_spec is not None:
            if not isinstance(self.cabinet_spec, CabinetSpec):
                raise ConfigError(
                    f"cabinet_spec must be a CabinetSpec or None, got {self.cabinet_spec!r}"
                )
            if self.cabinet_folder is not None:
                raise ConfigError("give cabinet_spec or cabinet_folder, not both")
        check_positive_float("cabinet_distance", self.cabinet_distance)
        check_positive_float("stand_height", self.stand_height, allow_zero=True, upper=1.5)
        check_positive_float("timestep", self.timestep, upper=0.01)
        for name in ("width", "height"):
            if not isinstance(getattr(self, name), int) or getattr(self, name) < 8:
                raise ConfigError(
                    f"{name} must be an integer >= 8 pixels, got {getattr(self, name)!r}"
                )


@dataclass
class SceneModel:
    """A compiled scene and what is needed to drive it.

    Attributes:
        model: the compiled MuJoCo model.
        cabinet: the loaded articulated object.
        cabinet_spec: the generator's ground truth (None for a loaded folder).
        home_qpos: robot joint name -> home position.
        cabinet_prefix: the name prefix of the cabinet's bodies and joints.
        T_world_cabinet: the cabinet frame at reset, 4x4.
    """

    model: mujoco.MjModel
    cabinet: ArticulatedObject
    cabinet_spec: CabinetSpec | None
    home_qpos: dict[str, float]
    cabinet_prefix: str = "cabinet/"
    T_world_cabinet: np.ndarray = field(default_factory=lambda: np.eye(4))


def look_at_xyaxes(eye: tuple[float, ...], target: tuple[float, ...]) -> list[float]:
    """MJCF ``xyaxes`` of a camera at ``eye`` looking at ``target`` with world z up."""
    forward = np.asarray(target, float) - np.asarray(eye, float)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return [*right.tolist(), *up.tolist()]


def _remove_robot(spec: mujoco.MjSpec) -> None:
    """Take the Fetch out of the scene spec (its body tree, actuators, tendons, contact
    rules, meshes and materials), keeping the floor, the light and the sky."""
    spec.delete(spec.body("base_link"))
    for group in (spec.actuators, spec.tendons, spec.equalities, spec.excludes, spec.sensors):
        for item in list(group):
            spec.delete(item)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    for mat in list(spec.materials):
        if mat.name != "groundplane":
            spec.delete(mat)


@functools.cache
def _home_by_name() -> dict[str, float]:
    robot = mujoco.MjModel.from_xml_path(str(FETCH_SCENE_XML))
    key = robot.key(HOME_KEYFRAME)
    out = {}
    for j in range(robot.njnt):
        adr = robot.jnt_qposadr[j]
        out[robot.joint(j).name] = float(key.qpos[adr])
    return out


def _add_stand(
    world: mujoco.MjsBody, edge: float, y: float, size: np.ndarray, height: float
) -> None:
    """The cabinet table, fixed to the world: its front edge at world ``x = edge``,
    centred on ``y``, its top ``height`` high [m], large enough for a cabinet footprint
    ``size`` = (depth along x, width along y) [m] standing :data:`STAND_SETBACK` behind
    the edge."""
    depth = max(STAND_TOP[0], STAND_SETBACK + float(size[0]) + 0.15)
    width = max(STAND_TOP[1], float(size[1]) + 0.2)
    stand = world.add_body(name="cabinet_table", pos=[edge + depth / 2, y, 0.0])
    stand.add_geom(
        name="cabinet_table_top",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[depth / 2, width / 2, STAND_THICKNESS / 2],
        pos=[0, 0, height - STAND_THICKNESS / 2],
        rgba=[0.42, 0.32, 0.24, 1],
        friction=[CABINET_FRICTION, 0.005, 0.0001],
    )
    leg = (height - STAND_THICKNESS) / 2
    for sx in (-1, 1):
        for sy in (-1, 1):
            stand.add_geom(
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=[0.02, 0.02, leg],
                pos=[sx * (depth / 2 - 0.03), sy * (width / 2 - 0.03), leg],
                rgba=[0.3, 0.25, 0.2, 1],
            )


def cabinet_pose(
    depth: float,
    cabinet_distance: float = 1.0,
    lateral: float = 0.0,
    stand: float = STAND_HEIGHT,
) -> np.ndarray:
    """Where the scene stands a cabinet ``depth`` deep on its table (the defaults are
    :class:`SceneConfig`'s): the object frame turned to face the robot (yaw pi), its
    front plane :data:`STAND_SETBACK` behind the table's edge at ``cabinet_distance``,
    on the table's top ``stand`` high, (4, 4) [m] (:func:`build_scene` then raises a
    cabinet whose glides reach below its frame by that much).

    Raises:
        ConfigError: ``stand`` is not > 0 (a cabinet on the floor has no table).
    """
    if not stand > 0:
        raise ConfigError("cabinets stand on the cabinet table (stand_height > 0)")
    T = np.diag([-1.0, -1.0, 1.0, 1.0])  # yaw pi: the front faces the robot
    T[:3, 3] = [cabinet_distance + STAND_SETBACK + depth / 2, lateral, stand]
    return T


def build_scene(config: SceneConfig) -> SceneModel:
    """Build the scene of ``config``, in memory (a generated or given cabinet is never
    written to disk; a ``cabinet_folder`` is read from it)."""
    if config.cabinet_folder is not None:
        cabinet = load_articulated_object(Path(config.cabinet_folder))
        cab_spec = describe_object(cabinet)
    else:
        cab_spec = config.cabinet_spec
        if cab_spec is None:
            cab_spec = generate_cabinet(
                config.cabinet_seed, kinds=config.cabinet_kinds, style=config.cabinet_style
            )
        cabinet = load_cabinet_spec(cab_spec)
    spec = mujoco.MjSpec.from_file(str(FETCH_SCENE_XML))
    home = dict(_home_by_name())
    # The robot-only keyframe no longer fits once the scene changes: reset by name.
    for key in list(spec.keys):
        spec.delete(key)
    if config.robot == "gripper":
        _remove_robot(spec)
        add_floating_gripper(spec)
        home = {j: home[j] for j in GRIPPER_JOINTS}
    spec.option.timestep = config.timestep
    spec.visual.global_.offwidth = max(config.width, 1280)
    spec.visual.global_.offheight = max(config.height, 960)
    world = spec.worldbody

    table = world.add_body(name="table", pos=[*config.table_xy, 0.0])
    table.add_geom(
        name="table_top",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=list(TABLE_HALF),
        pos=[0, 0, TABLE_HEIGHT - TABLE_HALF[2]],
        rgba=[0.55, 0.42, 0.3, 1],
    )
    for sx in (-1, 1):
        for sy in (-1, 1):
            table.add_geom(
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=[0.02, 0.02, (TABLE_HEIGHT - 0.04) / 2],
                pos=[
                    sx * (TABLE_HALF[0] - 0.03),
                    sy * (TABLE_HALF[1] - 0.03),
                    (TABLE_HEIGHT - 0.04) / 2,
                ],
                rgba=[0.3, 0.25, 0.2, 1],
            )
    obj = world.add_body(
        name="object",
        pos=[
            config.table_xy[0] + OBJECT_ON_TABLE[0],
            config.table_xy[1] + OBJECT_ON_TABLE[1],
            TABLE_HEIGHT + OBJECT_HALF_SIZE[2],
        ],
    )
    obj.add_freejoint(name="object/free")
    obj.add_geom(
        name="object",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=list(OBJECT_HALF_SIZE),
        mass=OBJECT_MASS,
        rgba=[0.15, 0.35, 0.8, 1],
        friction=[1.0, 0.01, 0.001],
        # A rigid tin: stiff contacts (as the finger pads'), so a held can does not
        # creep out of the grasp under its own weight.
        solref=[0.004, 1.0],
        solimp=[0.95, 0.99, 0.001, 0.5, 2.0],
    )

    # The cabinet faces the robot: its +x (front) points to -x of the world.
    yaw = math.pi
    if config.stand_height > 0:
        # The object frame's origin is the footprint's centre (generated and loaded).
        T_stand = cabinet_pose(
            cab_spec.depth, config.cabinet_distance, config.cabinet_lateral, config.stand_height
        )
        pos = [float(v) for v in T_stand[:3, 3]]
        size = cabinet.bounds[1, :2] - cabinet.bounds[0, :2]
        _add_stand(
            world, config.cabinet_distance, config.cabinet_lateral, size, config.stand_height
        )
        friction = CABINET_FRICTION
    else:
        pos = [config.cabinet_distance + cabinet.bounds[1, 0], config.cabinet_lateral, 0.0]
        friction = None
    add_to_spec(spec, cabinet, pos, yaw, free=True, prefix="cabinet/", base_friction=friction)
    eye = (-0.9, 1.5, 1.8)
    world.add_camera(name="overview", pos=list(eye), xyaxes=look_at_xyaxes(eye, (0.6, -0.5, 0.55)))
    with warnings.catch_warnings():
        # The twin's hand is attached without a name prefix (see floating_gripper).
        warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")
        model = spec.compile()
    if config.robot == "fetch":
        root = model.body("base_link").id
        for g in range(model.ngeom):
            if model.body_rootid[model.geom_bodyid[g]] == root and model.geom_contype[g]:
                model.geom_contype[g] = ROBOT_CONTYPE
                model.geom_conaffinity[g] = 1
    T = np.eye(4)
    T[:3, :3] = np.array(
        [[math.cos(yaw), -math.sin(yaw), 0], [math.sin(yaw), math.cos(yaw), 0], [0, 0, 1]]
    )
    # add_to_spec stands the cabinet's lowest point (the glides) on pos: its frame is
    # that much higher.
    T[:3, 3] = pos
    T[2, 3] -= float(cabinet.bounds[0, 2])
    return SceneModel(model, cabinet, cab_spec, home, "cabinet/", T)
