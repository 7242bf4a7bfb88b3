"""The Fetch's hand without the Fetch: the floating gripper of the planning twin.

:func:`add_floating_gripper` puts into a scene spec the Fetch's ``gripper_link`` subtree
as ``models/fetch/fetch.xml`` has it (palm mesh, finger pads, finger joints, their
coupling, tendon and servo, the ``gripper`` TCP site), carried by three slides along
the world axes and a ball joint at the palm, and drives it like an arm would:

- **translation**: three position servos with integral action (MuJoCo's PID
  actuators, critically damped, integral time :data:`INTEGRAL_TIME`), each on a fixed
  tendon of the three slides: a direction of the hand's motion. The twin sets per run
  the directions, gains and force limits (:mod:`strug_manip.control.twin_servo`): the
  principal axes and stiffnesses of the Fetch's arm and base servos seen at the hand at
  the grasp, and what the Fetch's joints can push along each (a reaching Fetch gives way
  horizontally, where its base yaws and its shoulder pans, far more than
  vertically, where its torso and shoulder lift hold it: one gain for every world axis
  cannot be right); until then the directions are the
  world axes and the gain :data:`TRANSLATION_KP`;
- **rotation**: a geodesic orientation servo on the ball joint (MuJoCo's SO3 actuator,
  quaternion target, :data:`ROTATION_KP`), its torque norm limited likewise;
- every body is gravity compensated, as the Fetch's arm is;
- the Fetch's arm links (:data:`ARM_LINKS`, their collision meshes) as mocap bodies: the
  twin moves them along the full robot's joint path where the arm moves freely (after
  the last release: the retreat and the stow), where a forearm can knock an open door
  or push a drawer back in; elsewhere they are parked out of the scene
  (:data:`ARM_PARK`).

A mocap body ``robot_base`` (no geometry) stands where the full robot's base is
believed to be: its pose is part of the simulation state, so a snapshot of the twin
carries it (the base placement of the next skill starts from there).

Joint names: ``twin_x``, ``twin_y``, ``twin_z`` (slides), ``twin_rot`` (ball); tendon
and actuator names :data:`SERVOS` (translation) and ``twin_rot`` (rotation); the
fingers keep the Fetch's names (``r_gripper_finger_joint``, ..., actuator and tendon
``gripper``), so code reading the fingers works on both.
"""

from __future__ import annotations

import warnings

import mujoco
import numpy as np

from strug_manip.robot.fetch import FETCH_XML

#: Slide joints (world x, y, z) and the ball joint of the floating gripper.
SLIDES: tuple[str, str, str] = ("twin_x", "twin_y", "twin_z")
BALL = "twin_rot"
#: The translation servos: fixed tendons of the slides (a direction each, the world
#: axes until the twin sets them) and the PID actuators on them.
SERVOS: tuple[str, str, str] = ("twin_u", "twin_v", "twin_w")
#: Translation servo gain until the twin sets the arm's [N/m]: the Fetch's arm servos
#: (kp 600-3000 N m/rad on levers of 0.3-0.9 m) seen at the hand.
TRANSLATION_KP = 3000.0
#: Orientation servo gain [N m/rad]: the wrist servos' (kp 200-600 N m/rad).
ROTATION_KP = 300.0
#: Integral time of the translation servos [s] (the arm servos').
INTEGRAL_TIME = 0.3
#: Force [N] and torque [N m] limits until the twin sets them per run.
DEFAULT_FORCE = 100.0
DEFAULT_TORQUE = 20.0
#: Mass of each carrier body [kg] (gravity compensated: only its inertia matters).
CARRIER_MASS = 0.1
#: Armature of the twin's finger joints [kg]: the finger servo (kp 10000 N/m) on the
#: Fetch's 0.13 kg of finger and armature would ring at 350 rad/s, too fast for the
#: twin's 4 ms step (the fingers chatter on a handle); with 0.5 kg it rings at 130
#: rad/s. The fingers squeeze with their force limit either way (the grip is force
#: controlled), they close in 0.1 s instead of 0.08 s.
FINGER_ARMATURE = 0.5
#: Where the gripper waits, out of the way, until a skill places it [m].
PARK = (0.0, 0.0, 1.6)
#: The Fetch's arm links (shoulder to wrist) the twin carries as mocap bodies, named as
#: in ``fetch.xml``; the hand (``gripper_link``) is the floating gripper itself.
ARM_LINKS: tuple[str, ...] = (
    "shoulder_pan_link",
    "shoulder_lift_link",
    "upperarm_roll_link",
    "elbow_flex_link",
    "forearm_roll_link",
    "wrist_flex_link",
    "wrist_roll_link",
)
#: Where the arm links wait when the arm is not simulated [m]: above everything (mocap
#: bodies never touch each other or the world's geoms, only the cabinet, the object and
#: the hand, which never rise there).
ARM_PARK = (0.0, 0.0, 10.0)


def add_floating_gripper(spec: mujoco.MjSpec) -> None:
    """Add the floating gripper, its servos and the ``robot_base`` mocap to ``spec``."""
    src = mujoco.MjSpec.from_file(str(FETCH_XML))
    for key in list(src.keys):  # the robot's keyframe does not fit the twin
        src.delete(key)
    carrier = spec.worldbody
    for name, axis in zip(SLIDES, np.eye(3), strict=True):
        carrier = carrier.add_body(name=name + "_carrier", gravcomp=1.0)
        carrier.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=axis, damping=1.0)
        carrier.mass = CARRIER_MASS
        carrier.inertia = [1e-4, 1e-4, 1e-4]
        carrier.explicitinertial = True
    frame = carrier.add_frame()
    # No prefix: the hand's parts keep the Fetch's names, so code reading the fingers,
    # their tendon and servo, and the TCP site works on both. (MuJoCo warns that such a
    # spec may not save as XML; it is never saved.)
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda message: None)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            frame.attach_body(src.body("gripper_link"), "", "")
    finally:
        mujoco.set_mju_user_warning(previous)
    hand = spec.body("gripper_link")
    hand.pos = [0.0, 0.0, 0.0]
    for finger in ("r_gripper_finger_joint", "l_gripper_finger_joint"):
        spec.joint(finger).armature = FINGER_ARMATURE
    hand.add_joint(name=BALL, type=mujoco.mjtJoint.mjJNT_BALL, damping=0.05)
    for mesh in list(spec.meshes):  # the attach brings every Fetch mesh; keep the hand's
        if mesh.name not in ("gripper_link", *ARM_LINKS):  # and the arm's
            spec.delete(mesh)
    _add_arm(spec, src)
    for name, axis in zip(SERVOS, np.eye(3), strict=True):
        tendon = spec.add_tendon(name=name)
        for slide, coef in zip(SLIDES, axis, strict=True):  # every slide: the twin turns it
            tendon.wrap_joint(slide, float(coef))
        act = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_TENDON)
        ki = TRANSLATION_KP / INTEGRAL_TIME
        act.set_to_pid(kp=TRANSLATION_KP, dampratio=1.0, ki=ki, imax=DEFAULT_FORCE / ki)
        act.forcelimited = True
        act.forcerange = [-DEFAULT_FORCE, DEFAULT_FORCE]
    rot = spec.add_actuator(name=BALL, target=BALL, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    rot.set_to_orientation(
        kp=ROTATION_KP, dampratio=1.0, ctrlspec=int(mujoco.mjtCtrlChart.mjCHART_QUAT)
    )
    rot.forcelimited = True
    rot.forcerange = [0.0, DEFAULT_TORQUE]
    base = spec.worldbody.add_body(name="robot_base", mocap=True)
    base.add_site(name="robot_base", size=[0.02, 0.02, 0.02], group=5)


def _add_arm(spec: mujoco.MjSpec, src: mujoco.MjSpec) -> None:
    """The arm links of ``src`` (the Fetch) as mocap bodies of ``spec`` with their
    collision geoms; the wrist's links never touch the hand (adjacent on the robot)."""
    for link in ARM_LINKS:
        body = spec.worldbody.add_body(name=link, mocap=True, pos=list(ARM_PARK))
        for g in src.body(link).geoms:
            if g.contype == 0 and g.conaffinity == 0:
                continue  # visual only
            body.add_geom(
                type=g.type, meshname=g.meshname, size=list(g.size), pos=list(g.pos),
                quat=list(g.quat), contype=g.contype, conaffinity=g.conaffinity,
                condim=g.condim, friction=list(g.friction), solref=list(g.solref),
                solimp=list(g.solimp), group=g.group, rgba=list(g.rgba),
            )  # fmt: skip
    for link in ("wrist_flex_link", "wrist_roll_link"):
        for hand in ("gripper_link", "r_gripper_finger_link", "l_gripper_finger_link"):
            spec.add_exclude(bodyname1=link, bodyname2=hand)
