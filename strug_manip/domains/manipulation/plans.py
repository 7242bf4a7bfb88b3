"""A particle's uncertainty-free plan and the task relevance of actions (the action
prior the tree solvers order untried actions by).

Under its own model a particle's plan is: open its target part (under each hypothesis
the catalogue holds for it, its own first), ``Pick`` the object, ``Place`` it into the
part; steps already done are left out (the part open enough, the object held). Shelf
needs no opening. :meth:`.model.ManipulationPOMDP.plan_for` runs these plans forward on
the particle; :meth:`.model.ManipulationPOMDP.action_prior` scores the actions by them
(:func:`relevance`, summed over a node's particles by :func:`prior_scores`).
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Sequence

from strug_manip.cache import LRU
from strug_manip.domains.manipulation.actions import TABLE, ManipAction
from strug_manip.domains.manipulation.catalogue import Catalogue
from strug_manip.domains.manipulation.state import REAL, ManipState

#: Task relevance of an action to one particle (dimensionless, summed over a node's
#: particles by weight): the next step of the particle's plan (open its target part
#: under its own hypothesis; ``Pick`` once the part is open enough; ``Place`` into it
#: once the object is held; ``Place(table)`` when the object is held and the part still
#: closed: one hand) ...
NEXT = 1.0
#: ... another action on its target part (an opening under another hypothesis, a probe:
#: what tells the hypotheses apart). Anything else scores 0, later steps of the plan
#: included: a ``Pick`` while the part is closed costs the ``Place(table)`` that undoes
#: it, so it must not win ties among actions whose simulations found nothing (measured
#: on tuning seed 9107: ranked before the other parts' actions it was chosen at value 0
#: and cycled with ``Place(table)``).
ON_TARGET = 0.5

#: ``holding(s)``: particle state ``s`` holds the object.
Holding = Callable[[ManipState], bool]
#: ``open_enough(s, k)``: part ``k`` stands open enough in particle state ``s``.
OpenEnough = Callable[[ManipState, int], bool]


def _opening(cat: Catalogue, k: int, h: int) -> ManipAction:
    """The opening of part ``k`` under hypothesis ``h`` (a drawer's or a hinge's)."""
    opening = "OpenDrawer" if cat.parts[k].hypotheses[h] == "drawer" else "OpenDoor"
    return ManipAction(opening, k, h)


def _tail(task: str, k: int, holding: bool) -> list[ManipAction]:
    """The plan's steps after the opening of part ``k``: Pick (not when ``holding``),
    then Place into ``k``."""
    grasp = "top" if task == "opendrawer" else "side"
    tail = [ManipAction("Pick", grasp=grasp), ManipAction("Place", k)]
    return tail[1:] if holding else tail


def plan_candidates(
    task: str, cat: Catalogue, s: ManipState, holding: Holding, open_enough: OpenEnough
) -> tuple[list[list[ManipAction]], bool]:
    """``(plans, opened)``: particle state ``s``'s plans, one per hypothesis of its
    target part (its own first), or the one plan without an opening when ``opened``
    (Shelf, or the part open enough); no plan without a target part."""
    k = cat.target_index(s.origin)
    if k is None:
        return [], False
    tail = _tail(task, k, holding(s))
    if task == "shelf" or open_enough(s, k):
        return [tail], True
    own = cat.parts[k].hypotheses.index(cat.own_kind(s.origin, k))
    order = [own, *(h for h in range(len(cat.parts[k].hypotheses)) if h != own)]
    return [[_opening(cat, k, h), *tail] for h in order], False


def relevance(
    task: str,
    cat: Catalogue,
    s: ManipState,
    actions: Iterable[ManipAction],
    holding: Holding,
    open_enough: OpenEnough,
) -> dict[ManipAction, float]:
    """Particle state ``s``'s relevance of the episode's ``actions`` (module constants;
    the actions it leaves out score 0)."""
    k = cat.target_index(s.origin)
    if k is None:
        return {}
    rel = {a: ON_TARGET for a in actions if a.part == k and a.skill not in ("Pick", "Place")}
    plans, opened = plan_candidates(task, cat, s, holding, open_enough)
    first = plans[0]
    # Held with the part closed (the opening is followed by Place): put it down first.
    put_down = not opened and first[1].skill == "Place"
    rel[ManipAction("Place", TABLE) if put_down else first[0]] = NEXT
    return rel


def prior_scores(
    states: Sequence[ManipState],
    weights: Sequence[float],
    actions: Sequence[Hashable],
    cache: LRU,
    relevance_of: Callable[[ManipState], dict[ManipAction, float]],
) -> list[float]:
    """Per action, shape ``(len(actions),)``: the sum over the node's particles, by
    weight, of their :func:`relevance` (``relevance_of``), cached per particle state in
    ``cache``; the real state and zero weights count nothing."""
    score: dict[Hashable, float] = {}
    for s, wt in zip(states, weights, strict=True):
        if s.origin == REAL or wt <= 0.0:
            continue
        key = (s.origin, s.sim.key)
        rel = cache.get(key)
        if rel is None:
            rel = relevance_of(s)
            cache.store(key, rel)
        for a, v in rel.items():
            score[a] = score.get(a, 0.0) + wt * v
    return [score.get(a, 0.0) for a in actions]
