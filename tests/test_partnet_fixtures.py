"""The PartNet-Mobility look-alike fixtures (:mod:`partnet_fixtures`): the files only.

The loader that consumes them is tested elsewhere; here plain ``xml.etree`` and numpy
check that every fixture looks like a PartNet download and that what
:func:`partnet_fixtures.fixture_truth` promises is true of the files.
"""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import cv2
import numpy as np
import pytest
from partnet_fixtures import (
    BASE_RPY,
    BROKEN,
    BROKEN_MENTIONS,
    FIXTURES,
    fixture_truth,
    write_broken,
    write_fixture,
)

Pose = tuple[np.ndarray, np.ndarray]


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Every good and broken fixture, written once per module."""
    root = tmp_path_factory.mktemp("partnet")
    out = {name: write_fixture(root, name) for name in FIXTURES}
    out.update({name: write_broken(root, name) for name in BROKEN})
    return out


# ------------------------------------------------------------------ small readers


def _floats(text: str | None) -> np.ndarray:
    return np.array([float(v) for v in text.split()]) if text else np.zeros(3)


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    """URDF roll-pitch-yaw: ``Rz(y) @ Ry(p) @ Rx(r)``."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _axis_angle(axis: np.ndarray, q: float) -> np.ndarray:
    a = axis / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(q) * k + (1 - np.cos(q)) * k @ k


def _joints(root: ET.Element) -> dict[str, ET.Element]:
    """Child link name -> its joint."""
    return {j.find("child").get("link"): j for j in root.iter("joint")}


def _pose(root: ET.Element, link: str, q: dict[str, float] | None = None) -> Pose:
    """``(R, t)`` of ``link`` in the base frame, joints at ``q`` (name -> value; 0)."""
    q = q or {}
    joints = _joints(root)
    chain = []
    while link in joints:
        chain.append(joints[link])
        link = joints[link].find("parent").get("link")
    R, t = np.eye(3), np.zeros(3)
    for j in reversed(chain):
        o = j.find("origin")
        t = t + R @ _floats(o.get("xyz"))
        R = R @ _rpy(*_floats(o.get("rpy")))
        v = q.get(j.get("name"), 0.0)
        if j.get("type") in ("revolute", "continuous"):
            R = R @ _axis_angle(_floats(j.find("axis").get("xyz")), v)
        elif j.get("type") == "prismatic":
            t = t + R @ (_floats(j.find("axis").get("xyz")) * v)
    return R, t


def _obj(path: Path) -> tuple[np.ndarray, list[tuple[str, list[int]]]]:
    """Vertices (n, 3) and ``(material, 0-based vertex indices)`` faces of an OBJ."""
    verts, faces, mtl = [], [], ""
    for line in path.read_text().splitlines():
        words = line.split()
        if not words:
            continue
        if words[0] == "v":
            verts.append([float(w) for w in words[1:4]])
        elif words[0] == "usemtl":
            mtl = words[1]
        elif words[0] == "f":
            faces.append((mtl, [int(w.split("/")[0]) - 1 for w in words[1:]]))
    return np.array(verts), faces


def _meshes(folder: Path, root: ET.Element, link: str) -> list[tuple[str, Path, np.ndarray]]:
    """``(visual name, OBJ path, visual origin xyz)`` of every visual of ``link``."""
    (el,) = [lk for lk in root.iter("link") if lk.get("name") == link]
    return [
        (
            v.get("name"),
            folder / v.find("geometry/mesh").get("filename"),
            _floats(v.find("origin").get("xyz")),
        )
        for v in el.iter("visual")
    ]


def _with_helpers(root: ET.Element, link: str) -> list[str]:
    """``link`` and the links hanging on it by fixed joints."""
    out = [link]
    for j in root.iter("joint"):
        if j.get("type") == "fixed" and j.find("parent").get("link") in out:
            out.append(j.find("child").get("link"))
    return out


def _points(folder: Path, root: ET.Element, link: str, q: dict[str, float]) -> np.ndarray:
    """Every mesh vertex of ``link`` and its helpers in the base frame at ``q``."""
    pts = []
    for name in _with_helpers(root, link):
        R, t = _pose(root, name, q)
        for _, path, xyz in _meshes(folder, root, name):
            pts.append((_obj(path)[0] + xyz) @ R.T + t)
    return np.vstack(pts)


def _upper(root: ET.Element, link: str) -> tuple[str, float]:
    j = _joints(root)[link]
    return j.get("name"), float(j.find("limit").get("upper"))


# ------------------------------------------------------------------ every fixture


@pytest.mark.parametrize("name", FIXTURES + tuple(BROKEN))
def test_fixture_writes_a_partnet_folder(written: dict[str, Path], name: str) -> None:
    folder = written[name]
    assert folder.name == name
    for f in ("mobility.urdf", "semantics.txt", "meta.json", "bounding_box.json"):
        assert (folder / f).is_file(), f
    meta = json.loads((folder / "meta.json").read_text())
    assert meta["model_cat"] == "StorageFurniture"
    assert re.fullmatch(r"[0-9a-f]{32}", meta["model_id"])


def test_fixtures_are_deterministic(tmp_path: Path, written: dict[str, Path]) -> None:
    for name in ("mixed", "several_problems"):
        again = (write_fixture if name in FIXTURES else write_broken)(tmp_path, name)
        files = sorted(p.relative_to(again) for p in again.rglob("*") if p.is_file())
        assert files == sorted(
            p.relative_to(written[name]) for p in written[name].rglob("*") if p.is_file()
        )
        for f in files:
            assert (again / f).read_bytes() == (written[name] / f).read_bytes(), f


@pytest.mark.parametrize("name", FIXTURES)
def test_urdf_is_written_as_partnet_writes_it(written: dict[str, Path], name: str) -> None:
    folder = written[name]
    text = (folder / "mobility.urdf").read_text()
    assert text.startswith('<?xml version="1.0" ?>\n<robot name="partnet_')
    root = ET.parse(folder / "mobility.urdf").getroot()
    assert re.fullmatch(r"partnet_[0-9a-f]{32}", root.get("name"))
    links = root.findall("link")
    assert links[0].get("name") == "base" and len(links[0]) == 0
    assert all(re.fullmatch(r"link_\d+", lk.get("name")) for lk in links[1:])
    assert not list(root.iter("inertial")) and not list(root.iter("dynamics"))
    base_joints = [j for j in root.iter("joint") if j.find("parent").get("link") == "base"]
    (bj,) = base_joints
    assert bj.get("type") == "fixed"
    assert bj.find("origin").get("rpy") == BASE_RPY
    for j in root.iter("joint"):
        kind = j.get("type")
        assert kind in ("fixed", "prismatic", "revolute", "continuous")
        limit = j.find("limit")
        if kind in ("prismatic", "revolute"):
            assert set(limit.attrib) == {"lower", "upper"}
            assert float(limit.get("upper")) > float(limit.get("lower")) >= 0.0
            assert j.find("axis") is not None
        else:
            assert limit is None
    for lk in links[1:]:
        visuals, collisions = lk.findall("visual"), lk.findall("collision")
        assert all(re.fullmatch(r"[a-z_]+-\d+", v.get("name")) for v in visuals)
        assert all(c.get("name") is None for c in collisions)
        meshes = [v.find("geometry/mesh").get("filename") for v in visuals]
        assert meshes == [c.find("geometry/mesh").get("filename") for c in collisions]
        assert [v.find("origin").get("xyz") for v in visuals] == [
            c.find("origin").get("xyz") for c in collisions
        ]
        for filename in meshes:
            assert re.fullmatch(r"textured_objs/original-\d+\.obj", filename)
            assert (folder / filename).is_file(), filename


@pytest.mark.parametrize("name", FIXTURES)
def test_meshes_and_materials(written: dict[str, Path], name: str) -> None:
    """Every OBJ names an existing .mtl, every texture exists; each fixture has an
    exactly flat (zero-thickness) OBJ and a closed 8-vertex board."""
    folder = written[name]
    flat = closed_board = 0
    for obj in sorted((folder / "textured_objs").glob("*.obj")):
        text = obj.read_text()
        assert text.startswith("# SSTK version 0.8.0\n")
        (mtllib,) = re.findall(r"^mtllib (\S+)$", text, flags=re.M)
        mtl = (obj.parent / mtllib).read_text()
        for used in set(re.findall(r"^usemtl (\S+)$", text, flags=re.M)):
            assert f"newmtl {used}\n" in mtl
        assert re.search(r"^Kd [\d.]+ [\d.]+ [\d.]+ $", mtl, flags=re.M)
        for texture in re.findall(r"^map_Kd (\S+)$", mtl, flags=re.M):
            img = cv2.imread(str(obj.parent / texture))
            assert img is not None and img.shape[2] == 3
        verts, faces = _obj(obj)
        assert np.all(np.array([i for _, f in faces for i in f]) < len(verts))
        if np.any(np.ptp(verts, axis=0) == 0.0):
            flat += 1
        if len(verts) == 8 and len(faces) == 12:
            edges: dict[tuple[int, int], int] = {}
            for _, f in faces:
                for a, b in zip(f, f[1:] + f[:1], strict=True):
                    edges[min(a, b), max(a, b)] = edges.get((min(a, b), max(a, b)), 0) + 1
            closed_board += all(n == 2 for n in edges.values())
    assert flat >= 1 and closed_board >= 1


def test_drawer_box_is_one_concave_open_mesh(written: dict[str, Path]) -> None:
    folder = written["drawers"]
    root = ET.parse(folder / "mobility.urdf").getroot()
    (box,) = [p for name, p, _ in _meshes(folder, root, "link_0") if name.startswith("drawer_box")]
    verts, faces = _obj(box)
    assert len(verts) == 5 * 8 and len(faces) == 5 * 12
    # open at the top: the vertices at the top height all sit on the walls' rims
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    top = verts[verts[:, 1] == hi[1]]
    inner = np.all(
        np.abs(top[:, [0, 2]] - 0.5 * (lo + hi)[[0, 2]]) < 0.5 * (hi - lo)[[0, 2]] - 0.02, axis=1
    )
    assert len(top) == 4 * 4 and not np.any(inner)  # four walls, no lid


@pytest.mark.parametrize("name", FIXTURES + tuple(BROKEN))
def test_semantics_lines_have_three_words(written: dict[str, Path], name: str) -> None:
    text = (written[name] / "semantics.txt").read_text()
    assert text.endswith("\n")
    lines = text.splitlines()
    for line in lines:
        words = line.split(" ")
        assert len(words) == 3, line
        assert re.fullmatch(r"link_\d+", words[0])
        assert words[1] in ("slider", "hinge", "heavy", "free", "static")
    if name != "malformed_urdf":
        root = ET.parse(written[name] / "mobility.urdf").getroot()
        links = [lk.get("name") for lk in root.iter("link")][1:]
        assert [line.split()[0] for line in lines] == links


# ------------------------------------------------------------------ conventions


@pytest.mark.parametrize("name", FIXTURES)
def test_drawers_open_toward_minus_x(written: dict[str, Path], name: str) -> None:
    """After the base joint's rotation a drawer slides out along base -x."""
    root = ET.parse(written[name] / "mobility.urdf").getroot()
    drawers = [j for j in root.iter("joint") if j.get("type") == "prismatic"]
    assert len(drawers) == sum(p["kind"] == "drawer" for p in fixture_truth(name)["parts"].values())
    for j in drawers:
        child = j.find("child").get("link")
        upper = float(j.find("limit").get("upper"))
        _, t0 = _pose(root, child)
        _, t1 = _pose(root, child, {j.get("name"): upper})
        np.testing.assert_allclose(t1 - t0, [-upper, 0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize("name", FIXTURES)
def test_doors_open_outward_and_hinge_sides_match_truth(
    written: dict[str, Path], name: str
) -> None:
    folder = written[name]
    root = ET.parse(folder / "mobility.urdf").getroot()
    for link, part in fixture_truth(name)["parts"].items():
        if part["kind"] != "door":
            continue
        joint, upper = _upper(root, link)
        assert _joints(root)[link].get("type") == "revolute"
        closed = _points(folder, root, link, {})
        opened = _points(folder, root, link, {joint: upper})
        c0, c1 = closed.mean(axis=0), opened.mean(axis=0)
        assert c1[0] < c0[0] - 0.05, "a door swings out of the front (-x)"
        R, hinge = _pose(root, link)
        axis = R @ _floats(_joints(root)[link].find("axis").get("xyz"))
        if abs(axis[2]) > 0.99:  # vertical hinge; a person at -x facing +x has +y on the left
            side = "right" if hinge[1] < c0[1] else "left"
        else:
            assert abs(axis[1]) > 0.99
            side = "bottom" if hinge[2] < c0[2] else "top"
        assert side == part["hinge"], link
        # gravity (-z) on the vertex centroid, about the hinge, toward opening (+q)
        torque = np.cross(c0 - hinge, [0.0, 0.0, -1.0]) @ axis
        assert (torque > 1e-6) == part["falls_open"], link


@pytest.mark.parametrize("name", FIXTURES)
def test_truth_matches_the_files(written: dict[str, Path], name: str) -> None:
    folder = written[name]
    truth = fixture_truth(name)
    root = ET.parse(folder / "mobility.urdf").getroot()
    joints = _joints(root)
    words = dict(
        (line.split()[0], line.split()[1:])
        for line in (folder / "semantics.txt").read_text().splitlines()
    )
    assert joints[truth["carcass"]].find("parent").get("link") == "base"
    assert words[truth["carcass"]] in (["heavy", "furniture_body"], ["free", "furniture_body"])
    movable = {c for c, j in joints.items() if j.get("type") in ("prismatic", "revolute")}
    assert set(truth["parts"]) == movable
    for link, part in truth["parts"].items():
        j = joints[link]
        assert j.get("name") == part["joint"]
        assert j.get("type") == {"drawer": "prismatic", "door": "revolute"}[part["kind"]]
        assert words[link][0] == {"drawer": "slider", "door": "hinge"}[part["kind"]]
        handles = {
            n
            for h in _with_helpers(root, link)
            for n, _, _ in _meshes(folder, root, h)
            if n.startswith("handle-")
        }
        assert len(handles) == part["handles"], link
    helpers = {
        c: j.find("parent").get("link")
        for c, j in joints.items()
        if j.get("type") == "fixed" and j.find("parent").get("link") != "base"
    }
    assert helpers == truth["helpers"]
    assert all(words[h][0] == "static" for h in helpers)
    continuous = tuple(c for c, j in joints.items() if j.get("type") == "continuous")
    assert continuous == truth["continuous"]
    assert all(words[c] == ["hinge", "wheel"] for c in continuous)
    box = json.loads((folder / "bounding_box.json").read_text())
    assert abs(box["max"][1] - box["min"][1] - truth["height"]) < 1e-5
    assert 0.6 <= truth["height"] <= 1.2


def test_every_fixture_has_its_quirk(written: dict[str, Path]) -> None:
    roots = {n: ET.parse(written[n] / "mobility.urdf").getroot() for n in FIXTURES}
    assert any(fixture_truth(n)["helpers"] for n in FIXTURES)
    assert any(fixture_truth(n)["continuous"] for n in FIXTURES)
    lowers = {
        j.find("limit").get("lower")
        for r in roots.values()
        for j in r.iter("joint")
        if j.get("type") == "revolute"
    }
    assert {"0.0", "-0.0"} <= lowers
    assert any(lk.get("name") != "base" and len(lk) == 0 for lk in roots["doors"].iter("link"))
    assert (written["mixed"] / "images" / "texture_0.png").is_file()
    hinges = {p.get("hinge") for n in FIXTURES for p in fixture_truth(n)["parts"].values()}
    assert {"left", "right", "bottom"} <= hinges


@pytest.mark.parametrize("name", FIXTURES)
def test_closed_parts_clear_the_carcass(written: dict[str, Path], name: str) -> None:
    """No two bodies' meshes interpenetrate (axis-aligned boxes, mesh frame) when the
    parts are closed, nor when a drawer is fully open."""
    folder = written[name]
    root = ET.parse(folder / "mobility.urdf").getroot()
    truth = fixture_truth(name)
    bodies = [truth["carcass"], *truth["parts"], *truth["continuous"]]
    boxes: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for body in bodies:
        boxes[body] = []
        for link in _with_helpers(root, body):
            for _, path, _ in _meshes(folder, root, link):
                v = _obj(path)[0]
                boxes[body].append((v.min(axis=0), v.max(axis=0)))

    def overlap(a: list, b: list, shift: np.ndarray) -> bool:
        return any(
            np.all(np.minimum(ah + shift, bh) - np.maximum(al + shift, bl) > 1e-9)
            for al, ah in a
            for bl, bh in b
        )

    for i, a in enumerate(bodies):
        for b in bodies[i + 1 :]:
            assert not overlap(boxes[a], boxes[b], np.zeros(3)), (a, b)
    for link, part in truth["parts"].items():
        if part["kind"] == "drawer":
            travel = np.array([0.0, 0.0, _upper(root, link)[1]])  # mesh +z: out of the front
            assert not overlap(boxes[link], boxes[truth["carcass"]], travel), link


# ------------------------------------------------------------------ broken fixtures


def _referenced(folder: Path) -> list[str]:
    root = ET.parse(folder / "mobility.urdf").getroot()
    return [m.get("filename") for m in root.iter("mesh")]


def test_broken_fixtures_hold_their_defects(written: dict[str, Path]) -> None:
    assert set(BROKEN) == {
        "missing_mesh",
        "malformed_urdf",
        "unsupported_joint",
        "no_movable_part",
        "several_problems",
    }
    for name, mention in BROKEN.items():
        assert mention == BROKEN_MENTIONS[name][0]

    def missing(name: str) -> list[str]:
        folder = written[name]
        return sorted({Path(f).name for f in _referenced(folder) if not (folder / f).is_file()})

    assert missing("missing_mesh") == [BROKEN["missing_mesh"]]
    with pytest.raises(ET.ParseError):
        ET.parse(written["malformed_urdf"] / "mobility.urdf")
    types = {
        n: [j.get("type") for j in ET.parse(written[n] / "mobility.urdf").getroot().iter("joint")]
        for n in ("unsupported_joint", "no_movable_part", "several_problems")
    }
    assert "floating" in types["unsupported_joint"]
    assert set(types["no_movable_part"]) == {"fixed"}
    mesh, joint_type, undefined = BROKEN_MENTIONS["several_problems"]
    assert missing("several_problems") == [mesh]
    assert joint_type in types["several_problems"]
    root = ET.parse(written["several_problems"] / "mobility.urdf").getroot()
    links = {lk.get("name") for lk in root.iter("link")}
    assert undefined not in links
    assert undefined in {j.find("parent").get("link") for j in root.iter("joint")}


def test_unknown_names_are_refused(tmp_path: Path) -> None:
    with pytest.raises(KeyError):
        write_fixture(tmp_path, "missing_mesh")
    with pytest.raises(KeyError):
        write_broken(tmp_path, "drawers")
    with pytest.raises(KeyError):
        fixture_truth("nope")
