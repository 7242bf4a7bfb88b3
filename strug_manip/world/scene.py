"""Compose the manipulation scene: Fetch + floor + table + object + one free cabinet.

World frame: the robot's base starts at the origin facing +x. The cabinet stands
``cabinet_distance`` in front of it, its open front (+x of the cabinet frame) facing
the robot, on a free joint (so a wrong pull drags it). A table stands to the robot's
right (-y) with a spam-can-sized box on it (YCB's potted meat can, 0.10 x 0.06 x 0.085 m,
0.37 kg). An ``overview`` camera looks at the whole scene; the robot's ``head_camera``
is its RGB-D sensor. Shadows are off (the floor light casts none) for speed.

Contacts: the cabinet base is excluded against its own moving parts (by the loader);
the robot base against the world (its wheels only touch the floor visually).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from planners.errors import ConfigError, check_positive_float
from strug_manip.objects import (
    ArticulatedObject,
    CabinetSpec,
    add_to_spec,
    generate_cabinet,
    load_articulated_object,
    write_partnet,
)
from strug_manip.robot.fetch import FETCH_SCENE_XML, HOME_KEYFRAME

#: Half sizes of the graspable object [m] (YCB potted meat can: 0.10 x 0.06 x 0.085 m).
OBJECT_HALF_SIZE = (0.05, 0.03, 0.0425)
#: Its mass [kg].
OBJECT_MASS = 0.37
#: Table top height [m], half extents of the top [m].
TABLE_HEIGHT = 0.72
TABLE_HALF = (0.30, 0.40, 0.02)


@dataclass(frozen=True)
class SceneConfig:
    """What the scene holds and where.

    Attributes:
        cabinet_seed: seed of the generated cabinet (ignored if ``cabinet_folder`` or
            ``cabinet_spec``).
        cabinet_kinds: part kinds the generator may use (``drawer``, ``door``,
            ``shelf``, ``panel``).
        cabinet_folder: a PartNet-Mobility folder to load instead of generating one.
        cabinet_distance: distance of the cabinet's front from the robot's origin [m].
        cabinet_lateral: lateral offset of the cabinet (+y) [m].
        table_xy: position of the table centre [m].
        timestep: physics step [s].
        width, height: camera image size [px].
        cabinet_spec: a cabinet to build instead of generating one from
            ``cabinet_seed`` (e.g. a belief particle: the generator's spec with some
            parts' joints replaced, see
            :func:`strug_manip.control.controllers.believed_spec`); excludes
            ``cabinet_folder``. Not compared or hashed.
    """

    cabinet_seed: int = 3
    cabinet_kinds: tuple[str, ...] = ("drawer", "door", "shelf", "panel")
    cabinet_folder: Path | None = None
    cabinet_distance: float = 1.0
    cabinet_lateral: float = 0.0
    table_xy: tuple[float, float] = (0.45, -0.85)
    timestep: float = 0.002
    width: int = 320
    height: int = 240
    cabinet_spec: CabinetSpec | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if self.cabinet_spec is not None:
            if not isinstance(self.cabinet_spec, CabinetSpec):
                raise ConfigError(
                    f"cabinet_spec must be a CabinetSpec or None, got {self.cabinet_spec!r}"
                )
            if self.cabinet_folder is not None:
                raise ConfigError("give cabinet_spec or cabinet_folder, not both")
        check_positive_float("cabinet_distance", self.cabinet_distance)
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


def _home_by_name() -> dict[str, float]:
    robot = mujoco.MjModel.from_xml_path(str(FETCH_SCENE_XML))
    key = robot.key(HOME_KEYFRAME)
    out = {}
    for j in range(robot.njnt):
        adr = robot.jnt_qposadr[j]
        out[robot.joint(j).name] = float(key.qpos[adr])
    return out


def build_scene(config: SceneConfig, workdir: Path) -> SceneModel:
    """Build the scene of ``config``; generated (or given) cabinets are written under
    ``workdir``."""
    if config.cabinet_folder is not None:
        folder, cab_spec = Path(config.cabinet_folder), None
    elif config.cabinet_spec is not None:
        cab_spec = config.cabinet_spec
        folder = write_partnet(cab_spec, Path(workdir) / cab_spec.name)
    else:
        cab_spec = generate_cabinet(config.cabinet_seed, kinds=config.cabinet_kinds)
        folder = write_partnet(cab_spec, Path(workdir) / cab_spec.name)
    cabinet = load_articulated_object(folder)
    spec = mujoco.MjSpec.from_file(str(FETCH_SCENE_XML))
    spec.option.timestep = config.timestep
    spec.visual.global_.offwidth = max(config.width, 1280)
    spec.visual.global_.offheight = max(config.height, 960)
    # The robot-only keyframe no longer fits once objects add coordinates: reset by name.
    for key in list(spec.keys):
        spec.delete(key)
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
            config.table_xy[0] - 0.1,
            config.table_xy[1] + 0.1,
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
    )

    # The cabinet faces the robot: its +x (front) points to -x of the world.
    yaw = math.pi
    pos = [config.cabinet_distance + cabinet.bounds[1, 0], config.cabinet_lateral, 0.0]
    add_to_spec(spec, cabinet, pos, yaw, free=True, prefix="cabinet/")
    eye = (-0.9, 1.5, 1.8)
    world.add_camera(name="overview", pos=list(eye), xyaxes=look_at_xyaxes(eye, (1.0, -0.35, 0.55)))
    model = spec.compile()
    T = np.eye(4)
    T[:3, :3] = np.array(
        [[math.cos(yaw), -math.sin(yaw), 0], [math.sin(yaw), math.cos(yaw), 0], [0, 0, 1]]
    )
    T[:3, 3] = pos
    return SceneModel(model, cabinet, cab_spec, _home_by_name(), "cabinet/", T)
