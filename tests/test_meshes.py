"""OBJ reading, colours and collision pieces (strug_manip.objects.meshes) on tiny OBJ files."""

from __future__ import annotations

from pathlib import Path

import cv2
import mujoco
import numpy as np
import pytest
from scipy.spatial import ConvexHull

from planners.errors import ConfigError
from strug_manip.objects import meshes
from strug_manip.objects.meshes import BOARD_THICKNESS, CONCAVITY_LIMIT, convex_pieces, read_obj

W, D, H, T = 0.4, 0.3, 0.2, 0.012  # open box: width, depth, height, board thickness [m]
CENTRE = np.array([W / 2, D / 2, H / 2])


def write_obj(path: Path, vertices: np.ndarray, faces: list, header: str = "") -> Path:
    """Writes an OBJ file: (n, 3) vertices [m], faces as lists of 0-based indices."""
    lines = [header] + [f"v {x:.17g} {y:.17g} {z:.17g}" for x, y, z in np.asarray(vertices, float)]
    lines += ["f " + " ".join(str(i + 1) for i in face) for face in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def cuboid(lo: tuple, hi: tuple, offset: int = 0) -> tuple[np.ndarray, list]:
    """Vertices (8, 3) [m] and 6 outward quads of an axis-aligned box."""
    v = np.array([[(lo, hi)[i >> k & 1][k] for k in range(3)] for i in range(8)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return v, [[q + offset for q in quad] for quad in quads]


def five_boards() -> tuple[np.ndarray, list]:
    """An open-top box as 5 separate boards in one mesh."""
    boxes = [
        ((0, 0, 0), (W, D, T)),
        ((0, 0, T), (T, D, H)),
        ((W - T, 0, T), (W, D, H)),
        ((T, 0, T), (W - T, T, H)),
        ((T, D - T, T), (W - T, D, H)),
    ]
    parts = [cuboid(lo, hi, 8 * k) for k, (lo, hi) in enumerate(boxes)]
    return np.concatenate([v for v, _ in parts]), [q for _, quads in parts for q in quads]


def solid_open_box() -> tuple[np.ndarray, list]:
    """An open-top box with T-thick walls as one closed, connected surface (16 vertices)."""
    outer = [(0, 0), (W, 0), (W, D), (0, D)]
    inner = [(T, T), (W - T, T), (W - T, D - T), (T, D - T)]
    v = [(*p, z) for z in (0, H) for p in outer] + [(*p, z) for z in (T, H) for p in inner]
    quads = [(0, 3, 2, 1), (8, 9, 10, 11)]  # outer bottom, inner floor
    for i in range(4):
        j = (i + 1) % 4
        quads += [
            (i, j, 4 + j, 4 + i),
            (4 + i, 4 + j, 12 + j, 12 + i),
            (12 + i, 12 + j, 8 + j, 8 + i),
        ]
    return np.array(v, float), quads


def triangles(quads: list) -> np.ndarray:
    """(2 q, 3) triangles of q quads."""
    return np.array([[q[0], q[k], q[k + 1]] for q in quads for k in (1, 2)])


def contains(piece: np.ndarray, point: np.ndarray) -> bool:
    """Whether a point [m] lies in the convex hull of a (k, 3) piece."""
    eq = ConvexHull(piece).equations
    return bool(np.all(eq[:, :3] @ point + eq[:, 3] <= 1e-9))


def principal_extents(piece: np.ndarray) -> np.ndarray:
    """Sorted (3,) extents [m] of a piece along its principal axes."""
    c = piece - piece.mean(axis=0)
    return np.sort(np.ptp(c @ np.linalg.svd(c)[2].T, axis=0))


def compile_pieces(pieces: tuple[np.ndarray, ...]) -> mujoco.MjModel:
    """Compiles every piece as a mesh geom of one body."""
    spec = mujoco.MjSpec()
    body = spec.worldbody.add_body(name="b")
    for k, piece in enumerate(pieces):
        spec.add_mesh(name=f"m{k}", uservert=piece.ravel().tolist())
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"m{k}")
    return spec.compile()


def test_read_obj_parses_index_forms_and_fans_polygons(tmp_path: Path) -> None:
    text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3//1 -1\n"
    (tmp_path / "q.obj").write_text(text)
    mesh = read_obj(tmp_path / "q.obj")
    assert mesh.vertices.shape == (4, 3) and mesh.vertices.dtype == np.float64
    assert mesh.faces.dtype == np.int64
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [0, 2, 3]])
    assert mesh.rgba == meshes.DEFAULT_RGBA


def test_read_obj_colour_of_dominant_material(tmp_path: Path) -> None:
    mtl = "newmtl small\nKd 1 0 0\n\nnewmtl big\nKd 0.2 0.4 0.6\nd 0.5\n"
    (tmp_path / "m.mtl").write_text(mtl)
    v, quads = cuboid((0, 0, 0), (1, 1, 1))
    head = "mtllib m.mtl\nusemtl small"
    write_obj(tmp_path / "c.obj", v, quads[:1], head)  # write faces in two materials
    text = (tmp_path / "c.obj").read_text() + "usemtl big\n"
    text += "".join("f " + " ".join(str(i + 1) for i in q) + "\n" for q in quads[1:])
    (tmp_path / "c.obj").write_text(text)
    assert read_obj(tmp_path / "c.obj").rgba == pytest.approx((0.2, 0.4, 0.6, 0.5))


def test_read_obj_colour_times_texture_mean(tmp_path: Path) -> None:
    (tmp_path / "images").mkdir()
    (tmp_path / "objs").mkdir()
    image = np.zeros((4, 4, 3), np.uint8)
    image[:2] = (50, 100, 200)  # BGR: rgb (200, 100, 50) on half, black on the other half
    assert cv2.imwrite(str(tmp_path / "images" / "t.png"), image)
    mtl = "newmtl a\nKd 1 1 0.5\nmap_Kd ../images/t.png\nnewmtl b\nKd 0.3 0.3 0.3\n"
    mtl += "map_Kd ../images/missing.jpg\n"
    (tmp_path / "objs" / "m.mtl").write_text(mtl)
    v, quads = cuboid((0, 0, 0), (1, 1, 1))
    for name in ("a", "b"):
        write_obj(tmp_path / "objs" / f"{name}.obj", v, quads, f"mtllib m.mtl\nusemtl {name}")
    rgba = read_obj(tmp_path / "objs" / "a.obj").rgba
    assert rgba == pytest.approx((100 / 255, 50 / 255, 12.5 / 255, 1.0))
    assert read_obj(tmp_path / "objs" / "b.obj").rgba == pytest.approx((0.3, 0.3, 0.3, 1.0))


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", ["line 4", "'4'"]),
        ("v 0 0 0\nv 1 0 0\nf 1 2 0\n", ["line 3"]),
        ("v 0 0 x\n", ["line 1"]),
        ("# nothing\n", ["no vertex"]),
    ],
)
def test_read_obj_errors_name_the_file(tmp_path: Path, text: str, words: list[str]) -> None:
    (tmp_path / "bad.obj").write_text(text)
    with pytest.raises(ConfigError, match=r"bad\.obj") as info:
        read_obj(tmp_path / "bad.obj")
    assert all(w in str(info.value) for w in words)
    with pytest.raises(ConfigError, match=r"absent\.obj"):
        read_obj(tmp_path / "absent.obj")


def test_flat_panel_becomes_one_board_mujoco_compiles(tmp_path: Path) -> None:
    v = [(0, 0, 0.5), (0.4, 0, 0.5), (0.4, 0.3, 0.5), (0, 0.3, 0.5)]
    pieces = convex_pieces(write_obj(tmp_path / "p.obj", v, [[0, 1, 2, 3]]), cache_dir=tmp_path)
    assert len(pieces) == 1
    np.testing.assert_allclose(np.ptp(pieces[0], axis=0), [0.4, 0.3, BOARD_THICKNESS], atol=1e-9)
    assert pieces[0][:, 2].mean() == pytest.approx(0.5)
    assert compile_pieces(pieces).nmesh == 1
    assert len(list(tmp_path.glob("*.npz"))) == 1  # every mesh's pieces: warm loads read them


def test_cube_is_one_piece_and_scale_applies(tmp_path: Path) -> None:
    v, quads = cuboid((0, 0, 0), (0.1, 0.1, 0.1))
    path = write_obj(tmp_path / "c.obj", v, quads)
    (piece,) = convex_pieces(path, cache_dir=tmp_path)
    assert len(piece) == 8
    (scaled,) = convex_pieces(path, (2.0, 1.0, 0.5), cache_dir=tmp_path)
    np.testing.assert_allclose(np.ptp(scaled, axis=0), [0.2, 0.1, 0.05])
    assert meshes.concavity(v, triangles(quads)) < 0.005  # [m] the sampling's resolution
    v, quads = solid_open_box()
    assert meshes.concavity(v, triangles(quads)) > CONCAVITY_LIMIT
    with pytest.raises(ConfigError, match=r"c\.obj"):
        convex_pieces(path, (1.0, float("nan"), 1.0), cache_dir=tmp_path)


def test_degenerate_meshes_give_no_piece(tmp_path: Path) -> None:
    triangle = write_obj(tmp_path / "t.obj", [(0, 0, 0), (1, 0, 0), (0, 1, 0)], [[0, 1, 2]])
    line = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (3, 0, 0)]
    collinear = write_obj(tmp_path / "l.obj", line, [[0, 1, 2], [1, 2, 3]])
    no_face = write_obj(tmp_path / "n.obj", line, [])
    for path in (triangle, collinear, no_face):
        assert convex_pieces(path, cache_dir=tmp_path) == ()


def test_separate_boards_in_one_mesh_stay_separate(tmp_path: Path) -> None:
    pieces = convex_pieces(write_obj(tmp_path / "b.obj", *five_boards()), cache_dir=tmp_path)
    assert len(pieces) == 5
    assert not any(contains(p, CENTRE) for p in pieces)
    np.testing.assert_allclose(sorted(principal_extents(p)[0] for p in pieces), [T] * 5)


def test_concave_mesh_is_decomposed_hollow_and_cached(tmp_path, monkeypatch) -> None:
    v, quads = solid_open_box()
    path = write_obj(tmp_path / "box.obj", v, quads)
    cache = tmp_path / "cache"
    pieces = convex_pieces(path, cache_dir=cache, progress=False)
    assert len(pieces) >= 3
    assert not any(contains(p, CENTRE) for p in pieces)
    assert all(principal_extents(p)[0] >= BOARD_THICKNESS - 1e-9 for p in pieces)
    assert compile_pieces(pieces).nmesh == len(pieces)
    assert len(list(cache.glob("*.npz"))) == 1

    def refuse(*args, **kwargs):
        raise AssertionError("CoACD ran although the result is cached")

    monkeypatch.setattr(meshes.coacd, "run_coacd", refuse)
    again = convex_pieces(path, cache_dir=cache, progress=False)
    assert len(again) == len(pieces)
    assert all(np.array_equal(a, b) for a, b in zip(again, pieces, strict=True))


def test_corrupt_cache_is_recomputed_with_progress(tmp_path, monkeypatch, capsys) -> None:
    calls = []
    halves = [cuboid((0, 0, 0), (W / 2, D, T))[0], cuboid((W / 2, 0, 0), (W, D, 2 * T))[0]]

    def fake(mesh, **kwargs):
        calls.append(kwargs)
        return [(h, np.zeros((0, 3), np.int32)) for h in halves]

    monkeypatch.setattr(meshes.coacd, "run_coacd", fake)
    monkeypatch.setenv("STRUG_MANIP_CACHE", str(tmp_path / "root"))
    assert meshes.default_cache_dir() == tmp_path / "root" / "coacd"
    path = write_obj(tmp_path / "box.obj", *solid_open_box())
    first = convex_pieces(path)
    assert "decomposing box.obj" in capsys.readouterr().err
    assert len(calls) == 1 and calls[0]["seed"] == 0
    (file,) = (tmp_path / "root" / "coacd").glob("*.npz")
    file.write_bytes(b"not a zip file")
    second = convex_pieces(path, progress=False)
    assert len(calls) == 2 and capsys.readouterr().err == ""
    assert all(np.array_equal(a, b) for a, b in zip(first, second, strict=True))
    assert [len(p) for p in second] == [8, 8]
    convex_pieces(path, (1.0, 1.0, 2.0), progress=False)  # another scale: another key
    assert len(calls) == 3


def test_importing_meshes_first_leaves_pinocchio_able_to_parse_urdf() -> None:
    """CoACD loaded before Pinocchio breaks urdfdom's number parsing; meshes.py imports
    Pinocchio first, whatever a user imports first (a fresh interpreter)."""
    import subprocess
    import sys

    code = (
        "import strug_manip.objects.meshes\n"
        "import pinocchio as pin\n"
        'x = \'<robot name="a"><link name="b"/><link name="c"/><joint name="j" '
        'type="revolute"><origin xyz="0 0 0.5" rpy="0 0 0"/><parent link="b"/>'
        '<child link="c"/><axis xyz="0 0 1"/><limit lower="0" upper="1" effort="1" '
        'velocity="1"/></joint></robot>\'\n'
        "print(pin.buildModelFromXML(x).nq)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "1"


def test_a_mesh_of_two_materials_keeps_each_and_its_texture_coordinates(tmp_path: Path) -> None:
    (tmp_path / "images").mkdir()
    (tmp_path / "objs").mkdir()
    image = np.full((4, 4, 3), (30, 60, 90), np.uint8)
    assert cv2.imwrite(str(tmp_path / "images" / "wood.jpg"), image)
    mtl = "newmtl grain\nKd 1 1 1\nmap_Kd ../images/wood.jpg\nnewmtl plain\nKd 0.2 0.4 0.6\n"
    (tmp_path / "objs" / "m.mtl").write_text(mtl)
    text = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
    text += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
    text += "usemtl grain\nf 1/1 2/2 3/3 4/4\nusemtl plain\nf 1/1 2/2 5/3\n"
    (tmp_path / "objs" / "two.obj").write_text(text)
    mesh = read_obj(tmp_path / "objs" / "two.obj")
    assert len(mesh.materials) == 2 and mesh.face_material.tolist() == [0, 0, 1]
    assert mesh.materials[0].texture == tmp_path / "images" / "wood.jpg"
    assert mesh.materials[1].texture is None
    assert mesh.materials[1].rgba == pytest.approx((0.2, 0.4, 0.6, 1.0))
    assert mesh.face_texcoords.tolist() == [[0, 1, 2], [0, 2, 3], [0, 1, 2]]
    assert mesh.rgba == mesh.materials[0].rgba  # the dominant material: 2 faces of 3
    # MuJoCo reads PNG, not JPEG: a PNG copy in the cache, the same pixels.
    png = meshes.png_texture(mesh.materials[0].texture, tmp_path / "cache")
    assert png.suffix == ".png" and png.parent == tmp_path / "cache" / "textures"
    assert np.array_equal(cv2.imread(str(png)), cv2.imread(str(tmp_path / "images" / "wood.jpg")))
    assert meshes.png_texture(png) == png
    assert meshes.png_texture(tmp_path / "images" / "absent.jpg") is None
