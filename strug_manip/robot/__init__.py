"""The robot: Fetch's model files and joint names (its kinematics: MuJoCo's, in IK).

See :mod:`strug_manip.robot.fetch`.
"""

from strug_manip.robot.fetch import (
    ACTUATORS,
    ALL_JOINTS,
    ARM_JOINTS,
    BASE_JOINTS,
    FETCH_DIR,
    FETCH_SCENE_XML,
    FETCH_URDF,
    FETCH_XML,
    GRIPPER_JOINTS,
    GRIPPER_SITE,
    HEAD_CAMERA,
    HEAD_JOINTS,
    HOME_KEYFRAME,
    TORSO_JOINT,
)

__all__ = [
    "ACTUATORS",
    "ALL_JOINTS",
    "ARM_JOINTS",
    "BASE_JOINTS",
    "FETCH_DIR",
    "FETCH_SCENE_XML",
    "FETCH_URDF",
    "FETCH_XML",
    "GRIPPER_JOINTS",
    "GRIPPER_SITE",
    "HEAD_CAMERA",
    "HEAD_JOINTS",
    "HOME_KEYFRAME",
    "TORSO_JOINT",
]
