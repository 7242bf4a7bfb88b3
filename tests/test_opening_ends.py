"""Issue 37: an opening ends where its part stops (a limit no view shows), in both
bodies, while a part that does not move as believed still stops the run; a pull that
tips the cabinet stops before it falls.

Cabinets: generator seeds 11 (drawers) and 25 (doors) as in ``tests/test_skills.py``,
the opened part's real limit cut to 0.7 of the generator's, the skill planned against
the generator's cabinet (its limit 1/0.7 too far out)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from strug_manip.control import (
    ControlContext,
    OpenDoor,
    OpenDrawer,
    PlanningTwin,
    PullH,
    SkillParams,
    Status,
    handle_grasps,
)
from strug_manip.control.executor import OpeningPath, at_part_end, cabinet_tipped, strained
from strug_manip.geometry import quat_of, z_axes
from strug_manip.objects.hypotheses import BelievedJoint, believed_spec, cell_joints
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

#: The real limit as a share of the believed one.
SHORT = 0.7


@pytest.fixture(scope="module")
def ctx() -> ControlContext:
    return ControlContext()


def short_limit_case(seed: int, kinds: tuple[str, ...], link: str):
    """The believed world (the generator's cabinet), the real world (``link``'s limit
    cut to :data:`SHORT`), the real cabinet's twin, the opening skill and the joint."""
    cfg = SceneConfig(cabinet_seed=seed, cabinet_kinds=kinds)
    believed = ManipulationWorld(cfg)
    spec, T = believed.scene.cabinet_spec, believed.scene.T_world_cabinet
    part = spec.part(link)
    short = dataclasses.replace(part, upper=part.upper * SHORT)
    real_spec = dataclasses.replace(
        spec, parts=tuple(short if p.link == link else p for p in spec.parts)
    )
    real = ManipulationWorld.from_cabinet_spec(real_spec, cfg)
    joint = BelievedJoint.of_part(part, 0.0, T)
    make = OpenDrawer if joint.type == "prismatic" else OpenDoor
    skill = make(handle_grasps(part, 0.0, T)[0], joint)
    return believed, real, real_spec, skill, believed.scene.cabinet_prefix + part.joint, short.upper


@pytest.mark.parametrize(("seed", "kinds", "link"), [(11, ("drawer",), "link_2"),
                                                     (25, ("door",), "link_2")])  # fmt: skip
def test_an_opening_ends_where_its_part_stops_in_both_bodies(ctx, seed, kinds, link) -> None:
    believed, real, real_spec, skill, joint, upper = short_limit_case(seed, kinds, link)
    p = SkillParams()
    out = skill.run(real, ctx=ctx, plan_world=believed)
    where = out.summary()
    assert out.status is Status.OK and "met its end" in out.detail, where
    assert out.phase in ("move", "ease") and not out.holding, where
    assert out.met_end, where
    assert out.part_positions[joint] == pytest.approx(upper, abs=0.02 * max(upper, 1.0)), where
    assert out.cabinet_motion < p.cabinet_motion_limit, where
    # The twin of the real cabinet predicts the same.
    twin = PlanningTwin(real_spec, real.config, ctx)
    twin.reset()
    believed.reset()
    tw = skill.simulate(twin, plan_world=believed)
    assert tw.status is Status.OK and "met its end" in tw.detail, tw.summary()
    assert tw.part_positions[joint] == pytest.approx(upper, abs=0.02 * max(upper, 1.0))
    assert tw.cabinet_motion < p.cabinet_motion_limit, tw.summary()
    # Without the rule (the share is never reached) the same pull drags the cabinet.
    real.reset()
    believed.reset()
    off = skill.run(real, ctx=ctx, params=dataclasses.replace(p, end_share=2.0),
                    plan_world=believed)  # fmt: skip
    assert off.status is Status.CABINET_MOVED, off.summary()
    assert not off.met_end


def test_the_part_end_rule_is_a_strain_along_the_path_after_an_unstrained_first_part() -> None:
    p = SkillParams()
    share = np.array([0.2, 0.4, 0.6, 0.8, 0.9])
    along = np.array([False, False, False, True, True])
    # No strain in the first half: the part's end where it strains along the path.
    early = np.zeros(5, dtype=bool)
    assert at_part_end(share, early, along, p).tolist() == [False, False, False, True, True]
    # A strain already at 0.4 (a wrong joint): never the part's end.
    early = np.array([False, True, True, True, True])
    assert not at_part_end(share, early, along, p).any()
    # Scalars (the full robot) as arrays (the twin).
    assert at_part_end(0.8, False, True, p) and not at_part_end(0.3, False, True, p)
    assert strained(p.end_give + 1e-3, 0.0, p) and strained(0.0, p.end_lag + 1e-3, p)
    assert not strained(p.end_give, p.end_lag, p)


def test_the_cabinets_give_is_where_the_hand_pulls() -> None:
    """A cabinet turned about its base gives at the grasp by the arc there, though its
    base does not slide; the share of an opening is its chord's; the tangent is the
    path's where the command is."""
    path = OpeningPath(np.array([[0.5, 0.0, 1.0], [0.7, 0.0, 1.0], [0.7, 0.2, 1.0]]),
                       np.array([0.5, 0.0, 1.0]))  # fmt: skip
    assert np.allclose(path.give(np.zeros(3), np.array([1.0, 0, 0, 0])), 0.0)
    tilt = 0.02  # [rad] about y, through the base's origin: the grasp 1.12 m away
    R = np.array([[np.cos(tilt), 0, np.sin(tilt)], [0, 1, 0], [-np.sin(tilt), 0, np.cos(tilt)]])
    give = path.give(np.zeros(3), quat_of(R))
    assert np.linalg.norm(give) == pytest.approx(np.linalg.norm(path.anchor) * tilt, rel=0.01)
    # The tilt rule reads the cabinet's up axis from its quaternion.
    ups = z_axes(np.stack([[1.0, 0, 0, 0], quat_of(R)]))
    assert np.allclose(ups, [[0, 0, 1.0], R[:, 2]]) and np.allclose(z_axes(quat_of(R)), R[:, 2])
    p = SkillParams()
    assert cabinet_tipped(np.array([0, 0, 1.0]), ups, dataclasses.replace(
        p, cabinet_tilt_limit=0.01)).tolist() == [False, True]  # fmt: skip
    assert not cabinet_tipped(np.array([0, 0, 1.0]), ups, p).any()
    both = path.give(np.zeros((2, 3)), np.stack([[1.0, 0, 0, 0], quat_of(R)]))
    assert np.allclose(both, [np.zeros(3), give])
    end = np.linalg.norm([0.2, 0.2])
    assert path.share(np.array([[0.6, 0, 1.0], [0.7, 0.2, 1.0]])) == pytest.approx([0.1 / end, 1.0])
    assert np.allclose(path.tangent(np.array([[0.6, 0, 1.0], [0.7, 0.15, 1.0]])),
                       [[1.0, 0, 0], [0, 1.0, 0]])  # fmt: skip


def test_an_opening_plan_has_a_path_and_a_probe_none(ctx) -> None:
    believed, _, _, skill, _, _ = short_limit_case(11, ("drawer",), "link_2")
    plan = skill.plan(believed)
    path = OpeningPath.of(plan, believed.scene.T_world_cabinet)
    assert path is not None
    lines = {ln.name: ln for ln in plan.lines}
    assert np.allclose(path.points[0], lines["approach"].poses[-1][:3, 3])
    assert np.allclose(path.points[-1], lines["ease"].poses[-1][:3, 3])
    assert OpeningPath.of(PullH(skill.g).plan(believed), np.eye(4)) is None


def test_a_pull_that_tips_the_cabinet_stops_before_it_falls(ctx) -> None:
    """A side door swung as a drop-down flap (the tests' ``doors_25``, ``link_2``) tips
    the cabinet about its front edge while its base hardly slides: without the tilt
    rule it falls over; with it the run stops ``cabinet_moved`` at the rule's tilt, on
    the full robot and the twin, and the cabinet stands."""
    world = ManipulationWorld(SceneConfig(cabinet_seed=25, cabinet_kinds=("door",)))
    spec, T = world.scene.cabinet_spec, world.scene.T_world_cabinet
    flap = cell_joints(spec.part("link_2"))["bottom"]
    as_flap = BelievedJoint(flap.type, T[:3, :3] @ flap.axis, (T @ np.r_[flap.origin, 1.0])[:3])
    bspec = believed_spec(spec, "link_2", as_flap, T)
    believed = ManipulationWorld.from_cabinet_spec(bspec, world.config)
    part = bspec.part("link_2")
    skill = OpenDoor(handle_grasps(part, 0.0, T)[0], BelievedJoint.of_part(part, 0.0, T))
    p = SkillParams()

    def tilt_deg(w: ManipulationWorld) -> float:
        return float(np.degrees(np.arccos(np.clip(w.cabinet_pose()[2, 2], -1.0, 1.0))))

    off = skill.run(world, ctx=ctx, params=dataclasses.replace(p, cabinet_tilt_limit=3.0),
                    plan_world=believed)  # fmt: skip
    assert tilt_deg(world) > 30.0, off.summary()  # fallen (or falling) over
    world.reset()
    believed.reset()
    out = skill.run(world, ctx=ctx, plan_world=believed)
    assert out.status is Status.CABINET_MOVED and "tipped" in out.detail, out.summary()
    assert tilt_deg(world) < 1.0 and out.cabinet_motion < p.cabinet_motion_limit, out.summary()
    twin = PlanningTwin(spec, world.config, ctx)
    twin.reset()
    believed.reset()
    tw = skill.simulate(twin, plan_world=believed)
    assert tw.status is Status.CABINET_MOVED and "tipped" in tw.detail, tw.summary()
