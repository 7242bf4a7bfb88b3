"""What every solver shares: the config base class, search budgets, SearchInfo.

A solver is a frozen dataclass of hyper-parameters, validated in ``__post_init__``;
``config.planner(pomdp)`` builds a planner whose ``act(belief, rng)`` returns
``(action, SearchInfo)``; the runner builds one planner per episode and, after every
real step that did not end the episode, calls its ``observe(action, observation)``
when it has one. By default planners keep no state between calls (no tree reuse),
so the same belief and generator state always give the same action when the budget
is a number of simulations; with ``reuse_tree`` (POMCP) the decision also
depends on the earlier ones of the episode, still bit for bit per seed. A wall-time
budget (``time_limit``) trades that determinism for a fixed decision time.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Hashable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np

from planners.belief import ParticleBelief
from planners.errors import ConfigError, UnknownNameError, check_positive_float, check_positive_int
from planners.solvers.exploration import check_exploration

if TYPE_CHECKING:
    from planners.pomdp import GenerativePOMDP


@dataclass
class SearchInfo:
    """Statistics of one decision.

    Attributes:
        sims: simulations (tree descents) run.
        seconds: wall time of the decision [s].
        tree_nodes: belief nodes + action nodes in the tree.
        actions: the root's action children, in creation order.
        q: value estimate per root action, shape ``(len(actions),)``.
        visits: visit count per root action, shape ``(len(actions),)``.
        extra: solver-specific figures (e.g. TRU at the root, ΔTRU per action).
        tree: the whole search tree, only when the config asked for it
            (``keep_tree=True``; None otherwise): a
            :class:`planners.solvers.belief_tree.BeliefTreeSearch` (STRUG, Entropy,
            Active Learning), a :class:`planners.solvers.pomcpow.POMCPOWTree` or a
            :class:`planners.solvers.pomcp.POMCPTree`.
    """

    sims: int = 0
    seconds: float = 0.0
    tree_nodes: int = 0
    actions: list[Hashable] = field(default_factory=list)
    q: np.ndarray = field(default_factory=lambda: np.zeros(0))
    visits: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    extra: dict[str, Any] = field(default_factory=dict)
    tree: Any = field(default=None, repr=False)

    @property
    def sims_per_second(self) -> float:
        """Simulation rate [1/s]."""
        return self.sims / self.seconds if self.seconds > 0 else 0.0


class Planner(Protocol):
    """What the runner calls once per real step.

    A planner may also define ``observe(action, observation) -> None``: the runner
    calls it after every real step that did not end the episode, with the executed
    action and the real observation, before the next ``act`` (tree reuse needs it).
    """

    def act(self, belief: ParticleBelief, rng: np.random.Generator) -> tuple[Hashable, SearchInfo]:
        """Choose an action for ``belief``."""
        ...


@dataclass(frozen=True)
class SolverConfig:
    """Base of every solver config: a search budget.

    Attributes:
        sims: simulations per decision (default 3000, the budget at which the Table I run was
            measured); ``None`` to use only ``time_limit``.
        time_limit: wall time per decision [s] (default ``None``: no time limit).
            With both set, the search stops at whichever comes first.
    """

    name: ClassVar[str] = "solver"

    sims: int | None = 3000
    time_limit: float | None = None

    def __post_init__(self) -> None:
        if self.sims is None and self.time_limit is None:
            raise ConfigError("set a budget: sims (an integer >= 1) or time_limit (seconds > 0)")
        if self.sims is not None:
            check_positive_int("sims", self.sims)
        if self.time_limit is not None:
            check_positive_float("time_limit", self.time_limit)

    def planner(self, pomdp: GenerativePOMDP) -> Planner:
        """Build the planner for ``pomdp``."""
        raise NotImplementedError

    @classmethod
    def field_names(cls) -> list[str]:
        """The overridable hyper-parameters."""
        return [f.name for f in dataclasses.fields(cls)]

    def with_overrides(self, overrides: dict[str, Any]) -> SolverConfig:
        """A copy with ``overrides`` applied (and validated); unknown names are rejected."""
        valid = self.field_names()
        for key in overrides:
            if key not in valid:
                raise UnknownNameError(f"{self.name} config field", key, valid)
        return dataclasses.replace(self, **overrides)


#: Valid values of ``TreeSearchConfig.horizon``.
HORIZONS = ("receding", "episode")


@dataclass(frozen=True)
class TreeSearchConfig(SolverConfig):
    """Fields shared by the tree-search solvers.

    Attributes:
        depth: maximum search depth, in steps from the root, counting tree and rollout
            steps alike (default ``None``: the domain's ``max_steps``).
        c: UCB exploration constant of ``exploration="fixed"``, in reward units
            (default ``None``: the domain's largest reward magnitude, as the STRUG paper
            sets it).
        discount: discount factor used in the search (default ``None``: the domain's).
        exploration: the UCB score (:mod:`planners.solvers.exploration`): ``"fixed"``
            (default, the published algorithms: ``Q + c sqrt(ln N / n)``) or
            ``"normalized"`` (Q min-max normalised over the node's visited children,
            plus ``c_normalized sqrt(ln N / n)``: no guess of the return spread).
        c_normalized: the dimensionless exploration constant of ``"normalized"``
            (default 1.0); ignored by ``"fixed"``.
        horizon: ``"receding"`` (default, the published algorithms: every decision
            searches ``depth`` steps ahead) or ``"episode"`` (the search stops where the
            episode does: ``min(depth, max_steps - t)`` steps at the planner's decision
            ``t``, counting the real steps the runner reported with ``observe``; a
            planner then serves one episode). On the classic Tiger the best
            receding-horizon policy is worth 6.11, the finite-horizon optimum 6.69: near
            the end, listening before a door stops paying.
        keep_tree: return the search tree in ``SearchInfo.tree`` (default False: it is
            dropped after the decision, so long episodes do not hold every tree).
    """

    depth: int | None = None
    c: float | None = None
    discount: float | None = None
    exploration: str = "fixed"
    c_normalized: float = 1.0
    horizon: str = "receding"
    keep_tree: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        if not isinstance(self.keep_tree, bool):
            raise ConfigError(f"keep_tree must be true or false, got {self.keep_tree!r}")
        if self.depth is not None:
            check_positive_int("depth", self.depth)
        if self.c is not None:
            check_positive_float("c", self.c, allow_zero=True)
        if self.discount is not None:
            check_positive_float("discount", self.discount, upper=1.0)
        check_exploration(self.exploration, self.c_normalized)
        if self.horizon not in HORIZONS:
            raise ConfigError(f"horizon must be one of {', '.join(HORIZONS)}, got {self.horizon!r}")

    @property
    def normalized(self) -> bool:
        """True when the UCB value term is normalised (``exploration="normalized"``)."""
        return self.exploration == "normalized"

    def resolved(self, pomdp: GenerativePOMDP) -> tuple[int, float, float]:
        """``(depth, c, discount)`` with the domain's defaults filled in.

        ``c`` is the constant of the chosen ``exploration``: ``c`` (reward units) when
        fixed, ``c_normalized`` (dimensionless) when normalised.
        """
        depth = self.depth if self.depth is not None else int(pomdp.max_steps)
        if self.normalized:
            c = self.c_normalized
        else:
            c = self.c if self.c is not None else float(pomdp.max_abs_reward)
        gamma = self.discount if self.discount is not None else float(pomdp.discount)
        return depth, c, gamma

    def search_depth(self, pomdp: GenerativePOMDP, steps_taken: int) -> int:
        """The depth of the decision after ``steps_taken`` real steps (see ``horizon``)."""
        depth = self.depth if self.depth is not None else int(pomdp.max_steps)
        if self.horizon == "episode":
            depth = max(1, min(depth, int(pomdp.max_steps) - steps_taken))
        return depth


class Budget:
    """Counts simulations and wall time of one decision."""

    __slots__ = ("deadline", "max_sims", "start")

    def __init__(self, sims: int | None, time_limit: float | None) -> None:
        self.start = time.perf_counter()
        self.max_sims = sims if sims is not None else math.inf
        self.deadline = self.start + time_limit if time_limit is not None else math.inf

    def done(self, sims: int) -> bool:
        """True once ``sims`` reached the limit or the deadline passed."""
        return sims >= self.max_sims or (
            self.deadline != math.inf and time.perf_counter() >= self.deadline
        )

    def elapsed(self) -> float:
        """Seconds since the decision started."""
        return time.perf_counter() - self.start


class UniformStream:
    """Uniform [0, 1) numbers drawn from a Generator in blocks.

    One ``rng.random()`` call costs ~0.5 µs; reading a pre-drawn block costs ~0.05 µs,
    which matters in rollouts that draw millions of times per decision. The stream is
    a pure function of the generator's state, so determinism is kept.
    """

    __slots__ = ("_block", "_buf", "_i", "_rng")

    def __init__(self, rng: np.random.Generator, block: int = 4096) -> None:
        self._rng = rng
        self._block = block
        self._buf: list[float] = []
        self._i = 0

    def __call__(self) -> float:
        i = self._i
        if i >= len(self._buf):
            self._buf = self._rng.random(self._block).tolist()
            i = 0
        self._i = i + 1
        return self._buf[i]


class RootSampler:
    """Draws root states from a belief in blocks (one ``searchsorted`` per 1024 draws)."""

    __slots__ = ("_belief", "_buf", "_i", "_rng")

    def __init__(self, belief: ParticleBelief, rng: np.random.Generator) -> None:
        self._belief = belief
        self._rng = rng
        self._buf: list[int] = []
        self._i = 0

    def __call__(self) -> Any:
        if self._i >= len(self._buf):
            self._buf = self._belief.sample_indices(self._rng, 1024).tolist()
            self._i = 0
        idx = self._buf[self._i]
        self._i += 1
        return self._belief.states[idx]
