"""Bad input to perception: one clear error or a documented fallback, never a confident
hallucination (issue 10, item 7)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from perception.errors import BadInputError, NoCabinetError, PerceptionError
from perception.fusion import fuse
from perception.inputs import MAX_DROPOUT, check_view
from strug_manip.world.perception_data import ViewRanges, render_cabinet, render_episode

WEIGHTS = Path(__file__).resolve().parents[1] / "models" / "perception" / "articulation_net.pt"
FOVY = math.radians(45.0)


@pytest.fixture(scope="module")
def frame():
    v = render_episode(1, views=1)[0]
    return v.rgb, v.depth, v.T_world_camera, v.fovy


@pytest.mark.parametrize(
    ("mutate", "match"),
    [
        (lambda r, d, T, f: (r[..., :2], d, T, f), "rgb must be an \\(H, W, 3\\) uint8"),
        (lambda r, d, T, f: (r.astype(float) / 255, d, T, f), "rgb must be uint8"),
        (lambda r, d, T, f: (r, d[:-1], T, f), "depth must be an \\(H, W\\)"),
        (lambda r, d, T, f: (r, (d * 1000).astype(np.uint16), T, f), "depth must be a float"),
        (lambda r, d, T, f: (r, d * 1000.0, T, f), "millimetres"),
        (lambda r, d, T, f: (r, np.zeros_like(d), T, f), "100% of the depth pixels are missing"),
        (lambda r, d, T, f: (r, np.full_like(d, np.nan), T, f), "missing"),
        (lambda r, d, T, f: (r, np.full_like(d, np.inf), T, f), "missing"),
        (lambda r, d, T, f: (r[:200], d[:200], T, f), "multiples of 16"),
        (lambda r, d, T, f: (r, d, T[:3], f), "T_world_camera must be a finite 4x4"),
        (lambda r, d, T, f: (r, d, np.full((4, 4), np.nan), f), "T_world_camera must be a finite"),
        (lambda r, d, T, f: (r, d, 2 * T, f), "rigid transform"),
        (lambda r, d, T, f: (r, d, T, 45.0), "fovy must be in \\(0, pi\\)"),
        (lambda r, d, T, f: (r, d, T, "wide"), "fovy must be a number"),
        (lambda r, d, T, f: ([[1, 2, 3]], d, T, f), "rgb must be an"),
    ],
)
def test_malformed_views_get_one_clear_error(frame, mutate, match) -> None:
    with pytest.raises(BadInputError, match=match):
        check_view(*mutate(*frame))


def test_errors_belong_to_the_stacks_hierarchy() -> None:
    assert issubclass(BadInputError, PerceptionError) and issubclass(NoCabinetError, ValueError)


def test_dropouts_are_masked_and_filled(frame) -> None:
    rgb, depth, T, fovy = frame
    rng = np.random.default_rng(0)
    d = depth.copy()
    holes = rng.random(d.shape) < 0.11
    d[holes] = np.nan
    d[rng.random(d.shape) < 0.02] = 0.0
    d[rng.random(d.shape) < 0.02] = -np.inf
    v = check_view(rgb, d, T, fovy)
    assert np.isfinite(v.depth).all() and (v.depth > 0).all()
    assert not v.valid[holes].any() and 0.13 < v.dropout < 0.17
    # Filled with a neighbour's depth: close to the truth almost everywhere.
    assert np.median(np.abs(v.depth[holes] - depth[holes])) < 0.01
    d[rng.random(d.shape) < MAX_DROPOUT] = np.nan
    with pytest.raises(BadInputError, match="at most 50% can be masked"):
        check_view(rgb, d, T, fovy)


@pytest.mark.skipif(not WEIGHTS.exists(), reason="no trained weights in models/perception")
def test_an_empty_table_is_no_cabinet() -> None:
    """Views of the scene without its cabinet: no part is reported, fusion refuses."""
    from perception.parts import Perceiver

    perceiver = Perceiver()
    views = render_cabinet(5, views=3, ranges=ViewRanges(empty_prob=1.0))
    parts = [
        perceiver.perceive(check_view(v.rgb, v.depth, v.T_world_camera, v.fovy)) for v in views
    ]
    assert not any(p.sees_cabinet for p in parts)
    assert sum(len(p.instances) for p in parts) <= 1
    with pytest.raises(NoCabinetError, match="no cabinet in view"):
        fuse(parts)


@pytest.mark.skipif(not WEIGHTS.exists(), reason="no trained weights in models/perception")
def test_nan_dropouts_keep_the_parts(frame) -> None:
    """One depth pixel in nine missing: the same parts are found, every 3D point finite."""
    from perception.parts import Perceiver

    perceiver = Perceiver()
    rgb, depth, T, fovy = frame
    clean = perceiver.perceive(check_view(rgb, depth, T, fovy))
    d = depth.copy()
    d[np.random.default_rng(1).random(d.shape) < 1 / 9] = np.nan
    holey = perceiver.perceive(check_view(rgb, d, T, fovy))
    assert abs(len(holey.instances) - len(clean.instances)) <= 1
    assert all(np.isfinite(i.points).all() for i in holey.instances)
    assert np.isfinite(holey.cabinet_points).all()
