"""An independent reference for the Fetch model's tests: forward kinematics and frame
Jacobians computed by Pinocchio from the URDF (``models/fetch/fetch.urdf``), against
which the MJCF the product uses (MuJoCo, mink) is checked. The product itself has one
kinematics path, MuJoCo's; this one lives with the tests."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from planners.errors import ConfigError, UnknownNameError
from strug_manip.robot.fetch import FETCH_URDF, GRIPPER_SITE


class FetchKinematics:
    """Forward kinematics and frame Jacobians of Fetch, computed by Pinocchio from URDF.

    Args:
        urdf: path of the URDF (default: ``models/fetch/fetch.urdf``).
        tcp_frame: the frame :meth:`forward` returns (default: ``gripper``, the TCP).

    Joints not given in a ``q_by_name`` mapping are at 0 (base at the world origin,
    torso down, arm straight ahead, fingers closed, head level).

    Raises:
        ConfigError: the URDF is missing or cannot be parsed.
        UnknownNameError: ``tcp_frame`` is not a frame of the URDF.
    """

    def __init__(self, urdf: str | Path = FETCH_URDF, tcp_frame: str = GRIPPER_SITE) -> None:
        self._pin = pin
        path = Path(urdf)
        if not path.is_file():
            raise ConfigError(f"Fetch URDF not found: {str(path)!r} (expected a .urdf file)")
        try:
            self.model = pin.buildModelFromUrdf(str(path))
        except (RuntimeError, ValueError) as exc:
            raise ConfigError(f"cannot parse the URDF {str(path)!r}: {exc}") from None
        self.data = self.model.createData()
        joints = self.model.joints
        #: Joint names in Pinocchio's order (each joint has one velocity coordinate).
        self.joint_names: tuple[str, ...] = tuple(self.model.names[1:])
        self._idx_q = {n: joints[i].idx_q for i, n in enumerate(self.model.names) if i > 0}
        self._nq = {n: joints[i].nq for i, n in enumerate(self.model.names) if i > 0}
        self._idx_v = {n: joints[i].idx_v for i, n in enumerate(self.model.names) if i > 0}
        if any(joints[i].nv != 1 for i in range(1, self.model.njoints)):
            raise ConfigError(f"{str(path)!r}: every joint must have one degree of freedom")
        self.frame_names: tuple[str, ...] = tuple(f.name for f in self.model.frames)
        self.tcp_frame = tcp_frame
        self._tcp_id = self._frame_id(tcp_frame)

    # -- configuration -------------------------------------------------------------------

    def joint_limits(self) -> dict[str, tuple[float, float]]:
        """``{joint: (lower, upper)}`` from the URDF [m or rad]; continuous: (-inf, inf)."""
        lo, hi = self.model.lowerPositionLimit, self.model.upperPositionLimit
        out: dict[str, tuple[float, float]] = {}
        for name in self.joint_names:
            i = self._idx_q[name]
            if self._nq[name] == 2:
                out[name] = (-math.inf, math.inf)
            else:
                out[name] = (float(lo[i]), float(hi[i]))
        return out

    def configuration(self, q_by_name: Mapping[str, float]) -> np.ndarray:
        """Pinocchio's configuration vector, shape (nq,), from joint values by name.

        Raises:
            UnknownNameError: a name is not a joint of the model (lists the valid ones).
            ConfigError: a value is not a finite number.
        """
        q = self._pin.neutral(self.model)
        for name, value in q_by_name.items():
            if name not in self._idx_q:
                raise UnknownNameError("Fetch joint", name, self.joint_names)
            if isinstance(value, bool) or not isinstance(value, int | float | np.number):
                raise ConfigError(f"joint {name!r} must be a number [m or rad], got {value!r}")
            x = float(value)
            if not math.isfinite(x):
                raise ConfigError(f"joint {name!r} must be finite, got {value!r}")
            i = self._idx_q[name]
            if self._nq[name] == 2:  # continuous joint: (cos, sin)
                q[i], q[i + 1] = math.cos(x), math.sin(x)
            else:
                q[i] = x
        return q

    # -- kinematics ----------------------------------------------------------------------

    def forward(self, q_by_name: Mapping[str, float]) -> np.ndarray:
        """``T_world_gripper``, shape (4, 4) [m]: the pose of the TCP frame in the world."""
        return self.frame_pose(self.tcp_frame, q_by_name)

    def frame_pose(self, frame: str, q_by_name: Mapping[str, float]) -> np.ndarray:
        """``T_world_frame``, shape (4, 4) [m], of any URDF frame (link or site)."""
        fid = self._frame_id(frame)
        q = self.configuration(q_by_name)
        self._pin.framesForwardKinematics(self.model, self.data, q)
        return np.array(self.data.oMf[fid].homogeneous)

    def jacobian(
        self,
        q_by_name: Mapping[str, float],
        joints: Sequence[str] | None = None,
        frame: str | None = None,
    ) -> np.ndarray:
        """Frame Jacobian, shape (6, len(joints)), of ``frame`` (default: the TCP).

        Rows: linear velocity of the frame origin [m/s], then angular velocity [rad/s],
        both in world axes (Pinocchio's ``LOCAL_WORLD_ALIGNED``). Column k is the
        derivative with respect to ``joints[k]`` [m or rad] (default: all joints in
        :attr:`joint_names` order).
        """
        pin = self._pin
        names = self.joint_names if joints is None else tuple(joints)
        for name in names:
            if name not in self._idx_v:
                raise UnknownNameError("Fetch joint", name, self.joint_names)
        fid = self._tcp_id if frame is None else self._frame_id(frame)
        q = self.configuration(q_by_name)
        J = pin.computeFrameJacobian(
            self.model, self.data, q, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        return np.array(J[:, [self._idx_v[n] for n in names]])

    def _frame_id(self, frame: str) -> int:
        if frame not in self.frame_names:
            raise UnknownNameError("Fetch frame", frame, sorted(set(self.frame_names)))
        return int(self.model.getFrameId(frame))
