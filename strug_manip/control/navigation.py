"""Where the base drives: a collision-free route on the floor between two base poses.

:func:`plan_route` first tries the straight segment; if the robot (in its drive
posture, holding what it carries) would touch anything on the way, it searches a grid
of the floor with A*: every collision geom that is not the robot's nor the floor, and
that reaches into the robot's height, blocks the cells its footprint (its horizontal
bounding box) covers, grown by the robot's own horizontal radius at that geom's
heights (in that posture, from the vertices of its meshes and the corners of its
boxes: so the base may stand under a table top or an open flap that only the narrower
upper body must keep clear of). The
grid path is shortened by line of sight, the heading turns evenly along it, and the
route is kept only if the full kinematic check (the real robot geometry at every
:data:`STEP` of it) finds it free; failing that, the grid is searched again with the
start's and the goal's surroundings open (a robot walled in by the grid's growth).

A robot that turns while it drives past an obstacle (the door it swung open, the
table) sweeps a corner of its arm into it where driving at a fixed heading would not.
So where no evenly-turning route is free, each of those paths (the straight segment,
the grid's) is tried again with the robot turning only where it stands: in place at
the start to one heading, driving the whole path at it, in place at the goal to the
goal's heading (the driver takes a waypoint of the same x, y and another yaw as a
turn in place). The headings tried (:func:`turn_headings`, every :data:`TURN`) are
those it has room to turn to at the start and from which it has room to turn to the
goal's heading at the goal; of those whose route the full check finds free, the one
with free headings on both sides (:data:`HEADING_ROOM`: the least turning free
heading grazes what it passes), then the least turning.

Units: [m], [rad]; a base pose is (x, y, yaw).
"""

from __future__ import annotations

import heapq
import itertools
import math

import mujoco
import numpy as np

from strug_manip.control.contacts import ContactChecker

#: Grid cell size [m].
CELL = 0.05
#: Half size of the searched square of floor, around the start and the goal [m].
MARGIN = 1.5
#: Spacing of the full collision checks along a route [m].
STEP = 0.05
#: Safety margin added to the robot's radius on the grid [m].
CLEARANCE = 0.03
#: Height above which geometry cannot touch the robot [m].
ROBOT_HEIGHT = 1.6
#: Spacing of the full collision checks along a turn, and of the headings tried [rad].
TURN = 0.1
#: Free headings wanted on either side of the one a route turning in place drives at [rad].
HEADING_ROOM = 0.3


def route_free(checker: ContactChecker, route: list[np.ndarray], arm: np.ndarray) -> bool:
    """The robot (base + ``arm``, torso + arm (8,)) touches nothing along the polyline of
    base poses ``route`` (checked every :data:`STEP` of travel, yaw interpolated)."""
    for a, b in itertools.pairwise(route):
        n = max(1, math.ceil(float(np.linalg.norm(b[:2] - a[:2])) / STEP))
        n = max(n, math.ceil(abs(float(b[2] - a[2])) / TURN))  # turns: every TURN
        for k in range(n + 1):
            if not checker.free(np.concatenate([a + (k / n) * (b - a), arm])):
                return False
    return True


def plan_route(
    checker: ContactChecker, start: np.ndarray, goal: np.ndarray, arm: np.ndarray
) -> list[np.ndarray] | None:
    """Base poses to drive through from ``start`` to ``goal`` (both (3,), the goal's yaw
    unwrapped to the nearest turn of the start's), the arm at ``arm``; None if none
    is found. ``checker`` is loaded with the scene's state (and any carried object).

    Where the grid has no route, or its route is not free, the grid is searched again
    with the cells within the robot's radius of the start and the goal open
    (:func:`grid_route`'s ``escape``): the grid grows every obstacle by the robot's
    widest reach at its heights in every direction, so a robot that stands free next
    to an obstacle (carrying the object beside the table, or beside a door it swung
    open) may find its own cell walled in; the full kinematic check still decides.
    Where no evenly-turning route is free, the same paths are tried turning in place
    at their ends only (:func:`turning_in_place`)."""
    start = np.asarray(start, dtype=float)
    goal = np.asarray(goal, dtype=float).copy()
    goal[2] = start[2] + (goal[2] - start[2] + math.pi) % (2 * math.pi) - math.pi
    checker.allow()
    if route_free(checker, [start, goal], arm):
        return [goal]
    robot = robot_points(checker, start, arm)
    lo = np.minimum(start[:2], goal[:2]) - MARGIN
    shape = np.ceil((np.maximum(start[:2], goal[:2]) + MARGIN - lo) / CELL).astype(int) + 1
    blocked = occupancy(checker, lo, shape, robot)
    paths = [[start[:2], goal[:2]]]  # the straight segment, then the grid's paths
    for escape in (0.0, float(robot[:, 0].max()) + CLEARANCE):
        route = grid_route(blocked, lo, start, goal, escape)
        if route is None:
            continue
        if route_free(checker, [start, *route], arm):
            return route
        paths.append([start[:2], *[p[:2] for p in route]])
    # (Only now: where an evenly-turning route is free, it stays the route.)
    headings = turn_headings(checker, start, goal, arm)
    for path in paths:
        route = turning_in_place(checker, path, start, goal, arm, headings)
        if route is not None:
            return route
    return None


def turn_headings(
    checker: ContactChecker, start: np.ndarray, goal: np.ndarray, arm: np.ndarray
) -> np.ndarray:
    """The headings [rad] (ascending, every :data:`TURN` from the start's yaw) the
    robot can turn to in place at ``start`` and from which it can turn in place to the
    goal's yaw at ``goal`` (:func:`turn_room`, within half a turn beyond either yaw)."""
    span = (min(start[2], goal[2]) - math.pi, max(start[2], goal[2]) + math.pi)
    a0, a1 = turn_room(checker, start, arm, span)
    b0, b1 = turn_room(checker, goal, arm, span)
    # (1e-9: the start's room ends on this grid of headings, but for rounding.)
    k0 = math.ceil((max(a0, b0) - start[2]) / TURN - 1e-9)
    k1 = math.floor((min(a1, b1) - start[2]) / TURN + 1e-9)
    return start[2] + TURN * np.arange(k0, k1 + 1)


def turning_in_place(
    checker: ContactChecker,
    path: list[np.ndarray],
    start: np.ndarray,
    goal: np.ndarray,
    arm: np.ndarray,
    headings: np.ndarray,
) -> list[np.ndarray] | None:
    """The route (the base poses after ``start``) along ``path`` (points (2,) [m], from
    the start's to the goal's) at one of ``headings`` (ascending, every :data:`TURN`
    [rad]): turning in place at the start to it, driving the whole path at it, turning
    in place at the goal to the goal's yaw. Of the headings whose route is free, the
    one with the most free headings on its tighter side (up to :data:`HEADING_ROOM`),
    then the least turning; None if none is free."""

    def route(h: float) -> list[np.ndarray]:
        poses = [np.array([*p, h]) for p in path] + [goal]
        # A turn of zero is no waypoint (the driver would stand still for it).
        return [b for a, b in itertools.pairwise([start, *poses]) if not np.allclose(a, b)]

    free = np.array([route_free(checker, [start, *route(h)], arm) for h in headings], bool)
    if not free.any():
        return None
    # The least turning heading that is free borders on one that is not: the arm
    # would graze what it passes, at the resolution of the check, and the base lags
    # its command by a centimetre or so. So room first.
    room = np.minimum(_run(free), _run(free[::-1])[::-1])
    want = round(HEADING_ROOM / TURN)
    turning = np.abs(headings - start[2]) + np.abs(goal[2] - headings)
    best = min(np.flatnonzero(free), key=lambda i: (-min(room[i], want), turning[i]))
    return route(float(headings[best]))


def _run(free: np.ndarray) -> np.ndarray:
    """For each entry of ``free`` (n,), how many entries right before it are free (the
    first's: none; beyond the ends of the headings the robot cannot turn)."""
    out = np.zeros(len(free), dtype=int)
    for i in range(1, len(free)):
        out[i] = out[i - 1] + 1 if free[i - 1] else 0
    return out


def turn_room(
    checker: ContactChecker, pose: np.ndarray, arm: np.ndarray, span: tuple[float, float]
) -> tuple[float, float]:
    """The yaws [rad] (lowest, highest) within ``span`` to which the robot standing at
    ``pose`` (3,) with the arm at ``arm`` turns in place from its yaw touching nothing
    (checked every :data:`TURN`); (yaw, yaw) if it cannot turn either way."""
    x, y, yaw = pose
    ends = []
    for sign, limit in ((-1.0, span[0]), (1.0, span[1])):
        end = yaw
        while sign * (limit - end) > 0.0:
            nxt = end + sign * min(TURN, sign * (limit - end))
            if not checker.free(np.concatenate([[x, y, nxt], arm])):
                break
            end = nxt
        ends.append(end)
    return ends[0], ends[1]


def grid_route(
    blocked: np.ndarray, lo: np.ndarray, start: np.ndarray, goal: np.ndarray, escape: float
) -> list[np.ndarray] | None:
    """The base poses (after ``start``) of the A* route on the grid ``blocked`` (its
    cell (0, 0) at ``lo`` (2,)), shortened by line of sight, the heading turning evenly
    along it; the cells within ``escape`` [m] of the start and the goal count as open
    (their own cells always do). None if the grid has none."""
    shape = np.array(blocked.shape)
    cell = lambda p: tuple(np.clip(np.round((p - lo) / CELL).astype(int), 0, shape - 1))  # noqa: E731
    a, b = cell(start[:2]), cell(goal[:2])
    grid = blocked.copy()
    xs = lo[0] + CELL * np.arange(shape[0])
    ys = lo[1] + CELL * np.arange(shape[1])
    for p in (start, goal):
        grid &= (xs[:, None] - p[0]) ** 2 + (ys[None, :] - p[1]) ** 2 >= escape * escape
    grid[a] = grid[b] = False  # the robot stands there already / will
    path = _astar(grid, a, b)
    if path is None:
        return None
    pts = [lo + CELL * np.array(c, dtype=float) for c in _shortcut(grid, path)]
    pts[0], pts[-1] = start[:2], goal[:2]
    lengths = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    s = lengths / max(lengths[-1], 1e-9)
    route = [
        np.array([*p, start[2] + f * (goal[2] - start[2])]) for p, f in zip(pts, s, strict=True)
    ]
    return route[1:]


def robot_points(checker: ContactChecker, base: np.ndarray, arm: np.ndarray) -> np.ndarray:
    """The robot's geometry (and any carried object's) in posture ``arm``, as points
    (N, 3): horizontal distance from the base centre, height above the floor [m]."""
    m, d = checker.model, checker.data
    checker.free(np.concatenate([base, arm]))  # sets the kinematics
    attached = checker.attached_body
    out = []
    for g in range(m.ngeom):
        b = int(m.geom_bodyid[g])
        collides = m.geom_contype[g] or m.geom_conaffinity[g]
        if (checker.robot[b] or b == attached) and collides:
            p = _points(m, d, g)
            out.append(np.column_stack([np.linalg.norm(p[:, :2] - base[:2], axis=1), p[:, 2]]))
    return np.vstack(out)


def _points(m: mujoco.MjModel, d: mujoco.MjData, g: int) -> np.ndarray:
    """Points bounding geom ``g``, world frame: a mesh's vertices (a round base's
    bounding box corners would stick out by sqrt 2), else its bounding box corners."""
    if int(m.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_MESH):
        mesh = m.geom_dataid[g]
        adr, n = m.mesh_vertadr[mesh], m.mesh_vertnum[mesh]
        R = d.geom_xmat[g].reshape(3, 3)
        return m.mesh_vert[adr : adr + n] @ R.T + d.geom_xpos[g]
    return _corners(m, d, g)


def _corners(m: mujoco.MjModel, d: mujoco.MjData, g: int) -> np.ndarray:
    """The 8 corners (8, 3) of geom ``g``'s bounding box, world frame."""
    center, half = m.geom_aabb[g, :3], m.geom_aabb[g, 3:]
    signs = np.array(list(itertools.product((-1, 1), repeat=3)), dtype=float)
    local = center + signs * half
    R = d.geom_xmat[g].reshape(3, 3)
    return local @ R.T + d.geom_xpos[g]


def occupancy(
    checker: ContactChecker, lo: np.ndarray, shape: np.ndarray, robot: np.ndarray
) -> np.ndarray:
    """Grid cells (shape) whose centre is within the robot's radius at an obstacle's
    heights (``robot``: its points, distance and height) of that obstacle's footprint."""
    m, d = checker.model, checker.data
    blocked = np.zeros(tuple(shape), dtype=bool)
    xs = lo[0] + CELL * np.arange(shape[0])
    ys = lo[1] + CELL * np.arange(shape[1])
    attached = checker.attached_body
    for g in range(m.ngeom):
        b = int(m.geom_bodyid[g])
        if (
            checker.robot[b]
            or b == attached
            or (b == 0 and m.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE)
        ):
            continue
        if not (m.geom_contype[g] or m.geom_conaffinity[g]):
            continue
        c = _corners(m, d, g)
        if c[:, 2].max() < 0.01 or c[:, 2].min() > ROBOT_HEIGHT:
            continue
        band = (robot[:, 1] >= c[:, 2].min() - CLEARANCE) & (
            robot[:, 1] <= c[:, 2].max() + CLEARANCE
        )
        if not band.any():
            continue  # nothing of the robot at this height
        radius = float(robot[band, 0].max()) + CLEARANCE
        (x0, y0), (x1, y1) = c[:, :2].min(axis=0), c[:, :2].max(axis=0)
        dx = np.maximum(0.0, np.maximum(x0 - xs, xs - x1))[:, None]
        dy = np.maximum(0.0, np.maximum(y0 - ys, ys - y1))[None, :]
        blocked |= dx * dx + dy * dy < radius * radius
    return blocked


def _astar(blocked: np.ndarray, a: tuple, b: tuple) -> list[tuple] | None:
    """8-connected A* on the grid from cell ``a`` to cell ``b``; the cells, or None."""
    moves = [(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1) if (i, j) != (0, 0)]
    h = lambda c: math.hypot(c[0] - b[0], c[1] - b[1])  # noqa: E731
    frontier = [(h(a), 0.0, a)]
    came: dict[tuple, tuple | None] = {a: None}
    cost = {a: 0.0}
    while frontier:
        _, g, c = heapq.heappop(frontier)
        if c == b:
            out = [c]
            while came[out[-1]] is not None:
                out.append(came[out[-1]])  # type: ignore[arg-type]
            return out[::-1]
        if g > cost[c]:
            continue
        for i, j in moves:
            n = (c[0] + i, c[1] + j)
            if not (0 <= n[0] < blocked.shape[0] and 0 <= n[1] < blocked.shape[1]) or blocked[n]:
                continue
            ng = g + math.hypot(i, j)
            if ng < cost.get(n, math.inf):
                cost[n], came[n] = ng, c
                heapq.heappush(frontier, (ng + h(n), ng, n))
    return None


def _shortcut(blocked: np.ndarray, path: list[tuple]) -> list[tuple]:
    """The path's cells kept only where the straight line to the next kept cell would
    cross a blocked cell."""
    out = [path[0]]
    k = 0
    while k < len(path) - 1:
        j = len(path) - 1
        while j > k + 1 and not _clear(blocked, path[k], path[j]):
            j -= 1
        out.append(path[j])
        k = j
    return out


def _clear(blocked: np.ndarray, a: tuple, b: tuple) -> bool:
    n = max(abs(b[0] - a[0]), abs(b[1] - a[1])) * 2 + 1
    for t in np.linspace(0.0, 1.0, n):
        c = (round(a[0] + t * (b[0] - a[0])), round(a[1] + t * (b[1] - a[1])))
        if blocked[c]:
            return False
    return True
