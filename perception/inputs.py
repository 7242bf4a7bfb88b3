"""Checking one RGB-D view before the network sees it.

:func:`check_view` turns a head-camera view into a :class:`View` or raises one
:class:`~perception.errors.BadInputError` that names the value and what was expected:

* ``rgb`` must be (H, W, 3) ``uint8``; ``depth`` (H, W) float [m] of the same size;
  H and W multiples of 16 (the network halves the image, then pools three times);
* depth dropouts (NaN, +-inf, zero or negative: what real RGB-D sensors return where
  they measure nothing) are *masked*: they are filled with the nearest valid depth
  for the network's input and left out of every 3D point set. More than
  :data:`MAX_DROPOUT` of the pixels missing is an error, so an all-zero or all-NaN
  depth map never yields a confident answer;
* depth in millimetres is caught: the nearest tenth of the valid pixels lies beyond
  :data:`MAX_NEAR_DEPTH` [m] (a head camera looking at a cabinet on a table sees it
  within 3 m; in millimetres that would read 300 or more);
* ``T_world_camera`` must be a finite (4, 4) rigid transform, ``fovy`` in (0, pi).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from perception.errors import BadInputError

#: Largest share of depth dropouts that is masked rather than refused.
MAX_DROPOUT = 0.5
#: The 10th percentile of valid depth beyond this [m] means the units are wrong.
MAX_NEAR_DEPTH = 30.0


@dataclass(frozen=True)
class View:
    """One checked head-camera view.

    Attributes:
        rgb: (H, W, 3) uint8.
        depth: (H, W) float32 [m], dropouts filled with the nearest valid depth.
        valid: (H, W) bool, False where the sensor returned no depth.
        T_world_camera: (4, 4) camera pose (MuJoCo convention: looks along -z).
        fovy: vertical field of view [rad].
    """

    rgb: np.ndarray
    depth: np.ndarray
    valid: np.ndarray
    T_world_camera: np.ndarray
    fovy: float

    @property
    def dropout(self) -> float:
        """Share of pixels without depth."""
        return float(1.0 - self.valid.mean())


def check_pose(name: str, T: object) -> np.ndarray:
    """``T`` as a float (4, 4) rigid transform, or :class:`BadInputError`."""
    try:
        arr = np.asarray(T, dtype=float)
    except (TypeError, ValueError):
        raise BadInputError(f"{name} must be a 4x4 rigid transform, got {T!r}") from None
    if arr.shape != (4, 4) or not np.all(np.isfinite(arr)):
        raise BadInputError(f"{name} must be a finite 4x4 rigid transform, got {arr!r}")
    R = arr[:3, :3]
    ok = np.allclose(arr[3], (0, 0, 0, 1)) and np.allclose(R.T @ R, np.eye(3), atol=1e-5)
    if not ok or np.linalg.det(R) < 0:
        raise BadInputError(f"{name} must be a rigid transform (rotation, last row 0 0 0 1)")
    return arr


def check_view(rgb: object, depth: object, T_world_camera: object, fovy: object) -> View:
    """Check and clean one view (module docstring); raises :class:`BadInputError`."""
    if not isinstance(rgb, np.ndarray) or rgb.ndim != 3 or rgb.shape[2] != 3:
        got = rgb.shape if isinstance(rgb, np.ndarray) else type(rgb).__name__
        raise BadInputError(f"rgb must be an (H, W, 3) uint8 array, got {got}")
    if rgb.dtype != np.uint8:
        raise BadInputError(f"rgb must be uint8 (0..255), got dtype {rgb.dtype}")
    if not isinstance(depth, np.ndarray) or depth.shape != rgb.shape[:2]:
        got = depth.shape if isinstance(depth, np.ndarray) else type(depth).__name__
        raise BadInputError(f"depth must be an (H, W) = {rgb.shape[:2]} float array [m], got {got}")
    if not np.issubdtype(depth.dtype, np.floating):
        raise BadInputError(f"depth must be a float array in metres, got dtype {depth.dtype}")
    h, w = depth.shape
    if h % 16 or w % 16:
        raise BadInputError(f"image height and width must be multiples of 16, got {h}x{w}")
    if isinstance(fovy, bool) or not isinstance(fovy, int | float | np.floating):
        raise BadInputError(f"fovy must be a number in (0, pi) [rad], got {fovy!r}")
    if not 0.0 < float(fovy) < math.pi:
        raise BadInputError(f"fovy must be in (0, pi) [rad], got {fovy!r}")
    T = check_pose("T_world_camera", T_world_camera)
    d = depth.astype(np.float32)
    valid = np.isfinite(d) & (d > 0.0)
    share = 1.0 - float(valid.mean())
    if share > MAX_DROPOUT:
        raise BadInputError(
            f"{share:.0%} of the depth pixels are missing (NaN, inf or <= 0); at most "
            f"{MAX_DROPOUT:.0%} can be masked"
        )
    near = float(np.percentile(d[valid], 10))
    if near > MAX_NEAR_DEPTH:
        raise BadInputError(
            f"depth must be in metres: its 10th percentile is {near:.4g}, beyond "
            f"{MAX_NEAR_DEPTH} m (millimetres?)"
        )
    if share > 0.0:  # fill each dropout with its nearest valid pixel's depth
        idx = ndimage.distance_transform_edt(~valid, return_distances=False, return_indices=True)
        d = d[idx[0], idx[1]]
    return View(rgb, d, valid, T, float(fovy))
