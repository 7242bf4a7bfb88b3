"""STRUG gathers only task-relevant information on LightDark2D (the paper's Fig. 3).

x is what the goal needs; the room's walls inform x (right wall: light; left wall:
clipping) or y (top wall: light; bottom wall: clipping). Over 20 seeds STRUG should
use x walls and leave the y walls alone, while Entropy Regularized, which values all
information, uses both. Episodes are deterministic given the seed and the numerical
libraries, but a search's near-ties can fall the other way under another numpy build
(a few episodes of 20 change), so the test asserts the contrast the paper draws, with
room for that, not exact counts (the README's LightDark2D section has the figures).
"""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor

from strug_manip.experiments.lightdark2d import run_trajectories, wall_visits

SEEDS = range(20)
BUDGET = {"sims": 1000}


def test_strug_visits_x_walls_not_y_walls_and_entropy_visits_both() -> None:
    # One process per solver (spawned: the suite's process has native threads running):
    # half the wall time on two cores, the same episodes.
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        runs = pool.map(run_trajectories, ("strug", "entropy"), (SEEDS, SEEDS), (BUDGET, BUDGET))
        strug, entropy = (wall_visits(r) for r in runs)
    assert strug.x_informed >= 10, strug
    assert entropy.x_informed >= 4 and entropy.y_informed >= 8, entropy
    # STRUG leaves the y walls to at most a quarter of Entropy's visits, and uses the x
    # walls at least twice as often as Entropy does.
    assert 4 * strug.y_informed <= entropy.y_informed, (strug, entropy)
    assert strug.x_informed >= 2 * entropy.x_informed, (strug, entropy)
    assert strug.mean_return > entropy.mean_return
