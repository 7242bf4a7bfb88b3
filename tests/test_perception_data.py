"""Labelled RGB-D views for perception: the labels agree with MuJoCo's own geometry."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from planners.errors import ConfigError
from strug_manip.world.perception_data import (
    CabinetViewer,
    ViewRanges,
    load_views,
    render_cabinet,
    save_views,
    shard_path,
)
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld, depth_to_points


@pytest.fixture(scope="module", params=[3, 25])  # drawers and a panel; doors and a flap
def viewer(request):
    world = ManipulationWorld(SceneConfig(cabinet_seed=request.param))
    yield CabinetViewer(world)
    world.close()


def _part_geoms(viewer: CabinetViewer, names: tuple[str, ...], k: int) -> list[int]:
    """Geoms of part k found from the URDF's link names (independently of the viewer)."""
    world, m = viewer.world, viewer.world.model
    obj, pre = world.scene.cabinet, world.scene.cabinet_prefix
    links = {obj.root, "link_0"} if k == 0 else {obj.joint(names[k - 1]).child}
    return [g for g in range(m.ngeom) if m.body(m.geom_bodyid[g]).name in {pre + x for x in links}]


def test_joint_labels_match_the_generators_ground_truth(viewer) -> None:
    """Origins and axes agree with the generator's part specs (object frame)."""
    spec = viewer.world.scene.cabinet_spec
    by_joint = {p.joint: p for p in spec.parts}
    rng = np.random.default_rng(0)
    movable = 0
    for _ in range(4):
        v = viewer.view(rng)
        R, t = v.T_camera_cabinet[:3, :3], v.T_camera_cabinet[:3, 3]
        for k, name in enumerate(v.joint_names):
            part = by_joint[name]
            assert v.joint_type[k] == {"fixed": 0, "prismatic": 1, "revolute": 2}[part.joint_type]
            assert v.semantic[k] == part.semantic
            np.testing.assert_allclose(v.origin_cam[k], R @ part.origin + t, atol=1e-6)
            if v.joint_type[k] == 0:
                assert not v.axis_cam[k].any() and v.q[k] == 0.0
                continue
            np.testing.assert_allclose(v.axis_cam[k], R @ part.axis, atol=1e-6)
            assert part.lower <= v.q[k] <= part.upper + 1e-9
            movable += 1
    assert movable >= 4


def test_labelled_pixels_lie_on_their_part(viewer) -> None:
    """Every pixel labelled part k deprojects into one of part k's geoms (5 mm margin)."""
    m, d = viewer.world.model, viewer.world.data
    v = viewer.view(np.random.default_rng(1))
    pts, idx = depth_to_points(v.depth, v.T_world_camera, v.fovy)
    labels = v.part_map.reshape(-1)[idx]
    checked = 0
    for k in range(0, len(v.joint_names) + 1):
        mine = pts[labels == k]
        if len(mine) < 50:
            continue
        inside = np.zeros(len(mine), dtype=bool)
        for g in _part_geoms(viewer, v.joint_names, k):
            local = (mine - d.geom_xpos[g]) @ d.geom_xmat[g].reshape(3, 3)
            centre, half = m.geom_aabb[g, :3], m.geom_aabb[g, 3:]
            inside |= np.all(np.abs(local - centre) <= half + 0.005, axis=1)
        assert inside.mean() > 0.995, (k, inside.mean())
        checked += 1
    assert checked >= 2
    assert v.pixels.sum() + (v.part_map == 0).sum() == (v.part_map >= 0).sum()


def test_the_head_looks_at_the_cabinet(viewer) -> None:
    rng = np.random.default_rng(2)
    for _ in range(5):
        v = viewer.view(rng)
        assert (v.part_map >= 0).mean() > 0.1
        # The cabinet's centre is near the image centre: within a quarter of the width.
        xs = np.nonzero(v.part_map >= 0)[1]
        assert abs(xs.mean() - v.part_map.shape[1] / 2) < v.part_map.shape[1] / 4


def test_handle_pixels_are_handle_geoms(viewer) -> None:
    """The pull-affordance labels: handle pixels lie on their part and on handle geoms."""
    m, d = viewer.world.model, viewer.world.data
    rng = np.random.default_rng(3)
    seen = 0
    for _ in range(4):
        v = viewer.view(rng)
        assert v.handle_map.dtype == bool and v.handle_map.shape == v.part_map.shape
        assert np.all(v.part_map[v.handle_map] >= 1)  # handles belong to parts
        pts, idx = depth_to_points(v.depth, v.T_world_camera, v.fovy)
        mine = pts[v.handle_map.reshape(-1)[idx]]
        if len(mine) < 10:
            continue
        handles = [g for g in range(m.ngeom) if "/handle" in m.geom(g).name]
        inside = np.zeros(len(mine), dtype=bool)
        for g in handles:
            local = (mine - d.geom_xpos[g]) @ d.geom_xmat[g].reshape(3, 3)
            centre, half = m.geom_aabb[g, :3], m.geom_aabb[g, 3:]
            inside |= np.all(np.abs(local - centre) <= half + 0.003, axis=1)
        assert inside.mean() > 0.99
        seen += 1
    has_handles = any(p.handle != "none" for p in viewer.world.scene.cabinet_spec.parts)
    assert seen >= 1 if has_handles else seen == 0


def test_empty_views_show_no_cabinet() -> None:
    views = render_cabinet(7, views=3, ranges=ViewRanges(empty_prob=1.0))
    for v in views:
        assert (v.part_map == -1).all() and not v.handle_map.any() and v.pixels.sum() == 0
        assert np.isfinite(v.depth).all()


def test_look_around_sees_one_state_from_the_standard_poses() -> None:
    from strug_manip.world.perception_data import render_episode
    from strug_manip.world.views import MAX_VIEWS, look_poses

    views = render_episode(9, views=4)
    assert len(views) == 4
    assert all(np.array_equal(v.q, views[0].q) for v in views)  # the cabinet does not move
    cams = np.stack([v.T_world_camera[:3, 3] for v in views])
    assert np.linalg.norm(cams[1] - cams[2]) > 0.4  # seen from both sides
    assert all((v.part_map >= 0).mean() > 0.05 for v in views)
    world = ManipulationWorld(SceneConfig(cabinet_seed=9))
    try:
        with pytest.raises(ConfigError, match=r"k \(views\) must be an integer in 1\.\."):
            look_poses(world, MAX_VIEWS + 1)
    finally:
        world.close()


def test_same_seed_same_views_bit_for_bit() -> None:
    a, b = render_cabinet(7, views=2), render_cabinet(7, views=2)
    for va, vb in zip(a, b, strict=True):
        assert np.array_equal(va.rgb, vb.rgb) and np.array_equal(va.part_map, vb.part_map)
        assert np.array_equal(va.origin_cam, vb.origin_cam)
    c = render_cabinet(8, views=1)
    assert not np.array_equal(a[0].depth, c[0].depth)


def test_dataset_shard_round_trip(tmp_path: Path) -> None:
    views = render_cabinet(11, views=2)
    first = shard_path(tmp_path, 11)
    save_views(first, views)
    data = load_views(first)
    n_parts = len(data["joint_names"])
    assert data["rgb"].shape == (2, 240, 320, 3) and data["part_map"].shape == (2, 240, 320)
    assert data["axis_cam"].shape == (2, n_parts, 3) and data["fovy"].shape == (2,)
    assert np.array_equal(data["rgb"][1], views[1].rgb)
    assert not list(tmp_path.glob("*.tmp"))  # written atomically


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"distance": (1.0, 0.5)}, "distance must be"),
        ({"distance": (0.0, 0.5)}, "distance must be > 0"),
        ({"open_prob": 1.5}, "open_prob"),
        ({"open_frac": (0.5, 1.2)}, "open_frac"),
        ({"empty_prob": -0.1}, "empty_prob"),
        ({"aim_jitter": float("nan")}, "aim_jitter"),
    ],
)
def test_view_ranges_are_validated(kwargs, match) -> None:
    with pytest.raises(ConfigError, match=match):
        ViewRanges(**kwargs)
