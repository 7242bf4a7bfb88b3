"""The initial belief: M particles of complete cabinet models from perception's fused
part hypotheses.

:func:`initial_belief` runs perception on the robot's views (clean, and
:attr:`BeliefConfig.noisy_runs` more times on inputs with sensor noise added), fuses each
run, and :func:`sample_particles` draws particles from those fusions. A particle is a
:class:`Particle`: a :class:`~strug_manip.objects.assembly.CabinetModel` (which parts
exist; each part's kind, rectangle, joint axis, origin, limits, current position and
handle), its compiled :class:`~strug_manip.objects.generator.CabinetSpec` and the
parts' joint positions, so every particle can be simulated
(``ManipulationWorld.from_cabinet_spec(p.spec)``, then ``reset(p.q)``).

The paper adds noise to the network's inputs, class predictions and joint parameters
because its network "had a tendency to be confidently incorrect". Here (per particle,
per part; defaults in :class:`BeliefConfig`):

* **inputs**: the particle's fusion is drawn from the clean run and the noisy-input runs;
* **classes**: the fused class probabilities are flattened (``p ** (1 / T)``) and every
  class keeps at least ``class_floor``: a drawer/door **flip** is always possible;
* **parameters**: axes turn by a random angle (``axis_noise`` [rad] per tangent
  direction), origins and rectangles shift (``origin_noise``, ``rect_noise`` [m]),
  openings vary by their spread over the views (at least ``q_noise``);
* **hinge side**: sampled from the fused side probabilities, every side the geometry
  allows keeping at least ``hinge_floor``: a closed door's opening sense is never
  certain from one look;
* **depth**: the carcass reaches a draw from ``depth_beyond_seen`` deeper than the views
  see it (the generator's range where they see none of it);
* **existence**: a part exists with its fused existence probability, clipped to
  ``existence_range``;
* **split**: a movable hypothesis large enough to hold two cells (at least twice the
  generator's smallest cell along its long side) is split in two with probability
  ``split_base`` plus ``split_merged`` times the share of views that saw it merged.

A part's handle is the style its seen shape says (a bar or a knob,
:func:`perception.fusion.handle_shape`; a bar along the direction seen) at the seen
grasp point; a door whose handle no view showed mostly gets one where the generator puts
it, in the style the cabinet's other handles show (``unseen_handle``). Limits, damping
and friction cannot be seen: they are drawn from the generator's documented ranges
(:mod:`strug_manip.objects.generator`), limits never below the opening seen; a flap (a
door hinged top or bottom) gets the generator's friction stay
(:attr:`~strug_manip.objects.assembly.PartModel.stay`), so that it stays where it is
unless pushed. Particles depend only on perception's outputs and the generator's
documented ranges, never on a true cabinet.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from perception.fusion import SIDES, FusedCabinet, PartHypothesis, fuse
from perception.inputs import View, check_view
from perception.parts import Perceiver
from planners.errors import ConfigError, check_positive_int
from strug_manip.geometry import axis_angle
from strug_manip.objects import generator as gen
from strug_manip.objects.assembly import (
    BAR,
    FRONT,
    GAP,
    SHELF_BOARD,
    WALL,
    CabinetModel,
    PartModel,
    assemble,
    drawer_fits,
    on_stand,
)
from strug_manip.objects.generator import CabinetSpec
from strug_manip.world.scene import cabinet_pose

#: A bar's grasp point read nearer its front's face than this [m] (front frame: the
#: closed front's face at x = 0) was read on the face behind the bar: the generator's
#: bars stand 2.5-4 cm out (``BAR_STANDOFF``), and a grasp at the face closes the fingers
#: in the panel. The thin bar (13 mm across) gives the head camera few pixels, and on
#: OpenDoor episode 10169 perception put its grasp point 3.9 cm behind the true one, on
#: the door's face: every opening was ``ik_infeasible`` (the approach's hand in the
#: door), in every model, where the oracle opened it.
ON_THE_FACE = 0.0125
#: Opening axis of a door hinged on each side, front frame (the generator's e x n).
SIDE_AXES = {
    "left": np.array([0.0, 0.0, -1.0]),
    "right": np.array([0.0, 0.0, 1.0]),
    "top": np.array([0.0, -1.0, 0.0]),
    "bottom": np.array([0.0, 1.0, 0.0]),
}


@dataclass(frozen=True)
class BeliefConfig:
    """How particles are drawn (module docstring); every field's default is given.

    Attributes:
        particles: M = 50.
        noisy_runs: extra perception runs on noisy inputs = 2.
        depth_noise: sensor noise on depth for those runs = 0.004 [m] (std, per pixel).
        rgb_noise: noise on colour for those runs = 6 (std, 0..255 scale).
        class_temperature: T = 2.
        class_floor: 0.05.
        hinge_floor: 0.05.
        existence_range: (0.05, 0.98).
        axis_noise: 0.03 [rad] (std per tangent direction, about 2.4 deg).
        origin_noise: 0.008 [m]; rect_noise: 0.006 [m]; q_noise: 0.01 [m or rad].
        split_base: 0.1; split_merged: 0.5.
        min_cell: 0.12 [m] (the generator's smallest cell height).
        unseen_handle: 0.8: the probability that a door whose handle no view showed has
            one at the generator's spot (:class:`~strug_manip.objects.assembly.PartModel`'s
            default: 4.5 cm in from the free edge, centred along it), in the style the
            cabinet's other parts show (the generator gives a cabinet one handle style
            for all its parts; without a handle seen anywhere, none is added). The
            target of OpenDoor episodes 10083 and 10088 was a door whose handle no view
            showed: every model had it handle-less, the catalogue had no part there, and
            no action could open it. The other 0.2 keeps a misread panel, or a cabinet
            whose pulls the look moves, without one.
        depth_beyond_seen: (-0.05, 0.10) [m]: where the views see the carcass's depth
            (:attr:`~perception.fusion.FrontFrame.depth`: how far behind the front its
            points reach), each particle's carcass goes a uniform draw from this range
            deeper. The views seldom see the back edge (the head looks at the front),
            and points of the table behind may pass for the carcass: on the episode
            cabinets of OpenDrawer 9100:9130 the true depth was the seen one plus
            +0.036 m (median; 10-90 %: -0.044..+0.086 m, extremes -0.085..+0.135 m).
            With the seen depth +- 1 cm, 8 of those 30 target drawers went farther out
            than every particle's limit (a drawer's travel is a share of its box's
            depth, which no view of a shut drawer shows), and the robot, its drawer
            short of open in every particle, never placed the object.
    """

    particles: int = 50
    noisy_runs: int = 2
    depth_noise: float = 0.004
    rgb_noise: float = 6.0
    class_temperature: float = 2.0
    class_floor: float = 0.05
    hinge_floor: float = 0.05
    existence_range: tuple[float, float] = (0.05, 0.98)
    axis_noise: float = 0.03
    origin_noise: float = 0.008
    rect_noise: float = 0.006
    q_noise: float = 0.01
    split_base: float = 0.1
    split_merged: float = 0.5
    min_cell: float = 0.12
    depth_beyond_seen: tuple[float, float] = (-0.05, 0.10)
    unseen_handle: float = 0.8

    def __post_init__(self) -> None:
        check_positive_int("particles", self.particles)
        check_positive_int("noisy_runs", self.noisy_runs, allow_zero=True)
        for name in (
            "depth_noise",
            "rgb_noise",
            "axis_noise",
            "origin_noise",
            "rect_noise",
            "q_noise",
            "split_base",
            "split_merged",
            "class_floor",
            "hinge_floor",
        ):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise ConfigError(f"BeliefConfig.{name} must be a finite number >= 0, got {v!r}")
        if not self.class_temperature > 0:
            raise ConfigError(
                f"BeliefConfig.class_temperature must be > 0, got {self.class_temperature!r}"
            )
        lo, hi = self.existence_range
        if not 0.0 <= lo <= hi <= 1.0:
            raise ConfigError(
                "BeliefConfig.existence_range must be 0 <= lo <= hi <= 1, "
                f"got {self.existence_range}"
            )
        lo, hi = self.depth_beyond_seen
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            raise ConfigError(
                "BeliefConfig.depth_beyond_seen must be finite (lo, hi) with lo <= hi [m], "
                f"got {self.depth_beyond_seen}"
            )
        if not (isinstance(self.unseen_handle, int | float) and 0 <= self.unseen_handle <= 1):
            raise ConfigError(
                f"BeliefConfig.unseen_handle must be a probability in [0, 1], "
                f"got {self.unseen_handle!r}"
            )
        if self.class_floor > 1 / 3 or self.hinge_floor > 1 / 4:
            raise ConfigError("class_floor must be <= 1/3 and hinge_floor <= 1/4")


@dataclass(frozen=True)
class Particle:
    """One complete cabinet model.

    Attributes:
        model: the cabinet as believed (front frame); None for the real cabinet as the
            oracle's particle (:func:`.oracle.true_particle`), which perception did not make.
        spec: its compiled description (``ManipulationWorld.from_cabinet_spec``).
        q: its parts' current joint positions ``{joint name: q}``.
        source: per part of ``spec`` (in order), the index of the fused hypothesis it
            comes from.
        run: which perception run (0 clean, then the noisy ones) it was drawn from.
    """

    model: CabinetModel | None
    spec: CabinetSpec
    q: dict[str, float]
    source: tuple[int, ...]
    run: int


def noisy_view(view: View, rng: np.random.Generator, depth_noise: float, rgb_noise: float) -> View:
    """``view`` with Gaussian noise on depth [m] and colour (dropouts stay dropouts)."""
    depth = view.depth + rng.normal(0.0, depth_noise, view.depth.shape).astype(np.float32)
    rgb = np.clip(view.rgb + rng.normal(0.0, rgb_noise, view.rgb.shape), 0, 255).astype(np.uint8)
    return dataclasses.replace(view, depth=np.where(view.valid, depth, view.depth), rgb=rgb)


def _tilt(axis: np.ndarray, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """``axis`` turned by Gaussian angles (std ``sigma`` [rad]) about two normals."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    t1 = np.cross(a, [0.0, 0.0, 1.0] if abs(a[2]) < 0.9 else [1.0, 0.0, 0.0])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(a, t1)
    out = a + sigma * (rng.normal() * t1 + rng.normal() * t2)
    return out / np.linalg.norm(out)


def _floored(p: np.ndarray, floor: float, allowed: np.ndarray | None = None) -> np.ndarray:
    allowed = np.ones(len(p), dtype=bool) if allowed is None else allowed
    p = np.where(allowed, np.maximum(p, floor), 0.0)
    return p / p.sum()


def closed_handle(
    h: PartHypothesis, kind: str, axis: np.ndarray, origin: np.ndarray, q: float
) -> np.ndarray | None:
    """The seen grasp point moved back to where it is with the part closed; a bar's
    read on its front's face (nearer it than :data:`ON_THE_FACE`) stood out
    :data:`~strug_manip.objects.assembly.BAR`'s standoff."""
    if h.handle is None:
        return None
    if kind == "drawer":
        closed = h.handle - q * axis
    else:
        closed = origin + axis_angle(axis, -q) @ (h.handle - origin)
    if h.handle_style == "bar" and closed[0] < ON_THE_FACE:
        closed = np.array([BAR[2], closed[1], closed[2]])
    return closed


def seen_style(f: FusedCabinet) -> str | None:
    """The handle style the fusion's parts show most (ties: the largest part's), or
    None when no part shows a handle."""
    styles = [h.handle_style for h in f.parts if h.handle is not None]
    return max(styles, key=styles.count) if styles else None


def _draw_part(
    h: PartHypothesis,
    depth: float,
    cfg: BeliefConfig,
    rng: np.random.Generator,
    style: str | None = None,
) -> list[PartModel]:
    """The part(s) one hypothesis contributes to one particle (none if it does not
    exist); ``style``: the handle style of the cabinet's seen handles
    (:func:`seen_style`), given to a door whose own handle no view showed with
    probability ``cfg.unseen_handle``."""
    lo, hi = cfg.existence_range
    if rng.random() >= float(np.clip(h.existence, lo, hi)):
        return []
    p = h.class_prob ** (1.0 / cfg.class_temperature)
    kind_i = int(rng.choice(3, p=_floored(p / p.sum(), cfg.class_floor)))
    if kind_i == 0:
        kind = "shelf" if h.shelf else "panel"
        rect = h.rect + rng.normal(0.0, cfg.rect_noise, 4)
        return [PartModel(kind, tuple(rect), np.zeros(3), np.zeros(3))] if _ok(rect) else []
    if kind_i == 1:
        rect = h.rect + rng.normal(0.0, cfg.rect_noise, 4)
        rects = [r for r in _maybe_split(rect, h, cfg, rng) if _ok(r) and drawer_fits(r)]
        q = max(0.0, h.q_drawer + rng.normal(0.0, max(h.q_std, cfg.q_noise)))
        out = []
        for r in rects:
            axis = _tilt(np.array([1.0, 0.0, 0.0]), cfg.axis_noise, rng)
            origin = np.array([0.0, 0.5 * (r[0] + r[1]), 0.5 * (r[2] + r[3])]) + rng.normal(
                0.0, cfg.origin_noise, 3
            )
            # The limit no view shows: the generator's share of a box whose depth share
            # of the free depth is drawn as well (from 0.56 to 0.855 of it; the
            # particle's box itself keeps one share, assembly.DRAWER_BOX).
            box_depth = float(rng.uniform(*gen.DRAWER_DEPTH_FRAC)) * (depth - FRONT - 0.01)
            upper = max(float(rng.uniform(*gen.DRAWER_TRAVEL_FRAC)) * box_depth, q + 0.01)
            handle = closed_handle(h, "drawer", axis, origin, q) if len(rects) == 1 else None
            out.append(
                PartModel(
                    "drawer",
                    tuple(r),
                    axis,
                    origin,
                    None,
                    upper,
                    q,
                    h.handle_style if handle is not None else "none",
                    handle,
                    float(rng.uniform(*gen.DRAWER_DAMPING)),
                    float(rng.uniform(*gen.DRAWER_FRICTION)),
                    handle_along=h.handle_along,
                )
            )
        return out
    allowed = h.hinge_prob > 1e-4
    side_i = int(rng.choice(4, p=_floored(h.hinge_prob, cfg.hinge_floor, allowed)))
    side = SIDES[side_i]
    rect = h.door_rect[side_i] + rng.normal(0.0, cfg.rect_noise, 4)
    if not _ok(rect):
        return []
    y0, y1, z0, z1 = rect
    yc, zc = 0.5 * (y0 + y1), 0.5 * (z0 + z1)
    origin = {
        "left": [0.0, y0 + GAP, zc],
        "right": [0.0, y1 - GAP, zc],
        "bottom": [0.0, yc, z0 + GAP],
        "top": [-FRONT, yc, z1 - GAP],
    }[side]
    origin = np.asarray(origin) + rng.normal(0.0, cfg.origin_noise, 3)
    axis = _tilt(SIDE_AXES[side], cfg.axis_noise, rng)
    q = max(0.0, float(h.door_q[side_i]) + rng.normal(0.0, cfg.q_noise))
    limits = gen.DOOR_SIDE_LIMIT if side in ("left", "right") else gen.DOOR_FLAP_LIMIT
    upper = max(float(rng.uniform(*limits)), q + 0.02)
    handle = closed_handle(h, "door", axis, origin, q)
    if handle is not None and side in ("left", "right") and not (y0 <= handle[1] <= y1):
        handle = None  # the seen handle does not fit this interpretation's panel
    # A handle no view showed, where the generator puts one (handle_pos None).
    unseen = h.handle is None and style is not None and rng.random() < cfg.unseen_handle
    damping, friction = (
        float(rng.uniform(*gen.DOOR_DAMPING)),
        float(rng.uniform(*gen.DOOR_FRICTION)),
    )
    # A flap has a friction stay, as the generator fits one (PartModel.stay).
    stay = float(rng.uniform(*gen.FLAP_STAY_HOLD)) if side in ("top", "bottom") else None
    return [
        PartModel(
            "door",
            tuple(rect),
            axis,
            origin,
            side,
            upper,
            q,
            style if unseen else h.handle_style if handle is not None else "none",
            handle,
            damping,
            friction,
            stay,
            handle_along=None if unseen else h.handle_along,
        )
    ]


def _ok(rect) -> bool:
    return rect[1] - rect[0] > 0.03 and rect[3] - rect[2] > 0.03


def _maybe_split(
    rect: np.ndarray, h: PartHypothesis, cfg: BeliefConfig, rng: np.random.Generator
) -> list[np.ndarray]:
    """The split move: one rectangle, or its two halves across its long side."""
    w, ht = rect[1] - rect[0], rect[3] - rect[2]
    if max(w, ht) < 2 * cfg.min_cell:
        return [rect]
    p = cfg.split_base + cfg.split_merged * h.merged / max(h.views + h.merged, 1)
    if rng.random() >= min(p, 1.0):
        return [rect]
    if ht >= w:
        mid = 0.5 * (rect[2] + rect[3])
        return [
            np.array([rect[0], rect[1], rect[2], mid]),
            np.array([rect[0], rect[1], mid, rect[3]]),
        ]
    mid = 0.5 * (rect[0] + rect[1])
    return [np.array([rect[0], mid, rect[2], rect[3]]), np.array([mid, rect[1], rect[2], rect[3]])]


def _overlaps(a, b) -> bool:
    iy = min(a[1], b[1]) - max(a[0], b[0])
    iz = min(a[3], b[3]) - max(a[2], b[2])
    return iy > 0.02 and iz > 0.02


def sample_particles(
    fused: Sequence[FusedCabinet],
    rng: np.random.Generator,
    config: BeliefConfig | None = None,
    scene: tuple[float, float, float] = (1.0, 0.0, 0.5),
) -> list[Particle]:
    """``config.particles`` particles from the fusions of one or more perception runs
    (module docstring).

    Args:
        fused: the runs' fusions (the first is the clean run).
        rng: the only source of randomness (same seed, same particles).
        config: the noise (default :class:`BeliefConfig`).
        scene: the cabinet table's ``(cabinet_distance, cabinet_lateral, stand_height)``
            [m] (:class:`~strug_manip.world.scene.SceneConfig`'s fields), where specs stand.

    Raises:
        ConfigError: no fusion was given, or a bad config.
    """
    cfg = config or BeliefConfig()
    if not fused:
        raise ConfigError("sample_particles needs at least one FusedCabinet")
    styles = [seen_style(f) for f in fused]  # per run, not per particle
    out = []
    for _ in range(cfg.particles):
        run = int(rng.integers(len(fused)))
        f = fused[run]
        front = f.front
        if front.depth_seen:
            depth = front.depth + float(rng.uniform(*cfg.depth_beyond_seen))
        else:
            depth = float(rng.uniform(*gen.DEPTH_RANGE)) + rng.normal(0.0, 0.01)
        depth = max(0.25, depth)
        parts: list[PartModel] = []
        source: list[int] = []
        for i, h in enumerate(f.parts):  # largest first: a smaller one overlapping it is dropped
            for m in _draw_part(h, depth, cfg, rng, styles[run]):
                if not any(_overlaps(m.rect, o.rect) for o in parts):
                    parts.append(m)
                    source.append(i)
        # The carcass holds every part (a part may reach past the front seen); the
        # cabinet stands on the table (on_stand below), so a part must reach above it.
        box = (0.5 * front.width + 0.1, front.height + 0.1)
        dz = scene[2] - float(front.T_world_front[2, 3])
        keep = [
            i
            for i, m in enumerate(parts)
            if max(abs(m.rect[0]), abs(m.rect[1])) <= box[0]
            and m.rect[2] >= -0.1
            and m.rect[3] <= box[1]
            and m.rect[3] - max(m.rect[2], dz) > 2 * GAP + 0.02
        ]
        parts, source = [parts[i] for i in keep], [source[i] for i in keep]
        # Never smaller than the generator's smallest cabinet (a failed front measurement).
        width = max(
            [front.width, gen.WIDTH_RANGE[0]]
            + [2 * max(abs(m.rect[0]), abs(m.rect[1])) + 0.04 for m in parts]
        )
        height = max([front.height, gen.HEIGHT_RANGE[0]] + [m.rect[3] + 0.02 for m in parts])
        # On the table, as the scene stands it: parts stay where perception saw them.
        model = on_stand(
            CabinetModel(float(width), float(height), float(depth), tuple(parts),
                         front.T_world_front), scene[2])  # fmt: skip
        spec, q = assemble(model, cabinet_pose(model.depth, *scene))
        order = sorted(range(len(parts)), key=lambda i: (-parts[i].rect[3], parts[i].rect[0]))
        out.append(Particle(model, spec, q, tuple(source[i] for i in order), run))
    return out


#: Where the open cell's boards and walls are read from: points between these
#: distances along the front's normal [m] (from 12 cm behind the front plane to 1 cm
#: before it, for noise): the boards' and walls' front edges, which the head camera
#: sees even where it sees neither a board's underside nor, deeper, anything but the
#: back panel, which would pass for a wall.
CELL_BAND = (-0.12, 0.01)
#: Half-width of the column above and below the point where boards are looked for [m].
CELL_COLUMN = 0.04


def open_cell(model: CabinetModel, point: np.ndarray, clouds: Sequence[np.ndarray]) -> PartModel:
    """The open shelf cell at world ``point`` (3,) [m], from the cabinet's points the
    head camera saw (``clouds``: world (N, 3) [m], e.g.
    :func:`~strug_manip.world.views.cabinet_cloud` of the views perception had).

    The network finds movable parts only; an open cell is empty space between boards.
    Across the opening (:data:`CELL_BAND`), the highest surface below ``point``
    is the cell's floor (a board's top), the lowest above it its ceiling (at most the
    model's carcass top), and the
    nearest surfaces left and right of it at mid-height its walls; where none is seen
    the carcass (``model``'s outer size less a board) bounds the cell.
    """
    T = np.linalg.inv(np.asarray(model.T_world_front, dtype=float))
    P = np.concatenate([np.asarray(c, dtype=float).reshape(-1, 3) for c in clouds])
    P = P @ T[:3, :3].T + T[:3, 3]
    _, yt, zt = T[:3, :3] @ np.asarray(point, dtype=float) + T[:3, 3]
    inside = (P[:, 0] > CELL_BAND[0]) & (P[:, 0] < CELL_BAND[1])
    col = inside & (np.abs(P[:, 1] - yt) < CELL_COLUMN)
    below, above = P[col & (P[:, 2] < zt - 0.01), 2], P[col & (P[:, 2] > zt + 0.01), 2]
    floor = below.max() if len(below) else WALL
    # Never above the carcass's top board as the model has it (a cell whose opening
    # reached into that board would let the object be carried in through it).
    ceiling = min(above.min() if len(above) else np.inf, model.height - WALL)
    band = inside & (P[:, 2] > floor + 0.02) & (P[:, 2] < ceiling - 0.02)
    right, left = P[band & (P[:, 1] > yt + 0.02), 1], P[band & (P[:, 1] < yt - 0.02), 1]
    y1 = right.min() if len(right) else model.width / 2 - WALL
    y0 = left.max() if len(left) else -model.width / 2 + WALL
    z0 = floor - SHELF_BOARD  # the cell's board, with its top where the floor was seen
    return PartModel("shelf", (float(y0), float(y1), float(z0), float(ceiling)),
                     np.zeros(3), np.zeros(3))  # fmt: skip


def with_open_cell(
    particle: Particle,
    point: np.ndarray,
    clouds: Sequence[np.ndarray],
    scene: tuple[float, float, float] = (1.0, 0.0, 0.5),
) -> Particle:
    """``particle`` with the open cell at ``point`` (:func:`open_cell`) and the board
    above it added, unless one of its parts covers the point already (it then believes
    something is there; the real cabinet, ``model`` None, has its cells)."""
    m = particle.model
    if m is None:
        return particle
    T = np.linalg.inv(np.asarray(m.T_world_front, dtype=float))
    _, y, z = T[:3, :3] @ np.asarray(point, dtype=float) + T[:3, 3]
    if any(p.rect[0] <= y <= p.rect[1] and p.rect[2] <= z <= p.rect[3] for p in m.parts):
        return particle
    cell = open_cell(m, point, clouds)
    if any(_overlaps(cell.rect, o.rect) for o in m.parts):
        return particle
    # The board above the cell too (as the floor of the space above it, up to the
    # carcass's top): the arm's free motions must clear it. Its rect starts a board
    # above the cell's ceiling: every rect is framed by a board under it, which would
    # otherwise hang into the cell and lower its ceiling by a board's thickness.
    y0, y1, _, top = cell.rect
    above = PartModel("shelf", (y0, y1, top + WALL, m.height - WALL), np.zeros(3),
                      np.zeros(3)) if m.height - WALL - top - WALL > 0.05 else None  # fmt: skip
    extra = (above,) if above is not None and not any(
        _overlaps(above.rect, o.rect) for o in m.parts) else ()  # fmt: skip
    parts = (*m.parts, cell, *extra)
    model = dataclasses.replace(m, parts=parts)
    spec, q = assemble(model, cabinet_pose(model.depth, *scene))
    # Per part of the spec (top to bottom, left to right), the fused hypothesis it
    # came from: -1 for the cells, which no hypothesis holds.
    source = dict(zip(sorted(range(len(m.parts)), key=lambda i: (-m.parts[i].rect[3],
                  m.parts[i].rect[0])), particle.source, strict=True))  # fmt: skip
    order = sorted(range(len(parts)), key=lambda i: (-parts[i].rect[3], parts[i].rect[0]))
    return Particle(model, spec, q, tuple(source.get(i, -1) for i in order), particle.run)


def perceive_cabinet(
    frames: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray, float]],
    perceiver: Perceiver,
    rng: np.random.Generator,
    config: BeliefConfig | None = None,
) -> list[FusedCabinet]:
    """Perception of one cabinet from its views ``(rgb, depth [m], T_world_camera,
    fovy [rad])``: the clean fusion, then ``config.noisy_runs`` fusions of noisy inputs.

    Raises:
        perception.errors.BadInputError: a malformed view.
        perception.errors.NoCabinetError: no view shows a cabinet.
    """
    cfg = config or BeliefConfig()
    views = [check_view(*f) for f in frames]
    runs = [fuse([perceiver.perceive(v) for v in views])]
    for _ in range(cfg.noisy_runs):
        noisy = [noisy_view(v, rng, cfg.depth_noise, cfg.rgb_noise) for v in views]
        runs.append(fuse([perceiver.perceive(v) for v in noisy]))
    return runs


def initial_belief(
    frames: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray, float]],
    perceiver: Perceiver,
    rng: np.random.Generator,
    config: BeliefConfig | None = None,
    scene: tuple[float, float, float] = (1.0, 0.0, 0.5),
) -> list[Particle]:
    """Particles of complete cabinets from the robot's views (:func:`perceive_cabinet`
    then :func:`sample_particles`)."""
    return sample_particles(perceive_cabinet(frames, perceiver, rng, config), rng, config, scene)
