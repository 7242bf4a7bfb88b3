"""What the twins' POMDP and the real robot share about one episode, as values.

- :class:`Catalogue`: the episode's parts named by where they are
  (:func:`.actions.catalogue`), and per model (initial particle) which of them it holds,
  as what kind, and which is its target; fixed for the episode once perception has run.
- :class:`Root`: what a search takes from the current real step, fixed within a search:
  per catalogued part and hypothesis the particle an opening or a probe follows
  (:func:`representatives`), each model's likeliest current state, and the actions the
  real robot refuses at the root.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from planners.particles import ParticleBelief
from strug_manip.domains.manipulation.actions import (
    CataloguePart,
    ManipAction,
    catalogue,
    part_at_point,
    part_kind,
)
from strug_manip.domains.manipulation.worlds import ParticleWorlds
from strug_manip.world.sim import WorldState

#: An opening or a probe is planned in at most this many models before the real robot
#: spends the step: the hypothesis's representative, then its next likeliest holders.
#: A plan that stops before anything moves (:data:`~.rules.BEFORE_MOTION`) costs a whole
#: step and is no evidence, so the belief cannot steer away from it; another holder's
#: model differs in where the handle, the hinge and the other parts are (a holder that
#: believes a neighbouring door ajar finds the approach to the target blocked).
#: Planning is cheap next to a step; three bounds what a step may spend on it.
PLAN_MODELS = 3


@dataclass(frozen=True)
class Catalogue:
    """The episode's catalogued parts and what each model holds of them.

    Attributes:
        parts: the catalogued parts (:class:`.actions.CataloguePart`).
        classes: per model, per part, the kinematic hypothesis it holds (None: it has
            no such part, or an open cell): what probes can tell apart.
        kinds: per model, per part, the kind of its own part (``shelf`` included;
            None: it has no such part).
        targets: per model, the link of its target part (None: it has none there).
    """

    parts: tuple[CataloguePart, ...] = ()
    classes: tuple[tuple[str | None, ...], ...] = ()
    kinds: tuple[tuple[str | None, ...], ...] = ()
    targets: tuple[str | None, ...] = ()

    def target_index(self, origin: int) -> int | None:
        """The catalogued part that is model ``origin``'s target (None: it has none)."""
        link = self.targets[origin] if 0 <= origin < len(self.targets) else None
        if link is None:
            return None
        for k, part in enumerate(self.parts):
            if part.links[origin] == link:
                return k
        return None

    def own_kind(self, origin: int, k: int) -> str:
        """The kind of model ``origin``'s own part at catalogued part ``k``."""
        kind = self.kinds[origin][k]
        if kind is None:
            raise KeyError(f"model {origin} has no part at catalogued part {k}")
        return kind

    def mass(self, belief: ParticleBelief) -> np.ndarray:
        """Each model's (particle origin's) weight in ``belief``, (n_models,)."""
        mass = np.zeros(len(self.classes))
        for s, wt in zip(belief.states, belief.weights.tolist(), strict=True):
            if s.origin >= 0:
                mass[s.origin] += wt
        return mass

    def holders(self, mass: np.ndarray, k: int, h: int) -> list[int]:
        """The models that hold hypothesis ``h`` of catalogued part ``k``, likeliest
        first (ties: the lowest index)."""
        kind = self.parts[k].hypotheses[h]
        held = [i for i in range(len(mass)) if self.classes[i][k] == kind]
        return sorted(held, key=lambda i: (-mass[i], i))


def build_catalogue(w: ParticleWorlds, kinds: tuple[str, ...], point: np.ndarray) -> Catalogue:
    """The :class:`Catalogue` of the particles of ``w``: their parts of ``kinds``
    catalogued by where they are (:func:`.actions.catalogue`), and each model's target,
    the part whose cell holds ``point`` (world (3,) [m])."""
    poses = [w.pose(i) for i in range(len(w))]
    particles = w.particles
    parts = catalogue([p.spec for p in particles], [p.q for p in particles], poses, kinds)
    own = tuple(
        tuple(None if (link := part.links[i]) is None
              else part_kind(particles[i].spec.part(link)) for part in parts)
        for i in range(len(w))
    )  # fmt: skip
    return Catalogue(
        parts=parts,
        classes=tuple(tuple(None if k == "shelf" else k for k in row) for row in own),
        kinds=own,
        targets=tuple(part_at_point(particles[i].spec, poses[i], point, kinds)
                      for i in range(len(w))),
    )  # fmt: skip


def representatives(
    cat: Catalogue, belief: ParticleBelief, previous: tuple[tuple[int, ...], ...]
) -> tuple[tuple[int, ...], ...]:
    """Per catalogued part and hypothesis, the particle whose grasp and joint the
    action follows: the likeliest particle of ``belief`` that holds the hypothesis
    (ties: the lowest index; none with weight: the ``previous`` one).

    Why not a fixed holder: particles of one hypothesis differ in where the hinge
    is (perception's noise), and the full robot's opening slips off a handle when
    the joint it follows is a few centimetres off. An opening that failed in the
    real world moves weight from the particles whose twins followed the joint
    successfully to those whose did not, so the next likeliest holder's joint is
    tried next; and a belief that has settled on one particle opens the part along
    that particle's own joint. Within one search the representatives are fixed
    (they change after a real step), so every search sees one POMDP."""
    mass = cat.mass(belief)
    out = []
    for k, part in enumerate(cat.parts):
        row = []
        for h in range(len(part.hypotheses)):
            held = cat.holders(mass, k, h)
            row.append(held[0] if held and mass[held[0]] > 0 else previous[k][h])
        out.append(tuple(row))
    return tuple(out)


def followers(
    cat: Catalogue, belief: ParticleBelief, reps: tuple[tuple[int, ...], ...]
) -> tuple[tuple[tuple[int, ...], ...], ...]:
    """Per catalogued part and hypothesis, the models an opening or a probe is planned
    in after the representative ``reps[k][h]``, while a plan stops before anything
    moves: the hypothesis's next likeliest holders with weight in ``belief``, at most
    :data:`PLAN_MODELS` with the representative (:meth:`Root.plan_models`); none
    before the episode's catalogue is built."""
    if not cat.classes:
        return ()
    mass = cat.mass(belief)
    return tuple(
        tuple(
            tuple(i for i in cat.holders(mass, k, h) if i != reps[k][h] and mass[i] > 0)[
                : PLAN_MODELS - 1
            ]
            for h in range(len(part.hypotheses))
        )
        for k, part in enumerate(cat.parts)
    )


def best_states(belief: ParticleBelief) -> dict[int, WorldState]:
    """Per model, the simulation state of its likeliest particle in ``belief`` (ties:
    the first)."""
    best: dict[int, tuple[float, WorldState]] = {}
    for s, wt in zip(belief.states, belief.weights.tolist(), strict=True):
        if s.origin not in best or wt > best[s.origin][0]:
            best[s.origin] = (wt, s.sim)
    return {i: sim for i, (_, sim) in best.items()}


@dataclass(frozen=True)
class Root:
    """What a search takes from the current real step (module docstring).

    Attributes:
        reps: per catalogued part and hypothesis, the particle an opening or a probe
            follows (:func:`representatives`).
        best: per model, its likeliest state in the current belief (:func:`best_states`):
            where an opening or a probe is planned.
        refused: the (action, particle it follows) pairs the real robot refuses at the
            root (:class:`.real.RealEpisode`).
        now: the step count of the root's states.
        also: per catalogued part and hypothesis, the models an opening or a probe is
            planned in after the representative's plan stops before anything moves
            (:func:`followers`; empty: none).
    """

    reps: tuple[tuple[int, ...], ...] = ()
    best: Mapping[int, WorldState] = field(default_factory=dict)
    refused: frozenset[tuple[ManipAction, int]] = frozenset()
    now: int = 0
    also: tuple[tuple[tuple[int, ...], ...], ...] = ()

    @classmethod
    def of(
        cls,
        cat: Catalogue,
        belief: ParticleBelief,
        reps: tuple[tuple[int, ...], ...],
        refused: frozenset[tuple[ManipAction, int]] = frozenset(),
        now: int = 0,
    ) -> Root:
        """The root of a search from ``belief``: the representatives ``reps``, each
        model's likeliest state and the followers derived from ``belief``."""
        return cls(reps, best_states(belief), refused, now, followers(cat, belief, reps))

    def plan_models(self, a: ManipAction) -> tuple[int, ...]:
        """The models opening or probe ``a`` is planned in, in turn, while a plan stops
        before anything moves: the representative, then :attr:`also`. The real robot
        tries them in this order, and so does every twin: a twin that stopped where the
        real robot goes on to the next model predicts a failure the real robot never
        shows (OpenDoor episode 10016: the representative's approach put the fingers
        3 mm into the carcass, every twin said ``ik_infeasible``, the real robot opened
        the door in the next model, and the true hypothesis lost its weight).
        ``(-1,)`` for Pick and Place, which follow none."""
        rep = self.rep(a)
        if rep < 0 or not self.also:
            return (rep,)
        return (rep, *self.also[a.part][max(a.hypothesis, 0)])

    def rep(self, a: ManipAction) -> int:
        """The particle whose grasp and joint opening or probe ``a`` follows (-1: Pick
        and Place, which follow none)."""
        if a.skill in ("Pick", "Place"):
            return -1
        return self.reps[a.part][max(a.hypothesis, 0)]
