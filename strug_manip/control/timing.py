"""The one timing law of every executed motion: a smooth trapezoid along a polyline.

A motion is a polyline of points (joint vectors, or a base pose) from where the command
is now. Each segment gets a share of the motion proportional to the time it needs at
the speed limits (the largest ``|step| / limit`` over its coordinates: ``tau`` in all),
and the whole path is traversed under one speed profile that starts and ends at rest
and does not stop at the waypoints: the path speed rises as a half cosine over
:data:`RAMP_TIME` (no jump in acceleration), cruises, and falls back the same way. Its
duration is the longer of

- the duration asked for (e.g. a Cartesian length over a Cartesian speed), and
- the time for which no coordinate exceeds its speed limit: ``tau + min(tau,
  RAMP_TIME)`` (the cruise speed is reached after the ramp; a motion shorter than the
  ramp is all ramp).

The full robot (:class:`~strug_manip.control.driver.JointDriver`) and the planning twin
(:mod:`~strug_manip.control.twin_body`) time their motions with it, so that a skill takes
the same simulated time in both.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

#: Time the path speed takes to rise from rest to its cruise, and to fall back [s]:
#: gentle enough that the arm's inertia torques stay within its effort limits.
RAMP_TIME = 0.5


def progress(t: np.ndarray, T: float) -> np.ndarray:
    """Progress ``s`` in [0, 1] along a motion of duration ``T`` [s] at times ``t`` [s]."""
    t = np.clip(np.asarray(t, dtype=float), 0.0, T)
    ta = min(RAMP_TIME, 0.5 * T)
    v = 1.0 / (T - ta)  # cruise speed, in path fraction per second

    def ramp(u: np.ndarray) -> np.ndarray:  # distance after u in [0, ta] of a ramp
        return v * (0.5 * u - ta / (2 * np.pi) * np.sin(np.pi * u / ta))

    s = v * (0.5 * ta + (t - ta))
    s = np.where(t < ta, ramp(np.minimum(t, ta)), s)
    s = np.where(t > T - ta, 1.0 - ramp(np.minimum(T - t, ta)), s)
    return np.clip(s, 0.0, 1.0)


def _segment_times(points: np.ndarray, speed_limits: np.ndarray) -> np.ndarray:
    """Time each segment of ``points`` (N + 1, n) needs at the speed limits, (N,) [s]."""
    return (np.abs(np.diff(points, axis=0)) / speed_limits).max(axis=1)


def duration(points: np.ndarray, speed_limits: np.ndarray, seconds: float) -> float:
    """Time [s] to traverse the polyline ``points`` (N + 1, n) (the first row: where the
    motion starts): at least ``seconds``, and long enough that no coordinate exceeds its
    speed limit ``speed_limits`` (n,) [unit/s]."""
    pts = np.asarray(points, dtype=float)
    if len(pts) < 2:
        return float(seconds)
    tau = float(_segment_times(pts, speed_limits).sum())
    return max(float(seconds), tau + min(tau, RAMP_TIME))


def schedule(
    points: np.ndarray, seconds: float, dt: float, speed_limits: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Where along the polyline ``points`` (N + 1, n) the motion is every ``dt`` [s] of
    ``seconds`` [s] (the first sample one ``dt`` after the start, the last at the end):
    ``(segment index (T,), fraction within it (T,))``. Segments share the time as
    :func:`duration` assumes (evenly where ``speed_limits`` is None or nothing moves)."""
    pts = np.asarray(points, dtype=float)
    n = max(1, round(seconds / dt))
    s = progress(np.arange(1, n + 1) * (seconds / n), seconds)
    if len(pts) < 2:
        return np.zeros(n, dtype=int), np.ones(n)
    w = None if speed_limits is None else _segment_times(pts, speed_limits)
    if w is None or w.sum() <= 0:
        w = np.ones(len(pts) - 1)
    knots = np.concatenate([[0.0], np.cumsum(w) / w.sum()])
    i = np.clip(np.searchsorted(knots, s, side="right") - 1, 0, len(pts) - 2)
    span = np.maximum(knots[i + 1] - knots[i], 1e-12)
    return i, np.clip((s - knots[i]) / span, 0.0, 1.0)


def samples(
    points: np.ndarray, seconds: float, dt: float, speed_limits: np.ndarray | None = None
) -> np.ndarray:
    """The motion through ``points`` (N + 1, n) in ``seconds`` [s], sampled every ``dt``
    [s] (:func:`schedule`): shape (round(seconds / dt), n)."""
    pts = np.asarray(points, dtype=float)
    if len(pts) < 2:
        return np.repeat(pts[:1], max(1, round(seconds / dt)), axis=0)
    i, frac = schedule(pts, seconds, dt, speed_limits)
    return pts[i] + frac[:, None] * (pts[i + 1] - pts[i])


def polyline(start: np.ndarray, path: Sequence[np.ndarray]) -> np.ndarray:
    """``start`` followed by ``path``, as one (N + 1, n) array."""
    return np.vstack([np.asarray(start, dtype=float), *[np.asarray(p, float) for p in path]])
