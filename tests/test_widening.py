"""POMCPOW's double progressive widening keeps child counts within k * N^alpha."""

from __future__ import annotations

import numpy as np
import pytest

from planners.solvers import POMCPOWConfig
from strug_manip.domains import make_domain


@pytest.mark.parametrize(
    ("domain", "k_a", "al_a", "k_o", "al_o"),
    [
        ("lightdark2d", 10.0, 1 / 30, 5.0, 1 / 15),  # defaults: action and obs widening
        ("lightdark2d", 1.0, 0.5, 1.0, 0.5),  # a steeper law, so a wrong bound shows
        ("lightdark1d", 10.0, 1 / 30, 2.0, 0.3),  # finite actions, continuous obs
    ],
)
def test_child_counts_obey_k_n_alpha(domain, k_a, al_a, k_o, al_o) -> None:
    pomdp = make_domain(domain)
    rng = np.random.default_rng(1)
    belief = pomdp.initial_belief(rng, 500)
    cfg = POMCPOWConfig(
        sims=3000, k_action=k_a, alpha_action=al_a, k_obs=k_o, alpha_obs=al_o, keep_tree=True
    )
    planner = cfg.planner(pomdp)
    _, info = planner.act(belief, rng)
    tree = info.tree
    widened = planner.widening == "dpw"
    checked_a = checked_o = 0
    for h, children in enumerate(tree.actions.b_children):
        n = tree.visits[h]
        if widened and children:
            assert len(children) <= k_a * n**al_a + 1
            checked_a += 1
        for anode in children:
            n_ha = tree.actions.a_n[anode]
            assert tree.obs_children(anode) <= k_o * n_ha**al_o + 1
            checked_o += 1
    assert checked_o > 50
    if widened:
        assert checked_a > 20
        root = len(tree.actions.b_children[0])
        # The root really widened: more than one child, as many as the law allows.
        assert root >= int(k_a * (tree.visits[0] - 1) ** al_a)


def test_finite_action_space_expands_every_action() -> None:
    pomdp = make_domain("tiger")
    planner = POMCPOWConfig(sims=50).planner(pomdp)
    _, info = planner.act(
        pomdp.initial_belief(np.random.default_rng(0), 50), np.random.default_rng(0)
    )
    assert len(info.actions) == 3
