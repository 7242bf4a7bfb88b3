"""LightDark2D trajectories: which walls a solver visits, and the paper's Fig. 3.

In LightDark2D the right wall (x = 10) makes x observable and the top wall (y = 10)
makes y observable; only x matters for the goal. A solver that gathers only
task-relevant information should visit the right wall and not the top one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from planners.solvers import make_solver
from strug_manip.domains import make_domain
from strug_manip.experiments.episode import EpisodeResult, run_episode

#: Distance to a wall [m] within which a trajectory counts as visiting it
#: (the observation noise there is at most 0.1 + 0.5 * 1.0 = 0.6 m).
WALL_MARGIN = 1.0


@dataclass(frozen=True)
class WallVisits:
    """Per solver: episodes, and how many gathered x or y information at a wall.

    A wall informs in two ways: the light walls (right: x, top: y) make observations
    precise within ``WALL_MARGIN`` of them, and the walls at 0 (left: x, bottom: y)
    clip the position, so a move into one leaves that coordinate exactly 0 whatever
    the belief was (the design's "positions clipped to the room").
    """

    episodes: int
    right: int
    top: int
    left_clip: int
    bottom_clip: int
    x_informed: int
    y_informed: int
    mean_return: float


def visits_walls(trajectory: Sequence[tuple[float, float]]) -> dict[str, bool]:
    """Which walls a trajectory used: ``right``, ``top`` (lights), ``left``, ``bottom`` (clips)."""
    xs = [x for x, _ in trajectory]
    ys = [y for _, y in trajectory]
    return {
        "right": max(xs) >= 10.0 - WALL_MARGIN,
        "top": max(ys) >= 10.0 - WALL_MARGIN,
        "left": min(xs) == 0.0,
        "bottom": min(ys) == 0.0,
    }


def run_trajectories(
    solver: str, seeds: Sequence[int], overrides: dict[str, Any] | None = None
) -> list[EpisodeResult]:
    """LightDark2D episodes of ``solver`` for ``seeds``."""
    pomdp = make_domain("lightdark2d")
    config = make_solver(solver, overrides or {})
    return [run_episode(pomdp, config, seed) for seed in seeds]


def wall_visits(results: Sequence[EpisodeResult]) -> WallVisits:
    """Count the wall visits of ``results``."""
    flags = [visits_walls(r.trajectory) for r in results]
    return WallVisits(
        episodes=len(results),
        right=sum(f["right"] for f in flags),
        top=sum(f["top"] for f in flags),
        left_clip=sum(f["left"] for f in flags),
        bottom_clip=sum(f["bottom"] for f in flags),
        x_informed=sum(f["right"] or f["left"] for f in flags),
        y_informed=sum(f["top"] or f["bottom"] for f in flags),
        mean_return=sum(r.discounted_return for r in results) / max(len(results), 1),
    )


def plot_trajectories(runs: dict[str, list[EpisodeResult]], path: Path) -> None:
    """One panel per solver: the room, the goal bar, the lights, every trajectory; one
    legend below the panels explains colours and markers."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    good, bad = "#1b7837", "#b2182b"
    fig, axes = plt.subplots(1, len(runs), figsize=(4.2 * len(runs), 5.0), squeeze=False)
    for ax, (solver, results) in zip(axes[0], runs.items(), strict=True):
        ax.axvspan(4.5, 5.5, color="#b7e4b0")
        ax.axvspan(10 - WALL_MARGIN, 10, color="#fff2b3", alpha=0.7)
        ax.axhspan(10 - WALL_MARGIN, 10, color="#d6e6ff", alpha=0.7)
        for r in results:
            xs = [s[0] for s in r.trajectory]
            ys = [s[1] for s in r.trajectory]
            color = good if r.discounted_return > 0 else bad
            ax.plot(xs, ys, "-", color=color, alpha=0.55, lw=1.2)
            ax.plot(xs[0], ys[0], "o", color=color, ms=3)
            ax.plot(xs[-1], ys[-1], "x", color=color, ms=5)
        v = wall_visits(results)
        ax.set_title(
            f"{solver}: x informed {v.x_informed}/{v.episodes}, y {v.y_informed}/{v.episodes}\n"
            f"mean return {v.mean_return:.2f}",
            fontsize=10,
        )
        ax.set_xlim(0, 10)
        ax.set_ylim(0, 10)
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    handles = [
        Patch(color="#b7e4b0", label="goal: declare at |x-5|<0.5"),
        Patch(color="#fff2b3", label="x light (within 1 m of the right wall): precise x"),
        Patch(color="#d6e6ff", label="y light (within 1 m of the top wall): precise y"),
        Line2D([], [], color=good, lw=1.5, label="episode with return > 0"),
        Line2D([], [], color=bad, lw=1.5, label="episode with return <= 0"),
        Line2D([], [], color="0.3", marker="o", ls="", ms=4, label="true start"),
        Line2D([], [], color="0.3", marker="x", ls="", ms=6, label="true end"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8, frameon=False)
    fig.text(
        0.5,
        0.105,
        "x (y) informed: episodes that entered the x (y) light or were clipped at the "
        "left (bottom) wall, which fixes x (y) exactly",
        ha="center",
        fontsize=8,
        color="0.3",
    )
    fig.tight_layout(rect=(0, 0.13, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)
