"""The Tiger problems (Kaelbling, Littman & Cassandra 1998) and the paper's variants.

States: ``0`` tiger behind the left door, ``1`` behind the right door.
Actions (schema indices): ``0`` listen, ``1`` open the left door, ``2`` open the right door.
Observations: ``0`` hear the tiger on the left, ``1`` on the right, ``2`` nothing.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Hashable
from typing import Any

import numpy as np

from planners.belief import ParticleBelief
from planners.errors import ConfigError, ObservationError, check_positive_int
from planners.pomdp import ActionSchema, ActionSpace, GenerativePOMDP, RolloutPolicy, Step

LISTEN, OPEN_LEFT, OPEN_RIGHT = 0, 1, 2
HEAR_LEFT, HEAR_RIGHT, HEAR_NOTHING = 0, 1, 2
_OBS_NAMES = ("hear-left", "hear-right", "nothing")

_TIGER_SPACE = ActionSpace(
    schemas=(ActionSchema("listen"), ActionSchema("open-left"), ActionSchema("open-right")),
    discretized=(LISTEN, OPEN_LEFT, OPEN_RIGHT),
)


class ListenUntilSure(RolloutPolicy):
    """The Tiger rollout heuristic: listen until one side leads by ``margin``, then open.

    Its memory is the number of ``hear-left`` minus ``hear-right`` observations since the
    rollout started or last opened a door. While that lead is below ``margin`` it
    listens; then it opens the door the tiger was heard less behind, and starts
    counting again (on :class:`TigerClassic` the tiger is placed anew). ``nothing``
    (ExtendedTiger's uninformative listens) changes nothing. Margin 2 (default): with
    listening accuracy 0.85 a lead of 2 puts the belief at 0.85^2 / (0.85^2 + 0.15^2)
    = 0.97, where opening pays in expectation on both Tiger scales (+9.4 on Tiger, +6.7
    on TigerClassic) while a lead of 1 (0.85) would lose on TigerClassic (-6.5); this is
    the textbook policy of the classic Tiger.

    Args:
        margin: the lead of one side, in observations, at which a door is opened.
    """

    def __init__(self, margin: int = 2) -> None:
        self.margin = check_positive_int("margin", margin)

    def start(self) -> int:
        return 0

    def action(self, memory: int, rng: np.random.Generator) -> int:
        if memory >= self.margin:
            return OPEN_RIGHT
        if memory <= -self.margin:
            return OPEN_LEFT
        return LISTEN

    def update(self, memory: int, a: Hashable, o: Any) -> int:
        if a != LISTEN:
            return 0
        if o == HEAR_LEFT:
            return memory + 1
        if o == HEAR_RIGHT:
            return memory - 1
        return memory


class Tiger(GenerativePOMDP):
    """Tiger at the STRUG paper's scale (rewards in [-10, 10]).

    Constants:
        listen reward -1; opening the tiger's door -10; opening the treasure door +10;
        listening reports the tiger's side with probability ``accuracy`` = 0.85;
        discount 0.95; opening a door ends the episode (observation ``nothing``);
        at most 10 steps per episode; the tiger starts left or right with p = 0.5.
    """

    name = "tiger"
    discount = 0.95
    max_steps = 10
    max_abs_reward = 10.0
    discrete_observations = True

    listen_reward = -1.0
    opening_ends = True
    tiger_reward = -10.0
    treasure_reward = 10.0
    accuracy = 0.85

    def __init__(self) -> None:
        self._log_acc = math.log(self.accuracy)
        self._log_err = math.log(1.0 - self.accuracy)

    def action_space(self) -> ActionSpace:
        return _TIGER_SPACE

    def sample_initial_state(self, rng: np.random.Generator) -> int:
        return int(rng.random() < 0.5)

    def step(self, s: int, a: Hashable, rng: np.random.Generator) -> Step:
        if a == LISTEN:
            o = s if rng.random() < self.accuracy else 1 - s
            return Step(s, o, self.listen_reward, False)
        r = self.tiger_reward if a - 1 == s else self.treasure_reward
        return Step(s, HEAR_NOTHING, r, True)

    def plan_for(self, s: int, rng: np.random.Generator) -> list[int]:
        """The uncertainty-free plan: open the door without the tiger."""
        return [OPEN_RIGHT if s == 0 else OPEN_LEFT]

    def rollout_policy(self) -> ListenUntilSure:
        """The domain's rollout heuristic: :class:`ListenUntilSure` with margin 2."""
        return ListenUntilSure()

    def obs_loglik(self, o: Any, s_next: int, a: Hashable) -> float:
        if a == LISTEN:
            if o == HEAR_NOTHING:
                return -math.inf
            return self._log_acc if o == s_next else self._log_err
        return 0.0 if o == HEAR_NOTHING else -math.inf

    def check_observation(self, o: Any) -> None:
        if not isinstance(o, int | np.integer) or o not in (0, 1, 2):
            raise ObservationError(
                f"{self.name}: observation must be 0 (hear-left), 1 (hear-right) or "
                f"2 (nothing), got {o!r}"
            )

    def format_obs(self, o: Any) -> str:
        return _OBS_NAMES[int(o)]

    def summarize_belief(self, belief: ParticleBelief) -> str:
        p_left = float(belief.weights[np.asarray(belief.states) == 0].sum())
        return f"P(tiger left)={p_left:.3f}"

    def optimal_value(self, p_left: float = 0.5) -> float:
        """The exact optimal expected discounted return from ``P(tiger left) = p_left``.

        Backward induction over the exact beliefs reachable in ``max_steps`` steps (at
        most ``2 ** max_steps`` of them): the best any solver can do in expectation, the
        yardstick for a Table I column.
        """
        return _tiger_optimum(self, float(p_left), uninformative_listens=0)


def _tiger_optimum(domain: Tiger, p_left: float, uninformative_listens: int) -> float:
    gamma, acc = domain.discount, domain.accuracy
    best_door = max(domain.treasure_reward, domain.tiger_reward)
    worst_door = min(domain.treasure_reward, domain.tiger_reward)

    @functools.cache
    def value(p: float, listens: int, t: int) -> float:
        if t >= domain.max_steps:
            return 0.0
        q = max(p, 1.0 - p)  # open the door the tiger is less likely behind
        open_value = q * best_door + (1.0 - q) * worst_door
        if not domain.opening_ends:  # TigerClassic: the tiger is placed anew, p = 0.5
            open_value += gamma * value(0.5, 0, t + 1)
        listens = min(listens + 1, uninformative_listens + 1)
        if listens <= uninformative_listens:
            future = value(p, listens, t + 1)
        else:
            hear_left = p * acc + (1.0 - p) * (1.0 - acc)
            future = hear_left * value(p * acc / hear_left, listens, t + 1) + (
                1.0 - hear_left
            ) * value(p * (1.0 - acc) / (1.0 - hear_left), listens, t + 1)
        return max(open_value, domain.listen_reward + gamma * future)

    return value(p_left, 0, 0)


class TigerClassic(Tiger):
    """The classic Tiger every other library ships (Kaelbling et al. 1998).

    Constants: listen -1, tiger -100, treasure +10, listening accuracy 0.85, discount
    0.95. Opening a door does not end the episode: the tiger is placed behind a
    uniformly random door again and the observation after opening is uniformly
    random (uninformative). Episodes last 10 steps.
    """

    name = "tigerclassic"
    max_abs_reward = 100.0
    opening_ends = False
    tiger_reward = -100.0

    def step(self, s: int, a: Hashable, rng: np.random.Generator) -> Step:
        if a == LISTEN:
            o = s if rng.random() < self.accuracy else 1 - s
            return Step(s, o, self.listen_reward, False)
        r = self.tiger_reward if a - 1 == s else self.treasure_reward
        u = rng.random()
        s2 = int(u < 0.5)
        o = int((u * 4.0) % 2.0 >= 1.0)  # a second independent fair bit from the same draw
        return Step(s2, o, r, False)

    def obs_loglik(self, o: Any, s_next: int, a: Hashable) -> float:
        if o == HEAR_NOTHING:
            return -math.inf  # TigerClassic never observes "nothing"
        if a == LISTEN:
            return self._log_acc if o == s_next else self._log_err
        return math.log(0.5)


class ExtendedTiger(Tiger):
    """Tiger whose listening says nothing until the agent has listened several times.

    The state is ``(tiger, listens)``: the tiger's side and the number of listens so
    far (capped at ``listens_required + 1``). Listens number 1..``listens_required``
    return ``nothing``; every further listen returns the 0.85-accurate observation.
    All other constants are :class:`Tiger`'s (rewards -1/-10/+10, discount 0.95, the
    episode ends when a door is opened, at most 10 steps).

    Args:
        listens_required: uninformative listens before listening informs (default 3).
    """

    name = "extendedtiger"

    def __init__(self, listens_required: int = 3) -> None:
        super().__init__()
        self.listens_required = check_positive_int("listens_required", listens_required)
        if self.listens_required >= self.max_steps - 1:
            raise ConfigError(
                f"listens_required must be < {self.max_steps - 1} (max_steps - 1) for a "
                f"door to be openable after an informative listen, got {listens_required}"
            )

    def sample_initial_state(self, rng: np.random.Generator) -> tuple[int, int]:
        return (int(rng.random() < 0.5), 0)

    def step(self, s: tuple[int, int], a: Hashable, rng: np.random.Generator) -> Step:
        tiger, listens = s
        if a == LISTEN:
            listens = min(listens + 1, self.listens_required + 1)
            if listens <= self.listens_required:
                return Step((tiger, listens), HEAR_NOTHING, self.listen_reward, False)
            o = tiger if rng.random() < self.accuracy else 1 - tiger
            return Step((tiger, listens), o, self.listen_reward, False)
        r = self.tiger_reward if a - 1 == tiger else self.treasure_reward
        return Step(s, HEAR_NOTHING, r, True)

    def plan_for(self, s: tuple[int, int], rng: np.random.Generator) -> list[int]:
        """The uncertainty-free plan: open the door without the tiger."""
        return [OPEN_RIGHT if s[0] == 0 else OPEN_LEFT]

    def obs_loglik(self, o: Any, s_next: tuple[int, int], a: Hashable) -> float:
        tiger, listens = s_next
        if a == LISTEN and listens > self.listens_required:
            if o == HEAR_NOTHING:
                return -math.inf
            return self._log_acc if o == tiger else self._log_err
        return 0.0 if o == HEAR_NOTHING else -math.inf

    def optimal_value(self, p_left: float = 0.5) -> float:
        """The exact optimal expected discounted return from ``P(tiger left) = p_left``
        and no listens yet (backward induction, as :meth:`Tiger.optimal_value`)."""
        return _tiger_optimum(self, float(p_left), self.listens_required)

    def summarize_belief(self, belief: ParticleBelief) -> str:
        tigers = np.array([s[0] for s in belief.states])
        p_left = float(belief.weights[tigers == 0].sum())
        listens = belief.states[int(np.argmax(belief.weights))][1]
        return f"P(tiger left)={p_left:.3f} listens={listens}"
