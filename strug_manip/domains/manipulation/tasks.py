"""Shelf, OpenDrawer and OpenDoor: each task is the twins' POMDP (:mod:`.model`, what
the planners simulate) together with the real Fetch and cabinet it acts in
(:mod:`.real`, its ``environment``).

``run_episode(task, solver, seed)`` (:func:`planners.episode.run_episode`) plans in the
task and executes in ``task.environment``; ``run_episode(task, task.environment,
solver, seed)`` says the same explicitly.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from planners.errors import ConfigError, UnknownNameError, check_positive_int
from strug_manip.domains.manipulation.actions import DEFAULT_PROBES
from strug_manip.domains.manipulation.episode_setup import world_point
from strug_manip.domains.manipulation.model import (
    MAX_PARTICLES,
    MAX_STEPS,
    VIEWS,
    ManipulationPOMDP,
)
from strug_manip.domains.manipulation.oracle import BELIEFS
from strug_manip.domains.manipulation.real import RealEnvironment, RealEpisode
from strug_manip.objects.loader import object_folders


class ManipulationTask(ManipulationPOMDP):
    """One manipulation task: the twins' POMDP, and the real robot as its
    :attr:`environment`; subclasses name the task.

    Args:
        cabinet_seed: the real cabinet's generator seed (default: drawn per episode
            from :data:`~.episode_setup.EPISODE_SEEDS`).
        target: the point of the cabinet front naming the target part, world (3,)
            [m] (the part whose cell contains it, seen from the front); default: drawn
            per episode (:mod:`.episode_setup`).
        particles: belief particles from perception (at most
            :data:`~.model.MAX_PARTICLES`).
        probes: the probe skills offered per part (``Push``, ``PullV``, ``PullH``).
        views: head-camera views for perception (1..6).
        max_steps: the episode's step limit (default the paper's
            :data:`~.model.MAX_STEPS`; fewer for quick checks).
        objects: real articulated objects (PartNet-Mobility folders) to act on instead
            of generated cabinets; the episode's seed draws one
            (:func:`~strug_manip.objects.loader.object_folders` lists a folder's).
        target_link: the target part by its link name (``link_2``), instead of
            ``target``.
        belief: ``perception`` (the robot's: particles from its head camera's views) or
            ``true`` (the oracle's, evaluation only: the real cabinet as the only
            particle, taking over the real state after every step; :mod:`.oracle`).
        twin_keys: how the real update weighs the real key's status against each
            twin's (``confusion`` or ``match``; :mod:`.twin_keys`; default
            :func:`.twin_keys.twin_keys_rule`).

    Raises:
        ConfigError, UnknownNameError: a bad argument, naming it.
    """

    task: str = ""

    def __init__(
        self,
        cabinet_seed: int | None = None,
        target: Sequence[float] | None = None,
        particles: int = MAX_PARTICLES,
        probes: Sequence[str] = DEFAULT_PROBES,
        views: int = VIEWS,
        max_steps: int = MAX_STEPS,
        objects: Sequence[str | Path] = (),
        target_link: str | None = None,
        belief: str = "perception",
        twin_keys: str | None = None,
    ) -> None:
        check_positive_int("max_steps", max_steps)
        if belief not in BELIEFS:
            raise UnknownNameError("belief", belief, list(BELIEFS))
        folders = tuple(p for o in objects for p in object_folders(o))
        if folders and cabinet_seed is not None:
            raise ConfigError("give cabinet_seed or objects, not both")
        if target_link is not None and target is not None:
            raise ConfigError("give target or target_link, not both")
        if cabinet_seed is not None:
            check_positive_int("cabinet_seed", cabinet_seed, allow_zero=True)
        point = None if target is None else world_point("target", target)
        super().__init__(self.task, particles, probes, max_steps, twin_keys=twin_keys)
        if not (isinstance(views, int) and 1 <= views <= 6):
            raise ConfigError(f"views must be an integer in 1..6, got {views!r}")
        self.cabinet_seed, self.target, self.target_link = cabinet_seed, point, target_link
        self.objects, self.views, self.belief_source = folders, views, belief
        self.environment = RealEnvironment(
            self, cabinet_seed=cabinet_seed, target=point, target_link=target_link,
            objects=folders, views=views, oracle=belief == "true",
        )  # fmt: skip

    @property
    def real(self) -> RealEpisode | None:
        """The environment's real episode (:class:`.real.RealEpisode`; None before the
        first reset)."""
        return self.environment.real

    def report(self) -> dict[str, Any]:
        """Where this episode's time went [s], the caches' hit rates, and what the real
        robot's skills did (:meth:`.real.RealEnvironment.report`)."""
        mine = super().report()
        out: dict[str, Any] = {"time": mine.pop("time"), **self.environment.report()}
        return {**out, **mine}

    def close(self) -> None:
        """Free the episode's worlds: the model's and the real one."""
        super().close()
        self.environment.close()


class ShelfTask(ManipulationTask):
    """The object goes onto an open shelf cell: no uncertainty needs reducing."""

    name = "shelf"
    task = "shelf"


class OpenDrawerTask(ManipulationTask):
    """Only drawers; the object goes into the target drawer."""

    name = "opendrawer"
    task = "opendrawer"


class OpenDoorTask(ManipulationTask):
    """Only doors and flaps; the object goes behind the target door."""

    name = "opendoor"
    task = "opendoor"
