"""The state and observation of the manipulation POMDPs.

A state is one cabinet model (the initial belief particle it descends from, or the
real world), the simulation state of that model's world (a snapshot of its planning
twin, or of the real world) and the step count. States compare and hash by value, so
the search trees, the outcome cache and the belief's importance correction can tell
equal ones apart from different ones.

An observation carries two things:

* ``key``: what the skill's outcome lets the robot see at once, as a flat tuple of
  numbers: the outcome's status, whether the hand holds something, and how far the
  acted part's handle moved (x, y, z, in :data:`MOTION_BIN` bins). The twin's outcome
  determines it, so the search trees file observations under it (discrete keys
  inside the tree, as ``GenerativePOMDP.observation_key`` asks).
* ``cloud``: the head camera's point cloud of the cabinet after the skill, (N, 3)
  world [m]; only real observations have one (rendering every simulated step would
  cost more than the simulation). The belief update weighs particles by it
  (:mod:`perception.likelihood`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from strug_manip.control import Status
from strug_manip.world.sim import WorldState

#: ``ManipState.origin`` of the real world (not a belief particle).
REAL = -1
#: Bin of the handle's motion in an observation key [m]: finer than any skill's travel
#: (a drawer opens 0.25 m, a door's handle swings 0.15-0.3 m), coarser than the twin's
#: disagreement with the full robot on a part's motion (1 cm).
MOTION_BIN = 0.05
#: The status of an action that cannot be made in a model (its part is not there, the
#: object does not fit, nothing is held to place): nothing moves.
NOT_APPLICABLE = "not_applicable"
#: Status codes in observation keys (the order of :class:`Status`, then
#: :data:`NOT_APPLICABLE`).
STATUS_CODES: dict[str, int] = {
    **{str(s): i for i, s in enumerate(Status)},
    NOT_APPLICABLE: len(Status),
}


@dataclass(frozen=True, eq=False)
class ManipState:
    """One state of a manipulation POMDP.

    Attributes:
        origin: index of the initial belief particle (the cabinet model) this state
            simulates, or :data:`REAL` for the real world.
        sim: the simulation state of that model's world.
        t: steps taken so far.
        last: the observation key of the step that led here (() at the start); not
            part of the state's identity (the likelihood of simulated observations
            compares it).
    """

    origin: int
    sim: WorldState
    t: int
    last: tuple[float, ...] = ()

    @property
    def key(self) -> tuple[int, bytes, int]:
        return (self.origin, self.sim.key, self.t)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ManipState) and self.key == other.key

    def __hash__(self) -> int:
        return hash(self.key)


@dataclass(frozen=True, eq=False)
class ManipObservation:
    """What the robot sees after a skill (module docstring).

    Attributes:
        key: ``(status code, holding, dx, dy, dz)`` (the handle's motion in bins of
            :data:`MOTION_BIN`, world frame).
        cloud: the head camera's cabinet points, (N, 3) [m]; None inside a search.
        summary: the skill's outcome in one line, for people.
        news: the cloud shows the cabinet changed (a part or its base moved by a
            millimetre or more) since the last cloud the belief weighed, or is the
            first: only then is it weighed. A model's misfit to a cabinet that has not
            changed is the same misfit again (perception's error, not independent
            noise), and weighing it at every step compounds one piece of evidence
            into certainty.
        on_the_way: the full robot stopped on its way to the part (the drive or the
            reach met something: :attr:`~strug_manip.control.Outcome.on_the_way`). The
            twins have no arm on the way, so their keys predict a run that reached the
            part, and a key that differs from theirs says nothing about the part: the
            real update does not weigh it (the cloud still, when it is news).
    """

    key: tuple[float, ...]
    cloud: np.ndarray | None = field(default=None, repr=False)
    summary: str = ""
    news: bool = True
    on_the_way: bool = False


def observation_key(status: str, holding: bool, motion: np.ndarray) -> tuple[float, ...]:
    """The key of an outcome: status, holding and the handle's motion (3,) [m] binned."""
    bins = np.round(np.asarray(motion, dtype=float) / MOTION_BIN).astype(int)
    return (float(STATUS_CODES[str(status)]), float(bool(holding)), *map(float, bins))
