"""Issue 9: the skills on known cabinets under true and wrong models, hard stops, both
chains, the planning twin's agreement with the full robot, determinism, bad parameters.

Cabinets (generator seeds below 1000: none of the evaluation ranges 1000-1029,
2000-2029, 3000-3099):

- ``drawers_11``: ``models/cabinets/drawers_11`` (seed 11, drawers only): three drawers
  ``link_1..3``, bar handles 1.06, 0.87 and 0.63 m high;
- ``mixed_17``: ``models/cabinets/mixed_17`` (seed 17, every kind): left-hinged doors
  ``link_3`` and ``link_5``, drawers ``link_4`` and ``link_7``, the top-hinged flap
  ``link_9``, bar handles;
- ``doors_25``: seed 25, doors only: the right-hinged ``link_1`` and the left-hinged
  ``link_2``, bar handles.

The worlds are generated from the seeds instead of loaded from the folders: a loaded
folder carries no :class:`~strug_manip.objects.generator.CabinetSpec` (the ground truth
the skills find handles by), and ``tests/test_cabinets.py`` checks that the folders are
exactly these generator outputs. ``models/cabinets/doors_7`` is not used: none of its
doors has a handle.

**The twin agreement sample** was fixed before it was run against the twin: every
handled part of the three cabinets, opened under its true model and under the two
likeliest confusions of its kinematics (:data:`CONFUSIONS`, those of
``tools/eval_skills.py``), plus one probe (``PullH`` out of the front) under the true
model: 40 (cabinet, model, skill) triples. The slow test repeats it on the unseen
generator seeds :data:`SLOW_SEEDS`.
"""

from __future__ import annotations

import dataclasses
import gc
import itertools
import math
from dataclasses import dataclass

import mujoco
import numpy as np
import pytest
from mujoco import rollout

from planners.errors import ConfigError, PlannersError, UnknownNameError
from strug_manip.control import (
    STATUSES,
    ControlContext,
    OpenDoor,
    OpenDrawer,
    Outcome,
    Pick,
    Place,
    PlanningTwin,
    PullH,
    PullV,
    Push,
    SkillParams,
    Status,
    handle_grasps,
    place_target,
    run_batch,
)
from strug_manip.control import twin_body as twin_body_mod
from strug_manip.control import twin_rollout as twin_mod
from strug_manip.control.base_servo import BaseServo
from strug_manip.control.executor import TUCKED_TOLERANCE
from strug_manip.control.outcome import SkillStop
from strug_manip.control.params import DEFAULT_PARAMS
from strug_manip.control.placement import WHOLE_BODY_LINES
from strug_manip.domains.manipulation.rules import dragged, inside, open_enough
from strug_manip.objects.hypotheses import BelievedJoint, believed_spec, cell_joints, model_of
from strug_manip.robot.fetch import (
    ARM_JOINTS,
    ARM_TORSO_JOINTS,
    BASE_JOINTS,
    CARRY,
    FINGERS_EMPTY,
    GRIPPER_SITE,
    GRIPPER_SQUEEZE,
    TUCK,
)
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

CABINETS: dict[str, SceneConfig] = {
    "drawers_11": SceneConfig(cabinet_seed=11, cabinet_kinds=("drawer",)),
    "mixed_17": SceneConfig(cabinet_seed=17),
    "doors_25": SceneConfig(cabinet_seed=25, cabinet_kinds=("door",)),
}
#: The two likeliest confusions of each kinematic model (as ``tools/eval_skills.py``).
CONFUSIONS: dict[str, tuple[str, str]] = {
    "drawer": ("left", "right"),
    "left": ("drawer", "right"),
    "right": ("drawer", "left"),
    "top": ("drawer", "bottom"),
    "bottom": ("drawer", "top"),
}
#: Twin agreement: part motion within these [m], [rad]; the issue's target fraction.
AGREE_M, AGREE_RAD, AGREE_FRACTION = 0.01, 0.05, 0.95
#: What the twin reaches today on the fixed sample (issue 9 asks AGREE_FRACTION; the gap
#: is the twin's hand against the arm's compliance under wrong-model pulls: README):
#: a regression floor below the measured agreement.
AGREE_FLOOR = 0.65
#: Generator seeds of the slow agreement sample (drawers-only and doors-only scenes).
SLOW_SEEDS = (500, 501, 502)
#: A part may sit this far past its closed stop (MuJoCo's soft limit under load) [m or rad].
STOP_TOLERANCE = 0.005
#: Base speeds above these count as driving [m/s], [rad/s] (a third of the drive speeds
#: 0.3 m/s and 0.9 rad/s; the arm's reaction jiggles the held base by less).
DRIVE_SPEED, DRIVE_YAW_RATE = 0.1, 0.3
#: A carried object may shift this much in the gripper [m], [rad].
CARRY_SHIFT_M, CARRY_SHIFT_RAD = 0.015, 0.05


@pytest.fixture(scope="module")
def worlds():
    ws = {name: ManipulationWorld(cfg) for name, cfg in CABINETS.items()}
    yield ws
    for w in ws.values():
        w.close()


@pytest.fixture(scope="module")
def twins(worlds, ctx) -> dict[str, PlanningTwin]:
    return {n: PlanningTwin(w.scene.cabinet_spec, w.config, ctx) for n, w in worlds.items()}


# --- helpers ----------------------------------------------------------------------------


def joint_name(world: ManipulationWorld, link: str) -> str:
    return world.scene.cabinet_prefix + world.scene.cabinet_spec.part(link).joint


def cabinet_pose(world: ManipulationWorld) -> np.ndarray:
    return world.body_pose(world.scene.cabinet_prefix + world.scene.cabinet.root)


def world_joint(world: ManipulationWorld, link: str, model: str) -> BelievedJoint:
    """Model ``model`` of part ``link``'s cell, world frame, the part closed."""
    T = world.scene.T_world_cabinet
    j = cell_joints(world.scene.cabinet_spec.part(link))[model]
    return BelievedJoint(j.type, T[:3, :3] @ j.axis, (T @ np.r_[j.origin, 1.0])[:3])


def opening(joint: BelievedJoint, g: np.ndarray):
    """The opening skill a belief calls for (a drawer belief: OpenDrawer)."""
    return OpenDrawer(g, joint) if joint.type == "prismatic" else OpenDoor(g, joint)


@dataclass
class Run:
    """One full-robot run from the world's reset and what the world said afterwards."""

    cabinet: str
    link: str
    joint: str  # the part's joint in the world
    model: str  # the part's true kinematic model
    belief: str  # the model the skill was planned with ("" for a probe)
    skill: object
    out: Outcome
    before: dict[str, float]  # part positions at the start
    after: dict[str, float]  # part positions read from the world at the end
    displacement: float  # world.cabinet_displacement() at the end
    cabinet_frame: np.ndarray  # the cabinet frame at the end, (4, 4)
    object_pose: np.ndarray
    units: dict[str, str]
    holding: bool  # the fingers squeeze something at the end (the world's reading)
    twin: Outcome | None = None


def run_full(world, ctx, link, make, plan_world=None, belief_part=None) -> tuple[object, Outcome]:
    """``make(g)`` for the handle grasps of the (believed) part in turn, each from a
    reset, until one is not ``ik_infeasible`` (as ``tools/eval_skills.py`` does)."""
    part = belief_part or world.scene.cabinet_spec.part(link)
    skill = out = None
    for g in handle_grasps(part, 0.0, world.scene.T_world_cabinet):
        world.reset()
        if plan_world is not None:
            plan_world.reset()
        skill = make(g)
        out = skill.run(world, ctx=ctx, plan_world=plan_world)
        if out.status is not Status.IK_INFEASIBLE:
            break
    return skill, out


def record(world, cabinet, link, model, belief, skill, out) -> Run:
    return Run(
        cabinet, link, joint_name(world, link), model, belief, skill, out,
        before={j: 0.0 for j in world.part_joints},  # every run starts from reset
        after=world.part_positions(),
        displacement=world.cabinet_displacement(),
        cabinet_frame=cabinet_pose(world),
        object_pose=world.object_pose(),
        units=world.part_units(),
        holding=fingers_hold(world),
    )  # fmt: skip


def fingers_hold(world: ManipulationWorld) -> bool:
    """The finger servo squeezes and the fingers stand apart (on something)."""
    m, d = world.model, world.data
    squeezing = d.ctrl[world.ctrl_index("gripper")] == GRIPPER_SQUEEZE
    return bool(squeezing and d.ten_length[m.tendon("gripper").id] > FINGERS_EMPTY)


def sample_runs(worlds, twins, ctx) -> list[Run]:
    """The agreement sample (module docstring): full robot, then twin, per triple."""
    runs = []
    for name, world in worlds.items():
        spec = world.scene.cabinet_spec
        T = world.scene.T_world_cabinet
        for part in spec.movable_parts:
            if part.handle == "none":
                continue
            model = model_of(part)
            true = BelievedJoint.of_part(part, 0.0, T)
            skill, out = run_full(world, ctx, part.link, lambda g, j=true: opening(j, g))
            runs.append(record(world, name, part.link, model, model, skill, out))
            for belief in CONFUSIONS[model]:
                bspec = believed_spec(spec, part.link, world_joint(world, part.link, belief), T)
                pw = ManipulationWorld.from_cabinet_spec(bspec, world.config)
                joint = BelievedJoint.of_part(bspec.part(part.link), 0.0, T)
                skill, out = run_full(
                    world, ctx, part.link, lambda g, j=joint: opening(j, g), pw,
                    bspec.part(part.link),
                )  # fmt: skip
                runs.append(record(world, name, part.link, model, belief, skill, out))
                # The twin simulates the same plan: made against the believed world.
                twins[name].reset()
                pw.reset()
                runs[-1].twin = skill.simulate(twins[name], plan_world=pw)
                pw.close()
            skill, out = run_full(world, ctx, part.link, PullH)
            runs.append(record(world, name, part.link, model, "", skill, out))
    for r in runs:
        if r.twin is None:
            twin = twins[r.cabinet]
            twin.reset()
            r.twin = r.skill.simulate(twin)
    return runs


@pytest.fixture(scope="module")
def sample(worlds, twins, ctx) -> list[Run]:
    return sample_runs(worlds, twins, ctx)


def check_facts(r: Run) -> None:
    """The outcome's facts are the world's, each in its unit."""
    out = r.out
    assert isinstance(out.status, Status) and out.status.value in STATUSES
    assert out.ok == (out.status is Status.OK)
    assert set(out.part_motion) == set(r.after) == set(out.part_units)
    assert out.part_units == r.units
    for j, q in r.after.items():
        assert out.part_motion[j] == pytest.approx(q - r.before[j], abs=1e-12), j
        assert out.part_positions[j] == q
    assert out.part_units[r.joint] == ("m" if r.model == "drawer" else "rad")
    assert out.motion_of(r.joint) == out.part_motion[r.joint]
    assert out.cabinet_displacement == pytest.approx(r.displacement, abs=1e-12)
    assert out.cabinet_motion == pytest.approx(r.displacement, abs=1e-9)  # from a reset
    np.testing.assert_array_equal(out.object_pose, r.object_pose)
    assert out.holding == r.holding
    if out.ok:  # an opening or a probe ends released
        assert not out.holding
    assert out.times.ndim == 1 and out.qpos.ndim == 2 and len(out.qpos) == len(out.times)
    assert np.all(np.isfinite(out.qpos))
    if len(out.times):
        assert np.all(np.diff(out.times) > 0) and out.times[-1] <= out.sim_time + 1e-9
    else:
        assert out.status is Status.IK_INFEASIBLE and out.sim_time == 0.0
    assert out.wall_seconds > 0
    assert out.ik_seconds + out.planning_seconds + out.physics_seconds <= out.wall_seconds


def commanded(skill) -> float:
    """How far an opening skill meant to move its part [m or rad]."""
    p = SkillParams()
    margin = p.limit_margin_m if skill.joint.type == "prismatic" else p.limit_margin_rad
    return min(skill.default_amount(p), skill.joint.limit - margin)


# --- 1. each skill on known cabinets, true and wrong models -----------------------------


def test_true_model_openings_open_every_handled_part(sample, worlds) -> None:
    runs = [r for r in sample if r.belief == r.model]
    assert {r.model for r in runs} == {"drawer", "left", "right", "top"}
    for r in runs:
        check_facts(r)
        world = worlds[r.cabinet]
        spec = world.scene.cabinet_spec
        where = f"{r.cabinet} {r.link} ({r.model}): {r.out.summary()}"
        assert r.out.ok, where
        assert isinstance(r.skill, OpenDrawer if r.model == "drawer" else OpenDoor)
        assert not dragged(r.displacement), where
        assert not r.out.holding, where
        # It followed its command: the part moved most of the way (a drawer slides a
        # little behind the gripper, a door lags on its hinge).
        assert r.out.motion_of(r.joint) >= 0.8 * commanded(r.skill), where
        # Drawers and side doors open far enough for the object; a flap is only
        # checked to have swung (mixed_17's flap cell is too low for the object at any
        # angle: 0.10 m of free height at its limit, the object carried in needs 0.102).
        if r.model in ("drawer", "left", "right"):
            assert open_enough(spec, r.link, r.after[r.joint], r.cabinet_frame), where


def test_wrong_model_outcomes_are_the_facts_of_physics(sample) -> None:
    runs = [r for r in sample if r.belief not in ("", r.model)]
    kinds = {
        ("drawer", "door"): [r for r in runs if r.model == "drawer"],
        ("door", "drawer"): [r for r in runs if r.model != "drawer" and r.belief == "drawer"],
        ("mirrored", ""): [
            r for r in runs if {r.model, r.belief} in ({"left", "right"}, {"top", "bottom"})
        ],
    }
    for what, rs in kinds.items():
        assert rs, f"the sample has no {what} confusion"
    for r in runs:
        check_facts(r)
    # A drawer believed to be a door is swung by OpenDoor and reports metres; a door
    # believed to be a drawer is pulled by OpenDrawer and reports radians.
    for r in kinds[("drawer", "door")]:
        assert isinstance(r.skill, OpenDoor) and r.out.part_units[r.joint] == "m"
    for r in kinds[("door", "drawer")]:
        assert isinstance(r.skill, OpenDrawer) and r.out.part_units[r.joint] == "rad"


def test_opening_skills_follow_the_joint_they_are_given(worlds, ctx) -> None:
    """OpenDrawer with a door belief on a drawer swings (``drawer_travel`` radians),
    OpenDoor with a drawer belief on a door pulls straight (``drawer_travel`` metres):
    the facts are in the part's own unit whatever the skill."""
    cases = (
        ("drawers_11", "link_1", "left", OpenDrawer),
        ("doors_25", "link_1", "drawer", OpenDoor),
    )
    for cabinet, link, belief, cls in cases:
        world = worlds[cabinet]
        spec, T = world.scene.cabinet_spec, world.scene.T_world_cabinet
        bspec = believed_spec(spec, link, world_joint(world, link, belief), T)
        pw = ManipulationWorld.from_cabinet_spec(bspec, world.config)
        joint = BelievedJoint.of_part(bspec.part(link), 0.0, T)
        skill, out = run_full(
            world, ctx, link, lambda g, j=joint, c=cls: c(g, j), pw, bspec.part(link)
        )
        r = record(world, cabinet, link, model_of(spec.part(link)), belief, skill, out)
        check_facts(r)
        assert out.status is not Status.IK_INFEASIBLE, out.summary()
        assert pw.data.time == 0.0 and pw.cabinet_displacement() == 0.0  # no physics there
        pw.close()


def test_pull_out_probes_move_parts_a_little(sample) -> None:
    p = SkillParams()
    for r in (r for r in sample if r.belief == ""):
        check_facts(r)
        where = f"{r.cabinet} {r.link} ({r.model}): {r.out.summary()}"
        assert isinstance(r.skill, PullH), where
        m = r.out.motion_of(r.joint)
        # A part that follows the pull lets it run to its end; one that moves on an arc
        # away from the straight pull (a flap) may hold the hand back: then the probe
        # says so (``collision``) and the part has still moved.
        assert r.out.ok or (r.model in ("top", "bottom") and r.out.status == "collision"), where
        if r.model == "drawer":  # the drawer follows the probe
            assert 0.5 * p.probe_distance < m < 1.5 * p.probe_distance, where
        else:  # a door swings open a little, a flap lifts
            assert 0.02 < m < 0.6, where


# --- 2. hard stops ----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("cabinet", "link", "q0"),
    [
        ("drawers_11", "link_1", 0.0),  # a closed drawer
        ("drawers_11", "link_1", 0.02),  # pushed 4 cm from 2 cm out
        ("doors_25", "link_1", 0.1),  # a side door pushed ~0.13 rad from 0.1 rad
        ("mixed_17", "link_9", 0.1),  # a top flap
    ],
)
def test_push_never_drives_a_part_past_its_closed_stop(worlds, twins, ctx, cabinet, link, q0):
    world = worlds[cabinet]
    part = world.scene.cabinet_spec.part(link)
    j = joint_name(world, link)
    adr = world.model.jnt_qposadr[world.model.joint(j).id]
    out = None
    for g in handle_grasps(part, q0, world.scene.T_world_cabinet):
        world.reset({j: q0})
        out = Push(g).run(world, ctx=ctx)
        if out.status is not Status.IK_INFEASIBLE:
            break
    assert isinstance(out.status, Status)
    assert out.status is not Status.IK_INFEASIBLE, out.summary()
    assert world.part_positions()[j] >= -STOP_TOLERANCE
    assert out.qpos[:, adr].min() >= -STOP_TOLERANCE, out.qpos[:, adr].min()
    if q0 > 0:  # it was pushed shut
        assert world.part_positions()[j] < q0
    twin = twins[cabinet]
    twin.reset({j: q0})
    t = Push(g).simulate(twin)
    assert isinstance(t.status, Status)
    assert twin.world.part_positions()[j] >= -STOP_TOLERANCE
    if len(t.qpos):
        assert t.qpos[:, twin.world.model.jnt_qposadr[twin.world.model.joint(j).id]].min() >= (
            -STOP_TOLERANCE
        )


def test_no_part_ever_passes_its_closed_stop(sample, worlds, twins) -> None:
    """Over every recorded instant of every run of the sample (true and wrong models,
    full robot and twin), no part joint is behind its closed stop."""
    for r in sample:
        pairs = ((r.out, worlds[r.cabinet].model), (r.twin, twins[r.cabinet].world.model))
        for out, model in pairs:
            if not len(out.qpos):
                continue
            for j in out.part_motion:
                q = out.qpos[:, model.jnt_qposadr[model.joint(j).id]]
                assert q.min() >= -STOP_TOLERANCE, (r.cabinet, r.link, r.belief, j, q.min())


# --- 3. chains --------------------------------------------------------------------------


def phase_windows(keys: list[tuple[str, float]]) -> list[tuple[str, float, float]]:
    """``(phase, t0, t1)`` [s since the run's start] from an observer's key instants:
    each key closes the phase named after it (``pre-grasp``: the free motion)."""
    t_start = keys[0][1]
    return [(b[0], a[1] - t_start, b[1] - t_start) for a, b in itertools.pairwise(keys)]


def check_no_drive_with_arm_out(world: ManipulationWorld, out: Outcome, keys) -> float:
    """The base drives only with the arm near its tuck or a carry posture (as the
    execution's ``_tucked``), except along a whole-body line; returns the distance
    driven [m]."""
    m = world.model
    base = out.qpos[:, [m.jnt_qposadr[m.joint(j).id] for j in BASE_JOINTS]]
    arm = out.qpos[:, [m.jnt_qposadr[m.joint(j).id] for j in ARM_JOINTS]]
    dt = np.diff(out.times)
    speed = np.linalg.norm(np.diff(base[:, :2], axis=0), axis=1) / dt
    yaw_rate = np.abs(np.diff(base[:, 2])) / dt
    postures = np.array([TUCK[1:], *(c[1:] for c in CARRY.values())])
    off = np.min(np.max(np.abs(arm[1:, None, :] - postures[None]), axis=2), axis=1)
    wb = np.zeros(len(dt), dtype=bool)
    for name, t0, t1 in phase_windows(keys):
        if name in WHOLE_BODY_LINES:
            wb |= (out.times[1:] > t0) & (out.times[1:] <= t1)
    driving = ((speed > DRIVE_SPEED) | (yaw_rate > DRIVE_YAW_RATE)) & ~wb
    bad = driving & (off > TUCKED_TOLERANCE)
    assert not bad.any(), (
        f"{out.skill}: the base drives with the arm {off[bad].max():.2f} rad from its tuck "
        f"at t = {out.times[1:][bad][:3]} s"
    )
    return float(np.sum(speed[driving] * dt[driving]))


def gripper_object(world: ManipulationWorld, out: Outcome, t0: float, t1: float) -> np.ndarray:
    """``T_gripper_object`` (n, 4, 4) at the recorded instants in ``[t0, t1]`` [s]."""
    m = world.model
    d = mujoco.MjData(m)
    site, body = m.site(GRIPPER_SITE).id, m.body("object").id
    rel = []
    for row in out.qpos[(out.times >= t0) & (out.times <= t1)]:
        d.qpos[:] = row
        mujoco.mj_kinematics(m, d)
        Tg, To = np.eye(4), np.eye(4)
        Tg[:3, :3], Tg[:3, 3] = d.site_xmat[site].reshape(3, 3), d.site_xpos[site]
        To[:3, :3], To[:3, 3] = d.xmat[body].reshape(3, 3), d.xpos[body]
        rel.append(np.linalg.inv(Tg) @ To)
    return np.array(rel)


@pytest.mark.parametrize(
    ("cabinet", "link"), [("drawers_11", "link_1"), ("mixed_17", "link_5")], ids=["drawer", "door"]
)
def test_open_pick_place_chain_puts_the_object_inside(worlds, ctx, cabinet, link) -> None:
    world = worlds[cabinet]
    spec, T = world.scene.cabinet_spec, world.scene.T_world_cabinet
    part = spec.part(link)
    j = joint_name(world, link)
    world.reset()
    runs = []

    def run(skill) -> Outcome:
        keys: list[tuple[str, float]] = []
        out = skill.run(world, ctx=ctx, observer=lambda n: keys.append((n, float(world.data.time))))
        runs.append((out, keys))
        assert out.ok, out.summary()
        return out

    g = handle_grasps(part, 0.0, T)[0]
    run(opening(BelievedJoint.of_part(part, 0.0, T), g))
    tgt = place_target(spec, link, world.part_positions()[j], cabinet_pose(world))
    assert tgt.grasp == ("top" if part.joint_type == "prismatic" else "side")
    pick = run(Pick("object", tgt.grasp))
    assert pick.holding
    # One hand: nothing that grasps runs while it holds the object, and nothing moves.
    held = world.snapshot()
    for skill in (Pick("object", tgt.grasp), opening(BelievedJoint.of_part(part, 0.0, T), g)):
        with pytest.raises(ConfigError, match=f"{skill.name} needs an empty gripper"):
            skill.run(world, ctx=ctx)
        assert world.snapshot() == held
    place = run(Place("object", tgt.p, tgt.lift))
    # The task's verdict, from the world: inside the part, let go, the cabinet in place.
    assert inside(spec, link, world.part_positions()[j], cabinet_pose(world), world.object_pose())
    assert not place.holding and not dragged(world.cabinet_displacement())
    # No drive with the arm out; Pick and Place both drive (the object's table is away).
    driven = [check_no_drive_with_arm_out(world, out, keys) for out, keys in runs]
    assert driven[1] > 0.1 and driven[2] > 0.1, driven
    # The object moves with the gripper from the lift to the release.
    (_, pick_keys), (_, place_keys) = runs[1], runs[2]
    t_lift = dict(phase_windows(pick_keys)[i][::2] for i in range(len(pick_keys) - 1))["lift"]
    rel = np.concatenate(
        [
            gripper_object(world, pick, t_lift, math.inf),
            gripper_object(world, place, 0.0, release_start(place_keys)),
        ]
    )
    assert len(rel) > 100
    shift = np.linalg.norm(rel[:, :3, 3] - rel[0, :3, 3], axis=1).max()
    cos = (np.einsum("nij,ij->n", rel[:, :3, :3], rel[0, :3, :3]) - 1) / 2
    turn = float(np.arccos(np.clip(cos, -1, 1)).max())
    assert shift < CARRY_SHIFT_M and turn < CARRY_SHIFT_RAD, (shift, turn)


def release_start(keys: list[tuple[str, float]]) -> float:
    """When the release phase started [s since the run's start]."""
    return next(t0 for name, t0, _ in phase_windows(keys) if name == "release")


# --- 4. the twin agrees with the full robot ---------------------------------------------


def agreement(r: Run) -> tuple[bool, str]:
    """The twin's outcome agrees with the full robot's: the same status, the part moved
    alike (within 1 cm or 0.05 rad), the cabinet dragged or not alike."""
    full, twin = r.out, r.twin
    tol = AGREE_M if full.part_units[r.joint] == "m" else AGREE_RAD
    dm = abs(full.motion_of(r.joint) - twin.motion_of(r.joint))
    same_drag = dragged(full.cabinet_displacement) == dragged(twin.cabinet_displacement)
    ok = full.status == twin.status and dm <= tol and same_drag
    why = (
        f"{r.cabinet} {r.link} ({r.model}) {r.skill.name} as {r.belief or 'probe'}: "
        f"full {full.status.value} {full.motion_of(r.joint):+.3f}, "
        f"twin {twin.status.value} {twin.motion_of(r.joint):+.3f} {full.part_units[r.joint]}; "
        f"cabinet {full.cabinet_displacement:.3f} / {twin.cabinet_displacement:.3f} m"
    )
    return ok, why


def _sample_agreement(sample) -> tuple[int, int, list[str]]:
    assert len(sample) == 40  # the sample of the module docstring
    assert {r.belief == r.model for r in sample} == {True, False}  # true and wrong models
    judged = [agreement(r) for r in sample]
    bad = [why for ok, why in judged if not ok]
    return len(judged) - len(bad), len(judged), bad


def test_twin_agreement_on_the_fixed_sample_stays_above_its_floor(sample) -> None:
    n_ok, n, bad = _sample_agreement(sample)
    assert n_ok >= AGREE_FLOOR * n, f"twin agrees on {n_ok}/{n}; disagreements:\n" + "\n".join(bad)


@pytest.mark.xfail(strict=True, reason="issue 9's 95 % agreement is not reached yet (README)")
def test_twin_agrees_with_the_full_robot_on_the_fixed_sample(sample) -> None:
    n_ok, n, bad = _sample_agreement(sample)
    why = f"twin agrees on {n_ok}/{n}; disagreements:\n" + "\n".join(bad)
    assert n_ok >= AGREE_FRACTION * n, why


@pytest.mark.slow
def test_twin_agrees_on_unseen_generator_seeds(ctx) -> None:
    """The same sample on :data:`SLOW_SEEDS` (drawers-only and doors-only scenes, as the
    OpenDrawer and OpenDoor tasks draw them), fixed before it was run."""
    worlds = {
        f"{kind}s_{seed}": ManipulationWorld(SceneConfig(cabinet_seed=seed, cabinet_kinds=(kind,)))
        for seed in SLOW_SEEDS
        for kind in ("drawer", "door")
    }
    twins = {n: PlanningTwin(w.scene.cabinet_spec, w.config, ctx) for n, w in worlds.items()}
    runs = sample_runs(worlds, twins, ctx)
    for w in worlds.values():
        w.close()
    judged = [agreement(r) for r in runs]
    bad = [why for ok, why in judged if not ok]
    n_ok = len(judged) - len(bad)
    assert len(judged) >= 30
    assert n_ok >= AGREE_FRACTION * len(judged), (
        f"twin agrees on {n_ok}/{len(judged)}; disagreements:\n" + "\n".join(bad)
    )


def test_run_batch_equals_per_twin_runs(worlds, ctx) -> None:
    """Particles of one cabinet (the truth, link_5 believed hinged on the right, and
    believed a drawer), one of them open a little and one with the robot's base
    elsewhere (another placement: another rollout group): a batch gives each twin the
    outcome it gets alone."""
    world = worlds["mixed_17"]
    spec, T = world.scene.cabinet_spec, world.scene.T_world_cabinet
    specs = [spec] + [
        believed_spec(spec, "link_5", world_joint(world, "link_5", b), T)
        for b in ("right", "drawer")
    ]
    twins = [PlanningTwin(s, world.config, ctx) for s in (*specs, spec)]
    starts = [({}, None), ({}, None), ({"joint_5": 0.05}, None), ({}, np.array([0.1, 0.05, 0.1]))]
    part = spec.part("link_5")
    skill = OpenDoor(handle_grasps(part, 0.0, T)[0], BelievedJoint.of_part(part, 0.0, T))
    plan = skill.plan(twins[0].world)
    alone = []
    for tw, (parts, base) in zip(twins, starts, strict=True):
        tw.reset(parts, base)
        alone.append(tw.run(plan))
    for tw, (parts, base) in zip(twins, starts, strict=True):
        tw.reset(parts, base)
    together = run_batch(twins, plan)
    assert len(together) == len(twins)
    for a, b in zip(alone, together, strict=True):
        assert a.same_as(b), (a.summary(), b.summary())
    # The particles differ: the batch did not hand one outcome to all.
    assert not alone[0].same_as(alone[1]) and not alone[0].same_as(alone[2])


def test_twins_standing_elsewhere_share_one_placement_search(worlds) -> None:
    """The base placement search sees the robot's base only through the work direction
    of a plan whose approach is vertical; a door's is not, so a twin standing elsewhere
    (a particle after another skill) takes the placement another twin found for the
    same plan in the same world, and gets the outcome it gets with a search of its own."""
    world = worlds["mixed_17"]
    spec, T = world.scene.cabinet_spec, world.scene.T_world_cabinet
    part = spec.part("link_5")
    skill = OpenDoor(handle_grasps(part, 0.0, T)[0], BelievedJoint.of_part(part, 0.0, T))
    believed = ManipulationWorld(world.config)  # the world both particles plan in
    elsewhere = np.array([0.1, 0.05, 0.1])
    ctx = ControlContext()
    here, there = (PlanningTwin(spec, world.config, ctx) for _ in range(2))
    here.reset()
    skill.simulate(here, plan_world=believed)
    misses = ctx.placement_misses
    there.reset(None, elsewhere)
    shared = skill.simulate(there, plan_world=believed)
    assert ctx.placement_misses == misses  # served, not searched again
    alone = PlanningTwin(spec, world.config, ControlContext())
    alone.reset(None, elsewhere)
    assert skill.simulate(alone, plan_world=believed).same_as(shared), shared.summary()


def test_what_the_twin_derives_from_a_placement_goes_with_it(worlds) -> None:
    """The twin keeps what it derives from a placement (servos, base response, arm and
    stow paths) per placement *object*, not per id: a simulation again finds it, and
    once the context's cache and the twin's programs let the placement go, nothing of
    it is left for a new placement at the same address to find."""
    world = worlds["mixed_17"]
    spec, T = world.scene.cabinet_spec, world.scene.T_world_cabinet
    ctx = ControlContext(max_placements=2)
    twin = PlanningTwin(spec, world.config, ctx)
    part = spec.part("link_5")
    skill = OpenDoor(handle_grasps(part, 0.0, T)[0], BelievedJoint.of_part(part, 0.0, T))
    twin.reset()
    first = skill.simulate(twin)
    assert len(twin._derived) == 1
    twin.reset()
    assert skill.simulate(twin).same_as(first) and len(twin._derived) == 1
    for i in range(ctx.max_placements):  # other placements push it out of the context
        ctx.store_placement(("another", i), SkillStop(Status.IK_INFEASIBLE, "filler"))
    twin._programs.clear()
    gc.collect()
    assert len(twin._derived) == 0
    twin.reset()
    assert skill.simulate(twin).same_as(first)  # found anew, the same


def test_twins_of_other_cabinets_derive_a_shared_placement_once(worlds, monkeypatch) -> None:
    """What the twin derives from a placement and the full robot alone (the arm's
    servos, the base's response, the arm's poses) is derived once for every twin that
    runs the placement (the particles of a search node, each its own cabinet), and each
    twin gets the outcome it gets with a context of its own."""
    world = worlds["mixed_17"]
    spec, T = world.scene.cabinet_spec, world.scene.T_world_cabinet
    part = spec.part("link_5")
    skill = OpenDoor(handle_grasps(part, 0.0, T)[0], BelievedJoint.of_part(part, 0.0, T))
    other = believed_spec(spec, "link_5", world_joint(world, "link_5", "drawer"), T)
    believed = ManipulationWorld(world.config)  # the world both particles plan in
    calls = {"servo": 0, "base": 0}
    servo, response = twin_body_mod.arm_servo, BaseServo.response

    def count_servo(*args):
        calls["servo"] += 1
        return servo(*args)

    def count_response(self, *args):
        calls["base"] += 1
        return response(self, *args)

    monkeypatch.setattr(twin_body_mod, "arm_servo", count_servo)
    monkeypatch.setattr(BaseServo, "response", count_response)
    ctx = ControlContext()
    shared = []
    for s in (spec, other):
        twin = PlanningTwin(s, world.config, ctx)
        twin.reset()
        shared.append(skill.simulate(twin, plan_world=believed))
    assert calls == {"servo": 1, "base": 1}
    for s, out in zip((spec, other), shared, strict=True):
        alone = PlanningTwin(s, world.config, ControlContext())
        alone.reset()
        assert skill.simulate(alone, plan_world=believed).same_as(out), out.summary()
    believed.close()


def test_a_runs_head_rolled_out_in_spans_is_one_rollout_cut_at_its_stop(worlds, ctx) -> None:
    """The twin rolls a run's head out span by span and stops at the span where the
    monitors stop it: its states are those of one rollout of the whole head, bit for
    bit, up to there, and its verdict is the one judged on the whole; a run the
    monitors never stop is rolled out to its end. (A door pulled as a drawer stops; the
    door opened on its own hinge does not.)"""
    world = worlds["mixed_17"]
    spec, T = world.scene.cabinet_spec, world.scene.T_world_cabinet
    part = spec.part("link_5")
    grasp = handle_grasps(part, 0.0, T)[0]
    verdicts = []
    for skill in (
        OpenDoor(grasp, BelievedJoint.of_part(part, 0.0, T)),
        OpenDrawer(grasp, world_joint(world, "link_5", "drawer")),
    ):
        twin = PlanningTwin(spec, world.config, ctx)
        twin.reset()
        m, d = twin.world.model, twin.world.data
        twin.mark_cabinet()
        prog = twin.program(skill.plan(twin.world))
        twin._start(prog)
        start = np.empty(mujoco.mj_stateSize(m, twin_mod.ROLLOUT_STATE))
        mujoco.mj_getState(m, d, start, twin_mod.ROLLOUT_STATE)
        ctrl = twin.controls(prog)
        whole, _ = rollout.rollout(m, d, start[None], ctrl[None, : prog.free],
                                          control_spec=twin_mod.CONTROL)  # fmt: skip
        mujoco.mj_setState(m, d, start, twin_mod.ROLLOUT_STATE)
        states, verdict = twin.head(prog, ctrl)
        assert verdict == twin.judge(prog.steps(slice(0, prog.free)), whole[0])
        assert np.array_equal(states, whole[0][: len(states)])
        k = verdict[0]
        expected = prog.free if verdict[1] is Status.OK else k + 1
        assert k < len(states) <= max(expected, k + twin_mod.HEAD_SPAN)
        assert len(states) == prog.free or len(states) % twin_mod.HEAD_SPAN == 0
        verdicts.append(verdict[1])
    assert verdicts[0] is Status.OK and verdicts[1] is not Status.OK, verdicts
    assert len(states) < prog.free  # the stopped run was not simulated to its end


def test_the_twins_arm_poses_along_a_path_are_forward_kinematics_to_the_millimetre(
    worlds,
) -> None:
    """The twin runs forward kinematics every few steps of a joint path and interpolates
    between; every step's poses are the exact ones to a millimetre and a milliradian."""
    world = worlds["mixed_17"]
    ctx = ControlContext()
    twin = PlanningTwin(world.scene.cabinet_spec, world.config, ctx)
    a = np.r_[0.1, -0.05, 0.2, TUCK]
    b = a + np.r_[0.0, 0.0, 0.0, 0.2, 1.2, -0.8, 1.0, 0.9, -1.1, 0.7, 1.3]
    joints = a + np.linspace(0.0, 1.0, 301)[:, None] * (b - a)  # 1 rad s^-1 at 5 ms
    tcp, arm = twin._fk_along(joints)
    names = (*BASE_JOINTS, *ARM_TORSO_JOINTS)
    for i in range(len(joints)):
        T, pos, quat = ctx.ik.frames(dict(zip(names, joints[i].tolist(), strict=True)),
                                     twin._arm_fetch)  # fmt: skip
        assert np.linalg.norm(tcp[i, :3] - T[:3, 3]) < 1e-3
        assert np.max(np.linalg.norm(arm[i, :, :3] - pos, axis=1)) < 1e-3
        dots = np.abs(np.sum(arm[i, :, 3:] * quat, axis=1))
        assert np.all(2 * np.arccos(np.clip(dots, -1, 1)) < 2e-3)


def test_the_twins_arm_never_enters_a_part_and_its_recovery_stops_a_sliding_cabinet(
    worlds,
) -> None:
    """Two guards against a twin moving its cabinet as no full robot could. The arm's
    links, simulated from the last release on, stay parked when they would appear more
    than ``ARM_ENTRY_DEPTH`` inside a part (a mocap link pushed out of a door launched a
    twin's cabinet at metres a second); and the recovery after a stop ends at the first
    10 ms check where the cabinet has slid more than the limit since it began, as the
    full robot's monitored recovery does."""
    world = worlds["mixed_17"]
    twin = PlanningTwin(world.scene.cabinet_spec, world.config, ControlContext())
    twin.reset()
    m, d = twin.world.model, twin.world.data
    start = np.empty(mujoco.mj_stateSize(m, twin_mod.ROLLOUT_STATE))
    mujoco.mj_getState(m, d, start, twin_mod.ROLLOUT_STATE)
    row = np.empty(mujoco.mj_stateSize(m, twin_mod.CONTROL))
    mujoco.mj_getState(m, d, row, twin_mod.CONTROL)
    assert not twin._arm_starts_inside(start, row)  # parked: above everything
    T = world.scene.T_world_cabinet
    handle = world.scene.cabinet_spec.part("link_5").handle_at(0.0, T)
    inside = row.copy()
    mpos = inside[m.nu : m.nu + 3 * m.nmocap].reshape(m.nmocap, 3)
    mpos[twin._arm_mocap] = handle - np.array([0.03, 0.0, 0.0])  # through the door panel
    assert twin._arm_starts_inside(start, inside)
    after = np.empty_like(start)
    mujoco.mj_getState(m, d, after, twin_mod.ROLLOUT_STATE)
    assert np.array_equal(after, start)  # the check leaves the twin as it was

    n, limit = 200, twin.params.cabinet_motion_limit
    states = np.repeat(start[None], n, axis=0)
    a = 1 + twin._cabinet_xy
    assert len(twin._until_slid(states, start)) == n  # a cabinet at rest: all of it
    states[:, a] += np.linspace(0.0, 4 * limit, n)  # slides on at a steady speed
    cut = twin._until_slid(states, start)
    every = max(1, round(0.01 / m.opt.timestep))
    first = int(np.flatnonzero(states[:, a] - start[a] > limit)[0])
    assert len(cut) == math.ceil((first + 1) / every) * every  # the check at or after it


# --- 5. determinism ---------------------------------------------------------------------


def test_same_state_skill_and_seed_give_the_same_outcome(worlds, twins, ctx) -> None:
    world = worlds["drawers_11"]
    T = world.scene.T_world_cabinet
    part = world.scene.cabinet_spec.part("link_2")
    skill = OpenDrawer(handle_grasps(part, 0.0, T)[0], BelievedJoint.of_part(part, 0.0, T))
    outs, states = [], []
    for _ in range(2):
        world.reset()
        outs.append(skill.run(world, ctx=ctx, seed=5))
        states.append(world.snapshot())
    assert outs[0].ok and outs[0].same_as(outs[1])
    assert states[0] == states[1]
    # From a snapshot (mid-episode: the drawer open, the robot where it stopped).
    j = joint_name(world, "link_2")
    g = handle_grasps(part, world.part_positions()[j], T)[0]
    again = []
    for _ in range(2):
        world.restore(states[0])
        again.append(Push(g).run(world, ctx=ctx, seed=2))
    assert again[0].status is not Status.IK_INFEASIBLE
    assert again[0].same_as(again[1])
    # A fresh context (cold caches) gives the same outcome too.
    world.restore(states[0])
    assert Push(g).run(world, ctx=ControlContext(), seed=2).same_as(again[0])
    # The twin, from its reset and from a snapshot.
    twin = twins["drawers_11"]
    sims = []
    for _ in range(2):
        twin.reset()
        sims.append(skill.simulate(twin))
    assert sims[0].same_as(sims[1])
    snap = twin.snapshot()
    a = Push(g).simulate(twin)
    twin.restore(snap)
    assert Push(g).simulate(twin).same_as(a)


# --- 6. bad parameters ------------------------------------------------------------------


def _joint(world: ManipulationWorld, link: str) -> BelievedJoint:
    part = world.scene.cabinet_spec.part(link)
    return BelievedJoint.of_part(part, 0.0, world.scene.T_world_cabinet)


def _grasp(world: ManipulationWorld, link: str) -> np.ndarray:
    part = world.scene.cabinet_spec.part(link)
    return handle_grasps(part, 0.0, world.scene.T_world_cabinet)[0]


def test_bad_parameters_raise_one_clear_error_before_anything_moves(worlds) -> None:
    world = worlds["drawers_11"]
    world.reset()
    before = world.snapshot()
    g, joint = _grasp(world, "link_1"), _joint(world, "link_1")
    nan = g.copy()
    nan[0, 3] = math.nan
    sheared = g.copy()
    sheared[:3, :3] *= 1.1
    far = g.copy()
    far[:3, 3] += [0.0, 0.4, 0.0]
    tight = BelievedJoint("prismatic", joint.axis, limit=0.01)
    cases = [
        (OpenDrawer(nan, joint), ConfigError, r"finite.*nan"),
        (OpenDrawer(np.eye(3), joint), ConfigError, r"4x4.*shape \(3, 3\)"),
        (OpenDrawer(sheared, joint), ConfigError, "rotation"),
        (OpenDrawer("g", joint), ConfigError, "'g'"),
        (OpenDrawer(far, joint), UnknownNameError, r"handle.*0\.982, 0\.4"),
        (OpenDrawer(g, tight), ConfigError, r"impossible travel.*0\.010 m"),
        (OpenDoor(g, _joint(world, "link_1"), amount=-0.2), ConfigError, r"amount.*-0\.2"),
        (OpenDrawer(g, joint, amount=math.inf), ConfigError, r"amount.*inf"),
        (OpenDrawer(g, "door"), ConfigError, r"BelievedJoint.*'door'"),
        (Push(nan), ConfigError, "nan"),
        (PullV(far), UnknownNameError, "handle"),
        (Pick("mug"), UnknownNameError, "'mug'.*object"),
        (Pick("object", "bottom"), UnknownNameError, "'bottom'.*top, side"),
        (Place("object", np.eye(4)), ConfigError, "not held"),
        (Place("mug", np.eye(4)), UnknownNameError, "'mug'"),
    ]
    for skill, error, pattern in cases:
        with pytest.raises(error, match=pattern):
            skill.run(world)
        assert world.snapshot() == before, f"{skill!r} moved the world"
    vertical = g.copy()
    vertical[:3, :3] = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    with pytest.raises(ConfigError, match="vertical"):
        PullH(vertical).run(world)
    for seed in (-1, 1.5, True):
        with pytest.raises(ConfigError, match=f"seed.*{seed!r}"):
            Push(g).run(world, seed=seed)
    with pytest.raises(ConfigError, match="'belief'"):
        OpenDrawer(g, joint).run(world, plan_world="belief")
    with pytest.raises(ConfigError, match="'world'"):
        OpenDrawer(g, joint).run("world")
    with pytest.raises(ConfigError, match=r"PlanningTwin.*ManipulationWorld"):
        OpenDrawer(g, joint).simulate(world)
    assert world.snapshot() == before
    # The errors are the stack's, each one sentence naming the value.
    for bad, pattern in (
        (dict(type="spherical", axis=[1.0, 0, 0]), "'spherical'"),
        (dict(type="prismatic", axis=[0.0, 0, 0]), "axis"),
        (dict(type="prismatic", axis=[1.0, 0, 0], limit=-1.0), "-1.0"),
        (dict(type="revolute", axis=[0, 0, 1.0], origin=[math.nan, 0, 0]), "origin"),
    ):
        with pytest.raises(ConfigError, match=pattern):
            BelievedJoint(**bad)
    with pytest.raises(ConfigError, match=r"line_step.*0"):
        SkillParams(line_step=0.0)
    with pytest.raises(ConfigError, match=r"time_budget.*nan"):
        SkillParams(time_budget=math.nan)
    assert issubclass(ConfigError, PlannersError) and issubclass(UnknownNameError, PlannersError)


def test_an_unreachable_grasp_is_ik_infeasible_and_nothing_moves(worlds, ctx) -> None:
    world = worlds["drawers_11"]
    world.reset()
    before = world.snapshot()
    g = _grasp(world, "link_1")
    joint = _joint(world, "link_1")
    # The handle's own pose, but believed 1.5 m higher: no handle there.
    high = g.copy()
    high[2, 3] += 1.5
    with pytest.raises(UnknownNameError):
        OpenDrawer(high, joint).run(world, ctx=ctx)
    # A reachable grasp with a travel that runs into the floor is planned, found
    # unreachable and reported: nothing moves.
    down = BelievedJoint("prismatic", np.array([0.0, 0.0, -1.0]), limit=2.0)
    out = OpenDrawer(g, down, amount=1.5).run(world, ctx=ctx)
    assert out.status is Status.IK_INFEASIBLE and out.sim_time == 0.0, out.summary()
    assert world.snapshot() == before
    assert "no base pose" in out.detail and out.phase == "plan"


def test_a_pull_that_slides_the_cabinet_stops_there(sample) -> None:
    """The cabinet-motion guard: a run stopped ``cabinet_moved`` did slide the cabinet
    past ``cabinet_motion_limit``; no run under the right model is stopped; and the
    twin, predicting the same plans, stops the same runs."""
    limit = SkillParams().cabinet_motion_limit
    stopped = [r for r in sample if r.out.status is Status.CABINET_MOVED]
    assert stopped, "no run of the sample slid the cabinet"
    for r in stopped:
        assert r.belief not in ("", r.model), (r.cabinet, r.link, r.belief)
        assert r.displacement > limit, (r.cabinet, r.link, r.belief, r.displacement)
    alike = [r for r in stopped if r.twin.status is Status.CABINET_MOVED]
    assert len(alike) >= 0.8 * len(stopped), (len(alike), len(stopped))
    # The recovery after the stop is guarded too: no single pull drags the cabinet off.
    assert max(r.displacement for r in sample) < 3 * limit


def test_an_opening_past_the_likeliest_limit_goes_on_slowly(worlds) -> None:
    """A drawer's limit shows in no view: pulled on toward a longer model's limit
    (``joint.limit``), an opening eases from ``ease_distance`` before the likeliest
    model's (``likely_limit`` less the margin) to its end, so the part meets either one
    slowly; with the likeliest limit the longest it eases as before."""
    world = worlds["drawers_11"]
    world.reset()
    link = "link_1"
    g = _grasp(world, link)
    joint = dataclasses.replace(world_joint(world, link, "drawer"), limit=0.3)
    p = DEFAULT_PARAMS
    amount = min(p.drawer_travel, joint.limit - p.limit_margin_m)
    for likely, slow in ((0.15, amount - (0.15 - p.limit_margin_m)), (0.3, 0.0)):
        plan = OpenDrawer(g, joint, likely_limit=likely).plan(world, p)
        lines = {ln.name: ln for ln in plan.lines}
        assert lines["ease"].speed == p.ease_speed
        assert abs(lines["ease"].length - (slow + p.ease_distance)) < p.line_step, likely
        assert abs(lines["move"].length + lines["ease"].length - amount) < 1e-9


def test_an_opening_ends_in_a_slow_ease_line(worlds) -> None:
    """An opening's pull is two lines: ``move`` at ``open_speed``, then ``ease``, its
    last ``ease_distance`` at ``ease_speed`` (the part meets a stop there slowly); one
    path together, the believed joint's positions split with it; a probe stays one
    line."""
    world = worlds["drawers_11"]
    world.reset()
    link = "link_1"
    g = _grasp(world, link)
    joint = world_joint(world, link, "drawer")
    p = DEFAULT_PARAMS
    plan = OpenDrawer(g, joint).plan(world, p)
    lines = {ln.name: ln for ln in plan.lines}
    move, ease = lines["move"], lines["ease"]
    names = [ph.name for ph in plan.phases]
    assert names[names.index("move") + 1] == "ease"
    assert move.speed == p.open_speed and ease.speed == p.ease_speed
    assert abs(ease.length - p.ease_distance) < p.line_step
    whole = OpenDrawer(g, joint).plan(world, dataclasses.replace(p, ease_distance=1.0))
    (one,) = [ln for ln in whole.lines if ln.name == "move"]
    assert "ease" not in [ln.name for ln in whole.lines]
    assert np.allclose(np.concatenate([move.poses, ease.poses]), one.poses)
    assert np.allclose(np.concatenate([move.part_q, ease.part_q]), one.part_q)
    assert abs(move.length + ease.length - one.length) < 1e-9
    probe = PullH(g).plan(world, p)
    assert "ease" not in [ln.name for ln in probe.lines]


class _Held:
    """What :meth:`Place.plan` reads of a world: the TCP's and the object's poses."""

    def __init__(self, T_wg: np.ndarray, T_wo: np.ndarray) -> None:
        self.T_wg, self.T_wo = T_wg, T_wo

    def site_pose(self, name: str) -> np.ndarray:
        return self.T_wg

    def object_pose(self) -> np.ndarray:
        return self.T_wo


def test_an_object_that_rose_in_the_fingers_is_let_go_as_high_above_its_target():
    """Held from the side 2.5 cm higher than Pick took it (OpenDoor 10053: every place,
    the table's too, put the palm into the surface), the hand stops where Pick's hold
    would put it and the object drops the 2.5 cm; a rise within the tolerance, or an
    object that slid down, changes nothing; held from above (the fingertips far above
    the object's bottom), nothing either."""
    from strug_manip.control.skills import RISE_TOLERANCE, held_rise

    side = np.eye(4)
    side[:3, :3] = np.column_stack([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    side[:3, 3] = (0.6, 0.0, 1.0)
    top = np.eye(4)
    top[:3, :3] = np.column_stack([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    top[:3, 3] = (0.6, 0.0, 1.0)

    def obj(T_wg: np.ndarray, dz: float) -> np.ndarray:
        T = np.eye(4)
        T[:3, 3] = T_wg[:3, 3] + (0.0, 0.0, dz)
        return T

    assert held_rise(side, obj(side, 0.0)) == 0.0
    assert held_rise(side, obj(side, 0.025)) == pytest.approx(0.025)
    assert held_rise(side, obj(side, RISE_TOLERANCE - 1e-4)) == 0.0
    assert held_rise(side, obj(side, -0.02)) == 0.0
    assert held_rise(top, obj(top, -0.01)) == 0.0
    assert held_rise(top, obj(top, 0.01)) == 0.0

    target = np.eye(4)
    target[:3, 3] = (1.0, 0.2, 0.7)
    centred = Place("object", target, lift=0.02).plan(_Held(side, obj(side, 0.0)))
    risen = Place("object", target, lift=0.02).plan(_Held(side, obj(side, 0.025)))
    # The hand goes where it goes with Pick's hold (the object 2.5 cm higher there),
    # not 2.5 cm lower.
    assert risen.pre[:3, 3] == pytest.approx(centred.pre[:3, 3])
    assert centred.phases[-3].name == risen.phases[-3].name == "lower"
    let_go = [p.poses[-1][:3, 3] for p in (centred.phases[-3], risen.phases[-3])]
    assert let_go[1] == pytest.approx(let_go[0])
