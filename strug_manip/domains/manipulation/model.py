"""Shelf, OpenDrawer and OpenDoor: a Fetch, a cabinet it has never seen, an object to
put into it (:class:`ManipulationPOMDP`).

An episode (what :func:`planners.episode.run_episode` does with these domains):

1. ``sample_initial_state``: the real cabinet is generated from a held-out seed
   (:data:`EPISODE_SEEDS`: no test, tuning or training run uses them) with the task's
   part kinds; the target is the part at the user's point of the cabinet front, or,
   without one, drawn among the parts the full robot opens under the true model
   (Shelf: among the open cells).
2. ``initial_belief``: the head camera looks from :data:`VIEWS` poses; perception
   turns those renders into particles (:mod:`.belief`), never reading the true
   cabinet; their parts are catalogued by where they are (:mod:`.actions`) and the
   episode's action list made.
3. ``step`` on a particle runs the skill on that particle's planning twin
   (:mod:`.worlds`, cached); on the real state it runs the full Fetch with the full
   skills, planned against the likeliest particle that holds the action's hypothesis,
   and renders the head camera's point cloud. The belief is updated with that cloud.

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

import collections
import functools
import math
import time
from collections.abc import Hashable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from perception.likelihood import log_likelihood, voxel_thin
from perception.parts import Perceiver
from planners.belief import ParticleBelief
from planners.errors import ConfigError, UnknownNameError, check_positive_int
from planners.pomdp import ActionSchema, ActionSpace, GenerativePOMDP, Step
from planners.tru import execute_plan
from strug_manip.control import (
    ControlContext,
    OpenDoor,
    OpenDrawer,
    Outcome,
    Pick,
    Place,
    PullH,
    PullV,
    Push,
    Status,
    handle_grasps,
    place_targets,
)
from strug_manip.control.skills import HANDLE_RADIUS, holds_object
from strug_manip.domains.manipulation import belief as belief_mod
from strug_manip.domains.manipulation.actions import (
    DEFAULT_PROBES,
    SAME_PART,
    SKILLS,
    TABLE,
    CataloguePart,
    ManipAction,
    action_list,
    catalogue,
    describe,
    label,
    part_kind,
    part_point,
)
from strug_manip.domains.manipulation.rules import dragged, inside, open_enough
from strug_manip.domains.manipulation.state import (
    NOT_APPLICABLE,
    REAL,
    STATUS_CODES,
    ManipObservation,
    ManipState,
    observation_key,
)
from strug_manip.domains.manipulation.worlds import ParticleWorlds, Timers
from strug_manip.objects.generator import CabinetSpec, PartSpec
from strug_manip.objects.hypotheses import BelievedJoint
from strug_manip.objects.loader import object_folders
from strug_manip.robot.fetch import BASE_JOINTS, GRIPPER_SITE
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import OBJECT_JOINT, CameraFrame, ManipulationWorld, WorldState
from strug_manip.world.views import cabinet_cloud, look_poses, take_views

#: The generator seeds of the episodes' cabinets: ``EPISODE_SEEDS.start + k`` with k
#: drawn per episode. Tests use seeds below 1,000, the skills' tuning 3,000-3,299, the
#: evaluations' reports 1,000-2,999, perception's training 100,000 and up.
EPISODE_SEEDS = range(6_000, 10_000)
#: Head-camera views perception gets.
VIEWS = 4
#: Steps per episode (the paper's).
MAX_STEPS = 10
#: A drawn cabinet with no part the full robot opens (fills, on Shelf) gives way to the
#: next draw, at most this many times: an episode is about the task, not about the
#: generator's rare cabinets whose parts are all out of the arm's reach.
MAX_DRAWS = 20
#: The outcomes of an action that could not start (nothing moved): no base and arm
#: reach it, or its plan cannot be made in the model.
CANNOT_START = (str(Status.IK_INFEASIBLE), NOT_APPLICABLE)
#: The outcomes of an action that, tried again from nearly the same state against the
#: same model, ends the same way: it could not start; its grasp slipped off a handle
#: that does not turn about the joint it followed; it stopped because it slid the
#: cabinet (again, the slides add up to a drag). A ``collision`` or a missing motion
#: plan is not among them: the next attempt plans a new path.
REPEATS_ITSELF = (*CANNOT_START, str(Status.GRASP_LOST), str(Status.CABINET_MOVED))
#: The outcomes the full robot reaches before anything moves: every IK solution, route
#: and arm motion of a skill (the stow after it included) is found before it moves, in
#: the model it plans against (:meth:`ManipulationPOMDP._plan_models`), not in the real
#: cabinet. Such an outcome is a function of that model and of the planners' budgets
#: alone, so the real belief weighs it as no evidence and keeps its states as they
#: were: after a Place whose stow found no plan in time, the particles whose twins
#: placed the object would otherwise lose to those without the target part (their
#: twins could not start either), and an episode gave up on the right model.
BEFORE_MOTION = (*CANNOT_START, str(Status.NO_MOTION_PLAN))
#: A ``no_motion_plan`` stop of one action (with the particle it follows) this many
#: times in a row since the last step that ended ``ok`` refuses it as
#: :data:`REPEATS_ITSELF` would: the robot did not move, so the next try plans the same
#: motion from the same state with another planner seed, and where two seeds found no
#: path in the planner's budget a third rarely does (a held-out door episode spent seven
#: steps on one ``Place`` that way).
NO_PLAN_TRIES = 2
#: A real front this near its closed position is seen shut, by joint type [m or rad]:
#: the head camera's cloud shows a front flush with the carcass to about a centimetre,
#: and 0.1 rad is 2 cm at the edge of a 0.2 m door.
SHUT = {"prismatic": 0.02, "revolute": 0.1}
#: Their status codes, as observation keys carry them.
BEFORE_MOTION_CODES = frozenset(STATUS_CODES[x] for x in BEFORE_MOTION)
#: The real robot plans an opening or a probe in at most this many models before it
#: spends the step: the hypothesis's representative, then its next likeliest holders.
#: A plan that stops before anything moves (:data:`BEFORE_MOTION`) costs a whole step
#: and is no evidence, so the belief cannot steer away from it; another holder's model
#: differs in where the handle, the hinge and the other parts are (a holder that
#: believes a neighbouring door ajar finds the approach to the target blocked).
#: Planning is cheap next to a step; three bounds what a step may spend on it.
REAL_PLAN_MODELS = 3
#: ``Place(table)`` with a side grasp starts this much above the object's spot and comes
#: down to it [m]: the object held level clears the table top (a top grasp comes down
#: from above anyway).
TABLE_LIFT = 0.03
#: Particles drawn from perception (the runner's ``n_particles`` is capped to this:
#: every particle is a compiled world and a twin).
MAX_PARTICLES = 24
#: Likelihood of a simulated observation whose status or holding differs [log].
MISMATCH = math.log(0.05)
#: The part kinds of each task's cabinets (the generator's ``kinds``).
TASK_KINDS: dict[str, tuple[str, ...]] = {
    "shelf": ("shelf",),
    "opendrawer": ("drawer",),
    "opendoor": ("door",),
}


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
        refused: the actions that failed on the full robot in a way that repeats
            itself (:data:`REPEATS_ITSELF`, or ``no_motion_plan``
            :data:`NO_PLAN_TRIES` times in a row) since its last step that ended
            ``ok``, each
            with the particle it followed
            (:meth:`ManipulationPOMDP._rep`); :meth:`ManipulationPOMDP.applicable`
            refuses them at the root while that particle is still their
            representative.
        unplanned: per such (action, particle), its ``no_motion_plan`` stops since the
            last step that ended ``ok``.
        now: the step count of the states after the last real step (the root's).
        still: the last real step stopped before anything moved (:data:`BEFORE_MOTION`).
        handles: the true cabinet's graspable parts' handles where they were when the
            episode began, world (3,) [m], by link: what tells which real part an
            opening or a probe acts on (:meth:`ManipulationPOMDP._real_link`).
    """

    world: ManipulationWorld
    seed: int
    target: str
    point: np.ndarray
    frames: list[CameraFrame]
    outcomes: list[Outcome]
    labels: list[str] = field(default_factory=list)
    weighed: bytes = b""
    refused: set[tuple[ManipAction, int]] = field(default_factory=set)
    unplanned: collections.Counter = field(default_factory=collections.Counter)
    now: int = 0
    still: bool = False
    handles: dict[str, np.ndarray] = field(default_factory=dict)

    def settle(self, key: tuple[ManipAction, int], status: str) -> None:
        """The refusals after a real step of ``key`` (action, the particle it
        followed) that ended ``status``: all lifted by ``ok``; ``key`` refused after a
        failure that repeats itself (:data:`REPEATS_ITSELF`) or after
        :data:`NO_PLAN_TRIES` ``no_motion_plan`` stops in a row."""
        if status == str(Status.OK):
            self.refused.clear()
            self.unplanned.clear()
        elif status in REPEATS_ITSELF:
            self.refused.add(key)
        elif status == str(Status.NO_MOTION_PLAN):
            self.unplanned[key] += 1
            if self.unplanned[key] >= NO_PLAN_TRIES:
                self.refused.add(key)


class ManipulationPOMDP(GenerativePOMDP):
    """One manipulation task as a POMDP (module docstring); subclasses name the task.

    Args:
        cabinet_seed: the real cabinet's generator seed (default: drawn per episode
            from :data:`EPISODE_SEEDS`).
        target: the point of the cabinet front naming the target part, world (3,)
            [m] (the part whose cell contains it, seen from the front); default: drawn
            per episode (module docstring).
        particles: belief particles from perception (at most :data:`MAX_PARTICLES`).
        probes: the probe skills offered per part (``Push``, ``PullV``, ``PullH``).
        views: head-camera views for perception (1..6).
        max_steps: the episode's step limit (default the paper's :data:`MAX_STEPS`;
            fewer for quick checks).
        objects: real articulated objects (PartNet-Mobility folders) to act on instead
            of generated cabinets; the episode's seed draws one
            (:func:`~strug_manip.objects.loader.object_folders` lists a folder's).
        target_link: the target part by its link name (``link_2``), instead of
            ``target``.

    Raises:
        ConfigError, UnknownNameError: a bad argument, naming it.
    """

    task: str = ""
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
        cabinet_seed: int | None = None,
        target: Sequence[float] | None = None,
        particles: int = MAX_PARTICLES,
        probes: Sequence[str] = DEFAULT_PROBES,
        views: int = VIEWS,
        max_steps: int = MAX_STEPS,
        objects: Sequence[str | Path] = (),
        target_link: str | None = None,
    ) -> None:
        self.max_steps = check_positive_int("max_steps", max_steps)
        self.objects = tuple(p for o in objects for p in object_folders(o))
        if self.objects and cabinet_seed is not None:
            raise ConfigError("give cabinet_seed or objects, not both")
        if target_link is not None and target is not None:
            raise ConfigError("give target or target_link, not both")
        self.target_link = target_link
        if cabinet_seed is not None:
            check_positive_int("cabinet_seed", cabinet_seed, allow_zero=True)
        self.cabinet_seed = cabinet_seed
        self.target = None if target is None else _point("target", target)
        self.particles = check_positive_int("particles", particles)
        for p in probes:
            if p not in ("Push", "PullV", "PullH"):
                raise UnknownNameError("probe", p, ["Push", "PullV", "PullH"])
        self.probes = tuple(probes)
        if not (isinstance(views, int) and 1 <= views <= 6):
            raise ConfigError(f"views must be an integer in 1..6, got {views!r}")
        self.views = views
        self.ctx = ControlContext()
        self._perceiver: Perceiver | None = None
        self.real: RealEpisode | None = None
        self.worlds: ParticleWorlds | None = None
        self.parts: tuple[CataloguePart, ...] = ()
        self._classes: tuple[tuple[str | None, ...], ...] = ()
        self._reps: tuple[tuple[int, ...], ...] = ()
        self.targets: tuple[str | None, ...] = ()
        self._belief: ParticleBelief | None = None
        self._home = np.eye(4)
        self.timers = Timers()
        self._space = self._make_space((ManipAction("Pick", grasp="top"),))

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
        return self._classes[s.origin] if s.origin >= 0 else None

    def _movable_kind(self, i: int, k: int) -> str | None:
        """Particle ``i``'s hypothesis for catalogued part ``k`` (None: it has no such
        part, or an open cell)."""
        if self.parts[k].links[i] is None:
            return None
        kind = self._own_kind(i, k)
        return None if kind == "shelf" else kind

    def observation_key(self, o: Any) -> Hashable:
        return o.key

    def check_observation(self, o: Any) -> None:
        if not isinstance(o, ManipObservation):
            raise ConfigError(f"{self.name}: expected a ManipObservation, got {o!r}")

    def condition(self, belief: ParticleBelief) -> ParticleBelief:
        """The belief given what the robot knows for certain after a real step, and kept:
        the real robot plans against its likeliest models.

        Known in every particle alike: where the robot's base stands (its odometry),
        how far the cabinet's base has moved since the start (the carcass, which the
        head camera's cloud shows to millimetres; taken from the simulator as a perfect
        localisation; each particle's own cabinet moves by that rigid motion from where
        it stood, its own front where perception put it) and, when the hand is empty,
        where the object rests (it is tracked as well), and which parts stand shut
        (:meth:`_shut_parts`: a front flush with the carcass; which way a part opens
        the camera does not show, so an open part keeps each particle's own joint).
        Each particle keeps its other parts' joints and, when the real hand holds the
        object, its own idea of the grasp; a particle whose hand is empty while the real
        one holds the object (its twin's Place went through where the real one stopped)
        gets the object back in its hand, in the real grasp. Without this a cabinet the
        real robot dragged by 5 cm stays put in every particle, and the next Place aims
        5 cm off; and after a real Place that stopped, every particle believes the
        object placed and none plans to place it again; and a drawer the arm pushed
        shut on its way to the cell stays open in every particle, and every later Place
        aims into it.
        """
        real, w = self.real, self.worlds
        if real is None or w is None or all(s.t == 0 for s in belief.states):
            self._belief = belief
            return belief
        belief = self._unmoved(belief)
        rw = real.world
        base = np.array([rw.robot_qpos()[j] for j in BASE_JOINTS])
        moved = rw.cabinet_pose() @ np.linalg.inv(rw.scene.T_world_cabinet)
        holding = holds_object(rw)
        known = [] if holding else [OBJECT_JOINT]
        T_go = np.linalg.inv(rw.site_pose(GRIPPER_SITE)) @ rw.object_pose() if holding else None
        shut = self._shut_parts()
        done: dict[ManipState, ManipState] = {}
        states = []
        for s in belief.states:
            if s not in done:
                tw = w.twins[s.origin]
                tw.restore(s.sim)
                tw.world.set_cabinet_pose(moved @ tw.world.scene.T_world_cabinet)
                tw.world.copy_joints(rw, known)
                tw.set_robot_base(base)
                opened = self._opened(s.origin, shut, tw.world)
                if opened:
                    tw.world.set_parts(opened)
                if T_go is not None and not holds_object(tw.world):
                    tw.world.set_object_pose(tw.world.site_pose(GRIPPER_SITE) @ T_go)
                done[s] = ManipState(s.origin, tw.snapshot(), s.t, s.last)
            states.append(done[s])
        self._belief = ParticleBelief(states, belief.weights, belief.origin)
        self._reps = self._representatives(self._belief)
        return self._belief

    def _shut_parts(self) -> list[int]:
        """The catalogued parts whose true part stands shut now (:data:`SHUT`): the true
        part whose handle, when the episode began, was within :data:`SAME_PART` of the
        catalogued point (none: perception's part has no true counterpart there)."""
        rw = self._need_real().world
        links = [self._real_link(k, within=SAME_PART) for k in range(len(self.parts))]
        return [k for k, link in enumerate(links)
                if link is not None and _shut(rw, rw.scene.cabinet_spec.part(link))]  # fmt: skip

    def _opened(self, i: int, shut: list[int], world: ManipulationWorld) -> dict[str, float]:
        """Particle ``i``'s joints (in its twin's ``world``) of the parts ``shut`` that it
        holds open, each at 0 (closed), by joint name."""
        spec = world.scene.cabinet_spec
        held = [spec.part(link) for k in shut if (link := self.parts[k].links[i]) is not None]
        return {p.joint: 0.0 for p in held if not _shut(world, p)}

    def _unmoved(self, belief: ParticleBelief) -> ParticleBelief:
        """After a real step that stopped before anything moved (:data:`BEFORE_MOTION`),
        ``belief`` with every particle back in its state before the step (its step
        count advanced): a twin that went through moved what the real robot did not
        touch. Particles correspond by position (the real belief is never resampled);
        ``belief`` as it is otherwise."""
        prior, real = self._belief, self.real
        if real is None or not real.still or prior is None or len(prior) != len(belief):
            return belief
        if not np.array_equal(prior.origin, belief.origin):
            return belief
        states = [ManipState(p.origin, p.sim, s.t, s.last)
                  for p, s in zip(prior.states, belief.states, strict=True)]  # fmt: skip
        return ParticleBelief(states, belief.weights, belief.origin)

    def _representatives(self, belief: ParticleBelief) -> tuple[tuple[int, ...], ...]:
        """Per catalogued part and hypothesis, the particle whose grasp and joint the
        action follows: the likeliest particle of ``belief`` that holds the hypothesis
        (ties: the lowest index; none with weight: the previous one).

        Why not a fixed holder: particles of one hypothesis differ in where the hinge
        is (perception's noise), and the full robot's opening slips off a handle when
        the joint it follows is a few centimetres off. An opening that failed in the
        real world moves weight from the particles whose twins followed the joint
        successfully to those whose did not, so the next likeliest holder's joint is
        tried next; and a belief that has settled on one particle opens the part along
        that particle's own joint. Within one search the representatives are fixed
        (they change after a real step), so every search sees one POMDP."""
        mass = self._mass(belief)
        out = []
        for k, part in enumerate(self.parts):
            row = []
            for h in range(len(part.hypotheses)):
                held = self._holders(mass, k, h)
                row.append(held[0] if held and mass[held[0]] > 0 else self._reps[k][h])
            out.append(tuple(row))
        return tuple(out)

    def _mass(self, belief: ParticleBelief) -> np.ndarray:
        """Each model's (particle origin's) weight in ``belief``, (n_models,)."""
        mass = np.zeros(len(self._classes))
        for s, wt in zip(belief.states, belief.weights.tolist(), strict=True):
            if s.origin >= 0:
                mass[s.origin] += wt
        return mass

    def _holders(self, mass: np.ndarray, k: int, h: int) -> list[int]:
        """The models that hold hypothesis ``h`` of catalogued part ``k``, likeliest
        first (ties: the lowest index)."""
        kind = self.parts[k].hypotheses[h]
        held = [i for i in range(len(mass)) if self._classes[i][k] == kind]
        return sorted(held, key=lambda i: (-mass[i], i))

    def _rep(self, a: ManipAction) -> int:
        """The particle whose grasp and joint opening or probe ``a`` follows (-1: Pick
        and Place, which follow none)."""
        if a.skill in ("Pick", "Place"):
            return -1
        return self._reps[a.part][max(a.hypothesis, 0)]

    def sample_initial_state(self, rng: np.random.Generator) -> ManipState:
        """A new real cabinet and its target (module docstring)."""
        self.close()
        t0 = time.perf_counter()
        drawn = self.cabinet_seed is None and self.target is None and self.target_link is None
        for attempt in range(MAX_DRAWS if drawn else 1):
            seed = self.cabinet_seed
            if self.objects:  # a real object: the seed draws which
                seed = -1
                folder = self.objects[int(rng.integers(len(self.objects)))]
                config = SceneConfig(cabinet_folder=folder)
            else:
                if seed is None:
                    seed = EPISODE_SEEDS.start + int(rng.integers(len(EPISODE_SEEDS)))
                config = SceneConfig(cabinet_seed=seed, cabinet_kinds=TASK_KINDS[self.task])
            world = ManipulationWorld(config)
            try:
                target, point = self._choose_target(world, rng)
                break
            except ConfigError:
                world.close()
                if not drawn or attempt == MAX_DRAWS - 1:
                    raise
        world.reset()
        self.real = RealEpisode(world, seed, target, point, [], [], handles=_handles(world))
        self._home = world.object_pose().copy()  # where Place(table) puts it back
        self.timers = Timers(setup=time.perf_counter() - t0)
        return ManipState(REAL, world.snapshot(), 0)

    def initial_belief(self, rng: np.random.Generator, n_particles: int) -> ParticleBelief:
        """Particles from perception on the head camera's views of the real cabinet."""
        real = self._need_real()
        t0 = time.perf_counter()
        frames = take_views(real.world, self.views)
        real.frames.extend(frames)
        if self._perceiver is None:
            self._perceiver = Perceiver()
        c = real.world.config
        cfg = belief_mod.BeliefConfig(particles=min(n_particles, self.particles))
        scene = (c.cabinet_distance, c.cabinet_lateral, c.stand_height)
        particles = belief_mod.initial_belief(
            [(f.rgb, f.depth, f.T_world_camera, f.fovy) for f in frames],
            self._perceiver, rng, cfg, scene=scene,
        )  # fmt: skip
        if self.task == "shelf":  # the network finds no open cells: read them off the cloud
            clouds = [cabinet_cloud(real.world, f) for f in frames]
            particles = [belief_mod.with_open_cell(p, real.point, clouds, scene)
                         for p in particles]  # fmt: skip
        self.timers.perception += time.perf_counter() - t0
        t0 = time.perf_counter()
        self.worlds = w = ParticleWorlds(particles, c, self.ctx)
        poses = [w.pose(i) for i in range(len(w))]
        self.parts = catalogue(
            [p.spec for p in particles], [p.q for p in particles], poses, TASK_KINDS[self.task]
        )
        self.targets = tuple(self._target_link(i, real.point) for i in range(len(w)))
        self._classes = tuple(tuple(self._movable_kind(i, k) for k in range(len(self.parts)))
                              for i in range(len(w)))  # fmt: skip
        self._reps = tuple(part.holders for part in self.parts)
        self._space = self._make_space(action_list(self.parts, self.task, self.probes))
        self.timers.setup += time.perf_counter() - t0
        belief = ParticleBelief.from_states([ManipState(i, w.initial[i], 0) for i in range(len(w))])
        self._belief = belief
        return belief

    def step(self, s: ManipState, a: Hashable, rng: np.random.Generator) -> Step:
        a = self._check_action(a)
        if s.origin == REAL:
            return self._real_step(s, a, rng)
        w = self._need_worlds()
        key = (s.origin, s.sim.key, a, self._rep(a))
        hit = w.outcomes.lookup(key)
        if hit is None:
            t0 = time.perf_counter()
            hit = self._simulate(s.origin, s.sim, a)
            w.timers.twin += time.perf_counter() - t0
            w.outcomes.store(key, hit)
        sim, okey, reward, terminal, summary = hit
        done = terminal or s.t + 1 >= self.max_steps
        return Step(ManipState(s.origin, sim, s.t + 1, okey),
                    ManipObservation(okey, None, summary), reward, done)  # fmt: skip

    def applicable(self, s: Any, a: Hashable) -> bool:
        """False when ``a`` cannot start in particle state ``s``; the solvers then leave
        it out of the node (a no-op costs one of the episode's 10 steps).

        Decided by the twin's outcome when the search has simulated it already (not
        :data:`NOT_APPLICABLE`), else by what the twin checks before anything moves:

        * one hand: a grasping skill with the object held, a ``Place`` without it;
        * a ``Place`` into a part ``s``'s model lacks, or one not open enough to place
          in (no placement pose);
        * an opening or probe on a part whose handle has moved more than
          :data:`~strug_manip.control.skills.HANDLE_RADIUS` in ``s`` from where the
          model put it: the action's grasps are at the model's initial handle
          (:meth:`_skills`), so there is nothing to grasp there (the part is open).
          A part ``s``'s model lacks stays applicable: acting on it is how the robot
          learns that the model is wrong.

        At the root (the states of the current real step), an action that failed on
        the full robot in a way that repeats itself (:data:`REPEATS_ITSELF`, or
        :data:`NO_PLAN_TRIES` stops without a motion plan; :meth:`RealEpisode.settle`)
        since the last step that ended ``ok`` is refused whatever the twins say, as long as it
        would follow the same particle's grasp and joint: the robot would plan it
        against the same model in nearly the same state and fail the same way again.
        The twins and the full robot disagree on such actions, and when every weighted
        particle predicted the failure, or none did, the observation moves no weight
        and the search chooses the action again (on held-out door episodes, one
        slipping opening until the steps ran out, and a ``Place`` stopped at
        ``cabinet_moved`` until the stops added up to a drag). When the belief moves
        the hypothesis to another particle, the opening follows that particle's joint
        and is offered again.

        The real state: always True (the real robot plans against the likeliest model).
        """
        if s.origin == REAL:
            return True
        a, real = self._check_action(a), self.real
        rep = self._rep(a)
        if real is not None and s.t == real.now and (a, rep) in real.refused:
            return False
        w = self._need_worlds()
        key = (s.origin, s.sim.key, a, rep)
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
        w = self._need_worlds()
        tw = w.twins[s.origin]
        tw.restore(s.sim)
        world = tw.world
        if (a.skill == "Place") != holds_object(world):
            return False
        if a.skill == "Pick" or a.part == TABLE:
            return True
        if a.skill == "Place":  # a pose to place at (the skills the twin would try)
            return bool(self._skills(s.origin, a, s.sim)[0])
        link = self.parts[a.part].links[s.origin]
        if link is None:
            return True
        part = w.particles[s.origin].spec.part(link)
        q, T = _position(world, part.joint), world.cabinet_pose()
        if part.handle_pos is None:
            return True
        q0 = w.particles[s.origin].q.get(part.joint, 0.0)
        moved = np.linalg.norm(part.handle_at(q, T) - part.handle_at(q0, T))
        return bool(moved < HANDLE_RADIUS)

    def obs_loglik(self, o: Any, s_next: Any, a: Hashable) -> float:
        return float(self.obs_loglik_many(o, [s_next], a)[0])

    def obs_loglik_many(self, o: Any, states: list[Any], a: Hashable) -> np.ndarray:
        """The key's likelihood per state, times (real observations) the cloud's."""
        a = self._check_action(a)
        w = self._need_worlds()
        if o.cloud is not None and self._before_motion(o.key):  # real: no evidence
            out = np.zeros(len(states))
        else:
            out = np.array([self._key_loglik(o.key, s, a) for s in states])
        if o.cloud is None or not o.news:
            return out
        t0 = time.perf_counter()
        pose = look_poses(self._need_real().world, 1)[0]
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
        """The uncertainty-free plan of particle ``s``: open the target part under each
        hypothesis in turn (the particle's own first), then Pick and Place; the first
        that earns the +10 when simulated on ``s`` (a forward search on that particle),
        else the own hypothesis's. Steps that ``s`` has done already are left out (the
        part open enough, the object held). Shelf: Pick, then Place."""
        k = self._target_index(s.origin)
        if k is None:
            return []
        part = self.parts[k]
        grasp = "top" if self.task == "opendrawer" else "side"
        tail = [ManipAction("Pick", grasp=grasp), ManipAction("Place", k)]
        if self._holding(s):
            tail = tail[1:]
        if self.task == "shelf" or self._open_enough(s, k):
            return tail
        own = part.hypotheses.index(self._own_kind(s.origin, k))
        first = None
        for h in [own, *(h for h in range(len(part.hypotheses)) if h != own)]:
            opening = "OpenDrawer" if part.hypotheses[h] == "drawer" else "OpenDoor"
            plan = [ManipAction(opening, k, h), *tail]
            first = first or plan
            if execute_plan(self, s, plan, rng, self.discount)[0] > 0:
                return plan
        return first or []

    def format_state(self, s: Any) -> str:
        who = "real" if s.origin == REAL else f"model {s.origin}"
        return f"{who}, step {s.t}"

    def format_obs(self, o: Any) -> str:
        return o.summary or str(o.key)

    def summarize_belief(self, belief: ParticleBelief) -> str:
        """The target part's hypotheses by weight, and the ESS."""
        mass: dict[str, float] = {}
        for s, wt in zip(belief.states, belief.weights.tolist(), strict=True):
            k = self._target_index(s.origin)
            kind = "none" if k is None else self._own_kind(s.origin, k)
            mass[kind] = mass.get(kind, 0.0) + wt
        top = ", ".join(f"{k} {v:.2f}" for k, v in sorted(mass.items(), key=lambda kv: -kv[1]))
        return f"target: {top}; ESS {belief.ess():.1f} of {len(belief)}"

    def report(self) -> dict[str, Any]:
        """Where this episode's time went [s], the caches' hit rates, and what the real
        robot's skills did (``real``: ``skill status`` per step that ran one, the skill
        named as in :attr:`RealEpisode.labels`)."""
        w = self.worlds
        out: dict[str, Any] = {"time": self.timers.as_dict()}
        if self.real is not None:
            out["cabinet_seed"] = self.real.seed
            out["cabinet"] = self.real.world.scene.cabinet_spec.name
            out["real"] = [f"{k} {o.status}" for k, o in zip(self.real.labels,
                           self.real.outcomes, strict=True)]  # fmt: skip
        if w is not None:
            out["time"].update({k: v for k, v in w.timers.as_dict().items() if v})
            out["outcome_cache"] = {"hits": w.outcomes.hits, "misses": w.outcomes.misses,
                                    "hit_rate": round(w.outcomes.hit_rate, 3)}  # fmt: skip
            out["cloud_cache_hit_rate"] = round(w.clouds.hit_rate, 3)
        return out

    def close(self) -> None:
        """Free the episode's worlds."""
        if self.worlds is not None:
            self.worlds.close()
        if self.real is not None:
            self.real.world.close()
        self.worlds, self.real, self._belief = None, None, None

    # --- set-up --------------------------------------------------------------------------
    def _make_space(self, actions: tuple[ManipAction, ...]) -> ActionSpace:
        parts = self.parts
        self._known = frozenset(actions)  # _check_action's O(1) membership (a hot path)
        return ActionSpace(
            schemas=tuple(ActionSchema(s) for s in SKILLS),
            discretized=actions,
            describe=lambda a: describe(a, parts),
        )

    def _choose_target(self, world: ManipulationWorld, rng: np.random.Generator):
        """(link, naming point) of the target part in the true cabinet."""
        spec = world.scene.cabinet_spec
        T = world.scene.T_world_cabinet
        kinds = TASK_KINDS[self.task]
        if self.target_link is not None:
            part = spec.part(self.target_link)
            if part.kind not in kinds:
                raise ConfigError(
                    f"target_link {self.target_link!r} of {spec.name} is a {part.kind}; "
                    f"the {self.task} task needs a {'/'.join(kinds)} (its: "
                    f"{[p.link for p in spec.parts if p.kind in kinds]})"
                )
            return part.link, (T @ np.r_[part.cell_center, 1.0])[:3]
        if self.target is not None:
            link = _part_at_point(spec, T, self.target, kinds)
            if link is None:
                raise ConfigError(
                    f"target {np.round(self.target, 3).tolist()} is on no "
                    f"{'/'.join(kinds)} part of {spec.name} "
                    f"(its cells: {_cells(spec, T, kinds)})"
                )
            return link, self.target
        parts = [p for p in spec.parts if p.kind in kinds and part_point(p, 0.0, T) is not None]
        for i in rng.permutation(len(parts)):
            p = parts[i]
            if self._fills(world, p) if p.kind == "shelf" else self._opens(world, p):
                return p.link, (T @ np.r_[p.cell_center, 1.0])[:3]
        raise ConfigError(
            f"{spec.name} has no {'/'.join(kinds)} part the robot "
            "can open; pass another cabinet_seed or object"
        )

    def _opens(self, world: ManipulationWorld, part) -> bool:
        """Whether the full robot opens ``part`` enough for the object under the true
        model (the target is drawn among such parts)."""
        T = world.scene.T_world_cabinet
        joint = BelievedJoint.of_part(part, 0.0, T)
        opening = OpenDrawer if part.joint_type == "prismatic" else OpenDoor

        def run(g: np.ndarray):
            world.reset()
            return opening(g, joint).run(world, ctx=self.ctx)

        out = _first_feasible(functools.partial(run, g) for g in handle_grasps(part, 0.0, T))
        if out is None or out.status == "ik_infeasible":
            return False
        q = _position(world, part.joint)
        return (
            out.ok
            and not dragged(out.cabinet_displacement)
            and open_enough(world.scene.cabinet_spec, part.link, q, world.cabinet_pose())
        )

    def _fills(self, world: ManipulationWorld, part) -> bool:
        """Whether the full robot, knowing the cabinet, puts the object onto the open
        cell ``part`` (Pick from the side, then Place: a Shelf target is drawn among
        such cells; many cells are too low or too tight for the arm)."""
        world.reset()
        if not Pick("object", "side").run(world, ctx=self.ctx).ok:
            return False
        T = world.scene.T_world_cabinet
        try:
            targets = place_targets(world.scene.cabinet_spec, part.link, 0.0, T)
        except ConfigError:
            return False
        out = _first_feasible(
            functools.partial(Place("object", t.p, t.lift).run, world, ctx=self.ctx)
            for t in targets
        )
        spec, T_now = world.scene.cabinet_spec, world.cabinet_pose()
        return bool(
            out is not None and out.ok and inside(spec, part.link, 0.0, T_now, world.object_pose())
        )

    def _target_link(self, i: int, point: np.ndarray) -> str | None:
        w = self._need_worlds()
        return _part_at_point(w.particles[i].spec, w.pose(i), point, TASK_KINDS[self.task])

    # --- simulation ------------------------------------------------------------------------
    def _simulate(self, i: int, sim: WorldState, a: ManipAction):
        """``a`` on particle ``i``'s twin from ``sim``: (next sim, observation key,
        reward, terminal, summary)."""
        w = self._need_worlds()
        candidates, plan_world = self._skills(i, a, sim)
        tw = w.twins[i]
        tw.restore(sim)
        before = self._handle(i, a, tw.world)

        def run(skill):
            tw.restore(sim)
            return skill.simulate(tw, plan_world=plan_world)

        out = _first_feasible(functools.partial(run, sk) for sk in candidates)
        if out is None:
            return sim, observation_key(NOT_APPLICABLE, holds_object(tw.world), np.zeros(3)), \
                0.0, False, f"{a.skill}: {NOT_APPLICABLE}"  # fmt: skip
        motion = self._handle(i, a, tw.world) - before
        reward = self._reward(w.particles[i].spec, self.targets[i], tw.world, out)
        return (tw.snapshot(), observation_key(out.status, out.holding, motion), reward,
                reward != 0.0, out.summary())  # fmt: skip

    def _skills(self, i: int, a: ManipAction, sim: WorldState, holder: int | None = None):
        """The skills to try in turn (each next grasp or placement while the previous is
        ``ik_infeasible``) and the planning world, for ``a`` on particle ``i`` in ``sim``
        (on the real robot: ``i`` is the model it plans in, ``sim`` its state). An
        opening or a probe follows ``holder``'s grasp and joint and plans in its
        likeliest state (default: the hypothesis's representative, :meth:`_rep`)."""
        w = self._need_worlds()
        if a.skill == "Pick":
            # The object's table is far from the cabinet: one planning world serves
            # every model, so the base placement is found once for all of them.
            return [Pick("object", a.grasp)], w.fetch(0)
        if a.skill == "Place" and a.part == TABLE:
            return [Place("object", self._home, TABLE_LIFT)], None
        part = self.parts[a.part]
        if a.skill == "Place":
            link = part.links[i]
            if link is None:
                return [], None
            tw = w.twins[i]
            tw.restore(sim)
            world = tw.world
            q = _position(world, w.particles[i].spec.part(link).joint)
            T_now = world.cabinet_pose()
            try:
                tgts = place_targets(w.particles[i].spec, link, q, T_now)
            except ConfigError:
                return [], None  # the part is not open enough: no pose to place at
            return [Place("object", t.p, t.lift) for t in tgts], None
        holder = self._rep(a) if holder is None else holder
        spec_part = w.particles[holder].spec.part(part.links[holder])
        q = w.particles[holder].q.get(spec_part.joint, 0.0)
        T = w.pose(holder)
        grasps = handle_grasps(spec_part, q, T)
        plan_world = w.fetch(holder, self._best_state(holder))
        if a.skill in ("OpenDrawer", "OpenDoor"):
            joint = BelievedJoint.of_part(spec_part, q, T)
            cls = OpenDrawer if a.skill == "OpenDrawer" else OpenDoor
            return [cls(g, joint) for g in grasps], plan_world
        probe = {"Push": Push, "PullV": PullV, "PullH": PullH}[a.skill]
        return [probe(g) for g in grasps], plan_world

    def _handle(self, i: int, a: ManipAction, world: ManipulationWorld) -> np.ndarray:
        """Where the acted part's handle (or the object, for Pick and Place) is in
        ``world`` (particle ``i``'s twin, or the real world for ``i`` = REAL), (3,)."""
        if a.skill in ("Pick", "Place"):
            return world.object_pose()[:3, 3].copy()
        spec = world.scene.cabinet_spec
        T = world.cabinet_pose()
        qs = world.part_positions()
        link = self._real_link(a.part) if i == REAL else self.parts[a.part].links[i]
        if link is None:
            return np.zeros(3)
        p = spec.part(link)
        pt = part_point(p, qs.get(world.scene.cabinet_prefix + p.joint, 0.0), T)
        return np.zeros(3) if pt is None else pt

    def _real_link(self, k: int, within: float = np.inf) -> str | None:
        """The true cabinet's part (link) at catalogued part ``k``, which an opening or
        a probe of ``k`` acts on: the one whose handle, where it was when the episode
        began, is nearest the catalogued part's point, if within ``within`` [m]. Not
        where the handles are now: a door swung open puts its handle far from where it
        was named, nearer another part's, and its motion would be measured on that
        other part. None: the cabinet has no graspable part (that near)."""
        handles = self._need_real().handles
        ref = self.parts[k].point
        dist = {n: float(np.linalg.norm(h - ref)) for n, h in handles.items()}
        link = min(dist, key=dist.__getitem__, default=None)
        return link if link is not None and dist[link] <= within else None

    def _reward(self, spec: CabinetSpec, target: str | None, world, out: Outcome) -> float:
        """-10 when dragged; +10 when a ``Place`` leaves the object resting in the target
        (only a Place can: a model that believes the object already in it, after a real
        Place that failed, earns nothing from its other actions)."""
        if dragged(out.cabinet_displacement):
            return -10.0
        if target is None or out.holding or out.skill != "Place":
            return 0.0
        q = _position(world, spec.part(target).joint)
        T_now = world.cabinet_pose()
        return 10.0 if inside(spec, target, q, T_now, world.object_pose()) else 0.0

    @staticmethod
    def _before_motion(key: tuple[float, ...]) -> bool:
        """The observation key's status is one of :data:`BEFORE_MOTION`."""
        return int(key[0]) in BEFORE_MOTION_CODES

    def _key_loglik(self, key: tuple[float, ...], s: ManipState, a: ManipAction) -> float:
        """How likely particle state ``s`` (after ``a``) makes an observation with
        ``key``: a mismatched status or grip costs :data:`MISMATCH` each; the handle's
        motion is Gaussian with one bin's standard deviation per axis."""
        mine = s.last
        if not mine:
            return 0.0
        ll = MISMATCH * ((key[0] != mine[0]) + (key[1] != mine[1]))
        d = np.subtract(key[2:], mine[2:])
        return float(ll - 0.5 * d @ d)

    # --- the real robot ------------------------------------------------------------------
    def _real_step(self, s: ManipState, a: ManipAction, rng: np.random.Generator) -> Step:
        real = self._need_real()
        t0 = time.perf_counter()
        world = real.world
        world.restore(s.sim)
        before = self._handle(REAL, a, world)
        seed = int(rng.integers(2**31))
        out, tried = None, 0
        for i, state in self._plan_models(a, rng):
            tried += 1
            world.restore(s.sim)  # a stop before motion may still have stepped it
            candidates, plan_world = self._skills(i, a, state, holder=i)
            if plan_world is None or a.skill == "Pick":
                # The model's state, not the search's shared one for Pick: the route
                # from the cabinet to the table must keep clear of the doors that
                # stand open (the arm swept an open door shut on the way).
                plan_world = self._need_worlds().fetch(i, state)
            out = _first_feasible(
                functools.partial(sk.run, world, ctx=self.ctx, plan_world=plan_world, seed=seed)
                for sk in candidates
            )
            if out is not None and out.status not in BEFORE_MOTION:
                break
        if out is None:
            status, holding, motion, reward, summary = NOT_APPLICABLE, holds_object(world), \
                np.zeros(3), 0.0, \
                f"{a.skill}: {NOT_APPLICABLE} under the likeliest model"  # fmt: skip
        else:
            real.outcomes.append(out)
            real.labels.append(label(a))
            status, holding, summary = out.status, out.holding, out.summary()
            if tried > 1:  # the belief weighs it as the representative's action
                summary += f" [planned in model {i}, after {tried - 1} that could not start]"
            motion = self._handle(REAL, a, world) - before
            reward = self._reward(world.scene.cabinet_spec, real.target, world, out)
        # Such a failure repeats itself until something changes: the plan is made
        # against the same model, in nearly the same state (applicable()).
        real.settle((a, self._rep(a)), status)
        real.now = s.t + 1
        real.still = status in BEFORE_MOTION
        frame = take_views(world, 1)[0]
        real.frames.append(frame)
        cloud = voxel_thin(cabinet_cloud(world, frame))
        scene = world.cabinet_key()
        news, real.weighed = scene != real.weighed, scene
        self.timers.real += time.perf_counter() - t0
        obs = ManipObservation(observation_key(status, holding, motion), cloud, summary, news)
        done = reward != 0.0 or s.t + 1 >= self.max_steps
        return Step(ManipState(REAL, world.snapshot(), s.t + 1, obs.key), obs, reward, done)

    def _plan_models(
        self, a: ManipAction, rng: np.random.Generator
    ) -> list[tuple[int, WorldState]]:
        """The models the real robot plans ``a`` against, in the order it tries them
        while a plan stops before anything moves, each with its state: for an opening
        or a probe, the hypothesis's representative (:meth:`_representatives`) and
        then its next likeliest holders with weight, at most :data:`REAL_PLAN_MODELS`,
        each in its likeliest current state; for Pick and Place, one model
        (:meth:`_likeliest`)."""
        w = self._need_worlds()
        if a.skill in ("Pick", "Place"):
            return [self._likeliest(a, rng)]
        rep = self._rep(a)
        b = self._belief
        mass = self._mass(b) if b is not None else np.zeros(len(self._classes))
        others = [i for i in self._holders(mass, a.part, max(a.hypothesis, 0))
                  if i != rep and mass[i] > 0]  # fmt: skip
        chosen = [rep, *others][:REAL_PLAN_MODELS]
        return [(i, self._best_state(i) or w.initial[i]) for i in chosen]

    def _likeliest(self, a: ManipAction, rng: np.random.Generator) -> tuple[int, WorldState]:
        """The model the real robot plans Pick or Place against, and its state: the
        likeliest particle that has the action's part and whose twin can
        make the action (not ``ik_infeasible``, not :data:`NOT_APPLICABLE`; the search
        chose the action for the models that can, and a plan made in one that cannot
        fails before anything moves), else the likeliest that has the part."""
        w = self._need_worlds()
        b = self._belief
        if b is None:
            return 0, w.initial[0]
        order = np.argsort(-b.weights, kind="stable")
        states = [b.states[j] for j in order]
        links = self.parts[a.part].links if a.skill == "Place" and a.part != TABLE else None
        has = [s for s in states if links is None or links[s.origin] is not None]
        cannot = {STATUS_CODES[x] for x in CANNOT_START}
        for s in has:  # the twins' outcomes are cached from the search, mostly
            if self.step(s, a, rng).obs.key[0] not in cannot:
                return s.origin, s.sim
        s = has[0] if has else states[0]
        return s.origin, s.sim

    def _best_state(self, origin: int) -> WorldState | None:
        b = self._belief
        if b is None:
            return None
        best = None
        for s, wt in zip(b.states, b.weights.tolist(), strict=True):
            if s.origin == origin and (best is None or wt > best[0]):
                best = (wt, s.sim)
        return None if best is None else best[1]

    # --- small queries -------------------------------------------------------------------
    def _target_index(self, origin: int) -> int | None:
        link = self.targets[origin] if 0 <= origin < len(self.targets) else None
        if link is None:
            return None
        for k, part in enumerate(self.parts):
            if part.links[origin] == link:
                return k
        return None

    def _own_kind(self, origin: int, k: int) -> str:
        w = self._need_worlds()
        return part_kind(w.particles[origin].spec.part(self.parts[k].links[origin]))

    def _holding(self, s: ManipState) -> bool:
        tw = self._need_worlds().twins[s.origin]
        tw.restore(s.sim)
        return holds_object(tw.world)

    def _open_enough(self, s: ManipState, k: int) -> bool:
        w = self._need_worlds()
        link = self.parts[k].links[s.origin]
        tw = w.twins[s.origin]
        tw.restore(s.sim)
        world = tw.world
        q = _position(world, w.particles[s.origin].spec.part(link).joint)
        T_now = world.cabinet_pose()
        return open_enough(w.particles[s.origin].spec, link, q, T_now)

    def _check_action(self, a: Hashable) -> ManipAction:
        if not isinstance(a, ManipAction) or a not in self._known:
            raise UnknownNameError(
                "action", str(a), [self._space.name(x) for x in self._space.discretized]
            )
        return a

    def _need_real(self) -> RealEpisode:
        if self.real is None:
            raise ConfigError(f"{self.name}: no episode yet (call sample_initial_state first)")
        return self.real

    def _need_worlds(self) -> ParticleWorlds:
        if self.worlds is None:
            raise ConfigError(f"{self.name}: no belief yet (call initial_belief first)")
        return self.worlds


def _attempt(run) -> Outcome | None:
    """``run()``, or None when the skill cannot be planned in this model (its plan
    raises: no handle at the grasp, no travel left, nothing held to place)."""
    try:
        return run()
    except (ConfigError, UnknownNameError):
        return None


def _handles(world: ManipulationWorld) -> dict[str, np.ndarray]:
    """The handles of ``world``'s cabinet's graspable parts where they are now, world
    (3,) [m], by link (:func:`.actions.part_point`)."""
    T, qs = world.cabinet_pose(), world.part_positions()
    out = {}
    for p in world.scene.cabinet_spec.movable_parts:
        pt = part_point(p, qs[world.scene.cabinet_prefix + p.joint], T)
        if pt is not None:
            out[p.link] = pt
    return out


def _position(world: ManipulationWorld, joint: str) -> float:
    """Cabinet joint ``joint``'s position in ``world`` [m or rad] (0 for a fixed part)."""
    return world.part_positions().get(world.scene.cabinet_prefix + joint, 0.0)


def _shut(world: ManipulationWorld, part: PartSpec) -> bool:
    """``part`` stands within :data:`SHUT` of closed in ``world`` (a fixed part always)."""
    kind = part.joint_type
    return kind == "fixed" or abs(_position(world, part.joint)) <= SHUT[kind]


def _first_feasible(runs) -> Outcome | None:
    """The outcome of the first of ``runs`` (callables, each a skill with its next
    grasp or placement) that is not ``ik_infeasible``, else the last one's (None when
    it could not be planned: :func:`_attempt`)."""
    out = None
    for run in runs:
        out = _attempt(run)
        if out is not None and out.status != "ik_infeasible":
            break
    return out


def _point(name: str, v: Sequence[float]) -> np.ndarray:
    arr = np.asarray(v, dtype=float).reshape(-1)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ConfigError(f"{name} must be a finite world point (x, y, z) [m], got {v!r}")
    return arr


def _part_at_point(
    spec: CabinetSpec, T: np.ndarray, point: np.ndarray, kinds: tuple[str, ...]
) -> str | None:
    """The part of ``kinds`` whose front cell contains ``point`` seen from the front
    (the cabinet frame's y, z), or None."""
    c = (np.linalg.inv(T) @ np.r_[point, 1.0])[:3]
    for p in spec.parts:
        if p.kind not in kinds:
            continue
        half = np.asarray(p.cell_size) / 2
        if abs(c[1] - p.cell_center[1]) <= half[0] and abs(c[2] - p.cell_center[2]) <= half[1]:
            return p.link
    return None


def _cells(spec: CabinetSpec, T: np.ndarray, kinds: tuple[str, ...]) -> list[list[float]]:
    return [np.round((T @ np.r_[p.cell_center, 1.0])[:3], 3).tolist()
            for p in spec.parts if p.kind in kinds]  # fmt: skip


class ShelfTask(ManipulationPOMDP):
    """The object goes onto an open shelf cell: no uncertainty needs reducing."""

    name = "shelf"
    task = "shelf"


class OpenDrawerTask(ManipulationPOMDP):
    """Only drawers; the object goes into the target drawer."""

    name = "opendrawer"
    task = "opendrawer"


class OpenDoorTask(ManipulationPOMDP):
    """Only doors and flaps; the object goes behind the target door."""

    name = "opendoor"
    task = "opendoor"
