"""The point-cloud observation model: how likely the cabinet cloud the head camera sees
after a skill is under each particle's prediction.

The paper's observation function, ``Z(o | s, a) = N(H(o, pcd(f(s, a))), sigma^2)``: the
observed cloud ``o`` against the cloud each particle predicts (its world simulated
through the skill, then rendered from the same camera), compared by a Hausdorff
distance ``H``. The plain Hausdorff distance is the *largest* nearest-neighbour
distance, so one stray pixel (a depth edge, a handle one model has and another lacks)
decides it; here ``H`` is the symmetric **quantile Hausdorff distance**: the
:data:`QUANTILE` quantile of the nearest-neighbour distances from ``o`` to the
prediction and from the prediction to ``o``, the larger of the two (outlier-robust,
as in Huttenlocher et al. 1993's partial Hausdorff distance). The 0.8 quantile, not
0.9: behind a pulled drawer the camera sees into the drawer's box and the cell above
it, whose look depends on sizes no particle can know (box height, depth); those voxels
made up to 15% of a cloud and, at 0.9, put the right belief 12 cm off
(``tools/eval_likelihood.py``).

Vectorised over particles: one KD-tree (scipy's ``cKDTree``) over the observation
answers every particle's points at once, and one KD-tree over all particles' points,
each lifted into its own slab of a fourth coordinate (particle index x
:data:`SLAB` [m], far beyond any scene distance), answers the observation's points
against every particle at once. Clouds are first thinned to one point per
:data:`VOXEL` [m] cube.

``sigma`` (:data:`SIGMA` = 0.01 m, not the paper's 1e-3 m): perception's particles are
never exact copies of the cabinet (board thickness, gaps, drawer boxes and handles are
set to the generator's middle values), so even the particle whose joint is right
predicts a cloud some millimetres off the observation, while a wrong joint after a probe
(a drawer believed a door, a door hinged on the wrong side) leaves the moved front
centimetres to decimetres away. ``sigma`` is set to the size of that irreducible model
error, about 1 cm (the figures measured by ``tools/eval_likelihood.py`` are in the
README): with 1e-3 m a 5 mm board error alone would be a 12.5-nat penalty and one
particle would take all the weight after any observation.

**Heavy tails** (:data:`NU` = 4, a Student-t in ``H / sigma`` instead of the paper's
Gaussian): the model error is not always about 1 cm. A part perception missed or
hallucinated (a door believed where the cabinet has an open cell) puts *every*
particle several centimetres off, and then a Gaussian turns differences between
wrong models into tens of nats: on a held-out shelf (cabinet 9032) all 24 particles
were 4.5-13 cm off after a Pick that moved nothing, and the Gaussian gave one of them
99 % of the weight (an effective sample size of 1.0) on a cloud that said nothing
new. A Student-t with ``nu`` degrees of freedom keeps the Gaussian's core
(``nu -> inf`` is the Gaussian) and makes a 1 cm difference far out in the tail
cost about a nat, not tens; the same cloud leaves an effective sample size of 10.6.
It ranks the particles exactly as the Gaussian does (both fall monotonically in
``H``), so ``tools/eval_likelihood.py``'s rankings are unchanged; after a probe the
right belief (``H`` about 9 mm) gains 1.1 nats over the best wrong one (19 mm)
instead of 1.4.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from perception.errors import BadInputError

#: Quantile of the nearest-neighbour distances.
QUANTILE = 0.8
#: Observation noise of H [m] (module docstring).
SIGMA = 0.01
#: Degrees of freedom of the Student-t in ``H / sigma`` (module docstring; inf: Gaussian).
NU = 4.0
#: Voxel size of the thinning [m].
VOXEL = 0.01
#: Separation of the particles' slabs in the fourth coordinate [m].
SLAB = 1000.0


def _check_cloud(name: str, c: object) -> np.ndarray:
    arr = np.asarray(c, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3 or len(arr) == 0:
        raise BadInputError(
            f"{name} must be a non-empty (N, 3) point cloud [m], got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise BadInputError(f"{name} must be finite (NaN or inf found)")
    return arr


def voxel_thin(points: np.ndarray, voxel: float = VOXEL) -> np.ndarray:
    """One point (the first) per ``voxel`` [m] cube of ``points`` (N, 3), in order."""
    keys = np.floor(points / voxel).astype(np.int64)
    if len(keys) == 0:
        return points[:0]
    # One integer per voxel (a row-major index into the cloud's bounding box): the 1-D
    # unique is several times faster than the row-wise one and keeps the same first
    # points (both sort stably).
    keys -= keys.min(axis=0)
    span = keys.max(axis=0) + 1
    flat = (keys[:, 0] * span[1] + keys[:, 1]) * span[2] + keys[:, 2]
    _, first = np.unique(flat, return_index=True)
    return points[np.sort(first)]


def _segment_quantile(d: np.ndarray, seg: np.ndarray, n_seg: int, q: float) -> np.ndarray:
    """The ``q`` quantile (lower) of ``d`` within each segment id of ``seg`` (all non-empty)."""
    order = np.lexsort((d, seg))
    counts = np.bincount(seg, minlength=n_seg)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    return d[order][starts + np.floor(q * (counts - 1)).astype(int)]


def quantile_hausdorff(
    observed: np.ndarray, predicted: Sequence[np.ndarray], quantile: float = QUANTILE
) -> np.ndarray:
    """Symmetric quantile Hausdorff distance (module docstring) from one observed cloud
    (N, 3) [m] to each predicted cloud (N_i, 3) [m]; returns (M,) [m].

    Raises:
        BadInputError: an empty, non-finite or malformed cloud, or a quantile outside (0, 1].
    """
    if not 0.0 < quantile <= 1.0:
        raise BadInputError(f"quantile must be in (0, 1], got {quantile!r}")
    obs = voxel_thin(_check_cloud("observed", observed))
    preds = [voxel_thin(_check_cloud(f"predicted[{i}]", p)) for i, p in enumerate(predicted)]
    if not preds:
        raise BadInputError("predicted must hold at least one cloud")
    m = len(preds)
    seg = np.concatenate([np.full(len(p), i) for i, p in enumerate(preds)])
    allp = np.concatenate(preds)
    d_po, _ = cKDTree(obs).query(allp)
    h_po = _segment_quantile(d_po, seg, m, quantile)
    lifted = np.column_stack([allp, seg * SLAB])
    queries = np.column_stack([np.tile(obs, (m, 1)), np.repeat(np.arange(m) * SLAB, len(obs))])
    d_op, _ = cKDTree(lifted).query(queries)
    h_op = _segment_quantile(d_op, np.repeat(np.arange(m), len(obs)), m, quantile)
    return np.maximum(h_po, h_op)


def log_likelihood(
    observed: np.ndarray,
    predicted: Sequence[np.ndarray],
    sigma: float = SIGMA,
    quantile: float = QUANTILE,
    nu: float = NU,
) -> np.ndarray:
    """The log density of ``H`` (:func:`quantile_hausdorff`) per predicted cloud, (M,):
    a Student-t with ``nu`` degrees of freedom and scale ``sigma`` [m] (the module
    docstring), ``log N(H; 0, sigma^2)`` for ``nu = inf``."""
    if not (isinstance(sigma, int | float) and math.isfinite(sigma) and sigma > 0):
        raise BadInputError(f"sigma must be a finite number > 0 [m], got {sigma!r}")
    if not (isinstance(nu, int | float) and nu > 0 and not math.isnan(nu)):
        raise BadInputError(f"nu must be a number > 0 (inf: Gaussian), got {nu!r}")
    z2 = (quantile_hausdorff(observed, predicted, quantile) / sigma) ** 2
    if math.isinf(nu):
        return -0.5 * z2 - math.log(sigma * math.sqrt(2.0 * math.pi))
    norm = (
        math.lgamma(0.5 * (nu + 1.0))
        - math.lgamma(0.5 * nu)
        - 0.5 * math.log(nu * math.pi)
        - math.log(sigma)
    )
    return norm - 0.5 * (nu + 1.0) * np.log1p(z2 / nu)
