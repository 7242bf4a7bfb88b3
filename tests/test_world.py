"""The manipulation world: composes, simulates without warnings, senses geometry right."""

from __future__ import annotations

import numpy as np
import pytest

from planners.errors import PlannersError
from strug_manip.world import ManipulationWorld, SceneConfig, depth_to_points
from strug_manip.world.scene import look_at_xyaxes

import mujoco  # after strug_manip, which selects offscreen rendering  # isort: skip


def _warnings(data: mujoco.MjData) -> dict[int, int]:
    return {
        i: int(data.warning[i].number) for i in range(len(data.warning)) if data.warning[i].number
    }


@pytest.fixture(scope="module")
def world():
    w = ManipulationWorld(SceneConfig(cabinet_seed=3))
    yield w
    w.close()


@pytest.mark.parametrize("kinds", [("drawer",), ("door",), ("drawer", "door", "shelf", "panel")])
def test_scene_simulates_two_seconds_without_warnings(kinds) -> None:
    w = ManipulationWorld(SceneConfig(cabinet_seed=11, cabinet_kinds=kinds))
    start = w.object_pose()
    w.step(2.0)
    assert _warnings(w.data) == {}
    assert np.all(np.isfinite(w.data.qpos))
    assert w.cabinet_displacement() < 0.005  # the cabinet stands still
    assert np.linalg.norm(w.object_pose()[:3, 3] - start[:3, 3]) < 0.005  # the can rests
    assert all(abs(q) < 0.01 for q in w.part_positions().values())  # parts stay shut
    w.close()


def test_reset_sets_part_positions_by_name(world) -> None:
    joint = world.part_joints[0]
    world.reset({joint: 0.05})
    assert world.part_positions()[joint] == pytest.approx(0.05)
    world.reset()
    assert world.part_positions()[joint] == 0.0
    with pytest.raises(PlannersError, match="unknown cabinet joint 'nope'"):
        world.reset({"nope": 0.1})


def test_rgbd_frame_shapes_and_ranges(world) -> None:
    world.reset()
    frame = world.render("head_camera")
    assert frame.rgb.shape == (240, 320, 3) and frame.rgb.dtype == np.uint8
    assert frame.depth.shape == (240, 320)
    assert frame.segmentation.shape == (240, 320)
    cabinet_geoms = {
        g for g in range(world.model.ngeom)
        if world.model.body(world.model.geom_bodyid[g]).name.startswith("cabinet/")
    }  # fmt: skip
    assert np.isin(frame.segmentation, list(cabinet_geoms)).mean() > 0.05  # it sees the cabinet
    pts, geoms = world.point_cloud(frame)
    on_cabinet = pts[np.isin(geoms, list(cabinet_geoms))]
    # Every cabinet point lies in the cabinet's footprint, in front of the robot.
    assert on_cabinet[:, 0].min() > world.config.cabinet_distance - 0.02
    # Without the colour pass: the same depth and segmentation, no colour.
    bare = world.render("head_camera", colour=False)
    assert bare.rgb.shape == (0, 0, 3)
    np.testing.assert_array_equal(bare.depth, frame.depth)
    np.testing.assert_array_equal(bare.segmentation, frame.segmentation)


def test_worlds_rendering_on_one_shared_context_render_what_their_own_would() -> None:
    """Two worlds of different cabinets on one RenderContext, rendered by turns: each
    frame (colour, depth, segmentation) equals its world's render on a context of its
    own, from a framebuffer of the image's size; closing the context frees the
    renderers, and a new render makes a new one."""
    from strug_manip.world.rendering import RenderContext

    shared = RenderContext()
    worlds = [ManipulationWorld(SceneConfig(cabinet_seed=s), render_context=shared)
              for s in (11, 12)]  # fmt: skip
    alone = [ManipulationWorld(SceneConfig(cabinet_seed=s)) for s in (11, 12)]
    try:
        for _ in range(2):
            for w, ref in zip(worlds, alone, strict=True):
                w.reset()
                ref.reset()
                a, b = w.render(), ref.render()
                for x, y in ((a.rgb, b.rgb), (a.depth, b.depth), (a.segmentation, b.segmentation)):
                    np.testing.assert_array_equal(x, y)
        # Its framebuffer is its image, the model's (sized for pictures) left as it was.
        ctx, c = worlds[0]._renderer._mjr_context, worlds[0].config
        assert (ctx.offWidth, ctx.offHeight) == (c.width, c.height)
        assert worlds[0].model.vis.global_.offwidth == max(c.width, 1280)
        shared.close()
        assert worlds[0]._renderer._mjr_context is None  # freed with the context
        worlds[0]._renderer = None
        np.testing.assert_array_equal(worlds[0].render().depth, alone[0].render().depth)
    finally:
        for w in (*worlds, *alone):
            w.close()
        shared.close()


def test_point_cloud_of_a_known_box_matches_its_geometry() -> None:
    eye = (-0.3, 0.4, 0.9)
    axes = " ".join(f"{v:.6f}" for v in look_at_xyaxes(eye, (0.4, -0.2, 0.2)))
    xml = f"""
    <mujoco><compiler angle="radian"/>
      <visual><global offwidth="320" offheight="240"/></visual>
      <worldbody>
        <camera name="cam" pos="-0.3 0.4 0.9" xyaxes="{axes}" fovy="50"/>
        <geom name="box" type="box" size="0.15 0.1 0.2" pos="0.4 -0.2 0.2" euler="0 0 0.5"/>
      </worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    with mujoco.Renderer(model, 240, 320) as r:
        r.update_scene(data, camera="cam")
        r.enable_depth_rendering()
        depth = r.render().copy()
    T = np.eye(4)
    T[:3, :3] = data.cam_xmat[0].reshape(3, 3)
    T[:3, 3] = data.cam_xpos[0]
    pts, _ = depth_to_points(depth, T, np.radians(model.cam_fovy[0]))
    assert len(pts) > 2000
    # Distance of each point to the box surface, in the box frame.
    R = data.geom_xmat[0].reshape(3, 3)
    local = (pts - data.geom_xpos[0]) @ R
    half = model.geom_size[0]
    inside = np.abs(local) - half
    dist = np.where(np.all(inside <= 0, axis=1), -inside.max(axis=1),
                    np.linalg.norm(np.maximum(inside, 0), axis=1))  # fmt: skip
    assert np.percentile(dist, 99) < 0.005, np.percentile(dist, [50, 99, 100])
    assert dist.max() < 0.01


def test_cabinet_stands_on_its_table_front_behind_the_edge(world) -> None:
    from strug_manip.objects.generator import GLIDE_RADIUS
    from strug_manip.world.scene import STAND_HEIGHT, STAND_SETBACK

    world.reset()
    spec = world.scene.cabinet_spec
    T = world.body_pose("cabinet/base")
    assert T[2, 3] == pytest.approx(STAND_HEIGHT + GLIDE_RADIUS)  # on its glides
    front = T[0, 3] - spec.depth / 2  # the cabinet faces -x
    assert front == pytest.approx(world.config.cabinet_distance + STAND_SETBACK)
    table = world.body_pose("cabinet_table")
    assert table[0, 3] > world.config.cabinet_distance  # the table extends behind its edge


def test_snapshot_restore_returns_to_the_same_physics(world) -> None:
    world.reset({world.part_joints[0]: 0.05})
    world.step(0.1)
    state = world.snapshot()
    world.step(0.3)
    after = world.data.qpos.copy()
    world.restore(state)
    assert world.snapshot() == state and hash(world.snapshot()) == hash(state)
    world.step(0.3)
    assert np.array_equal(world.data.qpos, after)  # bit for bit: physics is deterministic
    with pytest.raises(PlannersError, match="state must be a WorldState"):
        world.restore("not a state")  # type: ignore[arg-type]


def test_body_pose_by_name(world) -> None:
    world.reset()
    assert world.body_pose("object")[:3, 3] == pytest.approx(world.object_pose()[:3, 3])
    with pytest.raises(PlannersError, match="unknown body 'nope'"):
        world.body_pose("nope")


def test_a_spec_loads_in_memory_as_its_written_folder_does(tmp_path) -> None:
    from strug_manip.objects import generate_cabinet, load_articulated_object, write_partnet
    from strug_manip.objects.loader import load_cabinet_spec

    spec = generate_cabinet(17)
    mem = load_cabinet_spec(spec)
    disk = load_articulated_object(write_partnet(spec, tmp_path / "c"))
    assert mem.folder is None and mem.urdf_path is None
    assert mem.to_mjcf() == disk.to_mjcf()
    assert np.array_equal(mem.bounds, disk.bounds) and mem.mass == disk.mass
    assert list(mem.pin_model.names) == list(disk.pin_model.names)
