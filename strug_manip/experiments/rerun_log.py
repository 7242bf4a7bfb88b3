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
* ``search/q_table``: the same root Q values as a text table (action, Q as a bar of
  block characters, visits, bonus; the chosen action marked): rerun's ``BarChart``
  carries no per-bar labels, and long action names do not fit under bars;
* ``log``: one line per step, action -> observation.

The timelines are ``step`` (the episode's steps) and, for the manipulation tasks,
``sim_time`` (simulated seconds); rerun's wall-clock ``log_time`` is left out.

Every recording carries a blueprint (the layout the viewer opens with, :func:`blueprint`
and :func:`manipulation_blueprint`): the scene large, the step log, the labelled tables
and the statistics in tabs.

The manipulation tasks (:class:`ManipulationLog`) log instead, under ``world/``, the
robot's and the cabinet's MuJoCo geoms (static, per body) posed at every recorded
frame of every skill the real robot ran (timeline ``sim_time``, the episode's
simulated time), the head camera's images and the cabinet cloud it saw after each
step (``camera``, ``camera_cloud``), and the belief: every particle's joints of the
cabinet's parts as arrows on the cabinet, darker for more weight (``belief/joints``);
the belief per catalogued part, the mass of each kinematic hypothesis, as a text table
(``belief/parts``) and one named series each (``belief/part_mass/<part>/<hypothesis>``).
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


#: Width of a :func:`text_bar` at its largest [characters].
BAR_WIDTH = 12


def text_bar(value: float, top: float) -> str:
    """``value`` as a bar of block characters, :data:`BAR_WIDTH` long at ``|value| =
    top``, in eighths; a negative value's bar starts with a minus sign."""
    frac = min(abs(value) / top, 1.0) if top > 0 else 0.0
    eighths = round(frac * 8 * BAR_WIDTH)
    bar = (
        "\u2588" * (eighths // 8) + ("", *"\u258f\u258e\u258d\u258c\u258b\u258a\u2589")[eighths % 8]
    )
    return ("\u2212" if value < 0 and bar else "") + (bar or "\u00b7")


def _cell(text: str) -> str:
    """``text`` safe inside a markdown table cell."""
    return text.replace("|", "\\|")


def q_table(rec: StepRecord) -> str:
    """Markdown: one row per root action of ``rec`` (its Q value, as a bar and a number,
    its visits and bonus), the chosen action marked and in bold."""
    top = max((abs(q) for q in rec.q.values()), default=0.0)
    rows = [f"step {rec.step}: root Q per action (chosen: \u25b6)", "",
            "| | action | Q | | visits | bonus |", "|---|---|---|---:|---:|---:|"]  # fmt: skip
    for a, q in rec.q.items():
        mark, name = ("\u25b6", f"**{_cell(a)}**") if a == rec.action else ("", _cell(a))
        bonus = f"{rec.bonus[a]:+.3f}" if a in rec.bonus else ""
        rows.append(f"| {mark} | {name} | {text_bar(q, top)} | {q:+.2f} | "
                    f"{rec.visits.get(a, 0)} | {bonus} |")  # fmt: skip
    return "\n".join(rows)


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
        self.stream.set_log_time_enabled(False)  # timelines: step (and sim_time)
        self.stream.save(str(path))
        self._return = 0.0
        self._path: list[np.ndarray] = []
        self._named: set[str] = set()
        self.discrete_actions = pomdp.action_space().is_discrete
        self.manipulation = ManipulationLog(self.stream) if hasattr(pomdp, "real") else None
        self._log_geometry()
        if self.manipulation is None:  # the manipulation's, once its world exists
            self.stream.send_blueprint(blueprint(pomdp))

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
            log("search/q_table", rr.TextDocument(q_table(rec), media_type="text/markdown"))
            log("search/q_best", rr.Scalars(max(rec.q.values())))
        if self.discrete_actions:  # stable action names: one series each
            for action, q in rec.q.items():
                self._series(f"search/q/{_path_part(action)}", action, q)
            for action, b in rec.bonus.items():
                self._series(f"search/bonus/{_path_part(action)}", action, b)

    def _series(self, entity: str, name: str, value: float) -> None:
        """Log ``value`` on the series ``entity``, named ``name`` in plot legends."""
        if entity not in self._named:
            self._named.add(entity)
            self.stream.log(entity, self.rr.SeriesLines(names=[name]), static=True)
        self.stream.log(entity, self.rr.Scalars(value))

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
        self.named: set[str] = set()

    def log_step(self, pomdp: Any, belief: ParticleBelief | None) -> None:
        """Everything new since the last step: the real robot's runs, camera frames and
        the belief after the update."""
        from strug_manip.experiments.rerun_manip import WorldLogger, log_camera, scene_eye
        from strug_manip.world.views import cabinet_cloud

        real = pomdp.real
        if real is None:
            return
        if self.world_log is None:
            self.world_log = WorldLogger(self.stream, real.world, "world")
            self.stream.send_blueprint(manipulation_blueprint(scene_eye(real.world)))
        for out in real.outcomes[self.outcomes :]:
            self.t = self.world_log.log_replay(out, self.t, every=2)
        self.outcomes = len(real.outcomes)
        self.stream.set_time("sim_time", duration=self.t)
        for frame in real.frames[self.frames :]:
            log_camera(self.stream, "camera", frame, cabinet_cloud(real.world, frame))
        self.frames = len(real.frames)
        if belief is not None and pomdp.worlds is not None:
            self._log_belief(pomdp, belief)
            self._log_parts(pomdp, belief)

    def _log_parts(self, pomdp: Any, belief: ParticleBelief) -> None:
        """The mass of each kinematic hypothesis of each catalogued part (its particles'
        :meth:`entropy_key`; ``absent``: no such part, or an open cell): a table
        (``belief/parts``) and one named series each (``belief/part_mass/...``)."""
        import rerun as rr

        parts = pomdp.parts
        mass = [{h: 0.0 for h in p.hypotheses if h != "shelf"} for p in parts]
        for s, wt in zip(belief.states, belief.weights.tolist(), strict=True):
            key = pomdp.entropy_key(s)
            for k in range(len(parts)):
                kind = "absent" if key is None or key[k] is None else str(key[k])
                mass[k][kind] = mass[k].get(kind, 0.0) + wt
        total = max(float(np.sum(belief.weights)), 1e-300)
        rows = [f"belief after the step: ESS {belief.ess():.1f} of {len(belief)} particles",
                "", "| part | hypothesis | mass | |", "|---|---|---|---:|"]  # fmt: skip
        for k, (part, by_kind) in enumerate(zip(parts, mass, strict=True)):
            for j, (kind, m) in enumerate(by_kind.items()):
                p = m / total
                where = part.describe() if j == 0 else ""
                rows.append(f"| {where} | {kind} | {text_bar(p, 1.0)} | {p:.2f} |")
                entity = f"belief/part_mass/part{k}/{_path_part(kind)}"
                if entity not in self.named:
                    self.named.add(entity)
                    name = f"{part.describe()} {kind}"
                    self.stream.log(entity, rr.SeriesLines(names=[name]), static=True)
                self.stream.log(entity, rr.Scalars(p))
        self.stream.log(
            "belief/parts", rr.TextDocument("\n".join(rows), media_type="text/markdown")
        )

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


# --- blueprints: the layout the viewer opens a recording with ----------------------------

#: Names of the views of :func:`manipulation_blueprint`, as the viewer titles them.
MANIPULATION_VIEWS = (
    "scene",
    "head camera: colour",
    "head camera: depth [m]",
    "belief per part",
    "Q per action",
    "step log",
    "return",
    "search",
    "Q per action over steps",
    "belief per part over steps",
)
#: Names of the views of :func:`blueprint` (a toy domain's): every domain's, then those
#: only the Tigers' (``observation``, ``belief mass``) or the finite action spaces' have.
TOY_VIEWS = (
    "world",
    "Q per action",
    "step log",
    "return",
    "search",
    "Q bars",
    "Q per action over steps",
    "observation",
    "belief mass",
)


def _statistics(rrb: Any, *extra: Any) -> Any:
    """Tabs of time series: the return and reward, the search's statistics, ``extra``."""
    return rrb.Tabs(
        rrb.TimeSeriesView(name="return", origin="episode"),
        rrb.TimeSeriesView(
            name="search",
            origin="search",
            contents=["+ $origin/**", "- $origin/q/**", "- $origin/bonus/**"],
        ),
        *extra,
    )


def _step_log(rrb: Any) -> Any:
    return rrb.TextLogView(
        name="step log",
        origin="log",
        columns=rrb.TextLogColumns(text_log_columns=["Body"]),
    )


def _panels(rrb: Any, timeline: str) -> tuple[Any, ...]:
    """Side panels collapsed (the viewport gets the room), the time bar on ``timeline``."""
    return (
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline=timeline),
    )


def manipulation_blueprint(eye: tuple[Sequence[float], Sequence[float]] | None = None) -> Any:
    """The manipulation recording's layout (:data:`MANIPULATION_VIEWS`).

    Left, large: the 3D ``scene`` (the robot, the cabinet, the believed joints, the
    head camera's frustum and cloud; ``eye``: where it looks from and at, world [m]),
    the ``step log`` below it. Right: the head camera's colour and depth side by side,
    the ``belief per part`` and ``Q per action`` tables, and tabs of time series (the
    return, the search's statistics, Q per action and the belief per part over the
    steps). The time bar starts on the ``step`` timeline.
    """
    import rerun.blueprint as rrb

    controls = None
    if eye is not None:
        controls = rrb.EyeControls3D(
            kind=rrb.Eye3DKind.Orbital, position=eye[0], look_target=eye[1], eye_up=[0, 0, 1]
        )
    scene = rrb.Spatial3DView(
        name="scene",
        origin="world",
        contents=[
            "+ /world/**",
            "+ /belief/joints",
            "+ /camera/**",
            "- /camera/image/depth",  # drawn as the cloud instead
            "+ /camera_cloud",
        ],
        background=rrb.BackgroundKind.GradientBright,
        eye_controls=controls,
    )
    camera = rrb.Horizontal(
        rrb.Spatial2DView(
            name="head camera: colour", origin="camera/image", contents="$origin/rgb"
        ),
        rrb.Spatial2DView(
            name="head camera: depth [m]", origin="camera/image", contents="$origin/depth"
        ),
    )
    stats = _statistics(
        rrb,
        rrb.TimeSeriesView(name="Q per action over steps", origin="search/q"),
        rrb.TimeSeriesView(name="belief per part over steps", origin="belief/part_mass"),
    )
    right = rrb.Vertical(
        camera,
        rrb.TextDocumentView(name="belief per part", origin="belief/parts"),
        rrb.TextDocumentView(name="Q per action", origin="search/q_table"),
        stats,
        row_shares=[3, 3, 3, 2],
    )
    left = rrb.Vertical(scene, _step_log(rrb), row_shares=[3, 1])
    return rrb.Blueprint(
        rrb.Horizontal(left, right, column_shares=[3, 2]),
        *_panels(rrb, "step"),
        auto_views=False,
    )


def blueprint(pomdp: Any) -> Any:
    """A toy domain's layout (:data:`TOY_VIEWS`): the 2D ``world`` (geometry, true
    state, observation, belief) and the ``step log`` left; the ``Q per action`` table
    and tabs of time series and bars right."""
    import rerun.blueprint as rrb

    tabs = [rrb.Spatial2DView(name="Q bars", origin="search/q_root")]
    if pomdp.action_space().is_discrete:
        tabs.append(rrb.TimeSeriesView(name="Q per action over steps", origin="search/q"))
    bounds = None
    if isinstance(pomdp, LightDark2D):  # the room and a margin for what strays outside
        span = [-1.0, pomdp.size + 1.0]
        bounds = rrb.VisualBounds2D(x_range=span, y_range=span)
    world = rrb.Spatial2DView(name="world", origin="world", visual_bounds=bounds)
    left = [world]
    if isinstance(pomdp, Tiger):  # the observation is text; the belief, bars per state
        left = [
            rrb.Horizontal(
                world,
                rrb.Vertical(
                    rrb.TextDocumentView(name="observation", origin="world/observation"),
                    rrb.Spatial2DView(name="belief mass", origin="belief/mass"),
                    row_shares=[1, 3],
                ),
            )
        ]
    right = rrb.Vertical(
        rrb.TextDocumentView(name="Q per action", origin="search/q_table"),
        _statistics(rrb, *tabs),
    )
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(*left, _step_log(rrb), row_shares=[3, 1]), right, column_shares=[3, 2]
        ),
        *_panels(rrb, "step"),
        auto_views=False,
    )
