"""The one geometry module and the one bounded cache."""

from __future__ import annotations

import math

import mink
import numpy as np
import pytest

from strug_manip.cache import LRU
from strug_manip.geometry import (
    axis_angle,
    mat_of,
    quat_of,
    quats,
    rotation_angle,
    rpy_matrix,
    slerp,
    x_axes,
)

X, Y, Z = np.eye(3)


def test_rotations_agree_with_mink_to_the_last_bits() -> None:
    rng = np.random.default_rng(0)
    for _ in range(100):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        angle = float(rng.uniform(-3.0, 3.0))
        R = axis_angle(axis, angle)
        np.testing.assert_allclose(R, mink.SO3.exp(axis * angle).as_matrix(), atol=1e-15)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
        np.testing.assert_allclose(mat_of(quat_of(R)), R, atol=1e-15)
        assert rotation_angle(R) == pytest.approx(abs(angle), abs=1e-12)


def test_rpy_is_yaw_pitch_roll_about_fixed_axes() -> None:
    r, p, y = 0.3, -0.7, 1.9
    expected = axis_angle(Z, y) @ axis_angle(Y, p) @ axis_angle(X, r)
    np.testing.assert_allclose(rpy_matrix((r, p, y)), expected, atol=1e-15)
    # PartNet's base joint turns its y-up meshes z-up.
    np.testing.assert_allclose(rpy_matrix((math.pi / 2, 0.0, -math.pi / 2)) @ Y, Z, atol=1e-15)


def test_rotation_angle_is_accurate_near_zero() -> None:
    assert rotation_angle(axis_angle(X, 1e-9)) == pytest.approx(1e-9, rel=1e-6)


def test_slerp_runs_the_short_arc_between_its_ends() -> None:
    qa = quats(np.stack([np.eye(3)]))
    qb = quats(np.stack([axis_angle(Z, 2.0)]))
    for s in (0.0, 0.25, 1.0):
        (q,) = slerp(qa, -qb, np.array([s]))  # -qb: the same rotation, the long way
        np.testing.assert_allclose(mat_of(q), axis_angle(Z, 2.0 * s), atol=1e-12)
        np.testing.assert_allclose(x_axes(q[None])[0], axis_angle(Z, 2.0 * s)[:, 0], atol=1e-12)


def test_lru_keeps_the_most_recently_used_and_counts_hits() -> None:
    cache = LRU(2)
    cache.store("a", 1)
    cache.store("b", 2)
    assert cache.lookup("a") == 1  # "a" is now the most recent
    cache.store("c", 3)  # drops "b", the least recently used
    assert list(cache) == ["a", "c"]
    assert cache.lookup("b") is None
    assert (cache.hits, cache.misses, cache.hit_rate) == (1, 1, 0.5)
    cache.store("a", 4)  # a stored key becomes the most recent
    assert list(cache) == ["c", "a"] and cache["a"] == 4
