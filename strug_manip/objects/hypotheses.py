"""Joint hypotheses: a part's joint as the robot believes it, and the cabinet it implies.

:class:`BelievedJoint` is one movable part's joint in the world frame (type, axis,
hinge point, travel left): what an opening skill follows. :func:`believed_spec` turns
a :class:`~strug_manip.objects.generator.CabinetSpec` and a believed joint of one of its
parts into the cabinet that belief describes (a belief particle), which the world
compiles like any other (``ManipulationWorld.from_cabinet_spec``).

Units: [m], [rad]; poses are 4x4 homogeneous transforms ``T_world_frame``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from planners.errors import ConfigError, UnknownNameError
from strug_manip.geometry import axis_angle
from strug_manip.objects.generator import CabinetSpec, PartSpec

#: Tolerances of :func:`check_pose`, as ``np.allclose`` reads them (``atol + 1e-5 *
#: |expected|``): the last row to 1e-9, ``R^T R`` to the identity to 1e-6.
_LAST_ROW = np.array([0.0, 0.0, 0.0, 1.0])
_ROW_TOL = 1e-9 + 1e-5 * _LAST_ROW
_ORTHO_TOL = 1e-6 + 1e-5 * np.eye(3)


def check_pose(name: str, T: object) -> np.ndarray:
    """Return ``T`` as a float (4, 4) rigid transform, or raise :class:`ConfigError`.

    Checks shape, finiteness, the last row ``(0, 0, 0, 1)`` and that the rotation block
    is orthonormal with determinant +1 (to 1e-6).
    """
    try:
        arr = np.asarray(T, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a 4x4 homogeneous transform [m], got {T!r}") from None
    if arr.shape != (4, 4):
        raise ConfigError(
            f"{name} must be a 4x4 homogeneous transform [m], got shape {arr.shape}: {T!r}"
        )
    if not np.isfinite(arr).all():
        raise ConfigError(f"{name} must be finite, got {arr.tolist()!r}")
    if not (np.abs(arr[3] - _LAST_ROW) <= _ROW_TOL).all():
        raise ConfigError(f"{name} must end with the row (0, 0, 0, 1), got {arr[3].tolist()!r}")
    R = arr[:3, :3]
    # (The determinant of an orthonormal R is +-1: the sign of the triple product.)
    (a, b, c), (d, e, f), (g, h, i) = R.tolist()
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    if not (np.abs(R.T @ R - np.eye(3)) <= _ORTHO_TOL).all() or det < 0:
        raise ConfigError(
            f"the rotation block of {name} must be a rotation matrix (orthonormal, det +1), "
            f"got {R.tolist()!r}"
        )
    return arr


@dataclass(frozen=True)
class BelievedJoint:
    """The joint of the part to operate, as the robot believes it (world frame).

    Attributes:
        type: ``"prismatic"`` or ``"revolute"``.
        axis: unit axis, shape (3,): the opening direction of a prismatic joint, the
            hinge axis of a revolute one (opening is positive rotation about it).
        origin: a point on the hinge axis, shape (3,) [m] (unused for prismatic).
        limit: travel left before the joint limit from its current position
            [m or rad].
    """

    type: str
    axis: np.ndarray
    origin: np.ndarray = field(default_factory=lambda: np.zeros(3))
    limit: float = math.inf

    def __post_init__(self) -> None:
        if self.type not in ("prismatic", "revolute"):
            raise ConfigError(
                f"BelievedJoint.type must be 'prismatic' or 'revolute', got {self.type!r}"
            )
        axis = np.asarray(self.axis, dtype=float).reshape(-1)
        origin = np.asarray(self.origin, dtype=float).reshape(-1)
        if axis.shape != (3,) or not np.all(np.isfinite(axis)) or np.linalg.norm(axis) < 1e-9:
            raise ConfigError(
                f"BelievedJoint.axis must be a finite non-zero (3,), got {self.axis!r}"
            )
        if origin.shape != (3,) or not np.all(np.isfinite(origin)):
            raise ConfigError(f"BelievedJoint.origin must be a finite (3,), got {self.origin!r}")
        if not self.limit > 0:
            raise ConfigError(f"BelievedJoint.limit must be > 0, got {self.limit!r}")
        object.__setattr__(self, "axis", axis / np.linalg.norm(axis))
        object.__setattr__(self, "origin", origin)

    def move(self, T: np.ndarray, q: float) -> np.ndarray:
        """Where a pose ``T`` (4, 4) rigidly attached to the part goes when the joint
        opens by ``q`` [m or rad] more."""
        out = T.copy()
        if self.type == "prismatic":
            out[:3, 3] += q * self.axis
            return out
        R = axis_angle(self.axis, q)
        out[:3, :3] = R @ T[:3, :3]
        out[:3, 3] = self.origin + R @ (T[:3, 3] - self.origin)
        return out

    @classmethod
    def of_part(
        cls, part: PartSpec, q: float = 0.0, T_world_object: np.ndarray | None = None
    ) -> BelievedJoint:
        """The joint of ``part`` (e.g. the generator's ground truth) at joint position
        ``q`` [m or rad], in the world frame of ``T_world_object`` (4, 4; default
        identity: the object frame); ``limit`` is the travel left to the upper limit.

        A prismatic joint's origin is the closed front's centre (``cell_center``): its
        link origin says nothing about where the drawer is (the generator puts it
        there; PartNet-Mobility puts sliders' origins anywhere, 41083's at the
        carcass's back), and only a point of the part makes origins comparable."""
        if not isinstance(part, PartSpec) or not part.movable:
            raise ConfigError(f"part must be a movable PartSpec, got {part!r}")
        T = np.eye(4) if T_world_object is None else np.asarray(T_world_object, dtype=float)
        origin = part.cell_center if part.joint_type == "prismatic" else part.origin
        return cls(
            type=part.joint_type,
            axis=T[:3, :3] @ part.axis,
            origin=(T @ np.r_[origin, 1.0])[:3],
            limit=max(float(part.upper - q), 1e-9),
        )


#: A believed joint counts as the true one (:func:`same_joint`) with its axis within this
#: angle of the true axis [deg] ...
TRUE_AXIS_DEG = 10.0
#: ... and the true hinge point within this distance of the believed hinge line (a
#: revolute joint), or the origins within it (a prismatic one) [m].
TRUE_OFFSET = 0.05


def same_joint(
    believed: BelievedJoint,
    true: BelievedJoint,
    max_angle_deg: float = TRUE_AXIS_DEG,
    max_offset: float = TRUE_OFFSET,
) -> bool:
    """Whether ``believed`` is the ``true`` joint as the evaluations count a true
    hypothesis (``true_in_support`` of ``tools/eval_perception.py``, the belief health of
    ``tools/eval_manipulation.py``): the same type, the axes within ``max_angle_deg``
    [deg] (signed: a door believed hinged on the wrong side is 180 deg off), and the
    true joint's origin within ``max_offset`` [m] of the believed hinge line (revolute)
    or of the believed origin (prismatic). Both joints in one frame (e.g. the world's)."""
    if believed.type != true.type:
        return False
    cos = float(np.clip(believed.axis @ true.axis, -1.0, 1.0))
    if math.degrees(math.acos(cos)) > max_angle_deg:
        return False
    r = true.origin - believed.origin
    if believed.type == "revolute":
        r = r - (r @ believed.axis) * believed.axis
    return float(np.linalg.norm(r)) <= max_offset


def true_hypothesis(
    part: PartSpec, T_world_object: np.ndarray, truth: PartSpec, T_world_truth: np.ndarray
) -> bool:
    """Whether ``part`` of a believed cabinet standing at ``T_world_object`` (4, 4) holds
    the true hypothesis of the real part ``truth`` (its cabinet at ``T_world_truth``):
    for a movable real part, :func:`same_joint` of the two joints in the world frame;
    for a fixed one (an open cell), a fixed part of the same kind."""
    if not truth.movable:
        return not part.movable and part.kind == truth.kind
    if not part.movable:
        return False
    return same_joint(
        BelievedJoint.of_part(part, 0.0, T_world_object),
        BelievedJoint.of_part(truth, 0.0, T_world_truth),
    )


#: Joint limit of a part whose believed joint type differs from the spec's and whose
#: believed travel is unbounded: prismatic [m], revolute [rad].
BELIEVED_PRISMATIC_UPPER = 0.5
BELIEVED_REVOLUTE_UPPER = 0.5 * math.pi


def believed_spec(
    spec: CabinetSpec,
    link: str,
    joint: BelievedJoint,
    T_world_cabinet: np.ndarray | None = None,
    q: float = 0.0,
) -> CabinetSpec:
    """A copy of ``spec`` with part ``link``'s joint replaced by the believed ``joint``
    (a belief particle's cabinet, to build a planning world from).

    The part's geometry is kept where it is with the part closed; the link frame moves
    to the believed hinge (revolute beliefs), the geometry and centre of mass being
    re-expressed in it. Limits: ``[min(lower, 0), q + joint.limit]`` (same type: the
    spec's lower; a changed type with unbounded travel: :data:`BELIEVED_PRISMATIC_UPPER`
    [m] or :data:`BELIEVED_REVOLUTE_UPPER` [rad]).

    Args:
        spec: the cabinet (e.g. the generator's ground truth), not modified.
        link: the movable part to change (``link_1``, ...).
        joint: the believed joint in the world frame (axis, origin [m], limit: travel
            left [m or rad] from ``q``).
        T_world_cabinet: the cabinet frame in the world, (4, 4) [m] (default: identity,
            ``joint`` given in the cabinet frame), e.g. ``world.scene.T_world_cabinet``.
        q: the believed current joint position [m or rad].

    Raises:
        UnknownNameError: ``link`` is not a movable part of ``spec``.
        ConfigError: a bad argument.
    """
    if not isinstance(spec, CabinetSpec):
        raise ConfigError(f"spec must be a CabinetSpec, got {spec!r}")
    if not isinstance(joint, BelievedJoint):
        raise ConfigError(f"joint must be a BelievedJoint, got {joint!r}")
    T = np.eye(4) if T_world_cabinet is None else check_pose("T_world_cabinet", T_world_cabinet)
    if isinstance(q, bool) or not isinstance(q, int | float) or not math.isfinite(q):
        raise ConfigError(f"q must be a finite number [m or rad], got {q!r}")
    links = [p.link for p in spec.movable_parts]
    if link not in links:
        raise UnknownNameError("movable cabinet part link", link, links)
    part = spec.part(link)
    R, t = T[:3, :3], T[:3, 3]
    axis = R.T @ joint.axis
    if joint.type == "revolute":
        origin = R.T @ (joint.origin - t)
    else:
        origin = np.asarray(part.origin, dtype=float).copy()
    shift = np.asarray(part.origin, dtype=float) - origin  # old link frame in the new one
    geoms = tuple(
        dataclasses.replace(g, pos=tuple(float(v) for v in np.asarray(g.pos) + shift))
        for g in part.geoms
    )
    inertial = dataclasses.replace(part.inertial, com=np.asarray(part.inertial.com) + shift)
    same = joint.type == part.joint_type
    if math.isfinite(joint.limit):
        upper = float(q) + joint.limit
    elif same:
        upper = float(part.upper)
    else:
        upper = BELIEVED_PRISMATIC_UPPER if joint.type == "prismatic" else BELIEVED_REVOLUTE_UPPER
    lower = min(float(part.lower) if same else 0.0, float(q), 0.0)
    kind = "drawer" if joint.type == "prismatic" else "door"
    new = dataclasses.replace(
        part,
        kind=kind,
        semantic=kind,
        joint_type=joint.type,
        axis=axis,
        origin=origin,
        lower=lower,
        upper=upper,
        hinge=hinge_side(part, axis, origin) if joint.type == "revolute" else None,
        geoms=geoms,
        inertial=inertial,
    )
    parts = tuple(new if p.link == link else p for p in spec.parts)
    return dataclasses.replace(spec, parts=parts)


def hinge_side(part: PartSpec, axis: np.ndarray, origin: np.ndarray) -> str:
    """Which edge of ``part``'s cell a hinge (unit ``axis`` (3,) through ``origin`` (3,),
    object frame) is on: ``left``/``right`` (seen from the front: -y/+y) for a vertical
    axis, ``top``/``bottom`` for a horizontal one."""
    c = np.asarray(part.cell_center, dtype=float)
    if abs(float(axis[2])) > abs(float(axis[1])):
        return "left" if origin[1] < c[1] else "right"
    return "top" if origin[2] > c[2] else "bottom"


#: Every kinematic model a front in a cell can have: a drawer, or a door hinged on one
#: of the cell's four edges.
CELL_MODELS: tuple[str, ...] = ("drawer", "left", "right", "top", "bottom")


def cell_joints(part: PartSpec, limit: float = math.inf) -> dict[str, BelievedJoint]:
    """The joint of each model of :data:`CELL_MODELS` for ``part``'s cell, in the object
    frame, with the part closed: a drawer sliding out of the front, or a door hinged on
    the cell's left, right, top or bottom edge on the front plane (the top hinge on the
    panel's back face, as the generator makes it), opening outward; ``limit`` the travel.

    Raises:
        ConfigError: ``part`` is not a movable front (a shelf has no front).
    """
    if not isinstance(part, PartSpec) or part.kind not in ("drawer", "door", "panel"):
        raise ConfigError(f"part must be a drawer, door or panel, got {part!r}")
    c = np.asarray(part.cell_center, dtype=float)
    w, h = (float(v) for v in part.cell_size)
    x = np.array([1.0, 0.0, 0.0])
    t = float(part.geoms[0].size[0])  # the front's thickness
    edges = {
        "left": (np.array([0.0, 1.0, 0.0]), c + np.array([0.0, -w / 2, 0.0])),
        "right": (np.array([0.0, -1.0, 0.0]), c + np.array([0.0, w / 2, 0.0])),
        "bottom": (np.array([0.0, 0.0, 1.0]), c + np.array([0.0, 0.0, -h / 2])),
        "top": (np.array([0.0, 0.0, -1.0]), c + np.array([-t, 0.0, h / 2])),
    }
    out = {"drawer": BelievedJoint("prismatic", x, c, limit)}
    for name, (e, origin) in edges.items():
        out[name] = BelievedJoint("revolute", np.cross(e, x), origin, limit)
    return out


def model_of(part: PartSpec) -> str:
    """Which of :data:`CELL_MODELS` ``part`` is (``drawer`` or its door's hinge side)."""
    if part.joint_type == "prismatic":
        return "drawer"
    if part.hinge is None:
        raise ConfigError(f"part {part.link} ({part.kind}) has no kinematic model")
    return part.hinge
