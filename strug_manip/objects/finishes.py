"""Surface finishes of generated furniture: wood-grain textures, drawn per index.

Real storage furniture wears wood grain, veneer and painted finishes (PartNet-Mobility's
objects carry photographs of them as textures); the generator's plain cabinets are flat
colours. A finish here is a greyscale grain image that a material *tints*: MuJoCo
multiplies a material's texture by its ``rgba``, so one image serves oak, walnut or a
painted board alike, and a cabinet's colours stay in its :class:`CabinetSpec` as before.

``grain_image(k)`` draws the ``k``-th image from ``np.random.default_rng(k)``, bit for
bit the same on every machine; :func:`grain_texture` writes it once as a PNG into the
cache folder (the images are data derived from code, not shipped) and returns its path,
which the URDF writer puts in a ``<material><texture filename>``.
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np

from planners.errors import ConfigError
from strug_manip.cache import cache_root

#: How many grain images there are (``grain_0`` ... ``grain_7``).
GRAIN_COUNT = 8
#: Image side [px]: 256 px over :data:`GRAIN_METRES` keeps a 3 mm grain line at least
#: two pixels wide, more than a head-camera pixel covers at 1 m (about 3.5 mm).
GRAIN_PIXELS = 256
#: Metres of board one image covers (MuJoCo repeats it: ``texuniform``).
GRAIN_METRES = 0.5


def grain_image(k: int, size: int = GRAIN_PIXELS) -> np.ndarray:
    """The ``k``-th wood-grain image: luminance in [0.55, 1], grain along the image's
    rows (texture u), shape (size, size, 3) uint8.

    Growth rings are sines across the grain whose phase wanders (a sum of a few random
    low-frequency waves), with fine pores along the grain; contrast and ring density
    vary with ``k`` from nearly plain (painted, fine veneer) to strongly figured.
    """
    if not 0 <= int(k) < GRAIN_COUNT:
        raise ConfigError(f"grain index must be in [0, {GRAIN_COUNT}), got {k!r}")
    rng = np.random.default_rng(int(k))
    v, u = np.mgrid[0:size, 0:size].astype(float) / size  # v across the grain, u along it
    warp = np.zeros_like(u)
    for _ in range(4):  # periodic in both axes: the image tiles without seams
        fu, fv = rng.integers(1, 4), rng.integers(0, 3)
        warp += rng.uniform(0.2, 0.6) * np.sin(2 * np.pi * (fu * u + fv * v + rng.random()))
    rings = np.sin(2 * np.pi * (rng.integers(12, 40) * v + 0.8 * warp))
    pores = rng.normal(size=(size, 1)) * np.ones((1, size))  # streaks along the grain
    pores = cv2.GaussianBlur(pores, (0, 0), sigmaX=8.0, sigmaY=0.7)
    contrast = 0.015 + 0.055 * k / (GRAIN_COUNT - 1)
    lum = 0.86 + contrast * rings + 0.5 * contrast * pores / max(float(pores.std()), 1e-9)
    grey = np.clip(lum, 0.55, 1.0)
    return np.repeat((255 * grey).astype(np.uint8)[:, :, None], 3, axis=2)


def grain_texture(name: str, cache_dir: Path | None = None) -> Path:
    """The PNG file of the finish ``name`` (``grain_<k>``), written into ``cache_dir``
    (default: ``textures/`` in :func:`strug_manip.cache.cache_root`) on first use."""
    if not name.startswith("grain_") or not name[6:].isdigit():
        valid = ", ".join(f"grain_{k}" for k in range(GRAIN_COUNT))
        raise ConfigError(f"unknown finish {name!r}; valid: {valid}")
    k = int(name[6:])
    out = (cache_dir or cache_root()) / "textures" / f"{name}_v1.png"
    if not out.is_file():
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = out.with_name(f"{out.stem}.{os.getpid()}.tmp.png")
        cv2.imwrite(str(tmp), grain_image(k))
        os.replace(tmp, out)
    return out
