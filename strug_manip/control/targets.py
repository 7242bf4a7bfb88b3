"""Where the object goes in a cabinet part, and with which grasp it gets there.

:func:`place_targets` turns "put the object into this part" into poses ``p`` for
:class:`~strug_manip.control.skills.Place`, in the order to try them, and the grasp
:class:`~strug_manip.control.skills.Pick` must take for them (:func:`place_target`:
the first):

- an open **drawer**: lowered from above (``top`` grasp) into the part of the drawer's
  box that is out of the carcass, resting on its bottom: in its middle, else as near
  the drawer's front wall as it goes. The box must be out far enough for the object
  and the opened fingers (:data:`FINGER_SPAN`) with :data:`CLEARANCE` all round; the
  object lies along the pull (fingers across the box) where that fits, else across it.
  It is lowered from :data:`ABOVE_WALLS` over the box's walls (the target's ``lift``):
  the free motion ends above them, and only the straight, slow line down the middle
  of the box comes near them; where no base pose reaches that high, the same places
  follow lowered from ``SkillParams.place_clearance`` (the free motion then ends inside
  the box), then lowered from just over the walls (:data:`SKIM_OVER`, a drawer high
  up), then, in a deep box, let go higher up and dropped (:data:`DROPS`); last, held
  leaning (:data:`LEAN`), the wrist out in front of the drawer above.
- a **cell** (behind an open door, or an open shelf): carried in level from the front
  (``side`` grasp), resting on the cell's floor :data:`INSERT` behind the front; it
  comes in midway up the cell's free opening (up to :data:`MAX_LIFT` above its place),
  over the cell's front edge, and over an open drop-down flap (whose edge it must
  clear: a flap opened too little leaves no way in).

Poses are ``T_world_object`` of the object's box (its x: the 0.10 m side, y: the
0.06 m side the fingers close across, z up). Raises :class:`~planners.errors.ConfigError`
naming the sizes when the object does not fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planners.errors import ConfigError
from strug_manip.geometry import axis_angle
from strug_manip.objects.generator import CabinetSpec, PartSpec
from strug_manip.world.scene import OBJECT_HALF_SIZE

#: Span of the fully opened fingers, outer faces [m] (2 x (0.05 travel + 0.0149)).
FINGER_SPAN = 0.13
#: Clearance kept between the object (or the fingers) and every wall [m].
CLEARANCE = 0.01
#: The carcass's front edge: the drawer box counts as out of the carcass this far in
#: front of the front plane [m] (the gripper comes down past the cabinet's top edge).
FRONT_MARGIN = 0.01
#: How far behind the front plane (and the door's thickness) the object's centre goes
#: into a cell [m]: the whole object inside, the palm's front face just inside too.
INSERT = 0.08
#: Height of a level-held object with the hand around it, from the object's bottom
#: [m]: the palm's top is 7.5 mm above the object's (the TCP 1 cm above its centre).
HELD_HEIGHT = 0.0925
#: Behind a drop-down flap, the object comes in pitched down by this [rad] (its far
#: end low), its lowest edge this high above the floor [m], and is let go with its
#: centre this much higher than resting [m], whence it drops flat onto the floor.
FLAP_PITCH = 0.35
FLAP_LOWEST = 0.02
FLAP_DROP = FLAP_LOWEST + 0.05 * 0.343
#: The palm's top above a held object's top [m] (see :data:`HELD_HEIGHT`).
PALM_ABOVE = 0.0075
#: Highest start above its place of an object carried into a cell [m].
MAX_LIFT = 0.15
#: An object goes into a drawer lowered from with its bottom this far above the top of
#: the drawer's walls (its interior's top) [m]. Lowered from ``place_clearance`` (0.12
#: m) above its place, the object started below the walls, so the carrying reach (a
#: free motion) had to bring it down into the box over a wall: in the demo (issue 37)
#: perception's box stood 4.8 cm lower than the real one, the reach came in over a side
#: wall at the 2 cm ``held_clearance`` of the believed one, struck the real wall and,
#: on the next try, pushed the drawer shut. Lifts of 0.17-0.23 m over the place (0.6-6.6
#: cm over the believed walls) all placed the demo's object; 0.26 m was out of the
#: arm's reach over that 1.2 m high drawer: 5 cm, the box's error, within reach.
ABOVE_WALLS = 0.05
#: Where a drawer is out of the arm's reach from both heights above (a drawer 1.2 m up:
#: the hand held 0.12 m over the place is higher than a top grasp reaches), the object
#: is lowered from this little over the walls [m] (its bottom ``place_drop`` more):
#: measured on two episode cabinets (generator seeds 6339 and 8186, 6 and 8 cm deep
#: boxes with their objects' centres 1.23 and 1.24 m up) whose places were out of reach
#: (``ik_infeasible``) from 0.12 m: 6339 placed from 2 cm over its walls, 8186 only from
#: 0 cm (1 cm was out of reach). The walls' height is perception's, centimetres off,
#: which is why these come last: tried only where nothing higher is reachable.
SKIM_OVER = (0.02, 0.0)
#: In a deep drawer, the object is let go this high above the box's floor [m] (its
#: bottom), and drops in, where lowering it all the way is out of reach: measured on
#: episode cabinet 9473 (generator seed; a 0.32 m deep box, its floor 0.84 m up, out
#: 0.17 m), the forearm met the box's front wall whenever the wrist came below its top
#: (a release 0.05 m up); released 0.10 or 0.15 m up the object landed upright inside.
DROPS = (0.10, 0.15)
#: A dropped object's top stays this far below the walls' top when let go [m]: it
#: cannot tip out over them.
DROP_BELOW_WALLS = 0.05
#: Last of all, a drawer's object goes this near the box's front wall [m] (half
#: :data:`CLEARANCE`), from every height above: a low drawer out only 17 cm under
#: another leaves the wrist's roll link (a 10.4 cm disc) a window of 7 mm between the
#: knob above and the drawer's own front, which stands 7 cm over its walls (generator
#: seed 3025 ``link_4``, oracle OpenDrawer episode 9820): over an object 1 cm from the
#: wall it met the knob at every target (``ik_infeasible``); 5 mm from it the object
#: was placed.
TIGHT_GAP = 0.005
#: Where nothing level is reachable, a drawer's object is held leaning by this [rad]
#: about the drawer's width, its top toward the robot: the wrist, 0.19 m above the
#: object's centre along the grasp, stands 6.5 cm farther out, in front of the drawer
#: above and its knob, which a level hand over a drawer out 15.5 cm under another met
#: at all 15 level places (oracle OpenDrawer episodes 9823, 9988: both placed leaning).
LEAN = 0.35
#: The leaning object's lowest edge is let go this high over the box's floor [m]; it
#: drops onto that edge and falls back flat, its centre behind the edge.
LEAN_LOWEST = 0.01


@dataclass(frozen=True)
class PlaceTarget:
    """Where the object goes and how it must be held.

    Attributes:
        p: ``T_world_object`` of the object resting there, (4, 4) [m].
        grasp: ``top`` or ``side`` (the :class:`~strug_manip.control.skills.Pick` grasp).
        lift: how much higher than ``p`` the placing motion starts [m] (Place's
            ``lift``): a level object's way in over a cell's floor, a lowered
            object's drop into a drawer from above its walls (:data:`ABOVE_WALLS`).
        skim: a lowered object starts exactly ``lift`` above ``p``, even below
            ``SkillParams.place_clearance`` (Place's ``skim``, :data:`SKIM_OVER`).
    """

    p: np.ndarray
    grasp: str
    lift: float = 0.0
    skim: bool = False


def _cell_place(
    part: PartSpec, q: float, half: np.ndarray, link: str
) -> tuple[np.ndarray, float, float]:
    """Object centre (3,) in a cell (object frame), the lift to come in with, and the
    pitch to hold it at [rad].

    The object goes :data:`INSERT` behind the front, across the cell's width in the
    middle of the part of the opening an open door leaves free (a side door at angle
    ``q`` still covers ``w cos q + t sin q`` of it next to its hinge; a top flap hangs
    ``h cos q + t`` down into it), resting on the floor. It comes in level midway up
    the free height (the hand as far from the top as the object from the floor's front
    edge, up to :data:`MAX_LIFT`; under a top flap, up to its hanging edge: carried in
    at the floor, an object whose believed floor stood 1 cm low struck the cell's front
    edge and slid the cabinet); behind a drop-down flap it
    comes in pitched down by :data:`FLAP_PITCH`
    (the wrist and forearm, out over the open flap, ride higher), :data:`CLEARANCE`
    over the flap's edge and no higher (the pitched hand's wrist rises behind the
    object and meets the cell's top edge when it comes in higher), and is let go
    :data:`FLAP_DROP` above the floor, onto which it drops;
    the pitched object stands taller than a level one (its near top corner, and the palm
    over it), and a cell lower than that cannot take it (a level object cannot pass the
    flap's edge there either).
    """
    center = np.asarray(part.interior_center, dtype=float)
    size = np.asarray(part.interior_size, dtype=float)
    front, floor = center[0] + size[0] / 2, center[2] - size[2] / 2
    y_lo, y_hi = center[1] - size[1] / 2, center[1] + size[1] / 2
    top = center[2] + size[2] / 2
    drop = pitch = edge = 0.0
    if part.joint_type == "revolute" and part.hinge is not None:
        panel = part.geoms[0].size  # (thickness, width, height) of the door's panel
        t = float(panel[0])
        if part.hinge in ("left", "right"):
            cover = float(panel[1]) * max(np.cos(q), 0.0) + t * abs(np.sin(q))
            if part.hinge == "left":  # the viewer's left: -y of the object frame
                y_lo += cover
            else:
                y_hi -= cover
        elif part.hinge == "top":
            top -= float(panel[2]) * max(np.cos(q), 0.0) + t
        else:  # a drop-down flap: the wrist, out over it, must stay above its panel
            drop, pitch = FLAP_DROP, FLAP_PITCH
            edge = float(panel[2]) * max(np.cos(q), 0.0) + t  # its edge above the floor
    width, height = y_hi - y_lo, top - floor
    # Height over the floor of the object as let go, with the palm: level, or pitched
    # (its lowest edge FLAP_LOWEST up, its near top corner highest).
    held = HELD_HEIGHT
    if pitch:
        held = FLAP_LOWEST + 2 * (half[0] * np.sin(pitch) + half[2] * np.cos(pitch)) + PALM_ABOVE
    need = (2 * half[0] + INSERT, FINGER_SPAN + 2 * CLEARANCE, held + CLEARANCE)
    if size[0] < need[0] or width < need[1] or height < need[2]:
        raise ConfigError(
            f"cell {link} leaves {size[0]:.3f} x {width:.3f} x {height:.3f} m (depth, "
            f"free width, free height) at joint position {q:.3f}: the object carried in "
            f"needs {need[0]:.3f} x {need[1]:.3f} x {need[2]:.3f} m"
        )
    highest = float(np.clip(height - held - CLEARANCE, 0.0, MAX_LIFT))
    if pitch and highest + drop < edge + CLEARANCE:
        raise ConfigError(
            f"flap {link} at {q:.3f} rad stands {edge:.3f} m over its cell's floor: the "
            f"object carried in at most {highest + drop:.3f} m high does not pass over it"
        )
    # Behind a drop-down flap, just over its edge: higher, the pitched wrist meets the top.
    # Level: midway between the floor's front edge and the top (the cell's believed
    # floor and top are each perception's, centimetres off; hugging the top left 1 cm).
    middle = float(np.clip(0.5 * (height - held), 0.0, MAX_LIFT))
    lift = max(edge + CLEARANCE - drop, 0.0) if pitch else min(highest, middle)
    center = np.array([front - INSERT, 0.5 * (y_lo + y_hi), floor + half[2] + drop])
    return center, lift, pitch


def place_target(spec: CabinetSpec, link: str, q: float, T_world_object: np.ndarray) -> PlaceTarget:
    """The pose to put the object into part ``link`` of ``spec`` at joint position ``q``
    [m or rad], the cabinet frame at ``T_world_object`` (4, 4): the first of
    :func:`place_targets`.

    Raises:
        UnknownNameError: no part ``link``.
        ConfigError: the part has no interior (a panel), or the object does not fit
            (a drawer not out far enough, a cell too small), the sizes named.
    """
    return place_targets(spec, link, q, T_world_object)[0]


def place_targets(
    spec: CabinetSpec, link: str, q: float, T_world_object: np.ndarray
) -> tuple[PlaceTarget, ...]:
    """The poses to put the object into part ``link`` of ``spec`` at joint position
    ``q`` [m or rad], the cabinet frame at ``T_world_object`` (4, 4), in the order to
    try them (the next where :class:`~strug_manip.control.skills.Place` finds no base
    placement: ``ik_infeasible`` stops before any motion).

    A drawer has two places: the middle of the part of its box that is out of the
    carcass, then as near its front wall as the object (and the fingers, when they open
    along the pull) allow, with :data:`CLEARANCE`: the wrist and forearm above it then
    stay farther from the fronts and handles of the drawers above (a low drawer, out
    only 15-20 cm, leaves the hand little room in front of them). Each is lowered into
    from above the drawer's front where it stands higher than the walls, then from above
    the box's walls (:data:`ABOVE_WALLS` over each), then, where that is out of reach,
    from ``place_clearance`` (lift 0), then from just over the walls
    (:data:`SKIM_OVER`); then, in a box deep enough, each is let go :data:`DROPS` above
    the floor; then the object as near the front wall as :data:`TIGHT_GAP`, from each
    of these heights in turn; last, the object leaning (:data:`LEAN`), its top toward
    the robot, from each height but the drops (:func:`_leaning`). A cell has one.

    Raises:
        UnknownNameError: no part ``link``.
        ConfigError: the part has no interior (a panel), or the object does not fit
            (a drawer not out far enough, a cell too small), the sizes named.
    """
    part = spec.part(link)
    if part.interior_center is None or part.interior_size is None:
        raise ConfigError(f"part {link} ({part.kind}) has no interior to put an object in")
    half = np.array(OBJECT_HALF_SIZE)
    size = np.asarray(part.interior_size, dtype=float)
    T = np.asarray(T_world_object, dtype=float)
    if part.joint_type != "prismatic":
        local, lift, pitch = _cell_place(part, q, half, link)
        return (_target(T, local, 0.0, pitch, "side", lift),)
    center = part.point_at(part.interior_center, q)
    back, front_wall = center[0] - size[0] / 2, center[0] + size[0] / 2
    start = max(back, spec.depth / 2 + FRONT_MARGIN)  # out of the carcass
    out = front_wall - start
    width = size[1]
    along = out >= 2 * half[0] + 2 * CLEARANCE and width >= FINGER_SPAN + 2 * CLEARANCE
    across = out >= FINGER_SPAN + 2 * CLEARANCE and width >= 2 * half[0] + 2 * CLEARANCE
    if not (along or across):
        raise ConfigError(
            f"drawer {link} is out {out:.3f} m of the carcass ({width:.3f} m wide inside): "
            f"the object ({2 * half[0]:.2f} x {2 * half[1]:.2f} m) needs "
            f"{2 * half[0] + 2 * CLEARANCE:.2f} x {FINGER_SPAN + 2 * CLEARANCE:.2f} m"
        )
    yaw = 0.0 if along else 0.5 * np.pi
    middle = 0.5 * (start + front_wall)
    reach = half[0] if along else FINGER_SPAN / 2  # the object's, or the open fingers'
    near_wall = front_wall - CLEARANCE - reach
    tight = front_wall - TIGHT_GAP - reach
    z = center[2] - size[2] / 2 + half[2]
    xs = [middle] + ([near_wall] if near_wall > middle + 1e-3 else [])
    walls = float(size[2])
    over = walls + ABOVE_WALLS
    front = rim(part) - (center[2] - size[2] / 2)  # the front's top over the floor
    # (raise over the resting place [m], lift over the release [m], skim) in the order
    # to try: over the front; else over the walls; else as reach allows; else skimming
    # the walls; else dropped.
    starts = [(0.0, front + ABOVE_WALLS, False)] if front > walls + 1e-3 else []
    starts += [(0.0, over, False), (0.0, 0.0, False)]
    starts += [(0.0, walls + o, True) for o in SKIM_OVER]
    starts += [(r, over - r, False) for r in DROPS
               if r + 2 * half[2] <= walls - DROP_BELOW_WALLS]  # fmt: skip
    places = [(x, 0.0, start) for start in starts for x in xs]
    places += [(tight, 0.0, start) for start in starts] if tight > xs[-1] + 1e-3 else []
    places += _leaning(starts, back, front_wall, along)
    return tuple(
        _target(T, np.array([x, center[1], z + r]), yaw, -pitch, "top", lift, skim)
        for x, pitch, (r, lift, skim) in places
    )


def _leaning(
    starts: list[tuple[float, float, bool]], back: float, front_wall: float, along: bool
) -> list[tuple[float, float, tuple[float, float, bool]]]:
    """The last places in a drawer: the object leaning by :data:`LEAN`, its top toward
    the robot, as near the front wall as its tilted footprint allows (``x`` [m], object
    frame), from each level start but the drops, raised so its lowest edge is
    :data:`LEAN_LOWEST` over the floor. Returns ``(x, pitch [rad], (raise, lift,
    skim))``; none where the drawer lies across (the fingers then open along the pull)
    or the tilted object does not fit in the box. Its far end may stand under the
    carcass: such a place is reached only where the arm's collision check finds a
    way."""
    hx, _, hz = OBJECT_HALF_SIZE
    reach = hx * np.cos(LEAN) + hz * np.sin(LEAN)  # the tilted box's half-depth
    x = front_wall - CLEARANCE - reach
    if not along or x - reach < back + CLEARANCE:
        return []
    r = hx * np.sin(LEAN) + hz * (np.cos(LEAN) - 1.0) + LEAN_LOWEST
    return [(x, LEAN, (r, max(lift - r, 0.0), skim)) for r0, lift, skim in starts if r0 == 0.0]


def rim(part: PartSpec) -> float:
    """Height of the part's highest board [m], object frame, part closed: a drawer's
    front often stands higher than its box's walls (7 cm on generator seed 3021), and
    an object carried in just over the walls came over the front a centimetre or two
    over its top edge; a believed cabinet 1 cm low put the object on it, and the
    cabinet slid (``tools/eval_place_offset.py``)."""
    tops = [
        part.origin[2] + g.pos[2] + g.size[2] / 2
        for g in part.geoms
        if g.shape == "box" and not g.name.startswith("handle")
    ]
    return float(max(tops, default=-np.inf))


def _target(
    T: np.ndarray,
    local: np.ndarray,
    yaw: float,
    pitch: float,
    grasp: str,
    lift: float,
    skim: bool = False,
) -> PlaceTarget:
    """A :class:`PlaceTarget` from the object's centre ``local`` (3,) [m] in the cabinet
    frame ``T`` (4, 4), turned by ``yaw`` about the vertical and pitched by ``pitch``
    [rad]."""
    p = np.eye(4)
    # Pitch: the object's x (out of the front) tilted up, so the grasp's approach (its
    # -x, into the cabinet) tilts down.
    R = axis_angle(np.array([0.0, 0.0, 1.0]), yaw) @ axis_angle(np.array([0.0, 1.0, 0.0]), -pitch)
    p[:3, :3] = T[:3, :3] @ R
    p[:3, 3] = T[:3, :3] @ local + T[:3, 3]
    return PlaceTarget(p, grasp, lift, skim)
