"""What executes the chosen actions: the :class:`Environment` protocol, and
:class:`SimulatedEnvironment`, a true state drawn and stepped by the model itself.

The model (a :class:`~planners.pomdp.GenerativePOMDP`) is what the planner simulates;
the environment is what acts. The model keeps no belief and no real world (as
POMDPs.jl keeps the model apart from the simulator), so a user can put their own robot
behind :class:`Environment` and run :func:`planners.episode.run_episode` with it.
"""

from __future__ import annotations

from typing import Any, NamedTuple, Protocol, runtime_checkable

import numpy as np

from planners.errors import ConfigError
from planners.particles import ParticleBelief
from planners.pomdp import GenerativePOMDP


class Executed(NamedTuple):
    """What executing one action gave: the observation, the reward, whether the
    episode is over."""

    obs: Any
    reward: float
    done: bool


@runtime_checkable
class Environment(Protocol):
    """The world an episode acts in: a simulator of the true state, or a real robot.

    ``state`` is the true state as far as the environment knows it (for the step
    records and logs; None when it has none to show).
    """

    state: Any

    def reset(self, rng: np.random.Generator) -> None:
        """Start a new episode (draw or set up the true state)."""
        ...

    def execute(self, action: Any, rng: np.random.Generator) -> Executed:
        """Carry out ``action``: what was observed, earned, and whether it is done."""
        ...

    def condition(self, belief: ParticleBelief) -> ParticleBelief:
        """``belief`` conditioned on what is known for certain of the true state
        (called on the initial belief and after every update)."""
        ...


class SimulatedEnvironment:
    """The true state drawn from b0 and stepped by ``pomdp`` itself (the toy domains).

    Args:
        pomdp: the generative model that also plays the world.

    ``reset`` draws ``pomdp.sample_initial_state(rng)``; ``execute`` steps it with
    ``pomdp.step``; ``condition`` is ``pomdp.condition`` (the belief unchanged unless the
    domain knows something for certain).
    """

    def __init__(self, pomdp: GenerativePOMDP) -> None:
        self.pomdp = pomdp
        self.state: Any = None
        self._started = False

    def reset(self, rng: np.random.Generator) -> None:
        self.state = self.pomdp.sample_initial_state(rng)
        self._started = True

    def execute(self, action: Any, rng: np.random.Generator) -> Executed:
        if not self._started:
            raise ConfigError("execute before reset: call reset(rng) first")
        state, obs, reward, done = self.pomdp.step(self.state, action, rng)
        self.state = state
        return Executed(obs, float(reward), bool(done))

    def condition(self, belief: ParticleBelief) -> ParticleBelief:
        return self.pomdp.condition(belief)


def environment_for(model: Any) -> Environment:
    """The environment ``model`` comes with (its ``environment`` attribute: the
    manipulation tasks' real robot), else a :class:`SimulatedEnvironment` of it."""
    env = getattr(model, "environment", None)
    if isinstance(env, Environment):
        return env
    return SimulatedEnvironment(model)
