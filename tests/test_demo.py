"""``make demo``'s episode (``strug demo``: OpenDrawer with STRUG, seed 0, the default
budget and belief): its first two real steps, as the demo runs them.

The demo failed (return 0) when its opening pulled the top drawer into its stop at
full speed, tipped the cabinet 2.4 degrees, and, as the cabinet came down, the drawer
slid 6 cm back into the carcass while the belief kept it out; the Place then came down
onto its front. The opening now ends slowly (``SkillParams.ease_distance``): the drawer
stays out and the cabinet stands where it stood.
"""

from __future__ import annotations

import pytest

from planners.episode import StepRecord, run_episode
from strug_manip.domains import make_domain
from strug_manip.experiments.task import budget_for, solver_config

#: The demo's seed and solver (``strug_manip.cli._manipulation_demo``).
DEMO_SEED, DEMO_SOLVER = 0, "strug"


class _Enough(Exception):  # noqa: N818 (control flow, not an error)
    """Stops the episode after the steps the test looks at."""


def test_the_demo_opens_its_drawer_without_tipping_the_cabinet_and_picks() -> None:
    pomdp = make_domain("opendrawer")
    config = solver_config(DEMO_SOLVER, budget_for("opendrawer", {}))
    steps: list[StepRecord] = []
    opened = {}

    def on_step(rec: StepRecord) -> None:
        steps.append(rec)
        world = pomdp.real.world
        if rec.step == 0:
            opened.update(world.part_positions(), moved=world.cabinet_displacement())
        if len(steps) == 2:
            raise _Enough

    try:
        with pytest.raises(_Enough):
            run_episode(pomdp, config, DEMO_SEED, on_step=on_step)
        target = pomdp.real.world.scene.cabinet_prefix + "joint_1"
        assert pomdp.real.target == "link_1"  # the top drawer, handle at z = 1.17 m
    finally:
        pomdp.close()
    first, second = steps
    assert first.action.startswith("OpenDrawer(part@(y=+0.00, z=1.17)"), first.action
    assert "OpenDrawer: ok" in first.observation, first.observation
    # Out as far as its stop (0.213 m) lets it, not slid back in (it stood at 0.152 m).
    assert opened[target] > 0.2, opened
    assert opened["moved"] < 0.005, opened
    assert second.action == "Pick(top)" and "Pick: ok" in second.observation, second
