"""Grasp poses of cabinet handles, for the opening and probing skills.

A handle grasp puts the TCP on the handle's grasp point with the gripper's approach
(its x axis) into the part's front and its fingers straddling the handle: the finger
opening (gripper y) perpendicular to a bar. A knob can be taken either way, so the
fingers first straddle it as they would the bar such a part has: on a door a bar along
the hinge (vertical on a side door, horizontal on a flap), on a drawer a horizontal
bar. A bar perception took for a knob is then held too (OpenDoor episode 9800 and
OpenDrawer 10047, 10049, 10067: "the fingers closed on nothing", each time on a
bar); the other way is the next candidate. Of
the two finger directions the one pointing up (or, if level, to +y) is used; the
skills' base placement also tries the fingers swapped (the same grasp, the wrist
turned half a turn).

:func:`handle_grasps` lists candidates for one part, best first: level, then pitched
down by :data:`PITCHES` (the approach tilted downward: the wrist above the handle, so
the forearm clears low fronts and table edges), then pitched up. Each is a full
``T_world_gripper``; a caller (the manipulation domain's grasp sampler, an evaluation)
tries them in order. Where the open finger pads would reach the part's front before the
TCP is at the grasp point (a short knob, a steep pitch), the grasp backs off along the
front's normal until they clear it by :data:`FACE_CLEARANCE`; a grasp that would need
to back off so far that the handle leaves the pads is not offered (a bar must stay
:data:`MIN_OVERLAP` inside the pads' tips; a knob, squeezed on its sides, must keep
:data:`MIN_KNOB_GRIP` of its length between them).

Frames: ``T_world_object`` is the cabinet's frame (its +x the front's outward normal).
"""

from __future__ import annotations

import numpy as np

from strug_manip.geometry import axis_angle
from strug_manip.objects.generator import PartSpec

#: Pitch angles of the candidate grasps after the level one [rad] (positive: the
#: approach tilted down).
PITCHES: tuple[float, ...] = (0.35, 0.7, -0.35)
#: Corners of the open finger pads relative to the TCP, gripper frame [m] (fetch.xml:
#: pads 0.077 x 0.014 x 0.027 centred 0.02 behind the TCP, their inner faces 0.051
#: from the centre line with the fingers open).
PAD_CORNERS = np.array(
    [(x, sy * y, sz * 0.0135) for x in (0.0185, -0.0585) for y in (0.0509, 0.0649)
     for sy in (1.0, -1.0) for sz in (1.0, -1.0)]
)  # fmt: skip
#: Gap kept between the pads and the part's front at the grasp [m].
FACE_CLEARANCE = 0.003
#: The handle must stay this far inside the pads' tips when a grasp backs the TCP off
#: the front to keep the pads clear of it [m] (else that grasp is dropped).
MIN_OVERLAP = 0.008
#: A knob is squeezed on its sides, so it holds wherever it lies between the pads: a
#: grasp backed off the front is kept while at least this much of the knob's length
#: stays between the pads' tips and its end [m] (half the pads' 0.027 height, so a
#: pitched grasp still closes on the knob's cylinder, not its rim).
MIN_KNOB_GRIP = 0.012


def grasp_rotation(approach: np.ndarray, bar_axis: np.ndarray | None) -> np.ndarray:
    """Gripper orientation ``R_world_gripper`` (3, 3): x along ``approach``, y (the
    finger opening) perpendicular to ``bar_axis`` (a knob, or a bar along the approach:
    y horizontal), of the two the one with y pointing up (or, if level, to +y)."""
    a = np.asarray(approach, dtype=float)
    a = a / np.linalg.norm(a)
    y = None
    if bar_axis is not None:
        y = np.cross(a, np.asarray(bar_axis, dtype=float))
        if np.linalg.norm(y) < 1e-6:
            y = None
    if y is None:
        y = np.cross(np.array([0.0, 0.0, 1.0]), a)
        if np.linalg.norm(y) < 1e-6:
            y = np.array([0.0, 1.0, 0.0])
    y = y - (y @ a) * a
    y /= np.linalg.norm(y)
    if y[2] < -1e-9 or (abs(y[2]) <= 1e-9 and y[1] < 0):
        y = -y
    return np.column_stack([a, y, np.cross(a, y)])


def flip_fingers(T: np.ndarray) -> np.ndarray:
    """The same grasp with the fingers swapped: ``T`` (4, 4) turned half a turn about
    its approach axis."""
    out = np.array(T, dtype=float, copy=True)
    out[:3, 1] = -out[:3, 1]
    out[:3, 2] = -out[:3, 2]
    return out


def handle_grasps(
    part: PartSpec, q: float = 0.0, T_world_object: np.ndarray | None = None
) -> list[np.ndarray]:
    """Candidate ``T_world_gripper`` (4, 4) grasping ``part``'s handle at joint position
    ``q`` [m or rad], best first (level, then :data:`PITCHES`); [] for a part without a
    handle (a flat front cannot be grasped by a parallel gripper).

    The approach is against the front's outward normal as the part is at ``q`` (a door
    opened by q: its panel's normal), pitched about the horizontal axis of the front.
    """
    if part.handle_pos is None or part.handle == "none":
        return []
    T = np.eye(4) if T_world_object is None else np.asarray(T_world_object, dtype=float)
    R_part = np.eye(3) if part.joint_type != "revolute" else axis_angle(part.axis, q)
    normal = T[:3, :3] @ R_part @ np.array([1.0, 0.0, 0.0])
    bar = T[:3, :3] @ R_part @ part.handle_axis if part.handle == "bar" else None
    point = part.handle_at(q, T)
    side = np.cross([0.0, 0.0, 1.0], normal)  # horizontal, along the front
    if np.linalg.norm(side) < 1e-6:
        side = T[:3, :3] @ np.array([0.0, 1.0, 0.0])
    side /= np.linalg.norm(side)
    bars: list[np.ndarray | None] = [bar]
    if part.handle == "knob":
        # As if straddling the bar such a part has (a door: along the hinge; a
        # drawer: horizontal, the fingers open vertically); then the other way.
        if part.joint_type == "revolute":
            edge = T[:3, :3] @ R_part @ np.cross(part.axis, [1.0, 0.0, 0.0])
            bars = [np.cross(normal, edge), edge]
        else:
            bars = [side, None]
    depth = float(part.handle_pos[0] - front_of_handle(part))  # TCP in front of the face
    out = []
    slack = max_back_off(part)
    for b in bars:
        for pitch in (0.0, *PITCHES):
            approach = axis_angle(side, -pitch) @ -normal  # +pitch: tilted down
            g = np.eye(4)
            g[:3, :3] = grasp_rotation(approach, b)
            # The pads' deepest point toward the face, as far in front of the TCP.
            reach = float(np.max(PAD_CORNERS @ (g[:3, :3].T @ -normal)))
            back = max(0.0, reach + FACE_CLEARANCE - depth)
            if back > slack:
                continue  # the pads would hit the front before they straddle the handle
            g[:3, 3] = point + back * normal
            out.append(g)
    return out


def max_back_off(part: PartSpec) -> float:
    """How far a grasp of ``part`` may back off its grasp point along the front's
    normal [m]: a bar must stay :data:`MIN_OVERLAP` inside the pads' tips; a knob must
    keep :data:`MIN_KNOB_GRIP` of its length between the tips and its end. Both use the
    level grasp's pad reach, so a pitched grasp is held to the same margin."""
    slack = PAD_CORNERS[0, 0] - MIN_OVERLAP
    if part.handle == "knob":
        beyond = knob_end(part) - float(part.handle_pos[0])  # knob in front of the point
        slack = max(slack, PAD_CORNERS[0, 0] + beyond - MIN_KNOB_GRIP)
    return slack


def knob_end(part: PartSpec) -> float:
    """The x of a knob's free end (object frame, part closed) [m]."""
    xs = [
        part.origin[0] + g.pos[0] + 0.5 * g.size[1]
        for g in part.geoms
        if g.name.startswith("handle_knob") and g.shape == "cylinder"
    ]
    if not xs:
        raise ValueError(f"part {part.link!r} has no knob")
    return float(max(xs))


def front_of_handle(part: PartSpec) -> float:
    """The x of the front face the handle stands on (object frame, part closed) [m]:
    where its knob or posts start."""
    xs = [
        part.origin[0] + g.pos[0] - 0.5 * g.size[1]  # geoms are in the link frame
        for g in part.geoms
        if g.name.startswith(("handle_knob", "handle_post")) and g.shape == "cylinder"
    ]
    if not xs:
        raise ValueError(f"part {part.link!r} has no knob or bar posts")
    return float(min(xs))


def held_grasp(T_gripper_object: np.ndarray) -> str:
    """``top`` if the object hangs along the gripper's approach (its up axis against
    the approach: taken from above), else ``side``."""
    return "top" if float(np.asarray(T_gripper_object)[0, 2]) < -0.7 else "side"
