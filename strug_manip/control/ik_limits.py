"""The IK's joint limits and joint values: the bounds solutions keep inside the Fetch's
ranges (:data:`LIMIT_MARGIN`), the ranges restarts draw from, and joint values by name
checked against the model (:class:`~strug_manip.control.ik.FetchIK` uses them)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import mujoco
import numpy as np

from planners.errors import ConfigError, UnknownNameError

#: Distance the solutions keep from the joint limits [rad or m]: a servo commanded onto
#: a limit overshoots it under load.
LIMIT_MARGIN = 0.01


def limit_bounds(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The qpos addresses (k,) of ``model``'s limited hinge and slide joints and the
    bounds (k,), (k,) [rad or m] :data:`LIMIT_MARGIN` inside their ranges (at most a
    quarter of a range): what :func:`clip_into_limits` clips to, once."""
    adr, lows, highs = [], [], []
    kinds = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    for jid in range(model.njnt):
        if model.jnt_limited[jid] and int(model.jnt_type[jid]) in kinds:
            lo, hi = model.jnt_range[jid]
            margin = min(LIMIT_MARGIN, 0.25 * (hi - lo))
            adr.append(int(model.jnt_qposadr[jid]))
            lows.append(lo + margin)
            highs.append(hi - margin)
    return np.array(adr, dtype=int), np.array(lows), np.array(highs)


def clip_into_limits(q: np.ndarray, bounds: tuple[np.ndarray, np.ndarray, np.ndarray]) -> None:
    """Clip every limited hinge/slide joint of qpos ``q`` (nq,) into its range, at
    least :data:`LIMIT_MARGIN` inside it (where the limit constraint is satisfied):
    ``bounds`` as :func:`limit_bounds` gives them."""
    adr, lows, highs = bounds
    q[adr] = np.minimum(np.maximum(q[adr], lows), highs)


def joint_ranges(model: mujoco.MjModel, joints: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """The lower and upper bounds (k,), (k,) of ``joints`` (names) [rad or m]
    (unlimited: +-inf), for restarts and clipping."""
    lo, hi = [], []
    for j in joints:
        jid = model.joint(j).id
        limited = bool(model.jnt_limited[jid])
        lo.append(float(model.jnt_range[jid, 0]) if limited else -math.inf)
        hi.append(float(model.jnt_range[jid, 1]) if limited else math.inf)
    return np.array(lo), np.array(hi)


def check_joint_values(
    what: str, q: Mapping[str, float], known: Mapping[str, int]
) -> dict[str, float]:
    """``q`` as ``{joint: float}``, its names among ``known`` and its values finite
    numbers [m or rad].

    Raises:
        ConfigError: ``q`` is not a mapping, or a value is not a finite number.
        UnknownNameError: a name is not in ``known``.
    """
    if not isinstance(q, Mapping):
        raise ConfigError(f"{what} must map joint names to values [m or rad], got {q!r}")
    out = {}
    for name, value in q.items():
        if name not in known:
            raise UnknownNameError(f"joint of the IK model ({what})", name, list(known))
        if isinstance(value, bool) or not isinstance(value, int | float | np.number):
            raise ConfigError(f"{what}[{name!r}] must be a number [m or rad], got {value!r}")
        if not math.isfinite(float(value)):
            raise ConfigError(f"{what}[{name!r}] must be finite, got {value!r}")
        out[name] = float(value)
    return out
