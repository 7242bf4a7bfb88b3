"""Rotations along paths (the planning twin's commands): quaternions of rotation
matrices, their slerp, their x axes, and TCP poses carried to another base pose."""

from __future__ import annotations

import mujoco
import numpy as np


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


def x_axes(q: np.ndarray) -> np.ndarray:
    """The x axes (n, 3) of the rotations of unit quaternions ``q`` (n, 4)."""
    w, x, y, z = q.T
    return np.column_stack([1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)])
