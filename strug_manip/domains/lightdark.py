"""The LightDark problems (Platt et al. 2010): localise in the light, then act.

:class:`LightDark1D` follows POMDPModels.jl's ``LightDark1D``; :class:`LightDark2D`
is the two-walled room of the STRUG paper (Fig. 3), where only x matters for the task.
"""

from __future__ import annotations

import math
from collections.abc import Hashable
from typing import Any

import numpy as np

from planners.belief import ParticleBelief
from planners.pomdp import ActionSchema, ActionSpace, GenerativePOMDP, HybridAction, Step

_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


def _normal_logpdf(x: float, mean: float, std: float) -> float:
    z = (x - mean) / std
    return -0.5 * z * z - math.log(std) - _LOG_SQRT_2PI


_LD1D_SPACE = ActionSpace(
    schemas=(ActionSchema("left"), ActionSchema("declare"), ActionSchema("right")),
    discretized=(0, 1, 2),
)


class LightDark1D(GenerativePOMDP):
    """LightDark1D as in POMDPModels.jl.

    State: the position y [m] (a float). Actions (schema indices): ``0`` move -1,
    ``1`` declare the end, ``2`` move +1 (moves are exact; no movement cost).
    Declaring gives +10 if |y| < 1 else -10 and ends the episode. After every action
    the agent observes ``y' + N(0, sigma(y')^2)`` with
    ``sigma(y) = |y - 5| / sqrt(2) + 0.01`` (the light is at y = 5).
    Initial belief y0 ~ N(2, 3^2); discount 0.9. POMDPModels.jl sets no step limit;
    the runner stops an episode after ``max_steps`` = 20 steps (0.9^20 = 0.12, so a
    later declaration could not change a return by more than 1.2).
    """

    name = "lightdark1d"
    discount = 0.9
    max_steps = 20
    max_abs_reward = 10.0
    discrete_observations = False

    correct_reward = 10.0
    incorrect_reward = -10.0
    init_mean = 2.0
    init_std = 3.0
    light_y = 5.0

    def action_space(self) -> ActionSpace:
        return _LD1D_SPACE

    @staticmethod
    def sigma(y: float) -> float:
        """Observation noise standard deviation at position ``y`` [m]."""
        return abs(y - 5.0) / math.sqrt(2.0) + 0.01

    def sample_initial_state(self, rng: np.random.Generator) -> float:
        return float(self.init_mean + self.init_std * rng.standard_normal())

    def step(self, s: float, a: Hashable, rng: np.random.Generator) -> Step:
        if a == 1:
            r = self.correct_reward if abs(s) < 1.0 else self.incorrect_reward
            return Step(s, s + self.sigma(s) * rng.standard_normal(), r, True)
        y = s + (a - 1)
        return Step(y, y + self.sigma(y) * rng.standard_normal(), 0.0, False)

    def plan_for(self, s: float, rng: np.random.Generator) -> list[int]:
        """The uncertainty-free plan: unit moves toward 0 until |y| < 1, then declare."""
        plan, y = [], s
        while abs(y) >= 1.0 and len(plan) < self.max_steps - 1:
            step = -1.0 if y > 0 else 1.0
            plan.append(2 if step > 0 else 0)
            y += step
        return [*plan, 1]

    def obs_loglik(self, o: Any, s_next: float, a: Hashable) -> float:
        return _normal_logpdf(o, s_next, self.sigma(s_next))

    def transition_many(
        self, states: list[float], a: Hashable, rng: np.random.Generator
    ) -> tuple[list[float], np.ndarray, np.ndarray]:
        y = np.asarray(states, dtype=float)
        if a == 1:
            r = np.where(np.abs(y) < 1.0, self.correct_reward, self.incorrect_reward)
            return list(states), r, np.ones(len(y), dtype=bool)
        return (y + (a - 1)).tolist(), np.zeros(len(y)), np.zeros(len(y), dtype=bool)

    def obs_loglik_many(self, o: Any, states: list[float], a: Hashable) -> np.ndarray:
        y = np.asarray(states, dtype=float)
        sig = np.abs(y - 5.0) / math.sqrt(2.0) + 0.01
        z = (o - y) / sig
        return -0.5 * z * z - np.log(sig) - _LOG_SQRT_2PI

    def reinvigorate(self, o: Any, a: Hashable, n: int, rng: np.random.Generator) -> list[float]:
        """Positions drawn from N(o, sigma(o)^2): where the observation says we are."""
        return (o + self.sigma(o) * rng.standard_normal(n)).tolist()

    def summarize_belief(self, belief: ParticleBelief) -> str:
        y = np.asarray(belief.states, dtype=float)
        mean = float(belief.weights @ y)
        std = math.sqrt(max(float(belief.weights @ (y - mean) ** 2), 0.0))
        return f"y={mean:+.2f}±{std:.2f}"


_MOVE, _STOP = 0, 1
_UNIT_MOVES = tuple(
    HybridAction(_MOVE, (float(dx), float(dy)))
    for dx in (-1, 0, 1)
    for dy in (-1, 0, 1)
    if (dx, dy) != (0, 0)
)
_LD2D_SPACE = ActionSpace(
    schemas=(ActionSchema("move", (-1.0, -1.0), (1.0, 1.0)), ActionSchema("stop")),
    discretized=(*_UNIT_MOVES, HybridAction(_STOP, ())),
)


class LightDark2D(GenerativePOMDP):
    """LightDark2D: a room where only the x coordinate matters.

    State ``(x, y)`` [m] in the room [0, 10]^2. Actions: ``move(dx, dy)`` with
    (dx, dy) in [-1, 1]^2 (exact; the position is clipped to the room; no move cost)
    and ``stop``. The goal is the vertical bar |x - 5| < 0.5 at any y: ``stop`` there
    gives +10, elsewhere -10, both terminal. Discount 0.95, at most 20 steps.
    x0, y0 ~ N(3, 2^2) each, clipped to the room. Observation ``(x, y) + N(0,
    diag(sx^2, sy^2))`` with ``sx = 0.1 + 0.5 (10 - x)`` (precise near the right wall)
    and ``sy = 0.1 + 0.5 (10 - y)`` (precise near the top wall). POMCP's
    discretisation: the 8 unit moves (dx, dy in {-1, 0, 1}, not both 0) and ``stop``.
    """

    name = "lightdark2d"
    discount = 0.95
    max_steps = 20
    max_abs_reward = 10.0
    discrete_observations = False

    size = 10.0
    goal_x = 5.0
    goal_halfwidth = 0.5
    init_mean = 3.0
    init_std = 2.0

    def action_space(self) -> ActionSpace:
        return _LD2D_SPACE

    @staticmethod
    def sigma(v: float) -> float:
        """Observation noise std of a coordinate at value ``v`` [m] (same law for x and y)."""
        return 0.1 + 0.5 * (10.0 - v)

    def sample_initial_state(self, rng: np.random.Generator) -> tuple[float, float]:
        x, y = np.clip(self.init_mean + self.init_std * rng.standard_normal(2), 0.0, self.size)
        return (float(x), float(y))

    def step(self, s: tuple[float, float], a: Hashable, rng: np.random.Generator) -> Step:
        x, y = s
        schema, params = a  # type: ignore[misc]
        nx, ny = rng.standard_normal(2).tolist()
        if schema == _STOP:
            r = 10.0 if abs(x - self.goal_x) < self.goal_halfwidth else -10.0
            return Step(s, (x + self.sigma(x) * nx, y + self.sigma(y) * ny), r, True)
        dx, dy = params
        x = min(max(x + dx, 0.0), self.size)
        y = min(max(y + dy, 0.0), self.size)
        return Step((x, y), (x + self.sigma(x) * nx, y + self.sigma(y) * ny), 0.0, False)

    def plan_for(self, s: tuple[float, float], rng: np.random.Generator) -> list[HybridAction]:
        """The uncertainty-free plan: move straight (dy = 0) to x = 5, then stop.

        Each move covers min(1, remaining distance), so the plan ends exactly on the goal
        line; executed from another particle it ends |x_j - x_i| away from it, which is
        what makes only x task-relevant.
        """
        plan, x = [], s[0]
        while abs(self.goal_x - x) > 1e-9 and len(plan) < self.max_steps - 1:
            dx = min(max(self.goal_x - x, -1.0), 1.0)
            plan.append(HybridAction(_MOVE, (dx, 0.0)))
            x += dx
        return [*plan, HybridAction(_STOP, ())]

    def obs_loglik(self, o: Any, s_next: tuple[float, float], a: Hashable) -> float:
        x, y = s_next
        return _normal_logpdf(o[0], x, self.sigma(x)) + _normal_logpdf(o[1], y, self.sigma(y))

    def transition_many(
        self, states: list[tuple[float, float]], a: Hashable, rng: np.random.Generator
    ) -> tuple[list[tuple[float, float]], np.ndarray, np.ndarray]:
        xy = np.asarray(states, dtype=float).reshape(-1, 2)
        schema, params = a  # type: ignore[misc]
        if schema == _STOP:
            hit = np.abs(xy[:, 0] - self.goal_x) < self.goal_halfwidth
            return list(states), np.where(hit, 10.0, -10.0), np.ones(len(xy), dtype=bool)
        moved = np.clip(xy + np.asarray(params), 0.0, self.size)
        return list(map(tuple, moved.tolist())), np.zeros(len(xy)), np.zeros(len(xy), dtype=bool)

    def obs_loglik_many(self, o: Any, states: list[tuple[float, float]], a: Hashable) -> np.ndarray:
        xy = np.asarray(states, dtype=float).reshape(-1, 2)
        sig = 0.1 + 0.5 * (10.0 - xy)
        z = (np.asarray(o, dtype=float) - xy) / sig
        return (-0.5 * z * z - np.log(sig) - _LOG_SQRT_2PI).sum(axis=1)

    def reinvigorate(
        self, o: Any, a: Hashable, n: int, rng: np.random.Generator
    ) -> list[tuple[float, float]]:
        """Positions drawn around the observation with its noise, clipped to the room."""
        ox, oy = float(o[0]), float(o[1])
        sx, sy = self.sigma(min(max(ox, 0.0), 10.0)), self.sigma(min(max(oy, 0.0), 10.0))
        xs = np.clip(ox + sx * rng.standard_normal(n), 0.0, self.size)
        ys = np.clip(oy + sy * rng.standard_normal(n), 0.0, self.size)
        return list(zip(xs.tolist(), ys.tolist(), strict=True))

    def summarize_belief(self, belief: ParticleBelief) -> str:
        xy = np.asarray(belief.states, dtype=float)
        mean = belief.weights @ xy
        std = np.sqrt(np.maximum(belief.weights @ (xy - mean) ** 2, 0.0))
        return f"x={mean[0]:.2f}±{std[0]:.2f} y={mean[1]:.2f}±{std[1]:.2f}"
