"""Speed of the parameterised controllers: one execution each, from the world's reset.

Usage::

    python tools/bench_controllers.py [--runs 5] [--json]

For each controller, on the test cabinets (generator seed 3; drawers: top drawer
``link_1``; doors: right-hinged door ``link_1``) under the true model, prints the
median wall time of one execution [s] from the robot's home tuck (``Place`` from the
end of a ``Pick``), the share of it spent in inverse kinematics, OMPL motion planning
(and collision checks), MuJoCo physics and the rest (Python driving, bookkeeping), the
simulated time [s] and the outcome. Target (issue 5): a full ``OpenDrawer`` under
0.5 s of wall time on one core. Single process: run it on an idle core.
"""

from __future__ import annotations

import argparse
import json
import statistics
from collections.abc import Callable

import numpy as np

from strug_manip.control.controllers import (
    OpenDoor,
    OpenDrawer,
    Outcome,
    Pick,
    Place,
    PullH,
    PullV,
    Push,
    handle_grasp,
    true_joint,
)
from strug_manip.world import ManipulationWorld, SceneConfig


def place_pose(world: ManipulationWorld, link: str, q: float) -> np.ndarray:
    """``T_world_object`` (4, 4) on the bottom of the open drawer ``link`` (opened ``q``
    [m]), in its part outside the cabinet."""
    part = world.scene.cabinet_spec.part(link)
    T = world.scene.T_world_cabinet
    c = (T @ np.r_[part.point_at(part.interior_center, q), 1.0])[:3]
    s = part.interior_size
    p = np.eye(4)
    p[:3, 3] = [min(c[0] + s[0] / 2, 0.98) - 0.07, c[1], c[2] - s[2] / 2 + 0.045]
    return p


def cases(drawers: ManipulationWorld, doors: ManipulationWorld) -> dict[str, Callable]:
    """Name -> ``() -> Outcome`` running one controller from a fresh reset."""

    def open_drawer() -> Outcome:
        drawers.reset()
        g = handle_grasp(drawers, "link_1")
        return OpenDrawer(g, true_joint(drawers, "link_1")).run(drawers)

    def open_door() -> Outcome:
        doors.reset()
        g = handle_grasp(doors, "link_1")
        return OpenDoor(g, true_joint(doors, "link_1")).run(doors)

    def pick() -> Outcome:
        drawers.reset({"joint_1": 0.2})
        return Pick("object").run(drawers)

    def place() -> Outcome:
        pick()
        return Place("object", place_pose(drawers, "link_1", 0.2)).run(drawers)

    def probe(cls: type, q: float = 0.0) -> Callable[[], Outcome]:
        def run() -> Outcome:
            drawers.reset({"joint_1": q})
            return cls(handle_grasp(drawers, "link_1")).run(drawers)

        return run

    return {
        "OpenDrawer": open_drawer,
        "OpenDoor": open_door,
        "Pick": pick,
        "Place": place,
        "Push": probe(Push, 0.1),
        "PullV": probe(PullV),
        "PullH": probe(PullH),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=5, help="executions per controller")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args()

    drawers = ManipulationWorld(SceneConfig(cabinet_seed=3, cabinet_kinds=("drawer",)))
    doors = ManipulationWorld(SceneConfig(cabinet_seed=3, cabinet_kinds=("door",)))
    table = {}
    for name, fn in cases(drawers, doors).items():
        fn()  # warm up (solvers built once per process)
        outs = [fn() for _ in range(args.runs)]
        wall = statistics.median(o.wall_seconds for o in outs)
        total = sum(o.wall_seconds for o in outs)
        ik = sum(o.ik_seconds for o in outs) / total
        plan = sum(o.planning_seconds for o in outs) / total
        phys = sum(o.physics_seconds for o in outs) / total
        table[name] = {
            "median_wall_s": wall,
            "ik_share": ik,
            "planning_share": plan,
            "physics_share": phys,
            "other_share": 1.0 - ik - plan - phys,
            "sim_time_s": outs[-1].sim_time,
            "outcome": outs[-1].reason,
        }
    drawers.close()
    doors.close()
    if args.json:
        print(json.dumps(table, indent=2))
        return
    print(
        f"{'controller':<11} {'wall [s]':>8} {'IK':>6} {'plan':>6} {'physics':>8} "
        f"{'other':>6} {'sim [s]':>8}  outcome"
    )
    for name, r in table.items():
        print(
            f"{name:<11} {r['median_wall_s']:8.3f} {r['ik_share']:6.1%} "
            f"{r['planning_share']:6.1%} {r['physics_share']:8.1%} {r['other_share']:6.1%} "
            f"{r['sim_time_s']:8.1f}  {r['outcome']}"
        )


if __name__ == "__main__":
    main()
