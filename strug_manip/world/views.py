"""Where the robot looks from: the few head poses it takes to perceive the cabinet.

The paper builds its initial belief from "multiple camera perspectives" of the robot's
RGB-D camera. :func:`look_poses` says where the Fetch stands and where its head looks
for each of ``k`` views; :func:`take_views` puts the robot there (a teleport of the
planar base: the views happen before the episode's first skill, so no controller is
involved), renders the head camera and puts the robot back.

The poses depend only on the scene layout the robot knows (the cabinet table's front
edge and centre line, :class:`~strug_manip.world.scene.SceneConfig`), never on the
cabinet: the head aims at where a cabinet on that table stands (:data:`AIM_BEHIND`
behind the table's front edge, :data:`AIM_ABOVE` above its top).

Decisions: the first four poses spread the viewpoints as far as the Fetch's reach
allows: a central one, one from each side (0.3 m off the centre line, so a side
door's hinge gap and a drawer's side show), and one from further back with the torso
raised (the cabinet's top, hence its depth, shows). Poses 5-8 repeat the pattern with
the torso at other heights. Base positions are in the world frame (the robot starts at
the origin facing +x); the base always turns to face the aim point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from planners.errors import ConfigError
from strug_manip.robot.fetch import BASE_JOINTS, HEAD_CAMERA, HEAD_JOINTS, TORSO_JOINT
from strug_manip.world.scene import STAND_SETBACK
from strug_manip.world.sim import CameraFrame, ManipulationWorld

#: Where the head aims: this far behind the cabinet table's front edge [m] ...
AIM_BEHIND = STAND_SETBACK + 0.15
#: ... and this far above the table's top [m] (near the middle of the tallest cabinet,
#: 0.85 m: from the standard poses the whole of any generated cabinet is in view).
AIM_ABOVE = 0.38

#: (gap from the table's front edge to the base origin [m], lateral offset from the
#: centre line [m], torso lift [m]) of each standard view, in the order taken.
_POSES: tuple[tuple[float, float, float], ...] = (
    (1.05, 0.00, 0.20),
    (1.00, 0.30, 0.10),
    (1.00, -0.30, 0.10),
    (1.30, 0.00, 0.38),
    (1.15, 0.20, 0.30),
    (1.15, -0.20, 0.30),
    (0.95, 0.15, 0.00),
    (0.95, -0.15, 0.00),
)
#: Most views :func:`look_poses` gives.
MAX_VIEWS = len(_POSES)


@dataclass(frozen=True)
class LookPose:
    """One place to look from.

    Attributes:
        base: planar base pose ``(x [m], y [m], yaw [rad])`` in the world frame.
        torso: torso lift [m].
        target: world point the camera's optical axis goes through, (3,) [m].
    """

    base: tuple[float, float, float]
    torso: float
    target: tuple[float, float, float]


def look_poses(world: ManipulationWorld, k: int = 4) -> list[LookPose]:
    """The first ``k`` standard head poses (module docstring) for ``world``'s scene.

    Raises:
        ConfigError: ``k`` is not an integer in ``1..MAX_VIEWS``.
    """
    if isinstance(k, bool) or not isinstance(k, int | np.integer) or not 1 <= k <= MAX_VIEWS:
        raise ConfigError(f"k (views) must be an integer in 1..{MAX_VIEWS}, got {k!r}")
    c = world.config
    target = (c.cabinet_distance + AIM_BEHIND, c.cabinet_lateral, c.stand_height + AIM_ABOVE)
    out = []
    for gap, lateral, torso in _POSES[: int(k)]:
        x, y = c.cabinet_distance - gap, c.cabinet_lateral + lateral
        yaw = math.atan2(target[1] - y, target[0] - x)
        out.append(LookPose((x, y, yaw), torso, target))
    return out


def aim_head(world: ManipulationWorld, target: np.ndarray, iterations: int = 4) -> None:
    """Pan and tilt the head so that the head camera's optical axis meets ``target``
    (world, (3,) [m]), within the joints' ranges; then update the kinematics."""
    m, d = world.model, world.data
    pan_j, tilt_j = (m.joint(n) for n in HEAD_JOINTS)
    adr = [m.jnt_qposadr[j.id] for j in (pan_j, tilt_j)]
    target = np.asarray(target, dtype=float)
    for _ in range(iterations):
        mujoco.mj_kinematics(m, d)
        mujoco.mj_camlight(m, d)  # camera poses are not part of mj_kinematics
        T, _ = world.camera_pose(HEAD_CAMERA)
        to_target = T[:3, :3].T @ (target - T[:3, 3])  # camera frame; ahead is -z
        pan_err = math.atan2(-to_target[0], -to_target[2])
        tilt_err = math.atan2(-to_target[1], math.hypot(to_target[0], to_target[2]))
        d.qpos[adr[0]] = float(np.clip(d.qpos[adr[0]] + pan_err, *pan_j.range))
        d.qpos[adr[1]] = float(np.clip(d.qpos[adr[1]] + tilt_err, *tilt_j.range))  # +: down
    mujoco.mj_forward(m, d)


def place_robot(world: ManipulationWorld, pose: LookPose) -> None:
    """Put the base and torso at ``pose`` and aim the head at its target."""
    m, d = world.model, world.data
    for name, value in zip((*BASE_JOINTS, TORSO_JOINT), (*pose.base, pose.torso), strict=True):
        d.qpos[m.jnt_qposadr[m.joint(name).id]] = value
    aim_head(world, np.asarray(pose.target))


def take_views(world: ManipulationWorld, k: int = 4) -> list[CameraFrame]:
    """Render the head camera from the first ``k`` :func:`look_poses`; the robot's
    joints are put back afterwards (the cabinet is not touched)."""
    m, d = world.model, world.data
    names = (*BASE_JOINTS, TORSO_JOINT, *HEAD_JOINTS)
    saved = {n: float(d.qpos[m.jnt_qposadr[m.joint(n).id]]) for n in names}
    frames = []
    try:
        for pose in look_poses(world, k):
            place_robot(world, pose)
            frames.append(world.render(HEAD_CAMERA))
    finally:
        for n, v in saved.items():
            d.qpos[m.jnt_qposadr[m.joint(n).id]] = v
        mujoco.mj_forward(m, d)
    return frames


def cabinet_cloud(world: ManipulationWorld, frame: CameraFrame) -> np.ndarray:
    """World points (N, 3) [m] of ``frame`` that fall on the cabinet (its carcass and
    parts, by the simulator's segmentation): the observation of the point-cloud
    likelihood (:mod:`perception.likelihood`)."""
    pts, geoms = world.point_cloud(frame)
    m, pre = world.model, world.scene.cabinet_prefix
    is_cab = np.array(
        [m.body(m.geom_bodyid[g]).name.startswith(pre) for g in range(m.ngeom)] + [False]
    )
    return pts[is_cab[np.where(geoms < 0, m.ngeom, geoms)]]
