"""Log episodes to rerun: the domain's geometry, trajectories, observations, beliefs and
search statistics.

``strug run ... --rerun episode.rrd`` writes a recording to open with ``rerun
episode.rrd``. Once (static), the domain's geometry under ``world/``:

* LightDark2D: ``world/room`` (the 10 m x 10 m walls), ``world/goal`` (the bar
  |x - 5| < 0.5), ``world/x_light`` and ``world/y_light`` (within 1 m of the right and
  top walls, where x and y are observed to within 0.6 m);
* LightDark1D (the position y drawn on the horizontal axis): ``world/goal`` (|y| < 1)
  and ``world/light`` (y = 5, where y is observed exactly);
* the Tigers: ``world/doors``, the two doors, labelled.

Per step (timeline ``step``):

* ``world/true_state`` and ``world/true_path`` (continuous domains), or the tiger behind
  its door; ``world/observation``: the observation where the domain has a place for it
  (a point labelled with its value), and always as text in ``log``;
* ``world/belief``: the particles after the update, as points whose radius grows with
  weight (continuous domains); ``belief/mass``: labelled bars of the mass per state
  (discrete domains);
* ``episode/reward``, ``episode/return`` (discounted, so far): scalars;
* ``search/sims``, ``search/plan_seconds``, ``search/tree_nodes``, ``search/tru`` or
  ``search/entropy``, ``search/q_best``: scalars; ``search/q_root``: one bar per root
  action, labelled ``action Q (visits)``, the chosen action drawn in orange; on finite
  action spaces also ``search/q/<action>`` and ``search/bonus/<action>`` series
  (continuous actions are new every step, so no series each);
* ``log``: one line per step, action -> observation.

The manipulation tasks (:class:`ManipulationLog`) log instead, under ``world/``, the
robot's and the cabinet's MuJoCo geoms (static, per body) posed at every recorded
frame of every skill the real robot ran (timeline ``sim_time``, the episode's
simulated time), the head camera's images and the cabinet cloud it saw after each
step (``camera``, ``camera_cloud``), and the belief: every particle's joints of the
cabinet's parts as arrows on the cabinet, darker for more weight (``belief/joints``).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from planners.belief import ParticleBelief
from strug_manip.domains.lightdark import LightDark1D, LightDark2D
from strug_manip.domains.tiger import Tiger
from strug_manip.experiments.episode import StepRecord
from strug_manip.experiments.lightdark2d import WALL_MARGIN

TRUE, OBS, BELIEF, CHOSEN, OTHER = (
    [220, 40, 40],
    [240, 150, 20],
    [40, 110, 220],
    [240, 150, 20],
    [120, 140, 170],
)


_NUMBER = re.compile(r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")


def _path_part(name: str) -> str:
    """An entity-path-safe version of an action name."""
    return re.sub(r"[^A-Za-z0-9_-]+", "_", name).strip("_") or "action"


def labelled_bars(
    rr: Any, values: Sequence[float], labels: Sequence[str], highlight: int | None = None
) -> Any:
    """``rr.Boxes2D`` drawing one bar per value at x = 0, 1, ..., each with its label
    (rerun's ``BarChart`` has no per-bar labels); bar ``highlight`` in orange."""
    v = np.asarray(values, dtype=float)
    mins = np.c_[np.arange(len(v)) - 0.4, np.minimum(v, 0.0)]
    sizes = np.c_[np.full(len(v), 0.8), np.maximum(np.abs(v), 1e-3)]
    colors = [CHOSEN if i == highlight else OTHER for i in range(len(v))]
    return rr.Boxes2D(mins=mins, sizes=sizes, labels=list(labels), colors=colors, show_labels=True)


class RerunRecorder:
    """Writes one episode to a ``.rrd`` file as it runs.

    Args:
        path: the recording file.
        pomdp: the domain (its geometry, and ``entropy_features``: how to draw states).
        app: rerun application id.
    """

    def __init__(self, path: Path, pomdp: Any, app: str = "strug") -> None:
        import rerun as rr

        self.rr = rr
        self.pomdp = pomdp
        self.stream = rr.RecordingStream(app)
        self.stream.save(str(path))
        self._return = 0.0
        self._path: list[np.ndarray] = []
        self.discrete_actions = pomdp.action_space().is_discrete
        self.manipulation = ManipulationLog(self.stream) if hasattr(pomdp, "real") else None
        self._log_geometry()

    def _log_geometry(self) -> None:
        rr, log, p = self.rr, self.stream.log, self.pomdp
        if isinstance(p, LightDark2D):
            s, m = p.size, WALL_MARGIN
            room = [[0, 0], [s, 0], [s, s], [0, s], [0, 0]]
            log(
                "world/room",
                rr.LineStrips2D([room], colors=[80, 80, 80], labels=["room"]),
                static=True,
            )
            goal = f"goal |x-{p.goal_x:g}|<{p.goal_halfwidth:g}"
            log(
                "world/goal",
                rr.Boxes2D(
                    mins=[p.goal_x - p.goal_halfwidth, 0],
                    sizes=[2 * p.goal_halfwidth, s],
                    colors=[[80, 190, 80, 90]],
                    labels=[goal],
                ),
                static=True,
            )
            log(
                "world/x_light",
                rr.Boxes2D(
                    mins=[s - m, 0], sizes=[m, s], colors=[[250, 220, 60, 90]], labels=["x light"]
                ),
                static=True,
            )
            log(
                "world/y_light",
                rr.Boxes2D(
                    mins=[0, s - m], sizes=[s, m], colors=[[90, 150, 250, 90]], labels=["y light"]
                ),
                static=True,
            )
        elif isinstance(p, LightDark1D):
            log(
                "world/goal",
                rr.Boxes2D(
                    mins=[-1, -0.5], sizes=[2, 1], colors=[[80, 190, 80, 90]], labels=["goal |y|<1"]
                ),
                static=True,
            )
            light = [[p.light_y, -1], [p.light_y, 1]]
            log(
                "world/light",
                rr.LineStrips2D([light], colors=[250, 200, 40], labels=["light y=5"]),
                static=True,
            )
        elif isinstance(p, Tiger):
            log(
                "world/doors",
                rr.Boxes2D(
                    mins=[[0, 0], [2, 0]],
                    sizes=[[1, 2], [1, 2]],
                    colors=[[150, 110, 70]],
                    labels=["left door", "right door"],
                ),
                static=True,
            )

    def _features(self, states: list[Any]) -> np.ndarray | None:
        feats = self.pomdp.entropy_features(states)
        if feats is None or feats.shape[1] > 2:
            return None
        return feats if feats.shape[1] == 2 else np.c_[feats, np.zeros(len(feats))]

    def __call__(self, rec: StepRecord, belief: ParticleBelief | None, state: Any) -> None:
        """Log step ``rec``; ``belief`` is the belief after the update (None once it
        ended), ``state`` the true state after the step."""
        rr, log = self.rr, self.stream.log
        self.stream.set_time("step", sequence=rec.step)
        self._log_search(rec)
        log("log", rr.TextLog(f"{rec.action} -> {rec.observation} (r={rec.reward:+.2f})"))
        if self.manipulation is not None:
            self.manipulation.log_step(self.pomdp, belief)
            return
        self._log_world(state, rec.observation)
        if belief is None:
            return
        xy = self._features(belief.states)
        if xy is not None:
            radii = 0.02 + 0.2 * np.sqrt(belief.weights / belief.weights.max())
            log("world/belief", rr.Points2D(xy, radii=radii, colors=BELIEF))
        else:
            mass: dict[str, float] = {}
            for s, w in zip(belief.states, belief.weights.tolist(), strict=True):
                key = self.pomdp.format_state(s)
                mass[key] = mass.get(key, 0.0) + w
            labels = [f"{k}: {v:.2f}" for k, v in mass.items()]
            log("belief/mass", labelled_bars(rr, list(mass.values()), labels))

    def _log_search(self, rec: StepRecord) -> None:
        rr, log = self.rr, self.stream.log
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
            names = list(rec.q)
            labels = [f"{a} {rec.q[a]:+.2f} ({rec.visits.get(a, 0)})" for a in names]
            chosen = names.index(rec.action) if rec.action in rec.q else None
            log("search/q_root", labelled_bars(rr, list(rec.q.values()), labels, chosen))
            log("search/q_best", rr.Scalars(max(rec.q.values())))
        if self.discrete_actions:  # stable action names: one series each
            for action, q in rec.q.items():
                log(f"search/q/{_path_part(action)}", rr.Scalars(q))
            for action, b in rec.bonus.items():
                log(f"search/bonus/{_path_part(action)}", rr.Scalars(b))

    def _log_world(self, state: Any, obs_text: str) -> None:
        rr, log = self.rr, self.stream.log
        if isinstance(self.pomdp, Tiger):
            side = state if isinstance(state, int | np.integer) else state[0]
            log(
                "world/true_state",
                rr.Points2D([[0.5 + 2 * int(side), 1.0]], radii=0.3, colors=TRUE, labels=["tiger"]),
            )
            log("world/observation", rr.TextDocument(f"observation: {obs_text}"))
            return
        true_xy = self._features([state])
        if true_xy is None:
            return
        self._path.append(true_xy[0])
        log("world/true_state", rr.Points2D(true_xy, radii=0.15, colors=TRUE, labels=["true"]))
        log("world/true_path", rr.LineStrips2D([np.array(self._path)], colors=TRUE))
        # The runner hands over the observation as formatted (3 decimals): enough to draw.
        numbers = [float(x) for x in _NUMBER.findall(obs_text)]
        if numbers:
            point = numbers[:2] if len(numbers) >= 2 else [numbers[0], 0.0]
            log(
                "world/observation",
                rr.Points2D([point], radii=0.12, colors=OBS, labels=[f"observed {obs_text}"]),
            )

    def close(self) -> None:
        """Finish the recording (its footer written: ``rerun rrd verify`` checks it)."""
        self.stream.flush()
        self.stream.disconnect()


class ManipulationLog:
    """The manipulation tasks' 3D log (module docstring), on ``stream``."""

    def __init__(self, stream: Any) -> None:
        self.stream = stream
        self.world_log: Any = None
        self.t = 0.0
        self.outcomes = 0
        self.frames = 0

    def log_step(self, pomdp: Any, belief: ParticleBelief | None) -> None:
        """Everything new since the last step: the real robot's runs, camera frames and
        the belief after the update."""
        from strug_manip.experiments.rerun_manip import WorldLogger, log_camera
        from strug_manip.world.views import cabinet_cloud

        real = pomdp.real
        if real is None:
            return
        if self.world_log is None:
            self.world_log = WorldLogger(self.stream, real.world, "world")
        for out in real.outcomes[self.outcomes :]:
            self.t = self.world_log.log_replay(out, self.t, every=2)
        self.outcomes = len(real.outcomes)
        self.stream.set_time("sim_time", duration=self.t)
        for frame in real.frames[self.frames :]:
            log_camera(self.stream, "camera", frame, cabinet_cloud(real.world, frame))
        self.frames = len(real.frames)
        if belief is not None and pomdp.worlds is not None:
            self._log_belief(pomdp, belief)

    def _log_belief(self, pomdp: Any, belief: ParticleBelief) -> None:
        from strug_manip.experiments.rerun_manip import log_joints
        from strug_manip.objects.hypotheses import BelievedJoint

        w = pomdp.worlds
        mass = np.zeros(len(w))
        for s, wt in zip(belief.states, belief.weights.tolist(), strict=True):
            mass[s.origin] += wt
        joints, weights, origins = [], [], []
        for i in np.flatnonzero(mass):
            spec, T = w.particles[i].spec, w.pose(int(i))
            for part in spec.movable_parts:
                j = BelievedJoint.of_part(part, 0.0, T)
                joints.append(j)
                weights.append(mass[i])
                # A drawer's axis is drawn from its handle (its origin means nothing).
                at = part.handle_at(0.0, T) if part.joint_type == "prismatic" and \
                    part.handle_pos is not None else j.origin  # fmt: skip
                origins.append(at)
        if joints:
            log_joints(
                self.stream, "belief/joints", joints, np.array(weights), origins=np.array(origins)
            )
