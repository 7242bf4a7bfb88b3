"""Speed of the manipulation world: build, render, simulate.

Usage::

    python tools/bench_world.py [--seeds 5] [--frames 30] [--sim-seconds 5] [--json]

Prints the median time to generate and load one cabinet scene (generator, PartNet
files, loader into MuJoCo and Pinocchio, scene composition and compilation; target
< 0.5 s), to render one 320x240 RGB-D frame from the head camera (colour + depth
passes; target < 30 ms), and the simulation speed of the scene with the robot holding
its home pose (target >= 20x real time on one core).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

from strug_manip.world import ManipulationWorld, SceneConfig


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--sim-seconds", type=float, default=5.0)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    ManipulationWorld(SceneConfig(cabinet_seed=0)).close()  # warm imports and caches
    build, render, realtime = [], [], []
    for seed in range(args.seeds):
        t0 = time.perf_counter()
        world = ManipulationWorld(SceneConfig(cabinet_seed=seed))
        build.append(time.perf_counter() - t0)
        world.render("head_camera")  # create the GL context outside the timing
        for _ in range(args.frames):
            t0 = time.perf_counter()
            frame = world.render_rgbd("head_camera")
            render.append(time.perf_counter() - t0)
        del frame
        t0 = time.perf_counter()
        world.step(args.sim_seconds)
        realtime.append(args.sim_seconds / (time.perf_counter() - t0))
        world.close()
    out = {
        "build_seconds": statistics.median(build),
        "render_rgbd_ms": 1e3 * statistics.median(render),
        "sim_realtime_factor": statistics.median(realtime),
    }
    if args.json:
        print(json.dumps(out))
        return
    print(f"generate + load one cabinet scene: {out['build_seconds']:.3f} s (target < 0.5 s)")
    print(f"render one 320x240 RGB-D frame:    {out['render_rgbd_ms']:.1f} ms (target < 30 ms)")
    print(
        f"simulate the scene:                {out['sim_realtime_factor']:.0f}x real time "
        "(target >= 20x)"
    )


if __name__ == "__main__":
    main()
