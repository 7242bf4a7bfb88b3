"""The manipulation tasks as POMDPs: bad input, the initial belief, the solver contract
and determinism (cabinet seeds below 1,000: the episodes' own seeds are held out)."""

from __future__ import annotations

import dataclasses
import re
from types import SimpleNamespace

import mujoco
import numpy as np
import pytest

from planners.belief import ParticleBelief
from planners.errors import ConfigError, UnknownNameError
from planners.pomdp import Step
from planners.solvers import SOLVERS, make_solver
from strug_manip.domains import MANIPULATION_DOMAINS, make_domain
from strug_manip.domains.manipulation import episode_setup
from strug_manip.domains.manipulation.actions import TABLE, ManipAction, part_kind
from strug_manip.domains.manipulation.catalogue import PLAN_MODELS, representatives
from strug_manip.domains.manipulation.conditioning import (
    SAME_HINGE,
    Front,
    condition,
    ended_limits,
    longest_limit,
    passed_limits,
    seen_positions,
    swing,
)
from strug_manip.domains.manipulation.grounding import cabinet_frame, handle_point, position
from strug_manip.domains.manipulation.health import status_of
from strug_manip.domains.manipulation.real import MATCH_RADIUS
from strug_manip.domains.manipulation.rules import BEFORE_MOTION, REPEATS_ITSELF, UNCHANGED
from strug_manip.domains.manipulation.state import (
    STATUS_CODES,
    ManipObservation,
    ManipState,
    observation_key,
)
from strug_manip.experiments.episode import run_episode
from strug_manip.objects.generator import generate_cabinet
from strug_manip.objects.hypotheses import BelievedJoint, model_of
from strug_manip.robot.fetch import GRIPPER_SITE
from strug_manip.world.scene import cabinet_pose

#: A drawers-only cabinet whose top drawer the robot opens (``tools/eval_skills.py``).
SEED = 11


def _top_point(domain) -> np.ndarray:
    """The world point of the true cabinet's first part of the task's kind."""
    real = domain.real
    T = real.world.scene.T_world_cabinet
    part = next(p for p in real.world.scene.cabinet_spec.parts if p.link == real.target)
    return (T @ np.r_[part.cell_center, 1.0])[:3]


def _start(d, rng: np.random.Generator) -> ManipState:
    """A new real episode of task ``d`` (its environment reset): the real state."""
    d.environment.reset(rng)
    return d.environment.state


def _real_step(d, s: ManipState, a: ManipAction, rng: np.random.Generator) -> Step:
    """``a`` on the real robot from real state ``s`` (the environment put there)."""
    env = d.environment
    env.state = s
    obs, reward, done = env.execute(a, rng)
    return Step(env.state, obs, reward, done)


def _with_reps(d, reps) -> None:
    d.root = dataclasses.replace(d.root, reps=reps)


def test_bad_input_gets_one_clear_error():
    with pytest.raises(UnknownNameError, match="probe"):
        make_domain("opendrawer", probes=("Shake",))
    with pytest.raises(ConfigError, match="views"):
        make_domain("opendrawer", views=9)
    with pytest.raises(ConfigError, match="target"):
        make_domain("opendrawer", target=(1.0, 2.0))
    d = make_domain("opendrawer", cabinet_seed=SEED, target=(0.0, 5.0, 9.0))
    with pytest.raises(ConfigError, match=r"is on no drawer part of cabinet_0011 \(its cells"):
        _start(d, np.random.default_rng(0))
    with pytest.raises(ConfigError, match="no episode yet"):
        make_domain("opendoor").initial_belief(np.random.default_rng(0), 4)


def _drawer_episode(seed: int):
    """An OpenDrawer episode's domain after its initial belief (target given: no
    full-robot check of the target)."""
    probe = make_domain("opendrawer", cabinet_seed=seed, particles=8)
    _start(probe, np.random.default_rng(0))
    point = _top_point(probe)
    probe.close()
    d = make_domain("opendrawer", cabinet_seed=seed, particles=8, target=tuple(point))
    s0 = _start(d, np.random.default_rng(0))
    belief = d.environment.condition(d.initial_belief(np.random.default_rng(1), 8))
    return d, s0, belief


@pytest.fixture(scope="module")
def drawer_episode():
    """The episode of cabinet :data:`SEED` (:func:`_drawer_episode`)."""
    d, s0, belief = _drawer_episode(SEED)
    yield d, s0, belief
    d.close()


#: A cabinet with two catalogued parts or more that have a true counterpart
#: (:meth:`RealEnvironment.counterpart`).
SHUT_SEED = 12


@pytest.fixture(scope="module")
def shut_episode():
    """The episode of cabinet :data:`SHUT_SEED` (:func:`_drawer_episode`)."""
    d, s0, belief = _drawer_episode(SHUT_SEED)
    yield d, s0, belief
    d.close()


def test_initial_belief_holds_the_true_target_model(drawer_episode):
    d, _, belief = drawer_episode
    spec = d.real.world.scene.cabinet_spec
    true = model_of(spec.part(d.real.target))
    held = {
        part_kind(d.worlds.particles[s.origin].spec.part(d.cat.targets[s.origin]))
        for s in belief.states
        if d.cat.targets[s.origin] is not None
    }
    assert true in held, f"the target is a {true}; the particles hold {held}"


def test_unknown_actions_are_refused_and_steps_are_cached(drawer_episode):
    d, _, belief = drawer_episode
    rng = np.random.default_rng(0)
    with pytest.raises(UnknownNameError, match="action"):
        d.step(belief.states[0], ManipAction("Fly", 0), rng)
    with pytest.raises(UnknownNameError, match="action"):
        d.step(belief.states[0], ManipAction("Place", 99), rng)
    a = ManipAction("Pick", grasp="top")
    s = belief.states[0]
    first = d.step(s, a, rng)
    hits = d.worlds.outcomes.hits
    again = d.step(s, a, rng)
    assert d.worlds.outcomes.hits == hits + 1
    assert first.state == again.state and first.obs.key == again.obs.key
    assert isinstance(first.obs, ManipObservation) and first.obs.cloud is None
    # A twin that holds the object cannot pick (one hand), and nothing changes.
    assert first.obs.key[1] == 1.0, first.obs.summary
    twice = d.step(first.state, a, rng)
    assert twice.state.sim == first.state.sim and twice.reward == 0.0
    assert "not_applicable" in twice.obs.summary


def _record(domain: str, solver: str, seed: int, **kw) -> list[tuple]:
    d = make_domain(domain, cabinet_seed=SEED if domain == "opendrawer" else 12, **kw)
    cfg = make_solver(solver, {"sims": 2, "particles": 4} if solver in ("strug", "entropy",
                      "active") else {"sims": 2})  # fmt: skip
    try:
        res = run_episode(d, cfg, seed, n_particles=6)
    finally:
        d.close()
    return [(r.action, r.observation, r.reward) for r in res.steps]


@pytest.mark.parametrize("solver", list(SOLVERS))
def test_every_solver_runs_an_opendrawer_episode(solver):
    steps = _record("opendrawer", solver, 0, particles=6, max_steps=1)
    assert len(steps) == 1


@pytest.mark.slow
@pytest.mark.parametrize("domain", list(MANIPULATION_DOMAINS))
@pytest.mark.parametrize("solver", list(SOLVERS))
def test_every_solver_runs_every_manipulation_domain(domain, solver):
    steps = _record(domain, solver, 0, particles=6, max_steps=2)
    assert 1 <= len(steps) <= 2


def test_the_same_seed_gives_the_same_episode():
    a = _record("opendrawer", "random", 3, particles=6, max_steps=2)
    b = _record("opendrawer", "random", 3, particles=6, max_steps=2)
    assert a == b


def test_open_cell_is_read_off_the_boards_and_walls_front_edges():
    from strug_manip.domains.manipulation.belief import open_cell
    from strug_manip.objects.assembly import CabinetModel

    model = CabinetModel(0.6, 0.8, 0.4, (), np.eye(4))
    rng = np.random.default_rng(0)

    def slab(x, y, z, n=400):
        return np.column_stack([rng.uniform(*x, n), rng.uniform(*y, n), rng.uniform(*z, n)])

    cloud = np.concatenate([
        slab((-0.01, 0.0), (-0.28, 0.28), (0.292, 0.300)),  # the floor board's front edge
        slab((-0.01, 0.0), (-0.28, 0.28), (0.600, 0.608)),  # the board above
        slab((-0.3, -0.2), (-0.28, 0.28), (0.0, 0.8)),  # the back panel: not a wall
        slab((-0.1, 0.0), (0.280, 0.300), (0.0, 0.8)),  # the right wall
    ])  # fmt: skip
    cell = open_cell(model, np.array([0.0, 0.0, 0.45]), [cloud])
    y0, y1, z0, z1 = cell.rect
    assert cell.kind == "shelf"
    assert y0 == pytest.approx(-0.6 / 2 + 0.0175)  # no left wall seen: the carcass's
    assert y1 == pytest.approx(0.28, abs=2e-3)
    assert z0 + 0.008 == pytest.approx(0.300, abs=1e-3)  # the board's top is the floor
    assert z1 == pytest.approx(0.600, abs=1e-3)


def test_the_belief_takes_over_what_the_robot_knows_after_a_real_step(drawer_episode):
    d, s0, belief = drawer_episode
    rng = np.random.default_rng(0)
    real = _real_step(d, s0, ManipAction("Pick", grasp="top"), rng)
    moved = [d.step(s, ManipAction("Pick", grasp="top"), rng).state for s in belief.states]
    d.real.world.restore(real.state.sim)
    shift = np.eye(4)
    shift[:3, 3] = [0.03, -0.02, 0.0]  # as if the real cabinet had been dragged
    d.real.world.set_cabinet_pose(shift @ d.real.world.cabinet_pose())
    conditioned = d.environment.condition(type(belief)(moved, belief.weights, belief.origin))
    rw = d.real.world
    moved = rw.cabinet_pose() @ np.linalg.inv(rw.scene.T_world_cabinet)
    assert np.linalg.norm(moved[:2, 3]) > 0.03
    for s in conditioned.states:
        tw = d.worlds.twins[s.origin]
        tw.restore(s.sim)
        # Each model's cabinet moved as the real one did, from where it stood itself.
        assert np.allclose(tw.world.cabinet_pose(), moved @ tw.world.scene.T_world_cabinet,
                           atol=1e-6)  # fmt: skip
        assert np.allclose(tw.robot_base[:2], [d.real.world.robot_qpos()[j] for j in
                                               ("base_x_joint", "base_y_joint")])  # fmt: skip


def test_an_opening_grasps_where_the_dragged_cabinet_stands(drawer_episode):
    """Once the real cabinet has been dragged (and every particle's cabinet with it),
    an opening's grasp and joint move with the cabinet, so it can still start; a
    cabinet that settled by less than ``UNCHANGED`` keeps the model's own frame."""
    d, s0, belief = drawer_episode
    rw = d.real.world
    before_test = rw.snapshot()
    rw.restore(s0.sim)  # the episode's start: the object on the table
    T_reset = rw.scene.T_world_cabinet
    a = next(ManipAction("OpenDrawer", k, h) for k, part in enumerate(d.parts)
             for h, kind in enumerate(part.hypotheses) if kind == "drawer")  # fmt: skip
    rep = d.root.rep(a)
    later = [dataclasses.replace(s, t=1) for s in belief.states]  # after a real step

    def grounded(T: np.ndarray):
        """The real cabinet at ``T``, the belief conditioned: ``rep``'s state, and the
        first skill ``a`` grounds to there."""
        rw.set_cabinet_pose(T)
        conditioned = d.environment.condition(type(belief)(later, belief.weights, belief.origin))
        assert d.root.rep(a) == rep
        s = next(s for s in conditioned.states if s.origin == rep)
        return s, d.skills(rep, a, s.sim)[0][0]

    shift = np.eye(4)
    shift[:3, 3] = [0.04, -0.03, 0.0]  # the real cabinet dragged 5 cm
    try:
        _, before = grounded(T_reset)
        s, after = grounded(shift @ T_reset)
        np.testing.assert_allclose(after.g, shift @ before.g, atol=1e-9)
        np.testing.assert_allclose(after.joint.origin, before.joint.origin + shift[:3, 3],
                                   atol=1e-9)  # fmt: skip
        assert d.applicable(s, a)
        assert status_of(d.step(s, a, np.random.default_rng(0)).state.key) != "not_applicable"
    finally:
        rw.restore(before_test)
        d.environment.condition(belief)
    T_reset = np.eye(4)
    T_now = T_reset.copy()
    T_now[:3, 3] = [UNCHANGED / 2, 0.0, 0.0]
    assert cabinet_frame(T_now, T_reset) is T_reset
    T_now[:3, 3] = [0.0, 2 * UNCHANGED, 0.0]
    assert cabinet_frame(T_now, T_reset) is T_now


def test_a_catalogued_part_stands_for_the_true_part_nearest_it_both_ways(shut_episode, monkeypatch):
    """A true part is the counterpart of the catalogued part nearest its handle, up to
    MATCH_RADIUS away (a bar's handle named 6-12 cm from the bar's centre), not of a
    second catalogued part farther from it, and of none beyond MATCH_RADIUS."""
    d, _, _ = shut_episode
    env, handles = d.environment, d.real.handles
    points = np.array([p.point for p in d.parts])
    k, link = next((k, v) for k in range(len(d.parts)) if (v := env.counterpart(k)) is not None)
    others = np.delete(points, k, axis=0)
    away = points[k] - others[np.argmin(np.linalg.norm(others - points[k], axis=1))]
    away /= np.linalg.norm(away)
    for off, expected in ((0.08, link), (MATCH_RADIUS + 0.01, None)):
        monkeypatch.setitem(handles, link, points[k] + off * away)
        assert env.counterpart(k) == expected, off
    # The true handle 1 cm from another catalogued part: that one takes it, not k.
    j = int(np.argmin([np.inf if i == k else np.linalg.norm(p - points[k]) for i, p in
                       enumerate(points)]))  # fmt: skip
    toward = (points[k] - points[j]) / np.linalg.norm(points[k] - points[j])
    for other, h in list(handles.items()):  # j's own true part may be read nearer still
        if other != link and np.linalg.norm(h - points[j]) < 0.011:
            monkeypatch.setitem(handles, other, h + 1.0)
    monkeypatch.setitem(handles, link, points[j] + 0.01 * toward)
    assert env.counterpart(j) == link and env.counterpart(k) != link


def test_a_part_the_real_robot_sees_shut_is_shut_in_every_particle(shut_episode):
    """A drawer every particle holds open (as after a twin's opening) that stands shut in
    the real cabinet (as after an arm pushed it shut) is shut in every particle after
    conditioning; a particle's part where the real one stands open is moved along its
    own joint as far as the real handle is out (a drawer along its axis, a door about
    its hinge: the camera shows where a front stands, not which way it opens)."""
    d, s0, belief = shut_episode
    rng = np.random.default_rng(0)
    real = _real_step(d, s0, ManipAction("Pick", grasp="top"), rng)
    moved = [d.step(s, ManipAction("Pick", grasp="top"), rng).state for s in belief.states]
    opened = []
    for s in moved:
        tw = d.worlds.twins[s.origin]
        tw.restore(s.sim)
        tw.world.set_parts({p.joint: p.upper for p in tw.world.scene.cabinet_spec.movable_parts})
        opened.append(ManipState(s.origin, tw.snapshot(), s.t, s.last))
    rw = d.real.world
    rw.restore(real.state.sim)
    links = {k: d.environment.counterpart(k) for k in range(len(d.parts))}
    links = {k: v for k, v in links.items() if v is not None}
    assert len(set(links.values())) >= 2, links
    left_open = next(iter(links.values()))
    rw.set_parts({rw.scene.cabinet_spec.part(left_open).joint: 0.1})
    real_open = rw.scene.cabinet_spec.part(left_open)
    try:
        _, out = d.environment.fronts()
        conditioned = d.environment.condition(type(belief)(opened, belief.weights, belief.origin))
        for s in conditioned.states:
            tw = d.worlds.twins[s.origin]
            tw.restore(s.sim)
            spec, qs = tw.world.scene.cabinet_spec, tw.world.part_positions()
            for k, link in links.items():
                own = d.parts[k].links[s.origin]
                if own is None:
                    continue
                p = spec.part(own)
                q = qs[tw.world.scene.cabinet_prefix + p.joint]
                if link != left_open:
                    assert q == pytest.approx(0.0), (k, own)
                    continue
                R = tw.world.cabinet_pose()[:3, :3]
                local = R.T @ out[k].offset
                seen = local @ p.axis if p.joint_type == "prismatic" else swing(p, local)
                turn = out[k].turn
                if turn is not None and abs((R.T @ turn[0]) @ p.axis) >= SAME_HINGE:
                    seen = 0.1 * np.sign((R.T @ turn[0]) @ p.axis)  # the front's own angle
                assert q == pytest.approx(np.clip(seen, p.lower, p.upper), abs=1e-9), (k, own)
                if p.joint_type == real_open.joint_type == "prismatic":  # to the axes' tilt
                    assert q == pytest.approx(min(0.1, p.upper), abs=0.005), (k, own)
    finally:
        rw.restore(s0.sim)
        d.environment.condition(belief)


def test_a_part_the_real_front_passed_the_limit_of_gets_the_limit_the_front_showed(
    shut_episode,
):
    """A real front seen beyond a particle's limit moves that limit to the front (up
    to the longest the generator gives such a part): the particle keeps its weight, its
    twin is rebuilt with the new limit, its part stands where the front does, and the
    outcomes simulated under the old limit are dropped. A front short of every limit
    changes no particle."""
    d, s0, belief = shut_episode
    w, rw = d.worlds, d.real.world
    rw.restore(s0.sim)
    k, i, link = next(
        (k, s.origin, link)
        for k, part in enumerate(d.parts)
        for s in belief.states
        if (link := part.links[s.origin]) is not None
        and w.particles[s.origin].spec.part(link).joint_type == "prismatic"
    )
    p = w.particles[i].spec.part(link)
    R = (rw.cabinet_pose() @ np.linalg.inv(rw.scene.T_world_cabinet) @ w.pose(i))[:3, :3]
    short = {k: Front(R @ (0.5 * p.upper * np.asarray(p.axis)))}
    spec = w.particles[i].spec
    assert passed_limits(seen_positions(d.parts, i, short, spec, R), spec) == {}
    far = p.upper + 0.05
    fronts = {k: Front(R @ (far * np.asarray(p.axis)))}
    assert passed_limits(seen_positions(d.parts, i, fronts, spec, R), spec) == {
        link: pytest.approx(min(far, longest_limit(p)))
    }
    d.step(belief.states[0], ManipAction("Pick", grasp="top"), np.random.default_rng(0))
    assert len(w.outcomes) > 0
    twin = w.twins[i]
    conditioned = condition(belief, rw, w, d.parts, [], fronts)
    assert w.twins[i] is not twin
    assert not any(key[0] == i or key[2].part == k for key in w.outcomes)
    np.testing.assert_array_equal(conditioned.weights, belief.weights)
    wide = w.particles[i].spec.part(link)
    assert wide.upper == pytest.approx(min(far, longest_limit(p)))
    assert wide.upper > p.upper
    m = w.twins[i].world.model
    assert m.jnt_range[m.joint(w.twins[i].world.scene.cabinet_prefix + p.joint).id][1] == (
        pytest.approx(wide.upper)
    )
    for s in conditioned.states:
        if s.origin == i:
            w.twins[i].restore(s.sim)
            assert position(w.twins[i].world, p.joint) == pytest.approx(wide.upper, abs=1e-6)
    assert longest_limit(p) == pytest.approx(p.interior_size[0])


def test_a_drawer_whose_real_opening_met_its_end_gets_its_limit_where_the_front_stopped(
    shut_episode,
):
    """A real opening that met its part's end short of a particle's drawer limit moves
    that limit to where the front stands (the particle keeps its weight, its twin is
    rebuilt, its drawer stands at the new limit); a front that met no end, a front
    standing shut, and a door are left alone."""
    d, s0, belief = shut_episode
    w, rw = d.worlds, d.real.world
    rw.restore(s0.sim)
    kinds = {}
    for k, part in enumerate(d.parts):
        for s in belief.states:
            link = part.links[s.origin]
            if link is not None:
                kind = w.particles[s.origin].spec.part(link).joint_type
                kinds.setdefault(kind, (k, s.origin, link))
    k, i, link = kinds["prismatic"]
    spec = w.particles[i].spec
    p = spec.part(link)
    half = 0.5 * p.upper
    assert ended_limits({link: half}, spec, {link}) == {link: pytest.approx(half)}
    assert ended_limits({link: half}, spec, set()) == {}
    assert ended_limits({link: 0.005}, spec, {link}) == {}
    assert ended_limits({link: p.upper}, spec, {link}) == {}
    if "revolute" in kinds:
        _, j, door = kinds["revolute"]
        dspec = w.particles[j].spec
        assert ended_limits({door: 0.3 * dspec.part(door).upper}, dspec, {door}) == {}
    R = (rw.cabinet_pose() @ np.linalg.inv(rw.scene.T_world_cabinet) @ w.pose(i))[:3, :3]
    fronts = {k: Front(R @ (half * np.asarray(p.axis)))}
    twin = w.twins[i]
    conditioned = condition(belief, rw, w, d.parts, [], fronts, ended=[k])
    assert w.twins[i] is not twin
    np.testing.assert_array_equal(conditioned.weights, belief.weights)
    assert w.particles[i].spec.part(link).upper == pytest.approx(half, abs=1e-6)
    m = w.twins[i].world.model
    rng_ = m.jnt_range[m.joint(w.twins[i].world.scene.cabinet_prefix + p.joint).id]
    assert rng_[1] == pytest.approx(half, abs=1e-6)
    for s in conditioned.states:
        if s.origin == i:
            w.twins[i].restore(s.sim)
            assert position(w.twins[i].world, p.joint) == pytest.approx(half, abs=1e-6)


def test_a_new_limit_drops_what_was_simulated_under_the_old_one_and_keeps_the_rest(
    shut_episode,
):
    """:meth:`.ParticleWorlds.set_uppers` drops the particle's own cached outcomes,
    start checks and relevances, and every particle's outcomes and start checks of
    actions on the part whose limit moved (an opening's travel is the longest any
    particle holds); every other entry stays."""
    d, _, _ = shut_episode
    w = d.worlds
    i, j = 0, 1
    k = next(n for n, c in enumerate(d.parts) if c.links[i] is not None)
    link = d.parts[k].links[i]
    other = next(n for n in range(len(d.parts)) if n != k)
    opening = {n: ManipAction("OpenDrawer", n, 0) for n in (k, other)}
    pick = ManipAction("Pick", grasp="top")
    for cache in (w.outcomes, w.can_start):
        for key in [(i, b"s", pick, ()), (j, b"s", pick, ()), (j, b"s", opening[k], ()),
                    (j, b"s", opening[other], ())]:  # fmt: skip
            cache.store(key, "simulated")
    for key in [(i, b"s"), (j, b"s")]:
        w.relevance.store(key, "relevance")
    upper = w.particles[i].spec.part(link).upper
    w.set_uppers(i, {link: upper}, [k])
    for cache in (w.outcomes, w.can_start):
        assert (j, b"s", pick, ()) in cache and (j, b"s", opening[other], ()) in cache
        assert (i, b"s", pick, ()) not in cache and (j, b"s", opening[k], ()) not in cache
    assert (j, b"s") in w.relevance and (i, b"s") not in w.relevance


def test_a_turn_about_a_hinge_is_read_back_from_the_handles_offset():
    """:func:`~strug_manip.domains.manipulation.conditioning.swing` recovers the angle
    of a door, a flap or a drop-down flap from how far its handle moved; a drawer's
    offset along its axis is its travel."""
    parts = [p for seed in range(12) for p in generate_cabinet(seed).movable_parts
             if p.handle_pos is not None]  # fmt: skip
    hinges = {p.hinge for p in parts if p.joint_type == "revolute"}
    assert {"left", "right"} <= hinges and hinges & {"top", "bottom"}, hinges
    for p in parts:
        for q in (0.05, 0.15, p.upper):
            d = p.handle_at(q) - p.handle_at(0.0)
            seen = d @ p.axis if p.joint_type == "prismatic" else swing(p, d)
            assert seen == pytest.approx(q, abs=1e-9), (p.link, p.hinge, q)


def _standing_front(z: float, depth: float = 0.4) -> np.ndarray:
    """A front frame as the scene's cabinet table has it (facing the robot), its
    bottom ``z`` high [m]."""
    T = cabinet_pose(depth)
    F = np.eye(4)
    F[:3, :3] = T[:3, :3]
    F[:3, 3] = T[:3, :3] @ [depth / 2, 0.0, 0.0] + T[:3, 3]
    F[2, 3] = z
    return F


def test_a_perceived_cabinet_stands_on_the_table_with_its_parts_where_they_were_seen():
    from strug_manip.objects.assembly import CabinetModel, PartModel, on_stand

    drawer = PartModel("drawer", (-0.2, 0.2, 0.10, 0.25), np.array([1.0, 0.0, 0.0]),
                       np.array([0.0, 0.0, 0.175]), upper=0.3, handle_pos=np.array(
                           [0.02, 0.0, 0.2]))  # fmt: skip
    seen = CabinetModel(0.6, 0.8, 0.4, (drawer,), _standing_front(0.493))
    stood = on_stand(seen, 0.5)
    assert stood.T_world_front[2, 3] == pytest.approx(0.5)

    def world_z(m, k):  # the drawer's bottom (k=2) or top (k=3) in the world
        return float((m.T_world_front @ [0.0, 0.0, m.parts[0].rect[k], 1.0])[2])

    for k in (2, 3):
        assert world_z(stood, k) == pytest.approx(world_z(seen, k))
    for name in ("origin", "handle_pos"):
        before = seen.T_world_front @ [*getattr(seen.parts[0], name), 1.0]
        after = stood.T_world_front @ [*getattr(stood.parts[0], name), 1.0]
        assert np.allclose(before, after)
    assert stood.height + 0.5 == pytest.approx(seen.height + 0.493)  # the top stays too
    assert on_stand(stood, 0.5) is stood


def test_the_open_cell_keeps_its_measured_height_under_the_board_added_above_it():
    from strug_manip.domains.manipulation.belief import Particle, open_cell, with_open_cell
    from strug_manip.objects.assembly import CabinetModel, assemble

    F = _standing_front(0.5)
    model = CabinetModel(0.6, 0.8, 0.4, (), F)
    rng = np.random.default_rng(0)

    def slab(y, z, n=400):  # a board's front edge, in the front frame, to the world
        P = np.column_stack([rng.uniform(-0.01, 0.0, n), rng.uniform(*y, n), rng.uniform(*z, n)])
        return P @ F[:3, :3].T + F[:3, 3]

    cloud = np.concatenate([slab((-0.28, 0.28), (0.292, 0.300)),
                            slab((-0.28, 0.28), (0.420, 0.428))])  # fmt: skip
    point = F[:3, :3] @ [0.0, 0.0, 0.36] + F[:3, 3]
    spec, q = assemble(model, cabinet_pose(model.depth))
    cell = open_cell(model, point, [cloud])
    grown = with_open_cell(Particle(model, spec, q, (), 0), point, [cloud])
    assert len(grown.model.parts) == 2  # the cell and the space above it
    # No carcass board inside the opening: floor (0.300) to ceiling (0.420).
    T_wo = cabinet_pose(0.4)
    floor = float((F @ [0, 0, cell.rect[2] + 0.008, 1])[2])
    ceiling = float((F @ [0, 0, cell.rect[3], 1])[2])
    assert ceiling - floor == pytest.approx(0.12, abs=2e-3)
    for g in grown.spec.body_geoms:
        if g.name in ("back", "side_left", "side_right"):
            continue
        c = T_wo[:3, :3] @ np.asarray(g.pos) + T_wo[:3, 3]
        lo, hi = c[2] - g.size[2] / 2, c[2] + g.size[2] / 2
        across = abs(c[1]) < 0.25
        assert not (across and lo < ceiling - 1e-6 and hi > floor + 1e-6), (g.name, lo, hi)


def test_the_beliefs_entropy_counts_model_classes_not_particles(drawer_episode):
    """Every particle is a distinct state; the entropy Active Learning and Entropy
    Regularized see is over the particles' kinematic hypotheses per catalogued part."""
    from planners.entropy import state_entropy

    d, _, belief = drawer_episode
    mass: dict = {}
    for s, w in zip(belief.states, belief.weights / belief.weights.sum(), strict=True):
        key = d.entropy_key(s)
        assert len(key) == len(d.parts)
        for k, part in zip(key, d.parts, strict=True):
            assert k is None or k in part.hypotheses
        mass[key] = mass.get(key, 0.0) + w
    h = -sum(p * np.log(p) for p in mass.values())
    assert state_entropy(d, belief.states, belief.weights) == pytest.approx(h)
    assert h < np.log(len(belief.states)) - 1e-9 or len(mass) == len(belief.states)


def test_a_drawn_cabinet_without_a_target_gives_way_to_the_next_draw(monkeypatch):
    """A drawn cabinet with no part the robot opens is replaced by the next draw (the
    same seed, the same replacement); a cabinet the user chose raises."""
    from planners.errors import ConfigError

    def first_has_none(d):
        calls = []

        def choose(world, *args):
            calls.append(world.config.cabinet_seed)
            if len(calls) == 1:
                raise ConfigError("no part the robot can open")
            return "link_1", np.zeros(3)

        monkeypatch.setattr(episode_setup, "choose_target", choose)
        return calls

    drawn = []
    for _ in range(2):
        d = make_domain("opendrawer")
        calls = first_has_none(d)
        _start(d, np.random.default_rng(5))
        assert len(calls) == 2 and d.real.seed == calls[1]
        drawn.append(calls)
        d.close()
    assert drawn[0] == drawn[1]
    chosen = make_domain("opendrawer", cabinet_seed=SEED)
    first_has_none(chosen)
    with pytest.raises(ConfigError, match="no part"):
        _start(chosen, np.random.default_rng(5))


def test_a_believed_flap_has_a_friction_stay_and_stays_shut():
    """A bottom-hinged flap that perception sees 0.15 rad open (a few degrees past
    its balance over the hinge): without a stay it falls open under its own weight
    within two seconds; with the generator's
    stay (``PartModel.stay``) it holds, and its friction is the stay's multiple of its
    gravity torque when horizontal."""
    import mujoco

    from strug_manip.objects.assembly import CabinetModel, PartModel, assemble
    from strug_manip.world.sim import ManipulationWorld

    axis = np.array([0.0, 1.0, 0.0])
    rect = (-0.25, 0.25, 0.05, 0.40)

    def fall(stay: float | None) -> tuple[float, float]:
        flap = PartModel("door", rect, axis, np.array([0.0, 0.0, 0.052]), "bottom", 1.4,
                         q=0.15, damping=0.1, friction=0.1, stay=stay)  # fmt: skip
        spec, q = assemble(
            CabinetModel(0.6, 0.5, 0.4, (flap,), _standing_front(0.5)), cabinet_pose(0.4)
        )
        part = spec.movable_parts[0]
        w = ManipulationWorld.from_cabinet_spec(spec)
        try:
            w.reset()
            joint = w.scene.cabinet_prefix + part.joint
            w.set_parts({joint: q[part.joint]})
            for _ in range(round(2.0 / w.model.opt.timestep)):
                mujoco.mj_step(w.model, w.data)
            return abs(w.part_positions()[joint] - q[part.joint]), part.friction
        finally:
            w.close()

    fell, _ = fall(None)
    held, friction = fall(1.5)
    assert fell > 0.5 and held < 0.02, (fell, held)
    assert friction > 10 * 0.1
    with pytest.raises(ConfigError, match="stay"):
        PartModel("drawer", rect, np.array([1.0, 0.0, 0.0]), np.zeros(3), upper=0.3, stay=1.5)


def test_a_cloud_of_an_unchanged_cabinet_is_weighed_once(drawer_episode):
    """The first real cloud is news; after a step that moved nothing (a Pick with the
    object in hand is not applicable) the cloud shows the same cabinet and the belief
    update does not weigh the same misfit again (nor the key: the step stopped before
    anything moved)."""
    d, s0, belief = drawer_episode
    rng = np.random.default_rng(0)
    pick = ManipAction("Pick", grasp="top")
    try:
        d.real.weighed = b""
        first = _real_step(d, s0, pick, rng)
        again = _real_step(d, first.state, pick, rng)
        assert first.obs.news and not again.obs.news
        assert "not_applicable" in again.obs.summary
        nxt = [d.step(s, pick, rng).state for s in belief.states[:4]]
        keys_only = ManipObservation(first.obs.key, None, "")
        np.testing.assert_array_equal(d.obs_loglik_many(again.obs, nxt, pick), np.zeros(4))
        assert not np.allclose(d.obs_loglik_many(first.obs, nxt, pick),
                               d.obs_loglik_many(keys_only, nxt, pick))  # fmt: skip
    finally:
        d.real.world.restore(s0.sim)
        d.real.weighed = b""


def test_particles_take_the_object_back_when_the_real_hand_still_holds_it(drawer_episode):
    """After a real step that leaves the object in the hand, a particle whose twin
    ended empty-handed gets the object into its hand, in the real grasp."""
    d, s0, belief = drawer_episode
    rng = np.random.default_rng(0)
    try:
        real = _real_step(d, s0, ManipAction("Pick", grasp="top"), rng)
        assert real.obs.key[1] == 1.0, real.obs.summary
        rw = d.real.world
        T_go = np.linalg.inv(rw.site_pose(GRIPPER_SITE)) @ rw.object_pose()
        empty = [d.step(s, ManipAction("Place", 0), rng).state for s in belief.states[:3]]
        assert not any(d._holding(s) for s in empty)  # nothing held, nothing placed
        conditioned = d.environment.condition(type(belief)(empty, np.ones(3) / 3, np.arange(3)))
        for s in conditioned.states:
            assert d._holding(s)
            tw = d.worlds.twins[s.origin]
            tw.restore(s.sim)
            T = np.linalg.inv(tw.world.site_pose(GRIPPER_SITE)) @ tw.world.object_pose()
            np.testing.assert_allclose(T, T_go, atol=1e-6)
    finally:
        d.real.world.restore(s0.sim)
        d.real.weighed = b""
        d.environment.condition(belief)


def test_a_drawer_too_narrow_for_its_box_is_refused():
    """A cell 3.5 cm wide leaves a drawer's walls and clearances no inside (its box's
    back board would be of negative width): the model refuses it, and the belief never
    samples one (``assembly.drawer_fits``)."""
    from strug_manip.objects.assembly import PartModel, drawer_fits

    assert not drawer_fits((0.0, 0.035, 0.0, 0.2)) and drawer_fits((0.0, 0.3, 0.0, 0.2))
    with pytest.raises(ConfigError, match="drawer's box"):
        PartModel("drawer", (0.0, 0.035, 0.0, 0.2), np.array([1.0, 0.0, 0.0]),
                  np.zeros(3), upper=0.2)  # fmt: skip


def test_actions_that_cannot_start_are_not_applicable_and_the_twin_agrees(drawer_episode):
    """One hand: with nothing held no Place applies, with the object held only Place
    does, and the twin ends each refused action not_applicable; an opened drawer's
    opening no longer applies while the other parts' still do."""
    d, _, belief = drawer_episode
    rng = np.random.default_rng(0)
    s = belief.states[0]
    acts = list(d.action_space().discretized)
    assert not any(d.applicable(s, a) for a in acts if a.skill == "Place")
    pick = ManipAction("Pick", grasp="top")
    assert d.applicable(s, pick)
    held = d.step(s, pick, rng).state
    assert d._holding(held)
    for a in acts:
        if a.skill != "Place":
            assert not d.applicable(held, a), a
            assert "not_applicable" in d.step(held, a, rng).obs.summary
    openings = [a for a in acts if a.skill == "OpenDrawer" and d.applicable(s, a)]
    for a in openings:
        step = d.step(s, a, rng)
        if step.obs.summary.startswith("OpenDrawer: ok"):
            break
    else:
        pytest.fail(f"no drawer of particle {s.origin} opens in its twin")
    assert not d._can_start(step.state, a)
    others = [b for b in openings if b.part != a.part]
    assert others and all(d._can_start(step.state, b) for b in others)


def test_an_action_that_failed_on_the_real_robot_is_refused_until_a_step_ends_ok(
    drawer_episode,
):
    """A real step that failed in a way that repeats itself (here a Place with nothing
    held) is refused at the root, whatever the twins say; an opening only while it
    follows the particle it failed with; a refusal stands only while the cabinet and
    the hold are as they were when the action failed (after the Pick the hand holds the
    object: the Place is offered again). A collision is not refused: the next attempt
    plans a new path."""
    assert "collision" not in REPEATS_ITSELF and "grasp_lost" in REPEATS_ITSELF
    d, s0, belief = drawer_episode
    rng = np.random.default_rng(0)
    place, pick = ManipAction("Place", 0), ManipAction("Pick", grasp="top")
    opening = next(a for a in d.action_space().discretized if a.skill == "OpenDrawer")
    old, n0 = d.root.reps, len(d.real.outcomes)
    try:
        failed = _real_step(d, s0, place, rng)
        assert "not_applicable" in failed.obs.summary
        assert d.real.refused == {(place, -1)} and d.real.now == 1
        root = dataclasses.replace(belief.states[0], t=1)
        assert not d.applicable(root, place)
        d.root = dataclasses.replace(d.root, refused=d.root.refused | {(pick, -1)})
        # (as if the real Pick had found no IK)
        assert not d.applicable(root, pick)
        assert d.applicable(dataclasses.replace(root, t=2), pick)  # deeper: the twins
        slipped = (opening, d.root.rep(opening))  # as if it had slipped
        d.root = dataclasses.replace(d.root, refused=d.root.refused | {slipped})
        assert not d.applicable(root, opening)
        k, h = opening.part, opening.hypothesis
        _with_reps(d, tuple(tuple(r + 1 if (k2, h2) == (k, h) else r
                                  for h2, r in enumerate(row))
                            for k2, row in enumerate(old)))  # fmt: skip
        assert d.applicable(root, opening)  # another particle's joint: offered again
        for key in ((pick, -1), (opening, old[k][h])):
            d.real.refusals.pop(key, None)
        done = _real_step(d, failed.state, pick, rng)
        assert done.obs.key[1] == 1.0, done.obs.summary
        assert not d.real.refused and d.real.now == 2
        _real_step(d, done.state, ManipAction("Place", TABLE), rng)
        assert d.report()["real"][-2] == "Pick ok"
        assert d.report()["real"][-1].startswith("Place(table) ")  # told from a Place
    finally:
        del d.real.outcomes[n0:], d.real.labels[n0:]
        _with_reps(d, old)
        d.real.world.restore(s0.sim)
        d.real.weighed = b""
        d.real.refusals.clear()
        d.real.now = 0
        d.environment.condition(belief)


def test_a_real_step_that_stopped_before_anything_moved_is_no_evidence(drawer_episode):
    """The full robot finds its IK, route and arm motions before it moves, in the model
    it plans against: a stop then (no motion plan in time, no IK) weighs nothing in
    the real belief, and every particle stays as it was, its twin's opening undone."""
    assert {"no_motion_plan", "ik_infeasible"} <= set(BEFORE_MOTION)
    d, _, belief = drawer_episode
    d.environment.condition(belief)
    rng = np.random.default_rng(0)

    def joints(s):
        tw = d.worlds.twins[s.origin]
        tw.restore(s.sim)
        return np.array(list(tw.world.part_positions().values()))

    # An opening the twins disagree on (some open a part, some do not), so that a
    # real status that is evidence moves the weights.
    for opening in (a for a in d.action_space().discretized if a.skill == "OpenDrawer"):
        stepped = [d.step(s, opening, rng).state for s in belief.states]
        opened = [not np.allclose(joints(a), joints(b), atol=1e-3)
                  for a, b in zip(belief.states, stepped, strict=True)]  # fmt: skip
        if 0 < sum(opened) < len(opened):
            break
    else:
        raise AssertionError("no opening that some twins complete and others do not")
    cloud = np.zeros((4, 3))  # a real observation; the cabinet unchanged (news False)
    for status, evidence in (("no_motion_plan", False), ("ik_infeasible", False), ("ok", True)):
        obs = ManipObservation(observation_key(status, False, np.zeros(3)), cloud, "", False)
        assert (np.ptp(d.obs_loglik_many(obs, stepped, opening)) > 0) == evidence, status
    try:
        # As they were, given what the robot knows for certain (a part the real cabinet
        # holds shut is shut in every particle, whatever its perceived opening).
        d.real.now = 1
        before = [ManipState(s.origin, s.sim, 1, s.last) for s in belief.states]
        known = d.environment.condition(ParticleBelief(before, belief.weights, belief.origin))
        d.real.still = True
        post = d.environment.condition(ParticleBelief(stepped, belief.weights, belief.origin))
        for was, after in zip(known.states, post.states, strict=True):
            assert after.t == 1 and np.allclose(joints(was), joints(after), atol=1e-6)
        undone = [not np.allclose(joints(a), joints(b), atol=1e-3)
                  for a, b in zip(stepped, post.states, strict=True)]  # fmt: skip
        assert sum(undone) >= sum(opened)  # every twin's opening undone
    finally:
        d.real.still, d.real.now = False, 0
        d.environment.condition(belief)


def test_the_object_picked_too_early_goes_back_onto_the_table(drawer_episode):
    """One hand: an object picked before the target is open would be a dead end.
    Place(table) puts it back where it was picked, empty-handed and not done."""
    d, _, belief = drawer_episode
    rng = np.random.default_rng(0)
    back = ManipAction("Place", TABLE)
    assert back in d.action_space().discretized
    assert d.action_space().name(back) == "Place(table)"
    s = belief.states[1]
    assert not d.applicable(s, back)
    held = d.step(s, ManipAction("Pick", grasp="top"), rng).state
    assert d.applicable(held, back)
    down = d.step(held, back, rng)
    assert not d._holding(down.state) and down.reward == 0.0 and not down.done, down.obs.summary
    tw = d.worlds.twins[s.origin]
    tw.restore(down.state.sim)
    assert np.linalg.norm(tw.world.object_pose()[:3, 3] - d.view.home[:3, 3]) < 0.03
    assert d.applicable(down.state, ManipAction("Pick", grasp="top"))


def test_an_opening_follows_the_likeliest_particle_of_its_hypothesis(drawer_episode):
    """An opening's grasp and joint are the likeliest holder's of its hypothesis (the
    first holder while the belief is uniform), a hypothesis whose holders all lost
    their weight keeps its last one, and the twins' outcomes are cached per holder."""
    d, _, belief = drawer_episode
    n = len(d.worlds)
    found = [(k, h, [i for i in range(n) if d.cat.classes[i][k] == kind])
             for k, part in enumerate(d.parts) for h, kind in enumerate(part.hypotheses)
             if kind != "shelf"]  # fmt: skip
    k, h, held = next(f for f in found if len(f[2]) >= 2)
    assert representatives(d.cat, belief, d.root.reps)[k][h] == held[0] == d.root.reps[k][h]
    other = held[-1]
    w = np.array([1.0 if s.origin == other else 0.0 for s in belief.states])
    reps = representatives(d.cat, ParticleBelief(belief.states, w, belief.origin), d.root.reps)
    assert reps[k][h] == other
    lost = [f for f in found if other not in f[2]]
    assert all(reps[k2][h2] == d.root.reps[k2][h2] for k2, h2, _ in lost)
    opening = "OpenDrawer" if d.parts[k].hypotheses[h] == "drawer" else "OpenDoor"
    a, s, rng = ManipAction(opening, k, h), belief.states[0], np.random.default_rng(0)
    old = d.root.reps
    try:
        d.step(s, a, rng)
        joint = d.skills(s.origin, a, s.sim)[0][0].joint
        _with_reps(d, reps)
        misses = d.worlds.outcomes.misses
        d.step(s, a, rng)
        assert d.worlds.outcomes.misses == misses + 1
        moved = d.skills(s.origin, a, s.sim)[0][0].joint
        spec = d.worlds.particles[other].spec
        q = d.worlds.particles[other].q
        part = spec.part(d.parts[k].links[other])
        want = BelievedJoint.of_part(part, q.get(part.joint, 0.0), d.worlds.pose(other))
        np.testing.assert_allclose(moved.axis, want.axis)
        np.testing.assert_allclose(moved.origin, want.origin)
        assert not (np.allclose(moved.axis, joint.axis) and np.allclose(moved.origin, joint.origin))
    finally:
        _with_reps(d, old)


def _undo_real_steps(d, s0, belief, n0: int) -> None:
    """The real episode of ``d`` back at ``s0`` with ``belief``, its outcomes after the
    first ``n0`` dropped."""
    del d.real.outcomes[n0:], d.real.labels[n0:]
    d.real.world.restore(s0.sim)
    d.real.weighed = b""
    d.real.refusals.clear()
    d.real.now, d.real.still = 0, False
    d.environment.condition(belief)


def test_a_real_opening_that_cannot_start_is_planned_in_the_next_holder(
    drawer_episode, monkeypatch
):
    """The full robot plans an opening in its hypothesis's representative's model; when
    that plan cannot start (nothing moves: no evidence, a step lost), it plans in the
    next likeliest holders' models before it spends the step."""
    d, s0, belief = drawer_episode
    d.environment.condition(belief)
    rng = np.random.default_rng(0)
    mass = d.cat.mass(belief)
    a, held = next(
        (ManipAction("OpenDrawer", k, h), d.cat.holders(mass, k, h))
        for k, part in enumerate(d.parts)
        for h, kind in enumerate(part.hypotheses)
        if kind == "drawer" and len(d.cat.holders(mass, k, h)) >= 3
    )
    rep = d.root.rep(a)
    assert [i for i, _ in d.environment.plan_models(a, rng)] == held[:PLAN_MODELS]
    assert list(d.root.plan_models(a)) == held[:PLAN_MODELS]
    assert held[0] == rep and PLAN_MODELS >= 2
    skills = d.skills

    # A twin plans in the same models in the same order while its plan cannot start:
    # one that stopped at the representative predicted a failure the real robot,
    # going on to the next model, never shows (OpenDoor episode 10016).
    asked = []

    def no_plan_anywhere(i, act, sim, holder=None):
        asked.append(holder)
        return [], None

    with monkeypatch.context() as m:
        m.setattr(d, "skills", no_plan_anywhere)
        twin = next(s for s in belief.states if s.origin == rep)
        d._simulate(twin.origin, twin.sim, a)  # the twin run itself, not the cache
    assert asked == held[:PLAN_MODELS]

    def no_plan_in_rep(i, act, sim, holder=None):
        return ([], None) if holder == rep else skills(i, act, sim, holder)

    monkeypatch.setattr(d, "skills", no_plan_in_rep)
    n0 = len(d.real.outcomes)
    try:
        step = _real_step(d, s0, a, rng)
        m = re.search(r"\[planned in model (\d+), after (\d) that could not start\]",
                      step.obs.summary)  # fmt: skip
        assert m, step.obs.summary
        assert int(m[1]) == held[int(m[2])] and int(m[2]) >= 1
        assert len(d.real.outcomes) == n0 + 1  # one step, whatever was planned
    finally:
        _undo_real_steps(d, s0, belief, n0)


def test_a_real_place_is_planned_in_the_likeliest_models_whose_twins_can(
    drawer_episode, monkeypatch
):
    """The full robot plans a Place into a part in up to PLAN_MODELS models, likeliest
    first, one state each, skipping the models whose twins cannot make it: the real
    hold is not the twins', and a place that could not start in the likeliest model
    ran in the next (OpenDoor episode 10153). Pick plans in one."""
    d, _, belief = drawer_episode
    d.environment.condition(belief)
    rng = np.random.default_rng(0)
    k = next(k for k, part in enumerate(d.parts) if sum(x is not None for x in part.links) >= 4)
    place = ManipAction("Place", k)
    order = [belief.states[j] for j in np.argsort(-belief.weights, kind="stable")]
    holders = list(dict.fromkeys(s.origin for s in order if d.parts[k].links[s.origin] is not None))
    cannot = holders[1]  # the second likeliest model's twins cannot place
    code = {True: float(STATUS_CODES["ik_infeasible"]), False: float(STATUS_CODES["ok"])}

    def step(s, a, rng):
        return SimpleNamespace(obs=SimpleNamespace(key=(code[s.origin == cannot],)))

    monkeypatch.setattr(d, "step", step)
    models = d.environment.plan_models(place, rng)
    want = [i for i in holders if i != cannot][:PLAN_MODELS]
    assert [i for i, _ in models] == want
    first = {i: next(s.sim for s in order if s.origin == i) for i in want}
    assert all(sim is first[i] for i, sim in models)  # each in its likeliest state
    pick = d.environment.plan_models(ManipAction("Pick", grasp="top"), rng)
    assert [i for i, _ in pick] == [next(s.origin for s in order if s.origin != cannot)]


def test_the_real_pick_routes_in_the_models_current_state(drawer_episode, monkeypatch):
    """The full robot's route from the cabinet to the table is planned with the parts
    where the model it plans in has them now (a door it opened stands in the way), not
    in the search's shared planning world of the closed cabinet (model 0 as
    perceived), through which the arm once swept an open door shut."""
    d, s0, belief = drawer_episode
    d.environment.condition(belief)
    rng = np.random.default_rng(0)
    pick = ManipAction("Pick", grasp="top")
    i, state = d.environment.likeliest(pick, rng)
    calls = []
    fetch = d.worlds.fetch
    monkeypatch.setattr(d.worlds, "fetch", lambda j, st=None: calls.append((j, st)) or fetch(j, st))
    n0 = len(d.real.outcomes)
    try:
        step = _real_step(d, s0, pick, rng)
        assert step.obs.key[1] == 1.0, step.obs.summary
        assert calls and calls[-1][0] == i and calls[-1][1] is state
    finally:
        _undo_real_steps(d, s0, belief, n0)


def test_the_real_handle_motion_is_measured_on_the_part_acted_on(drawer_episode):
    """A real opening's handle motion (the observation key) is measured on the real part
    the catalogued part was named from, however far it moves: an opened drawer (a door
    swung open) puts its handle nearer another part's start than its own, and the
    motion was once measured on that other part, which cost the particles that had
    predicted the opening right ~45 nats."""
    d, s0, _ = drawer_episode
    world, m = d.real.world, d.real.world.model
    spec = world.scene.cabinet_spec
    openings = {a.part: a for a in d.action_space().discretized if a.skill == "OpenDrawer"}
    acted = [d.environment.real_link(a.part) for a in openings.values()]
    assert len(set(acted)) >= 2, acted  # (perception may see a part twice)
    try:
        for a, link in zip(openings.values(), acted, strict=True):
            p = spec.part(link)
            before = handle_point(world, a, lambda a=a: d.environment.real_link(a.part))
            np.testing.assert_allclose(before, d.real.handles[link])
            world.data.qpos[m.jnt_qposadr[m.joint(world.scene.cabinet_prefix + p.joint).id]] = (
                p.upper
            )
            mujoco.mj_forward(m, world.data)
            moved = handle_point(world, a, lambda a=a: d.environment.real_link(a.part)) - before
            assert abs(np.linalg.norm(moved) - p.upper) < 1e-6, (link, moved, p.upper)
            world.restore(s0.sim)
    finally:
        world.restore(s0.sim)


def test_a_believed_knob_is_built_as_a_knob_and_grasped_pitched():
    """A part perception saw with a knob gets a knob, its tip ``KNOB_GRASP_INSET`` in
    front of the grasp point, and the knob's grasps: pitched ones too, which a bar at the same
    point does not offer (its pads would meet the front), and which a low drop-down
    flap needs. A bar follows the direction seen; an unknown style is refused."""
    from strug_manip.control import handle_grasps
    from strug_manip.control.grasps import knob_end
    from strug_manip.objects.assembly import CabinetModel, PartModel, assemble
    from strug_manip.objects.generator import KNOB_GRASP_INSET

    axis = np.array([0.0, -1.0, 0.0])
    rect = (-0.25, 0.25, 0.30, 0.50)
    seen = np.array([0.027, 0.0, 0.46])  # the knob's tip, as the camera sees it

    def part(handle: str, along: str | None = None):
        flap = PartModel("door", rect, axis, np.array([0.0, 0.0, 0.303]), "bottom", 1.4,
                         handle=handle, handle_pos=seen, stay=1.5,
                         handle_along=along)  # fmt: skip
        spec, _ = assemble(
            CabinetModel(0.6, 0.6, 0.4, (flap,), _standing_front(0.6)), cabinet_pose(0.4)
        )
        return spec.movable_parts[0]

    knob, bar = part("knob"), part("bar")
    assert knob.handle == "knob" and np.allclose(knob.handle_axis, [1.0, 0.0, 0.0], atol=1e-6)
    assert knob_end(knob) - knob.handle_pos[0] == pytest.approx(KNOB_GRASP_INSET, abs=1e-9)
    pitched = [g for g in handle_grasps(knob) if abs(g[2, 0]) > 0.1]
    assert len(pitched) >= 2 and not [g for g in handle_grasps(bar) if abs(g[2, 0]) > 0.1]
    assert abs(bar.handle_axis[1]) > 0.99 and abs(part("bar", "z").handle_axis[2]) > 0.99
    with pytest.raises(ConfigError, match="handle"):
        PartModel("door", rect, axis, np.zeros(3), "bottom", 1.4, handle="hook")


def test_an_action_without_a_motion_plan_twice_in_a_row_is_refused(world):
    """``no_motion_plan`` is tried again (another planner seed) but not a third time;
    a collision never refuses; a step that ends ok restarts the count but lifts no
    refusal: a refusal stands while the cabinet (every coordinate within UNCHANGED)
    and the hold are as they were when the action failed (a Place that could not
    start came back after each Place(table) and Pick, which move nothing of the
    cabinet), and stands again when they are back."""
    from strug_manip.domains.manipulation.real import NO_PLAN_TRIES, RealEpisode

    assert NO_PLAN_TRIES == 2
    world.reset()
    real = RealEpisode(world, 0, "link_1", np.zeros(3), [], [])
    place, pick = (ManipAction("Place", 0), -1), (ManipAction("Pick", grasp="top"), -1)
    real.settle(place, "no_motion_plan")
    assert not real.refused
    real.settle(pick, "collision")
    real.settle(pick, "collision")
    assert not real.refused
    real.settle(place, "no_motion_plan")
    assert real.refused == {place}
    real.settle(pick, "grasp_lost")
    assert real.refused == {place, pick}
    real.settle(pick, "ok")
    assert real.refused == {place, pick} and not real.unplanned  # nothing changed
    joint = next(iter(world.part_positions()))
    world.set_parts({joint: 0.5 * UNCHANGED})  # a drift: the same cabinet
    assert real.refused == {place, pick}
    world.set_parts({joint: 3 * UNCHANGED})  # a part moved: another cabinet
    assert not real.refused
    world.reset()
    assert real.refused == {place, pick}  # back as it was
    world.set_object_pose(world.site_pose(GRIPPER_SITE))  # the hand holds the object
    assert not real.refused
    world.reset()
    real.refusals.clear()
    real.settle(place, "no_motion_plan")
    assert not real.refused  # counted afresh after the ok
