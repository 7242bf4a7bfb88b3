"""The Fetch mobile manipulator: model files, joint names, and Pinocchio kinematics.

The robot is described twice, from one source (see ``models/fetch/README.md``):

* ``fetch.xml`` / ``scene.xml`` (MuJoCo): dynamics, actuators, the ``home`` keyframe,
  the ``gripper`` site (the TCP, between the fingers) and the ``head_camera`` camera
  and site;
* ``fetch.urdf`` (Pinocchio, or any URDF tool): the same kinematic tree, with frames
  ``gripper`` and ``head_camera`` at the MuJoCo sites.

The two models order their joints differently (Pinocchio sorts the fingers ``l``
before ``r``; its continuous base yaw takes two coordinates, cos and sin). Always map
between them BY NAME: every function here takes ``{joint name: value}``.

Units: prismatic joints [m], revolute joints [rad]; poses are 4x4 homogeneous
transforms ``T_world_frame`` [m]; Jacobians are 6 x n, rows ``(v_x, v_y, v_z, w_x, w_y,
w_z)`` of the frame origin's linear velocity [m/s] and the frame's angular velocity
[rad/s], both in world axes, per unit joint velocity.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np

from planners.errors import ConfigError, UnknownNameError

#: Folder of the Fetch description (MJCF, URDF, meshes, README with source and licence).
FETCH_DIR: Path = Path(__file__).resolve().parents[2] / "models" / "fetch"
#: The robot alone in MJCF (compiler angle=radian, meshdir=assets).
FETCH_XML: Path = FETCH_DIR / "fetch.xml"
#: The robot on a floor with a light (shadows off), including ``fetch.xml``.
FETCH_SCENE_XML: Path = FETCH_DIR / "scene.xml"
#: The same kinematics as URDF, with frames ``gripper`` and ``head_camera``.
FETCH_URDF: Path = FETCH_DIR / "fetch.urdf"

#: Planar base: world-frame translation x [m], y [m], then yaw about z [rad].
BASE_JOINTS: tuple[str, str, str] = ("base_x_joint", "base_y_joint", "base_yaw_joint")
#: Torso lift (prismatic, [0, 0.38615] m).
TORSO_JOINT: str = "torso_lift_joint"
#: The 7 arm joints, shoulder to wrist [rad].
ARM_JOINTS: tuple[str, ...] = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "upperarm_roll_joint",
    "elbow_flex_joint",
    "forearm_roll_joint",
    "wrist_flex_joint",
    "wrist_roll_joint",
)
#: The two fingers, each travelling [0, 0.05] m outwards from closed; in MuJoCo they are
#: coupled (equality) and driven by one actuator ``gripper`` on their mean travel.
GRIPPER_JOINTS: tuple[str, str] = ("r_gripper_finger_joint", "l_gripper_finger_joint")
#: Head pan and tilt [rad] (tilt > 0 looks down).
HEAD_JOINTS: tuple[str, str] = ("head_pan_joint", "head_tilt_joint")
#: Every joint of the robot, in the order above.
ALL_JOINTS: tuple[str, ...] = (
    *BASE_JOINTS,
    TORSO_JOINT,
    *ARM_JOINTS,
    *GRIPPER_JOINTS,
    *HEAD_JOINTS,
)

#: Torso lift + the 7 arm joints: what the IK, the arm motion planner and the joint
#: driver move, in this order.
ARM_TORSO_JOINTS: tuple[str, ...] = (TORSO_JOINT, *ARM_JOINTS)
#: Fraction of each joint's speed limit a motion may use at its peak [-]: with every
#: joint near its own limit at once, the coupled arm needs more torque than the
#: shoulder's and elbow's effort limits give, and the servos fall behind.
SPEED_FRACTION = 0.8
#: Gripper commands, mean finger travel [m]: open, and the grip: a target 5 cm inside
#: the closed stop, so the finger servo squeezes with its full force (60 N per finger,
#: fetch_description's effort limit) whatever it holds.
GRIPPER_OPEN = 0.05
GRIPPER_SQUEEZE = -0.05
#: Mean finger travel [m] below which closed fingers hold nothing.
FINGERS_EMPTY = 1e-3
#: The tucked torso + arm (the ``home`` keyframe's arm, torso 0.3 m): the posture the
#: robot drives in, inside its footprint and out of its head camera's view.
TUCK: tuple[float, ...] = (0.3, 1.32, 1.40, -0.2, 1.72, 0.0, 1.56, 0.0)
#: Torso + arm carrying the object, per grasp (``top``: taken from above; ``side``:
#: level): the object held beside the head, 3 cm clear of the robot, out of the head
#: camera's view and 0.85-1.35 m high, the arm within 0.33 m of the base's centre, a
#: straight joint-space way out to the IK's ready posture
#: (``python tools/find_carry_posture.py --samples 40000``).
CARRY: dict[str, tuple[float, ...]] = {
    "top": (0.171, 0.426, -1.069, 2.105, 1.488, -2.332, -1.534, 1.147),
    "side": (0.158, 1.043, 1.396, 2.155, -2.199, -2.646, 1.153, -1.484),
}

#: MuJoCo site (and URDF frame) of the tool centre point, between the fingers.
GRIPPER_SITE: str = "gripper"
#: MuJoCo camera (and site, and URDF frame) of the head RGB-D camera; MuJoCo camera
#: convention: looks along its -z axis, +x is image right, +y image up.
HEAD_CAMERA: str = "head_camera"
#: Name of the MuJoCo keyframe with the arm tucked and the gripper open.
HOME_KEYFRAME: str = "home"
#: MuJoCo actuator of each controlled joint (the fingers share ``gripper``).
ACTUATORS: dict[str, str] = {
    **{j: j.removesuffix("_joint") for j in (*BASE_JOINTS, TORSO_JOINT, *ARM_JOINTS)},
    **{j: "gripper" for j in GRIPPER_JOINTS},
    **{j: j.removesuffix("_joint") for j in HEAD_JOINTS},
}


def urdf_velocity_limits(urdf: str | Path = FETCH_URDF) -> dict[str, float]:
    """``{joint: velocity limit}`` [rad/s or m/s] from the ``<limit velocity=...>`` tags
    of a URDF (default: the Fetch's, fetch_ros' values).

    Raises:
        ConfigError: the file is missing or is not valid XML.
    """
    path = Path(urdf)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise ConfigError(f"cannot read velocity limits from URDF {str(path)!r}: {exc}") from None
    out: dict[str, float] = {}
    for joint in root.iter("joint"):
        limit = joint.find("limit")
        if limit is not None and limit.get("velocity") is not None:
            out[joint.get("name", "")] = float(limit.get("velocity", "nan"))
    return out


def speed_limits(model: mujoco.MjModel, joints: Sequence[str] = ARM_TORSO_JOINTS) -> np.ndarray:
    """The speeds motions of ``joints`` may use, shape (n,) [rad/s or m/s].

    Per joint: the smaller of fetch_ros' velocity limit (the URDF) and the speed at
    which the joint's damping absorbs its actuator's whole force (wrist roll: 7.36 N m /
    5 N m s = 1.47 rad/s), times :data:`SPEED_FRACTION`.

    Raises:
        UnknownNameError: a joint is not in ``model``.
    """
    urdf = urdf_velocity_limits()
    names = [model.joint(j).name for j in range(model.njnt)]
    out = []
    for name in joints:
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
        if jid < 0:
            raise UnknownNameError("joint", name, names)
        limit = urdf.get(name, 1.0)
        damping = float(model.dof_damping[model.jnt_dofadr[jid]])
        for a in range(model.nactuator):
            own = int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT)
            if own and model.actuator_trnid[a, 0] == jid and damping > 0:
                limit = min(limit, float(np.max(np.abs(model.actuator_forcerange[a]))) / damping)
        out.append(SPEED_FRACTION * limit)
    return np.array(out)
