"""The one timing law (:mod:`strug_manip.control.timing`) and the joint driver that
follows it: durations respect the speed limits, the samples start one step from the
start, end exactly at the end and advance monotonically along the path."""

from __future__ import annotations

import numpy as np
import pytest

from strug_manip.control import timing
from strug_manip.control.driver import JointDriver
from strug_manip.robot.fetch import ARM_TORSO_JOINTS, TUCK, speed_limits
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

LIMITS = np.array([0.1, 1.0, 2.0])
#: A polyline whose segments each have another slowest coordinate, (4, 3).
PATH = np.array([[0.0, 0.0, 0.0], [0.05, 0.2, 0.0], [0.05, 0.2, 1.5], [0.2, -0.3, 1.0]])
DT = 0.002


def needed(points: np.ndarray, limits: np.ndarray) -> float:
    """Sum over the segments of the largest |step| / limit [s]."""
    return float((np.abs(np.diff(points, axis=0)) / limits).max(axis=1).sum())


@pytest.mark.parametrize("asked", [0.0, 1.0, 10.0])
def test_duration_is_the_longer_of_the_asked_and_the_speed_limited(asked: float) -> None:
    tau = needed(PATH, LIMITS)
    T = timing.duration(PATH, LIMITS, asked)
    assert pytest.approx(max(asked, tau + min(tau, timing.RAMP_TIME))) == T
    assert asked <= T
    # A short motion is all ramp: twice the time at the limits.
    short = PATH[:2] * 0.01
    assert timing.duration(short, LIMITS, 0.0) == pytest.approx(2 * needed(short, LIMITS))
    assert timing.duration(PATH[:1], LIMITS, 0.7) == 0.7  # nothing to move


@pytest.mark.parametrize("stretch", [1.0, 1.7])
def test_samples_respect_the_limits_and_end_at_the_endpoint(stretch: float) -> None:
    T = stretch * timing.duration(PATH, LIMITS, 0.0)
    qs = timing.samples(PATH, T, DT, LIMITS)
    assert qs.shape == (round(T / DT), PATH.shape[1])
    np.testing.assert_allclose(qs[-1], PATH[-1], atol=1e-12)
    # The first sample is one step from the start; no coordinate ever exceeds its limit.
    steps = np.abs(np.diff(np.vstack([PATH[:1], qs]), axis=0)) / DT
    assert np.all(steps <= LIMITS * (1 + 1e-9)), (steps.max(axis=0), LIMITS)
    # At the speed-limited duration the slowest coordinate does reach its limit.
    if stretch == 1.0:
        assert np.max(steps / LIMITS) > 0.95


def test_progress_is_monotone_from_rest_to_rest() -> None:
    T = 2.0
    t = np.linspace(0.0, T, 2001)
    s = timing.progress(t, T)
    assert s[0] == 0.0 and s[-1] == 1.0
    assert np.all(np.diff(s) >= 0)
    v = np.diff(s) / np.diff(t)
    assert v[0] < 0.01 * v.max() and v[-1] < 0.01 * v.max()  # starts and ends at rest
    seg, frac = timing.schedule(PATH, T, DT, LIMITS)
    where = seg + frac
    assert np.all(np.diff(where) >= -1e-12)  # never backwards along the path
    assert where[-1] == pytest.approx(len(PATH) - 1)
    assert np.all((frac >= 0) & (frac <= 1))
    # Each segment's share of the motion follows the time it needs at the limits.
    per = (np.abs(np.diff(PATH, axis=0)) / LIMITS).max(axis=1)
    knots = np.concatenate([[0.0], np.cumsum(per) / per.sum()])
    s = timing.progress(np.arange(1, len(seg) + 1) * T / len(seg), T)
    np.testing.assert_allclose(knots[seg] + frac * np.diff(knots)[seg], s, atol=1e-9)


def test_the_driver_times_its_motions_with_the_law() -> None:
    world = ManipulationWorld(SceneConfig(cabinet_seed=11, cabinet_kinds=("drawer",)))
    drv = JointDriver(world)
    goal = np.array(TUCK) + np.array([0.05, 0.0, 0.0, -0.1, 0.0, 0.0, 0.0, 0.5])
    start = drv.arm_cmd.copy()
    T = drv.follow([goal], 0.3)
    vmax = speed_limits(world.model, ARM_TORSO_JOINTS)
    assert pytest.approx(timing.duration(np.array([start, goal]), vmax, 0.3)) == T
    assert drv.elapsed == pytest.approx(T, abs=world.model.opt.timestep)
    np.testing.assert_array_equal(drv.arm_cmd, goal)
    drv.hold(0.5)
    assert np.max(np.abs(drv.q - goal)) < 0.01
    times, qpos = drv.recording()
    assert np.all(np.diff(times) > 0) and len(qpos) == len(times)
    world.close()
