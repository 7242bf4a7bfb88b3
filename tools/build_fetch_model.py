"""Regenerate ``models/fetch/`` (MJCF, URDF, meshes) from gymnasium-robotics' Fetch.

Usage::

    pip install --no-deps gymnasium-robotics==1.4.2   # only its data files are read
    python tools/build_fetch_model.py [--source DIR | --wheel FILE.whl] [--out models/fetch]
                                      [--picture]   # also renders fetch.png (MUJOCO_GL=egl)

Source: the MuJoCo Fetch of gymnasium-robotics (Farama Foundation, MIT licence on
PyPI), ``gymnasium_robotics/envs/assets/fetch/robot.xml`` and ``shared.xml`` with the
STL meshes of ``envs/assets/stls/fetch/``. That model is itself a conversion of Fetch
Robotics' ``fetch_description`` (fetch_ros), whose own package.xml says "Proprietary"
(0.5.x) and CC BY-NC-SA 4.0 (0.8.x): see ``models/fetch/README.md``. The script reads the body
tree, the link offsets, the inertials, the joint axes and ranges, the mesh assignment,
the finger boxes, the ``robot0:grip`` site and the head camera frame from it, then
writes, from one in-memory description:

* ``fetch.xml``: the robot in MJCF (menagerie style), with actuators and a ``home``
  keyframe;
* ``scene.xml``: the robot on a floor with a light (shadows off);
* ``fetch.urdf``: the same kinematics for Pinocchio (and any URDF tool);
* ``assets/*.stl``: the meshes, copied verbatim; ``LICENSE``: the source's licence.

What is changed with respect to the gymnasium-robotics model, and why:

* The world offset of the base and its three heavily damped slide joints (x, y, z)
  are replaced by a planar base: slide ``base_x_joint``, slide ``base_y_joint``,
  hinge ``base_yaw_joint``, driven by velocity actuators (holonomic: the real base is
  differential drive).
* The mocap body and weld, the gripper camera (the real Fetch has none), the lidar
  and external cameras and the zero-mass camera frame bodies are dropped; the head
  RGB-D camera becomes one camera ``head_camera`` (plus a site) on ``head_tilt_link``
  at the RGB optical frame.
* Joint dynamics (damping, armature) and effort limits come from fetch_ros's
  ``fetch.urdf`` (gymnasium-robotics uses armature 1, damping 50 and 4 kg fingers to
  suit mocap control). ``head_tilt_joint``'s ``ref=0.06`` is dropped so that q = 0 is
  fetch_ros's zero; ``torso_lift_joint``'s range is fetch_ros's [0, 0.38615] m (the
  gym file has a lower limit of 0.0386 m). The three continuous roll joints are
  limited to [-pi, pi] so that every arm joint has a position actuator with
  ctrlrange = range, and Pinocchio sees one coordinate per arm joint.
* Gravity compensation (``gravcomp``, routed through the actuators, so it counts
  against the effort limits) on the torso, head and arm, as Fetch's own controllers
  do.
* The wheels (fixed, visual only) are added at fetch_ros's offsets.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import importlib.util
import math
import shutil
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DEFAULT_OUT = REPO / "models" / "fetch"
SOURCE_PACKAGE = "gymnasium-robotics"
SOURCE_VERSION = "1.4.2"
PREFIX = "robot0:"

# ---------------------------------------------------------------------------------------
# Numbers that do not come from the gymnasium-robotics file.
# ---------------------------------------------------------------------------------------

#: Joint effort limits [N] or [N m] and velocity limits [m/s] or [rad/s], from fetch_ros
#: ``fetch_description/robots/fetch.urdf``. Base values: the base's two wheels give
#: 8.85 N m at 0.06 m radius (~300 N, ~55 N m about the centre at 0.187 m track);
#: the speed limits are the Fetch's 1 m/s and a chosen 1.5 rad/s.
EFFORT = {
    "base_x_joint": 300.0,
    "base_y_joint": 300.0,
    "base_yaw_joint": 55.0,
    "torso_lift_joint": 450.0,
    "head_pan_joint": 0.32,
    "head_tilt_joint": 0.68,
    "shoulder_pan_joint": 33.82,
    "shoulder_lift_joint": 131.76,
    "upperarm_roll_joint": 76.94,
    "elbow_flex_joint": 66.18,
    "forearm_roll_joint": 29.35,
    "wrist_flex_joint": 25.7,
    "wrist_roll_joint": 7.36,
    "r_gripper_finger_joint": 60.0,
    "l_gripper_finger_joint": 60.0,
}
VELOCITY = {
    "base_x_joint": 1.0,
    "base_y_joint": 1.0,
    "base_yaw_joint": 1.5,
    "torso_lift_joint": 0.1,
    "head_pan_joint": 1.57,
    "head_tilt_joint": 1.57,
    "shoulder_pan_joint": 1.256,
    "shoulder_lift_joint": 1.454,
    "upperarm_roll_joint": 1.571,
    "elbow_flex_joint": 1.521,
    "forearm_roll_joint": 1.571,
    "wrist_flex_joint": 2.268,
    "wrist_roll_joint": 2.268,
    "r_gripper_finger_joint": 0.05,
    "l_gripper_finger_joint": 0.05,
}
#: Viscous joint damping [N s/m] or [N m s/rad], fetch_ros values.
DAMPING = {
    "torso_lift_joint": 100.0,
    "shoulder_pan_joint": 1.0,
    "shoulder_lift_joint": 1.0,
    "upperarm_roll_joint": 5.0,
    "elbow_flex_joint": 1.0,
    "forearm_roll_joint": 5.0,
    "wrist_flex_joint": 1.0,
    "wrist_roll_joint": 5.0,
    "r_gripper_finger_joint": 100.0,
    "l_gripper_finger_joint": 100.0,
    "head_pan_joint": 0.1,
    "head_tilt_joint": 0.1,
}
#: Reflected rotor inertia [kg m^2] or [kg]: not published; chosen so that the stiff
#: position loops below stay well inside the stability limit of the 2 ms step.
ARMATURE = {
    "torso_lift_joint": 1.0,
    "shoulder_pan_joint": 0.1,
    "shoulder_lift_joint": 0.1,
    "upperarm_roll_joint": 0.05,
    "elbow_flex_joint": 0.05,
    "forearm_roll_joint": 0.02,
    "wrist_flex_joint": 0.02,
    "wrist_roll_joint": 0.01,
    "r_gripper_finger_joint": 0.05,
    "l_gripper_finger_joint": 0.05,
    "head_pan_joint": 0.01,
    "head_tilt_joint": 0.01,
}
#: Position-actuator stiffness [N/m] or [N m/rad]; damping is set by ``dampratio`` = 1
#: (critical at the model's zero pose). Each saturates at its effort limit beyond an
#: error of effort / kp (torso 4.5 cm, arm 0.02-0.05 rad, head ~0.1 rad).
KP = {
    "torso_lift_joint": 10000.0,
    "shoulder_pan_joint": 1000.0,
    "shoulder_lift_joint": 3000.0,
    "upperarm_roll_joint": 1500.0,
    "elbow_flex_joint": 1500.0,
    "forearm_roll_joint": 600.0,
    "wrist_flex_joint": 600.0,
    "wrist_roll_joint": 200.0,
    "head_pan_joint": 4.0,
    "head_tilt_joint": 8.0,
}
#: Integral time of the torso and arm servos [s] (ki = kp / INTEGRAL_TIME): the Fetch's
#: joint controllers hold their position under a steady load (up to the effort limit)
#: rather than giving way by load / kp; a steady error is pushed against with the
#: proportional force again every 0.3 s, slow enough not to excite the arm.
INTEGRAL_TIME = 0.3
#: Position gains of the base servos [N/m] or [N m/rad]: x, y as the velocity loop of
#: the previous model (1500 N s/m) closed by a 3 1/s position loop, as the Fetch's base
#: controller tracks where the navigation stack sends it; yaw stiffer (a standing
#: differential drive turns only as its wheels roll: the arm's reaction torques must
#: not swing it); force limited at the wheels' 300 N and 55 N m (EFFORT).
KP_BASE = {"base_x_joint": 4500.0, "base_y_joint": 4500.0, "base_yaw_joint": 3000.0}
#: Gripper: one position actuator on the tendon 0.5 (q_l + q_r) [m] (finger travel,
#: 0 closed, 0.05 open); the two fingers are coupled by an equality constraint. The
#: tendon force is split 50/50, so forcerange +-120 N gives fetch_ros's 60 N per finger,
#: reached for a position error of 120 / 10000 = 12 mm. The command range reaches 5 cm
#: below the closed stop: a grip commands a target inside whatever is held, and the
#: servo squeezes with its full force (the Fetch's gripper closes with a force, not to a
#: width), whatever the handle's radius.
GRIPPER_KP = 10000.0
GRIPPER_FORCE = 120.0
FINGER_MASS = 0.0798  # [kg] fetch_ros (gymnasium-robotics uses 4 kg for mocap stability)
#: Wheel links from fetch_ros: offset [m] from base_link, mass [kg], diagonal inertia.
WHEELS = {
    "r_wheel_link": (0.0012914, -0.18738, 0.055325),
    "l_wheel_link": (0.0012914, 0.18738, 0.055325),
}
WHEEL_MASS = 4.3542
WHEEL_INERTIA = (0.0045, 0.005, 0.0045)
#: Head camera: vertical field of view [deg] of the Primesense Carmine 1.09 at 4:3
#: (57.5 x 45 deg); gymnasium-robotics uses 50.
HEAD_CAMERA_FOVY = 45.0
#: Limits of the otherwise unbounded base translations in the URDF, which requires
#: limits on prismatic joints [m]. The MJCF slides are unlimited.
URDF_BASE_LIMIT = 100.0

#: ``home``: Fetch's tuck pose (fetch_teleop ``tuck_arm.py``: 1.32, 1.40, -0.2, 1.72, 0,
#: 1.66, 0) with wrist_flex 1.56 instead of 1.66, which clears the convex hull of
#: ``torso_lift_link`` by 1 cm (MuJoCo collides convex hulls); the torso raised 0.3 m
#: (the arm leaves its tuck from there without touching the base, and the torso, the
#: robot's slowest joint at 0.1 m/s, is near the heights the arm works at), head level,
#: gripper open. The tucked arm stays out of the head camera's view.
HOME = {
    "base_x_joint": 0.0,
    "base_y_joint": 0.0,
    "base_yaw_joint": 0.0,
    "torso_lift_joint": 0.3,
    "head_pan_joint": 0.0,
    "head_tilt_joint": 0.0,
    "shoulder_pan_joint": 1.32,
    "shoulder_lift_joint": 1.40,
    "upperarm_roll_joint": -0.2,
    "elbow_flex_joint": 1.72,
    "forearm_roll_joint": 0.0,
    "wrist_flex_joint": 1.56,
    "wrist_roll_joint": 0.0,
    "r_gripper_finger_joint": 0.05,
    "l_gripper_finger_joint": 0.05,
}
GRIPPER_OPEN = 0.05  # [m] finger travel

ROLL_JOINTS = ("upperarm_roll_joint", "forearm_roll_joint", "wrist_roll_joint")
ARM_JOINTS = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "upperarm_roll_joint",
    "elbow_flex_joint",
    "forearm_roll_joint",
    "wrist_flex_joint",
    "wrist_roll_joint",
)
FINGER_JOINTS = ("r_gripper_finger_joint", "l_gripper_finger_joint")
HEAD_JOINTS = ("head_pan_joint", "head_tilt_joint")
BASE_JOINTS = ("base_x_joint", "base_y_joint", "base_yaw_joint")
#: Bodies of the source that are dropped (cameras become one camera + site).
DROPPED_BODIES = {
    "robot0:mocap",
    "robot0:external_camera_body_0",
    "robot0:gripper_camera_link",
    "robot0:head_camera_link",
}
#: Visual-only parts (inside the base hull or touching the floor).
VISUAL_ONLY = {"estop_link", "laser_link", "r_wheel_link", "l_wheel_link"}
#: Bodies that get gravity compensation: the torso and everything it carries.
GRAVCOMP_ROOT = "torso_lift_link"

MATERIALS = {  # name: rgba (gymnasium-robotics / fetch_ros colours)
    "white": (1.0, 1.0, 1.0, 1.0),
    "grey": (0.356, 0.361, 0.376, 1.0),
    "blue": (0.086, 0.506, 0.767, 1.0),
    "red": (0.8, 0.0, 0.0, 1.0),
    "laser": (0.7922, 0.8196, 0.9333, 1.0),
}

# ---------------------------------------------------------------------------------------
# In-memory description
# ---------------------------------------------------------------------------------------

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]  # (w, x, y, z)


@dataclass
class Joint:
    name: str
    kind: str  # "slide" | "hinge"
    axis: Vec3
    range: tuple[float, float] | None  # None: unbounded


@dataclass
class Inertial:
    mass: float
    pos: Vec3
    quat: Quat
    diaginertia: Vec3


@dataclass
class Geom:
    mesh: str | None  # mesh name, or None for a box
    material: str
    pos: Vec3 = (0.0, 0.0, 0.0)
    size: Vec3 | None = None  # box half sizes [m]
    visual_only: bool = False


@dataclass
class Frame:
    """A site (and optionally a camera) rigidly attached to a body."""

    name: str
    pos: Vec3
    quat: Quat
    camera_fovy: float | None = None


@dataclass
class Body:
    name: str
    pos: Vec3
    quat: Quat
    inertial: Inertial
    joints: list[Joint] = field(default_factory=list)
    geoms: list[Geom] = field(default_factory=list)
    frames: list[Frame] = field(default_factory=list)
    children: list[Body] = field(default_factory=list)
    gravcomp: bool = False

    def walk(self):
        yield self
        for c in self.children:
            yield from c.walk()


def _floats(text: str | None, n: int, default: tuple[float, ...]) -> tuple[float, ...]:
    if text is None:
        return default
    vals = tuple(float(v) for v in text.split())
    if len(vals) != n:
        raise ValueError(f"expected {n} numbers, got {text!r}")
    return vals


def _unit_quat(q: tuple[float, ...]) -> Quat:
    a = np.asarray(q, dtype=float)
    a = a / np.linalg.norm(a)
    return (float(a[0]), float(a[1]), float(a[2]), float(a[3]))


def _quat_of(el: ET.Element) -> Quat:
    if el.get("quat") is not None:
        return _unit_quat(_floats(el.get("quat"), 4, (1, 0, 0, 0)))
    euler = _floats(el.get("euler"), 3, (0.0, 0.0, 0.0))
    if any(euler):
        raise ValueError(f"unexpected euler on {el.get('name')}: {euler}")
    return (1.0, 0.0, 0.0, 0.0)


def _strip(name: str) -> str:
    return name.removeprefix(PREFIX)


def _material_of(el: ET.Element, inherited: str) -> str:
    cls = el.get("class", "")
    if cls.endswith("grey"):
        return "grey"
    if cls.endswith("blue"):
        return "blue"
    if "estop" in el.get("name", ""):
        return "red"
    if "laser" in el.get("name", ""):
        return "laser"
    return inherited


def read_source(robot_xml: Path) -> tuple[Body, Vec3]:
    """Read gymnasium-robotics' ``robot.xml`` into a :class:`Body` tree.

    Returns the base body and the position [m] of the ``robot0:grip`` site in
    ``gripper_link``.
    """
    root = ET.parse(robot_xml).getroot()
    base_el = root.find("body[@name='robot0:base_link']")
    if base_el is None:
        raise SystemExit(f"{robot_xml}: no body robot0:base_link; unexpected source layout")
    grip: list[Vec3] = []
    head_camera: list[Frame] = []

    def convert(el: ET.Element, material: str) -> Body:
        name = _strip(el.get("name", ""))
        inert_el = el.find("inertial")
        if inert_el is None:
            raise SystemExit(f"{robot_xml}: body {name} has no inertial")
        inertial = Inertial(
            mass=float(inert_el.get("mass", "0")),
            pos=_floats(inert_el.get("pos"), 3, (0.0, 0.0, 0.0)),  # type: ignore[arg-type]
            quat=_quat_of(inert_el),
            diaginertia=_floats(inert_el.get("diaginertia"), 3, (0.0, 0.0, 0.0)),  # type: ignore[arg-type]
        )
        body = Body(
            name=name,
            pos=_floats(el.get("pos"), 3, (0.0, 0.0, 0.0)),  # type: ignore[arg-type]
            quat=_quat_of(el),
            inertial=inertial,
        )
        finger = el.get("childclass", "").endswith("fetchGripper")
        for j in el.findall("joint"):
            jname = _strip(j.get("name", ""))
            if jname.startswith("slide"):
                continue  # the base's damped slides: replaced by the planar base
            kind = j.get("type", "slide" if finger else "hinge")
            limited = j.get("limited", "true" if j.get("range") else "false") == "true"
            rng = _floats(j.get("range"), 2, (0.0, 0.0)) if limited else None
            body.joints.append(
                Joint(jname, kind, _floats(j.get("axis"), 3, (0, 0, 1)), rng)  # type: ignore[arg-type]
            )
        for g in el.findall("geom"):
            mat = _material_of(g, material)
            if g.get("mesh"):
                body.geoms.append(Geom(mesh=_strip(g.get("mesh", "")), material=mat))
            else:
                body.geoms.append(
                    Geom(
                        mesh=None,
                        material="grey",
                        pos=_floats(g.get("pos"), 3, (0.0, 0.0, 0.0)),  # type: ignore[arg-type]
                        size=_floats(g.get("size"), 3, (0.0, 0.0, 0.0)),  # type: ignore[arg-type]
                    )
                )
        for s in el.findall("site"):
            if s.get("name") == "robot0:grip":
                grip.append(_floats(s.get("pos"), 3, (0.0, 0.0, 0.0)))  # type: ignore[arg-type]
        for c in el.findall("body"):
            cname = c.get("name", "")
            if cname == "robot0:head_camera_link":
                head_camera.append(_head_camera(c))
            if cname in DROPPED_BODIES:
                continue
            body.children.append(convert(c, material))
        return body

    base = convert(base_el, "white")
    if len(grip) != 1 or len(head_camera) != 1:
        raise SystemExit(f"{robot_xml}: expected one robot0:grip site and one head camera")
    tilt = next(b for b in base.walk() if b.name == "head_tilt_link")
    tilt.frames.append(head_camera[0])
    return base, grip[0]


def _head_camera(link: ET.Element) -> Frame:
    """The RGB optical frame of the head camera as a MuJoCo camera frame.

    MuJoCo cameras look along their -z axis with +y up; the ROS optical frame looks
    along +z with +y down, so the camera is the optical frame turned by pi about x.
    On ``head_tilt_link`` that is: looking along +x, image right = -y, image up = +z.
    """
    rgb = link.find("body[@name='robot0:head_camera_rgb_frame']")
    if rgb is None:
        raise SystemExit("head camera: no robot0:head_camera_rgb_frame")
    p_link = np.array(_floats(link.get("pos"), 3, (0.0, 0.0, 0.0)))
    p_rgb = np.array(_floats(rgb.get("pos"), 3, (0.0, 0.0, 0.0)))
    pos = tuple(float(v) for v in p_link + p_rgb)
    # columns: camera x (image right), y (image up), z (backwards) in head_tilt_link
    R = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    return Frame("head_camera", pos, _mat_to_quat(R), HEAD_CAMERA_FOVY)  # type: ignore[arg-type]


def _mat_to_quat(R: np.ndarray) -> Quat:
    import mujoco

    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).ravel())
    return _unit_quat(tuple(q))


def _quat_to_mat(q: Quat) -> np.ndarray:
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _rpy(q: Quat) -> Vec3:
    """URDF roll-pitch-yaw [rad] (R = Rz(y) Ry(p) Rx(r)) of a unit quaternion."""
    R = _quat_to_mat(q)
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if math.hypot(R[0, 0], R[1, 0]) < 1e-12:  # gimbal lock
        return (math.atan2(-R[1, 2], R[1, 1]), pitch, 0.0)
    return (math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0]))


def adapt(base: Body, grip: Vec3) -> Body:
    """Apply the documented changes (planar base, limits, fingers, wheels, gravcomp)."""
    base.pos = (0.0, 0.0, 0.0)
    base.quat = (1.0, 0.0, 0.0, 0.0)
    base.joints = [
        Joint("base_x_joint", "slide", (1.0, 0.0, 0.0), None),
        Joint("base_y_joint", "slide", (0.0, 1.0, 0.0), None),
        Joint("base_yaw_joint", "hinge", (0.0, 0.0, 1.0), None),
    ]
    for name, pos in WHEELS.items():
        base.children.append(
            Body(
                name=name,
                pos=pos,
                quat=(1.0, 0.0, 0.0, 0.0),
                inertial=Inertial(WHEEL_MASS, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0), WHEEL_INERTIA),
                geoms=[Geom(mesh=name, material="blue")],
            )
        )
    seen: set[str] = set()
    for body in base.walk():
        for j in body.joints:
            seen.add(j.name)
            if j.name == "torso_lift_joint":
                j.range = (0.0, 0.38615)
            if j.name in ROLL_JOINTS:
                j.range = (-math.pi, math.pi)
        if body.name.endswith("gripper_finger_link"):
            # fetch_ros mass; box inertia of the finger pad about the COM
            (hx, hy, hz) = body.geoms[0].size or (0.0, 0.0, 0.0)
            m = FINGER_MASS
            ine = (m * (hy**2 + hz**2) / 3, m * (hx**2 + hz**2) / 3, m * (hx**2 + hy**2) / 3)
            body.inertial = Inertial(m, body.inertial.pos, (1.0, 0.0, 0.0, 0.0), ine)
        if body.name == "gripper_link":
            body.frames.append(Frame("gripper", grip, (1.0, 0.0, 0.0, 0.0)))
        for g in body.geoms:
            g.visual_only = body.name in VISUAL_ONLY
    expected = {*BASE_JOINTS, "torso_lift_joint", *ARM_JOINTS, *FINGER_JOINTS, *HEAD_JOINTS}
    if seen != expected:
        raise SystemExit(f"source joints differ from the expected Fetch: {sorted(seen ^ expected)}")
    torso = next(b for b in base.walk() if b.name == GRAVCOMP_ROOT)
    for b in torso.walk():
        b.gravcomp = True
    return base


# ---------------------------------------------------------------------------------------
# Writers
# ---------------------------------------------------------------------------------------


def f(x: float) -> str:
    """Shortest decimal that round-trips ``x`` (``-0`` written as ``0``)."""
    if x == 0:
        return "0"
    s = repr(float(x))
    return s[:-2] if s.endswith(".0") else s


def fs(v) -> str:
    return " ".join(f(float(x)) for x in v)


def _sub(parent: ET.Element, tag: str, **attrs: str) -> ET.Element:
    return ET.SubElement(parent, tag, {k.rstrip("_"): v for k, v in attrs.items()})


def read_meshes(shared_xml: Path) -> dict[str, str]:
    """Mesh name (prefix stripped) -> STL file name, from gymnasium-robotics' ``shared.xml``."""
    root = ET.parse(shared_xml).getroot()
    return {_strip(m.get("name", "")): m.get("file", "") for m in root.iter("mesh")}


def _used_meshes(base: Body, meshes: dict[str, str]) -> dict[str, str]:
    used = {g.mesh for b in base.walk() for g in b.geoms if g.mesh is not None}
    missing = used - set(meshes)
    if missing:
        raise SystemExit(f"meshes not declared in shared.xml: {sorted(missing)}")
    return {name: meshes[name] for name in sorted(used)}


def _joint_names(base: Body) -> list[str]:
    return [j.name for b in base.walk() for j in b.joints]


def write_mjcf(base: Body, meshes: dict[str, str], header: str) -> str:
    root = ET.Element("mujoco", model="fetch")
    root.append(ET.Comment(header))
    _sub(root, "compiler", angle="radian", meshdir="assets", autolimits="true")
    _sub(root, "option", integrator="implicitfast", cone="elliptic", impratio="10")

    default = _sub(root, "default")
    fetch = _sub(default, "default", class_="fetch")
    _sub(fetch, "geom", type="mesh", material="white")
    _sub(fetch, "site", group="5", size="0.01", rgba="1 0 0 0.5")
    vis = _sub(fetch, "default", class_="visual")
    _sub(vis, "geom", contype="0", conaffinity="0", group="2")
    fin = _sub(fetch, "default", class_="finger")
    # Rubber pads: friction 1 (rubber on dry wood or metal: 0.6-1.0), torsional friction
    # (condim 4), and stiff contacts (a 2-step time constant) so a squeezed handle does
    # not sink into the pads.
    _sub(
        fin,
        "geom",
        type="box",
        material="grey",
        condim="4",
        friction="1 0.05 0.01",
        solref="0.004 1",
        solimp="0.95 0.99 0.001",
    )

    asset = _sub(root, "asset")
    for name, rgba in MATERIALS.items():
        _sub(asset, "material", name=name, rgba=fs(rgba), specular="0.4", shininess="0.03")
    for name, file in meshes.items():
        _sub(asset, "mesh", name=name, file=file)

    world = _sub(root, "worldbody")

    def emit(parent: ET.Element, b: Body, top: bool) -> None:
        attrs = {"name": b.name}
        if top:
            attrs["childclass"] = "fetch"
        if any(b.pos):
            attrs["pos"] = fs(b.pos)
        if b.quat != (1.0, 0.0, 0.0, 0.0):
            attrs["quat"] = fs(b.quat)
        if b.gravcomp:
            attrs["gravcomp"] = "1"
        el = ET.SubElement(parent, "body", attrs)
        i = b.inertial
        iattrs = {"mass": f(i.mass), "pos": fs(i.pos), "diaginertia": fs(i.diaginertia)}
        if i.quat != (1.0, 0.0, 0.0, 0.0):
            iattrs["quat"] = fs(i.quat)
        ET.SubElement(el, "inertial", iattrs)
        for j in b.joints:
            ja = {"name": j.name, "type": j.kind, "axis": fs(j.axis)}
            if j.range is not None:
                ja["range"] = fs(j.range)
            if j.name in DAMPING:
                ja["damping"] = f(DAMPING[j.name])
            if j.name in ARMATURE:
                ja["armature"] = f(ARMATURE[j.name])
            if j.name not in BASE_JOINTS:
                ja["actuatorfrcrange"] = fs((-EFFORT[j.name], EFFORT[j.name]))
                ja["actuatorgravcomp"] = "true"
            ET.SubElement(el, "joint", ja)
        for g in b.geoms:
            if g.mesh is not None:
                ga = {"mesh": g.mesh}
                if g.material != "white":
                    ga["material"] = g.material
                if g.visual_only:
                    ga["class"] = "visual"
            else:
                ga = {"class": "finger", "pos": fs(g.pos), "size": fs(g.size or ())}
            ET.SubElement(el, "geom", ga)
        for fr in b.frames:
            fa = {"name": fr.name, "pos": fs(fr.pos)}
            if fr.quat != (1.0, 0.0, 0.0, 0.0):
                fa["quat"] = fs(fr.quat)
            ET.SubElement(el, "site", fa)
            if fr.camera_fovy is not None:
                ET.SubElement(el, "camera", {**fa, "fovy": f(fr.camera_fovy)})
        for c in b.children:
            emit(el, c, False)

    emit(world, base, True)

    contact = _sub(root, "contact")
    _sub(contact, "exclude", body1="r_gripper_finger_link", body2="l_gripper_finger_link")
    _sub(contact, "exclude", body1="torso_lift_link", body2="torso_fixed_link")
    # Their convex hulls overlap at the shoulder mount once |shoulder_pan| > ~1 rad (the
    # tuck pose included), where the real links clear each other.
    _sub(contact, "exclude", body1="torso_lift_link", body2="shoulder_lift_link")

    tendon = _sub(root, "tendon")
    split = _sub(tendon, "fixed", name="gripper")
    for j in FINGER_JOINTS:
        _sub(split, "joint", joint=j, coef="0.5")
    eq = _sub(root, "equality")
    _sub(eq, "joint", joint1=FINGER_JOINTS[0], joint2=FINGER_JOINTS[1], solimp="0.95 0.99 0.001")

    act = _sub(root, "actuator")
    ranges = {j.name: j.range for b in base.walk() for j in b.joints}
    for j in (*BASE_JOINTS, "torso_lift_joint", *ARM_JOINTS):
        _servo(act, j, ranges.get(j) or (-URDF_BASE_LIMIT, URDF_BASE_LIMIT))
    _sub(
        act,
        "position",
        name="gripper",
        tendon="gripper",
        kp=f(GRIPPER_KP),
        dampratio="1",
        ctrlrange=fs((-GRIPPER_OPEN, GRIPPER_OPEN)),
        forcerange=fs((-GRIPPER_FORCE, GRIPPER_FORCE)),
    )
    for j in HEAD_JOINTS:
        _position(act, j, ranges[j])

    keyframe = _sub(root, "keyframe")
    qpos = [HOME[n] for n in _joint_names(base)]
    # The PID servos take two controls each (position and velocity targets: MuJoCo 4),
    # the gripper and head servos one.
    ctrl = (
        [v for _ in range(3) for v in (0.0, 0.0)]
        + [v for j in ("torso_lift_joint", *ARM_JOINTS) for v in (HOME[j], 0.0)]
        + [GRIPPER_OPEN]
        + [HOME[j] for j in HEAD_JOINTS]
    )
    _sub(keyframe, "key", name="home", qpos=fs(qpos), ctrl=fs(ctrl))
    ET.indent(root, "  ")
    return ET.tostring(root, encoding="unicode") + "\n"


def _position(act: ET.Element, joint: str, rng: tuple[float, float] | None) -> None:
    if rng is None:
        raise SystemExit(f"{joint} needs a range for its position actuator")
    _sub(
        act,
        "position",
        name=joint.removesuffix("_joint"),
        joint=joint,
        kp=f(KP[joint]),
        dampratio="1",
        ctrlrange=fs(rng),
        forcerange=fs((-EFFORT[joint], EFFORT[joint])),
    )


def _servo(act: ET.Element, joint: str, rng: tuple[float, float] | None) -> None:
    """A position servo with integral action (MuJoCo's PID actuator): force =
    kp (ctrl - q) - kv qdot + ki * integral of (ctrl - q), clamped at the effort limit,
    the integral clamped so that it alone asks for at most the effort limit."""
    if rng is None:
        raise SystemExit(f"{joint} needs a range for its servo")
    kp = KP[joint] if joint in KP else KP_BASE[joint]
    ki = kp / INTEGRAL_TIME
    _sub(
        act,
        "general",
        name=joint.removesuffix("_joint"),
        joint=joint,
        dyntype="pid",
        dynprm=f(EFFORT[joint] / ki),
        gaintype="pid",
        gainprm=f(ki),
        biastype="affine",
        biasprm=fs((0.0, -kp, 1.0)),  # biasprm[2] > 0: a damping ratio (critical)
        ctrlrange=fs(rng),
        forcerange=fs((-EFFORT[joint], EFFORT[joint])),
    )


def write_scene(header: str) -> str:
    return f"""<mujoco model="fetch scene">
  <!-- {header} -->
  <compiler angle="radian"/>
  <include file="fetch.xml"/>

  <statistic center="0.3 0 0.7" extent="1.8"/>

  <visual>
    <headlight diffuse="0.6 0.6 0.6" ambient="0.3 0.3 0.3" specular="0 0 0"/>
    <rgba haze="0.15 0.25 0.35 1"/>
    <global azimuth="150" elevation="-20"/>
    <quality shadowsize="0"/>
  </visual>

  <asset>
    <texture type="skybox" builtin="gradient" rgb1="0.3 0.5 0.7" rgb2="0 0 0" width="32"
      height="192"/>
    <texture type="2d" name="groundplane" builtin="checker" mark="edge" rgb1="0.2 0.3 0.4"
      rgb2="0.1 0.2 0.3" markrgb="0.8 0.8 0.8" width="300" height="300"/>
    <material name="groundplane" texture="groundplane" texuniform="true" texrepeat="5 5"/>
  </asset>

  <worldbody>
    <light name="sun" pos="0 0 4" dir="0 0 -1" directional="true" castshadow="false"/>
    <geom name="floor" size="0 0 0.05" type="plane" material="groundplane"/>
  </worldbody>

  <!-- The base is held at floor height by its planar joints: its wheels touch the floor
       only visually, and base-floor contacts would only brake it. -->
  <contact>
    <exclude body1="world" body2="base_link"/>
  </contact>
</mujoco>
"""


def write_urdf(base: Body, meshes: dict[str, str], header: str) -> str:
    robot = ET.Element("robot", name="fetch")
    robot.append(ET.Comment(header))
    for name, rgba in MATERIALS.items():
        m = _sub(robot, "material", name=name)
        _sub(m, "color", rgba=fs(rgba))
    _sub(robot, "link", name="world")

    def link(b: Body) -> None:
        el = _sub(robot, "link", name=b.name)
        i = b.inertial
        R = _quat_to_mat(i.quat)
        full = R @ np.diag(i.diaginertia) @ R.T
        ine = _sub(el, "inertial")
        _sub(ine, "origin", xyz=fs(i.pos), rpy="0 0 0")
        _sub(ine, "mass", value=f(i.mass))
        _sub(
            ine,
            "inertia",
            **{
                k: f(round(float(full[a, c]), 12))
                for k, (a, c) in {
                    "ixx": (0, 0),
                    "ixy": (0, 1),
                    "ixz": (0, 2),
                    "iyy": (1, 1),
                    "iyz": (1, 2),
                    "izz": (2, 2),
                }.items()
            },
        )
        for g in b.geoms:
            tags = ("visual",) if g.visual_only else ("visual", "collision")
            for tag in tags:
                ge = _sub(el, tag)
                _sub(ge, "origin", xyz=fs(g.pos), rpy="0 0 0")
                geo = _sub(ge, "geometry")
                if g.mesh is not None:
                    _sub(geo, "mesh", filename=f"assets/{meshes[g.mesh]}")
                else:
                    _sub(geo, "box", size=fs(2 * np.asarray(g.size)))
                if tag == "visual":
                    _sub(ge, "material", name=g.material)

    def joint(parent: str, child: str, j: Joint | None, pos: Vec3, quat: Quat) -> None:
        if j is None:
            el = _sub(robot, "joint", name=f"{child}_joint", type="fixed")
        elif j.kind == "slide":
            el = _sub(robot, "joint", name=j.name, type="prismatic")
        elif j.range is None:
            el = _sub(robot, "joint", name=j.name, type="continuous")
        else:
            el = _sub(robot, "joint", name=j.name, type="revolute")
        _sub(el, "origin", xyz=fs(pos), rpy=fs(_rpy(quat)))
        _sub(el, "parent", link=parent)
        _sub(el, "child", link=child)
        if j is None:
            return
        _sub(el, "axis", xyz=fs(j.axis))
        lim = {"effort": f(EFFORT[j.name]), "velocity": f(VELOCITY[j.name])}
        if j.range is not None:
            lim = {"lower": f(j.range[0]), "upper": f(j.range[1]), **lim}
        elif j.kind == "slide":
            lim = {"lower": f(-URDF_BASE_LIMIT), "upper": f(URDF_BASE_LIMIT), **lim}
        _sub(el, "limit", **lim)
        if j.name in DAMPING:
            _sub(el, "dynamics", damping=f(DAMPING[j.name]))

    def emit(parent: str, b: Body) -> None:
        # A MuJoCo body with several joints becomes a chain of massless links.
        chain = [parent] + [f"{j.name.removesuffix('_joint')}_link" for j in b.joints[:-1]]
        for k, j in enumerate(b.joints[:-1]):
            _sub(robot, "link", name=chain[k + 1])
            pos, quat = (b.pos, b.quat) if k == 0 else ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
            joint(chain[k], chain[k + 1], j, pos, quat)
        link(b)
        last = b.joints[-1] if b.joints else None
        if len(b.joints) > 1:
            joint(chain[-1], b.name, last, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
        else:
            joint(parent, b.name, last, b.pos, b.quat)
        for fr in b.frames:
            _sub(robot, "link", name=fr.name)
            joint(b.name, fr.name, None, fr.pos, fr.quat)
        for c in b.children:
            emit(b.name, c)

    emit("world", base)
    ET.indent(robot, "  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"


# ---------------------------------------------------------------------------------------
# Driver
# ---------------------------------------------------------------------------------------


def locate_source(source: Path | None, wheel: Path | None, tmp: Path) -> tuple[Path, str]:
    """Return the ``gymnasium_robotics/envs/assets`` folder and the package version."""
    if wheel is not None:
        with zipfile.ZipFile(wheel) as z:
            z.extractall(tmp)
        pkg = tmp / "gymnasium_robotics"
        version = wheel.name.split("-")[1]
    elif source is not None:
        pkg = source / "gymnasium_robotics" if (source / "gymnasium_robotics").is_dir() else source
        version = "unknown (--source)"
    else:
        spec = importlib.util.find_spec("gymnasium_robotics")
        if spec is None or not spec.submodule_search_locations:
            raise SystemExit(
                f"{SOURCE_PACKAGE} is not installed: "
                f"pip install --no-deps {SOURCE_PACKAGE}=={SOURCE_VERSION}"
            )
        pkg = Path(next(iter(spec.submodule_search_locations)))
        version = importlib.metadata.version(SOURCE_PACKAGE)
    assets = pkg / "envs" / "assets"
    if not (assets / "fetch" / "robot.xml").is_file():
        raise SystemExit(f"{assets}/fetch/robot.xml not found")
    return assets, version


def build(out: Path, source: Path | None = None, wheel: Path | None = None) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        assets, version = locate_source(source, wheel, Path(tmp))
        if version != SOURCE_VERSION:
            print(
                f"warning: {SOURCE_PACKAGE} {version}, this script was written for "
                f"{SOURCE_VERSION}; check the output",
                file=sys.stderr,
            )
        base, grip = read_source(assets / "fetch" / "robot.xml")
        base = adapt(base, grip)
        meshes = _used_meshes(base, read_meshes(assets / "fetch" / "shared.xml"))
        header = (
            f" Generated by tools/build_fetch_model.py from {SOURCE_PACKAGE} {version} "
            "(MIT; from Fetch Robotics' fetch_description, see README.md). "
            "Do not edit: edit the script. "
        )
        (out / "assets").mkdir(parents=True, exist_ok=True)
        for file in sorted(set(meshes.values())):
            shutil.copyfile(assets / "stls" / "fetch" / file, out / "assets" / file)
        (out / "fetch.xml").write_text(write_mjcf(base, meshes, header))
        (out / "scene.xml").write_text(write_scene(header.strip()))
        (out / "fetch.urdf").write_text(write_urdf(base, meshes, header))
        lic = assets.parents[2] / f"gymnasium_robotics-{version}.dist-info" / "licenses"
        lic_file = lic / "LICENSE"
        if lic_file.is_file():
            (out / "LICENSE").write_text(lic_file.read_text())
        else:
            print(f"warning: no licence file at {lic_file}; LICENSE not updated", file=sys.stderr)
    print(f"wrote {out} from {SOURCE_PACKAGE} {version}")


def render_picture(out: Path, width: int = 640, height: int = 480) -> None:
    """Write ``fetch.png``: the scene at the ``home`` keyframe (needs an OpenGL backend,
    e.g. ``MUJOCO_GL=egl``)."""
    import mujoco
    from PIL import Image

    model = mujoco.MjModel.from_xml_path(str(out / "scene.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    cam = mujoco.MjvCamera()
    cam.lookat[:] = (0.1, 0.0, 0.65)
    cam.distance, cam.azimuth, cam.elevation = 2.4, 150.0, -15.0
    with mujoco.Renderer(model, height, width) as renderer:
        renderer.update_scene(data, cam)
        Image.fromarray(renderer.render()).save(out / "fetch.png")
    print(f"wrote {out / 'fetch.png'}")


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    g = p.add_mutually_exclusive_group()
    g.add_argument("--source", type=Path, help="an unpacked gymnasium-robotics (site-packages)")
    g.add_argument("--wheel", type=Path, help="a gymnasium_robotics-*.whl file")
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output folder")
    p.add_argument("--picture", action="store_true", help="also render fetch.png")
    a = p.parse_args(argv)
    build(a.out, a.source, a.wheel)
    if a.picture:
        render_picture(a.out)


if __name__ == "__main__":
    main()
