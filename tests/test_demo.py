"""``make demo``'s episode (``strug demo``: OpenDrawer with STRUG, seed 0, the default
budget and belief): its first two real steps, as the demo runs them; and (``slow``) the
whole episode, which must end with the task's +10.

The demo failed (return 0) when its first opening pulled the top drawer into its stop
at full speed and tipped the cabinet 2.4 degrees; as the cabinet came down, the drawer
slid 6 cm back into the carcass (0.213 -> 0.152 m) while the belief kept it out, and
the Place came down onto its front. Openings now end slowly
(``SkillParams.ease_distance``). Which parts the planner opens first depends on the
belief (the perception weights), so the test checks what the real steps do to the
cabinet: its base stays, and no drawer slides back.
"""

from __future__ import annotations

import pytest

from planners.episode import EpisodeResult, StepRecord, run_episode
from strug_manip.domains import make_domain
from strug_manip.experiments.task import budget_for, solver_config

#: The demo's seed and solver (``strug_manip.cli._manipulation_demo``).
DEMO_SEED, DEMO_SOLVER = 0, "strug"
#: A part a step moved stands at its end within this of the farthest it went [m]: the
#: tipped demo's drawer slid 6 cm back; an eased opening leaves its drawer where it
#: went, but for what the arm, settling back to its command, pushes it (0.3 cm when the
#: opening stopped short of the drawer's end; since openings go on slowly to the
#: longest limit any particle holds, the demo's first one meets the top drawer's end,
#: 0.2134 m, and the drawer comes back 3.9 cm as the fingers open, issue 37). What the
#: slide used to cost, a belief holding the drawer farther out than it stood, is gone:
#: every particle's drawer now stands where the real one does (conditioning.as_seen).
MAX_SLIDE_BACK = 0.05


#: The demo's cabinet base moves less than this in the whole episode [m]: two thirds of
#: the slide guard (``SkillParams.cabinet_motion_limit``, 3 cm) that stopped the
#: demo's first opening when its pull ran into the drawer's stop.
CABINET_STOOD = 0.02


class _Enough(Exception):  # noqa: N818 (control flow, not an error)
    """Stops the episode after the steps the test looks at."""


def test_the_demos_first_steps_leave_the_cabinet_and_let_no_drawer_slide_back() -> None:
    pomdp = make_domain("opendrawer")
    config = solver_config(DEMO_SOLVER, budget_for("opendrawer", {}))
    steps: list[StepRecord] = []

    def on_step(rec: StepRecord) -> None:
        steps.append(rec)
        if len(steps) == 2:
            raise _Enough

    try:
        with pytest.raises(_Enough):
            run_episode(pomdp, config, DEMO_SEED, on_step=on_step)
        real = pomdp.real
        world, outcomes = real.world, list(real.outcomes)
        displacement = world.cabinet_displacement()
        joints = {j: int(world.model.jnt_qposadr[world.model.joint(j).id])
                  for j in world.part_joints}  # fmt: skip
    finally:
        pomdp.close()
    assert steps[0].action.startswith("OpenDrawer(") and ": ok" in steps[0].observation, steps[0]
    assert len(outcomes) == 2, [s.observation for s in steps]
    for out in outcomes:
        for joint, adr in joints.items():
            q = out.qpos[:, adr]
            assert q[-1] > q.max() - MAX_SLIDE_BACK, (out.summary(), joint, q.max(), q[-1])
    # The base (the 0.1 m rule's), through both steps: well inside the slide guard's 3
    # cm. 7 mm until the openings ended at the part's end (issue 37); since, the
    # second opening pulls the top drawer 0.18 m instead of 0.13 m, and 13 mm.
    assert displacement < CABINET_STOOD


#: The demo's episode since STRUG's root chooses by PUCT with 100 simulations (issue
#: 37): its real steps, each ``ok``, the last placing the object in the target drawer
#: (+10, discounted +9.025; at 2cdb37e, UCB and 20 simulations, it opened a second
#: drawer first, +8.574). Its planning depends on nothing but the seed (a
#: simulation-count budget, motion plans budgeted in validity checks), so the same
#: steps come out on an idle or a loaded machine.
DEMO_SKILLS = ("OpenDrawer", "Pick", "Place")


@pytest.mark.slow
def test_the_demos_episode_places_the_object_and_earns_the_plus_10() -> None:
    """The whole demo (about 5 minutes: its cabinet's Place finds no base in most
    particles, and each twin's placement search then costs about 0.9 s). It used to
    fail: its carrying reach ended 0.12 m above the place, inside the drawer's box, came
    in over a side wall that perception put 4.8 cm low and struck the real one, then
    pushed the drawer shut on the next try (``targets.ABOVE_WALLS``); and it ended
    differently with the machine's load (OMPL's wall-time budgets;
    ``SkillParams.plan_checks``)."""
    pomdp = make_domain("opendrawer")
    config = solver_config(DEMO_SOLVER, budget_for("opendrawer", {}))
    try:
        result: EpisodeResult = run_episode(pomdp, config, DEMO_SEED)
        real = pomdp.real
        statuses = [str(out.status) for out in real.outcomes]
        skills = tuple(out.skill for out in real.outcomes)
        displacement = real.world.cabinet_displacement()
    finally:
        pomdp.close()
    observations = [s.observation for s in result.steps]
    # The guarantee: the task's +10 at the last step, nothing failed on the way, the
    # cabinet stood. The steps that get there may change with the planner (DEMO_SKILLS:
    # what they are now).
    assert result.steps[-1].reward == 10.0, observations
    assert all(s.reward == 0.0 for s in result.steps[:-1]), observations
    assert skills[-1] == "Place" and set(statuses) == {"ok"}, (skills, statuses)
    assert len(skills) <= len(DEMO_SKILLS), observations
    assert displacement < CABINET_STOOD, displacement  # the base stayed (the 0.1 m rule's)
