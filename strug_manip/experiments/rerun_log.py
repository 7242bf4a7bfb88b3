"""Log episodes to rerun: trajectories, beliefs and search statistics.

``strug run ... --rerun episode.rrd`` writes a recording to open with ``rerun
episode.rrd``. Per step (timeline ``step``):

* ``episode/reward``, ``episode/return`` (discounted, so far): scalars;
* ``search/sims``, ``search/plan_seconds``, ``search/tree_nodes``, ``search/tru`` or
  ``search/entropy``, ``search/q_best``: scalars; ``search/q_root``: a bar chart of the
  root children's values; on finite action spaces also ``search/q/<action>`` and
  ``search/bonus/<action>`` (continuous actions are new every step, so no series each);
* ``belief/particles``: the particles after the update, as 2D points (a 1D state is drawn
  on the x axis) with radius growing with weight; discrete states as a bar chart of mass;
* ``world/true_state``: the true state (continuous domains);
* ``log``: one line per step, action -> observation.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from planners.belief import ParticleBelief
from strug_manip.experiments.episode import StepRecord


def _path_part(name: str) -> str:
    """An entity-path-safe version of an action name."""
    return re.sub(r"[^A-Za-z0-9_-]+", "_", name).strip("_") or "action"


class RerunRecorder:
    """Writes one episode to a ``.rrd`` file as it runs.

    Args:
        path: the recording file.
        pomdp: the domain (for ``entropy_features``: how to draw states).
        app: rerun application id.
    """

    def __init__(self, path: Path, pomdp: Any, app: str = "strug") -> None:
        import rerun as rr

        self.rr = rr
        self.pomdp = pomdp
        self.stream = rr.RecordingStream(app)
        self.stream.save(str(path))
        self._return = 0.0
        self.discrete_actions = pomdp.action_space().is_discrete

    def _features(self, states: list[Any]) -> np.ndarray | None:
        feats = self.pomdp.entropy_features(states)
        if feats is None or feats.shape[1] > 2:
            return None
        return feats if feats.shape[1] == 2 else np.c_[feats, np.zeros(len(feats))]

    def __call__(self, rec: StepRecord, belief: ParticleBelief | None, state: Any) -> None:
        """Log step ``rec``; ``belief`` is the belief after the update (None once it ended)."""
        rr, log = self.rr, self.stream.log
        self.stream.set_time("step", sequence=rec.step)
        self._return += rec.reward * self.pomdp.discount**rec.step
        log("episode/reward", rr.Scalars(rec.reward))
        log("episode/return", rr.Scalars(self._return))
        log("search/sims", rr.Scalars(rec.sims))
        log("search/plan_seconds", rr.Scalars(rec.plan_seconds))
        log("search/tree_nodes", rr.Scalars(rec.tree_nodes))
        for key in ("tru", "entropy"):
            value = getattr(rec, key)
            if value is not None:
                log(f"search/{key}", rr.Scalars(value))
        if rec.q:
            log("search/q_root", rr.BarChart(np.array(list(rec.q.values()))))
            log("search/q_best", rr.Scalars(max(rec.q.values())))
        if self.discrete_actions:  # stable action names: one series each
            for action, q in rec.q.items():
                log(f"search/q/{_path_part(action)}", rr.Scalars(q))
            for action, b in rec.bonus.items():
                log(f"search/bonus/{_path_part(action)}", rr.Scalars(b))
        log("log", rr.TextLog(f"{rec.action} -> {rec.observation} (r={rec.reward:+.2f})"))
        true_xy = self._features([state])
        if true_xy is not None:
            log("world/true_state", rr.Points2D(true_xy, radii=0.15, colors=[220, 40, 40]))
        if belief is None:
            return
        xy = self._features(belief.states)
        if xy is not None:
            radii = 0.02 + 0.2 * np.sqrt(belief.weights / belief.weights.max())
            log("belief/particles", rr.Points2D(xy, radii=radii, colors=[40, 110, 220]))
        else:
            mass: dict[str, float] = {}
            for s, w in zip(belief.states, belief.weights.tolist(), strict=True):
                mass[str(s)] = mass.get(str(s), 0.0) + w
            log("belief/mass", rr.BarChart(np.array(list(mass.values()))))

    def close(self) -> None:
        """Flush the recording."""
        self.stream.flush()
