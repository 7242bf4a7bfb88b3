"""The generative-model protocol every solver plans against.

A POMDP here is what POMDPs.jl calls a *generative* model: a function
``step(s, a, rng) -> Step(state, obs, reward, done)`` that draws one transition, plus
``obs_loglik(o, s_next, a)`` for weighting particles with continuous observations.
Nothing else about the transition needs a closed form.

Actions are *hybrid*: the action space is a tuple of :class:`ActionSchema` (a
controller kind, e.g. ``listen`` or ``move``), each with a box of continuous
parameters (possibly none). A purely discrete domain (every schema of dimension 0) has
the schema indices as actions (plain ``int``). A hybrid domain (some schema with
parameters) uses :class:`HybridAction` ``(schema, params)`` for *every* action, a
parameter-free schema's included (``HybridAction(1, ())``), so that domain code can
always unpack ``schema, params = a``. An ``ActionSpace.make`` replaces both defaults.
Either way actions are hashable, which the search trees rely on to merge repeated
samples.

A domain sets five class attributes (:data:`REQUIRED_ATTRIBUTES`; checked by
:func:`check_pomdp`, which every planner constructor and
:func:`planners.episode.run_episode` call) and implements four methods. Everything
else has a default a domain may override: the optional capabilities ``plan_for`` (an
uncertainty-free plan for one state), ``discrete_states`` (whether states are compared
exactly), ``observation_key`` (the hashable key under which a search tree files an
observation), ``rollout_policy``, ``reinvigorate`` and the array versions of ``step``
and ``obs_loglik``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from planners.determinized import determinized_plan
from planners.errors import ConfigError, ModelError, ObservationError
from planners.particles import ParticleBelief


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
        make: builds an action from ``(schema index, params tuple)``. Default: the
            schema index (``int``) when *every* schema is parameter-free (a discrete
            space), else :class:`HybridAction` for every schema, a parameter-free one
            included (``HybridAction(i, ())``).
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


#: The class attributes every domain sets, with what each must be.
REQUIRED_ATTRIBUTES: dict[str, str] = {
    "name": "a non-empty str naming the domain",
    "discount": "the discount factor gamma, a number in (0, 1]",
    "max_steps": "the episode length limit, an int >= 1",
    "max_abs_reward": "the largest reward magnitude, a finite number > 0",
    "discrete_observations": "a bool: True when observations are finitely many and "
    "compared by their observation_key, False when they are weighted with obs_loglik",
}


class GenerativePOMDP(ABC):
    """Base class of the domains: the protocol solvers use, plus sensible defaults.

    Subclasses set the five class attributes (no defaults: a missing one is a
    :class:`planners.errors.ModelError` naming it, see :func:`check_pomdp`) and
    implement the four abstract methods. The other methods are optional capabilities,
    each with one default.

    Attributes:
        name: canonical domain name (``tiger``, ``lightdark1d``, ...).
        discount: the discount factor gamma in (0, 1].
        max_steps: the episode length limit used by the runner.
        max_abs_reward: the largest reward magnitude; the default UCB constant ``c``
            and TRU's reward scale.
        discrete_observations: True when observations are finitely many and compared
            exactly (by :meth:`observation_key`): the belief update keeps the particles
            whose simulated observation matches, and the belief tree merges repeats.
            False when they are real values or vectors weighted with ``obs_loglik``.
        resample_ess: the runner's belief update resamples when the effective sample
            size falls below this fraction of the particles (optional, default 0.5; see
            :func:`planners.belief.update_belief`). A domain whose particles are
            distinct, deterministic models and that cannot propose new ones sets it
            near 0: resampling there only copies the likeliest models and drops the
            others for good.
    """

    name: str
    discount: float
    max_steps: int
    max_abs_reward: float
    discrete_observations: bool
    resample_ess: float = 0.5

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

    def applicable(self, s: Any, a: Hashable) -> bool:
        """False when ``a`` cannot start in ``s``: it would do nothing and cost a step
        (a skill that needs an empty hand while the hand is full, a door already open).

        The tree solvers leave such actions out of a node (:func:`legal_in`, and
        :class:`planners.solvers.action_tree.ActionTree`'s ``keep``); a no-op's value
        is the discounted value of its own node, so with a few visits per action the
        noise of the estimates lets it win the root. Default: every action is
        applicable. Must be cheap (it is asked per particle, node and action), must not
        draw randomness, and may say True for an action that then turns out to do
        nothing, never False for one that would do something.
        """
        return True

    def action_prior(
        self, states: Sequence[Any], weights: Sequence[float], actions: Sequence[Hashable]
    ) -> Sequence[float] | None:
        """How promising each of ``actions`` is at a tree node whose particles are
        ``states`` (live ones only) with ``weights`` (shape ``(N,)``, > 0, not
        necessarily normalised): one score per action, shape ``(len(actions),)``,
        dimensionless, higher first.

        The tree solvers try a node's untried actions in the order of these scores (ties
        keep the order of ``actions``, see :func:`prior_order`), so with a small budget
        the first simulations go to the actions the task needs (opening the believed
        target, grasping what is reachable) rather than to whatever comes first in the
        list. Once every child has a visit, UCB alone decides, so the prior changes
        which actions a small budget sees, not what a large one converges to.

        Default: None, the list order (every toy domain: their searches are unchanged
        bit for bit). Must not draw randomness; it is asked once per node expansion.
        """
        return None

    def obs_loglik_many(self, o: Any, states: list[Any], a: Hashable) -> np.ndarray:
        """``obs_loglik(o, s, a)`` for every ``s`` in ``states``, shape ``(N,)``."""
        return np.array([self.obs_loglik(o, s, a) for s in states], dtype=float)

    def initial_belief(self, rng: np.random.Generator, n_particles: int) -> ParticleBelief:
        """``n_particles`` equally weighted draws from b0, each its own origin."""
        return ParticleBelief.from_states(
            [self.sample_initial_state(rng) for _ in range(n_particles)]
        )

    def plan_for(self, s: Any, rng: np.random.Generator) -> list[Hashable]:
        """An uncertainty-free plan from state ``s``: an open-loop action sequence that
        earns a high return if ``s`` were known to be the true state.

        STRUG uses it twice: for the compatibility matrix behind TRU
        (:func:`planners.tru.compatibility_matrix`) and for the ``"plan"`` rollouts of
        the belief-tree solvers. The default, :func:`planners.determinized.determinized_plan`,
        is a beam search over the discretised actions on a determinised model: it needs
        nothing from the domain but costs ``8 * len(discretized) * max_steps`` simulated
        sequences per call. A domain that knows its optimal plan should say so here:
        with the default STRUG's rollouts fall back to random ones (``rollout="auto"``),
        and only the M plans of the matrix pay for the search.
        """
        return determinized_plan(self, s, rng)

    def discrete_states(self, states: list[Any]) -> bool:
        """True when ``states`` (a non-empty list) are finitely many and compared with
        ``==``: their entropy is categorical, the root particles of the belief-tree
        solvers are importance-corrected per distinct state, and Active Learning's most
        likely state is the mode. Default: ints and tuples of ints are discrete.
        """
        first = states[0]
        return isinstance(first, int | np.integer) or (
            isinstance(first, tuple) and all(isinstance(x, int | np.integer) for x in first)
        )

    def observation_key(self, o: Any) -> Hashable:
        """The hashable key of observation ``o``: two observations are the same exactly
        when their keys are equal.

        The search trees file observation children under it (POMCP's observation bins,
        POMCPOW's and the belief tree's children) and the exact-match belief update
        compares with it, so observations may be unhashable values such as numpy
        arrays. Default: a numpy array of at most one dimension becomes the tuple of its
        values, a higher-dimensional one ``(shape, values)``, a list a tuple, and
        anything else is its own key. (POMCP bins the key on continuous-observation
        domains, so there it must be a number or a flat tuple of numbers.)
        """
        cls = o.__class__
        if cls is np.ndarray:
            values = tuple(o.ravel().tolist())
            return values if o.ndim <= 1 else (o.shape, values)
        if cls is list:
            return tuple(o)
        return o

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

    def condition(self, belief: ParticleBelief) -> ParticleBelief:
        """The belief, after it is made and after every update, given what the domain
        knows for certain of the true state (default: ``belief`` unchanged): what a
        :class:`~planners.environment.SimulatedEnvironment` of this model conditions
        with. An environment of its own conditions in its ``condition`` (the
        manipulation tasks' real robot puts its and the cabinet's known poses into every
        particle there)."""
        return belief

    def rollout_policy(self) -> RolloutPolicy | None:
        """The domain's rollout heuristic (``rollout="heuristic"`` in the tree solvers).

        None (the default) means the domain has none; asking for one is then a
        :class:`planners.errors.ConfigError`.
        """
        return None

    def entropy_key(self, s: Any) -> Hashable:
        """What the categorical entropy of discrete states tells apart (Entropy
        Regularized, Active Learning): by default the state itself. A domain whose
        states carry detail that is not the uncertainty the robot has (e.g. one
        simulator snapshot per particle, every particle a distinct state) returns the
        part that is: e.g. the particle's model class."""
        return s

    def entropy_features(self, states: list[Any]) -> np.ndarray | None:
        """Continuous features of ``states`` for entropy estimates, shape ``(N, d)``.

        None when :meth:`discrete_states` says the states are discrete (their entropy
        is then categorical; see :mod:`planners.entropy`); by default the states as a
        float array.
        """
        if self.discrete_states(states):
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


def provides_applicable(pomdp: GenerativePOMDP) -> bool:
    """True when ``pomdp``'s class defines its own :meth:`GenerativePOMDP.applicable`
    (the solvers skip the filter on domains where every action always applies)."""
    return type(pomdp).applicable is not GenerativePOMDP.applicable


def provides_prior(pomdp: GenerativePOMDP) -> bool:
    """True when ``pomdp``'s class defines its own :meth:`GenerativePOMDP.action_prior`
    (the solvers keep the list order, and skip the ranking, on the others)."""
    return type(pomdp).action_prior is not GenerativePOMDP.action_prior


def prior_order(
    pomdp: GenerativePOMDP,
    states: Sequence[Any],
    weights: Sequence[float],
    actions: Sequence[Hashable],
    extra: Callable[[Hashable], float] | None = None,
) -> list[Hashable]:
    """``actions`` in the order a node tries them while untried: by ``extra(a)`` (a
    solver's own preference, e.g. STRUG's particle plans; 0 without it), then by
    ``pomdp.action_prior``, both descending; ties (and a domain without a prior) keep
    the order of ``actions``. ``states`` and ``weights`` (shape ``(N,)``) are the
    node's live, weighted particles."""
    scores = pomdp.action_prior(states, weights, actions)
    prior = [0.0] * len(actions) if scores is None else [float(x) for x in scores]
    if len(prior) != len(actions):
        raise ModelError(
            f"{type(pomdp).__name__}.action_prior must return one score per action "
            f"({len(actions)}), got {len(prior)}"
        )
    first = [0.0] * len(actions) if extra is None else [float(extra(a)) for a in actions]
    order = sorted(range(len(actions)), key=lambda j: (-first[j], -prior[j], j))
    return [actions[j] for j in order]


def provides_plan(pomdp: GenerativePOMDP) -> bool:
    """True when ``pomdp``'s class defines its own :meth:`GenerativePOMDP.plan_for`."""
    return type(pomdp).plan_for is not GenerativePOMDP.plan_for


def check_pomdp(pomdp: Any) -> None:
    """Raise :class:`ModelError` unless ``pomdp`` is a complete :class:`GenerativePOMDP`.

    Checks the class attributes of :data:`REQUIRED_ATTRIBUTES` (present, of the right
    type and range) and that ``action_space()`` returns an :class:`ActionSpace`. The
    message names the domain class and the attribute.
    """
    if not isinstance(pomdp, GenerativePOMDP):
        raise ModelError(
            f"expected a planners.GenerativePOMDP instance, got {type(pomdp).__name__}"
        )
    cls = type(pomdp).__name__
    for attr, expected in REQUIRED_ATTRIBUTES.items():
        if not hasattr(pomdp, attr):
            raise ModelError(f"{cls} must set the class attribute {attr}: {expected}")
        if not _attribute_ok(attr, getattr(pomdp, attr)):
            raise ModelError(f"{cls}.{attr} must be {expected}, got {getattr(pomdp, attr)!r}")
    space = pomdp.action_space()
    if not isinstance(space, ActionSpace):
        raise ModelError(
            f"{cls}.action_space() must return a planners.ActionSpace, got {type(space).__name__}"
        )


def _attribute_ok(attr: str, v: Any) -> bool:
    number = isinstance(v, int | float | np.integer | np.floating) and not isinstance(v, bool)
    if attr == "name":
        return isinstance(v, str) and bool(v)
    if attr == "discount":
        return number and 0.0 < v <= 1.0
    if attr == "max_steps":
        return isinstance(v, int | np.integer) and not isinstance(v, bool) and v >= 1
    if attr == "max_abs_reward":
        return number and math.isfinite(v) and v > 0.0
    return isinstance(v, bool | np.bool_)


def legal_in(
    pomdp: GenerativePOMDP,
    states: Sequence[Any],
    weights: Sequence[float] | None = None,
    alive: Sequence[bool] | None = None,
) -> Callable[[Hashable], bool]:
    """The predicate "``a`` is applicable in at least one of ``states`` (those with a
    weight > 0 when ``weights`` is given, and alive when ``alive`` is)": the actions a
    node of these particles offers (:meth:`GenerativePOMDP.applicable`). The live
    particles are listed at the first call (a node asks only when it expands)."""
    applicable = pomdp.applicable
    live: list[Any] | None = None

    def keep(a: Hashable) -> bool:
        nonlocal live
        if live is None:
            live = [
                s
                for i, s in enumerate(states)
                if (weights is None or weights[i] > 0.0) and (alive is None or alive[i])
            ]
        return any(applicable(s, a) for s in live)

    return keep
