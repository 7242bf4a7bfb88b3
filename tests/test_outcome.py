"""What a skill reports (:mod:`strug_manip.control.outcome`): statuses, per-joint facts,
comparisons that ignore the wall clock."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from strug_manip.control import STATUSES, Outcome, Status
from strug_manip.control.outcome import SkillStop


def outcome(**kw) -> Outcome:
    base = dict(
        skill="OpenDrawer",
        status=Status.OK,
        detail="",
        phase="",
        part_motion={"cabinet/joint_1": 0.2, "cabinet/joint_2": -0.3},
        part_units={"cabinet/joint_1": "m", "cabinet/joint_2": "rad"},
        part_positions={"cabinet/joint_1": 0.2, "cabinet/joint_2": 0.0},
        cabinet_displacement=0.012,
        cabinet_motion=0.01,
        object_pose=np.eye(4),
        holding=False,
        times=np.arange(3) * 0.02,
        qpos=np.zeros((3, 5)),
        sim_time=0.06,
        wall_seconds=0.5,
    )
    base.update(kw)
    return Outcome(**base)


def test_statuses_are_an_enum_in_the_documented_order() -> None:
    assert STATUSES == (
        "ok", "ik_infeasible", "no_motion_plan", "grasp_lost", "collision", "timeout",
        "cabinet_moved",
    )  # fmt: skip
    assert Status("grasp_lost") is Status.GRASP_LOST and Status.OK == "ok"
    with pytest.raises(ValueError):
        Status("success")
    stop = SkillStop(Status.COLLISION, "held back", "move")
    assert (stop.status, str(stop), stop.phase) == (Status.COLLISION, "held back", "move")


def test_facts_by_joint_in_their_units() -> None:
    o = outcome()
    assert o.ok and not outcome(status=Status.TIMEOUT).ok
    assert o.motion_of("cabinet/joint_2") == o.motion_of("joint_2") == -0.3
    with pytest.raises(KeyError, match=r"joint_9.*cabinet/joint_1"):
        o.motion_of("joint_9")
    s = outcome(status=Status.COLLISION, detail="held back 0.1 m").summary()
    assert s == "OpenDrawer: collision (held back 0.1 m); cabinet/joint_2 moved -0.300 rad; " + (
        "cabinet 0.012 m"
    )


def test_same_as_ignores_only_the_wall_clock() -> None:
    o = outcome()
    assert o.same_as(outcome(wall_seconds=3.0, ik_seconds=1.0, physics_seconds=1.0))
    qpos = np.zeros((3, 5))
    qpos[1, 2] = 1e-12
    for change in (
        dict(status=Status.COLLISION),
        dict(detail="x"),
        dict(phase="move"),
        dict(part_motion={"cabinet/joint_1": 0.2, "cabinet/joint_2": -0.31}),
        dict(cabinet_displacement=0.013),
        dict(object_pose=np.diag([1.0, 1.0, 1.0, 1.0]) + 1e-12),
        dict(holding=True),
        dict(qpos=qpos),
        dict(sim_time=0.08),
        dict(skill="Push"),
    ):
        assert not o.same_as(outcome(**change)), change
    with pytest.raises(dataclasses.FrozenInstanceError):
        o.status = Status.TIMEOUT  # type: ignore[misc]


def test_a_run_reports_the_cabinet_once_it_is_at_rest(world) -> None:
    """:func:`~strug_manip.control.executor.settle`: a cabinet still rocking (tipped
    toward the robot and let go) is stepped until it is at rest, up to
    ``settle_limit``; a cabinet at rest is not stepped at all."""
    from strug_manip.control.executor import at_rest, cabinet_dofs, settle
    from strug_manip.control.params import DEFAULT_PARAMS
    from strug_manip.geometry import axis_angle

    world.reset()
    dofs = cabinet_dofs(world)
    assert len(dofs) == 6 + len(world.part_joints)
    t0 = world.data.time
    settle(world, world.step, 0.01, DEFAULT_PARAMS)
    assert world.data.time == t0  # at rest: not stepped
    T = world.cabinet_pose()
    tipped = T.copy()
    tipped[:3, :3] = axis_angle(np.array([0.0, 1.0, 0.0]), -0.05) @ T[:3, :3]
    tipped[2, 3] += 0.01
    world.set_cabinet_pose(tipped)
    world.step(0.01)
    assert not at_rest(world.data.qvel[dofs])  # it falls back
    settle(world, world.step, 0.01, DEFAULT_PARAMS)
    assert at_rest(world.data.qvel[dofs])
    assert world.data.time - t0 < DEFAULT_PARAMS.settle_limit + 0.05
    world.reset()
