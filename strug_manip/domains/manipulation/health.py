"""Belief health: how the real belief treats the true model, step by step (evaluation
only: the real robot's environment, :mod:`.real`, knows the true cabinet; the robot
does not).

A model (an initial particle) holds the **true hypothesis** of a real part when its part
there has the real part's joint: the same type, the axis within 10 deg, the hinge line
or origin within 5 cm (:func:`~strug_manip.objects.hypotheses.true_hypothesis`, the
criterion of perception's ``true_in_support``). Its **weight** is the belief's mass on
the models that hold it. The parts that matter: the task's target (the real target part
against the models' targets, the parts at the target point), and the part an action
touched (an opening's, a probe's, a ``Place``'s catalogued part against the real part
it acts on, :meth:`.real.RealEnvironment.real_link`: the one whose handle is nearest
the catalogued point, or, in a cabinet without handles (Shelf's cells), the one whose
cell holds it; ``Pick`` and ``Place(table)`` touch the target).

:class:`HealthRecorder` keeps, per episode (the report's ``health``,
:meth:`HealthRecorder.as_dict`): the initial weight of the true target hypothesis and
how many models hold it, and how many models' target part an action can act on; per
real step (:class:`StepHealth`) the true hypotheses' weights before and after the
step's update, the model the real robot planned in and whether it holds the true
hypothesis, and the key the twin of the best particle of the true hypothesis (the
likeliest before the step) predicted against the real key
(:data:`~.state.ManipObservation.key`); and ``lost_at``, the first step after which the
true target hypothesis held less than :data:`LOST_WEIGHT`.

Everything is read from values the episode computes anyway (the beliefs before and
after each update, the twins' predicted keys their states carry, the outcome cache
peeked without counting): recording simulates nothing and changes no episode.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from planners.particles import ParticleBelief
from strug_manip.domains.manipulation.actions import TABLE, ManipAction, part_at_point
from strug_manip.domains.manipulation.catalogue import Catalogue
from strug_manip.domains.manipulation.state import STATUS_CODES
from strug_manip.domains.manipulation.worlds import ParticleWorlds
from strug_manip.objects.generator import CabinetSpec
from strug_manip.objects.hypotheses import true_hypothesis

#: The true hypothesis counts as lost when the belief's weight on it falls below this:
#: the search's 12 root particles, drawn by weight, then miss it 9 times in 10
#: (0.99 ** 12 = 0.89), so no plan made for it competes.
LOST_WEIGHT = 0.01
#: Observation key status codes back to their names.
STATUS_NAMES: dict[int, str] = {code: name for name, code in STATUS_CODES.items()}


def status_of(key: Sequence[float] | None) -> str | None:
    """The status named in an observation key (None: no key)."""
    return None if key is None else STATUS_NAMES[int(key[0])]


@dataclass
class StepHealth:
    """The belief's health around one real step.

    Attributes:
        step: index from 0.
        action: the action, as the step records name it.
        part: the real part (link) the action touched (``Pick``, ``Place(table)``: the
            target); None: no real part there.
        planned_in: the model the real robot planned the action in.
        planned_true: that model holds the true hypothesis of ``part`` (None: no part).
        real_key, real_status: the real observation's key and its status.
        twin_key, twin_status: the key the twin of the best particle of the true
            hypothesis of ``part`` predicted (None: no model holds it, or the episode
            ended before the update and the search never simulated it).
        reward: the step's reward.
        news: the real cloud showed the cabinet changed (it was weighed).
        target_before, target_after: weight of the true target hypothesis in the belief
            the step was planned in, and after its update (None: the episode ended).
        part_before, part_after: the same for ``part`` (None: no real part).
    """

    step: int
    action: str
    part: str | None
    planned_in: int
    planned_true: bool | None
    real_key: tuple[float, ...]
    real_status: str
    twin_key: tuple[float, ...] | None
    twin_status: str | None
    reward: float
    news: bool
    target_before: float
    part_before: float | None
    target_after: float | None = None
    part_after: float | None = None


@dataclass(frozen=True)
class RealStep:
    """What the real robot did in one step, as :meth:`HealthRecorder.record` reads it.

    Attributes:
        step: index from 0.
        action: the action.
        name: the action as the step records name it.
        planned_in: the model it was planned in.
        key: the real observation's key.
        reward: the step's reward.
        news: the real cloud was weighed (the cabinet changed).
        rep: the particle the action follows (:meth:`.catalogue.Root.rep`).
    """

    step: int
    action: ManipAction
    name: str
    planned_in: int
    key: tuple[float, ...]
    reward: float
    news: bool
    rep: int


class HealthRecorder:
    """The belief health of one episode (module docstring).

    Args:
        cat: the episode's catalogue (which part each model holds where).
        w: the models' worlds (their cabinets and where they stand; the outcome cache).
        truth: the real cabinet; ``T_truth``: where it stood when the episode began
            (4, 4).
        target: the real target part (link).
        real_link: the real part (link) at a catalogued part, or None.
        max_steps: the episode's step limit.
        initial: the initial belief (conditioned).
    """

    def __init__(
        self,
        cat: Catalogue,
        w: ParticleWorlds,
        truth: CabinetSpec,
        T_truth: np.ndarray,
        target: str,
        real_link: Callable[[int], str | None],
        max_steps: int,
        initial: ParticleBelief,
    ) -> None:
        self.cat, self.w, self.truth, self.T_truth = cat, w, truth, T_truth
        self.target, self.real_link, self.max_steps = target, real_link, max_steps
        self._target = self._holders([cat.targets[i] for i in range(len(w))], target)
        self._parts: dict[int, tuple[str | None, np.ndarray | None]] = {}
        #: The initial belief's weight on the true target hypothesis, and its holders.
        self.initial = (self._weight(initial, self._target), int(self._target.sum()))
        #: How many models' target part an action can act on (a catalogued part: one
        #: with a handle, or a shelf's cell; :func:`.actions.part_point`).
        self.catalogued = sum(cat.target_index(i) is not None for i in range(len(w)))
        self.steps: list[StepHealth] = []
        self._pending: tuple[int, np.ndarray | None] | None = None

    def _holders(self, links: Sequence[str | None], true_link: str) -> np.ndarray:
        """Per model, whether its part ``links[i]`` holds the true hypothesis of the
        real part ``true_link``, (n_models,) bool."""
        truth = self.truth.part(true_link)
        ps = self.w.particles
        return np.array([link is not None and true_hypothesis(
            ps[i].spec.part(link), self.w.pose(i), truth, self.T_truth)
            for i, link in enumerate(links)], dtype=bool)  # fmt: skip

    def _touched(self, a: ManipAction) -> tuple[str | None, np.ndarray | None]:
        """The real part action ``a`` touched and, per model, whether it holds its true
        hypothesis (the target's for Pick and Place(table))."""
        if a.skill == "Pick" or a.part == TABLE:
            return self.target, self._target
        if a.part not in self._parts:
            cell = self.cat.parts[a.part]
            link = self.real_link(a.part)
            if link is None:  # no graspable part (Shelf's cells): the part at its point
                kinds = tuple({p.kind for p in self.truth.parts})
                link = part_at_point(self.truth, self.T_truth, cell.point, kinds)
            links = cell.links
            self._parts[a.part] = (link, None if link is None else self._holders(links, link))
        return self._parts[a.part]

    def _weight(self, belief: ParticleBelief, holds: np.ndarray) -> float:
        """The mass of ``belief`` on the models ``holds`` marks."""
        return float(self.cat.mass(belief) @ holds)

    def _maybe(self, belief: ParticleBelief, holds: np.ndarray | None) -> float | None:
        return None if holds is None else self._weight(belief, holds)

    def record(self, prior: ParticleBelief, real: RealStep) -> None:
        """One real step, planned in belief ``prior``; the twin's key peeked from the
        outcome cache until :meth:`updated` reads it off the updated belief."""
        part, holds = self._touched(real.action)
        best = _best(prior, holds)
        twin = None
        if best is not None:
            s = prior.states[best]
            hit = self.w.outcomes.get((s.origin, s.sim.key, real.action, real.rep))
            twin = None if hit is None else tuple(hit[1])
        right = None if holds is None else bool(0 <= real.planned_in < len(holds)
                                                 and holds[real.planned_in])  # fmt: skip
        self.steps.append(StepHealth(
            real.step, real.name, part, real.planned_in, right, tuple(real.key),
            str(status_of(real.key)), twin, status_of(twin), real.reward, real.news,
            self._weight(prior, self._target), self._maybe(prior, holds),
        ))  # fmt: skip
        self._pending = (best if best is not None else -1, holds)

    def updated(self, belief: ParticleBelief) -> None:
        """The last recorded step's belief after its update (conditioned): the weights
        after, and the key the best true particle's twin predicted (its state's
        ``last``; particles keep their positions: the real belief is never resampled)."""
        if self._pending is None or not self.steps:
            return
        best, holds = self._pending
        h = self.steps[-1]
        h.target_after = self._weight(belief, self._target)
        h.part_after = self._maybe(belief, holds)
        if 0 <= best < len(belief) and belief.states[best].last:
            h.twin_key = tuple(belief.states[best].last)
            h.twin_status = status_of(h.twin_key)
        self._pending = None

    def lost_at(self) -> int | None:
        """The first step after which the true target hypothesis held less than
        :data:`LOST_WEIGHT`, having held at least that before it (None: never)."""
        for h in self.steps:
            if h.target_after is not None and h.target_before >= LOST_WEIGHT > h.target_after:
                return h.step
        return None

    def as_dict(self) -> dict[str, Any]:
        """The report's ``health`` (JSON-ready)."""
        return {
            "target": self.target,
            "max_steps": self.max_steps,
            "lost_weight": LOST_WEIGHT,
            "initial": {
                "weight": self.initial[0],
                "models": self.initial[1],
                "catalogued": self.catalogued,
            },
            "lost_at": self.lost_at(),
            "steps": [dataclasses.asdict(h) for h in self.steps],
        }


def _best(belief: ParticleBelief, holds: np.ndarray | None) -> int | None:
    """The position in ``belief`` of the likeliest particle whose model holds the true
    hypothesis (ties: the first), or None."""
    if holds is None:
        return None
    mine = [j for j, s in enumerate(belief.states) if 0 <= s.origin < len(holds)
            and holds[s.origin]]  # fmt: skip
    if not mine:
        return None
    return max(mine, key=lambda j: (belief.weights[j], -j))
