"""Complete cabinets from part hypotheses: what makes a belief particle a cabinet the
world compiles.

A :class:`CabinetModel` is a cabinet as perception describes it: the carcass's outer
size and, per part, its kind, its closed-state rectangle on the front plane, its joint
(axis, origin, limits, current position) and its handle, all in the *front frame*
(``x`` the front's outward normal, ``z`` up, ``y = z x x``, origin on the front plane at
the front's lateral centre and the carcass's bottom) with the front frame's pose in the
world. :func:`assemble` turns it into a
:class:`~strug_manip.objects.generator.CabinetSpec` (carcass boards, drawer boxes,
door panels, handles, masses, joints, interiors) that
``ManipulationWorld.from_cabinet_spec`` compiles like a generated one.

Where the spec is placed: the caller gives the object frame's pose in the world, as
the scene stands a spec of that depth (:func:`strug_manip.world.scene.cabinet_pose`:
its front plane behind the cabinet table's edge, facing the robot). Everything
perceived in the world frame is expressed in that placement's object frame, so a
particle's parts are where perception saw them; box geoms keep the object frame's axes
(a perceived yaw of the front of a degree or two tilts joint axes, not boards).

What perception cannot see is set to documented values (the middle of the generator's
ranges, :mod:`strug_manip.objects.generator`): board thickness :data:`WALL` [m], front
thickness :data:`FRONT` [m], the gap around fronts :data:`GAP` [m], drawer boxes as
the generator builds them, bar handles :data:`BAR` (radius, length, standoff) [m], wood
density :data:`DENSITY` [kg/m^3]; damping and friction are given per part (the belief
samples them from the generator's ranges).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from planners.errors import ConfigError
from strug_manip.objects import generator as gen
from strug_manip.objects.generator import (
    METAL_DENSITY,
    SEMANTICS,
    CabinetSpec,
    Geom,
    PartSpec,
    box,
    flap_stay_friction,
)

#: Carcass board thickness [m] (generator: 0.015-0.020).
WALL = 0.0175
#: Back panel thickness [m] (generator: 0.004-0.008).
BACK = 0.006
#: Front (drawer front, door, panel) thickness [m] (generator: 0.015-0.022).
FRONT = 0.018
#: Gap around a front in its cell [m] (generator: 0.002-0.004).
GAP = 0.003
#: Bar handle: radius, length, standoff from the front face [m].
BAR = (0.0065, 0.12, 0.032)
#: Knob radius: the generator's middle one [m] (its length follows the seen grasp point,
#: :func:`_knob`).
KNOB_RADIUS = 0.5 * sum(gen.KNOB_RADIUS)
#: Unit vectors of the front frame's axes, by name.
_AXES = {"y": np.array([0.0, 1.0, 0.0]), "z": np.array([0.0, 0.0, 1.0])}
#: Handle styles a believed part may have (the generator's).
HANDLES = gen.HANDLE_KINDS
#: Wood density [kg/m^3] (generator: 450-700).
DENSITY = 575.0
#: Drawer box: height as a share of the front, depth as a share of the free cell depth,
#: board thickness [m], side clearance [m] (generator: 0.60-0.85, 0.80-0.95, 0.008-0.012,
#: 0.006). The height is the generator's tallest: no view of a closed drawer shows its
#: box, and motions planned against the believed box (an object carried in over its
#: walls) must clear the real walls; with the middle share (0.72) a 0.28 m front's real
#: walls stood up to 3.5 cm above the believed ones, and the object carried over them at
#: the 2 cm ``held_clearance`` struck them and slid the cabinet (the demo, issue 39).
DRAWER_BOX = (gen.DRAWER_HEIGHT_FRAC[1], 0.875, 0.010, 0.006)
#: The narrowest cell a drawer fits [m]: side clearances and box walls, and a 1 cm inside.
_MIN_DRAWER_WIDTH = 2 * DRAWER_BOX[3] + 2 * DRAWER_BOX[2] + 0.01


def drawer_fits(rect: Sequence[float]) -> bool:
    """A drawer's box fits the cell ``rect`` (y0, y1, z0, z1) [m] (front frame): its
    walls and side clearances leave an inside at least 1 cm wide."""
    return float(rect[1]) - float(rect[0]) > _MIN_DRAWER_WIDTH


#: Shelf board thickness [m] (the generator's).
SHELF_BOARD = 0.008
KINDS = ("drawer", "door", "panel", "shelf")
SIDES = ("left", "right", "top", "bottom")
_BODY_RGBA = (0.76, 0.60, 0.42, 1.0)
_FRONT_RGBA = (0.87, 0.72, 0.53, 1.0)
_METAL_RGBA = (0.72, 0.72, 0.75, 1.0)


@dataclass(frozen=True)
class PartModel:
    """One believed part (front frame, part closed unless ``q``).

    Attributes:
        kind: ``drawer``, ``door``, ``panel`` or ``shelf``.
        rect: the cell opening ``(y0, y1, z0, z1)`` on the front plane [m].
        axis: unit joint axis (3,) (drawer: the opening direction; door: opening is a
            positive turn about it); ignored for fixed parts.
        origin: drawer: the cell centre on the front plane; door: a point of the hinge
            line (3,) [m]; ignored for fixed parts.
        hinge: door hinge side (:data:`SIDES`), else None.
        upper: joint limit [m or rad] (lower is 0).
        q: current joint position [m or rad].
        handle: ``bar``, ``knob`` or ``none``; handle_pos: the grasp point (3,) [m]
            with the part closed, or None for the default (the generator's spot);
            handle_along: a bar's direction on the front, ``y`` or ``z`` (None: the
            generator's for the part, vertical on a side door, else horizontal). A
            knob stands out of the front face with its axis through the grasp point,
            its tip :data:`generator.KNOB_GRASP_INSET` in front of it (as the
            generator grasps knobs).
        damping: [N s/m] or [N m s/rad]; friction: [N] or [N m].
        stay: a top- or bottom-hinged flap's friction stay, as the generator fits one
            (:data:`~strug_manip.objects.generator.FLAP_STAY_HOLD`): the joint's
            friction is then ``stay`` times the assembled flap's gravity torque when
            horizontal (its mass and lever are known only once it is built), and
            ``friction`` is ignored; None: ``friction`` as given. Without a stay a
            flap believed bottom-hinged, its axis a few degrees off level as
            perception leaves it, falls open under its own weight in the planning
            twin (and a model predicts a cabinet that changes on its own).
    """

    kind: str
    rect: tuple[float, float, float, float]
    axis: np.ndarray
    origin: np.ndarray
    hinge: str | None = None
    upper: float = 0.0
    q: float = 0.0
    handle: str = "none"
    handle_pos: np.ndarray | None = None
    damping: float = 0.0
    friction: float = 0.0
    stay: float | None = None
    handle_along: str | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ConfigError(f"PartModel.kind must be one of {KINDS}, got {self.kind!r}")
        y0, y1, z0, z1 = (float(v) for v in self.rect)
        if not (y1 - y0 > 2 * GAP + 0.01 and z1 - z0 > 2 * GAP + 0.01):
            raise ConfigError(f"PartModel.rect must span at least 1 cm each way, got {self.rect}")
        if self.handle not in HANDLES:
            raise ConfigError(f"PartModel.handle must be one of {HANDLES}, got {self.handle!r}")
        if self.handle_along not in (None, "y", "z"):
            raise ConfigError(
                f"PartModel.handle_along must be 'y', 'z' or None, got {self.handle_along!r}"
            )
        if self.kind == "door" and self.hinge not in SIDES:
            raise ConfigError(f"a door needs hinge in {SIDES}, got {self.hinge!r}")
        if self.kind in ("drawer", "door") and not self.upper > 0:
            raise ConfigError(f"a movable part needs upper > 0, got {self.upper!r}")
        if self.kind == "drawer" and not drawer_fits(self.rect):
            raise ConfigError(
                f"a drawer's box needs a cell wider than {_MIN_DRAWER_WIDTH:.3f} m, "
                f"got rect {self.rect}"
            )
        if self.stay is not None and not (
            self.kind == "door" and self.hinge in ("top", "bottom") and self.stay > 0
        ):
            raise ConfigError(
                f"a stay (> 0) is for a top- or bottom-hinged door, got stay={self.stay!r} "
                f"on a {self.kind} hinged {self.hinge!r}"
            )


@dataclass(frozen=True)
class CabinetModel:
    """A whole believed cabinet (front frame; see the module docstring).

    Attributes:
        width, height: the front's extents [m]; depth: the carcass depth [m].
        parts: the parts, any order.
        T_world_front: (4, 4) the front frame in the world.
    """

    width: float
    height: float
    depth: float
    parts: tuple[PartModel, ...]
    T_world_front: np.ndarray

    def __post_init__(self) -> None:
        for name in ("width", "height", "depth"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0.1 <= v <= 3.0):
                raise ConfigError(f"CabinetModel.{name} must be in [0.1, 3] m, got {v!r}")


def on_stand(model: CabinetModel, stand: float) -> CabinetModel:
    """``model`` with its bottom on the cabinet table's top (``stand`` [m] high) and
    every part where it was in the world.

    The scene stands a spec's lowest point on the table (:func:`~strug_manip.world.
    scene.build_scene`); a front frame perceived a little below or above the table top
    would otherwise carry every part up or down by the difference. The front frame is
    taken as upright (its z along the world's): the shift goes into its height, the
    carcass's height and the parts' rects, joint origins and handles (a part reaching
    below the new bottom is cut there).

    Raises:
        ConfigError: a part would be cut to less than :class:`PartModel` allows.
    """
    T = np.array(model.T_world_front, dtype=float)
    dz = float(stand - T[2, 3])
    if abs(dz) < 1e-6:
        return model
    T[2, 3] = stand
    down = np.array([0.0, 0.0, dz])

    def moved(p: PartModel) -> PartModel:
        y0, y1, z0, z1 = p.rect
        return dataclasses.replace(
            p,
            rect=(y0, y1, max(z0 - dz, 0.0), z1 - dz),
            origin=np.asarray(p.origin, float) - down,
            handle_pos=None if p.handle_pos is None else np.asarray(p.handle_pos, float) - down,
        )

    parts = tuple(moved(p) for p in model.parts)
    return CabinetModel(model.width, model.height - dz, model.depth, parts, T)


def _carcass(m: CabinetModel, cells: list[tuple[float, float, float, float]]) -> list[Geom]:
    """Carcass boards in the front frame: sides, top, bottom, back, and boards framing
    every cell."""
    w, h, D, t = m.width, m.height, m.depth, WALL
    geoms = [
        box("side_left", (-D, -w / 2, 0), (0, -w / 2 + t, h), _BODY_RGBA),
        box("side_right", (-D, w / 2 - t, 0), (0, w / 2, h), _BODY_RGBA),
        box("top", (-D, -w / 2 + t, h - t), (0, w / 2 - t, h), _BODY_RGBA),
        box("bottom", (-D, -w / 2 + t, 0), (0, w / 2 - t, t), _BODY_RGBA),
        box("back", (-D, -w / 2 + t, t), (-D + BACK, w / 2 - t, h - t), _BODY_RGBA),
    ]
    lo_y, hi_y, lo_z, hi_z = -w / 2 + t, w / 2 - t, t, h - t
    for i, (y0, y1, z0, z1) in enumerate(cells):
        ya, yb = max(y0 - t, lo_y), min(y1 + t, hi_y)
        for k, (za, zb) in enumerate(((z0 - t, z0), (z1, z1 + t))):
            za, zb = max(za, lo_z - t), min(zb, hi_z + t)
            if zb - za > 1e-3 and yb - ya > 1e-3:
                geoms.append(
                    box(f"frame_{i}_{'bt'[k]}", (-D + BACK, ya, za), (0, yb, zb), _BODY_RGBA)
                )
        for k, (ya2, yb2) in enumerate(((y0 - t, y0), (y1, y1 + t))):
            ya2, yb2 = max(ya2, lo_y - t), min(yb2, hi_y + t)
            if yb2 - ya2 > 1e-3 and z1 - z0 > 1e-3:
                geoms.append(
                    box(f"frame_{i}_{'lr'[k]}", (-D + BACK, ya2, z0), (0, yb2, z1), _BODY_RGBA)
                )
    return geoms


def _bar(grasp: np.ndarray, along: str) -> list[Geom]:
    """A bar handle (:data:`BAR`) whose grasp point (bar centre) is ``grasp`` (link
    frame)."""
    r, length, s = BAR
    return gen.bar_handle(grasp, along, r, length, s, _METAL_RGBA)


def _knob(grasp: np.ndarray) -> tuple[list[Geom], np.ndarray]:
    """A knob on the front face (front frame, the face at x = 0) whose tip stands
    :data:`generator.KNOB_GRASP_INSET` in front of the seen grasp point ``grasp`` (its
    length clipped to the generator's range), and the grasp point it has, (3,) [m]
    (front frame)."""
    length = float(np.clip(grasp[0] + gen.KNOB_GRASP_INSET, *gen.KNOB_LENGTH))
    return gen.knob_handle(np.array([0.0, grasp[1], grasp[2]]), KNOB_RADIUS, length, _METAL_RGBA)


def _moved_by(geoms: list[Geom], shift: np.ndarray) -> list[Geom]:
    """``geoms`` translated by ``shift`` (3,) [m] (front frame to a link frame)."""
    return [dataclasses.replace(g, pos=tuple(float(v) for v in np.asarray(g.pos) + shift))
            for g in geoms]  # fmt: skip


def _part_geoms(
    p: PartModel, depth: float
) -> tuple[list[Geom], np.ndarray, np.ndarray, np.ndarray | None, tuple]:
    """Geometry in the part's link frame, the link origin (front frame), the grasp
    point (front frame), the bar direction, and the interior (centre, size) in the front
    frame."""
    y0, y1, z0, z1 = p.rect
    yc, zc = 0.5 * (y0 + y1), 0.5 * (z0 + z1)
    fw, fh = y1 - y0 - 2 * GAP, z1 - z0 - 2 * GAP
    centre = np.array([0.0, yc, zc])
    if p.kind in ("panel", "shelf"):
        if p.kind == "panel":
            return (
                [box("panel", (-FRONT, -fw / 2, -fh / 2), (0, fw / 2, fh / 2), _FRONT_RGBA)],
                centre,
                None,
                None,
                (None, None),
            )
        origin = np.array([0.0, yc, z0])
        board = box(
            "board", (-depth + BACK + 0.001, -fw / 2, 0), (0, fw / 2, SHELF_BOARD), _BODY_RGBA
        )
        inner = np.array([depth, y1 - y0, z1 - z0 - SHELF_BOARD])
        return (
            [board],
            origin,
            None,
            None,
            (np.array([-depth / 2, yc, 0.5 * (z0 + SHELF_BOARD + z1)]), inner),
        )
    if p.kind == "drawer":
        hf, df, tb, clr = DRAWER_BOX
        bw, bh = y1 - y0 - 2 * clr, hf * fh
        bd = df * (depth - FRONT - 0.01)
        zb = -0.5 * (z1 - z0) + 0.005
        xr = -FRONT - bd
        geoms = [
            box("front", (-FRONT, -fw / 2, -fh / 2), (0, fw / 2, fh / 2), _FRONT_RGBA),
            box("bottom", (xr, -bw / 2, zb), (-FRONT, bw / 2, zb + tb), _FRONT_RGBA),
            box("side_left", (xr, -bw / 2, zb + tb), (-FRONT, -bw / 2 + tb, zb + bh), _FRONT_RGBA),
            box("side_right", (xr, bw / 2 - tb, zb + tb), (-FRONT, bw / 2, zb + bh), _FRONT_RGBA),
            box("back", (xr, -bw / 2 + tb, zb + tb), (xr + tb, bw / 2 - tb, zb + bh), _FRONT_RGBA),
        ]
        grasp = (
            centre + np.array([BAR[2], 0.0, 0.0])
            if p.handle_pos is None
            else np.asarray(p.handle_pos, float)
        )
        if p.handle == "bar":
            geoms += _bar(grasp - centre, p.handle_along or "y")
        elif p.handle == "knob":
            knob, grasp = _knob(grasp)
            geoms += _moved_by(knob, -centre)
        inner = np.array([bd - tb, bw - 2 * tb, bh - tb])
        ic = centre + np.array([xr + tb + 0.5 * inner[0], 0.0, zb + tb + 0.5 * inner[2]])
        return geoms, centre, grasp, _AXES[p.handle_along or "y"], (ic, inner)
    # A door: link frame on the hinge line, at the edge's middle.
    origin = np.asarray(p.origin, dtype=float)
    lo = np.array([-FRONT, y0 + GAP, z0 + GAP]) - origin
    hi = np.array([0.0, y1 - GAP, z1 - GAP]) - origin
    geoms = [box("panel", lo, hi, _FRONT_RGBA)]
    side = p.hinge in ("left", "right")
    e = {"left": (0, 1, 0), "right": (0, -1, 0), "top": (0, 0, -1), "bottom": (0, 0, 1)}[p.hinge]
    span = fw if side else fh
    if p.handle_pos is None:
        free = centre + np.asarray(e, float) * (0.5 * span - 0.045)
        grasp = free + np.array([BAR[2] if p.handle == "bar" else 0.0, 0.0, 0.0])
    else:
        grasp = np.asarray(p.handle_pos, dtype=float)
    along = p.handle_along or ("z" if side else "y")
    if p.handle == "bar":
        geoms += _bar(grasp - origin, along)
    elif p.handle == "knob":
        knob, grasp = _knob(grasp)
        geoms += _moved_by(knob, -origin)
    inner = np.array([depth - FRONT, y1 - y0, z1 - z0])
    ic = np.array([-0.5 * (depth + FRONT), yc, zc])
    return geoms, origin, grasp, _AXES[along], (ic, inner)


def assemble(
    model: CabinetModel, T_world_object: np.ndarray
) -> tuple[CabinetSpec, dict[str, float]]:
    """The :class:`CabinetSpec` of ``model`` in the object frame at ``T_world_object``
    (4, 4) (where the scene stands a spec of ``model.depth``:
    :func:`strug_manip.world.scene.cabinet_pose`), and the parts' current joint
    positions ``{joint name: q}`` (``ManipulationWorld.reset`` takes them).

    Raises:
        ConfigError: a malformed model or pose.
    """
    if not isinstance(model, CabinetModel):
        raise ConfigError(f"model must be a CabinetModel, got {model!r}")
    T_wo = np.asarray(T_world_object, dtype=float)
    if T_wo.shape != (4, 4) or not np.all(np.isfinite(T_wo)):
        raise ConfigError(f"T_world_object must be a finite (4, 4) pose, got {T_world_object!r}")
    A = np.linalg.inv(T_wo) @ np.asarray(model.T_world_front, dtype=float)
    R, b = A[:3, :3], A[:3, 3]

    def point(p: np.ndarray) -> np.ndarray:
        return R @ np.asarray(p, float) + b

    def moved(g: Geom, shift: np.ndarray) -> Geom:
        return Geom(
            g.name,
            g.shape,
            tuple(float(v) for v in np.asarray(g.pos) + shift),
            g.size,
            g.axis,
            g.material,
            g.rgba,
        )

    body = [
        moved(g, point(np.zeros(3)) + R @ np.asarray(g.pos) - np.asarray(g.pos))
        for g in _carcass(model, [p.rect for p in model.parts])
    ]
    densities = {"wood": DENSITY, "metal": METAL_DENSITY}
    order = sorted(
        range(len(model.parts)), key=lambda i: (-model.parts[i].rect[3], model.parts[i].rect[0])
    )
    parts, q = [], {}
    for n, i in enumerate(order, start=1):
        p = model.parts[i]
        geoms, origin, grasp, bar_dir, (ic, isize) = _part_geoms(p, model.depth)
        origin_o = point(origin)
        geoms_o = [moved(g, R @ np.asarray(g.pos) - np.asarray(g.pos)) for g in geoms]
        movable = p.kind in ("drawer", "door")
        y0, y1, z0, z1 = p.rect
        inertial = gen.mass_properties(geoms_o, densities)
        friction = float(p.friction) if movable else 0.0
        if p.stay is not None:  # as the generator fits one
            friction = flap_stay_friction(p.stay, inertial)
        spec = PartSpec(
            link=f"link_{n}",
            joint=f"joint_{n}",
            kind=p.kind,
            semantic=SEMANTICS[p.kind][1],
            row=0,
            col=n - 1,
            cell_center=point([0.0, 0.5 * (y0 + y1), 0.5 * (z0 + z1)]),
            cell_size=np.array([y1 - y0, z1 - z0]),
            joint_type={"drawer": "prismatic", "door": "revolute"}.get(p.kind, "fixed"),
            axis=R @ (np.asarray(p.axis, float) / np.linalg.norm(p.axis))
            if movable
            else np.zeros(3),
            origin=origin_o,
            lower=0.0,
            upper=float(p.upper) if movable else 0.0,
            damping=float(p.damping) if movable else 0.0,
            friction=friction,
            hinge=p.hinge if p.kind == "door" else None,
            handle=p.handle if movable else "none",
            handle_pos=point(grasp) if grasp is not None else None,
            handle_axis=(R @ bar_dir if p.handle == "bar" else R @ np.array([1.0, 0, 0]))
            if movable
            else None,
            interior_center=point(ic) if ic is not None else None,
            interior_size=isize,
            geoms=tuple(geoms_o),
            inertial=inertial,
        )
        parts.append(spec)
        if movable:
            q[spec.joint] = float(np.clip(p.q, 0.0, p.upper))
    kinds = tuple(
        k for k in ("drawer", "door", "shelf", "panel") if any(p.kind == k for p in model.parts)
    ) or ("panel",)
    spec = CabinetSpec(
        seed=0,
        kinds=kinds,
        width=float(model.width),
        depth=float(model.depth),
        height=float(model.height),
        wall=WALL,
        back=BACK,
        plinth=0.0,
        rows=1,
        cols=max(len(parts), 1),
        row_heights=np.array([model.height]),
        col_widths=np.array([model.width]),
        body_geoms=tuple(body),
        body_inertial=gen.mass_properties(body, densities),
        parts=tuple(parts),
        colors={"body": _BODY_RGBA, "front": _FRONT_RGBA, "handle": _METAL_RGBA},
    )
    return spec, q
