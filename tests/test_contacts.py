"""The robot-contact checker (:class:`strug_manip.control.contacts.ContactChecker`): the
one collision check of plans, lines, placements and routes.

Scene: ``models/cabinets/drawers_11`` (seed 11, top drawer ``link_1``'s bar handle at
(0.98, 0, 1.06) m), the base at the origin; configurations are IK solutions.
"""

from __future__ import annotations

import numpy as np
import pytest

from planners.errors import ConfigError, UnknownNameError
from strug_manip.control import ControlContext
from strug_manip.control.contacts import ContactChecker
from strug_manip.robot.fetch import ARM_TORSO_JOINTS, BASE_JOINTS, TUCK

BASE = np.zeros(3)


@pytest.fixture(scope="module")
def ik():
    return ControlContext().ik


def arm_at(ik, p) -> np.ndarray:
    """Base + torso + arm (11,) with the gripper at ``p`` (3,) [m] pointing +x."""
    T = np.eye(4)
    T[:3, 3] = p
    r = ik.solve(T, dict(zip(BASE_JOINTS, BASE.tolist(), strict=True)))
    assert r.success
    return np.concatenate([BASE, [r.q[j] for j in ARM_TORSO_JOINTS]])


@pytest.fixture
def checker(world) -> ContactChecker:
    world.reset()
    c = ContactChecker(world.model, (*BASE_JOINTS, *ARM_TORSO_JOINTS))
    return c.load(world.data)


def test_contacts_name_the_bodies_and_allowed_pairs_clear_them(checker, ik) -> None:
    tuck = np.concatenate([BASE, TUCK])
    assert checker.free(tuck) and checker.contacts(tuck) == []
    inside = arm_at(ik, (1.05, 0.0, 1.06))  # the hand inside the top drawer's front
    hits = checker.contacts(inside)
    assert hits and all("cabinet/link_1" in h for h in hits), hits
    assert checker.pairs(inside).shape[1] == 2
    drawer = checker.body_id("cabinet/link_1")
    checker.allow(checker.hand_with([drawer]))
    assert checker.free(inside)
    checker.allow()  # replaced, not added to
    assert not checker.free(inside)
    # A segment from free to blocked reports the contacts on the way.
    outside = arm_at(ik, (0.8, 0.0, 1.06))
    assert checker.free(outside)
    assert checker.segment(outside, inside) != [] and checker.path([outside]) == []
    assert checker.path([outside, arm_at(ik, (0.8, 0.0, 0.95))]) == []
    # The straight joint-space line out of the tuck folds the wrist into the torso: the
    # robot's contacts with itself count too.
    hits = checker.path([np.concatenate([BASE, TUCK]), outside])
    assert hits and not any("cabinet" in h for h in hits), hits


def test_the_hand_depth_grows_as_the_fingers_meet_the_front(checker, ik) -> None:
    """How deep the hand is in the scene at the last check: 0 where it is free, and,
    as the fingertips first meet the drawer's front (TCP at x = 0.955 m), growing as
    much as the TCP is pushed; 0 again once the contact is allowed."""
    depths = []
    for x in (0.94, 0.96, 0.965, 0.97):
        checker.free(arm_at(ik, (x, 0.0, 1.06)))
        depths.append(checker.hand_depth())
    assert depths[0] == 0.0
    assert 0.0 < depths[1] < depths[2] < depths[3], depths
    assert abs((depths[3] - depths[1]) - 0.01) < 0.003, depths
    checker.allow(checker.hand_with([checker.body_id("cabinet/link_1")]))
    checker.free(arm_at(ik, (0.97, 0.0, 1.06)))
    assert checker.hand_depth() == 0.0


def test_the_checker_sees_the_state_it_was_loaded_with(world, ik) -> None:
    """Opened 0.2 m, the top drawer fills where the hand was free (the drawer's front
    comes to x = 0.76 m); set() moves a joint of the scratch state without physics."""
    hand = arm_at(ik, (0.85, 0.0, 1.06))
    world.reset()
    c = ContactChecker(world.model, (*BASE_JOINTS, *ARM_TORSO_JOINTS)).load(world.data)
    assert c.free(hand)
    world.reset({"joint_1": 0.2})
    c.load(world.data)
    assert any("cabinet/link_1" in h for h in c.contacts(hand))
    c.set({"cabinet/joint_1": 0.0})
    assert c.get("cabinet/joint_1") == 0.0 and c.free(hand)
    world.reset()


def test_an_attached_object_follows_the_gripper_and_its_contacts_count(checker, ik) -> None:
    T_go = np.eye(4)
    T_go[0, 3] = 0.3  # the object held 0.3 m ahead of the TCP: in the drawer's front board
    hand = arm_at(ik, (0.75, 0.0, 1.06))
    assert checker.free(hand)
    checker.attach("object", T_go)
    assert checker.attached_body == checker.body_id("object")
    hits = checker.contacts(hand)
    assert any("object" in h and "cabinet" in h for h in hits), hits
    T_go[0, 3] = 0.0  # in the hand: touching the fingers is allowed
    checker.attach("object", T_go)
    checker.allow()
    assert checker.free(hand)
    checker.attach(None)
    assert checker.attached_body == -1


def test_bad_names_and_joints_raise(world, checker) -> None:
    with pytest.raises(UnknownNameError, match="'elbow'"):
        ContactChecker(world.model, ("torso_lift_joint", "elbow"))
    with pytest.raises(ConfigError, match=r"object/free.*hinge or slide"):
        ContactChecker(world.model, ("object/free",))
    with pytest.raises(ConfigError, match="non-empty"):
        ContactChecker(world.model, ())
    with pytest.raises(UnknownNameError, match="'mug'"):
        checker.body_id("mug")
    with pytest.raises(UnknownNameError, match="'joint_9'"):
        checker.set({"joint_9": 0.1})
    with pytest.raises(ConfigError, match=r"free joint.*cabinet/link_1"):
        checker.attach("cabinet/link_1", np.eye(4))


def _reference_pairs(world, q: np.ndarray, attached: tuple[str, np.ndarray] | None) -> set:
    """The forbidden robot contacts at ``q`` computed on the whole model, the scene's
    contacts among themselves included (self-contacts on): what the checker must
    report without computing the scene's own contacts."""
    import copy

    import mujoco

    m = copy.copy(world.model)
    c = ContactChecker(world.model, (*BASE_JOINTS, *ARM_TORSO_JOINTS))
    robot_geoms = c.robot[np.asarray(m.geom_bodyid)] & (np.asarray(m.geom_contype) != 0)
    m.geom_conaffinity[robot_geoms] |= m.geom_contype[robot_geoms]
    d = mujoco.MjData(m)
    d.qpos[:] = world.data.qpos
    d.qpos[c.qadr] = q
    mujoco.mj_kinematics(m, d)
    counts = c.robot.copy()
    allowed = set()
    if attached is not None:
        bid = c.body_id(attached[0])
        adr = int(m.jnt_qposadr[m.body_jntadr[bid]])
        site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "gripper")
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = d.site_xmat[site].reshape(3, 3), d.site_xpos[site]
        T = T @ attached[1]
        d.qpos[adr : adr + 3] = T[:3, 3]
        mujoco.mju_mat2Quat(d.qpos[adr + 3 : adr + 7], T[:3, :3].reshape(9).copy())
        mujoco.mj_kinematics(m, d)
        counts[bid] = True
        allowed = {frozenset((bid, int(h))) for h in c.hand}
    mujoco.mj_collision(m, d)
    out = set()
    for k in range(d.ncon):
        a, b = (int(m.geom_bodyid[g]) for g in d.contact.geom[k])
        if (counts[a] or counts[b]) and frozenset((a, b)) not in allowed:
            out.add(frozenset((a, b)))
    return out


def test_leaving_out_the_scenes_own_contacts_changes_no_answer(world, checker, ik) -> None:
    """On random arm configurations before the open top drawer (many touching the
    cabinet or the robot itself), free or held: the checker reports exactly the
    forbidden pairs the whole model's contacts give."""
    world.reset({"joint_1": 0.2})
    checker.load(world.data)
    rng = np.random.default_rng(0)
    lo = np.array([0.0, -1.6, -1.2, -3.1, -2.2, -3.1, -2.1, -3.1])
    hi = np.array([0.38, 1.6, 1.5, 3.1, 2.2, 3.1, 2.1, 3.1])
    T_go = np.eye(4)
    T_go[0, 3] = 0.12
    seen_hits = 0
    for attached in (None, ("object", T_go)):
        checker.attach(*attached) if attached else checker.attach(None)
        checker.allow()
        for _ in range(60):
            q = np.concatenate([[0.25, 0.0, 0.0], rng.uniform(lo, hi)])
            got = {frozenset(p) for p in checker.pairs(q).tolist()}
            assert got == _reference_pairs(world, q, attached), q
            seen_hits += bool(got)
    assert 20 < seen_hits < 110  # both answers were asked for
    checker.attach(None)
    world.reset()


def test_a_held_object_kept_clear_counts_its_contacts_from_that_distance(checker, ik) -> None:
    """``keep_clear(d)``: the attached object 1 cm short of the drawer's front (beside
    the handle) touches nothing, yet counts with 2 cm to keep; 0 and detaching give the
    plain check back."""
    hand = arm_at(ik, (0.75, 0.15, 1.06))
    T_go = np.eye(4)
    for reach in np.arange(0.0, 0.4, 0.002):  # the object ahead of the TCP meets the front
        T_go[0, 3] = reach
        checker.attach("object", T_go)
        checker.allow()
        if not checker.free(hand):
            break
    T_go[0, 3] = reach - 0.01
    checker.attach("object", T_go)
    checker.allow()
    assert checker.free(hand)
    checker.keep_clear(0.02)
    assert not checker.free(hand)
    assert any("object" in h and "cabinet" in h for h in checker.contacts(hand))
    checker.keep_clear(0.0)
    assert checker.free(hand)
    checker.keep_clear(0.02)
    checker.attach(None)
    with pytest.raises(ConfigError, match="attached"):
        checker.keep_clear(0.02)
    checker.attach("object", T_go)
    checker.allow()
    assert checker.free(hand)  # detaching reset the distance
    with pytest.raises(ConfigError, match="distance"):
        checker.keep_clear(-0.01)


def test_scene_bodies_kept_clear_count_the_robot_from_a_distance_unless_excused(
    checker, ik
) -> None:
    """``keep_clear_of(bodies, d)``: the hand 1 cm short of the top drawer's front
    touches nothing, yet counts with 2 cm to keep from the cabinet (the robot's own
    pairs are unaffected: the tuck stays free); an excused pair counts only where it
    touches; 0 gives the plain check back."""
    cabinet = [b for b in range(checker.model.nbody)
               if checker.model.body(b).name.startswith("cabinet/")]  # fmt: skip
    tuck = np.concatenate([BASE, TUCK])
    for x in np.arange(0.90, 1.0, 0.002):  # the fingertips meet the front at 0.955
        if not checker.free(arm_at(ik, (x, 0.0, 1.06))):
            break
    near = arm_at(ik, (x - 0.01, 0.0, 1.06))
    assert checker.free(near)
    checker.keep_clear_of(cabinet, 0.02)
    try:
        assert checker.free(tuck)
        assert not checker.free(near)
        hits = checker.pairs(near)
        assert len(hits) and all(
            checker.model.body(int(b)).name.startswith("cabinet/")
            for b in hits.ravel() if not checker.robot[int(b)]
        )  # fmt: skip
        gaps = checker.geom_gaps(near)  # the pairs within the margin, their distances
        pairs = [tuple(p) for p in checker.geom_pairs(near).tolist()]
        checker.excuse(pairs)
        assert checker.free(near)  # within the margin, excused
        assert not checker.free(arm_at(ik, (x + 0.01, 0.0, 1.06)))  # touching still counts
        # Excused down to the distance it has at `near` less 5 mm: 3 mm nearer is free,
        # 8 mm nearer is not (yet touches nothing).
        within = [float(gaps[1][(gaps[0] == p).all(axis=1)].min()) - 0.005 for p in pairs]
        checker.excuse(pairs, within)
        assert checker.free(arm_at(ik, (x - 0.007, 0.0, 1.06)))
        assert not checker.free(arm_at(ik, (x - 0.002, 0.0, 1.06)))
        checker.keep_clear_of(cabinet, 0.0)
        assert checker.free(arm_at(ik, (x - 0.002, 0.0, 1.06)))
        checker.keep_clear_of(cabinet, 0.02)
        with pytest.raises(ConfigError, match="2 distances"):
            checker.excuse(pairs, [0.0, 0.0] if len(pairs) != 2 else [0.0] * 3)
        checker.excuse()
        assert not checker.free(near)
    finally:
        checker.keep_clear_of(cabinet, 0.0)
    assert checker.free(near)
    with pytest.raises(ConfigError, match="distance"):
        checker.keep_clear_of(cabinet, -0.01)
    with pytest.raises(ConfigError, match="scene bodies"):
        checker.keep_clear_of([checker.body_id("gripper_link")], 0.02)
