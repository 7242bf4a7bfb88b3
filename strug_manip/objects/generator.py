"""Seeded procedural generator of PartNet-Mobility-style storage furniture.

``generate_cabinet(seed)`` draws a cabinet: a carcass (a box open at the front) divided
into a grid of cells, each cell holding one part: a **drawer** (prismatic joint), a
**door** (revolute joint, hinge on the left, right, top or bottom edge of the cell), a
fixed **panel**, or an open **shelf** compartment. Every random number comes from
``np.random.default_rng(seed)``: the same seed gives the same cabinet, bit for bit.
:func:`strug_manip.objects.partnet.write_partnet` writes it as ``mobility.urdf`` and
``semantics.txt``.

Object frame (all positions below, and every ``*_pos`` of the spec, are in it)
-----------------------------------------------------------------------------
Origin on the floor at the centre of the footprint; ``+x`` is the outward normal of the
open front (the front plane is ``x = depth / 2``), ``+z`` is up, ``+y = z × x``. A person
standing in front of the cabinet looks along ``-x``, so *their* left is ``-y``; "left"
and "right" (hinges, columns) are always meant from that person's point of view.
Rows are counted from the top (row 0 is the top row), columns from the viewer's left.
Every part link frame is parallel to the object frame, so a joint axis has the same
coordinates in the link, base and object frames.

Documented ranges (all drawn uniformly unless stated)
-----------------------------------------------------
What is drawn, and why: *small storage furniture that stands on a table*, the paper's
setting (its introduction speaks of "pulling the cabinet off the table"): bedside
chests, desk-top drawer units, small wall or kitchen cabinets. On a table the Fetch
reaches every handle with a level or slightly pitched grasp, and the cabinet is light
enough for a wrong pull to drag it (see ``strug_manip.world.scene`` for the table and
the friction of wood on wood).

Carcass:

- width ``W`` in [0.35, 0.90] m (along y), depth ``D`` in [0.30, 0.45] m (along x),
  height ``H`` in [0.30, 0.85] m;
- wall, top, bottom and divider thickness ``t`` in [0.015, 0.020] m, back panel
  thickness in [0.004, 0.008] m;
- plinth (bottom panel raised on a recessed kick board): none with probability 0.5,
  else a height in [0.03, 0.08] m;
- four glides (furniture feet: :data:`GLIDE_RADIUS` balls under the corners, inset
  :data:`GLIDE_INSET`, centred on the bottom plane), on which the carcass stands
  :data:`GLIDE_RADIUS` high: it touches its table at four points (the boards' edges
  would make a dozen contacts). The object frame's origin stays on the bottom plane.

Grid: cell widths in [0.20, 0.60] m and cell heights in [0.12, 0.45] m; the number of
columns (1..3) and rows (1..4) is drawn uniformly among the counts that fit those
bounds, then the widths/heights are split with Dirichlet(4, ..., 4) proportions, shrunk
toward equal sizes just enough to respect the bounds.

Part kinds (default, all allowed): drawer 0.35, door 0.35, shelf 0.15, panel 0.15
(renormalised over the allowed ``kinds``). If movable kinds are allowed but none was
drawn, one random cell is redrawn among the movable kinds.

Fronts (drawer fronts, doors, panels) are inset in the cell opening, flush with the
front plane, with a gap in [0.002, 0.004] m all round, thickness in [0.015, 0.022] m.

Drawer: front panel plus an open box (bottom, two sides, back) of board thickness in
[0.008, 0.012] m, 6 mm side clearance, 5 mm above the cell floor; box height = [0.60,
0.85] × the front height, box depth = [0.80, 0.95] × the free cell depth. Joint:
prismatic along ``+x`` (the outward normal), origin on the front plane at the cell
centre, limits ``[0, u]`` with ``u`` = [0.70, 0.90] × the box depth [m]; damping in
[2, 10] N s/m, Coulomb friction in [0.5, 3.0] N.

Door: one panel; hinge side left 0.35, right 0.35, top 0.15, bottom 0.15. Joint:
revolute about the hinge edge on the front plane (top hinges: on the panel's back face,
so a hanging flap rests shut rather than sagging open), axis ``e × n`` (``e`` the unit vector
from the hinge to the free edge, ``n = +x``) so that a positive angle opens outward;
limits ``[0, u]`` with ``u`` in [1.57, 2.10] rad (side hinges) or [1.20, 1.57] rad (top
and bottom hinges); damping in [0.05, 0.50] N m s/rad, friction in [0.05, 0.30] N m.
Top- and bottom-hinged flaps get a friction stay instead (a lift-up or drop-down flap
fitting): friction = [1.3, 2.0] × the flap's gravity torque when horizontal, so a flap
stays where it is put, shut or open (without one, a lifted top flap falls shut as soon
as it is let go, and a drop-down door falls open).

Panel: a fixed front board. Shelf: an open cell whose link is an 8 mm shelf board
lying on the cell floor (the surface an object is placed on).

Handles (one style per cabinet, among the allowed ``handles``; bar 0.5, knob 0.3,
none 0.2), on drawers and doors only:

- bar: a cylinder of radius [0.005, 0.008] m and length [0.08, 0.20] m (at most 0.6 ×
  the front extent), its axis [0.025, 0.040] m in front of the front face, on two posts;
- knob: a cylinder along ``x`` of radius [0.010, 0.018] m, length [0.020, 0.035] m;
- drawers: centred on the front, bar horizontal; doors: on the free edge's side,
  [0.03, 0.06] m in from it, centred along it, bar parallel to the hinge axis.

``handle_pos`` is the grasp point with the part closed: the bar's centre, the knob's
axis 1 cm behind its tip, or (no handle) the point on the front face where the
handle would be.

Furniture style (``style="furniture"``)
--------------------------------------
The plain cabinets above are what the tasks use; real storage furniture
(PartNet-Mobility's StorageFurniture, e.g. SAPIEN's public objects 40147 and 41083: wood
with grain, panelled doors with moulded drawer fronts above them, a plinth, bar pulls
with finials) looks different, and perception trained on plain cabinets alone typed
under half of those objects' parts right. The furniture style draws the same carcass,
grid, parts, joints and dynamics (the same ranges and draws) and then, from its own
stream ``np.random.default_rng([seed, 1])`` (:func:`draw_look`):

- finishes: stained woods (oak to espresso) with a grain texture, or paints; fronts in
  the body's finish or another (two-tone, 0.35); a countertop (0.5) 18-40 mm thick
  overhanging the front by 5-30 mm and the sides by up to 20 mm, in the body's colour,
  stone or another wood; a plinth (0.7) 4-12 cm high, its kick board the body's colour
  or black;
- fronts (:data:`FRONT_DESIGNS`): slab, shaker (rails 2-8 cm, 12-22% of the front's
  smaller side, around a panel 4-9 mm behind them), raised field (a panelled door), or
  an applied moulding on a slab; drawer fronts share the doors' design half the time;
  fronts smaller than 10 cm stay slabs;
- hardware (:data:`HARDWARE`): steel, brass, bronze, black or chrome; door bars up to
  40 cm (0.4); square bars (0.3); round finials (0.3); mushroom knobs (0.5); a dark
  finger-grip slot on handle-less fronts (0.5);
- doors hinged at the side (0.9; flaps 0.1, against 0.3 in the plain style);
- pull placement: drawer pulls centred or raised toward the top edge (0.5: 35-75% of
  the front's half-height above its centre; 41083's sit at 71%), raised only on fronts
  that read as furniture (framed, or a figured grain: a raised pull on a flat slab is
  the plain style's flap); side doors' pulls a
  vertical bar by the free edge, centred or raised (0.5: up to 60%; 40147's at 51%), or
  a horizontal bar centred across by the top edge (0.25: 70-90%; 41083's at 89%);
- layout (:data:`MERGES`): one column's lower rows as one tall cell (a door beside a
  stack of drawers), the top row as one wide cell across the columns (a drawer over
  doors), or both; a tall cell is never a drawer.

Mass: boards have density ``rho`` in [450, 700] kg/m^3 (pine to MDF), handles 2700
kg/m^3 (aluminium); ``rho`` is then rescaled if needed so the total mass lies in
[5, 25] kg, the range of real small storage furniture (IKEA's KULLEN 3-drawer chest,
35 x 40 x 70 cm: 10.5 kg; RAST bedside chest, 62 x 30 x 70 cm, pine: 11 kg; ALEX
drawer unit, 36 x 58 x 70 cm: 24 kg): hollow-core boards for the largest, solid wood
for the smallest.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from planners.errors import ConfigError, UnknownNameError
from strug_manip.geometry import axis_angle
from strug_manip.objects.finishes import GRAIN_COUNT

PartKind = Literal["drawer", "door", "shelf", "panel"]
HandleKind = Literal["bar", "knob", "none"]
HingeSide = Literal["left", "right", "top", "bottom"]

PART_KINDS: tuple[str, ...] = ("drawer", "door", "shelf", "panel")
HANDLE_KINDS: tuple[str, ...] = ("bar", "knob", "none")
MOVABLE_KINDS: tuple[str, ...] = ("drawer", "door")

KIND_WEIGHTS: dict[str, float] = {"drawer": 0.35, "door": 0.35, "shelf": 0.15, "panel": 0.15}
HINGE_WEIGHTS: dict[str, float] = {"left": 0.35, "right": 0.35, "top": 0.15, "bottom": 0.15}
HANDLE_WEIGHTS: dict[str, float] = {"bar": 0.5, "knob": 0.3, "none": 0.2}

# (PartNet-Mobility joint word, semantic label) per kind, as written to semantics.txt.
SEMANTICS: dict[str, tuple[str, str]] = {
    "body": ("heavy", "furniture_body"),
    "drawer": ("slider", "drawer"),
    "door": ("hinge", "door"),
    "shelf": ("static", "shelf"),
    "panel": ("static", "panel"),
}

# Documented ranges [m], [kg/m^3], [N s/m], [N], [N m s/rad], [N m], [rad].
WIDTH_RANGE = (0.35, 0.90)
DEPTH_RANGE = (0.30, 0.45)
HEIGHT_RANGE = (0.30, 0.85)
WALL_RANGE = (0.015, 0.020)
BACK_RANGE = (0.004, 0.008)
PLINTH_RANGE = (0.03, 0.08)
PLINTH_PROB = 0.5
GLIDE_RADIUS = 0.006
GLIDE_INSET = 0.01
CELL_WIDTH_RANGE = (0.20, 0.60)
CELL_HEIGHT_RANGE = (0.12, 0.45)
MAX_COLS = 3
MAX_ROWS = 4
GAP_RANGE = (0.002, 0.004)
FRONT_RANGE = (0.015, 0.022)
DRAWER_BOARD_RANGE = (0.008, 0.012)
DRAWER_SIDE_CLEARANCE = 0.006
DRAWER_FLOOR_CLEARANCE = 0.005
DRAWER_HEIGHT_FRAC = (0.60, 0.85)
DRAWER_DEPTH_FRAC = (0.80, 0.95)
DRAWER_TRAVEL_FRAC = (0.70, 0.90)
DRAWER_DAMPING = (2.0, 10.0)
DRAWER_FRICTION = (0.5, 3.0)
DOOR_SIDE_LIMIT = (1.57, 2.10)
DOOR_FLAP_LIMIT = (1.20, 1.57)
DOOR_DAMPING = (0.05, 0.50)
DOOR_FRICTION = (0.05, 0.30)
FLAP_STAY_HOLD = (1.3, 2.0)
SHELF_BOARD = 0.008
BAR_RADIUS = (0.005, 0.008)
BAR_LENGTH = (0.08, 0.20)
BAR_STANDOFF = (0.025, 0.040)
KNOB_RADIUS = (0.010, 0.018)
KNOB_LENGTH = (0.020, 0.035)
DOOR_HANDLE_INSET = (0.03, 0.06)
WOOD_DENSITY = (450.0, 700.0)
METAL_DENSITY = 2700.0
TOTAL_MASS = (5.0, 25.0)
JOINT_EFFORT = 100.0  # URDF <limit effort>: [N] or [N m], informative only
JOINT_VELOCITY = 2.0  # URDF <limit velocity>: [m/s] or [rad/s], informative only
GRAVITY = 9.81  # [m/s^2]

_WOODS: tuple[tuple[float, float, float, float], ...] = (
    (0.76, 0.60, 0.42, 1.0),  # oak
    (0.87, 0.72, 0.53, 1.0),  # birch
    (0.55, 0.35, 0.20, 1.0),  # walnut
    (0.93, 0.93, 0.90, 1.0),  # white laminate
    (0.45, 0.47, 0.50, 1.0),  # grey laminate
    (0.20, 0.20, 0.22, 1.0),  # black laminate
)
_METAL = (0.72, 0.72, 0.75, 1.0)


@dataclass(frozen=True)
class Geom:
    """A box, cylinder or sphere in a link frame.

    Attributes:
        name: unique within the link; handle geometry is named ``handle*``.
        shape: ``"box"``, ``"cylinder"`` or ``"sphere"``.
        pos: centre in the link frame, shape (3,) [m].
        size: box full extents (3,) [m], cylinder ``(radius, length)`` (2,) [m], or
            sphere ``(radius,)`` [m].
        axis: cylinder axis, ``"x"``, ``"y"`` or ``"z"`` (ignored for boxes).
        material: ``"wood"`` or ``"metal"`` (selects the density).
        rgba: colour, shape (4,).
        finish: a surface finish the colour tints (``grain_<k>``,
            :mod:`strug_manip.objects.finishes`), or ``""`` for a flat colour.
    """

    name: str
    shape: Literal["box", "cylinder", "sphere"]
    pos: tuple[float, float, float]
    size: tuple[float, ...]
    axis: Literal["x", "y", "z"] = "z"
    material: Literal["wood", "metal"] = "wood"
    rgba: tuple[float, float, float, float] = (0.8, 0.8, 0.8, 1.0)
    finish: str = ""

    def volume(self) -> float:
        """Volume [m^3]."""
        if self.shape == "box":
            return float(np.prod(self.size))
        if self.shape == "sphere":
            return 4.0 / 3.0 * math.pi * self.size[0] ** 3
        r, length = self.size
        return math.pi * r * r * length

    def inertia_about_center(self, mass: float) -> np.ndarray:
        """Inertia tensor about the geom centre in the link frame, shape (3, 3) [kg m^2]."""
        if self.shape == "box":
            a, b, c = self.size
            return mass / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
        if self.shape == "sphere":
            return 0.4 * mass * self.size[0] ** 2 * np.eye(3)
        r, length = self.size
        perp = mass * (3 * r * r + length * length) / 12.0
        diag = [perp, perp, perp]
        diag["xyz".index(self.axis)] = 0.5 * mass * r * r
        return np.diag(diag)


@dataclass(frozen=True)
class Inertial:
    """Mass properties of a link, in the link frame.

    Attributes:
        mass: [kg].
        com: centre of mass, shape (3,) [m].
        inertia: inertia tensor about the centre of mass, shape (3, 3) [kg m^2].
    """

    mass: float
    com: np.ndarray
    inertia: np.ndarray


def mass_properties(geoms: Sequence[Geom], densities: dict[str, float]) -> Inertial:
    """The geoms' combined mass, centre of mass and inertia (parallel-axis theorem),
    each geom's mass its volume times ``densities[material]`` [kg/m^3]."""
    masses = np.array([g.volume() * densities[g.material] for g in geoms])
    centers = np.array([g.pos for g in geoms], dtype=float)
    total = float(masses.sum())
    com = (masses[:, None] * centers).sum(axis=0) / total
    inertia = np.zeros((3, 3))
    for g, m, c in zip(geoms, masses, centers, strict=True):
        d = c - com
        inertia += g.inertia_about_center(float(m)) + m * (d @ d * np.eye(3) - np.outer(d, d))
    return Inertial(total, com, inertia)


def flap_stay_friction(hold: float, inertial: Inertial) -> float:
    """The friction [N m] of a flap's friction stay: ``hold`` (:data:`FLAP_STAY_HOLD`)
    times the flap's gravity torque when horizontal (its mass at its centre of mass's
    distance from the hinge, ``inertial`` in the link frame)."""
    return hold * inertial.mass * GRAVITY * abs(float(inertial.com[2]))


@dataclass(frozen=True)
class PartSpec:
    """One cell's part: its link, its joint to the carcass and where to grasp it.

    Positions and axes are in the object frame (see the module docstring) with the part
    closed (joint position 0); link frames are parallel to the object frame.

    Attributes:
        link: URDF link name (``link_1``, ...); the carcass is ``link_0``.
        joint: URDF joint name (``joint_1``, ...) joining ``link`` to ``link_0``.
        kind: ``drawer``, ``door``, ``shelf`` or ``panel``.
        semantic: the semantics.txt label (``drawer``, ``door``, ``shelf``, ``panel``).
        row, col: grid cell (row 0 at the top, col 0 at the viewer's left).
        cell_center: centre of the cell opening on the front plane, (3,) [m].
        cell_size: opening (width along y, height along z), (2,) [m].
        joint_type: ``prismatic``, ``revolute`` or ``fixed``.
        axis: unit joint axis, (3,); zeros for fixed parts.
        origin: joint origin = link frame origin, (3,) [m].
        lower, upper: joint limits [m] (prismatic) or [rad] (revolute); 0 for fixed.
        damping: [N s/m] or [N m s/rad]; friction: [N] or [N m].
        hinge: door hinge side, else ``None``.
        handle: ``bar``, ``knob`` or ``none`` (always ``none`` for shelves and panels).
        handle_pos: grasp point, (3,) [m], or ``None`` for shelves and panels.
        handle_axis: unit bar direction (3,) (for knobs: ``+x``), or ``None``.
        interior_center, interior_size: the free box where an object can be put (the
            drawer's inside, the cell behind a door, the space above a shelf board),
            centre (3,) [m] and full extents (3,) [m]; moves with the part for drawers.
        geoms: the link's geometry in the link frame.
        inertial: the link's mass properties.
    """

    link: str
    joint: str
    kind: str
    semantic: str
    row: int
    col: int
    cell_center: np.ndarray
    cell_size: np.ndarray
    joint_type: str
    axis: np.ndarray
    origin: np.ndarray
    lower: float
    upper: float
    damping: float
    friction: float
    hinge: str | None
    handle: str
    handle_pos: np.ndarray | None
    handle_axis: np.ndarray | None
    interior_center: np.ndarray | None
    interior_size: np.ndarray | None
    geoms: tuple[Geom, ...]
    inertial: Inertial

    @property
    def movable(self) -> bool:
        """True for drawers and doors."""
        return self.joint_type != "fixed"

    def point_at(self, p: np.ndarray, q: float) -> np.ndarray:
        """Where a point of the part (object frame, part closed) is at joint position ``q``.

        Args:
            p: point, shape (3,) [m].
            q: joint position [m] or [rad].

        Returns:
            The moved point, shape (3,) [m], object frame.
        """
        p = np.asarray(p, dtype=float)
        if self.joint_type == "prismatic":
            return p + q * self.axis
        if self.joint_type == "revolute":
            return self.origin + axis_angle(self.axis, q) @ (p - self.origin)
        return p.copy()

    def handle_at(self, q: float, T_world_object: np.ndarray | None = None) -> np.ndarray | None:
        """Grasp point at joint position ``q``, in the world frame if ``T_world_object``.

        Args:
            q: joint position [m] or [rad].
            T_world_object: pose of the object frame, shape (4, 4); identity if None.

        Returns:
            Shape (3,) [m], or ``None`` for parts without a grasp point.
        """
        if self.handle_pos is None:
            return None
        p = self.point_at(self.handle_pos, q)
        if T_world_object is None:
            return p
        return T_world_object[:3, :3] @ p + T_world_object[:3, 3]


@dataclass(frozen=True)
class CabinetSpec:
    """A generated cabinet: carcass dimensions, grid and parts (object frame, [m]).

    Attributes:
        seed: generator seed.
        kinds: the part kinds that were allowed.
        width, depth, height: outer dimensions along y, x, z [m].
        wall: carcass board thickness [m]; back: back panel thickness [m].
        plinth: height of the raised bottom (0 if none) [m].
        rows, cols: grid size.
        row_heights: cell heights, top row first, shape (rows,) [m].
        col_widths: cell widths, viewer's left first, shape (cols,) [m].
        body_geoms: the carcass geometry (``link_0``, frame = object frame).
        body_inertial: the carcass mass properties.
        parts: one per cell, row-major from the top-left.
        colors: ``{"body": rgba, "front": rgba, "handle": rgba}``.
        carcass: the carcass link (the generator's ``link_0``; a loaded object's
            ``furniture_body`` link, :func:`strug_manip.objects.describe.describe_object`).
        carcass_joint: the fixed joint that holds the carcass on the root ``base``.
        label: a loaded object's name (its folder); ``""`` for generated cabinets.
    """

    seed: int
    kinds: tuple[str, ...]
    width: float
    depth: float
    height: float
    wall: float
    back: float
    plinth: float
    rows: int
    cols: int
    row_heights: np.ndarray
    col_widths: np.ndarray
    body_geoms: tuple[Geom, ...]
    body_inertial: Inertial
    parts: tuple[PartSpec, ...]
    colors: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)
    carcass: str = "link_0"
    carcass_joint: str = "joint_0"
    label: str = ""

    @property
    def name(self) -> str:
        """A file-system friendly name, e.g. ``cabinet_0042`` (a loaded object: its
        label)."""
        return self.label or f"cabinet_{self.seed:04d}"

    @property
    def mass(self) -> float:
        """Total mass [kg]."""
        return self.body_inertial.mass + sum(p.inertial.mass for p in self.parts)

    @property
    def movable_parts(self) -> tuple[PartSpec, ...]:
        """Drawers and doors."""
        return tuple(p for p in self.parts if p.movable)

    def part(self, link: str) -> PartSpec:
        """The part whose link is named ``link``."""
        for p in self.parts:
            if p.link == link:
                return p
        raise UnknownNameError("part link", link, [p.link for p in self.parts])


def _uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    return float(rng.uniform(bounds[0], bounds[1]))


def _choice(rng: np.random.Generator, weights: dict[str, float], allowed: Sequence[str]) -> str:
    names = [k for k in weights if k in allowed]
    p = np.array([weights[k] for k in names])
    return names[int(rng.choice(len(names), p=p / p.sum()))]


def _split(
    rng: np.random.Generator, total: float, n: int, bounds: tuple[float, float]
) -> np.ndarray:
    """Split ``total`` into ``n`` sizes within ``bounds`` (Dirichlet(4), shrunk to fit)."""
    lo, hi = bounds
    mean = total / n
    raw = total * rng.dirichlet(np.full(n, 4.0))
    dev = raw - mean
    lam = 1.0
    for d in dev:
        if d > 0 and mean + d > hi:
            lam = min(lam, (hi - mean) / d)
        elif d < 0 and mean + d < lo:
            lam = min(lam, (mean - lo) / -d)
    return mean + max(lam, 0.0) * dev


def _count(
    rng: np.random.Generator, span: float, t: float, bounds: tuple[float, float], cap: int
) -> int:
    """Number of cells (separated by boards ``t``) whose size can lie within ``bounds``."""
    lo, hi = bounds
    n_min = max(1, math.ceil((span + t) / (hi + t) - 1e-9))
    n_max = max(n_min, min(cap, math.floor((span + t) / (lo + t) + 1e-9)))
    return int(rng.integers(n_min, n_max + 1))


def box(name: str, lo: Sequence[float], hi: Sequence[float], rgba, material="wood") -> Geom:
    """An axis-aligned box geom from its lower and upper corners (3,) [m]."""
    lo_a, hi_a = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    center = tuple(float(v) for v in 0.5 * (lo_a + hi_a))
    size = tuple(float(v) for v in hi_a - lo_a)
    return Geom(name, "box", center, size, material=material, rgba=rgba)


#: How far a knob's grasp point lies behind its tip [m] (the fingertips' half width).
KNOB_GRASP_INSET = 0.01


def bar_handle(
    grasp: np.ndarray, along: str, radius: float, length: float, standoff: float, rgba
) -> list[Geom]:
    """A bar handle whose grasp point (the bar's centre, (3,) [m]) is ``grasp``, the
    bar along ``along`` ("x", "y" or "z") ``standoff`` in front of the face (+x), held
    by two posts 1 cm in from its ends."""
    g = np.asarray(grasp, dtype=float)
    bar = tuple(float(v) for v in g)
    geoms = [Geom("handle_bar", "cylinder", bar, (radius, length), along, "metal", rgba)]
    k = "xyz".index(along)
    for i, sign in enumerate((-1.0, 1.0)):
        p = g - np.array([0.5 * standoff, 0.0, 0.0])
        p[k] += sign * (0.5 * length - 0.01)
        post = (0.8 * radius, standoff)
        at = tuple(float(v) for v in p)
        geoms.append(Geom(f"handle_post_{i}", "cylinder", at, post, "x", "metal", rgba))
    return geoms


def knob_handle(
    face: np.ndarray, radius: float, length: float, rgba
) -> tuple[list[Geom], np.ndarray]:
    """A knob standing ``length`` [m] out of the face (+x) at ``face`` (3,) [m], and its
    grasp point (3,): :data:`KNOB_GRASP_INSET` behind the tip, at most half way in."""
    x0, y, z = (float(v) for v in face)
    knob = Geom("handle_knob", "cylinder", (x0 + 0.5 * length, y, z), (radius, length), "x",
                "metal", rgba)  # fmt: skip
    return [knob], np.array([x0 + max(length - KNOB_GRASP_INSET, 0.5 * length), y, z])


def _handle_geoms(
    kind: str,
    center: np.ndarray,
    bar_dir: str,
    params: dict[str, float],
    max_len: float,
    rgba: tuple[float, float, float, float],
) -> tuple[list[Geom], np.ndarray]:
    """Handle geometry on the front face through ``center`` (link frame, the face at
    ``x = center[0]``), and its grasp point, (3,) [m]."""
    x0, y, z = float(center[0]), float(center[1]), float(center[2])
    if kind == "bar":
        s = params["bar_standoff"]
        grasp = np.array([x0 + s, y, z])
        length = min(params["bar_length"], max_len)
        return bar_handle(grasp, bar_dir, params["bar_radius"], length, s, rgba), grasp
    if kind == "knob":
        return knob_handle(center, params["knob_radius"], params["knob_length"], rgba)
    return [], np.array([x0, y, z])


# --- the furniture style ------------------------------------------------------------
#: Cabinet styles: ``plain`` (flat boards in one grid: the tasks' cabinets) and
#: ``furniture`` (what real storage furniture looks like, for perception to learn from).
STYLES: tuple[str, ...] = ("plain", "furniture")
#: Furniture colours (tinting a grain finish): stained woods, paints, stone tops and
#: hardware, read off the look of PartNet-Mobility's StorageFurniture (no mesh copied).
FURNITURE_WOODS: tuple[tuple[float, float, float, float], ...] = (
    (0.72, 0.53, 0.33, 1.0),  # oak
    (0.55, 0.28, 0.15, 1.0),  # cherry
    (0.42, 0.19, 0.11, 1.0),  # mahogany
    (0.38, 0.25, 0.16, 1.0),  # walnut
    (0.22, 0.15, 0.11, 1.0),  # espresso
    (0.80, 0.56, 0.30, 1.0),  # honey pine
    (0.88, 0.74, 0.55, 1.0),  # maple
)
FURNITURE_PAINTS: tuple[tuple[float, float, float, float], ...] = (
    (0.93, 0.92, 0.88, 1.0),  # white
    (0.90, 0.85, 0.72, 1.0),  # cream
    (0.58, 0.65, 0.54, 1.0),  # sage
    (0.20, 0.26, 0.40, 1.0),  # navy
    (0.55, 0.56, 0.57, 1.0),  # grey
    (0.13, 0.13, 0.14, 1.0),  # black
)
STONES: tuple[tuple[float, float, float, float], ...] = (
    (0.90, 0.90, 0.88, 1.0),  # marble
    (0.42, 0.42, 0.43, 1.0),  # granite
    (0.12, 0.12, 0.13, 1.0),  # black stone
)
HARDWARE: tuple[tuple[float, float, float, float], ...] = (
    (0.72, 0.72, 0.75, 1.0),  # brushed steel
    (0.72, 0.58, 0.30, 1.0),  # brass
    (0.40, 0.29, 0.19, 1.0),  # bronze
    (0.10, 0.10, 0.10, 1.0),  # black
    (0.86, 0.86, 0.88, 1.0),  # chrome
)
#: Front designs: a slab, a shaker frame around a recessed panel, a raised field in the
#: frame (a panelled door), an applied moulding on a slab.
FRONT_DESIGNS: dict[str, float] = {"slab": 0.3, "shaker": 0.3, "raised": 0.3, "moulded": 0.1}
#: Layout merges: a column's lower rows one tall cell, the top row one wide cell, both.
MERGES: dict[str, float] = {"none": 0.4, "tall": 0.3, "wide": 0.15, "both": 0.15}
FURNITURE_PLINTH = (0.04, 0.12)  # [m], real kitchen bases stand on 10 cm plinths
FURNITURE_PLINTH_PROB = 0.7
COUNTERTOP_PROB = 0.5
COUNTERTOP_THICKNESS = (0.018, 0.04)  # [m]
COUNTERTOP_OVERHANG = ((0.005, 0.03), (0.0, 0.02))  # front, sides [m]
FRAME_FRAC = (0.12, 0.22)  # rail width / the front's smaller extent
FRAME_WIDTH = (0.02, 0.08)  # [m], clamp of the rail width
RECESS = (0.004, 0.009)  # [m], how far a panel sits behind its frame
MIN_FRAMED = 0.10  # [m], a smaller front stays a slab
LONG_BAR = (0.15, 0.40)  # [m], door pulls of real furniture reach 40 cm
LONG_BAR_PROB = 0.4
#: A short top row (drawers over doors, as kitchen bases and 41083/40147 have) [m].
DRAWER_ROW = (0.12, 0.20)
DRAWER_ROW_PROB = 0.5
#: Door hinge sides in the furniture style (one draw, as the plain style's): real
#: storage furniture hinges its doors at the side (both SAPIEN objects: three side
#: doors, no flap), and a flap's pull by its edge looks like a raised drawer pull.
FURNITURE_HINGES: dict[str, float] = {"left": 0.45, "right": 0.45, "top": 0.05, "bottom": 0.05}
#: Grain images from this index on are figured woods; lower ones the faint grain of
#: paints and stone (:func:`draw_look`).
FIGURED_GRAIN = 3
#: Drawer pulls raised toward the top edge: probability, and the offset of the pull's
#: centre above the front's centre in half-heights (41083's drawers: 0.71).
DRAWER_PULL_RAISED = (0.5, (0.35, 0.75))
#: Side doors' pulls: ``edge`` (vertical by the free edge, as the plain style) or
#: ``top`` (horizontal, centred across, by the top edge: 41083's doors).
DOOR_PULLS: dict[str, float] = {"edge": 0.75, "top": 0.25}
#: Offset of a side door's pull above its centre in half-heights: an ``edge`` pull is
#: raised with probability 0.5 by up to 0.6 (40147's door: 0.51), a ``top`` one sits
#: at 0.7-0.9 (41083's: 0.89).
DOOR_PULL_RAISE, DOOR_PULL_TOP = (0.0, 0.6), (0.7, 0.9)
#: Clearance kept between a moved pull's geometry and its front's edge [m] (41083's
#: drawer pulls: 1 cm).
PULL_MARGIN = 0.01
#: Part kinds by a cell's height / width: real drawers are short and wide (SAPIEN's
#: 40147 and 41083: 0.35-0.39), real doors tall (1.2-1.3); cells in between keep the
#: plain weights.
WIDE_CELL, TALL_CELL = 0.55, 0.9
WIDE_KINDS: dict[str, float] = {"drawer": 0.7, "door": 0.1, "shelf": 0.1, "panel": 0.1}
TALL_KINDS: dict[str, float] = {"drawer": 0.1, "door": 0.6, "shelf": 0.15, "panel": 0.15}


def kind_weights(aspect: float) -> dict[str, float]:
    """The furniture style's part-kind weights for a cell of height / width ``aspect``."""
    if aspect < WIDE_CELL:
        return WIDE_KINDS
    return TALL_KINDS if aspect > TALL_CELL else KIND_WEIGHTS


@dataclass(frozen=True)
class FurnitureLook:
    """What a furniture-style cabinet looks like, drawn by :func:`draw_look`.

    Attributes:
        colors: ``body``, ``front``, ``handle``, ``kick`` and ``top`` colours (4,).
        finishes: ``body``, ``front`` and ``top`` finish names (``""``: flat colour).
        plinth: plinth height [m] (0: none).
        top: countertop thickness, front and side overhang [m], or ``None``.
        door_design, drawer_design: keys of :data:`FRONT_DESIGNS`.
        drawer_row: the height of a short top row [m] (drawers over doors), or 0.
        frame_frac: rail width as a share of a front's smaller extent.
        recess: panel depth behind the frame [m].
        bar_length: bar handle length [m] (before the 0.6 x front cap).
        square_bar: a square bar instead of a round one.
        bar_ends: round finials on the bar's ends.
        knob_cap: a mushroom knob's cap radius / the knob's radius (0: a plain cylinder).
        grip_slot: handle-less fronts get a dark finger-grip slot.
        merge: key of :data:`MERGES`; merge_at: (column, row) draws in [0, 1).
        drawer_pull_v: a drawer pull's centre above its front's centre, in half-heights.
        door_pull: key of :data:`DOOR_PULLS`, for side-hinged doors.
        door_pull_v: a side door's pull centre above the door's centre, in half-heights.
    """

    colors: dict[str, tuple[float, float, float, float]]
    finishes: dict[str, str]
    plinth: float
    top: tuple[float, float, float] | None
    door_design: str
    drawer_design: str
    frame_frac: float
    recess: float
    bar_length: float
    square_bar: bool
    bar_ends: bool
    knob_cap: float
    grip_slot: bool
    merge: str
    merge_at: tuple[float, float]
    drawer_row: float = 0.0
    drawer_pull_v: float = 0.0
    door_pull: str = "edge"
    door_pull_v: float = 0.0

    def rows(self, heights: np.ndarray) -> np.ndarray:
        """Row heights [m] with a short top row of drawers (``drawer_row`` > 0: its
        height) over the rest, which share the remainder as they did; unchanged for a
        single row or no drawer row."""
        if self.drawer_row <= 0.0 or len(heights) < 2 or heights[0] <= self.drawer_row:
            return heights
        out = np.array(heights, dtype=float)
        rest = out[1:].sum() + out[0] - self.drawer_row
        out[1:] *= rest / out[1:].sum()
        out[0] = self.drawer_row
        return out

    @property
    def top_height(self) -> float:
        """Height the countertop adds on the carcass [m]."""
        return self.top[0] if self.top is not None else 0.0

    def top_geoms(self, W: float, D: float, H: float) -> list[Geom]:
        """The countertop on the carcass (object frame), if any."""
        if self.top is None:
            return []
        th, front, side = self.top
        lo, hi = (-0.5 * D, -0.5 * W - side, H), (0.5 * D + front, 0.5 * W + side, H + th)
        top = box("countertop", lo, hi, self.colors["top"])
        return [dataclasses.replace(top, finish=self.finishes["top"])]

    def finish_body(self, geoms: Sequence[Geom]) -> list[Geom]:
        """The carcass boards in the body finish (glides, kick board and top as they are)."""
        body = self.colors["body"]
        return [
            dataclasses.replace(g, finish=self.finishes["body"])
            if g.shape == "box" and g.rgba == body and not g.finish
            else g
            for g in geoms
        ]

    def reads_as_furniture(self, fw: float, fh: float) -> bool:
        """A ``fw`` x ``fh`` [m] drawer front in this look shows what no plain-style
        front has: a frame (shaker, raised or moulded, on fronts of
        :data:`MIN_FRAMED` and more) or a figured wood grain."""
        framed = self.drawer_design != "slab" and min(fw, fh) >= MIN_FRAMED
        finish = self.finishes["front"]
        return framed or (finish.startswith("grain_") and int(finish[6:]) >= FIGURED_GRAIN)

    def place_pull(
        self, draft: dict, style: str, hp: dict[str, float], gap: float, metal: tuple
    ) -> dict:
        """``draft`` with its handle (geometry and grasp point, or a handle-less front's
        would-be handle point) moved where this look puts pulls; flaps, shelves and
        panels as they are. ``style``, ``hp``: the cabinet's handle style and params;
        ``gap``: the reveal around fronts [m]; ``metal``: the handle colour."""
        kind, hinge = draft["kind"], draft["hinge"]
        if kind not in MOVABLE_KINDS or hinge in ("top", "bottom"):
            return draft
        fw, fh = (float(x) - 2 * gap for x in draft["cell_size"])
        front = draft["cell_center"] - draft["origin"]  # front centre, link frame
        face = np.array([front[0], *(draft["handle_pos"] - draft["origin"])[1:]])
        bar_dir, v = ("y", self.drawer_pull_v) if kind == "drawer" else ("z", self.door_pull_v)
        if kind == "drawer" and not self.reads_as_furniture(fw, fh):
            # A raised pull on a flat-coloured slab is, pixel for pixel, the plain
            # style's flap pull by its edge: keep the two conventions told apart by
            # the look (the first retraining typed plain flaps drawers).
            v = 0.0
        if kind == "door" and self.door_pull == "top":
            bar_dir, face[1] = "y", front[1]
        along = fw if bar_dir == "y" else fh
        # How far the pull reaches above its centre: half a vertical bar, a bar's
        # radius, or a knob's (mushroom) cap.
        reach = hp["knob_radius"] * max(self.knob_cap, 1.0)
        if style == "bar":
            reach = 0.5 * min(hp["bar_length"], 0.6 * along) if bar_dir == "z" else 0.0
            reach += hp["bar_radius"] * (1.5 if self.bar_ends else 1.0)
        face[2] = front[2] + min(v * 0.5 * fh, max(0.5 * fh - PULL_MARGIN - reach, 0.0))
        hg, grasp = _handle_geoms(style, face, bar_dir, hp, 0.6 * along, metal)
        axis = np.array([0.0, 1.0, 0.0]) if bar_dir == "y" else np.array([0.0, 0.0, 1.0])
        geoms = [g for g in draft["geoms"] if not g.name.startswith("handle")]
        return {
            **draft,
            "geoms": tuple(geoms + hg),
            "handle_pos": draft["origin"] + grasp,
            "handle_axis": axis if style == "bar" else draft["handle_axis"],
        }

    def dress(self, draft: dict, tf: float) -> tuple[Geom, ...]:
        """A part's geometry in this look: framed fronts, finishes, restyled handles."""
        design = self.drawer_design if draft["kind"] == "drawer" else self.door_design
        out: list[Geom] = []
        for g in draft["geoms"]:
            if g.name in ("front", "panel") and draft["kind"] != "shelf":
                out += self._front(g, design, tf)
            elif g.name.startswith("handle"):
                out += self._handle(g)
            else:
                out.append(g)
        if draft["handle"] == "none" and self.grip_slot and draft["kind"] in MOVABLE_KINDS:
            out.append(self._slot(draft))
        finish = {
            self.colors["front"]: self.finishes["front"],
            self.colors["body"]: self.finishes["body"],
        }
        return tuple(
            dataclasses.replace(g, finish=finish.get(g.rgba, "")) if g.material == "wood" else g
            for g in out
        )

    def _front(self, g: Geom, design: str, tf: float) -> list[Geom]:
        """A front board ``g`` (thickness along x) built as ``design``."""
        c, (_, fw, fh) = np.asarray(g.pos), g.size
        small = min(fw, fh)
        if design == "slab" or small < MIN_FRAMED:
            return [g]
        x1 = c[0] + 0.5 * tf  # the front face
        y0, y1, z0, z1 = c[1] - 0.5 * fw, c[1] + 0.5 * fw, c[2] - 0.5 * fh, c[2] + 0.5 * fh
        if design == "moulded":
            m, w = min(max(0.12 * small, 0.02), 0.06), 0.012
            strips = [
                ((y0 + m, z1 - m - w), (y1 - m, z1 - m)), ((y0 + m, z0 + m), (y1 - m, z0 + m + w)),
                ((y0 + m, z0 + m + w), (y0 + m + w, z1 - m - w)),
                ((y1 - m - w, z0 + m + w), (y1 - m, z1 - m - w)),
            ]  # fmt: skip
            return [g] + [
                box(f"{g.name}_moulding_{k}", (x1, a[0], a[1]), (x1 + 0.005, b[0], b[1]), g.rgba)
                for k, (a, b) in enumerate(strips)
            ]
        r = min(max(self.frame_frac * small, FRAME_WIDTH[0]), FRAME_WIDTH[1], 0.3 * small)
        x0, rec = x1 - tf, min(self.recess, tf - 0.006)
        rails = [
            ((y0, z1 - r), (y1, z1)), ((y0, z0), (y1, z0 + r)),
            ((y0, z0 + r), (y0 + r, z1 - r)), ((y1 - r, z0 + r), (y1, z1 - r)),
        ]  # fmt: skip
        out = [
            box(f"{g.name}_rail_{k}", (x0, a[0], a[1]), (x1, b[0], b[1]), g.rgba)
            for k, (a, b) in enumerate(rails)
        ]
        out.append(
            box(f"{g.name}_centre", (x0, y0 + r, z0 + r), (x1 - rec, y1 - r, z1 - r), g.rgba)
        )
        if design == "raised":
            b = min(0.25 * r + 0.01, 0.03)  # the bevel's width around the field
            lo, hi = (x0, y0 + r + b, z0 + r + b), (x1 - 0.3 * rec, y1 - r - b, z1 - r - b)
            out.append(box(f"{g.name}_field", lo, hi, g.rgba))
        return out

    def _handle(self, g: Geom) -> list[Geom]:
        """A handle geom in this look: square bars, finials, mushroom knobs."""
        if g.name == "handle_bar":
            r, length = g.size
            out = [g]
            if self.square_bar:
                side = [1.8 * r] * 3
                side["xyz".index(g.axis)] = length
                out = [Geom("handle_bar", "box", g.pos, tuple(side), "x", "metal", g.rgba)]
            if self.bar_ends:
                for k, sign in enumerate((-1.0, 1.0)):
                    p = np.asarray(g.pos, dtype=float)
                    p["xyz".index(g.axis)] += sign * 0.5 * length
                    at = tuple(float(v) for v in p)
                    out.append(
                        Geom(f"handle_end_{k}", "sphere", at, (1.5 * r,), "z", "metal", g.rgba)
                    )
            return out
        if g.name == "handle_knob" and self.knob_cap > 0:
            r, length = g.size
            x = g.pos[0] - 0.5 * length  # the face
            yz = tuple(g.pos[1:])
            stem_size, cap_size = (0.5 * r, 0.6 * length), (self.knob_cap * r, 0.4 * length)
            stem = Geom("handle_knob", "cylinder", (x + 0.3 * length, *yz), stem_size, "x",
                        "metal", g.rgba)  # fmt: skip
            cap = Geom("handle_cap", "cylinder", (x + 0.8 * length, *yz), cap_size, "x",
                       "metal", g.rgba)  # fmt: skip
            return [stem, cap]
        return [g]

    def _slot(self, draft: dict) -> Geom:
        """A dark finger-grip slot (a flat strip on the face) where a pull would be."""
        (fw, fh), hinge = draft["cell_size"], draft["hinge"]
        p = draft["handle_pos"] - draft["origin"]  # the would-be handle point, link frame
        if hinge in ("left", "right"):
            size = (0.002, 0.012, min(0.12, 0.5 * fh))
        else:
            size = (0.002, min(0.15, 0.5 * fw), 0.012)
        centre = (float(p[0]) + 0.001, float(p[1]), float(p[2]))
        return Geom("grip_slot", "box", centre, size, "z", "wood", (0.05, 0.05, 0.05, 1.0))


def draw_look(rng: np.random.Generator) -> FurnitureLook:
    """Draw a :class:`FurnitureLook` (its own stream: the plain draws stay as they are)."""
    painted = rng.random() < 0.35
    body = FURNITURE_PAINTS[int(rng.integers(len(FURNITURE_PAINTS)))] if painted else (
        FURNITURE_WOODS[int(rng.integers(len(FURNITURE_WOODS)))])  # fmt: skip
    two_tone = rng.random() < 0.35
    pool = FURNITURE_WOODS if rng.random() < 0.5 else FURNITURE_PAINTS
    front = pool[int(rng.integers(len(pool)))] if two_tone else body
    top_kind = rng.random()
    top_rgba = body if top_kind < 0.4 else (
        STONES[int(rng.integers(len(STONES)))] if top_kind < 0.8 else
        FURNITURE_WOODS[int(rng.integers(len(FURNITURE_WOODS)))])  # fmt: skip

    def finish(rgba: tuple) -> str:
        if rgba in FURNITURE_WOODS:  # figured grain
            return f"grain_{int(rng.integers(FIGURED_GRAIN, GRAIN_COUNT))}"
        return "" if rng.random() < 0.5 else f"grain_{int(rng.integers(0, 2))}"  # paint, stone

    finishes = {"body": finish(body), "front": finish(front), "top": finish(top_rgba)}
    kick = body if rng.random() < 0.6 else (0.1, 0.1, 0.1, 1.0)
    colors = {"body": body, "front": front, "kick": kick, "top": top_rgba,
              "handle": HARDWARE[int(rng.integers(len(HARDWARE)))]}  # fmt: skip
    plinth = _uniform(rng, FURNITURE_PLINTH) if rng.random() < FURNITURE_PLINTH_PROB else 0.0
    top = None
    if rng.random() < COUNTERTOP_PROB:
        front_o, side_o = COUNTERTOP_OVERHANG
        top = (_uniform(rng, COUNTERTOP_THICKNESS), _uniform(rng, front_o), _uniform(rng, side_o))
    door_design = _choice(rng, FRONT_DESIGNS, tuple(FRONT_DESIGNS))
    drawer_design = (
        door_design
        if rng.random() < 0.5
        else _choice(rng, FRONT_DESIGNS, ("slab", "shaker", "moulded"))
    )
    long_bar = rng.random() < LONG_BAR_PROB
    bar_length = _uniform(rng, LONG_BAR if long_bar else BAR_LENGTH)
    cap = float(rng.uniform(1.3, 1.8)) if rng.random() < 0.5 else 0.0  # mushroom knobs
    merge_at = (float(rng.random()), float(rng.random()))
    drawer_row = _uniform(rng, DRAWER_ROW) if rng.random() < DRAWER_ROW_PROB else 0.0
    raised, drawer_v = DRAWER_PULL_RAISED
    drawer_pull_v = _uniform(rng, drawer_v) if rng.random() < raised else 0.0
    door_pull = _choice(rng, DOOR_PULLS, tuple(DOOR_PULLS))
    door_pull_v = _uniform(rng, DOOR_PULL_TOP if door_pull == "top" else DOOR_PULL_RAISE)
    if door_pull == "edge" and rng.random() < 0.5:
        door_pull_v = 0.0  # centred on the free edge, as the plain style
    return FurnitureLook(
        colors=colors, finishes=finishes, plinth=plinth, top=top,
        door_design=door_design, drawer_design=drawer_design,
        frame_frac=_uniform(rng, FRAME_FRAC), recess=_uniform(rng, RECESS),
        bar_length=bar_length, square_bar=bool(rng.random() < 0.3),
        bar_ends=bool(rng.random() < 0.3), knob_cap=cap, grip_slot=bool(rng.random() < 0.5),
        merge=_choice(rng, MERGES, tuple(MERGES)), merge_at=merge_at, drawer_row=drawer_row,
        drawer_pull_v=drawer_pull_v, door_pull=door_pull, door_pull_v=door_pull_v,
    )  # fmt: skip


def merge_cells(look: FurnitureLook, rows: int, cols: int) -> list[tuple[int, int, int, int]]:
    """The cells of a ``rows`` x ``cols`` grid after the look's merges, row-major by
    their top-left cell: ``(row, col, row span, col span)``. ``tall``: one column's
    rows from a drawn row down to the bottom are one cell; ``wide``: the top row is one
    cell across every column; ``both``: the two (tall below the wide top)."""
    owner = [[(i, j) for j in range(cols)] for i in range(rows)]
    spans: dict[tuple[int, int], tuple[int, int]] = {}
    wide = look.merge in ("wide", "both") and cols >= 2 and rows >= 2
    if wide:
        spans[(0, 0)] = (1, cols)
        for j in range(cols):
            owner[0][j] = (0, 0)
    first = 1 if wide else 0
    if look.merge in ("tall", "both") and rows - first >= 2:
        j = min(int(look.merge_at[0] * cols), cols - 1)
        r0 = first + min(int(look.merge_at[1] * (rows - first - 1)), rows - first - 2)
        spans[(r0, j)] = (rows - r0, 1)
        for i in range(r0, rows):
            owner[i][j] = (r0, j)
    cells = sorted({owner[i][j] for i in range(rows) for j in range(cols)})
    return [(i, j, *spans.get((i, j), (1, 1))) for i, j in cells]


def _dividers(
    cells: Sequence[tuple[int, int, int, int]],
    z_edges: Sequence[tuple[float, float]],
    y_edges: Sequence[tuple[float, float]],
    xs: tuple[float, float],
    t: float,
    rgba: tuple[float, float, float, float],
) -> list[Geom]:
    """The divider boards between different cells (thickness ``t``, from the back panel's
    inner face to the front plane ``xs``): horizontal boards in runs of columns, upright
    ones through the horizontal boards' thickness so the carcass stays closed."""
    rows, cols = len(z_edges), len(y_edges)
    owner = [[-1] * cols for _ in range(rows)]
    for k, (i, j, rs, cs) in enumerate(cells):
        for a in range(i, i + rs):
            for b in range(j, j + cs):
                owner[a][b] = k
    xb, xf = xs
    out: list[Geom] = []
    for i in range(rows - 1):
        z1 = z_edges[i][0]
        run = [j for j in range(cols) if owner[i][j] != owner[i + 1][j]]
        for k, (a, b) in enumerate(_runs(run)):
            lo, hi = (xb, y_edges[a][0], z1 - t), (xf, y_edges[b][1], z1)
            out.append(box(f"shelf_divider_{i}_{k}", lo, hi, rgba))
    for i, (z0, z1) in enumerate(z_edges):
        below = t if i < rows - 1 else 0.0
        for j in range(cols - 1):
            if owner[i][j] != owner[i][j + 1]:
                y1 = y_edges[j][1]
                out.append(box(f"divider_{i}_{j}", (xb, y1, z0 - below), (xf, y1 + t, z1), rgba))
    return out


def _runs(js: Sequence[int]) -> list[tuple[int, int]]:
    """Consecutive runs of sorted integers, as (first, last)."""
    out: list[tuple[int, int]] = []
    for j in js:
        if out and out[-1][1] == j - 1:
            out[-1] = (out[-1][0], j)
        else:
            out.append((j, j))
    return out


def generate_cabinet(
    seed: int,
    *,
    kinds: Sequence[str] = PART_KINDS,
    handles: Sequence[str] = HANDLE_KINDS,
    style: str = "plain",
) -> CabinetSpec:
    """Draw one storage cabinet from ``np.random.default_rng(seed)``.

    Args:
        seed: integer >= 0; the same seed (and options) gives the same cabinet.
        kinds: part kinds allowed in the cells, a subset of ``("drawer", "door",
            "shelf", "panel")``: ``("drawer",)`` for OpenDrawer, ``("door",)`` for
            OpenDoor, ``("shelf",)`` for Shelf.
        handles: handle styles allowed, a subset of ``("bar", "knob", "none")``.
        style: ``"plain"`` (the tasks' cabinets: flat boards, one grid) or
            ``"furniture"`` (the look of real storage furniture, :data:`STYLES`; what
            perception is trained on besides the plain ones).

    Returns:
        The :class:`CabinetSpec` (ranges in the module docstring).

    Raises:
        ConfigError: a negative or non-integer seed, or an empty ``kinds``/``handles``.
        UnknownNameError: an unknown part kind or handle style.
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ConfigError(f"seed must be an integer >= 0, got {seed!r}")
    kinds = _check_names("part kind", kinds, PART_KINDS)
    handles = _check_names("handle style", handles, HANDLE_KINDS)
    if style not in STYLES:
        raise UnknownNameError("cabinet style", style, STYLES)
    rng = np.random.default_rng(int(seed))
    # The furniture look draws from its own stream: the plain draws stay as they were.
    look = draw_look(np.random.default_rng([int(seed), 1])) if style == "furniture" else None

    # --- carcass --------------------------------------------------------------------
    W, D, H = _uniform(rng, WIDTH_RANGE), _uniform(rng, DEPTH_RANGE), _uniform(rng, HEIGHT_RANGE)
    t, tb = _uniform(rng, WALL_RANGE), _uniform(rng, BACK_RANGE)
    plinth = _uniform(rng, PLINTH_RANGE) if rng.random() < PLINTH_PROB else 0.0
    if look is not None:
        plinth = look.plinth
    W_in, H_in = W - 2 * t, H - plinth - 2 * t
    cols = _count(rng, W_in, t, CELL_WIDTH_RANGE, MAX_COLS)
    rows = _count(rng, H_in, t, CELL_HEIGHT_RANGE, MAX_ROWS)
    col_widths = _split(rng, W_in - (cols - 1) * t, cols, CELL_WIDTH_RANGE)
    row_heights = _split(rng, H_in - (rows - 1) * t, rows, CELL_HEIGHT_RANGE)
    if look is not None:
        row_heights = look.rows(row_heights)
    palette = rng.permutation(len(_WOODS))
    body_rgba = _WOODS[int(palette[0])]
    front_rgba = body_rgba if rng.random() < 0.5 else _WOODS[int(palette[1])]
    colors = {"body": body_rgba, "front": front_rgba, "handle": _METAL}
    if look is not None:
        colors, body_rgba = dict(look.colors), look.colors["body"]

    xf, xb = 0.5 * D, -0.5 * D + tb  # front plane, inner face of the back panel
    y_lo, y_hi = -0.5 * W + t, 0.5 * W - t
    z_bot, z_top = plinth + t, H - t  # inner floor and ceiling of the carcass
    body: list[Geom] = [
        box("side_left", (-0.5 * D, -0.5 * W, 0.0), (xf, y_lo, H), body_rgba),
        box("side_right", (-0.5 * D, y_hi, 0.0), (xf, 0.5 * W, H), body_rgba),
        box("top", (xb, y_lo, z_top), (xf, y_hi, H), body_rgba),
        box("bottom", (xb, y_lo, plinth), (xf, y_hi, z_bot), body_rgba),
        box("back", (-0.5 * D, y_lo, plinth), (xb, y_hi, z_top), body_rgba),
    ]
    if plinth > 0:
        kick = body_rgba if look is None else look.colors["kick"]
        body.append(box("kick", (xf - 0.03 - t, y_lo, 0.0), (xf - 0.03, y_hi, plinth), kick))
    for i, (sx, sy) in enumerate(((1, 1), (1, -1), (-1, 1), (-1, -1))):
        center = (sx * (0.5 * D - GLIDE_INSET), sy * (0.5 * W - GLIDE_INSET), 0.0)
        body.append(Geom(f"glide_{i}", "sphere", center, (GLIDE_RADIUS,), rgba=(0.2, 0.2, 0.2, 1)))
    # Cell boundaries: rows from the top, columns from the viewer's left (-y).
    z_edges, z = [], z_top
    for h in row_heights:
        z_edges.append((z - h, z))
        z -= h + t
    y_edges, y = [], y_lo
    for w in col_widths:
        y_edges.append((y, y + w))
        y += w + t
    cells = [(i, j, 1, 1) for i in range(rows) for j in range(cols)]
    if look is None:
        for i in range(rows - 1):
            z1 = z_edges[i][0]
            body.append(box(f"shelf_divider_{i}", (xb, y_lo, z1 - t), (xf, y_hi, z1), body_rgba))
        for i, (z0, z1) in enumerate(z_edges):
            for j in range(cols - 1):
                y1 = y_edges[j][1]
                body.append(box(f"divider_{i}_{j}", (xb, y1, z0), (xf, y1 + t, z1), body_rgba))
    else:
        cells = merge_cells(look, rows, cols)
        body += _dividers(cells, z_edges, y_edges, (xb, xf), t, body_rgba)
        body = look.finish_body(body) + look.top_geoms(W, D, H)

    # --- cells ----------------------------------------------------------------------
    n_cells = len(cells)
    cell_kinds = [_choice(rng, KIND_WEIGHTS, kinds) for _ in range(n_cells)]
    if look is not None:  # real furniture: drawers short and wide, doors tall
        for idx, (i, j, rs, cs) in enumerate(cells):
            h = z_edges[i][1] - z_edges[i + rs - 1][0]
            w = y_edges[j + cs - 1][1] - y_edges[j][0]
            cell_kinds[idx] = _choice(rng, kind_weights(h / w), kinds)
    movable_allowed = [k for k in kinds if k in MOVABLE_KINDS]
    if movable_allowed and not any(k in MOVABLE_KINDS for k in cell_kinds):
        cell_kinds[int(rng.integers(n_cells))] = _choice(rng, KIND_WEIGHTS, movable_allowed)
    others = [k for k in kinds if k != "drawer"]
    for idx, (_, _, rs, _) in enumerate(cells):
        # No drawer is taller than a row: a door, else another kind if a part still moves.
        if rs == 1 or cell_kinds[idx] != "drawer" or not others:
            continue
        if "door" in others:
            cell_kinds[idx] = "door"
        elif sum(k in MOVABLE_KINDS for k in cell_kinds) > 1:
            cell_kinds[idx] = _choice(rng, KIND_WEIGHTS, others)
    handle_style = _choice(rng, HANDLE_WEIGHTS, handles)
    gap, tf = _uniform(rng, GAP_RANGE), _uniform(rng, FRONT_RANGE)
    handle_params = {
        "bar_radius": _uniform(rng, BAR_RADIUS),
        "bar_length": _uniform(rng, BAR_LENGTH),
        "bar_standoff": _uniform(rng, BAR_STANDOFF),
        "knob_radius": _uniform(rng, KNOB_RADIUS),
        "knob_length": _uniform(rng, KNOB_LENGTH),
    }
    if look is not None:
        handle_params["bar_length"] = look.bar_length
    rho = _uniform(rng, WOOD_DENSITY)

    drafts: list[dict] = []
    for idx, (i, j, rs, cs) in enumerate(cells):
        (z0, z1), (y0, y1) = (
            (z_edges[i + rs - 1][0], z_edges[i][1]),
            (y_edges[j][0], y_edges[j + cs - 1][1]),
        )
        draft = _draft_part(
            rng, cell_kinds[idx], (y0, y1), (z0, z1), xf, xb, gap, tf, handle_style,
            handle_params, colors, HINGE_WEIGHTS if look is None else FURNITURE_HINGES,
        )  # fmt: skip
        if look is not None:
            draft = look.place_pull(draft, handle_style, handle_params, gap, colors["handle"])
            draft["geoms"] = look.dress(draft, tf)
        draft.update(row=i, col=j, link=f"link_{idx + 1}", joint=f"joint_{idx + 1}")
        drafts.append(draft)

    # --- masses: wood density rescaled so the total lies in TOTAL_MASS ----------------
    all_geoms = body + [g for d in drafts for g in d["geoms"]]
    wood_v = sum(g.volume() for g in all_geoms if g.material == "wood")
    metal_m = sum(g.volume() for g in all_geoms if g.material == "metal") * METAL_DENSITY
    total = rho * wood_v + metal_m
    target = min(max(total, TOTAL_MASS[0]), TOTAL_MASS[1])
    rho = (target - metal_m) / wood_v
    densities = {"wood": rho, "metal": METAL_DENSITY}

    parts = []
    for d in drafts:
        inertial = mass_properties(d["geoms"], densities)
        if d["kind"] == "door" and d["hinge"] in ("top", "bottom"):
            # Friction stay: hold the flap against gravity, even horizontal.
            d["friction"] = flap_stay_friction(_uniform(rng, FLAP_STAY_HOLD), inertial)
        parts.append(_finish_part(d, inertial))
    return CabinetSpec(
        seed=int(seed),
        kinds=kinds,
        width=W,
        depth=D,
        height=H + (look.top_height if look is not None else 0.0),
        wall=t,
        back=tb,
        plinth=plinth,
        rows=rows,
        cols=cols,
        row_heights=np.asarray(row_heights),
        col_widths=np.asarray(col_widths),
        body_geoms=tuple(body),
        body_inertial=mass_properties(body, densities),
        parts=tuple(parts),
        colors=colors,
    )


def _check_names(what: str, names: Sequence[str], valid: tuple[str, ...]) -> tuple[str, ...]:
    if isinstance(names, str):
        names = tuple(n for n in names.split(",") if n)
    names = tuple(dict.fromkeys(str(n).strip().lower() for n in names))
    if not names:
        raise ConfigError(f"at least one {what} is needed; choose from {', '.join(valid)}")
    for n in names:
        if n not in valid:
            raise UnknownNameError(what, n, valid)
    return names


def _draft_part(
    rng: np.random.Generator,
    kind: str,
    ys: tuple[float, float],
    zs: tuple[float, float],
    xf: float,
    xb: float,
    gap: float,
    tf: float,
    style: str,
    hp: dict[str, float],
    colors: dict[str, tuple[float, float, float, float]],
    hinges: dict[str, float] = HINGE_WEIGHTS,
) -> dict:
    """Geometry (link frame), joint and grasp point of one cell's part (``hinges``: a
    door's hinge-side weights)."""
    (y0, y1), (z0, z1) = ys, zs
    w, h, d = y1 - y0, z1 - z0, xf - xb
    yc, zc = 0.5 * (y0 + y1), 0.5 * (z0 + z1)
    cell_center = np.array([xf, yc, zc])
    fw, fh = w - 2 * gap, h - 2 * gap  # front panel extents
    front, metal = colors["front"], colors["handle"]
    out: dict = {
        "kind": kind,
        "cell_center": cell_center,
        "cell_size": np.array([w, h]),
        "hinge": None,
        "handle": "none",
        "handle_pos": None,
        "handle_axis": None,
        "damping": 0.0,
        "friction": 0.0,
        "lower": 0.0,
        "upper": 0.0,
        "axis": np.zeros(3),
    }
    if kind == "drawer":
        tb = _uniform(rng, DRAWER_BOARD_RANGE)
        bw = w - 2 * DRAWER_SIDE_CLEARANCE
        bh = _uniform(rng, DRAWER_HEIGHT_FRAC) * fh
        bd = _uniform(rng, DRAWER_DEPTH_FRAC) * (d - tf - 0.01)
        zb = -0.5 * h + DRAWER_FLOOR_CLEARANCE  # box bottom, link frame
        xr = -tf - bd  # box rear
        geoms = [
            box("front", (-tf, -0.5 * fw, -0.5 * fh), (0.0, 0.5 * fw, 0.5 * fh), front),
            box("bottom", (xr, -0.5 * bw, zb), (-tf, 0.5 * bw, zb + tb), front),
            box("side_left", (xr, -0.5 * bw, zb + tb), (-tf, -0.5 * bw + tb, zb + bh), front),
            box("side_right", (xr, 0.5 * bw - tb, zb + tb), (-tf, 0.5 * bw, zb + bh), front),
            box("back", (xr, -0.5 * bw + tb, zb + tb), (xr + tb, 0.5 * bw - tb, zb + bh), front),
        ]
        hg, hpos = _handle_geoms(style, np.zeros(3), "y", hp, 0.6 * fw, metal)
        inner = np.array([bd - tb, bw - 2 * tb, bh - tb])
        out.update(
            joint_type="prismatic",
            origin=cell_center,
            axis=np.array([1.0, 0.0, 0.0]),
            upper=_uniform(rng, DRAWER_TRAVEL_FRAC) * bd,
            damping=_uniform(rng, DRAWER_DAMPING),
            friction=_uniform(rng, DRAWER_FRICTION),
            handle=style,
            handle_pos=cell_center + hpos,
            handle_axis=np.array([0.0, 1.0, 0.0]) if style == "bar" else np.array([1.0, 0, 0]),
            interior_center=cell_center
            + np.array([xr + tb + 0.5 * inner[0], 0.0, zb + tb + 0.5 * inner[2]]),
            interior_size=inner,
            geoms=tuple(geoms + hg),
        )
        return out
    if kind == "door":
        hinge = _choice(rng, hinges, tuple(hinges))
        # e: unit vector from the hinge line to the free edge; origin: hinge point.
        e, origin = {
            "left": (np.array([0.0, 1.0, 0.0]), np.array([xf, y0 + gap, zc])),
            "right": (np.array([0.0, -1.0, 0.0]), np.array([xf, y1 - gap, zc])),
            "bottom": (np.array([0.0, 0.0, 1.0]), np.array([xf, yc, z0 + gap])),
            # A top hinge sits on the panel's back face, so the hanging flap rests shut.
            "top": (np.array([0.0, 0.0, -1.0]), np.array([xf - tf, yc, z1 - gap])),
        }[hinge]
        axis = np.cross(e, np.array([1.0, 0.0, 0.0]))
        c = cell_center - origin  # panel centre, link frame
        panel = box(
            "panel",
            (c[0] - tf, c[1] - 0.5 * fw, c[2] - 0.5 * fh),
            (c[0], c[1] + 0.5 * fw, c[2] + 0.5 * fh),
            front,
        )
        span = fw if hinge in ("left", "right") else fh  # hinge -> free edge
        along = fh if hinge in ("left", "right") else fw  # parallel to the hinge
        inset = min(_uniform(rng, DOOR_HANDLE_INSET), 0.25 * span)
        hcenter = c + e * (0.5 * span - inset)
        bar_dir = "z" if hinge in ("left", "right") else "y"
        hg, hpos = _handle_geoms(style, hcenter, bar_dir, hp, 0.6 * along, metal)
        side = hinge in ("left", "right")
        limit = DOOR_SIDE_LIMIT if side else DOOR_FLAP_LIMIT
        bar_axis = np.array([0.0, 0.0, 1.0]) if side else np.array([0.0, 1.0, 0.0])
        out.update(
            joint_type="revolute",
            origin=origin,
            axis=axis,
            hinge=hinge,
            upper=_uniform(rng, limit),
            damping=_uniform(rng, DOOR_DAMPING),
            friction=_uniform(rng, DOOR_FRICTION),
            handle=style,
            handle_pos=origin + hpos,
            handle_axis=bar_axis if style == "bar" else np.array([1.0, 0.0, 0.0]),
            interior_center=np.array([0.5 * (xb + xf - tf), yc, zc]),
            interior_size=np.array([d - tf, w, h]),
            geoms=(panel, *hg),
        )
        return out
    if kind == "panel":
        geoms = (box("panel", (-tf, -0.5 * fw, -0.5 * fh), (0.0, 0.5 * fw, 0.5 * fh), front),)
        out.update(joint_type="fixed", origin=cell_center, geoms=geoms)
        return out
    # Open shelf: a board on the cell floor; link frame at the cell's front-bottom edge.
    origin = np.array([xf, yc, z0])
    board = box(
        "board",
        (xb - xf + 0.001, -0.5 * w + 0.001, 0.0),
        (0.0, 0.5 * w - 0.001, SHELF_BOARD),
        colors["body"],
    )
    out.update(
        joint_type="fixed",
        origin=origin,
        geoms=(board,),
        interior_center=np.array([0.5 * (xb + xf), yc, 0.5 * (z0 + SHELF_BOARD + z1)]),
        interior_size=np.array([d, w, h - SHELF_BOARD]),
    )
    return out


def _finish_part(d: dict, inertial: Inertial) -> PartSpec:
    return PartSpec(
        link=d["link"],
        joint=d["joint"],
        kind=d["kind"],
        semantic=SEMANTICS[d["kind"]][1],
        row=d["row"],
        col=d["col"],
        cell_center=d["cell_center"],
        cell_size=d["cell_size"],
        joint_type=d["joint_type"],
        axis=d["axis"],
        origin=d["origin"],
        lower=float(d["lower"]),
        upper=float(d["upper"]),
        damping=float(d["damping"]),
        friction=float(d["friction"]),
        hinge=d["hinge"],
        handle=d["handle"],
        handle_pos=d["handle_pos"],
        handle_axis=d["handle_axis"],
        interior_center=d.get("interior_center"),
        interior_size=d.get("interior_size"),
        geoms=tuple(d["geoms"]),
        inertial=inertial,
    )
