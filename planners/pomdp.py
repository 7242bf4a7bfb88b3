"""The generative-model protocol every solver plans against.

A POMDP here is what POMDPs.jl calls a *generative* model: a function
``step(s, a, rng) -> Step(state, obs, reward, done)`` that draws one transition, plus
``obs_loglik(o, s_next, a)`` for weighting particles with continuous observations.
Nothing else about the transition needs a closed form.

Actions are *hybrid*: the action space is a tuple of :class:`ActionSchema` (a
controller kind, e.g. ``listen`` or ``move``), each with a box of continuous
parameters (possibly none). A purely discrete domain has schemas of dimension 0 and
its actions are the schema indices (plain ``int``); a hybrid domain uses
:class:`HybridAction` ``(schema, params)``. Either way actions are hashable, which the
search trees rely on to merge repeated samples.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from planners.errors import ConfigError, ObservationError

if TYPE_CHECKING:
    from planners.belief import ParticleBelief


class Step(NamedTuple):
    """One draw of the generative model: next state, observation, reward, terminal flag."""

    state: Any
    obs: Any
    reward: float
    done: bool


class HybridAction(NamedTuple):
    """An action of a hybrid space: the schema index and its continuous parameters."""

    schema: int
    params: tuple[float, ...]


@dataclass(frozen=True)
class ActionSchema:
    """One kind of action (a controller) with a box of continuous parameters.

    Attributes:
        name: human-readable name, e.g. ``"move"``.
        low: lower bounds of the parameters, shape ``(dim,)``; empty for no parameters.
        high: upper bounds, same shape as ``low``.
    """

    name: str
    low: tuple[float, ...] = ()
    high: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if len(self.low) != len(self.high):
            raise ConfigError(
                f"schema {self.name!r}: low has {len(self.low)} bounds, high has {len(self.high)}"
            )
        for lo, hi in zip(self.low, self.high, strict=True):
            if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
                raise ConfigError(f"schema {self.name!r}: bad parameter bounds [{lo}, {hi}]")

    @property
    def dim(self) -> int:
        """Number of continuous parameters."""
        return len(self.low)


@dataclass(frozen=True)
class ActionSpace:
    """The hybrid action space of a domain.

    Attributes:
        schemas: the action kinds, indexed by position.
        discretized: a finite action set for solvers that need one (POMCP). For a
            purely discrete space it is every action; for a continuous one it is the
            domain's documented discretisation (e.g. 8 unit moves + stop).
        make: builds an action from ``(schema index, params tuple)``; defaults to the
            schema index for parameter-free schemas and :class:`HybridAction` otherwise.
        describe: formats an action for people.
    """

    schemas: tuple[ActionSchema, ...]
    discretized: tuple[Hashable, ...]
    make: Callable[[int, tuple[float, ...]], Hashable] | None = None
    describe: Callable[[Hashable], str] | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if not self.schemas:
            raise ConfigError("an action space needs at least one schema")
        if not self.discretized:
            raise ConfigError("an action space needs a non-empty discretized action set")

    @property
    def is_discrete(self) -> bool:
        """True when no schema has continuous parameters (the action set is finite)."""
        return all(s.dim == 0 for s in self.schemas)

    def build(self, schema: int, params: tuple[float, ...]) -> Hashable:
        """The action of ``schema`` with ``params`` (clipped to the schema's box)."""
        if self.make is not None:
            return self.make(schema, params)
        if self.is_discrete:
            return schema
        return HybridAction(schema, params)

    def sample_params(self, schema: int, rng: np.random.Generator) -> tuple[float, ...]:
        """Uniform parameters inside the box of ``schema``; shape ``(dim,)`` as a tuple."""
        sc = self.schemas[schema]
        if sc.dim == 0:
            return ()
        return tuple(rng.uniform(sc.low, sc.high).tolist())

    def sample(self, rng: np.random.Generator) -> Hashable:
        """A uniform schema, then uniform parameters in its box.

        For a purely discrete space this is a uniform draw from ``discretized``.
        """
        if self.is_discrete:
            return self.discretized[int(rng.integers(len(self.discretized)))]
        schema = int(rng.integers(len(self.schemas)))
        return self.build(schema, self.sample_params(schema, rng))

    def name(self, a: Hashable) -> str:
        """A readable name of ``a``."""
        if self.describe is not None:
            return self.describe(a)
        if isinstance(a, int):
            return self.schemas[a].name
        if isinstance(a, HybridAction):
            if not a.params:
                return self.schemas[a.schema].name
            p = ", ".join(f"{x:+.2f}" for x in a.params)
            return f"{self.schemas[a.schema].name}({p})"
        return repr(a)


def format_value(x: Any) -> str:
    """Floats with 3 decimals, tuples element-wise, anything else as ``str``."""
    if isinstance(x, tuple):
        return "(" + ", ".join(format_value(v) for v in x) + ")"
    if isinstance(x, float | np.floating):
        return f"{x:.3f}"
    return str(x)


class RolloutPolicy(ABC):
    """A domain's own rollout heuristic (see :meth:`GenerativePOMDP.rollout_policy`).

    Tree searches estimate the value of a new node with a rollout. A uniformly random
    rollout knows nothing about the domain, and on a domain with a large penalty (the
    classic Tiger's -100 door) its returns are so noisy that they mislead the search for
    thousands of simulations. A heuristic policy gives leaf values that are closer to
    the truth and far less noisy.

    The policy sees only what an agent could: the actions it took and the observations
    it received since the rollout started, folded into a small *memory* (never the
    state the rollout simulates). A rollout calls ``memory = start()``, then per step
    ``a = action(memory, rng)`` and, after the step, ``memory = update(memory, a, o)``.
    """

    def start(self) -> Any:
        """The memory at the start of a rollout (default None)."""
        return None

    @abstractmethod
    def action(self, memory: Any, rng: np.random.Generator) -> Hashable:
        """The next rollout action given ``memory``."""

    def update(self, memory: Any, a: Hashable, o: Any) -> Any:
        """The memory after action ``a`` and observation ``o`` (default: unchanged)."""
        return memory


class GenerativePOMDP(ABC):
    """Base class of the domains: the protocol solvers use, plus sensible defaults.

    Subclasses set the class attributes and implement the abstract methods.

    Attributes:
        name: canonical domain name (``tiger``, ``lightdark1d``, ...).
        discount: the discount factor gamma in (0, 1].
        max_steps: the episode length limit used by the runner.
        max_abs_reward: the largest reward magnitude; the default UCB constant ``c``.
        discrete_observations: True when observations are finitely many and compared
            with ``==``; False when they are real vectors weighted with ``obs_loglik``.
    """

    name: str = "pomdp"
    discount: float = 0.95
    max_steps: int = 10
    max_abs_reward: float = 10.0
    discrete_observations: bool = True

    @abstractmethod
    def sample_initial_state(self, rng: np.random.Generator) -> Any:
        """One state drawn from the initial distribution b0."""

    @abstractmethod
    def step(self, s: Any, a: Hashable, rng: np.random.Generator) -> Step:
        """Draw ``(s', o, r, done)`` from the generative model G(s, a)."""

    @abstractmethod
    def obs_loglik(self, o: Any, s_next: Any, a: Hashable) -> float:
        """log Z(o | s', a); ``-inf`` where ``o`` is impossible."""

    @abstractmethod
    def action_space(self) -> ActionSpace:
        """The action space (the same object on every call)."""

    def transition_many(
        self, states: list[Any], a: Hashable, rng: np.random.Generator
    ) -> tuple[list[Any], np.ndarray, np.ndarray]:
        """Step every state in ``states`` with ``a``, observations discarded.

        Returns ``(next states, rewards (N,), done flags (N,))``. The default loops over
        ``step``; domains override it with array code where the belief-tree solvers'
        particle propagation dominates their cost.
        """
        out = [self.step(s, a, rng) for s in states]
        return (
            [x.state for x in out],
            np.array([x.reward for x in out], dtype=float),
            np.array([x.done for x in out], dtype=bool),
        )

    def obs_loglik_many(self, o: Any, states: list[Any], a: Hashable) -> np.ndarray:
        """``obs_loglik(o, s, a)`` for every ``s`` in ``states``, shape ``(N,)``."""
        return np.array([self.obs_loglik(o, s, a) for s in states], dtype=float)

    def initial_belief(self, rng: np.random.Generator, n_particles: int) -> ParticleBelief:
        """``n_particles`` equally weighted draws from b0, each its own origin."""
        from planners.belief import ParticleBelief

        return ParticleBelief.from_states(
            [self.sample_initial_state(rng) for _ in range(n_particles)]
        )

    def is_terminal(self, s: Any) -> bool:
        """True when ``s`` is absorbing (the search stops there)."""
        return False

    def check_observation(self, o: Any) -> None:
        """Raise :class:`ObservationError` when ``o`` is malformed (NaN, not finite)."""
        if isinstance(o, float | np.floating) and not math.isfinite(o):
            raise ObservationError(f"{self.name}: observation must be finite, got {o!r}")
        if isinstance(o, tuple | list | np.ndarray):
            arr = np.asarray(o, dtype=float)
            if not np.all(np.isfinite(arr)):
                raise ObservationError(f"{self.name}: observation must be finite, got {o!r}")

    def reinvigorate(
        self, o: Any, a: Hashable, n: int, rng: np.random.Generator
    ) -> list[Any] | None:
        """States consistent with ``o`` after ``a`` when no particle explains it.

        Returns None where the domain cannot propose any; the belief update then
        raises :class:`planners.errors.BeliefError` (see ``update_belief``).
        """
        return None

    def rollout_policy(self) -> RolloutPolicy | None:
        """The domain's rollout heuristic (``rollout="heuristic"`` in the tree solvers).

        None (the default) means the domain has none; asking for one is then a
        :class:`planners.errors.ConfigError`.
        """
        return None

    def entropy_features(self, states: list[Any]) -> np.ndarray | None:
        """Continuous features of ``states`` for entropy estimates, shape ``(N, d)``.

        None (the default for ints and tuples of ints) means the states are discrete and
        their entropy is categorical; see :mod:`planners.entropy`.
        """
        first = states[0]
        if isinstance(first, int | np.integer) or (
            isinstance(first, tuple) and all(isinstance(x, int | np.integer) for x in first)
        ):
            return None
        return np.asarray(states, dtype=float).reshape(len(states), -1)

    def format_state(self, s: Any) -> str:
        """A readable state."""
        return format_value(s)

    def format_obs(self, o: Any) -> str:
        """A readable observation."""
        return format_value(o)

    def summarize_belief(self, belief: ParticleBelief) -> str:
        """A one-line summary of a belief (domains override with something meaningful)."""
        return f"{len(belief)} particles, ESS {belief.ess():.0f}"
