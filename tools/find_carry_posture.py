"""Search the Fetch's carry posture: torso + arm holding the object, compact for driving.

Usage::

    python tools/find_carry_posture.py [--samples 20000] [--seed 0]

Samples torso + arm configurations (uniform within the joint limits, seeded) with the
object held in a top grasp (gripper pointing down, the object under it) or a side grasp
(gripper level, the object ahead of the fingers) and keeps, per grasp, the one with
the smallest horizontal reach (the farthest robot body or object point from the base
centre) among those that

- are free of contacts (robot with itself), and keep :data:`CLEARANCE` between the
  object and the robot (the object's contacts are sought that far out);
- have a free way out: the straight joint-space line to the IK's ready posture, the
  object carried along, is free (a carry posture in a narrow pocket is a trap for the
  motion planner);
- hold the object between 0.85 m (clear of 0.72 m tables while driving) and 1.35 m
  (below the head camera), out of the head camera's view ahead: behind the shoulder
  (x < 0.15 m in the robot's frame) or off to the side (|y| > 0.25 m).
Prints the postures as Python tuples for ``strug_manip.robot.fetch.CARRY``.
"""

from __future__ import annotations

import argparse

import mujoco
import numpy as np

from strug_manip.control.contacts import ContactChecker
from strug_manip.control.ik import READY_POSTURE
from strug_manip.robot.fetch import ARM_TORSO_JOINTS, BASE_JOINTS, GRIPPER_SITE
from strug_manip.world import ManipulationWorld, SceneConfig
from strug_manip.world.scene import OBJECT_HALF_SIZE

#: Clearance kept around the robot's parts and the held object [m].
CLEARANCE = 0.03


def grasp_offsets() -> dict[str, np.ndarray]:
    """``T_gripper_object`` of the top and the side grasp (as the skills grasp)."""
    top = np.eye(4)
    # Gripper x down, y along the object's y: the object's centre 1 cm below the TCP.
    top[:3, :3] = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]).T
    top[:3, 3] = [0.01, 0.0, 0.0]
    side = np.eye(4)  # gripper x along the object's x, the TCP at its centre
    return {"top": top, "side": side}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--samples", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    world = ManipulationWorld(SceneConfig(stand_height=0.0, cabinet_distance=3.0))
    m = world.model
    m.geom_margin[m.geom("object").id] = CLEARANCE  # the object's contacts count early
    checker = ContactChecker(m, (*BASE_JOINTS, *ARM_TORSO_JOINTS)).load(world.data)
    ready = np.array([READY_POSTURE[j] for j in ARM_TORSO_JOINTS])
    robot_bodies = [b for b in range(m.nbody) if checker.robot[b]]
    lo = np.array([m.jnt_range[m.joint(j).id, 0] for j in ARM_TORSO_JOINTS])
    hi = np.array([m.jnt_range[m.joint(j).id, 1] for j in ARM_TORSO_JOINTS])
    lo[[3, 5, 7]], hi[[3, 5, 7]] = -np.pi, np.pi  # the roll joints: one turn
    rng = np.random.default_rng(args.seed)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    corners = corners * np.array(OBJECT_HALF_SIZE)
    site = m.site(GRIPPER_SITE).id
    for name, T_go in grasp_offsets().items():
        checker.attach("object", T_go)
        checker.allow()
        best = None
        for _ in range(args.samples):
            q = rng.uniform(lo, hi)
            if not checker.free(np.concatenate([np.zeros(3), q])):
                continue
            d = checker.data
            T = np.eye(4)
            T[:3, :3] = d.site_xmat[site].reshape(3, 3)
            T[:3, 3] = d.site_xpos[site]
            pts = (T @ T_go)[:3, :3] @ corners.T
            pts = pts.T + (T @ T_go)[:3, 3]
            if pts[:, 2].min() < 0.85 or pts[:, 2].max() > 1.35:
                continue
            ahead = pts[:, 0].max() >= 0.15 and np.abs(pts[:, 1]).min() <= 0.25
            if ahead:
                continue
            reach = max(
                np.hypot(*d.xpos[robot_bodies][:, :2].T).max(), np.hypot(*pts[:, :2].T).max()
            )
            if best is not None and reach >= best[0]:
                continue
            if checker.segment(
                np.concatenate([np.zeros(3), q]), np.concatenate([np.zeros(3), ready])
            ):
                continue
            best = (reach, q)
        assert best is not None, f"no carry posture found for the {name} grasp"
        print(f"{name}: reach {best[0]:.3f} m:", tuple(round(float(v), 3) for v in best[1]))
    mujoco.mj_forward(m, world.data)


if __name__ == "__main__":
    main()
