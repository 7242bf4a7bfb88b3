"""Issue 4: a scripted gripper opens a drawer in the scene.

The Fetch drives up to a generated cabinet, grasps a drawer handle and pulls it open
(:func:`strug_manip.world.scripted.open_drawer_scripted`, ground-truth kinematics, no
planner). Seeds, with ``cabinet_kinds=("drawer",)``:

- 3 (the scene's default seed): a 1.04 m tall single-column cabinet, bar handles; the
  top drawer's handle is 0.82 m high on the robot's forward line.
- 13: a 1.05 m tall three-column cabinet (40 kg) with knob handles (a pinch grasp that
  only friction holds, the harder case); the chosen handle is 0.85 m high.
- 9, ``link_3``: bar handle 0.79 m high, 0.25 m to the robot's right (the arm reaches
  sideways: the base only drives along the opening direction).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.errors import ConfigError, StrugError, UnknownNameError
from strug_manip.world.scene import SceneConfig
from strug_manip.world.scripted import ScriptedResult, open_drawer_scripted
from strug_manip.world.sim import ManipulationWorld

MIN_OPENING = 0.08  # [m]
MAX_CABINET_SHIFT = 0.03  # [m]


def _world(seed: int, kinds: tuple[str, ...] = ("drawer",)) -> ManipulationWorld:
    return ManipulationWorld(SceneConfig(cabinet_seed=seed, cabinet_kinds=kinds))


def _warnings(world: ManipulationWorld) -> dict[int, int]:
    d = world.data
    return {i: int(d.warning[i].number) for i in range(len(d.warning)) if d.warning[i].number}


@pytest.mark.parametrize(
    ("seed", "link", "expected_link"),
    [(3, None, "link_1"), (13, None, "link_2"), (9, "link_3", "link_3")],
)
def test_scripted_gripper_opens_a_drawer(seed: int, link: str | None, expected_link: str) -> None:
    world = _world(seed)
    try:
        res = open_drawer_scripted(world, link, pull=0.15)
        assert isinstance(res, ScriptedResult)
        assert res.part_link == expected_link
        assert res.joint == f"cabinet/joint_{expected_link.removeprefix('link_')}"
        assert res.opening > MIN_OPENING, res
        assert res.q_after == pytest.approx(world.part_positions()[res.joint])
        assert res.cabinet_displacement < MAX_CABINET_SHIFT, res
        assert res.grasp_held, res
        assert 0 < res.sim_time < 40.0
        assert _warnings(world) == {}
        assert np.all(np.isfinite(world.data.qpos))
    finally:
        world.close()


def test_scripted_opening_is_deterministic() -> None:
    results = []
    for _ in range(2):
        world = _world(3)
        results.append((open_drawer_scripted(world), world.data.qpos.copy()))
        world.close()
    (a, qa), (b, qb) = results
    assert a == b
    np.testing.assert_array_equal(qa, qb)


def test_pull_is_capped_before_the_joint_limit() -> None:
    world = _world(3)
    try:
        res = open_drawer_scripted(world, "link_1", pull=0.9)
        upper = world.scene.cabinet_spec.part("link_1").upper
        assert MIN_OPENING < res.opening < upper
        assert res.cabinet_displacement < MAX_CABINET_SHIFT
    finally:
        world.close()


def test_errors_name_the_problem() -> None:
    doors = _world(3, kinds=("door",))
    try:
        with pytest.raises(ConfigError, match="no drawer"):
            open_drawer_scripted(doors)
        with pytest.raises(ConfigError, match="is a door"):
            open_drawer_scripted(doors, "link_1")
    finally:
        doors.close()
    world = _world(3)
    try:
        with pytest.raises(UnknownNameError, match="link_9"):
            open_drawer_scripted(world, "link_9")
        for bad in (-0.1, 0.0, math.nan, True, "0.1"):
            with pytest.raises(ConfigError, match="pull"):
                open_drawer_scripted(world, "link_1", pull=bad)  # type: ignore[arg-type]
        with pytest.raises(StrugError, match="link_3"):  # the bottom drawer, 0.18 m high
            open_drawer_scripted(world, "link_3")
    finally:
        world.close()
    no_handles = _world(0)  # seed 0's drawers have no handles
    try:
        with pytest.raises(ConfigError, match="no handle"):
            open_drawer_scripted(no_handles)
    finally:
        no_handles.close()
