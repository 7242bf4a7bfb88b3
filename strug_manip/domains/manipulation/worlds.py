"""The compiled worlds of one episode's particles, and what is cached about them.

Per initial particle (a cabinet model): its planning twin (where its skills are
simulated), a world of the same cabinet with the full Fetch (the planning world the
real robot's skills are made against when that particle is believed, and the camera
that predicts its point clouds), and its initial simulation state. All are built once
per episode; the twins share one :class:`~strug_manip.control.context.ControlContext`,
so a base placement found for one particle serves every particle whose world offers
the same plan the same state.

Caches (bounded, least recently used dropped first):

* **outcomes**, keyed by (particle, simulation state, action): a skill on a twin is
  deterministic, so a search never simulates the same thing twice;
* **clouds**, keyed by (particle, the cabinet's joint positions to the millimetre):
  the point cloud each particle predicts for the belief update;
* **relevance**, keyed by (particle, simulation state): which actions that particle's
  plan takes next (the tree nodes' action prior).
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from perception.likelihood import voxel_thin
from strug_manip.cache import LRU
from strug_manip.control import ControlContext, PlanningTwin
from strug_manip.domains.manipulation.belief import Particle
from strug_manip.world.rendering import RenderContext
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld, WorldState
from strug_manip.world.views import LookPose, cabinet_cloud, place_robot

#: Outcomes kept (a state is ~2 kB; 20,000 of them about 40 MB).
OUTCOMES = 20_000
#: Predicted clouds kept.
CLOUDS = 2_000


@dataclass
class Timers:
    """Where an episode's time goes [s] (the domain's report)."""

    twin: float = 0.0
    render: float = 0.0
    likelihood: float = 0.0
    real: float = 0.0
    perception: float = 0.0
    setup: float = 0.0

    def as_dict(self) -> dict[str, float]:
        return {k: round(v, 3) for k, v in vars(self).items()}


class ParticleWorlds:
    """The worlds of an episode's initial particles (module docstring).

    Args:
        particles: the initial belief particles.
        config: the real scene (its table, object and cabinet placement).
        ctx: the shared control context.
    """

    def __init__(
        self, particles: Sequence[Particle], config: SceneConfig, ctx: ControlContext
    ) -> None:
        self.particles = list(particles)
        self.config, self.ctx = config, ctx
        self.twins: list[PlanningTwin] = []
        self.initial: list[WorldState] = []
        for p in self.particles:
            tw = PlanningTwin(p.spec, config, ctx)
            tw.reset(p.q)
            self.twins.append(tw)
            self.initial.append(tw.snapshot())
        self._fetch: dict[int, ManipulationWorld] = {}
        # The particles' head-camera renders share one OpenGL context (most of a
        # renderer's set-up is a fresh context's).
        self._render = RenderContext()
        self.outcomes = LRU(OUTCOMES)
        # Whether an action can start in a particle state, where not simulated yet.
        self.can_start = LRU(OUTCOMES)
        # Per particle state, the task relevance of the actions (the action prior).
        self.relevance = LRU(OUTCOMES)
        self.clouds = LRU(CLOUDS)
        self.timers = Timers()

    def __len__(self) -> int:
        return len(self.particles)

    def pose(self, i: int) -> np.ndarray:
        """Particle ``i``'s cabinet frame at its reset, (4, 4)."""
        return self.twins[i].world.scene.T_world_cabinet

    def fetch(self, i: int, state: WorldState | None = None) -> ManipulationWorld:
        """The world of particle ``i``'s cabinet with the Fetch, its cabinet (parts and
        base) as in ``state`` of the particle's twin (default: the initial one)."""
        w = self._fetch.get(i)
        if w is None:
            w = ManipulationWorld.from_cabinet_spec(
                self.particles[i].spec, self.config, self._render
            )
            self._fetch[i] = w
        tw = self.twins[i]
        tw.restore(self.initial[i] if state is None else state)
        w.reset()
        w.copy_joints(tw.world, [*w.part_joints, w.scene.cabinet_prefix + "free"])
        return w

    def set_uppers(self, i: int, uppers: Mapping[str, float], parts: Collection[int]) -> None:
        """Particle ``i``'s cabinet with the upper limits of the parts ``uppers`` names
        (link -> limit [m or rad]) set to those values: its particle, its twin and its
        Fetch world rebuilt from the new description. Its states stay valid (a limit
        changes no state's layout), and so do its predicted clouds (a limit does not
        show). A particle's limit moves only when a real front passes it or a real
        opening meets its end (:mod:`.conditioning`).

        Dropped from the caches, as simulated under the old limits: particle ``i``'s
        outcomes, start checks and action relevances, and every particle's outcomes and
        start checks of actions on the catalogued ``parts`` (those ``uppers`` names in
        ``i``): an opening goes on toward the longest limit any particle holds for its
        part (:func:`~.grounding.longest_travel`). The rest stay valid, and the next
        search reuses them."""
        p = self.particles[i]
        described = tuple(
            replace(q, upper=float(uppers[q.link])) if q.link in uppers else q for q in p.spec.parts
        )
        spec = replace(p.spec, parts=described)
        self.particles[i] = replace(p, spec=spec)
        old, self.twins[i] = self.twins[i], PlanningTwin(spec, self.config, self.ctx)
        old.world.close()
        fetch = self._fetch.pop(i, None)
        if fetch is not None:
            fetch.close()
        for cache in (self.outcomes, self.can_start):  # keyed (particle, state, action, ...)
            for key in [k for k in cache if k[0] == i or k[2].part in parts]:
                del cache[key]
        for key in [k for k in self.relevance if k[0] == i]:  # keyed (particle, state)
            del self.relevance[key]

    def predicted_cloud(self, i: int, state: WorldState, pose: LookPose) -> np.ndarray:
        """The head camera's cabinet cloud (N, 3) [m] particle ``i`` predicts in
        ``state``, seen from ``pose``, thinned to the likelihood's voxels (cached by the
        cabinet's joints to the mm: equal keys give the same array object)."""
        tw = self.twins[i]
        tw.restore(state)
        w = tw.world
        key = (i, w.cabinet_key())
        cloud = self.clouds.lookup(key)
        if cloud is None:
            fw = self.fetch(i, state)
            place_robot(fw, pose)
            cloud = voxel_thin(cabinet_cloud(fw, fw.render(colour=False)))
            self.clouds.store(key, cloud)
        return cloud

    def close(self) -> None:
        for w in (*self._fetch.values(), *(t.world for t in self.twins)):
            w.close()
        self._fetch.clear()
        self._render.close()
