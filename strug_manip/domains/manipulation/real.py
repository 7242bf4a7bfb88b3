"""The real Fetch and cabinet as an :class:`~planners.environment.Environment`
(:class:`RealEnvironment`): what executes the planners' actions in a manipulation
episode.

- ``reset``: a new real cabinet and its target (:mod:`.episode_setup`); the head camera
  looks from :data:`~.model.VIEWS` poses and the twins' POMDP is handed what it saw
  (:meth:`.model.ManipulationPOMDP.begin`), never the true cabinet.
- ``execute``: the full Fetch runs the full skills, planned against the model the
  belief holds likeliest for the action (:meth:`RealEnvironment.plan_models`), and the
  head camera's point cloud is rendered: the observation.
- ``condition``: the belief given what the robot knows for certain
  (:mod:`.conditioning`); the belief is kept, since the next real step plans against
  its likeliest models, and the twins' POMDP gets the next search's
  :class:`.catalogue.Root` (the particle each opening follows, the refused actions).

The oracle (``oracle=True``, :mod:`.oracle`) hands the model the real cabinet as its
only particle and has that particle take over the real state after every step. Every
episode records its belief's health against the true cabinet (:mod:`.health`; the
report's ``health``), reading only what the episode computes anyway.
"""

from __future__ import annotations

import collections
import functools
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from perception.likelihood import voxel_thin
from planners.environment import Executed
from planners.errors import ConfigError
from planners.particles import ParticleBelief
from planners.pomdp import Step
from strug_manip.control import Outcome, Status
from strug_manip.control.skills import holds_object
from strug_manip.domains.manipulation import conditioning
from strug_manip.domains.manipulation.actions import SAME_PART, TABLE, ManipAction, label
from strug_manip.domains.manipulation.catalogue import (
    PLAN_MODELS,
    Root,
    representatives,
)
from strug_manip.domains.manipulation.episode_setup import draw_episode, handles
from strug_manip.domains.manipulation.grounding import (
    first_feasible,
    handle_point,
    in_turn,
    position,
    reward,
)
from strug_manip.domains.manipulation.health import HealthRecorder, RealStep
from strug_manip.domains.manipulation.model import EpisodeView, ManipulationPOMDP
from strug_manip.domains.manipulation.oracle import take_over, true_particle
from strug_manip.domains.manipulation.rules import (
    BEFORE_MOTION,
    CANNOT_START,
    REPEATS_ITSELF,
    UNCHANGED,
)
from strug_manip.domains.manipulation.state import (
    NOT_APPLICABLE,
    REAL,
    STATUS_CODES,
    ManipObservation,
    ManipState,
    observation_key,
)
from strug_manip.domains.manipulation.worlds import Timers
from strug_manip.objects.generator import PartSpec
from strug_manip.world.sim import CameraFrame, ManipulationWorld, WorldState
from strug_manip.world.views import cabinet_cloud, look_poses, take_views

#: A ``no_motion_plan`` stop of one action (with the particle it follows) this many
#: times in a row since the last step that ended ``ok`` refuses it as
#: :data:`~.rules.REPEATS_ITSELF` would: the robot did not move, so the next try plans
#: the same motion from the same state with another planner seed, and where two seeds
#: found no path in the planner's budget a third rarely does (a held-out door episode
#: spent seven steps on one ``Place`` that way).
NO_PLAN_TRIES = 2
#: A catalogued part and a true part are one part when each is the other's nearest and
#: their handles are this close [m] (:meth:`RealEnvironment.counterpart`). Perception
#: names a bar handle anywhere along the bar: in OpenDrawer episode 9870 the catalogued
#: point lay 6.1 cm from the true bar's centre, past :data:`~.actions.SAME_PART`, so the
#: real front of the drawer just opened was passed to no particle; the likeliest held
#: it 3 cm further out than the real one, and the Place set the object on its front
#: and tipped the cabinet. Catalogued parts stand at least ``SAME_PART`` apart, and
#: the nearest of two takes the true part, so twice that is not ambiguous.
MATCH_RADIUS = 2 * SAME_PART


@dataclass
class RealEpisode:
    """The real world of the current episode (nothing a planner may read).

    Attributes:
        world: the scene with the full Fetch.
        seed: the cabinet's generator seed.
        target: the target part's link in the true cabinet.
        point: the point of the cabinet front that names it, world (3,) [m].
        frames: the head-camera frames taken so far (the initial views, then one per
            step), for logs.
        outcomes: the full robot's outcomes, one per step that ran a skill.
        labels: per outcome, the skill as the report names it (:func:`.actions.label`:
            ``Place(table)`` for the Place back onto the table, else the skill).
        weighed: the cabinet's joints (to the mm, as bytes) when the belief last
            weighed a cloud (``ManipObservation.news``); empty before the first.
        refusals: the actions that failed on the full robot in a way that repeats
            itself (:data:`~.rules.REPEATS_ITSELF`, or ``no_motion_plan``
            :data:`NO_PLAN_TRIES` times in a row), each with the particle it followed
            (:meth:`.catalogue.Root.rep`), and the cabinet's coordinates (rounded, as
            :meth:`~strug_manip.world.sim.ManipulationWorld.cabinet_key`) and whether
            the hand held the object when it failed; :attr:`refused` those that stand
            now.
        unplanned: per such (action, particle), its ``no_motion_plan`` stops since the
            last step that ended ``ok``.
        now: the step count of the states after the last real step (the root's).
        still: the last real step stopped before anything moved
            (:data:`~.rules.BEFORE_MOTION`).
        ended: the catalogued part whose real opening the last step ended where the
            part met its end (:attr:`.Outcome.met_end`), else None.
        handles: the true cabinet's graspable parts' handles where they were when the
            episode began, world (3,) [m], by link: what tells which real part an
            opening or a probe acts on (:meth:`RealEnvironment.real_link`).
    """

    world: ManipulationWorld
    seed: int
    target: str
    point: np.ndarray
    frames: list[CameraFrame]
    outcomes: list[Outcome]
    labels: list[str] = field(default_factory=list)
    weighed: bytes = b""
    refusals: dict[tuple[ManipAction, int], tuple[np.ndarray, bool]] = field(default_factory=dict)
    unplanned: collections.Counter = field(default_factory=collections.Counter)
    now: int = 0
    still: bool = False
    ended: int | None = None
    handles: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def refused(self) -> set[tuple[ManipAction, int]]:
        """The refusals that stand now: the cabinet within
        :data:`~.rules.UNCHANGED` of where it was when the action failed, the hand
        holding what it held (what failed against that cabinet fails again); the twins'
        POMDP refuses them at the root while the particle each followed is still their
        representative. Until issue 37 any step that ended ``ok`` lifted every refusal,
        and a Place that could not start came back after each ``Place(table)`` /
        ``Pick``, which move nothing of the cabinet: 8 of STRUG's 16 OpenDoor failures
        on held-out 9300:9330 spent their last steps in that cycle."""
        q, held = self._situation()
        return {key for key, (q0, held0) in self.refusals.items()
                if held0 == held and np.max(np.abs(q - q0), initial=0.0) <= UNCHANGED}  # fmt: skip

    def _situation(self) -> tuple[np.ndarray, bool]:
        """The cabinet's coordinates (to the mm and mrad) and whether the hand holds the
        object."""
        return np.frombuffer(self.world.cabinet_key()), holds_object(self.world)

    def settle(self, key: tuple[ManipAction, int], status: str) -> None:
        """The refusals after a real step of ``key`` (action, the particle it
        followed) that ended ``status``: ``key`` refused in the situation it leaves
        after a failure that repeats itself (:data:`~.rules.REPEATS_ITSELF`) or after
        :data:`NO_PLAN_TRIES` ``no_motion_plan`` stops in a row (counted since the last
        step that ended ``ok``)."""
        if status == str(Status.OK):
            self.unplanned.clear()
        elif status in REPEATS_ITSELF:
            self.refusals[key] = self._situation()
        elif status == str(Status.NO_MOTION_PLAN):
            self.unplanned[key] += 1
            if self.unplanned[key] >= NO_PLAN_TRIES:
                self.refusals[key] = self._situation()


class RealEnvironment:
    """The real Fetch and cabinet of a manipulation task (module docstring).

    Args:
        model: the twins' POMDP the planners plan in (its worlds are the models the
            real robot plans against).
        cabinet_seed: the real cabinet's generator seed (default: drawn per episode
            from :data:`~.episode_setup.EPISODE_SEEDS`).
        target: the point of the cabinet front naming the target part, world (3,)
            [m]; default: drawn per episode (:mod:`.episode_setup`).
        target_link: the target part by its link name (``link_2``), instead of
            ``target``.
        objects: real object folders (PartNet-Mobility) to act on instead of generated
            cabinets; the episode's seed draws one.
        views: head-camera views for perception.
        oracle: the model's belief is the real cabinet (:mod:`.oracle`; evaluation only).
    """

    def __init__(
        self,
        model: ManipulationPOMDP,
        *,
        cabinet_seed: int | None = None,
        target: np.ndarray | None = None,
        target_link: str | None = None,
        objects: Sequence[Path] = (),
        views: int = 4,
        oracle: bool = False,
    ) -> None:
        self.model = model
        self.cabinet_seed, self.target, self.target_link = cabinet_seed, target, target_link
        self.objects, self.views, self.oracle = tuple(objects), views, oracle
        self.real: RealEpisode | None = None
        self.state: ManipState | None = None
        #: The belief after the last update, conditioned: what the robot plans against.
        self.belief: ParticleBelief | None = None
        #: The episode's belief health against the true cabinet (:mod:`.health`).
        self.health: HealthRecorder | None = None

    # --- the Environment protocol ------------------------------------------------------
    def reset(self, rng: np.random.Generator) -> None:
        """A new real cabinet and its target; the model gets the head camera's views."""
        self.close()
        self.model.free_worlds()
        t0 = time.perf_counter()
        world, seed, target, point = draw_episode(
            self.model.task, rng, self.model.ctx, cabinet_seed=self.cabinet_seed,
            objects=self.objects, target=self.target, target_link=self.target_link,
        )  # fmt: skip
        self.real = real = RealEpisode(world, seed, target, point, [], [], handles=handles(world))
        home = world.object_pose().copy()  # where Place(table) puts it back
        timers = Timers(setup=time.perf_counter() - t0)
        self.state = ManipState(REAL, world.snapshot(), 0)
        t0 = time.perf_counter()
        frames = take_views(world, self.views)
        real.frames.extend(frames)
        clouds = tuple(cabinet_cloud(world, f) for f in frames)
        timers.perception += time.perf_counter() - t0
        pose = look_poses(world, 1)[0]
        truth = true_particle(world) if self.oracle else None
        self.model.begin(
            EpisodeView(tuple(frames), clouds, point, home, world.config, pose, truth), timers
        )

    def execute(self, action: Any, rng: np.random.Generator) -> Executed:
        """The full Fetch runs ``action`` (module docstring)."""
        a = self.model.check_action(action)
        if self.state is None:
            raise self._no_episode()
        step = self._real_step(self.state, a, rng)
        self.state = step.state
        return Executed(step.obs, step.reward, step.done)

    def condition(self, belief: ParticleBelief) -> ParticleBelief:
        """``belief`` given what the robot knows for certain (:mod:`.conditioning`),
        kept; the model's :class:`.catalogue.Root` for the next search. The oracle's
        particle then takes over the real state (:func:`.oracle.take_over`)."""
        real, w, model = self.real, self.model.worlds, self.model
        if real is None or w is None or all(s.t == 0 for s in belief.states):
            self.belief = belief
            refused = frozenset(real.refused) if real is not None else frozenset()
            model.root = Root.of(model.cat, belief, model.root.reps, refused, 0)
            if real is not None and w is not None:
                self.health = self._health(belief)
            return belief
        if real.still:
            belief = conditioning.unmoved(belief, self.belief)
        shut, out = self.fronts()
        # The oracle's particle is the real cabinet: its limits are the real ones.
        ended = [real.ended] if real.ended in out and not self.oracle else []
        self.belief = conditioning.condition(belief, real.world, w, model.parts, shut, out, ended)
        if self.oracle:
            self.belief = take_over(self.belief, real.world, w)
        if self.health is not None:
            self.health.updated(self.belief)
        reps = representatives(model.cat, self.belief, model.root.reps)
        model.root = Root.of(model.cat, self.belief, reps, frozenset(real.refused), real.now)
        return self.belief

    # --- the real step -----------------------------------------------------------------
    def _real_step(self, s: ManipState, a: ManipAction, rng: np.random.Generator):
        real, model = self._need_real(), self.model
        t0 = time.perf_counter()
        world = real.world
        world.restore(s.sim)
        link = functools.partial(self.real_link, a.part)
        before = handle_point(world, a, link)
        seed = int(rng.integers(2**31))
        models = dict(self.plan_models(a, rng))
        order = list(models)

        def plan_in(i: int) -> Outcome | None:
            world.restore(s.sim)  # a stop before motion may still have stepped it
            candidates, plan_world = model.skills(i, a, models[i], holder=i)
            if plan_world is None or a.skill == "Pick":
                # The model's state, not the search's shared one for Pick: the route
                # from the cabinet to the table must keep clear of the doors that
                # stand open (the arm swept an open door shut on the way).
                plan_world = model.need_worlds().fetch(i, models[i])
            return first_feasible(
                functools.partial(sk.run, world, ctx=model.ctx, plan_world=plan_world, seed=seed)
                for sk in candidates
            )

        out, tried = in_turn(order, plan_in)
        planned = order[tried - 1] if tried else -1
        if out is None:
            status, holding, motion, r, summary = NOT_APPLICABLE, holds_object(world), \
                np.zeros(3), 0.0, \
                f"{a.skill}: {NOT_APPLICABLE} under the likeliest model"  # fmt: skip
        else:
            real.outcomes.append(out)
            real.labels.append(label(a))
            status, holding, summary = out.status, out.holding, out.summary()
            if tried > 1:  # the belief weighs it as the representative's action
                summary += f" [planned in model {planned}, after {tried - 1} that could not start]"
            motion = handle_point(world, a, link) - before
            r = reward(world.scene.cabinet_spec, real.target, world, out)
        # Such a failure repeats itself until something changes: the plan is made
        # against the same model, in nearly the same state (applicable()).
        real.settle((a, model.root.rep(a)), status)
        real.now = s.t + 1
        real.still = status in BEFORE_MOTION
        real.ended = a.part if out is not None and out.met_end else None
        model.root = replace(model.root, refused=frozenset(real.refused), now=real.now)
        frame = take_views(world, 1)[0]
        real.frames.append(frame)
        cloud = voxel_thin(cabinet_cloud(world, frame))
        scene = world.cabinet_key()
        news, real.weighed = scene != real.weighed, scene
        model.timers.real += time.perf_counter() - t0
        way = out is not None and out.on_the_way
        key = observation_key(status, holding, motion)
        obs = ManipObservation(key, cloud, summary, news, on_the_way=way)
        if self.health is not None and self.belief is not None:
            name = model.action_space().name(a)
            done_step = RealStep(s.t, a, name, planned, obs.key, r, news, model.root.rep(a))
            self.health.record(self.belief, done_step)
        done = r != 0.0 or s.t + 1 >= model.max_steps
        return Step(ManipState(REAL, world.snapshot(), s.t + 1, obs.key), obs, r, done)

    def _health(self, initial: ParticleBelief) -> HealthRecorder:
        """A new episode's belief-health recorder, from its initial belief."""
        real, model = self._need_real(), self.model
        return HealthRecorder(
            model.cat, model.need_worlds(), real.world.scene.cabinet_spec,
            real.world.scene.T_world_cabinet, real.target,
            self.real_link, model.max_steps, initial,
        )  # fmt: skip

    def plan_models(self, a: ManipAction, rng: np.random.Generator) -> list[tuple[int, WorldState]]:
        """The models the real robot plans ``a`` against, in the order it tries them
        while a plan stops before anything moves, each with its state: for an opening
        or a probe, :meth:`.catalogue.Root.plan_models` (the hypothesis's
        representative, then its next likeliest holders with weight, as the twins try
        them), each in its likeliest current state; for a Place into a part, up to
        :data:`~.catalogue.PLAN_MODELS` models that can make it (:meth:`able`); for
        Pick and the Place onto the table, one (:meth:`likeliest`)."""
        model = self.model
        w = model.need_worlds()
        if a.skill == "Pick" or a.part == TABLE:
            return [self.likeliest(a, rng)]
        if a.skill == "Place":
            # The real hold is not the twins' (the object sits a few millimetres off
            # where their hands hold it), and a place the likeliest model's twin made
            # could not start on the full robot, where the next models' places ran
            # (OpenDoor episode 10153: model 10 ik_infeasible, 8, 19 and 18 ok).
            return self.able(a, rng, PLAN_MODELS)
        return [(i, model.root.best.get(i) or w.initial[i]) for i in model.root.plan_models(a)]

    def likeliest(self, a: ManipAction, rng: np.random.Generator) -> tuple[int, WorldState]:
        """The model the real robot plans Pick or Place against first, and its state:
        the first of :meth:`able`."""
        return self.able(a, rng, 1)[0]

    def able(
        self, a: ManipAction, rng: np.random.Generator, n: int
    ) -> list[tuple[int, WorldState]]:
        """Up to ``n`` models (an int >= 1) to plan Pick or Place against, likeliest
        first, each in its likeliest state that has the action's part and whose twin
        can make the action (not ``ik_infeasible``, not :data:`NOT_APPLICABLE`: the
        search chose the action for the models that can, and a plan made in one that
        cannot fails before anything moves); if none can, the likeliest that has the
        part."""
        model = self.model
        w = model.need_worlds()
        b = self.belief
        if b is None:
            return [(0, w.initial[0])]
        order = np.argsort(-b.weights, kind="stable")
        states = [b.states[j] for j in order]
        links = model.parts[a.part].links if a.skill == "Place" and a.part != TABLE else None
        has = [s for s in states if links is None or links[s.origin] is not None]
        cannot = {STATUS_CODES[x] for x in CANNOT_START}
        out: dict[int, WorldState] = {}
        for s in has:  # the twins' outcomes are cached from the search, mostly
            if s.origin in out:
                continue
            if model.step(s, a, rng).obs.key[0] not in cannot:
                out[s.origin] = s.sim
                if len(out) == n:
                    break
        if not out:
            s = has[0] if has else states[0]
            out[s.origin] = s.sim
        return list(out.items())

    def real_link(self, k: int, within: float = np.inf) -> str | None:
        """The true cabinet's part (link) at catalogued part ``k``, which an opening or
        a probe of ``k`` acts on: the one whose handle, where it was when the episode
        began, is nearest the catalogued part's point, if within ``within`` [m]. Not
        where the handles are now: a door swung open puts its handle far from where it
        was named, nearer another part's, and its motion would be measured on that
        other part. None: the cabinet has no graspable part (that near)."""
        handles = self._need_real().handles
        ref = self.model.parts[k].point
        dist = {n: float(np.linalg.norm(h - ref)) for n, h in handles.items()}
        link = min(dist, key=dist.__getitem__, default=None)
        return link if link is not None and dist[link] <= within else None

    def counterpart(self, k: int) -> str | None:
        """The true part (link) that catalogued part ``k`` stands for, whose front the
        head camera is read at (:meth:`fronts`): the one whose handle, where it was when
        the episode began, is nearest ``k``'s point, within :data:`MATCH_RADIUS`, and
        to which no other catalogued part's point is nearer. None: perception's part
        has no true counterpart there."""
        link = self.real_link(k, within=MATCH_RADIUS)
        if link is None:
            return None
        h = self._need_real().handles[link]
        nearest = int(np.argmin([np.linalg.norm(p.point - h) for p in self.model.parts]))
        return link if nearest == k else None

    def fronts(self) -> tuple[list[int], dict[int, conditioning.Front]]:
        """Where the true cabinet's fronts stand now, per catalogued part with a true
        part there (:meth:`counterpart`): the catalogued parts whose true part stands shut
        (:data:`~.conditioning.SHUT`), and each one that stands open as the head camera
        shows it (:class:`~.conditioning.Front`: how far its handle is out of where it
        is shut, and how a door's or a flap's front is turned), in the cabinet as it
        stands now. The head camera's cloud shows a front flush or standing out of the
        carcass to about a centimetre, and a flat front's plane best of all (taken from
        the simulator, as the carcass's motion is); :func:`.conditioning.condition`
        moves each particle's part there."""
        real = self._need_real()
        rw, spec = real.world, real.world.scene.cabinet_spec
        T = rw.cabinet_pose()
        shut, out = [], {}
        for k in range(len(self.model.parts)):
            link = self.counterpart(k)
            if link is None:
                continue
            part = spec.part(link)
            if conditioning.is_shut(rw, part):
                shut.append(k)
                continue
            q = position(rw, part.joint)
            now, closed = part.handle_at(q, T), part.handle_at(0.0, T)
            if now is not None and closed is not None:  # a part with a handle
                out[k] = conditioning.Front(now - closed, _turn(part, q, T[:3, :3]))
        return shut, out

    # --- reports -------------------------------------------------------------------------
    def report(self) -> dict[str, Any]:
        """The real cabinet, and what the real robot's skills did (``real``: ``skill
        status`` per step that ran one, named as in :attr:`RealEpisode.labels`)."""
        if self.real is None:
            return {}
        out = {
            "cabinet_seed": self.real.seed,
            "cabinet": self.real.world.scene.cabinet_spec.name,
            "real": [f"{k} {o.status}" for k, o in zip(self.real.labels, self.real.outcomes,
                     strict=True)],
        }  # fmt: skip
        return out if self.health is None else {**out, "health": self.health.as_dict()}

    def close(self) -> None:
        """Free the real world (the model frees its own: its ``close``)."""
        if self.real is not None:
            self.real.world.close()
        self.real, self.belief, self.state, self.health = None, None, None, None

    def _need_real(self) -> RealEpisode:
        if self.real is None:
            raise self._no_episode()
        return self.real

    def _no_episode(self) -> ConfigError:
        return ConfigError(f"{self.model.name}: no episode yet (call reset first)")


def _turn(part: PartSpec, q: float, R: np.ndarray) -> tuple[np.ndarray, float] | None:
    """How ``part``'s front at joint position ``q`` is turned from shut: the hinge's
    axis, world (3,) (the cabinet turned by ``R``, (3, 3)), and the angle [rad]; None
    for a front that is not turned (a drawer's)."""
    if part.joint_type != "revolute":
        return None
    return R @ np.asarray(part.axis, dtype=float), float(q)
