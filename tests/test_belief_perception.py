"""From views to a belief: fusion, particles of complete cabinets, the point-cloud
likelihood (issue 10)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.stats

from perception.errors import BadInputError
from perception.fusion import PartHypothesis, fuse
from perception.inputs import check_view
from perception.likelihood import log_likelihood, quantile_hausdorff
from perception.parts import extract
from planners.errors import ConfigError
from strug_manip.domains.manipulation.belief import BeliefConfig, closed_handle, sample_particles
from strug_manip.objects import generator as gen
from strug_manip.objects.assembly import BAR, FRONT
from strug_manip.objects.partnet import cabinet_urdf
from strug_manip.world.perception_data import render_episode
from strug_manip.world.sim import ManipulationWorld

ROOT = Path(__file__).resolve().parents[1]
WEIGHTS = ROOT / "models" / "perception" / "articulation_net.pt"
sys.path.insert(0, str(ROOT / "tools"))
from eval_perception import evaluate_cabinet, oracle_output, summarise, type_unseen  # noqa: E402


def _oracle_fusion(views):
    return fuse(
        [
            extract(check_view(v.rgb, v.depth, v.T_world_camera, v.fovy), oracle_output(v))
            for v in views
        ]
    )


def test_geometry_from_perfect_maps_is_exact() -> None:
    """With perfect per-pixel maps, the fused joints are as good as the depth allows
    (cabinets with handles: a closed bare front's type is the prior's guess)."""
    from strug_manip.objects import generate_cabinet

    args = argparse.Namespace(views=4, dropout=0.0, noisy_runs=0, particles=30, style="plain")
    seeds = [
        s for s in range(3000, 3010) if any(p.handle != "none" for p in generate_cabinet(s).parts)
    ]
    for seed in seeds[:2]:
        r = evaluate_cabinet(seed, args, None, np.random.default_rng(0))
        assert r["complete"] and r["support"][0] == r["support"][1]
        assert all(e < 1.0 for _, e in r["axis"]), r["axis"]
        assert all(e < 0.02 for e in r["hinge"]), r["hinge"]


def test_unseen_types_are_closed_fronts_of_handle_less_cabinets() -> None:
    """The evaluation sets apart exactly the fronts whose type no view shows, and counts
    them inside ``joint_type``."""
    from strug_manip.objects import generate_cabinet

    bare = next(s for s in range(3000, 3100) if generate_cabinet(s).parts[0].handle == "none")
    handled = next(s for s in range(3000, 3100) if generate_cabinet(s).parts[0].handle == "bar")
    part, other = generate_cabinet(bare).parts[0], generate_cabinet(handled).parts[0]
    assert type_unseen(part, 0.0) and type_unseen(part, 0.02)
    assert not type_unseen(part, 0.3)  # open: the motion shows the joint
    assert not type_unseen(other, 0.0)  # a handle's place shows it
    args = argparse.Namespace(views=2, dropout=0.0, noisy_runs=0, particles=10, style="plain")
    res = evaluate_cabinet(bare, args, None, np.random.default_rng(0))
    out, _ = summarise([res])
    assert out["joint_type_unseen"]["n"] >= 1  # seed 3001 shows closed bare fronts
    assert out["joint_type_unseen"]["ok"] <= out["joint_type_unseen"]["n"]
    assert out["joint_type_unseen"]["n"] <= out["joint_type"]["n"]


def test_a_closed_bare_front_is_typed_by_the_training_prior() -> None:
    """In a cabinet without handles, a closed front's drawer/door odds are the training
    prior's (``UNSEEN_SPLIT``), whatever the pixels say, so its type is the prior's mode."""
    from perception.joint_cues import UNSEEN_SPLIT
    from strug_manip.objects import generate_cabinet

    bare = next(s for s in range(3000, 3100) if generate_cabinet(s).parts[0].handle == "none")
    spec, checked = generate_cabinet(bare), 0
    for lv in render_episode(bare, 2):
        vp = extract(check_view(lv.rgb, lv.depth, lv.T_world_camera, lv.fovy), oracle_output(lv))
        pm = lv.part_map[::2, ::2]
        for k, part in enumerate(spec.parts):
            if not (part.kind in ("drawer", "door") and type_unseen(part, lv.q[k])):
                continue
            inst = max(vp.instances, key=lambda i: int((i.mask & (pm == k + 1)).sum()))
            p = inst.class_prob
            assert p[2] / p[1] == pytest.approx(UNSEEN_SPLIT[1] / UNSEEN_SPLIT[0])
            assert int(np.argmax(p)) == 2
            checked += 1
    assert checked >= 1


def test_particles_are_cabinets_the_world_compiles() -> None:
    fused = _oracle_fusion(render_episode(3000, 4))
    particles = sample_particles([fused], np.random.default_rng(0), BeliefConfig(particles=3))
    for p in particles:
        assert p.spec.parts and len(p.source) == len(p.spec.parts)
        world = ManipulationWorld.from_cabinet_spec(p.spec)
        try:
            world.reset(p.q)
            got = world.part_positions()
            for name, q in p.q.items():
                assert abs(got["cabinet/" + name] - q) < 1e-9
        finally:
            world.close()


def test_particles_reach_deeper_than_the_views_see_and_their_drawers_farther() -> None:
    """The views seldom see a carcass's back edge: each particle's depth is the seen
    depth plus a draw from ``depth_beyond_seen``, and its drawers' limits span the
    generator's travel share of the generator's box depths (which no view of a shut
    drawer shows); a range that is no range is refused, named."""
    fused = _oracle_fusion(render_episode(3000, 4))
    assert fused.front.depth_seen
    cfg = BeliefConfig(particles=200)
    particles = sample_particles([fused], np.random.default_rng(2), cfg)
    lo, hi = cfg.depth_beyond_seen
    depths = np.array([p.spec.depth for p in particles])
    assert np.all(depths >= fused.front.depth + lo - 1e-9)
    assert np.all(depths <= fused.front.depth + hi + 1e-9)
    assert np.ptp(depths) > 0.8 * (hi - lo)  # the draw spans the range
    shares = [
        part.upper / (p.spec.depth - FRONT - 0.01)
        for p in particles
        for part in p.spec.parts
        # (a drawer seen open has its limit past where it was seen, not drawn)
        if part.joint_type == "prismatic" and part.upper > p.q.get(part.joint, 0.0) + 0.011
    ]
    low = gen.DRAWER_TRAVEL_FRAC[0] * gen.DRAWER_DEPTH_FRAC[0]
    high = gen.DRAWER_TRAVEL_FRAC[1] * gen.DRAWER_DEPTH_FRAC[1]
    assert low - 1e-9 <= min(shares) < low + 0.05 and high - 0.05 < max(shares) <= high + 1e-9
    with pytest.raises(ConfigError, match="depth_beyond_seen"):
        BeliefConfig(depth_beyond_seen=(0.1, -0.1))


def test_belief_moves_keep_alternatives() -> None:
    """Flips, both hinge senses and splits appear among the particles."""
    fused = _oracle_fusion(render_episode(3000, 4))
    cfg = BeliefConfig(particles=200, split_base=0.3)
    particles = sample_particles([fused], np.random.default_rng(1), cfg)
    kinds = {(p.source[i], part.kind) for p in particles for i, part in enumerate(p.spec.parts)}
    drawer_hyps = {i for i, h in enumerate(fused.parts) if h.joint_type == "prismatic"}
    assert any((i, "door") in kinds for i in drawer_hyps)  # the class flip
    counts = [sum(s == i for s in p.source) for p in particles for i in drawer_hyps]
    assert max(counts) == 2  # a split: two parts from one hypothesis
    sizes = {len(p.spec.parts) for p in particles}
    assert len(sizes) > 1  # existence varies


@pytest.mark.skipif(not WEIGHTS.exists(), reason="no trained weights in models/perception")
def test_fused_hypotheses_and_particles_are_identical_for_the_same_seed() -> None:
    from perception.parts import Perceiver
    from strug_manip.domains.manipulation.belief import perceive_cabinet

    views = render_episode(1001, 4)
    frames = [(v.rgb, v.depth, v.T_world_camera, v.fovy) for v in views]
    cfg = BeliefConfig(particles=8, noisy_runs=1)

    def run(seed: int):
        rng = np.random.default_rng(seed)
        fused = perceive_cabinet(frames, Perceiver(), rng, cfg)
        return fused, sample_particles(fused, rng, cfg)

    (fa, pa), (fb, pb), (_, pc) = run(5), run(5), run(6)
    for a, b in zip(fa, fb, strict=True):
        assert np.array_equal(a.front.T_world_front, b.front.T_world_front)
        assert len(a.parts) == len(b.parts)
        for ha, hb in zip(a.parts, b.parts, strict=True):
            for name in ("rect", "class_prob", "hinge_prob", "door_rect", "door_q"):
                assert np.array_equal(getattr(ha, name), getattr(hb, name)), name
            assert ha.existence == hb.existence
    assert [cabinet_urdf(p.spec) for p in pa] == [cabinet_urdf(p.spec) for p in pb]
    assert [p.q for p in pa] == [p.q for p in pb]
    assert [cabinet_urdf(p.spec) for p in pa] != [cabinet_urdf(p.spec) for p in pc]


def test_quantile_hausdorff_matches_its_definition() -> None:
    rng = np.random.default_rng(0)
    obs = rng.uniform(0, 1, (300, 3))
    preds = [rng.uniform(0, 1, (n, 3)) + off for n, off in ((200, 0.0), (250, 0.05), (150, 0.3))]
    got = quantile_hausdorff(obs, preds, quantile=0.9)
    from perception.likelihood import voxel_thin

    o = voxel_thin(obs)
    for g, p in zip(got, preds, strict=True):
        p = voxel_thin(p)
        d = np.linalg.norm(o[:, None] - p[None], axis=-1)
        a, b = np.sort(d.min(axis=1)), np.sort(d.min(axis=0))
        ref = max(a[int(0.9 * (len(a) - 1))], b[int(0.9 * (len(b) - 1))])
        assert abs(g - ref) < 1e-12
    assert got[0] < got[1] < got[2]
    ll = log_likelihood(obs, preds, quantile=0.9, nu=np.inf)
    np.testing.assert_allclose(ll, -0.5 * (got / 0.01) ** 2 - np.log(0.01 * np.sqrt(2 * np.pi)))
    assert np.argmax(ll) == 0
    t = log_likelihood(obs, preds, quantile=0.9, nu=4.0)
    np.testing.assert_allclose(t, scipy.stats.t.logpdf(got, df=4.0, scale=0.01))


def test_voxel_thinning_keeps_the_first_point_of_each_voxel_in_order() -> None:
    """One point per voxel, the first of the cloud's order, the kept ones in that order:
    as the row-wise definition (``np.unique(axis=0)`` of the voxel indices) gives,
    across signs, spans and repeated points; an empty cloud stays empty."""
    from perception.likelihood import VOXEL, voxel_thin

    rng = np.random.default_rng(5)
    for n in (1, 7, 2000):
        pts = rng.uniform(-1.5, 2.5, (n, 3)) * rng.uniform(0.05, 1.0, 3)
        pts = np.concatenate([pts, pts[::-3]])  # repeats, later: never kept
        keys = np.floor(pts / VOXEL).astype(np.int64)
        _, first = np.unique(keys, axis=0, return_index=True)
        np.testing.assert_array_equal(voxel_thin(pts), pts[np.sort(first)])
    assert voxel_thin(np.zeros((0, 3))).shape == (0, 3)


def test_the_likelihood_keeps_wrong_models_alive_when_none_fits() -> None:
    """Particles 4.5-13 cm off (a part perception got wrong in all of them): the
    Student-t spreads the weight over the near ones, where the Gaussian gives one
    particle all of it; the ranking is the same."""
    h = np.array([0.045, 0.055, 0.06, 0.065, 0.07, 0.13])
    obs = np.zeros((1, 3))
    preds = [np.array([[x, 0.0, 0.0]]) for x in h]

    def ess(ll: np.ndarray) -> float:
        w = np.exp(ll - ll.max())
        w /= w.sum()
        return float(1.0 / (w @ w))

    gauss, student = log_likelihood(obs, preds, nu=np.inf), log_likelihood(obs, preds)
    assert ess(gauss) < 1.2 < 3.0 < ess(student)
    assert list(np.argsort(-gauss)) == list(np.argsort(-student))
    with pytest.raises(BadInputError, match="nu must be"):
        log_likelihood(obs, preds, nu=0.0)


@pytest.mark.parametrize("seed", [3, 25])  # drawers; doors and a flap
def test_the_likelihood_ranks_the_true_model_first_after_a_probe(seed: int) -> None:
    """A closed cabinet is seen and a particle drawn; the robot's probe moves one real
    part (a drawer 12 cm out, a door 0.4 rad). Candidates: the true cabinet, and the
    particle with the probed part believed a drawer, a door hinged on each side, or a
    fixed panel, each predicting the probe by its own joint. The true model ranks first
    and the right belief above every wrong one (``tools/eval_likelihood.py``)."""
    from eval_likelihood import probe_cabinet

    rows = probe_cabinet(seed, None, np.random.default_rng(0))
    assert rows
    for r in rows:
        ranking = sorted(r["H"], key=r["H"].get)
        assert ranking[:2] == ["true", r["right"]], r
        ll = log_likelihood(np.zeros((1, 3)), [np.full((1, 3), h) for h in r["H"].values()])
        assert np.argmax(ll) == list(r["H"]).index("true")


def test_a_door_whose_handle_no_view_showed_mostly_gets_one_in_the_cabinets_style() -> None:
    """A door hypothesis without a seen handle gets, in about ``unseen_handle`` of the
    particles that read it as a door, a handle at the generator's spot in the style the
    cabinet's other parts show; in a cabinet that shows no handle, none gets one."""
    import dataclasses

    from strug_manip.domains.manipulation.belief import seen_style

    fused = _oracle_fusion(render_episode(3000, 4))
    style = seen_style(fused)
    assert style is not None
    # The hypothesis most likely a door among those whose handle the views show.
    k = max(
        (i for i, h in enumerate(fused.parts) if h.handle is not None),
        key=lambda i: fused.parts[i].class_prob[2],
    )
    hidden = dataclasses.replace(fused.parts[k], handle=None)
    one_hidden = dataclasses.replace(
        fused, parts=tuple(hidden if i == k else h for i, h in enumerate(fused.parts))
    )
    cfg = BeliefConfig(particles=300)

    def doors_from_k(f) -> list:
        particles = sample_particles([f], np.random.default_rng(3), cfg)
        return [
            part
            for p in particles
            for i, part in enumerate(p.spec.parts)
            if p.source[i] == k and part.kind == "door"
        ]

    doors = doors_from_k(one_hidden)
    assert len(doors) >= 30
    handled = [d for d in doors if d.handle != "none"]
    share = len(handled) / len(doors)
    lo, hi = scipy.stats.binom.interval(0.999, len(doors), cfg.unseen_handle)
    assert lo / len(doors) <= share <= hi / len(doors), share
    assert all(d.handle == style for d in handled)
    # At the generator's spot: 4.5 cm in from the free edge (a flap's: its lower or
    # upper edge; a side door's: its left or right edge).
    for d in handled:
        y0, y1 = d.cell_center[1] - d.cell_size[0] / 2, d.cell_center[1] + d.cell_size[0] / 2
        z0, z1 = d.cell_center[2] - d.cell_size[1] / 2, d.cell_center[2] + d.cell_size[1] / 2
        edges = [abs(d.handle_pos[1] - y0), abs(d.handle_pos[1] - y1)]
        if d.hinge not in ("left", "right"):
            edges = [abs(d.handle_pos[2] - z0), abs(d.handle_pos[2] - z1)]
        assert 0.03 < min(edges) < 0.07, (d.hinge, edges)
    none_seen = dataclasses.replace(
        fused, parts=tuple(dataclasses.replace(h, handle=None) for h in fused.parts)
    )
    assert seen_style(none_seen) is None
    assert all(d.handle == "none" for d in doors_from_k(none_seen))
    with pytest.raises(ConfigError, match="unseen_handle"):
        BeliefConfig(unseen_handle=1.5)


def _hypothesis(handle: np.ndarray, style: str = "bar") -> PartHypothesis:
    rect = np.array([-0.2, 0.2, 0.2, 0.5])
    return PartHypothesis(
        rect=rect, rect_std=np.zeros(4), class_prob=np.array([0.0, 0.5, 0.5]), existence=1.0,
        hinge_prob=np.full(4, 0.25), door_rect=np.tile(rect, (4, 1)), door_q=np.zeros(4),
        q_drawer=0.0, q_std=0.0, handle=handle, handle_score=0.9, views=1, visible=1, merged=0,
        shelf=False, handle_style=style,
    )  # fmt: skip


def test_a_bar_read_on_its_fronts_face_stands_out_at_the_bars_standoff() -> None:
    """A bar's grasp point read on the face behind it (front frame x = 0: the bar's few
    pixels gave the face's depth; OpenDoor 10169, every opening ``ik_infeasible``)
    stands out at the standoff a bar has (``BAR``); one read 2 cm out, and a knob's, stay
    where they were read. Front frame: the closed front's face at x = 0."""
    axis, origin = np.array([0.0, 0.0, 1.0]), np.array([0.0, -0.2, 0.35])
    face = np.array([0.0, 0.15, 0.35])
    np.testing.assert_allclose(closed_handle(_hypothesis(face), "door", axis, origin, 0.0),
                               [BAR[2], 0.15, 0.35])  # fmt: skip
    out = np.array([0.02, 0.15, 0.35])
    np.testing.assert_allclose(closed_handle(_hypothesis(out), "door", axis, origin, 0.0), out)
    knob = _hypothesis(face, "knob")
    np.testing.assert_allclose(closed_handle(knob, "door", axis, origin, 0.0), face)
    # A drawer seen 5 cm out, its bar read on its face: closed, on the carcass's front.
    seen = np.array([0.05, 0.0, 0.3])
    pull = np.array([1.0, 0.0, 0.0])
    np.testing.assert_allclose(closed_handle(_hypothesis(seen), "drawer", pull, origin, 0.05),
                               [BAR[2], 0.0, 0.3])  # fmt: skip
