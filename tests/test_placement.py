"""Where the base stands for a skill (:func:`strug_manip.control.placement.find_placement`):
a reachable skill gets a placement whose joint paths do what the plan says, free of
collisions; an absurd one gets ``SkillStop(ik_infeasible)`` with the reasons counted.

Scene: ``models/cabinets/drawers_11`` (seed 11): the top drawer ``link_1``'s bar handle
at (0.98, 0, 1.06) m, 0.215 m of travel.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from strug_manip.control import OpenDrawer, Place, SkillPlan, handle_grasps
from strug_manip.control.driver import BASE_SPEED
from strug_manip.control.outcome import SkillStop, Status
from strug_manip.control.params import DEFAULT_PARAMS
from strug_manip.control.placement import (
    CANDIDATES,
    HAND_IN_COLLISION,
    LINE_HAND_IN_COLLISION,
    MAX_CANDIDATES,
    Placement,
    find_placement,
)
from strug_manip.control.plan import line_of, straight
from strug_manip.geometry import axis_angle
from strug_manip.objects.hypotheses import BelievedJoint
from strug_manip.robot.fetch import (
    ARM_TORSO_JOINTS,
    BASE_JOINTS,
    GRIPPER_SITE,
    TUCK,
    speed_limits,
)

POS_TOL, ROT_TOL = 0.01, 0.05


def search(ctx, world, plan: SkillPlan, checked: bool = True) -> Placement:
    checker = None
    if checked:
        checker = ctx.checker(world.model).load(world.data)
        checker.attach(None)
        checker.allow()
    speeds = (speed_limits(ctx.ik.model), np.array(BASE_SPEED))
    postures = (np.array(TUCK), np.array(TUCK))
    return find_placement(plan, ctx.ik, ctx.wb_ik, np.zeros(3), postures, speeds, checker)


def gripper_at(ctx, base: np.ndarray, q: np.ndarray) -> np.ndarray:
    return ctx.ik.forward(
        {**dict(zip(BASE_JOINTS, base.tolist(), strict=True)),
         **dict(zip(ARM_TORSO_JOINTS, q.tolist(), strict=True))}
    )  # fmt: skip


def close(T: np.ndarray, goal: np.ndarray) -> bool:
    angle = np.arccos(np.clip((np.trace(T[:3, :3].T @ goal[:3, :3]) - 1) / 2, -1, 1))
    return bool(np.linalg.norm(T[:3, 3] - goal[:3, 3]) < POS_TOL and angle < ROT_TOL)


def drawer_plan(world) -> SkillPlan:
    part = world.scene.cabinet_spec.part("link_1")
    T = world.scene.T_world_cabinet
    skill = OpenDrawer(handle_grasps(part, 0.0, T)[0], BelievedJoint.of_part(part, 0.0, T))
    return skill.plan(world)


def test_a_reachable_skill_gets_a_placement_that_tracks_every_line(world, ctx) -> None:
    world.reset()
    plan = drawer_plan(world)
    p = search(ctx, world, plan)
    assert p.base.shape == (3,) and p.q_pre.shape == (len(ARM_TORSO_JOINTS),)
    assert len(p.lines) == len(p.base_paths) == len(p.plan.lines) == len(plan.lines)
    assert 1 <= p.tried <= 2 * MAX_CANDIDATES and p.seconds > 0
    assert close(gripper_at(ctx, p.base, p.q_pre), p.plan.pre)
    for k, line in enumerate(p.plan.lines):
        qs = p.lines[k]
        bases = p.base_paths[k] if p.base_paths[k] is not None else [p.start_of(k)[0]] * len(qs)
        assert len(qs) == len(line.poses)
        for q, b, T in zip(qs, bases, line.poses, strict=True):
            assert close(gripper_at(ctx, np.asarray(b), q), T), (line.name, k)
    # The robot stands free with its arm tucked there, and is free at the pre-grasp.
    checker = ctx.checker(world.model).load(world.data)
    checker.allow()
    assert checker.free(np.concatenate([p.base, TUCK]))
    assert checker.free(np.concatenate([p.base, p.q_pre]))
    # It stands in front of the cabinet (+x ahead), facing it.
    assert p.base[0] < 0.96 and abs(np.cos(p.base[2])) > 0.9 and np.cos(p.base[2]) > 0
    # The same search again: the same placement (deterministic).
    again = search(ctx, world, plan)
    np.testing.assert_array_equal(again.base, p.base)
    np.testing.assert_array_equal(again.q_pre, p.q_pre)


def absurd(z: float) -> SkillPlan:
    pre = np.eye(4)
    pre[:3, 3] = (0.8, 0.0, z)
    return SkillPlan("Reach", pre, ())


def test_an_unreachable_pre_grasp_is_ik_infeasible(world, ctx) -> None:
    """A pre-grasp 3 m above the floor: every candidate base (fingers either way) fails
    its IK (the twin's kinematic search is the same search without the checker)."""
    world.reset()
    with pytest.raises(SkillStop) as stop:
        search(ctx, world, absurd(3.0))
    assert stop.value.status is Status.IK_INFEASIBLE and stop.value.phase == "plan"
    n = 2 * min(MAX_CANDIDATES, len(CANDIDATES))
    assert f"of {n} reaches" in stop.value.detail
    assert f"pre-grasp unreachable: {n}" in stop.value.detail


def test_a_pre_grasp_with_the_hand_in_the_cabinet_is_tried_from_one_base(world, ctx) -> None:
    """The hand inside the top drawer's front: its pose is the plan's from every base,
    so after the first base (fingers either way) no other is tried."""
    world.reset()
    with pytest.raises(SkillStop) as stop:
        search(ctx, world, SkillPlan("Reach", _at(1.05, 1.06), ()))
    assert stop.value.status is Status.IK_INFEASIBLE
    assert "of 2 reaches" in stop.value.detail, stop.value.detail
    assert f"{HAND_IN_COLLISION}: 2" in stop.value.detail
    # Unchecked (the twin's kinematic search) the same pre-grasp is reachable.
    assert search(ctx, world, SkillPlan("Reach", _at(1.05, 1.06), ()), checked=False).lines == ()


def test_a_line_with_the_hand_deep_in_the_cabinet_is_tried_from_one_base(world, ctx) -> None:
    """A free pre-grasp 0.2 m before the top drawer, its approach line 5 cm into the
    drawer's front: the hand's poses along the line are the plan's from every base, so
    after the first base that tracks it (fingers either way) no other is tried; the
    same line stopped before the front gets a placement."""
    world.reset()
    pre = _at(0.85, 1.06)
    into = line_of("approach", straight(pre, np.array([0.2, 0.0, 0.0]), 0.02), 0.1)
    with pytest.raises(SkillStop) as stop:
        search(ctx, world, SkillPlan("Reach", pre, (into,)))
    assert stop.value.status is Status.IK_INFEASIBLE
    hits = re.search(rf"approach {LINE_HAND_IN_COLLISION}: (\d+)", stop.value.detail)
    assert hits is not None and hits.group(1) == "2", stop.value.detail
    assert f"of {2 * MAX_CANDIDATES} reaches" not in stop.value.detail
    short = line_of("approach", straight(pre, np.array([0.02, 0.0, 0.0]), 0.02), 0.1)
    assert len(search(ctx, world, SkillPlan("Reach", pre, (short,))).lines) == 1


def _at(x: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, 0.0, z)
    return T


def test_an_unreachable_line_is_ik_infeasible(world, ctx) -> None:
    """A reachable pre-grasp whose line goes 1.5 m up."""
    world.reset()
    pre = absurd(1.0).pre
    up = line_of("lift", straight(pre, np.array([0.0, 0.0, 1.5]), 0.02), 0.1)
    with pytest.raises(SkillStop) as stop:
        search(ctx, world, SkillPlan("Reach", pre, (up,)))
    assert stop.value.status is Status.IK_INFEASIBLE
    assert "lift line unreachable" in stop.value.detail
    assert search(ctx, world, SkillPlan("Reach", pre, ())).lines == ()


def test_a_hint_from_a_similar_plan_is_tried_first_and_taken_if_it_works(world, ctx) -> None:
    """The twins' placement hints: a search given the hint of a plan centimetres away
    takes its candidate in one try, tracking every line; the store hands a hint only to
    the same skill from the same base with a work point within HINT_RADIUS."""
    from strug_manip.control.placement import HINT_RADIUS, PlacementHints

    world.reset()
    plan = drawer_plan(world)
    full = search(ctx, world, plan)
    hints = PlacementHints()
    hints.put(plan, np.zeros(3), full)
    shift = np.eye(4)
    shift[1, 3] = 0.02  # the same drawer as another particle has it, 2 cm aside
    near = SkillPlan(plan.skill, shift @ plan.pre, tuple(
        p if not hasattr(p, "poses") else type(p)(**{**p.__dict__, "poses": shift @ p.poses})
        for p in plan.phases))  # fmt: skip
    hint = hints.get(near, np.zeros(3))
    assert hint is not None and hint.candidate == full.candidate
    checker = ctx.checker(world.model).load(world.data)
    checker.attach(None)
    checker.allow()
    speeds = (speed_limits(ctx.ik.model), np.array(BASE_SPEED))
    postures = (np.array(TUCK), np.array(TUCK))
    p = find_placement(near, ctx.ik, ctx.wb_ik, np.zeros(3), postures, speeds, checker, hint)
    assert p.tried == 1 and p.candidate == full.candidate
    for k, line in enumerate(p.plan.lines):
        assert close(gripper_at(ctx, *p.start_of(k + 1)), line.poses[-1])  # where it ends
    far = np.eye(4)
    far[1, 3] = 2 * HINT_RADIUS
    assert hints.get(SkillPlan(plan.skill, far @ plan.pre, ()), np.zeros(3)) is None
    assert hints.get(near, np.array([0.5, 0.0, 0.0])) is None  # another base
    assert hints.get(SkillPlan("Push", near.pre, near.phases), np.zeros(3)) is None


def test_a_skimming_place_starts_exactly_its_lift_over_the_place(world) -> None:
    """A Place from above starts ``place_clearance`` over its place, or ``lift`` if
    higher; a skimming one (a drawer too high up to start higher) exactly ``lift``
    over it, and it retreats as high."""
    world.reset()
    held = np.eye(4)  # the object in the fingers, the gripper's approach down once level
    held[:3, :3] = axis_angle(np.array([0.0, 1.0, 0.0]), -0.5 * np.pi)
    world.set_object_pose(world.site_pose(GRIPPER_SITE) @ held)
    p = np.eye(4)
    p[:3, 3] = (0.9, 0.0, 1.2)
    drop = DEFAULT_PARAMS.place_drop
    cases = [(0.05, False, DEFAULT_PARAMS.place_clearance), (0.2, False, 0.2),
             (0.05, True, 0.05), (0.0, True, DEFAULT_PARAMS.place_clearance)]  # fmt: skip
    for lift, skim, start in cases:
        plan = Place("object", p, lift, skim).plan(world)
        release = plan.lines[0].poses[-1]
        assert release[2, 0] < -0.99  # from above
        assert release[2, 3] == pytest.approx(p[2, 3] + drop, abs=0.02)
        assert plan.pre[2, 3] - release[2, 3] == pytest.approx(start, abs=1e-9)
        assert plan.lines[-1].poses[-1][2, 3] - release[2, 3] == pytest.approx(start, abs=1e-9)
    world.reset()
