"""OBJ meshes to MuJoCo collision pieces (:func:`convex_pieces`) and colours (:func:`read_obj`).

MuJoCo rejects flat meshes (PartNet panels have zero thickness) and replaces every mesh by
its convex hull, which fills a drawer solid. Rules, in order, for one OBJ:

- degenerate (fewer than 4 distinct vertices or zero area): no piece;
- flat (thinnest extent along the principal axes below :data:`BOARD_THICKNESS`): one piece,
  padded to that thickness along the thin axis (along every thin axis for rods);
- nearly convex (:func:`concavity` <= :data:`CONCAVITY_LIMIT`): one piece, the hull;
- otherwise each connected component (a drawer modelled as separate boards needs no
  decomposition) goes through these rules, a concave one through CoACD
  (:data:`COACD_PARAMS`, each piece then through the flat rule); cached on disk.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import zipfile
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

# isort: off
# Pinocchio before CoACD: CoACD's wheel loads libraries that, loaded first, break
# urdfdom's number parsing (every URDF then fails in pin.buildModelFromXML: "Unable to
# parse component [0] to a double"). Measured with coacd 1.0.14, pin 3.x.
import pinocchio  # noqa: F401
import coacd

# isort: on
import cv2
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError, cKDTree
from tqdm import tqdm

from planners.errors import ConfigError
from strug_manip.cache import cache_root

# PartNet panels are zero-thickness surfaces; 1 cm is a thin board, between the generator's
# drawer boards (8-12 mm) and its fronts (15-22 mm), see strug_manip/objects/generator.py.
BOARD_THICKNESS: float = 0.01
"""Thickness [m] given to a flat panel."""

# Measured on every collision sub-mesh of PartNet-Mobility cabinets 40147 and 41083 (140):
# panels 0, boards 0-27 mm (open tubes: half their thickness), handles 6-31 mm (the bar's
# stand-off). One link's sub-meshes merged into one mesh: door + handle 47-53 mm, drawer
# 121-136 mm, carcass 379-396 mm. 4 cm keeps every handle (the generator's stand-offs are
# 25-40 mm) a single hull and decomposes any drawer box or carcass.
CONCAVITY_LIMIT: float = 0.04
"""Largest :func:`concavity` [m] of a mesh kept as a single convex hull."""

DEFAULT_RGBA: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)
"""Colour of a mesh without material [rgba in 0..1]."""

# CoACD's defaults take ~45 s per concave mesh here. These take 0.5-3 s on a watertight
# drawer or carcass and 3-10 s on a non-manifold one (CoACD then voxel-remeshes it at
# `preprocess_resolution` cells along its longest side, which thickens its boards by up to a
# cell); drawer boxes stay hollow. `preprocess_mode="off"` crashes CoACD on non-manifold input.
COACD_PARAMS: Mapping[str, object] = MappingProxyType(
    {
        "threshold": 0.05,
        "max_convex_hull": 32,
        "preprocess_mode": "auto",
        "preprocess_resolution": 30,
        "resolution": 500,
        "mcts_nodes": 10,
        "mcts_iterations": 30,
        "mcts_max_depth": 2,
        "merge": True,
        "max_ch_vertex": 64,
        "seed": 0,
    }
)
"""Keyword arguments of ``coacd.run_coacd`` (part of the cache key)."""

MAX_COMPONENTS: int = 64
"""A concave mesh with more connected components than this goes to CoACD whole."""

_CACHE_VERSION = "strug-manip-meshes-2"  # 2: every mesh's pieces, not only CoACD's
_SAMPLE_BUDGET = 60_000  # surface samples of a mesh in concavity() (a quarter on its hull)
_MIN_SPACING = 0.002  # [m] finest sample spacing in concavity(), about its error


@dataclass(frozen=True)
class ObjMaterial:
    """How one material of an OBJ mesh looks.

    Attributes:
        rgba: its colour [0..1]: ``Kd`` times its texture's mean colour, alpha ``d``.
        tint: ``Kd`` and alpha, what a mapped texture is multiplied by.
        texture: its ``map_Kd`` image file if that exists, else None.
    """

    rgba: tuple[float, float, float, float]
    tint: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    texture: Path | None = None


@dataclass(frozen=True)
class ObjMesh:
    """A triangle mesh read from an OBJ file.

    Attributes:
        vertices: (n, 3) float64 vertex positions [m], in the OBJ's own frame.
        faces: (m, 3) int64 vertex indices of triangles (polygons fan-triangulated).
        rgba: colour of the material used by most triangles [0..1].
        materials: the materials the faces use (at least one: a mesh without any
            gets :data:`DEFAULT_RGBA`).
        face_material: (m,) int64 index into ``materials`` of each face.
        texcoords: (k, 2) texture coordinates (``vt`` lines), or None.
        face_texcoords: (m, 3) int64 indices into ``texcoords`` of each face's
            corners, or None when some face has none (no texture can be mapped).
    """

    vertices: np.ndarray
    faces: np.ndarray
    rgba: tuple[float, float, float, float]
    materials: tuple[ObjMaterial, ...] = (ObjMaterial(DEFAULT_RGBA),)
    face_material: np.ndarray | None = None
    texcoords: np.ndarray | None = None
    face_texcoords: np.ndarray | None = None


def read_obj(path: Path, textures: dict[Path, np.ndarray | None] | None = None) -> ObjMesh:
    """Reads the ``v``, ``vt``, ``f``, ``usemtl`` and ``mtllib`` lines of a Wavefront OBJ
    file and its materials (``Kd``, ``map_Kd``, ``d`` or ``Tr`` of the MTL libraries).

    Args:
        path: the OBJ file.
        textures: texture path -> mean RGB (3,) [0..1] (or None: unreadable), filled and
            reused across calls (PartNet meshes share a handful of texture images).

    Raises:
        ConfigError: naming the file, if it is unreadable, has no vertex or a bad face.
    """
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8", errors="replace")
    except OSError as exc:
        raise ConfigError(f"cannot read OBJ file {path}: {exc}") from None
    obj = _parse_obj(text, path)
    cache = {} if textures is None else textures
    names = list(dict.fromkeys(obj["tri_mtl"])) or [None]
    materials = []
    for name in names:
        found = None if name is None else _material(path.parent, obj["libs"], name)
        if found is None:
            materials.append(ObjMaterial(DEFAULT_RGBA))
            continue
        texture, tint = _texture_of(*found)
        materials.append(ObjMaterial(_props_rgba(*found, cache), tint, texture))
    counts = Counter(obj["tri_mtl"])  # insertion-ordered: a tie goes to the first used
    dominant = names.index(max(counts, key=counts.__getitem__)) if counts else 0
    index = {n: k for k, n in enumerate(names)}
    uvs, tri_uv = obj["uvs"], obj["tri_uv"]
    mapped = bool(uvs) and all(0 <= t < len(uvs) for tri in tri_uv for t in tri)
    return ObjMesh(
        vertices=np.asarray(obj["verts"], dtype=np.float64),
        faces=np.asarray(obj["tris"], dtype=np.int64).reshape(-1, 3),
        rgba=materials[dominant].rgba,
        materials=tuple(materials),
        face_material=np.array([index[n] for n in obj["tri_mtl"]], dtype=np.int64),
        texcoords=np.asarray(uvs, dtype=np.float64).reshape(-1, 2) if mapped else None,
        face_texcoords=np.asarray(tri_uv, dtype=np.int64).reshape(-1, 3) if mapped else None,
    )


def _parse_obj(text: str, path: Path) -> dict:
    """The vertex (``verts``), texture-coordinate (``uvs``), triangle (``tris``, with
    their ``tri_uv`` and ``tri_mtl``) and ``libs`` lists of an OBJ file's text."""
    out: dict = {"verts": [], "uvs": [], "tris": [], "tri_uv": [], "tri_mtl": [], "libs": []}
    verts, uvs = out["verts"], out["uvs"]
    material: str | None = None
    for lineno, raw in enumerate(text.splitlines(), 1):
        key, rest = ([*raw.split(None, 1), "", ""])[:2]
        try:
            if key == "v":
                xyz = [float(x) for x in rest.split()[:3]]
                if len(xyz) != 3 or not np.all(np.isfinite(xyz)):
                    raise ValueError("a vertex needs 3 finite coordinates")
                verts.append(xyz)
            elif key == "vt":
                uvs.append([float(x) for x in [*rest.split(), "0", "0"][:2]])
            elif key == "f":
                idx, uv = [], []
                for entry in rest.split():
                    fields = entry.split("/")
                    i = int(fields[0])
                    i = i - 1 if i > 0 else len(verts) + i if i < 0 else -1
                    if not 0 <= i < len(verts):
                        raise ValueError(f"face index {entry!r} is not one of 1..{len(verts)}")
                    idx.append(i)
                    t = int(fields[1]) if len(fields) > 1 and fields[1] else 0
                    uv.append(t - 1 if t > 0 else len(uvs) + t if t < 0 else -1)
                if len(idx) < 3:
                    raise ValueError("a face needs at least 3 vertices")
                fan = range(1, len(idx) - 1)
                out["tris"].extend((idx[0], idx[k], idx[k + 1]) for k in fan)
                out["tri_uv"].extend((uv[0], uv[k], uv[k + 1]) for k in fan)
                out["tri_mtl"].extend([material] * len(fan))
            elif key == "usemtl":
                material = rest.strip() or None
            elif key == "mtllib":
                out["libs"].append(rest.strip())
        except ValueError as exc:
            raise ConfigError(f"malformed OBJ file {path}, line {lineno}: {exc}") from None
    if not verts:
        raise ConfigError(f"OBJ file {path} has no vertex (expected 'v x y z' lines)")
    return out


def _texture_of(
    folder: Path, props: dict[str, str]
) -> tuple[Path | None, tuple[float, float, float, float]]:
    """A material's ``map_Kd`` image (None if absent) and its ``Kd`` and alpha."""
    words = props.get("map_Kd", "").split()
    image = folder / words[-1] if words else None
    try:
        kd = [float(x) for x in props.get("Kd", "1 1 1").split()[:3]]
        alpha = float(props["d"]) if "d" in props else 1.0 - float(props.get("Tr", 0.0))
    except ValueError:
        kd, alpha = [1.0, 1.0, 1.0], 1.0
    r, g, b = (float(c) for c in np.clip(np.resize(kd, 3), 0.0, 1.0))
    tint = (r, g, b, float(np.clip(alpha, 0.0, 1.0)))
    return (image.resolve() if image is not None and image.is_file() else None), tint


def _material(folder: Path, libs: list[str], name: str) -> tuple[Path, dict[str, str]] | None:
    """The folder of the first MTL library defining material ``name`` (its texture
    paths are relative to it) and the material's properties (``Kd``, ``map_Kd``, ``d``
    ...), or None."""
    files = [folder / lib for lib in libs] + [folder / w for lib in libs for w in lib.split()]
    for mtl in dict.fromkeys(f for f in files if f.is_file()):  # a name may hold spaces
        try:
            lines = mtl.read_bytes().decode("utf-8", errors="replace").splitlines()
        except OSError:
            continue
        props: dict[str, str] | None = None
        for raw in lines:
            key, value = ([*raw.split(None, 1), "", ""])[:2]
            if key == "newmtl" and props is not None:
                break
            if key == "newmtl" and value.strip() == name:
                props = {}
            elif props is not None and key:
                props[key] = value.strip()
        if props is not None:
            return mtl.parent, props
    return None


def _props_rgba(
    folder: Path, props: dict[str, str], textures: dict[Path, np.ndarray | None]
) -> tuple[float, float, float, float]:
    """Colour [rgba 0..1] from the ``Kd``, ``map_Kd``, ``d`` and ``Tr`` of one material."""
    texture = props.get("map_Kd", "").split()
    try:
        kd = [float(x) for x in props.get("Kd", "").split()[:3]]
        alpha = float(props["d"]) if "d" in props else 1.0 - float(props.get("Tr", 0.0))
    except ValueError:
        kd, alpha = [], 1.0
    rgb = np.resize(np.asarray(kd or [1.0 if texture else DEFAULT_RGBA[0]]), 3)
    if texture:  # the file name is the last word (options like `-s 1 1 1` come first)
        file = folder / texture[-1]
        if file not in textures:
            image = cv2.imread(str(file), cv2.IMREAD_COLOR) if file.is_file() else None
            ok = image is not None and image.size
            textures[file] = image.reshape(-1, 3).mean(axis=0)[::-1] / 255.0 if ok else None
        if textures[file] is not None:
            rgb = rgb * textures[file]  # BGR -> RGB above
    r, g, b = (float(c) for c in np.clip(rgb, 0.0, 1.0))
    return (r, g, b, float(np.clip(alpha, 0.0, 1.0)))


def _surface_samples(vertices: np.ndarray, faces: np.ndarray, budget: int) -> np.ndarray:
    """Grid samples (p, 3) [m] on triangles, at most ``h`` apart along the two edges at the
    widest corner, with ``h`` >= :data:`_MIN_SPACING` grown until they fit ``budget``."""
    tri = vertices[faces]  # (m, 3, 3)
    opposite = np.linalg.norm(tri[:, [1, 2, 0]] - tri[:, [2, 0, 1]], axis=2)
    corner = np.argmax(opposite, axis=1)  # faces the longest edge: the widest angle
    rows = np.arange(len(tri))
    a = tri[rows, corner]
    e1, e2 = tri[rows, (corner + 1) % 3] - a, tri[rows, (corner + 2) % 3] - a
    l1, l2 = np.linalg.norm(e1, axis=1), np.linalg.norm(e2, axis=1)
    h = _MIN_SPACING
    while True:
        n1, n2 = np.ceil(l1 / h).astype(np.int64) + 1, np.ceil(l2 / h).astype(np.int64) + 1
        if int(np.sum((n1 + 1) * (n2 + 1) // 2)) <= budget:
            break
        h *= 1.5
    points = [vertices[np.unique(faces)]]
    for k1, k2 in sorted(set(zip(n1.tolist(), n2.tolist(), strict=True))):
        sel = (n1 == k1) & (n2 == k2)
        u, w = np.meshgrid(np.arange(k1 + 1) / k1, np.arange(k2 + 1) / k2, indexing="ij")
        keep = u + w <= 1.0 + 1e-9
        u, w = u[keep][None, :, None], w[keep][None, :, None]
        points.append((a[sel, None] + u * e1[sel, None] + w * e2[sel, None]).reshape(-1, 3))
    return np.concatenate(points)


def _hull(points: np.ndarray) -> ConvexHull | None:
    """Convex hull of (n, 3) points [m], or None if they are coplanar or too few."""
    try:
        return ConvexHull(points)
    except (QhullError, ValueError):
        return None


def concavity(vertices: np.ndarray, faces: np.ndarray) -> float:
    """How far a mesh is from convex [m].

    The largest distance from a sample of its convex hull's surface to the nearest sample
    of its own surface (samples at most a few mm apart, so accurate to a few mm); 0 for a
    flat or degenerate mesh.

    Args:
        vertices: (n, 3) vertex positions [m].
        faces: (m, 3) triangle vertex indices.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    hull = _hull(vertices[np.unique(faces)]) if len(faces) else None
    if hull is None:
        return 0.0
    hull_points = _surface_samples(hull.points, hull.simplices, _SAMPLE_BUDGET // 4)
    tree = cKDTree(_surface_samples(vertices, faces, _SAMPLE_BUDGET), balanced_tree=False)
    return float(tree.query(hull_points)[0].max())


def _solid_piece(points: np.ndarray) -> np.ndarray | None:
    """Hull vertices (k, 3) [m] of an (n, 3) point cloud, every principal axis thinner than
    :data:`BOARD_THICKNESS` first padded to that thickness about its midpoint; None if the
    cloud has no extent."""
    points = np.unique(np.asarray(points, dtype=np.float64), axis=0)
    centre = points.mean(axis=0)
    axes = np.linalg.svd(points - centre, full_matrices=False)[2]  # rows: principal axes
    local = (points - centre) @ axes.T
    extent = np.ptp(local, axis=0)
    if extent.max() < 1e-9:
        return None
    for axis in np.flatnonzero(extent < BOARD_THICKNESS):
        mid = 0.5 * (local[:, axis].max() + local[:, axis].min())
        lo, hi = local.copy(), local.copy()
        lo[:, axis], hi[:, axis] = mid - BOARD_THICKNESS / 2, mid + BOARD_THICKNESS / 2
        local = np.concatenate([lo, hi])
    points = local @ axes + centre
    hull = _hull(points)
    return None if hull is None else points[hull.vertices]


def _classify(vertices: np.ndarray, faces: np.ndarray) -> str:
    """``"degenerate"``, ``"flat"``, ``"convex"`` or ``"concave"`` (the module's rules) for
    an (n, 3) [m] / (m, 3) mesh."""
    used = np.unique(vertices[np.unique(faces)], axis=0) if len(faces) else vertices[:0]
    tri = vertices[faces]
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
    if len(used) < 4 or area / 2 <= 1e-12:
        return "degenerate"
    local = (used - used.mean(axis=0)) @ np.linalg.svd(used - used.mean(axis=0))[2].T
    if np.ptp(local, axis=0).min() < BOARD_THICKNESS:
        return "flat"
    return "convex" if concavity(vertices, faces) <= CONCAVITY_LIMIT else "concave"


def png_texture(image: Path, cache_dir: Path | None = None) -> Path | None:
    """``image`` as a PNG file MuJoCo reads: itself if it is one, else a PNG copy in
    ``cache_dir`` (default :func:`default_cache_dir`), keyed by the image's bytes; None
    if it cannot be read (PartNet's textures are mostly JPEG, which MuJoCo does not
    read)."""
    image = Path(image)
    if image.suffix.lower() == ".png":
        return image
    try:
        data = image.read_bytes()
    except OSError:
        return None
    out = (
        (cache_dir or default_cache_dir()) / "textures" / f"{hashlib.sha256(data).hexdigest()}.png"
    )
    if not out.is_file():
        pixels = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
        if pixels is None:
            return None
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = out.with_name(f"{out.stem}.{os.getpid()}.tmp.png")
        if not cv2.imwrite(str(tmp), pixels):
            return None
        os.replace(tmp, out)
    return out


def default_cache_dir() -> Path:
    """Folder of cached decompositions: ``$STRUG_MANIP_CACHE/coacd`` if that variable is
    set, else ``platformdirs.user_cache_dir("strug-manip")/coacd``."""
    return cache_root() / "coacd"


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
        scale: (3,) factors applied to its vertices first.
        cache_dir: where decompositions are stored (default :func:`default_cache_dir`).
        progress: show a progress bar on stderr while decomposing.

    Returns:
        Pieces, each a (k, 3) float64 array [m] of k >= 4 non-coplanar points in the OBJ's
        frame, scaled, no thinner than :data:`BOARD_THICKNESS`; () for a degenerate mesh.
        The same file and scale always give the same pieces.

    Raises:
        ConfigError: naming the file, for an unreadable or malformed OBJ or a bad scale.
    """
    path = Path(path)
    try:
        s = np.asarray(scale, dtype=np.float64).reshape(3)
    except (TypeError, ValueError):
        s = np.full(3, np.nan)
    if not np.all(np.isfinite(s)):
        raise ConfigError(f"mesh scale {scale!r} for {path}: expected 3 finite numbers")
    try:
        digest = hashlib.sha256(path.read_bytes())
    except OSError as exc:
        raise ConfigError(f"cannot read OBJ file {path}: {exc}") from None
    digest.update(s.astype("<f8").tobytes())
    digest.update(json.dumps([dict(COACD_PARAMS), MAX_COMPONENTS, CONCAVITY_LIMIT]).encode())
    digest.update(f"{_CACHE_VERSION} {BOARD_THICKNESS!r}".encode())
    # Every mesh's pieces are cached, not only decompositions: measuring concavity costs
    # tens of milliseconds a mesh, seconds for an object of a hundred sub-meshes.
    file = (cache_dir or default_cache_dir()) / f"{digest.hexdigest()}.npz"
    pieces = _load_pieces(file)
    if pieces is None:
        mesh = read_obj(path)
        pieces = _pieces_of(path.name, mesh.vertices * s, mesh.faces, progress)
        _save_pieces(file, pieces)
    return pieces


def _pieces_of(
    name: str, vertices: np.ndarray, faces: np.ndarray, progress: bool
) -> tuple[np.ndarray, ...]:
    """The pieces of one scaled mesh (:func:`convex_pieces`'s rules), uncached."""
    kind = _classify(vertices, faces)
    if kind == "degenerate":
        return ()
    if kind != "concave":
        piece = _solid_piece(vertices[np.unique(faces)])
        return () if piece is None else (piece,)
    return _decompose(name, vertices, faces, progress)


def _components(faces: np.ndarray) -> list[np.ndarray]:
    """Faces (m_i, 3) of each connected component (sharing vertex indices) of a mesh."""
    n = int(faces.max()) + 1
    rows, cols = faces[:, [0, 1, 2]].ravel(), faces[:, [1, 2, 0]].ravel()
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    labels = connected_components(graph, directed=False)[1][faces[:, 0]]
    return [faces[labels == k] for k in np.unique(labels)]


def _decompose(
    name: str, vertices: np.ndarray, faces: np.ndarray, progress: bool
) -> tuple[np.ndarray, ...]:
    """Pieces of a concave (n, 3) [m] / (m, 3) mesh: per connected component, one piece if
    flat or nearly convex, else the CoACD pieces (each through the flat rule)."""
    parts = _components(faces)
    if len(parts) > MAX_COMPONENTS:
        parts = [faces]
    kinds = [_classify(vertices, f) if len(parts) > 1 else "concave" for f in parts]
    clouds: list[np.ndarray] = []
    n = kinds.count("concave")
    bar = tqdm(total=n, desc=f"decomposing {name}", file=sys.stderr, disable=not (progress and n))
    with bar:
        for part, kind in zip(parts, kinds, strict=True):
            if kind in ("flat", "convex"):
                clouds.append(vertices[np.unique(part)])
            elif kind == "concave":
                coacd.set_log_level("error")
                used, local = np.unique(part, return_inverse=True)
                mesh = coacd.Mesh(vertices[used], local.reshape(-1, 3))
                clouds.extend(v for v, _ in coacd.run_coacd(mesh, **COACD_PARAMS))
                bar.update(1)
    return tuple(p for p in map(_solid_piece, clouds) if p is not None)


def _load_pieces(file: Path) -> tuple[np.ndarray, ...] | None:
    """Pieces stored by :func:`_save_pieces`, or None if absent or unreadable."""
    try:
        with np.load(file, allow_pickle=False) as data:
            points, counts = data["points"].astype(np.float64), data["counts"]
        if points.shape[1:] != (3,) or counts.sum() != len(points) or np.any(counts < 4):
            return None
        return tuple(np.split(points, np.cumsum(counts)[:-1])) if len(counts) else ()
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        return None


def _save_pieces(file: Path, pieces: tuple[np.ndarray, ...]) -> None:
    """Writes pieces to ``file`` atomically; a cache that cannot be written is skipped."""
    tmp = file.with_name(f"{file.stem}.{os.getpid()}.tmp.npz")
    try:
        file.parent.mkdir(parents=True, exist_ok=True)
        points = np.concatenate(pieces) if pieces else np.zeros((0, 3))
        np.savez(tmp, points=points, counts=np.array([len(p) for p in pieces], dtype=np.int64))
        os.replace(tmp, file)
    except OSError:
        tmp.unlink(missing_ok=True)
