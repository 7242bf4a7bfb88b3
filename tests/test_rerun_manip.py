"""The manipulation episode's rerun recording: geometry, poses, camera, joints, replay, the
belief per part and the blueprint (the layout the viewer opens with); and the PNG strip of
camera images."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import rerun as rr

from planners.errors import ConfigError
from planners.particles import ParticleBelief
from strug_manip.control.outcome import Outcome, Status
from strug_manip.domains.manipulation.actions import CataloguePart
from strug_manip.experiments.rerun_log import (
    MANIPULATION_VIEWS,
    ManipulationLog,
    manipulation_blueprint,
)
from strug_manip.experiments.rerun_manip import (
    WorldLogger,
    episode_strip,
    log_camera,
    log_joints,
    scene_eye,
)
from strug_manip.objects.hypotheses import BelievedJoint
from strug_manip.world import ManipulationWorld, SceneConfig
from strug_manip.world.views import cabinet_cloud


@pytest.fixture(scope="module")
def world() -> ManipulationWorld:
    w = ManipulationWorld(SceneConfig(cabinet_seed=5))
    yield w
    w.close()


def _rows(path: Path) -> dict[str, dict[str, list]]:
    """entity path -> column -> its values, row by row (components as Python values,
    timelines as integers: sequence numbers or nanoseconds)."""
    import pyarrow as pa
    from rerun.chunk import RrdReader

    out: dict[str, dict[str, list]] = {}
    for chunk in RrdReader(path).stream().to_chunks():
        batch = chunk.to_record_batch()
        cols = out.setdefault(chunk.entity_path, {})
        for name in batch.schema.names:
            col = batch.column(name)
            if ":" not in name and pa.types.is_temporal(col.type):
                col = col.cast(pa.int64())
            cols.setdefault(name, []).extend(col.to_pylist())
    return out


def _verify(path: Path) -> None:
    exe = Path(sys.executable).parent / "rerun"
    run = subprocess.run(
        [str(exe), "rrd", "verify", str(path)], capture_output=True, text=True, timeout=60
    )
    assert run.returncode == 0, run.stderr[-2000:]


def _replay_outcome(world: ManipulationWorld, joint: str, values: list[float]) -> Outcome:
    """An Outcome whose recording moves one cabinet joint through ``values``."""
    adr = world.model.jnt_qposadr[world.model.joint(joint).id]
    qpos = np.tile(world.data.qpos, (len(values), 1))
    qpos[:, adr] = values
    return Outcome(
        skill="replay", status=Status.OK, detail="", phase="", part_motion={},
        part_units={}, part_positions={}, cabinet_displacement=0.0, cabinet_motion=0.0,
        object_pose=np.eye(4), holding=False,
        times=0.1 * np.arange(len(values)), qpos=qpos,
    )  # fmt: skip


def _recording(tmp_path: Path, name: str) -> tuple[Path, rr.RecordingStream]:
    """A new stream saving to ``tmp_path / name.rrd``."""
    path = tmp_path / f"{name}.rrd"
    stream = rr.RecordingStream(f"test_rerun_manip_{name}")
    stream.save(str(path))
    return path, stream


def test_recording_verifies_with_geometry_poses_camera_and_joints(
    world: ManipulationWorld, tmp_path: Path
) -> None:
    path, stream = _recording(tmp_path, "episode")
    logger = WorldLogger(stream, world)
    stream.set_time("step", sequence=0)
    logger.log_pose()
    frame = world.render("head_camera")
    cloud = cabinet_cloud(world, frame)
    log_camera(stream, "world/head_camera", frame, cloud)
    joints = [
        BelievedJoint("prismatic", np.array([1.0, 0.0, 0.0]), np.array([1.0, 0.0, 1.0])),
        BelievedJoint("revolute", np.array([0.0, 0.0, 1.0]), np.array([1.2, 0.2, 0.9])),
    ]
    log_joints(stream, "world/joints", joints, np.array([0.2, 0.8]))
    stream.disconnect()  # writes the footer `rrd verify` checks
    _verify(path)

    kinds = list(logger.kinds.values())
    assert kinds.count("Mesh3D") >= 1 and kinds.count("Boxes3D") >= 1
    assert sorted(logger.kinds) == sorted(logger.entities)
    rows = _rows(path)
    assert {"/" + e for e in logger.entities} <= set(rows)
    floor = rows["/world/world/floor"]["Boxes3D:half_sizes"][0][0]
    assert floor[2] > 0 and min(floor[:2]) >= 1.0  # the plane: a large flat box
    mesh = next(e for e in logger.entities if logger.kinds[e] == "Mesh3D")
    assert len(rows["/" + mesh]["Mesh3D:vertex_positions"][0]) > 3
    # A moving body's logged pose (the fast path's arrow slices) is its pose in the world.
    m, d = world.model, world.data
    for name in ("wrist_roll_link", "cabinet/link_1"):
        b = m.body(name).id
        got = rows["/" + logger.body_paths[name]]
        np.testing.assert_allclose(got["Transform3D:translation"][-1][0], d.xpos[b], atol=1e-6)
        q = got["Transform3D:quaternion"][-1][0]
        np.testing.assert_allclose(q, d.xquat[b][[1, 2, 3, 0]], atol=1e-6)
    cam = rows["/world/head_camera"]
    np.testing.assert_allclose(
        cam["Transform3D:translation"][0][0], frame.T_world_camera[:3, 3], atol=1e-6
    )
    assert "Pinhole:image_from_camera" in rows["/world/head_camera/image"]
    assert "Image:buffer" in rows["/world/head_camera/image/rgb"]
    assert "DepthImage:buffer" in rows["/world/head_camera/image/depth"]
    assert len(rows["/world/head_camera_cloud"]["Points3D:positions"][0]) == len(cloud) > 0
    arrows = rows["/world/joints"]
    assert arrows["Arrows3D:labels"][0] == ["prismatic", "revolute"]
    light, dark = arrows["Arrows3D:colors"][0]  # packed RGBA: the heavier is darker
    assert (dark >> 24) < (light >> 24)


def test_log_replay_logs_every_frame_and_leaves_the_world_as_it_was(
    world: ManipulationWorld, tmp_path: Path
) -> None:
    path, stream = _recording(tmp_path, "replay")
    logger = WorldLogger(stream, world)
    joint = world.part_joints[0]
    outcome = _replay_outcome(world, joint, [0.0, 0.1, 0.2])
    before = world.snapshot().key
    end = logger.log_replay(outcome, t0=2.0)
    assert end == pytest.approx(2.2)
    assert world.snapshot().key == before
    stream.disconnect()
    _verify(path)

    m = world.model
    part = m.body(int(m.jnt_bodyid[m.joint(joint).id])).name
    got = _rows(path)["/" + logger.body_paths[part]]
    assert got["sim_time"] == [2_000_000_000, 2_100_000_000, 2_200_000_000]  # [ns]
    poses = [
        t[0] + q[0]
        for t, q in zip(got["Transform3D:translation"], got["Transform3D:quaternion"], strict=True)
    ]
    assert not np.allclose(poses[0], poses[2], atol=1e-4)  # the part moved in the replay


def test_log_replay_thins_frames_but_keeps_the_last(
    world: ManipulationWorld, tmp_path: Path
) -> None:
    path, stream = _recording(tmp_path, "thin")
    logger = WorldLogger(stream, world)
    outcome = _replay_outcome(world, world.part_joints[0], [0.0, 0.02, 0.04, 0.06, 0.08])
    assert logger.log_replay(outcome, every=3) == pytest.approx(0.4)
    with pytest.raises(ConfigError):
        logger.log_replay(outcome, every=0)
    stream.disconnect()
    got = _rows(path)["/" + logger.body_paths["base_link"]]
    assert got["sim_time"] == [0, 300_000_000, 400_000_000]  # frames 0, 3 and the last [ns]


def test_bad_inputs_are_config_errors(world: ManipulationWorld, tmp_path: Path) -> None:
    stream = rr.RecordingStream("test_rerun_manip_errors")
    stream.memory_recording()
    joint = BelievedJoint("prismatic", np.array([1.0, 0.0, 0.0]))
    with pytest.raises(ConfigError, match="weights"):
        log_joints(stream, "world/joints", [joint], np.array([0.5, 0.5]))
    with pytest.raises(ConfigError, match="labels"):
        episode_strip([np.zeros((4, 4, 3), np.uint8)], tmp_path / "x.png", labels=["a", "b"])
    outcome = _replay_outcome(world, world.part_joints[0], [0.0])
    with pytest.raises(ConfigError, match="qpos"):
        WorldLogger(stream, world).log_replay(dataclasses.replace(outcome, qpos=np.zeros((1, 3))))


@pytest.mark.parametrize("labels", [None, ["reach", "grasp", "open"]])
def test_episode_strip_puts_the_images_side_by_side(
    tmp_path: Path, labels: list[str] | None
) -> None:
    from matplotlib.image import imread

    rng = np.random.default_rng(0)
    images = [rng.integers(0, 255, (40, 60, 3), dtype=np.uint8) for _ in range(3)]
    out = episode_strip(images, tmp_path / "sub" / "strip.png", labels)
    assert out == tmp_path / "sub" / "strip.png" and out.is_file()
    h, w = imread(out).shape[:2]
    assert w == 180  # three 60 px images at their native resolution
    assert h == 40 if labels is None else 40 < h < 80  # a title band above


def _blueprint(path: Path) -> dict[str, dict[str, list]]:
    """The recording's blueprint: view title -> its components and its properties' (the
    last row of each, keyed ``Archetype:field``), with ``origin`` and ``class``."""
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    (store,) = reader.blueprints()
    rows: dict[str, dict[str, list]] = {}
    for chunk in reader.stream(store=store).to_chunks():
        parts = chunk.entity_path.split("/")  # /view/<id>[/Property]
        if parts[1] != "view":
            continue
        batch = chunk.to_record_batch()
        view = rows.setdefault(parts[2], {})
        for name in batch.schema.names:
            if ":" in name:
                view[name] = batch.column(name)[-1].as_py()
    views = {}
    for props in rows.values():
        if "ViewBlueprint:display_name" in props:
            props["origin"] = "/" + props["ViewBlueprint:space_origin"][0].strip("/")
            props["class"] = props["ViewBlueprint:class_identifier"][0]
            views[props["ViewBlueprint:display_name"][0]] = props
    return views


def test_blueprint_names_its_views_and_looks_at_the_robot_and_the_cabinet(
    world: ManipulationWorld, tmp_path: Path
) -> None:
    path, stream = _recording(tmp_path, "blueprint")
    WorldLogger(stream, world)
    eye, target = scene_eye(world)
    stream.send_blueprint(manipulation_blueprint((eye, target)))
    stream.disconnect()
    _verify(path)

    views = _blueprint(path)
    assert set(views) == set(MANIPULATION_VIEWS)
    scene = views["scene"]
    assert (scene["class"], scene["origin"]) == ("3D", "/world")
    assert {"+ /world/**", "+ /belief/joints", "+ /camera_cloud", "- /camera/image/depth"} <= set(
        scene["ViewContents:query"]
    )
    np.testing.assert_allclose(scene["EyeControls3D:position"][0], eye, atol=1e-5)
    np.testing.assert_allclose(scene["EyeControls3D:look_target"][0], target, atol=1e-5)
    for name, image in (("head camera: colour", "rgb"), ("head camera: depth [m]", "depth")):
        view = views[name]
        assert (view["class"], view["origin"]) == ("2D", "/camera/image")
        assert view["ViewContents:query"] == [f"$origin/{image}"]
    assert (views["belief per part"]["class"], views["belief per part"]["origin"]) == (
        "TextDocument",
        "/belief/parts",
    )
    assert views["Q per action"]["origin"] == "/search/q_table"
    assert (views["step log"]["class"], views["step log"]["origin"]) == ("TextLog", "/log")
    # The eye: behind the robot (the cabinet ahead along +x), above, looking between them.
    m, d = world.model, world.data
    base, cabinet = d.xpos[m.body("base_link").id], d.xpos[m.body("cabinet/base").id]
    assert base[0] < target[0] < cabinet[0] and eye[0] < base[0] and eye[2] > 1.2


def test_belief_per_part_is_a_table_and_a_named_series_per_hypothesis(tmp_path: Path) -> None:
    from types import SimpleNamespace

    path, stream = _recording(tmp_path, "parts")
    parts = (
        CataloguePart(np.array([1.0, 0.1, 1.17]), ("a", "a", "a"), ("drawer", "left"), (0, 1)),
        CataloguePart(np.array([1.0, 0.1, 0.80]), ("b", None, "b"), ("drawer",), (0,)),
    )
    classes = {0: ("drawer", "drawer"), 1: ("left", None), 2: ("drawer", "drawer")}
    pomdp = SimpleNamespace(parts=parts, entropy_key=classes.__getitem__)
    belief = ParticleBelief([0, 1, 2], np.array([0.5, 0.25, 0.25]), np.arange(3))
    stream.set_time("step", sequence=0)
    ManipulationLog(stream)._log_parts(pomdp, belief)
    stream.disconnect()

    rows = _rows(path)
    (table,) = rows["/belief/parts"]["TextDocument:text"][0]
    lines = table.splitlines()
    assert lines[0].startswith("belief after the step: ESS 2.7 of 3")
    assert lines[4].startswith("| part@(y=+0.10, z=1.17) | drawer |") and lines[4].endswith(
        "| 0.75 |"
    )
    assert lines[5].startswith("|  | left |") and lines[5].endswith("| 0.25 |")
    assert lines[6].startswith("| part@(y=+0.10, z=0.80) | drawer |")
    assert lines[7].startswith("|  | absent |") and lines[7].endswith("| 0.25 |")
    series = rows["/belief/part_mass/part1/absent"]
    assert series["Scalars:scalars"][-1] == [0.25]
    assert series["SeriesLines:names"][0] == ["part@(y=+0.10, z=0.80) absent"]
