"""OBJ meshes to MuJoCo collision pieces: read, colour, solidify and convex-decompose.

PartNet-Mobility links reference many OBJ sub-meshes (``textured_objs/original-N.obj``).
MuJoCo rejects flat meshes (PartNet panels have zero thickness) and replaces every mesh
by its convex hull, which fills a drawer solid. :func:`convex_pieces` turns one OBJ into
vertex arrays whose convex hulls MuJoCo compiles:

- degenerate (fewer than 4 distinct vertices or zero area): no piece;
- flat (thinnest extent along the principal axes below :data:`BOARD_THICKNESS`): one
  piece, padded to that thickness along the thin axis (along every thin axis for rods);
- nearly convex (:func:`concavity` <= :data:`CONCAVITY_LIMIT`): one piece, the hull;
- otherwise: a CoACD decomposition (cached on disk), each piece through the flat rule.

:func:`read_obj` also gives the display colour of the dominant material.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import zipfile
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull, QhullError, cKDTree

from planners.errors import ConfigError

BOARD_THICKNESS: float = 0.01
"""Thickness [m] given to a flat panel. PartNet panels are zero-thickness surfaces; 1 cm is
a thin board, between the generator's drawer boards (8-12 mm) and fronts (15-22 mm), see
:mod:`strug_manip.objects.generator`."""

CONCAVITY_LIMIT: float = 0.02
"""Largest :func:`concavity` [m] of a sub-mesh kept as one convex hull. Measured on two
real PartNet-Mobility cabinets (40147, 41083): boards, panels and handles are below 4 mm,
drawer boxes and carcasses are above 9 cm; nothing lies in between. 2 cm is also the
largest gap a hull may fill without swallowing a gripper finger."""

DEFAULT_RGBA: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)
"""Colour of a mesh without material [rgba in 0..1]."""

COACD_PARAMS: dict[str, object] = {
    "threshold": 0.05,
    "max_convex_hull": 24,
    "preprocess_mode": "auto",
    "preprocess_resolution": 40,
    "resolution": 1000,
    "mcts_nodes": 15,
    "mcts_iterations": 60,
    "mcts_max_depth": 2,
    "merge": True,
    "max_ch_vertex": 64,
    "seed": 0,
}
"""CoACD settings: coarser than its defaults (about 45 s per mesh) for a few seconds per
PartNet mesh, still keeping a drawer box hollow."""

_CACHE_VERSION = "meshes-1"
_SAMPLE_BUDGET = 200_000  # surface samples per mesh in concavity()
_MIN_SPACING = 0.002  # [m] finest sample spacing in concavity()


@dataclass(frozen=True)
class ObjMesh:
    """A triangle mesh read from an OBJ file.

    Attributes:
        vertices: (n, 3) float64 vertex positions [m], in the OBJ's own frame.
        faces: (m, 3) int64 vertex indices of triangles (polygons fan-triangulated).
        rgba: colour of the material used by most triangles [0..1].
    """

    vertices: np.ndarray
    faces: np.ndarray
    rgba: tuple[float, float, float, float]


def read_obj(path: Path) -> ObjMesh:
    """Reads the ``v``, ``f``, ``usemtl`` and ``mtllib`` lines of a Wavefront OBJ file.

    The colour is the MTL ``Kd`` of the material used by most triangles, times the mean
    colour of its ``map_Kd`` texture if that file reads, with alpha ``d`` (or
    ``1 - Tr``); :data:`DEFAULT_RGBA` without material.

    Raises:
        ConfigError: naming the file, if it is unreadable, has no vertex or a bad face.
    """
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8", errors="replace")
    except OSError as exc:
        raise ConfigError(f"cannot read OBJ file {path}: {exc}") from None
    verts: list[list[float]] = []
    tris: list[tuple[int, int, int]] = []
    tri_mtl: list[str | None] = []
    libs: list[str] = []
    material: str | None = None
    for lineno, raw in enumerate(text.splitlines(), 1):
        parts = raw.split()
        if not parts:
            continue
        key = parts[0]
        try:
            if key == "v":
                xyz = [float(x) for x in parts[1:4]]
                if len(xyz) != 3 or not np.all(np.isfinite(xyz)):
                    raise ValueError("a vertex needs 3 finite coordinates")
                verts.append(xyz)
            elif key == "f":
                idx = []
                for entry in parts[1:]:
                    i = int(entry.split("/")[0])
                    i = i - 1 if i > 0 else len(verts) + i
                    if not 0 <= i < len(verts):
                        raise ValueError(f"face index {entry!r} out of 1..{len(verts)}")
                    idx.append(i)
                if len(idx) < 3:
                    raise ValueError("a face needs at least 3 vertices")
                tris.extend((idx[0], idx[k], idx[k + 1]) for k in range(1, len(idx) - 1))
                tri_mtl.extend([material] * (len(idx) - 2))
            elif key == "usemtl":
                material = raw.strip()[len("usemtl") :].strip() or None
            elif key == "mtllib":
                libs.append(raw.strip()[len("mtllib") :].strip())
        except ValueError as exc:
            raise ConfigError(f"malformed OBJ file {path}, line {lineno}: {exc}") from None
    if not verts:
        raise ConfigError(f"OBJ file {path} has no vertex (expected 'v x y z' lines)")
    counts = Counter(tri_mtl)  # insertion-ordered: ties go to the first material used
    name = max(counts, key=counts.__getitem__) if counts else None
    rgba = DEFAULT_RGBA if name is None else _material_rgba(path.parent, libs, name)
    return ObjMesh(
        vertices=np.asarray(verts, dtype=np.float64),
        faces=np.asarray(tris, dtype=np.int64).reshape(-1, 3),
        rgba=rgba,
    )


def _material_rgba(folder: Path, libs: list[str], name: str) -> tuple[float, float, float, float]:
    """Colour [rgba 0..1] of material ``name`` from the first MTL library defining it."""
    for lib in libs:
        candidates = [folder / lib] + [folder / p for p in lib.split()]
        mtl = next((c for c in candidates if c.is_file()), None)
        if mtl is None:
            continue
        try:
            lines = mtl.read_bytes().decode("utf-8", errors="replace").splitlines()
        except OSError:
            continue
        props: dict[str, str] | None = None
        for raw in lines:
            parts = raw.split(maxsplit=1)
            if not parts:
                continue
            if parts[0] == "newmtl":
                if props is not None:
                    break
                if len(parts) > 1 and parts[1].strip() == name:
                    props = {}
            elif props is not None and len(parts) > 1:
                props[parts[0]] = parts[1].strip()
        if props is not None:
            return _props_rgba(mtl.parent, props)
    return DEFAULT_RGBA


def _props_rgba(folder: Path, props: dict[str, str]) -> tuple[float, float, float, float]:
    """Colour [rgba 0..1] from the ``Kd``, ``map_Kd``, ``d`` and ``Tr`` of one material."""
    texture = props.get("map_Kd")
    default_kd = 1.0 if texture else DEFAULT_RGBA[0]
    try:
        kd = np.array([float(x) for x in props.get("Kd", "").split()[:3]] or [default_kd] * 3)
        alpha = float(props["d"]) if "d" in props else 1.0 - float(props.get("Tr", 0.0))
    except ValueError:
        kd, alpha = np.full(3, DEFAULT_RGBA[0]), 1.0
    if kd.size != 3:
        kd = np.full(3, kd[0])
    if texture:
        kd = kd * _texture_mean(folder / texture.split()[-1])
    r, g, b = (float(c) for c in np.clip(kd, 0.0, 1.0))
    return (r, g, b, float(np.clip(alpha, 0.0, 1.0)))


def _texture_mean(path: Path) -> np.ndarray:
    """Mean (3,) RGB [0..1] of an image file; ones if it does not read."""
    import cv2

    image = cv2.imread(str(path), cv2.IMREAD_COLOR) if path.is_file() else None
    if image is None or image.size == 0:
        return np.ones(3)
    return image.reshape(-1, 3).mean(axis=0)[::-1] / 255.0


def _surface_samples(vertices: np.ndarray, faces: np.ndarray, budget: int) -> np.ndarray:
    """Grid samples (p, 3) [m] on triangles, spaced at most ``h`` along both edges at the
    widest-angle corner, with ``h`` >= :data:`_MIN_SPACING` chosen to fit ``budget``."""
    tri = vertices[faces]  # (m, 3, 3)
    edge = np.linalg.norm(tri[:, [1, 2, 0]] - tri[:, [2, 0, 1]], axis=2)  # opposite corner k
    corner = np.argmax(edge, axis=1)  # the corner facing the longest edge has the widest angle
    rows = np.arange(len(tri))
    a = tri[rows, corner]
    e1 = tri[rows, (corner + 1) % 3] - a
    e2 = tri[rows, (corner + 2) % 3] - a
    l1, l2 = np.linalg.norm(e1, axis=1), np.linalg.norm(e2, axis=1)
    h = _MIN_SPACING
    while True:
        n1, n2 = np.ceil(l1 / h).astype(np.int64) + 1, np.ceil(l2 / h).astype(np.int64) + 1
        if int(np.sum((n1 + 1) * (n2 + 1) // 2)) <= budget:
            break
        h *= 1.5
    points = [vertices]
    for k1, k2 in {(int(x), int(y)) for x, y in zip(n1, n2, strict=True)}:
        sel = (n1 == k1) & (n2 == k2)
        u, w = np.meshgrid(np.arange(k1 + 1) / k1, np.arange(k2 + 1) / k2, indexing="ij")
        keep = u + w <= 1.0 + 1e-9
        u, w = u[keep], w[keep]
        points.append(
            (
                a[sel, None] + u[None, :, None] * e1[sel, None] + w[None, :, None] * e2[sel, None]
            ).reshape(-1, 3)
        )
    return np.concatenate(points)


def _hull(points: np.ndarray) -> ConvexHull | None:
    """Convex hull of (n, 3) points, or None if they are (nearly) coplanar."""
    try:
        return ConvexHull(points)
    except (QhullError, ValueError):
        return None


def concavity(vertices: np.ndarray, faces: np.ndarray) -> float:
    """How far a mesh is from convex [m].

    The largest distance from a sample of its convex hull's surface to the nearest sample
    of its own surface (samples a few mm apart, so accurate to a few mm); 0 for a flat or
    degenerate mesh.

    Args:
        vertices: (n, 3) vertex positions [m].
        faces: (m, 3) triangle vertex indices.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if len(faces) == 0:
        return 0.0
    used = vertices[np.unique(faces)]
    hull = _hull(used)
    if hull is None:
        return 0.0
    mesh_pts = _surface_samples(vertices, faces, _SAMPLE_BUDGET)
    hull_pts = _surface_samples(hull.points, hull.simplices, _SAMPLE_BUDGET // 4)
    dist, _ = cKDTree(mesh_pts).query(hull_pts)
    return float(dist.max())


def _principal_frame(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centre (3,) [m], principal axes (3, 3) as rows, and extents (3,) [m] along them."""
    centre = points.mean(axis=0)
    _, _, axes = np.linalg.svd(points - centre, full_matrices=False)
    local = (points - centre) @ axes.T
    return centre, axes, np.ptp(local, axis=0)


def _solid_piece(points: np.ndarray) -> np.ndarray | None:
    """A (k, 3) vertex array [m] whose hull MuJoCo compiles, from an (n, 3) point cloud.

    Every principal axis thinner than :data:`BOARD_THICKNESS` is padded to that thickness
    around its midpoint; the result is the hull vertices. None for fewer than 3 distinct
    points or a cloud with no extent at all.
    """
    points = np.unique(np.asarray(points, dtype=np.float64), axis=0)
    if len(points) < 3:
        return None
    centre, axes, extent = _principal_frame(points)
    if extent.max() < 1e-9:
        return None
    local = (points - centre) @ axes.T
    thin = np.flatnonzero(extent < BOARD_THICKNESS)
    for axis in thin:
        mid = 0.5 * (local[:, axis].max() + local[:, axis].min())
        lo, hi = local.copy(), local.copy()
        lo[:, axis], hi[:, axis] = mid - BOARD_THICKNESS / 2, mid + BOARD_THICKNESS / 2
        local = np.concatenate([lo, hi])
    points = local @ axes + centre
    hull = _hull(points)
    return None if hull is None else points[hull.vertices]


def default_cache_dir() -> Path:
    """Folder of cached CoACD results: ``$STRUG_MANIP_CACHE/coacd`` if that variable is set,
    else ``platformdirs.user_cache_dir("strug-manip")/coacd``."""
    root = os.environ.get("STRUG_MANIP_CACHE")
    if not root:
        import platformdirs

        root = platformdirs.user_cache_dir("strug-manip")
    return Path(root) / "coacd"


def _check_scale(scale: Sequence[float], path: Path) -> np.ndarray:
    """(3,) float64 scale, or ConfigError naming the file."""
    try:
        out = np.asarray(scale, dtype=np.float64).reshape(3)
    except (TypeError, ValueError):
        out = np.full(3, np.nan)
    if not np.all(np.isfinite(out)):
        raise ConfigError(f"mesh scale {scale!r} for {path}: expected 3 finite numbers")
    return out


def convex_pieces(
    path: Path,
    scale: Sequence[float] = (1.0, 1.0, 1.0),
    *,
    cache_dir: Path | None = None,
    progress: bool = True,
) -> tuple[np.ndarray, ...]:
    """Collision pieces of one OBJ mesh: vertex arrays whose convex hulls MuJoCo compiles.

    Args:
        path: the OBJ file.
        scale: (3,) factors applied to the vertices first.
        cache_dir: where CoACD results are stored (default :func:`default_cache_dir`).
        progress: show a progress bar on stderr while decomposing.

    Returns:
        Pieces, each a (k, 3) float64 array [m] of k >= 4 non-coplanar points in the OBJ's
        frame, scaled; () for a degenerate mesh. Deterministic.

    Raises:
        ConfigError: naming the file, for an unreadable OBJ or a bad scale.
    """
    path = Path(path)
    mesh = read_obj(path)
    s = _check_scale(scale, path)
    vertices, faces = mesh.vertices * s, mesh.faces
    if len(faces) == 0:
        return ()
    used = np.unique(vertices[np.unique(faces)], axis=0)
    tri = vertices[faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    if len(used) < 4 or area.sum() <= 1e-12:
        return ()
    _, _, extent = _principal_frame(used)
    if extent.min() < BOARD_THICKNESS or concavity(vertices, faces) <= CONCAVITY_LIMIT:
        piece = _solid_piece(used)
        return () if piece is None else (piece,)
    return _decompose(path, vertices, faces, s, cache_dir or default_cache_dir(), progress)


def _decompose(
    path: Path,
    vertices: np.ndarray,
    faces: np.ndarray,
    scale: np.ndarray,
    cache_dir: Path,
    progress: bool,
) -> tuple[np.ndarray, ...]:
    """CoACD pieces of a concave (n, 3) / (m, 3) mesh, through the on-disk cache."""
    digest = hashlib.sha256()
    digest.update(path.read_bytes())
    digest.update(scale.astype("<f8").tobytes())
    digest.update(json.dumps(COACD_PARAMS, sort_keys=True).encode())
    digest.update(_CACHE_VERSION.encode())
    file = cache_dir / f"{digest.hexdigest()}.npz"
    cached = _load_pieces(file)
    if cached is not None:
        return cached
    import coacd
    from tqdm import tqdm

    coacd.set_log_level("error")
    with tqdm(
        total=1, desc=f"convex decomposition of {path.name}", file=sys.stderr, disable=not progress
    ) as bar:
        parts = coacd.run_coacd(coacd.Mesh(vertices, faces), **COACD_PARAMS)
        bar.update(1)
    pieces = tuple(p for p in (_solid_piece(v) for v, _ in parts) if p is not None)
    _save_pieces(file, pieces)
    return pieces


def _load_pieces(file: Path) -> tuple[np.ndarray, ...] | None:
    """Pieces stored by :func:`_save_pieces`, or None if absent or unreadable."""
    if not file.is_file():
        return None
    try:
        with np.load(file, allow_pickle=False) as data:
            points, counts = data["points"], data["counts"]
        if len(counts) == 0:
            return ()
        if points.ndim != 2 or points.shape[1] != 3 or counts.sum() != len(points):
            return None
        return tuple(np.split(points.astype(np.float64), np.cumsum(counts)[:-1]))
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        return None


def _save_pieces(file: Path, pieces: tuple[np.ndarray, ...]) -> None:
    """Writes pieces to ``file`` atomically; a cache that cannot be written is skipped."""
    try:
        file.parent.mkdir(parents=True, exist_ok=True)
        tmp = file.with_name(f"{file.stem}.{os.getpid()}.tmp.npz")
        points = np.concatenate(pieces) if pieces else np.zeros((0, 3))
        np.savez(tmp, points=points, counts=np.array([len(p) for p in pieces], dtype=np.int64))
        os.replace(tmp, file)
    except OSError:
        pass
