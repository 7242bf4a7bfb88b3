"""A probe's evidence in the head camera: after PullH the point cloud tells a drawer from a
door.

The robot looks at the closed cabinet from where it starts, pulls a part's handle 4 cm
out (:class:`~strug_manip.control.skills.PullH`), stows, and looks again from the same
pose. The part is where the depth changed. Each kinematic hypothesis moves the part's
before-points: a drawer translates them along the front's normal (by 0-10 cm), a door
turns them about one edge of its cell (left, right, top or bottom; by -0.4..0.4 rad).
A hypothesis explains the after-cloud when the moved points lie on it: its score is a
quantile of their distances to the nearest after-point (a *quantile Hausdorff*
distance: robust to the pixels the motion revealed or hid). The kind whose best
hypothesis scores lowest is the answer; it must be the true one, by :data:`MARGIN`.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from strug_manip.control import PullH, handle_grasps
from strug_manip.geometry import axis_angle
from strug_manip.world import ManipulationWorld, SceneConfig
from strug_manip.world.sim import depth_to_points
from strug_manip.world.views import aim_head

#: Depth change that marks a pixel as moved [m].
CHANGED = 0.01
#: Quantile of the nearest-neighbour distances that scores a hypothesis.
QUANTILE = 0.8
#: The true kind's best hypothesis must explain the after-cloud this much better [m]
#: (the right model itself scores about a centimetre: pixels the motion revealed or hid,
#: the inside of a pulled drawer).
MARGIN = 0.004
#: At most this many moved points are scored (subsampled evenly).
MAX_POINTS = 400


def _nearest(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of each point of ``a`` (n, 3) to its nearest point of ``b`` (m, 3)."""
    out = np.empty(len(a))
    for i in range(0, len(a), 100):
        d = np.linalg.norm(a[i : i + 100, None, :] - b[None, :, :], axis=2)
        out[i : i + 100] = d.min(axis=1)
    return out


def _best(score, lo: float, hi: float, n: int = 11, rounds: int = 3) -> float:
    """The least ``score(x)`` over ``x`` in [lo, hi]: a grid of ``n``, refined ``rounds``
    times around its best point."""
    best = np.inf
    for _ in range(rounds):
        xs = np.linspace(lo, hi, n)
        vals = [score(x) for x in xs]
        k = int(np.argmin(vals))
        best = min(best, vals[k])
        step = xs[1] - xs[0]
        lo, hi = xs[k] - step, xs[k] + step
    return float(best)


def _score(moved: np.ndarray, after: np.ndarray) -> float:
    return float(np.quantile(_nearest(moved, after), QUANTILE))


def probe_evidence(frames, part, T_world_cabinet) -> dict[str, float]:
    """The best score [m] of the drawer and the door hypotheses, given the before and
    after frames of a probe on ``part`` (its cell's geometry in the cabinet frame)."""
    before, after = frames
    changed = np.abs(after.depth - before.depth) > CHANGED
    changed &= (before.depth > 0) & (after.depth > 0)
    assert changed.sum() > 50, "the probe moved nothing the camera sees"
    pts_b, pix_b = depth_to_points(before.depth, before.T_world_camera, before.fovy)
    pts_a, _ = depth_to_points(after.depth, after.T_world_camera, after.fovy)
    P = pts_b[changed.reshape(-1)[pix_b]]
    P = P[np.linspace(0, len(P) - 1, min(MAX_POINTS, len(P))).astype(int)]
    lo, hi = P.min(axis=0) - 0.15, P.max(axis=0) + 0.15
    Q = pts_a[np.all((pts_a > lo) & (pts_a < hi), axis=1)]
    Q = Q[np.linspace(0, len(Q) - 1, min(4 * MAX_POINTS, len(Q))).astype(int)]
    R, t = T_world_cabinet[:3, :3], T_world_cabinet[:3, 3]
    normal = R @ np.array([1.0, 0.0, 0.0])
    drawer = _best(lambda s: _score(P + s * normal, Q), 0.0, 0.10)
    c, (w, h) = part.cell_center, part.cell_size
    up, side = np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0])
    edges = [  # (a point on the hinge line, its axis), cabinet frame
        (c - 0.5 * w * side, up),
        (c + 0.5 * w * side, up),
        (c - 0.5 * h * up, side),
        (c + 0.5 * h * up, side),
    ]
    door = np.inf
    for o, a in edges:
        ow, aw = R @ o + t, R @ a
        door = min(door, _best(lambda th, ow=ow, aw=aw: _score(
            (P - ow) @ axis_angle(aw, th).T + ow, Q), -0.4, 0.4))  # fmt: skip
    return {"drawer": drawer, "door": door}


@pytest.mark.parametrize(
    ("seed", "kind"), [(11, "drawer"), (11, "door"), (16, "drawer"), (16, "door")]
)
def test_point_cloud_after_pull_h_tells_drawer_from_door(ctx, seed: int, kind: str) -> None:
    world = ManipulationWorld(SceneConfig(cabinet_seed=seed, cabinet_kinds=(kind,)))
    spec, T = world.scene.cabinet_spec, world.scene.T_world_cabinet
    part = next(
        p
        for p in spec.movable_parts
        if p.handle != "none" and (kind == "drawer" or abs(p.axis[2]) > 0.7)
    )
    # The head looks at the part's handle (the robot stands where it starts).
    aim_head(world, part.handle_at(0.0, T))
    robot0 = world.robot_qpos()
    before = world.render()
    out = None
    for g in handle_grasps(part, 0.0, T):
        world.reset()
        out = PullH(g).run(world, ctx=ctx)
        if out.status != "ik_infeasible":
            break
    assert out is not None and out.ok, out.summary() if out else "no grasp"
    moved = abs(out.motion_of(part.joint))
    assert moved > (0.01 if kind == "drawer" else 0.03), out.summary()
    # Look again from where the robot looked before (it drives back there).
    m, d = world.model, world.data
    for name, q in robot0.items():
        d.qpos[m.jnt_qposadr[m.joint(name).id]] = q
    mujoco.mj_forward(m, d)
    after = world.render()
    scores = probe_evidence((before, after), part, T)
    truth, other = ("drawer", "door") if kind == "drawer" else ("door", "drawer")
    assert scores[truth] + MARGIN < scores[other], scores
    world.close()
