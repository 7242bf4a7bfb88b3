"""Pull affordances: grasp poses ``g`` for the opening and probing skills, biased by the
network's per-pixel pull-affordance map (as the paper biases its controller parameters
with Where2Act's pull heat maps).

:func:`sample_grasps` draws grasp poses on one fused part: a pixel of the part (from any
view that saw it) with probability proportional to ``pull ** SHARPNESS + FLOOR``
(``pull`` the network's probability that the pixel is a handle; the floor keeps every
pixel of the part possible, so a handle-less front can still be pushed or pulled at),
its world point as the grasp point, the approach straight into the cabinet front, the
fingers straddling the handle. A point on the handle (pull > :data:`SNAP_P`) is moved
onto the line of the bar through the middle of the handle's pixels, within
:data:`BAR_MIDDLE` of that middle (its depth kept): a pull
there does not twist the part, and the skills find the handle a grasp is on by its
middle (:data:`strug_manip.control.skills.HANDLE_RADIUS`), so a grasp near the end of a
20 cm bar would not be taken for that handle's.

Gripper frame (the skills' convention, :mod:`strug_manip.control`): the ``gripper``
site's x axis is the approach direction (out of the palm), y the direction in which the
fingers open, z = x x y. The fingers open across the handle's bar: the bar's direction
is the principal direction of the part's high-affordance points on the front plane, or,
without a visible handle, the direction a handle of that joint type has (a drawer's bar
is horizontal, a side door's vertical, a flap's horizontal).
"""

from __future__ import annotations

import numpy as np

from perception.errors import BadInputError
from perception.fusion import FusedCabinet, handle_middle

#: Exponent and floor of the sampling weights.
SHARPNESS, FLOOR = 2.0, 1e-4
#: Affordance above which a pixel counts as handle for the bar direction.
HANDLE_P = 0.5
#: Affordance above which a grasp point counts as on the handle (its edge pixels too).
SNAP_P = 0.2
#: A grasp point on the handle lies at most this far from the handle's middle along
#: its bar [m].
BAR_MIDDLE = 0.02


def grasp_frame(approach: np.ndarray, bar: np.ndarray) -> np.ndarray:
    """Rotation (3, 3): x = ``approach``, y across ``bar`` (perpendicular to both)."""
    x = np.asarray(approach, float) / np.linalg.norm(approach)
    y = np.cross(np.asarray(bar, float), x)
    if np.linalg.norm(y) < 1e-6:
        raise BadInputError("the bar direction must not be parallel to the approach")
    y /= np.linalg.norm(y)
    return np.stack([x, y, np.cross(x, y)], axis=1)


def sample_grasps(
    fused: FusedCabinet,
    part: int,
    n: int,
    rng: np.random.Generator,
    joint_type: str | None = None,
    sharpness: float = SHARPNESS,
    floor: float = FLOOR,
) -> tuple[np.ndarray, np.ndarray]:
    """``n`` grasp poses on fused part ``part`` (module docstring).

    Args:
        fused: the fusion; part: index into ``fused.parts``.
        n: number of poses; rng: the only randomness.
        joint_type: the believed type (default: the part's most probable), which sets the
            bar direction when no handle is seen.
        sharpness, floor: the weights ``pull ** sharpness + floor`` (``sharpness=0``:
            uniform over the part's pixels).

    Returns:
        ``(T_world_gripper (n, 4, 4), pull affordance of each grasp point (n,))``.

    Raises:
        BadInputError: a bad part index or ``n``.
    """
    if not 0 <= part < len(fused.parts):
        raise BadInputError(
            f"part must index fused.parts (0..{len(fused.parts) - 1}), got {part!r}"
        )
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise BadInputError(f"n must be an integer >= 1, got {n!r}")
    h = fused.parts[part]
    pts = np.concatenate([r.instance.points for r in h.readings])
    pull = np.concatenate([r.instance.pull for r in h.readings])
    front = fused.front
    normal = front.dir_to_world([1.0, 0.0, 0.0])
    kind = joint_type or h.joint_type
    handle = pts[pull > HANDLE_P]
    middle, along = handle_middle(handle, front), None
    if middle is not None:
        local = front.to_front(handle)[:, 1:]
        _, _, vt = np.linalg.svd(local - local.mean(axis=0), full_matrices=False)
        along = vt[0]
        bar = front.dir_to_world([0.0, *along])
    elif kind == "revolute" and h.side in ("left", "right"):
        bar = front.dir_to_world([0.0, 0.0, 1.0])
    else:
        bar = front.dir_to_world([0.0, 1.0, 0.0])
    w = pull**sharpness + floor
    idx = rng.choice(len(pts), size=n, p=w / w.sum())
    R = grasp_frame(-normal, bar)
    T = np.tile(np.eye(4), (n, 1, 1))
    T[:, :3, :3] = R
    p = front.to_front(pts[idx])
    if middle is not None:  # on the handle: toward its middle (module docstring)
        on = pull[idx] > SNAP_P
        off = np.clip((p[:, 1:] - middle) @ along, -BAR_MIDDLE, BAR_MIDDLE)
        p[on, 1:] = middle + off[on, None] * along
    T[:, :3, 3] = front.to_world(p)
    return T, pull[idx]
