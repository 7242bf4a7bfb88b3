"""Real PartNet-Mobility objects, as downloaded, on fixtures the suite writes
(:mod:`partnet_fixtures`: zero-thickness panels, y-up meshes under PartNet's base
rotation, the front toward -x, no dynamics or inertials, helper links, continuous
joints, handles named only in visual names): they load, stand still, are described
like generated cabinets, hold an object in a drawer, and the skills open them."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import mujoco
import numpy as np
import pytest
from partnet_fixtures import BROKEN, BROKEN_MENTIONS, FIXTURES, fixture_truth, write_broken
from partnet_fixtures import write_fixture as write_partnet_fixture

from planners.errors import ConfigError
from strug_manip.cli import main
from strug_manip.control import ControlContext, OpenDoor, OpenDrawer
from strug_manip.control.grasps import handle_grasps
from strug_manip.domains.manipulation.rules import dragged
from strug_manip.domains.manipulation.tasks import OpenDoorTask
from strug_manip.objects import load_articulated_object
from strug_manip.objects.describe import describe_object
from strug_manip.objects.generator import HEIGHT_RANGE, TOTAL_MASS
from strug_manip.objects.hypotheses import BelievedJoint
from strug_manip.objects.loader import object_folders
from strug_manip.world import ManipulationWorld, SceneConfig


@pytest.fixture(scope="module")
def folders(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Path]]:
    """Every fixture written once; convex decompositions cached in a folder of the
    module's own (never the user's cache)."""
    root = tmp_path_factory.mktemp("partnet")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("STRUG_MANIP_CACHE", str(root / "cache"))
        yield {name: write_partnet_fixture(root, name) for name in FIXTURES}


def _warnings(data: mujoco.MjData) -> int:
    return sum(int(data.warning[i].number) for i in range(len(data.warning)))


@pytest.mark.parametrize("name", FIXTURES)
def test_a_downloaded_object_loads_stands_still_and_is_described(
    folders: dict[str, Path], name: str
) -> None:
    obj = load_articulated_object(folders[name], progress=False)
    truth = fixture_truth(name)
    # Scaled into the generator's envelope, with a generated cabinet's mass.
    size = obj.bounds[1] - obj.bounds[0]
    assert HEIGHT_RANGE[0] * 0.95 <= size[2] <= HEIGHT_RANGE[1] * 1.05 + 0.05
    assert TOTAL_MASS[0] - 1e-6 <= obj.mass <= TOTAL_MASS[1] + 1e-6
    m = obj.mj_model
    data = mujoco.MjData(m)
    mujoco.mj_forward(m, data)
    root = m.body(obj.root).id
    start, quat = data.xpos[root].copy(), data.xquat[root].copy()
    q0 = data.qpos[7:].copy()
    for _ in range(int(2.0 / m.opt.timestep)):
        mujoco.mj_step(m, data)
    assert _warnings(data) == 0
    assert np.linalg.norm(data.xpos[root] - start) < 0.002  # no drift, no tipping
    assert abs(abs(float(quat @ data.xquat[root])) - 1.0) < 1e-4
    # Parts stay where they are (no drawer sliding shut, no flap falling open).
    assert np.abs(data.qpos[7:] - q0).max() < 0.01
    # The description: kinds, hinge sides, handles, all from the object itself.
    spec = describe_object(obj)
    parts = {p.link: p for p in spec.parts}
    for link, want in truth["parts"].items():
        part = parts[link]
        assert part.kind == want["kind"], link
        if want["kind"] == "door":
            assert part.hinge == want["hinge"], link
        assert (part.handle != "none") == (want["handles"] > 0), link
        assert part.upper > 0 and part.lower == 0.0  # positive positions open
    assert spec.carcass == truth["carcass"]


def test_a_box_dropped_into_an_open_drawer_rests_inside(folders: dict[str, Path]) -> None:
    obj = load_articulated_object(folders["drawers"], free=False, progress=False)
    spec = describe_object(obj)
    drawer = next(p for p in spec.parts if p.kind == "drawer" and p.interior_size is not None)
    q = 0.8 * drawer.upper
    inner_c = drawer.point_at(drawer.interior_center, q)
    scene = mujoco.MjSpec.from_string(obj.to_mjcf())
    half = 0.025
    box = scene.worldbody.add_body(name="box", pos=[*inner_c[:2], inner_c[2] + 0.05])
    box.add_freejoint()
    box.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[half] * 3, mass=0.2)
    m = scene.compile()
    data = mujoco.MjData(m)
    data.qpos[m.jnt_qposadr[m.joint(drawer.joint).id]] = q
    for _ in range(int(1.5 / m.opt.timestep)):
        mujoco.mj_step(m, data)
    assert _warnings(data) == 0
    p = data.body("box").xpos - data.body(obj.root).xpos  # object frame: no turn, no scale
    lo = drawer.point_at(drawer.interior_center - drawer.interior_size / 2, q)
    hi = drawer.point_at(drawer.interior_center + drawer.interior_size / 2, q)
    assert np.all(p[:2] > lo[:2]) and np.all(p[:2] < hi[:2]), (p, lo, hi)
    assert lo[2] - 0.003 <= p[2] - half < lo[2] + 0.02  # on the bottom (contact: mm)
    assert np.linalg.norm(data.qvel[-6:]) < 0.05


@pytest.mark.parametrize(("name", "kind"), [("drawers", "drawer"), ("doors", "door")])
def test_the_skills_open_a_downloaded_object_under_its_own_description(
    folders: dict[str, Path], name: str, kind: str
) -> None:
    world = ManipulationWorld(SceneConfig(cabinet_folder=folders[name]))
    try:
        spec, T = world.scene.cabinet_spec, world.scene.T_world_cabinet
        part = next(p for p in spec.parts if p.kind == kind and p.handle != "none")
        joint = BelievedJoint.of_part(part, 0.0, T)
        skill = OpenDrawer if kind == "drawer" else OpenDoor
        ctx = ControlContext()
        out = None
        for g in handle_grasps(part, 0.0, T):
            world.reset()
            out = skill(g, joint).run(world, ctx=ctx)
            if out.status != "ik_infeasible":
                break
        assert out is not None and out.ok, out.status
        moved = out.motion_of(world.scene.cabinet_prefix + part.joint)
        assert moved > (0.10 if kind == "drawer" else 0.6)  # [m] / [rad]
        assert not dragged(out.cabinet_displacement)
    finally:
        world.close()


@pytest.mark.parametrize("name", sorted(BROKEN))
def test_a_broken_object_gives_one_line_naming_the_file_and_every_problem(
    tmp_path: Path, name: str
) -> None:
    folder = write_broken(tmp_path, name)
    with pytest.raises(ConfigError) as info:
        load_articulated_object(folder, progress=False)
    message = str(info.value)
    assert "\n" not in message
    assert str(folder) in message
    for word in BROKEN_MENTIONS[name]:
        assert word in message, (word, message)


def test_object_folders_lists_a_folder_of_objects(folders: dict[str, Path], tmp_path: Path):
    root = next(iter(folders.values())).parent
    assert object_folders(root) == tuple(sorted(folders.values()))
    assert object_folders(folders["doors"]) == (folders["doors"],)
    with pytest.raises(ConfigError, match="holds no object"):
        object_folders(tmp_path)
    with pytest.raises(ConfigError, match="not found"):
        object_folders(tmp_path / "missing")


def _error_line(argv: list[str], capsys) -> str:
    """``strug argv``'s one error line (exit 2)."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's errors
        code = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("strug: error: "), err
    return err[0]


def test_the_commands_take_an_object_folder(folders: dict[str, Path], tmp_path: Path, capsys):
    out = tmp_path / "scene.png"
    assert main(["scene", "--object", str(folders["mixed"]), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "object mixed" in printed and "door" in printed and "drawer" in printed
    assert out.stat().st_size > 10_000
    line = _error_line(["run", "--domain", "tiger", "--solver", "strug",
                        "--object", str(folders["mixed"])], capsys)  # fmt: skip
    assert "--object" in line and "tiger" in line
    line = _error_line(["run", "--domain", "opendrawer", "--solver", "strug",
                        "--target", "link_1"], capsys)  # fmt: skip
    assert "--target" in line
    bench = ["bench", "--domains", "opendrawer", "--solvers", "strug", "--seeds", "1"]
    line = _error_line([*bench, "--objects", str(tmp_path), "--out", str(tmp_path / "b")], capsys)
    assert "holds no object" in line


def test_a_task_on_an_object_names_its_target_by_link(folders: dict[str, Path]) -> None:
    task = OpenDoorTask(objects=(folders["mixed"],), target_link="link_1", particles=4)
    with pytest.raises(ConfigError, match="is a drawer"):
        task.environment.reset(np.random.default_rng(0))
    door = next(p for p, t in fixture_truth("mixed")["parts"].items() if t["kind"] == "door")
    task = OpenDoorTask(objects=(folders["mixed"],), target_link=door, particles=4)
    task.environment.reset(np.random.default_rng(0))
    try:
        assert task.real.target == door
        assert task.real.world.scene.cabinet_spec.name == "mixed"
    finally:
        task.close()


def test_a_textured_front_wears_its_texture(folders: dict[str, Path]) -> None:
    """The fixture's drawer front has a PNG texture and texture coordinates: the loaded
    model maps it (a material with the texture on the front's visual geom)."""
    obj = load_articulated_object(folders["mixed"], progress=False)
    m = obj.mj_model
    assert m.ntex >= 1 and m.nmat >= 1
    textured = [g for g in range(m.ngeom) if m.geom_matid[g] >= 0]
    assert textured and all(m.geom_contype[g] == 0 for g in textured)  # visual geoms
    assert all(m.mesh_texcoordnum[m.geom_dataid[g]] > 0 for g in textured)
