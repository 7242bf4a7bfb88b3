"""Issue 5: the parameterised controllers in the scene, under true and wrong models.

Cabinets (generator seeds, one kind each): seed 3 drawers (top drawer ``link_1``, bar
handle 0.82 m high on the robot's forward line, 0.25 m of travel); seed 3 doors
(``link_1``: a right-hinged door, bar handle 0.82 m high, hinge 0.35 m to its right);
seed 25 doors (``link_2``: a top-hinged flap, bar handle 0.45 m high, 0.10 m below the
hinge and 0.05 m in front of it, upper limit 1.34 rad).
"""

from __future__ import annotations

import numpy as np
import pytest

from planners.errors import ConfigError, StrugError, UnknownNameError
from strug_manip.control.controllers import (
    REASONS,
    BelievedJoint,
    Controller,
    OpenDoor,
    OpenDrawer,
    Outcome,
    Pick,
    Place,
    PullH,
    PullV,
    Push,
    handle_grasp,
    true_joint,
)
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

DRAWER_JOINT = "cabinet/joint_1"
DOOR_JOINT = "cabinet/joint_1"


@pytest.fixture(scope="module")
def drawers() -> ManipulationWorld:
    world = ManipulationWorld(SceneConfig(cabinet_seed=3, cabinet_kinds=("drawer",)))
    yield world
    world.close()


@pytest.fixture(scope="module")
def doors() -> ManipulationWorld:
    world = ManipulationWorld(SceneConfig(cabinet_seed=3, cabinet_kinds=("door",)))
    yield world
    world.close()


@pytest.fixture(scope="module")
def flaps() -> ManipulationWorld:
    world = ManipulationWorld(SceneConfig(cabinet_seed=25, cabinet_kinds=("door",)))
    yield world
    world.close()


def _warnings(world: ManipulationWorld) -> int:
    return sum(int(world.data.warning[i].number) for i in range(len(world.data.warning)))


def _check(out: Outcome) -> None:
    assert out.reason in REASONS
    assert out.success == (out.reason == "ok")
    assert out.trajectory.ndim == 2 and out.trajectory.shape[1] == 8
    assert out.trajectory.shape[0] == out.times.shape[0]
    assert np.all(np.isfinite(out.trajectory))
    assert out.sim_time >= 0 and out.wall_seconds > 0
    parts = out.ik_seconds + out.planning_seconds + out.physics_seconds
    assert parts <= out.wall_seconds + 1e-6


def test_open_drawer_true_model_opens_it(drawers: ManipulationWorld) -> None:
    drawers.reset()
    g = handle_grasp(drawers, "link_1")
    out = OpenDrawer(g, true_joint(drawers, "link_1"), travel=0.15).run(drawers)
    _check(out)
    assert out.success, out.detail
    assert out.part_motion[DRAWER_JOINT] > 0.12
    assert out.cabinet_displacement < 0.03
    assert 0 < out.sim_time < 30
    assert isinstance(OpenDrawer(g, true_joint(drawers, "link_1")), Controller)


def test_open_drawer_under_a_door_model_fails_or_drags(drawers: ManipulationWorld) -> None:
    drawers.reset()
    g = handle_grasp(drawers, "link_1")
    # Believed: a door hinged 0.35 m to the handle's right (the gripper swings an arc).
    door = BelievedJoint("revolute", np.array([0.0, 0.0, 1.0]), g[:3, 3] + [0.03, -0.35, 0], 1.5)
    out = OpenDrawer(g, door, travel=0.8).run(drawers)
    _check(out)
    assert not out.success
    assert out.reason in ("grasp_lost", "collision") or out.cabinet_displacement > 0.1


def test_open_door_true_model_opens_it(doors: ManipulationWorld) -> None:
    doors.reset()
    g = handle_grasp(doors, "link_1")
    joint = true_joint(doors, "link_1")
    assert joint.type == "revolute"
    out = OpenDoor(g, joint, angle=0.8).run(doors)
    _check(out)
    assert out.success, out.detail
    assert out.part_motion[DOOR_JOINT] > 0.6
    assert out.cabinet_displacement < 0.03


def test_open_door_under_a_drawer_model_fails_or_drags(doors: ManipulationWorld) -> None:
    doors.reset()
    g = handle_grasp(doors, "link_1")
    drawer = BelievedJoint("prismatic", -g[:3, 0], limit=0.3)  # straight out of the front
    out = OpenDoor(g, drawer, angle=0.25).run(doors)
    _check(out)
    assert not out.success
    assert out.reason in ("grasp_lost", "collision") or out.cabinet_displacement > 0.1


def test_pick_then_place_into_an_open_drawer(drawers: ManipulationWorld) -> None:
    q_open = 0.2
    drawers.reset({"joint_1": q_open})
    z0 = drawers.object_pose()[2, 3]
    picked = Pick("object").run(drawers)
    _check(picked)
    assert picked.success, picked.detail
    assert drawers.object_pose()[2, 3] > z0 + 0.1

    part = drawers.scene.cabinet_spec.part("link_1")
    T = drawers.scene.T_world_cabinet
    centre = (T @ np.r_[part.point_at(part.interior_center, q_open), 1.0])[:3]
    size = part.interior_size
    p = np.eye(4)  # in the exposed part of the drawer, on its bottom
    p[:3, 3] = [
        min(centre[0] + size[0] / 2, 0.98) - 0.07,
        centre[1],
        centre[2] - size[2] / 2 + 0.045,
    ]
    placed = Place("object", p).run(drawers)
    _check(placed)
    assert placed.success, placed.detail
    # The object's centre is inside the drawer's interior box (cabinet frame = world
    # rotated by pi about z: the box is axis-aligned in the world too).
    T_now = drawers.scene.T_world_cabinet
    q_now = drawers.part_positions()[DRAWER_JOINT]
    c_now = (T_now @ np.r_[part.point_at(part.interior_center, q_now), 1.0])[:3]
    obj = drawers.object_pose()[:3, 3]
    assert np.all(np.abs(obj - c_now) < size / 2), (obj, c_now, size)
    assert drawers.cabinet_displacement() < 0.03


def test_probes_move_a_part_a_little(drawers: ManipulationWorld, doors: ManipulationWorld) -> None:
    drawers.reset()
    out = PullH(handle_grasp(drawers, "link_1")).run(drawers)
    _check(out)
    assert out.success, out.detail
    assert 0.02 < out.part_motion[DRAWER_JOINT] < 0.06

    drawers.reset({"joint_1": 0.1})
    out = Push(handle_grasp(drawers, "link_1")).run(drawers)
    _check(out)
    assert out.success, out.detail
    assert -0.06 < out.part_motion[DRAWER_JOINT] < -0.02

    drawers.reset()  # a drawer does not move up: the gripper is held back
    out = PullV(handle_grasp(drawers, "link_1")).run(drawers)
    _check(out)
    assert not out.success and out.reason == "collision"
    assert abs(out.part_motion[DRAWER_JOINT]) < 0.01

    doors.reset()  # pulling a door's handle out swings it a little
    out = PullH(handle_grasp(doors, "link_1")).run(doors)
    _check(out)
    assert out.success, out.detail
    assert 0.05 < out.part_motion[DOOR_JOINT] < 0.3


def test_pull_v_true_model_lifts_a_top_hinged_flap(flaps: ManipulationWorld) -> None:
    part = flaps.scene.cabinet_spec.part("link_2")
    assert part.hinge == "top" and part.handle == "bar"
    joint = "cabinet/" + part.joint
    flaps.reset()
    g = handle_grasp(flaps, "link_2")
    assert 0.45 <= g[2, 3] <= 1.15  # a handle height the Fetch reaches
    # Pulling the handle up swings the flap open about its top hinge (the handle stands
    # off the panel, in front of the hinge line, so the vertical pull has a component
    # along its arc); the grasp stays within HELD_TOLERANCE of the straight pull.
    out = PullV(g).run(flaps)
    _check(out)
    assert out.success, out.detail
    assert out.part_motion[joint] > 0.05  # positive: opening outward (~0.13 rad)
    assert out.cabinet_displacement < 0.03
    assert _warnings(flaps) == 0


def test_same_state_and_parameters_give_the_same_outcome(drawers: ManipulationWorld) -> None:
    outs, qpos = [], []
    for _ in range(2):
        drawers.reset()
        g = handle_grasp(drawers, "link_1")
        outs.append(OpenDrawer(g, true_joint(drawers, "link_1")).run(drawers, seed=7))
        qpos.append(drawers.data.qpos.copy())
    assert outs[0].same_as(outs[1])
    np.testing.assert_array_equal(qpos[0], qpos[1])


def test_unreachable_grasp_is_ik_infeasible(drawers: ManipulationWorld) -> None:
    drawers.reset()
    g = handle_grasp(drawers, "link_1")
    g[2, 3] += 1.5  # 2.3 m above the floor
    out = OpenDrawer(g, BelievedJoint("prismatic", -g[:3, 0], limit=0.2)).run(drawers)
    assert not out.success and out.reason == "ik_infeasible"
    assert out.sim_time == 0.0


def test_bad_parameters_raise_strug_errors(drawers: ManipulationWorld) -> None:
    with pytest.raises(ConfigError, match="prismatic"):
        BelievedJoint("spherical", np.array([1.0, 0, 0]))
    with pytest.raises(ConfigError, match="axis"):
        BelievedJoint("prismatic", np.zeros(3))
    with pytest.raises(ConfigError):
        BelievedJoint("prismatic", np.array([1.0, 0, 0]), limit=-1.0)
    j = BelievedJoint("prismatic", np.array([-1.0, 0, 0]))
    with pytest.raises(StrugError):
        OpenDrawer(np.eye(3), j).run(drawers)
    with pytest.raises(ConfigError, match="travel"):
        OpenDrawer(np.eye(4), j, travel=-0.1).run(drawers)
    with pytest.raises(UnknownNameError):
        Pick("mug").run(drawers)
    with pytest.raises(ConfigError, match="seed"):
        Push(np.eye(4)).run(drawers, seed=-1)
    with pytest.raises(UnknownNameError):
        handle_grasp(drawers, "link_9")
