"""Rotations and poses, in one place: axis-angle and roll-pitch-yaw matrices, MuJoCo
quaternions (w, x, y, z) of matrices and back, the angle of a rotation, and the planning
twin's rotations along paths (slerp, x axes, TCP poses carried to another base pose).

Why hand-written formulas rather than ``mink.lie`` or ``scipy.spatial.transform``:
they give the same rotations but not the same bits (``mink.SO3.exp`` and
``Rotation.from_rotvec`` differ from :func:`axis_angle` by up to 1.1e-16 in 995 and 994
of 1,000 random axis-angles), and an episode's contacts amplify a last-bit difference:
the project keeps its episodes identical, seed for seed, across refactors. Quaternions
are MuJoCo's own (``mju_mat2Quat``, ``mju_quat2Mat``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix of ``angle`` [rad] about the unit ``axis`` (3,), shape (3, 3)."""
    x, y, z = axis
    c, s = math.cos(angle), math.sin(angle)
    K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + s * K + (1 - c) * K @ K


def rpy_matrix(rpy: Sequence[float]) -> np.ndarray:
    """URDF fixed-axis roll-pitch-yaw [rad] -> rotation matrix Rz(y) Ry(p) Rx(r), (3, 3)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = (
        math.cos(r),
        math.sin(r),
        math.cos(p),
        math.sin(p),
        math.cos(y),
        math.sin(y),
    )
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def quat_of(R: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) -> MuJoCo quaternion (w, x, y, z), (4,)."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).ravel())
    return q


def mat_of(quat: np.ndarray) -> np.ndarray:
    """MuJoCo quaternion (w, x, y, z), (4,) -> rotation matrix (3, 3)."""
    R = np.empty(9)
    mujoco.mju_quat2Mat(R, np.ascontiguousarray(quat, dtype=float))
    return R.reshape(3, 3)


def rotation_angle(R: np.ndarray) -> float:
    """Angle [rad] of a rotation matrix (3, 3), accurate near 0."""
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(R, dtype=float).reshape(9))
    v = quat[1:]
    return 2.0 * math.atan2(math.sqrt(v.dot(v)), abs(float(quat[0])))  # = np.linalg.norm


def with_base(
    pos: np.ndarray, quat: np.ndarray, planned: np.ndarray, actual: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """TCP poses ``pos`` (n, 3), ``quat`` (n, 4) planned with the base at ``planned``
    (n, 3: x, y, yaw) carried to the base at ``actual`` (n, 3): the same pose in the
    base's frame."""
    dyaw = actual[:, 2] - planned[:, 2]
    c, s = np.cos(dyaw), np.sin(dyaw)
    rel = pos[:, :2] - planned[:, :2]
    out = pos.copy()
    out[:, 0] = c * rel[:, 0] - s * rel[:, 1] + actual[:, 0]
    out[:, 1] = s * rel[:, 0] + c * rel[:, 1] + actual[:, 1]
    # (cos h, 0, 0, sin h) * (w, x, y, z): a turn by 2h about the world's z first.
    ch, sh = np.cos(dyaw / 2)[:, None], np.sin(dyaw / 2)[:, None]
    w, x, y, z = quat.T[:, :, None]
    q = np.hstack([ch * w - sh * z, ch * x - sh * y, ch * y + sh * x, ch * z + sh * w])
    return out, q


def quats(R: np.ndarray) -> np.ndarray:
    """Unit quaternions (w, x, y, z), (n, 4), of rotation matrices (n, 3, 3)."""
    out = np.empty((len(R), 4))
    for i in range(len(R)):
        mujoco.mju_mat2Quat(out[i], np.ascontiguousarray(R[i]).reshape(9))
    return out


def slerp(qa: np.ndarray, qb: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Unit quaternions the fractions ``s`` (n,) of the way from ``qa`` to ``qb`` (each
    (n, 4)) along the shortest arc, (n, 4)."""
    qb = np.where((np.sum(qa * qb, axis=1) < 0)[:, None], -qb, qb)
    theta = np.arccos(np.clip(np.sum(qa * qb, axis=1), -1.0, 1.0))
    small = theta < 1e-6
    sin = np.where(small, 1.0, np.sin(theta))
    wa = np.where(small, 1.0 - s, np.sin((1.0 - s) * theta) / sin)
    wb = np.where(small, s, np.sin(s * theta) / sin)
    q = wa[:, None] * qa + wb[:, None] * qb
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def z_axes(q: np.ndarray) -> np.ndarray:
    """The z axes ((n, 3), or (3,) for (4,)) of the rotations of unit quaternions ``q``
    ((n, 4) or (4,), w x y z)."""
    w, x, y, z = np.moveaxis(np.asarray(q, dtype=float), -1, 0)
    return np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], axis=-1)


def x_axes(q: np.ndarray) -> np.ndarray:
    """The x axes (n, 3) of the rotations of unit quaternions ``q`` (n, 4)."""
    w, x, y, z = q.T
    return np.column_stack([1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)])


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``v`` (3,) rotated by unit quaternions ``q`` (w, x, y, z), (n, 4) -> (n, 3)
    (or (4,) -> (3,))."""
    q = np.asarray(q, dtype=float)
    w, u = q[..., :1], q[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)
