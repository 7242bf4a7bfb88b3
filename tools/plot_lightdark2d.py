"""LightDark2D trajectories of several solvers (the STRUG paper's Fig. 3).

Usage::

    python tools/plot_lightdark2d.py [--solvers strug,entropy,pomcpow] [--seeds 20]
                                     [--sims 1000] [--out docs/lightdark2d.png]

Prints, per solver, how many episodes gathered x information at a wall (within 1 m
of the right wall's light, or clipped at the left wall) and y information (top light,
bottom clip), and the mean discounted return; saves the figure.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from strug_manip.experiments.lightdark2d import plot_trajectories, run_trajectories, wall_visits


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--solvers", default="strug,entropy,pomcpow")
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--sims", type=int, default=None, help="default: the solvers' own")
    parser.add_argument("--out", type=Path, default=Path("docs/lightdark2d.png"))
    args = parser.parse_args()
    overrides = {"sims": args.sims} if args.sims else {}
    runs = {}
    for solver in args.solvers.split(","):
        runs[solver] = run_trajectories(solver, range(args.seeds), overrides)
        v = wall_visits(runs[solver])
        print(
            f"{solver:<8} x informed {v.x_informed:>3}/{v.episodes} (right light {v.right}, "
            f"left clip {v.left_clip})  y informed {v.y_informed:>3}/{v.episodes} (top light "
            f"{v.top}, bottom clip {v.bottom_clip})  mean return {v.mean_return:+.2f}",
            flush=True,
        )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    plot_trajectories(runs, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
