"""Issue 37: a skill stopped on its way to the part (the drive, the reach) leaves the
cabinet where the stop found it.

The skill plans in a believed world whose cabinet stands where the generator put it;
the real cabinet stands in the drive's way (behind the base's pose at the object table),
as a cabinet a few centimetres off its believed pose, or slid by an earlier skill, does.
Before the drive was watched, the base drove on and slid it 0.09 m, nearly the 0.1 m at
which the task counts it dragged (OpenDoor episode 10188 slid one 0.27 m so).
"""

from __future__ import annotations

import numpy as np

from strug_manip.control import Pick, Status
from strug_manip.control.params import DEFAULT_PARAMS
from strug_manip.domains.manipulation.rules import dragged
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

#: Doors only (generator seed 25, as ``tests/test_skills.py``'s ``doors_25``).
CONFIG = SceneConfig(cabinet_seed=25, cabinet_kinds=("door",))
#: Where the real cabinet stands (x, y) [m]: its front 0.2 m into the base's pose for
#: the Pick at the object table ((0.636, -0.8), facing -x), which the drive ends at.
IN_THE_WAY = (1.0, -0.8)
#: What the cabinet may move past the guard's limit [m]: the monitor's 10 ms period at
#: the 0.3 m/s drive speed, and the cabinet sliding on after the base stopped (2.6 cm
#: measured here, the base stopped mid-turn).
STOP_SLACK = 0.04


def test_a_drive_that_meets_the_cabinet_stops_where_it_met_it(ctx) -> None:
    world, believed = ManipulationWorld(CONFIG), ManipulationWorld(CONFIG)
    try:
        world.reset()
        believed.reset()
        T = world.cabinet_pose()
        T[:2, 3] = IN_THE_WAY
        world.set_cabinet_pose(T)
        start = world.cabinet_pose()[:2, 3].copy()
        out = Pick("object", "side").run(world, ctx=ctx, plan_world=believed)
        moved = float(np.linalg.norm(world.cabinet_pose()[:2, 3] - start))
        assert out.status is Status.CABINET_MOVED, out.summary()
        assert "(drive)" in out.detail, out.summary()
        assert moved < DEFAULT_PARAMS.cabinet_motion_limit + STOP_SLACK, (moved, out.summary())
        assert not dragged(moved)
        assert not out.holding
        assert out.on_the_way  # the real belief update does not weigh its key
    finally:
        world.close()
        believed.close()
