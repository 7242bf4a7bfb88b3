"""The twins' POMDP of Shelf, OpenDrawer and OpenDoor (:class:`ManipulationPOMDP`): what
the planners simulate. It holds no belief and no real world: the real Fetch and
cabinet are an environment of their own (:mod:`.real`), and a task (:mod:`.tasks`) is
the two together.

1. The real robot's environment starts an episode (:mod:`.episode_setup`) and hands the
   model what the head camera saw from :data:`VIEWS` poses (:class:`EpisodeView`:
   frames, the point naming the target, where the object rests, the scene's layout).
2. ``initial_belief``: perception turns those renders into particles (:mod:`.belief`),
   never reading the true cabinet (but for the oracle, :mod:`.oracle`, whose only
   particle is the true cabinet the environment hands over); their parts are
   catalogued by where they are (:mod:`.catalogue`) and the episode's action list made.
3. ``step`` on a particle runs the skill on that particle's planning twin
   (:mod:`.worlds`, cached; the skills of an action: :mod:`.grounding`). What a search
   takes from the current real step (the particle each opening follows, the refused
   actions) is a value, :class:`.catalogue.Root`, that the environment sets after each
   belief update.

Rewards (:mod:`.rules`): +10 and the episode ends when the object rests inside the
target part (not held); -10 and it ends when the cabinet's base is more than 0.1 m from
where it stood at the start of the episode; 0 otherwise; at most :data:`MAX_STEPS`
steps. The discount is 0.95 (one wasted step costs 5 % of the +10, as on the toy
domains' scale, so the planners prefer short plans without ignoring a probe that
prevents a -10).

Observations: see :mod:`.state`. Inside a search the twin's outcome determines the
observation (the status, whether the hand holds something, the handle's motion), so
simulated observations carry only that key and are weighted by it; real observations
carry the head camera's cloud as well, weighted by the quantile-Hausdorff likelihood of
:mod:`perception.likelihood` against each particle's predicted cloud, times the key's
likelihood.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Hashable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from perception.likelihood import log_likelihood
from perception.parts import Perceiver
from planners.errors import ConfigError, UnknownNameError, check_positive_int
from planners.particles import ParticleBelief
from planners.pomdp import ActionSchema, ActionSpace, GenerativePOMDP, Step
from planners.tru import execute_plan
from strug_manip.control import ControlContext
from strug_manip.control.skills import HANDLE_RADIUS, holds_object
from strug_manip.domains.manipulation import belief as belief_mod
from strug_manip.domains.manipulation.actions import (
    DEFAULT_PROBES,
    SKILLS,
    TABLE,
    CataloguePart,
    ManipAction,
    action_list,
    describe,
)
from strug_manip.domains.manipulation.catalogue import (
    Catalogue,
    Root,
    build_catalogue,
)
from strug_manip.domains.manipulation.episode_setup import TASK_KINDS
from strug_manip.domains.manipulation.grounding import (
    position,
    skills,
    twin_run,
)
from strug_manip.domains.manipulation.plans import plan_candidates, prior_scores, relevance
from strug_manip.domains.manipulation.rules import BEFORE_MOTION_CODES, open_enough
from strug_manip.domains.manipulation.state import (
    NOT_APPLICABLE,
    REAL,
    STATUS_CODES,
    ManipObservation,
    ManipState,
)
from strug_manip.domains.manipulation.twin_keys import (
    TwinConfusion,
    load_confusion,
    twin_keys_rule,
)
from strug_manip.domains.manipulation.worlds import ParticleWorlds, Timers
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import CameraFrame, WorldState
from strug_manip.world.views import LookPose

#: Head-camera views perception gets.
VIEWS = 4
#: Steps per episode (the paper's).
MAX_STEPS = 10
#: Particles drawn from perception (the runner's ``n_particles`` is capped to this:
#: every particle is a compiled world and a twin).
MAX_PARTICLES = 24
#: Likelihood of a simulated observation whose status or holding differs [log].
MISMATCH = math.log(0.05)


@dataclass(frozen=True)
class EpisodeView:
    """What the robot saw when the episode began: what the model's initial belief is
    made from (nothing of the true cabinet's description).

    Attributes:
        frames: the head camera's frames from the :data:`VIEWS` look poses.
        clouds: per frame, its points on the cabinet, world (N, 3) [m].
        point: the point of the cabinet front naming the target part, world (3,) [m].
        home: where the object rests on the table, (4, 4) (``Place(table)`` puts it
            back there).
        config: the scene (the table, the object and where the cabinet stands).
        look_pose: the head pose the real clouds after each step are taken from.
        truth: the real cabinet as a particle, handed over for the oracle alone
            (:mod:`.oracle`: the initial belief is this particle instead of
            perception's); None for every robot that perceives.
    """

    frames: tuple[CameraFrame, ...]
    clouds: tuple[np.ndarray, ...]
    point: np.ndarray
    home: np.ndarray
    config: SceneConfig
    look_pose: LookPose
    truth: belief_mod.Particle | None = None


class ManipulationPOMDP(GenerativePOMDP):
    """The twins' POMDP of one manipulation task (module docstring).

    Args:
        task: ``shelf``, ``opendrawer`` or ``opendoor`` (the part kinds and the plans).
        particles: belief particles from perception (at most :data:`MAX_PARTICLES`).
        probes: the probe skills offered per part (``Push``, ``PullV``, ``PullH``).
        max_steps: the episode's step limit.
        ctx: the control context the twins share (default: a new one).
        twin_keys: how the real update weighs the real key's status against a twin's:
            ``confusion`` (the measured P(real status | twin status), :mod:`.twin_keys`)
            or ``match`` (:data:`MISMATCH` for any difference); default
            :func:`.twin_keys.twin_keys_rule` (the ``STRUG_TWIN_KEYS`` environment
            variable, else :data:`.twin_keys.DEFAULT_TWIN_KEYS`).

    Raises:
        ConfigError, UnknownNameError: a bad argument, naming it.
    """

    discount = 0.95
    max_steps = MAX_STEPS
    max_abs_reward = 10.0
    discrete_observations = False
    #: Never resample the real belief: every particle is a distinct cabinet model whose
    #: twin is deterministic, so copies of the likeliest add nothing, and a model
    #: resampled away is gone for good (no new ones are drawn mid-episode): after one
    #: surprising grasp_lost, a belief of copies of one wrong model cannot recover.
    resample_ess = 1e-9

    def __init__(
        self,
        task: str,
        particles: int = MAX_PARTICLES,
        probes: Sequence[str] = DEFAULT_PROBES,
        max_steps: int = MAX_STEPS,
        ctx: ControlContext | None = None,
        twin_keys: str | None = None,
    ) -> None:
        if task not in TASK_KINDS:
            raise UnknownNameError("task", task, list(TASK_KINDS))
        self.task = task
        self.max_steps = check_positive_int("max_steps", max_steps)
        self.particles = check_positive_int("particles", particles)
        for p in probes:
            if p not in ("Push", "PullV", "PullH"):
                raise UnknownNameError("probe", p, ["Push", "PullV", "PullH"])
        self.probes = tuple(probes)
        self.ctx = ControlContext() if ctx is None else ctx
        self.twin_keys = twin_keys_rule(twin_keys)
        #: The real update's status confusion (None: the exact-match rule).
        self.confusion: TwinConfusion | None = (
            load_confusion() if self.twin_keys == "confusion" else None
        )
        self._perceiver: Perceiver | None = None
        self.view: EpisodeView | None = None
        self.worlds: ParticleWorlds | None = None
        self.cat = Catalogue()
        self.root = Root()
        self.timers = Timers()
        self._space = self._make_space((ManipAction("Pick", grasp="top"),))

    @property
    def parts(self) -> tuple[CataloguePart, ...]:
        """The episode's catalogued parts (:attr:`.catalogue.Catalogue.parts`)."""
        return self.cat.parts

    # --- the episode's set-up ------------------------------------------------------------
    def begin(self, view: EpisodeView, timers: Timers) -> None:
        """A new episode: what the robot saw (``view``), and where its time is counted."""
        self.free_worlds()
        self.view, self.timers = view, timers

    def initial_belief(self, rng: np.random.Generator, n_particles: int) -> ParticleBelief:
        """Particles from perception on the head camera's views (:meth:`begin`); the
        oracle's: the true cabinet alone (:attr:`EpisodeView.truth`)."""
        view = self._need_view()
        c = view.config
        particles = [view.truth] if view.truth is not None else self._perceive(rng, n_particles)
        t0 = time.perf_counter()
        if self.worlds is not None:
            self.worlds.close()
        self.worlds = w = ParticleWorlds(particles, c, self.ctx)
        self.cat = build_catalogue(w, TASK_KINDS[self.task], view.point)
        parts = self.cat.parts
        self._space = self._make_space(action_list(parts, self.task, self.probes))
        self.timers.setup += time.perf_counter() - t0
        belief = ParticleBelief.from_states([ManipState(i, w.initial[i], 0) for i in range(len(w))])
        self.root = Root.of(self.cat, belief, tuple(part.holders for part in parts))
        return belief

    def _perceive(self, rng: np.random.Generator, n_particles: int) -> list[belief_mod.Particle]:
        """Perception's particles from the head camera's views (:func:`perceive`)."""
        t0 = time.perf_counter()
        if self._perceiver is None:
            self._perceiver = Perceiver()
        m = min(n_particles, self.particles)
        out = perceive(self._need_view(), self._perceiver, self.task, m, rng)
        self.timers.perception += time.perf_counter() - t0
        return out

    def sample_initial_state(self, rng: np.random.Generator) -> ManipState:
        """A particle of b0 (the model's own states are its particles; the real
        cabinet is the environment's)."""
        w = self.need_worlds()
        i = int(rng.integers(len(w)))
        return ManipState(i, w.initial[i], 0)

    # --- the protocol ----------------------------------------------------------------
    def action_space(self) -> ActionSpace:
        """The current episode's actions (before the first belief: Pick alone)."""
        return self._space

    def discrete_states(self, states: list[Any]) -> bool:
        return True  # finitely many, compared by value (ManipState)

    def entropy_key(self, s: Any) -> Hashable:
        """The model class of ``s``'s particle: per catalogued part, the kinematic
        hypothesis it holds for it (None: it has no such part, or an open cell, empty
        space in which nothing moves: no probe tells it from its absence). Every
        particle is a distinct state (its own geometry, its own simulator snapshot), so
        the entropy of the states would be the log of their number however sure the
        robot is of what matters to a skill; the classes are what probes can tell
        apart."""
        return self.cat.classes[s.origin] if s.origin >= 0 else None

    def observation_key(self, o: Any) -> Hashable:
        return o.key

    def check_observation(self, o: Any) -> None:
        if not isinstance(o, ManipObservation):
            raise ConfigError(f"{self.name}: expected a ManipObservation, got {o!r}")

    def step(self, s: ManipState, a: Hashable, rng: np.random.Generator) -> Step:
        """``a`` on particle state ``s``'s twin (cached by particle, state, action and
        the models the action is planned in, :meth:`.catalogue.Root.plan_models`)."""
        a = self.check_action(a)
        if s.origin == REAL:
            raise ConfigError(
                f"{self.name}: the model steps particles; the real robot is "
                "the environment's (strug_manip.domains.manipulation.real)"
            )
        w = self.need_worlds()
        key = (s.origin, s.sim.key, a, self.root.plan_models(a))
        hit = w.outcomes.lookup(key)
        if hit is None:
            t0 = time.perf_counter()
            hit = self._simulate(s.origin, s.sim, a)
            w.timers.twin += time.perf_counter() - t0
            w.outcomes.store(key, hit)
        sim, okey, r, terminal, summary = hit
        done = terminal or s.t + 1 >= self.max_steps
        return Step(ManipState(s.origin, sim, s.t + 1, okey),
                    ManipObservation(okey, None, summary), r, done)  # fmt: skip

    def applicable(self, s: Any, a: Hashable) -> bool:
        """False when ``a`` cannot start in particle state ``s``; the solvers then leave
        it out of the node (a no-op costs one of the episode's 10 steps).

        Decided by the twin's outcome when the search has simulated it already (not
        :data:`NOT_APPLICABLE`), else by what the twin checks before anything moves:

        * one hand: a grasping skill with the object held, a ``Place`` without it;
        * a ``Place`` into a part ``s``'s model lacks, or one not open enough to place
          in (no placement pose);
        * an opening or probe on a part whose handle has moved more than
          ``HANDLE_RADIUS`` (:mod:`strug_manip.control.skills`) in ``s`` from where
          the model put it: the action's grasps are at the model's initial handle,
          with the cabinet where it stands (:func:`.grounding.skills`), so there is
          nothing to grasp there (the part is open). A part ``s``'s model lacks stays
          applicable: acting on it is how the robot learns that the model is wrong.

        At the root (the states of the current real step, :attr:`.catalogue.Root.now`),
        an action the real robot refuses (:attr:`.catalogue.Root.refused`: it failed on
        the full robot in a way that repeats itself, and the cabinet and the hold are
        still as they were then, :attr:`.real.RealEpisode.refused`) is refused whatever
        the twins say, as
        long as it would follow the same particle's grasp and joint: the robot would
        plan it against the same model in nearly the same state and fail the same way
        again. The twins and the full robot disagree on such actions, and when every
        weighted particle predicted the failure, or none did, the observation moves no
        weight and the search chooses the action again (on held-out door episodes, one
        slipping opening until the steps ran out, and a ``Place`` stopped at
        ``cabinet_moved`` until the stops added up to a drag). When the belief moves
        the hypothesis to another particle, the opening follows that particle's joint
        and is offered again.

        The real state: always True.
        """
        if s.origin == REAL:
            return True
        a = self.check_action(a)
        rep = self.root.rep(a)
        if s.t == self.root.now and (a, rep) in self.root.refused:
            return False
        w = self.need_worlds()
        key = (s.origin, s.sim.key, a, self.root.plan_models(a))
        hit = w.outcomes.get(key)  # a peek: the search's hit rate counts steps only
        if hit is not None:
            return hit[1][0] != STATUS_CODES[NOT_APPLICABLE]
        can = w.can_start.get(key)
        if can is None:
            can = self._can_start(s, a)
            w.can_start.store(key, can)
        return can

    def _can_start(self, s: ManipState, a: ManipAction) -> bool:
        """:meth:`applicable` without a simulated outcome (its checks, in order)."""
        w = self.need_worlds()
        tw = w.twins[s.origin]
        tw.restore(s.sim)
        world = tw.world
        if (a.skill == "Place") != holds_object(world):
            return False
        if a.skill == "Pick" or a.part == TABLE:
            return True
        if a.skill == "Place":  # a pose to place at (the skills the twin would try)
            return bool(self.skills(s.origin, a, s.sim)[0])
        link = self.parts[a.part].links[s.origin]
        if link is None:
            return True
        part = w.particles[s.origin].spec.part(link)
        q, T = position(world, part.joint), world.cabinet_pose()
        if part.handle_pos is None:
            return True
        q0 = w.particles[s.origin].q.get(part.joint, 0.0)
        moved = np.linalg.norm(part.handle_at(q, T) - part.handle_at(q0, T))
        return bool(moved < HANDLE_RADIUS)

    def obs_loglik(self, o: Any, s_next: Any, a: Hashable) -> float:
        return float(self.obs_loglik_many(o, [s_next], a)[0])

    def obs_loglik_many(self, o: Any, states: list[Any], a: Hashable) -> np.ndarray:
        """The key's likelihood per state, times (real observations) the cloud's. A
        real key's status is weighed by :attr:`confusion` when there is one (a search's
        keys, twin against twin, by the exact match). A real key is no evidence where
        nothing moved, or where the robot stopped on its way to the part
        (:attr:`.state.ManipObservation.on_the_way`)."""
        a = self.check_action(a)
        w = self.need_worlds()
        real = o.cloud is not None
        if real and (int(o.key[0]) in BEFORE_MOTION_CODES or o.on_the_way):  # no evidence
            out = np.zeros(len(states))
        else:
            conf = self.confusion if real else None
            # Where the hand carried the object to or from the table is the full
            # robot's, which the twins' floating hand does not reproduce: a real Pick's
            # object motion 8 bins off every twin's dropped the true model, whose twin
            # was farther off than others (OpenDoor 10166).
            motion = not (real and (a.skill == "Pick" or a.part == TABLE))
            out = np.array([key_loglik(o.key, s, conf, motion) for s in states])
        if o.cloud is None or not o.news:
            return out
        t0 = time.perf_counter()
        pose = self._need_view().look_pose
        clouds = [w.predicted_cloud(s.origin, s.sim, pose) for s in states]
        t1 = time.perf_counter()
        # Particles of one model in one cabinet state share a cloud (the same object
        # from the cache): each distinct cloud is compared once.
        distinct = {id(c): c for c in clouds if len(c)}
        ll = dict.fromkeys(distinct, 0.0)
        if distinct and len(o.cloud):
            ll = dict(zip(distinct, log_likelihood(o.cloud, list(distinct.values())), strict=True))
        w.timers.render += t1 - t0
        w.timers.likelihood += time.perf_counter() - t1
        # A model whose camera sees no cabinet at all explains no cloud.
        return out + np.array([ll.get(id(c), -1e3) for c in clouds])

    def plan_for(self, s: Any, rng: np.random.Generator) -> list[Hashable]:
        """The uncertainty-free plan of particle ``s`` (:mod:`.plans`): the first of its
        plans that earns the +10 when simulated on ``s`` (a forward search on that
        particle), else its own hypothesis's; no search when the part needs no opening."""
        plans, opened = plan_candidates(self.task, self.cat, s, self._holding, self._open_enough)
        if opened or not plans:
            return plans[0] if plans else []
        for plan in plans:
            if execute_plan(self, s, plan, rng, self.discount)[0] > 0:
                return plan
        return plans[0]

    def action_prior(
        self, states: Sequence[Any], weights: Sequence[float], actions: Sequence[Hashable]
    ) -> list[float]:
        """Task relevance per action, shape ``(len(actions),)``: :func:`.plans.relevance`
        summed over the node's particles by weight, cached per particle state."""

        def of(s: ManipState) -> dict[ManipAction, float]:
            acts = self._space.discretized
            return relevance(self.task, self.cat, s, acts, self._holding, self._open_enough)

        return prior_scores(states, weights, actions, self.need_worlds().relevance, of)

    def format_state(self, s: Any) -> str:
        who = "real" if s.origin == REAL else f"model {s.origin}"
        return f"{who}, step {s.t}"

    def format_obs(self, o: Any) -> str:
        return o.summary or str(o.key)

    def summarize_belief(self, belief: ParticleBelief) -> str:
        """The target part's hypotheses by weight, and the ESS."""
        mass: dict[str, float] = {}
        for s, wt in zip(belief.states, belief.weights.tolist(), strict=True):
            k = self.cat.target_index(s.origin)
            kind = "none" if k is None else self.cat.own_kind(s.origin, k)
            mass[kind] = mass.get(kind, 0.0) + wt
        top = ", ".join(f"{k} {v:.2f}" for k, v in sorted(mass.items(), key=lambda kv: -kv[1]))
        return f"target: {top}; ESS {belief.ess():.1f} of {len(belief)}"

    def report(self) -> dict[str, Any]:
        """Where this episode's time went [s] and the caches' hit rates."""
        w = self.worlds
        out: dict[str, Any] = {"time": self.timers.as_dict(), "twin_keys": self.twin_keys}
        if w is not None:
            out["time"].update({k: v for k, v in w.timers.as_dict().items() if v})
            out["outcome_cache"] = {"hits": w.outcomes.hits, "misses": w.outcomes.misses,
                                    "hit_rate": round(w.outcomes.hit_rate, 3)}  # fmt: skip
            out["cloud_cache_hit_rate"] = round(w.clouds.hit_rate, 3)
        return out

    def close(self) -> None:
        """Free the episode's worlds."""
        self.free_worlds()

    def free_worlds(self) -> None:
        """Free the particles' worlds (:mod:`.worlds`)."""
        if self.worlds is not None:
            self.worlds.close()
        self.worlds = None

    # --- simulation ------------------------------------------------------------------------
    def skills(self, i: int, a: ManipAction, sim: WorldState, holder: int | None = None):
        """:func:`.grounding.skills` in this episode (its catalogue, its root)."""
        home = self._need_view().home
        return skills(self.need_worlds(), self.cat, self.root, home, i, a, sim, holder)

    def _simulate(self, i: int, sim: WorldState, a: ManipAction):
        """:func:`.grounding.twin_run` in this episode, planned with :meth:`skills`:
        (next sim, observation key, reward, terminal, summary)."""
        plan_for = functools.partial(self.skills, i, a, sim)
        return twin_run(self.need_worlds(), self.cat, i, a, sim, self.root.plan_models(a), plan_for)

    def _holding(self, s: ManipState) -> bool:
        tw = self.need_worlds().twins[s.origin]
        tw.restore(s.sim)
        return holds_object(tw.world)

    def _open_enough(self, s: ManipState, k: int) -> bool:
        w = self.need_worlds()
        link = self.parts[k].links[s.origin]
        tw = w.twins[s.origin]
        tw.restore(s.sim)
        world = tw.world
        q = position(world, w.particles[s.origin].spec.part(link).joint)
        T_now = world.cabinet_pose()
        return open_enough(w.particles[s.origin].spec, link, q, T_now)

    def _make_space(self, actions: tuple[ManipAction, ...]) -> ActionSpace:
        parts = self.cat.parts
        self._known = frozenset(actions)  # check_action's O(1) membership (a hot path)
        return ActionSpace(
            schemas=tuple(ActionSchema(s) for s in SKILLS),
            discretized=actions,
            describe=lambda a: describe(a, parts),
        )

    def check_action(self, a: Hashable) -> ManipAction:
        """``a`` as one of this episode's actions.

        Raises:
            UnknownNameError: it is not one, listing them.
        """
        if not isinstance(a, ManipAction) or a not in self._known:
            raise UnknownNameError(
                "action", str(a), [self._space.name(x) for x in self._space.discretized]
            )
        return a

    def _need_view(self) -> EpisodeView:
        if self.view is None:
            raise ConfigError(f"{self.name}: no episode yet (reset its environment first)")
        return self.view

    def need_worlds(self) -> ParticleWorlds:
        """The particles' worlds (:mod:`.worlds`; ConfigError before the first belief)."""
        if self.worlds is None:
            raise ConfigError(f"{self.name}: no belief yet (call initial_belief first)")
        return self.worlds


def perceive(
    view: EpisodeView, perceiver: Perceiver, task: str, particles: int, rng: np.random.Generator
) -> list[belief_mod.Particle]:
    """``particles`` particles from perception on ``view``'s frames (:mod:`.belief`);
    on Shelf each with the open cell at the target point read off the clouds."""
    c = view.config
    cfg = belief_mod.BeliefConfig(particles=particles)
    scene = (c.cabinet_distance, c.cabinet_lateral, c.stand_height)
    out = belief_mod.initial_belief(
        [(f.rgb, f.depth, f.T_world_camera, f.fovy) for f in view.frames],
        perceiver, rng, cfg, scene=scene,
    )  # fmt: skip
    if task == "shelf":  # the network finds no open cells: read them off the cloud
        out = [belief_mod.with_open_cell(p, view.point, list(view.clouds), scene) for p in out]
    return out


def key_loglik(
    key: tuple[float, ...],
    s: ManipState,
    confusion: TwinConfusion | None = None,
    motion: bool = True,
) -> float:
    """How likely particle state ``s`` (after the action) makes an observation with
    ``key`` [log]: the status by ``confusion`` (log P(key's status | ``s``'s twin's
    status)) or, without one, a mismatched status costs :data:`MISMATCH`; a mismatched
    grip costs :data:`MISMATCH`; the handle's motion (if ``motion``) is Gaussian with
    one bin's standard deviation per axis."""
    mine = s.last
    if not mine:
        return 0.0
    if confusion is None:
        ll = MISMATCH * ((key[0] != mine[0]) + (key[1] != mine[1]))
    else:
        ll = confusion.loglik(mine[0], key[0]) + MISMATCH * (key[1] != mine[1])
    if not motion:
        return float(ll)
    d = np.subtract(key[2:], mine[2:])
    return float(ll - 0.5 * d @ d)
