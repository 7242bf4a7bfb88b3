"""The real cabinet of an episode and its target (:func:`draw_episode`).

The real cabinet is generated from a held-out seed (:data:`EPISODE_SEEDS`: no test,
tuning or training run uses them) with the task's part kinds, or is one of a user's real
objects; the target is the part at the user's point of the cabinet front, or, without
one, drawn among the parts the full robot opens under the true model (Shelf: among the
open cells it fills). Only the real robot's environment (:mod:`.real`) calls this: it
reads the true cabinet.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from planners.errors import ConfigError
from strug_manip.control import (
    ControlContext,
    OpenDoor,
    OpenDrawer,
    Pick,
    Place,
    handle_grasps,
    place_targets,
)
from strug_manip.domains.manipulation.actions import part_at_point, part_point
from strug_manip.domains.manipulation.grounding import first_feasible, position
from strug_manip.domains.manipulation.rules import dragged, inside, open_enough
from strug_manip.objects.generator import CabinetSpec
from strug_manip.objects.hypotheses import BelievedJoint
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

#: The generator seeds of the episodes' cabinets: ``EPISODE_SEEDS.start + k`` with k
#: drawn per episode. Tests use seeds below 1,000, the skills' tuning 3,000-3,299, the
#: evaluations' reports 1,000-2,999, perception's training 100,000 and up.
EPISODE_SEEDS = range(6_000, 10_000)
#: A drawn cabinet with no part the full robot opens (fills, on Shelf) gives way to the
#: next draw, at most this many times: an episode is about the task, not about the
#: generator's rare cabinets whose parts are all out of the arm's reach.
MAX_DRAWS = 20
#: The part kinds of each task's cabinets (the generator's ``kinds``).
TASK_KINDS: dict[str, tuple[str, ...]] = {
    "shelf": ("shelf",),
    "opendrawer": ("drawer",),
    "opendoor": ("door",),
}


def draw_episode(
    task: str,
    rng: np.random.Generator,
    ctx: ControlContext,
    *,
    cabinet_seed: int | None = None,
    objects: Sequence[Path] = (),
    target: np.ndarray | None = None,
    target_link: str | None = None,
) -> tuple[ManipulationWorld, int, str, np.ndarray]:
    """The real world of a new episode of ``task`` (module docstring), reset: (world,
    cabinet seed (-1 for a real object), target link, the point naming it, world (3,)
    [m])."""
    drawn = cabinet_seed is None and target is None and target_link is None
    for draw in range(MAX_DRAWS if drawn else 1):
        seed = cabinet_seed
        if objects:  # a real object: the seed draws which
            seed = -1
            folder = objects[int(rng.integers(len(objects)))]
            config = SceneConfig(cabinet_folder=folder)
        else:
            if seed is None:
                seed = EPISODE_SEEDS.start + int(rng.integers(len(EPISODE_SEEDS)))
            config = SceneConfig(cabinet_seed=seed, cabinet_kinds=TASK_KINDS[task])
        world = ManipulationWorld(config)
        try:
            link, point = choose_target(world, task, rng, ctx, target, target_link)
            break
        except ConfigError:
            world.close()
            if not drawn or draw == MAX_DRAWS - 1:
                raise
    world.reset()
    return world, seed, link, point


def choose_target(
    world: ManipulationWorld,
    task: str,
    rng: np.random.Generator,
    ctx: ControlContext,
    target: np.ndarray | None = None,
    target_link: str | None = None,
) -> tuple[str, np.ndarray]:
    """(link, naming point) of the target part in the true cabinet."""
    spec = world.scene.cabinet_spec
    T = world.scene.T_world_cabinet
    kinds = TASK_KINDS[task]
    if target_link is not None:
        part = spec.part(target_link)
        if part.kind not in kinds:
            raise ConfigError(
                f"target_link {target_link!r} of {spec.name} is a {part.kind}; "
                f"the {task} task needs a {'/'.join(kinds)} (its: "
                f"{[p.link for p in spec.parts if p.kind in kinds]})"
            )
        return part.link, (T @ np.r_[part.cell_center, 1.0])[:3]
    if target is not None:
        link = part_at_point(spec, T, target, kinds)
        if link is None:
            raise ConfigError(
                f"target {np.round(target, 3).tolist()} is on no "
                f"{'/'.join(kinds)} part of {spec.name} "
                f"(its cells: {_cells(spec, T, kinds)})"
            )
        return link, target
    parts = [p for p in spec.parts if p.kind in kinds and part_point(p, 0.0, T) is not None]
    for i in rng.permutation(len(parts)):
        p = parts[i]
        if _fills(world, p, ctx) if p.kind == "shelf" else _opens(world, p, ctx):
            return p.link, (T @ np.r_[p.cell_center, 1.0])[:3]
    raise ConfigError(
        f"{spec.name} has no {'/'.join(kinds)} part the robot "
        "can open; pass another cabinet_seed or object"
    )


def _opens(world: ManipulationWorld, part, ctx: ControlContext) -> bool:
    """Whether the full robot opens ``part`` enough for the object under the true
    model (the target is drawn among such parts)."""
    T = world.scene.T_world_cabinet
    joint = BelievedJoint.of_part(part, 0.0, T)
    opening = OpenDrawer if part.joint_type == "prismatic" else OpenDoor

    def run(g: np.ndarray):
        world.reset()
        return opening(g, joint).run(world, ctx=ctx)

    out = first_feasible(functools.partial(run, g) for g in handle_grasps(part, 0.0, T))
    if out is None or out.cannot_reach:
        return False
    q = position(world, part.joint)
    return (
        out.ok
        and not dragged(out.cabinet_displacement)
        and open_enough(world.scene.cabinet_spec, part.link, q, world.cabinet_pose())
    )


def _fills(world: ManipulationWorld, part, ctx: ControlContext) -> bool:
    """Whether the full robot, knowing the cabinet, puts the object onto the open
    cell ``part`` (Pick from the side, then Place: a Shelf target is drawn among
    such cells; many cells are too low or too tight for the arm)."""
    world.reset()
    if not Pick("object", "side").run(world, ctx=ctx).ok:
        return False
    T = world.scene.T_world_cabinet
    try:
        targets = place_targets(world.scene.cabinet_spec, part.link, 0.0, T)
    except ConfigError:
        return False
    out = first_feasible(functools.partial(Place.onto(t).run, world, ctx=ctx) for t in targets)
    spec, T_now = world.scene.cabinet_spec, world.cabinet_pose()
    return bool(
        out is not None and out.ok and inside(spec, part.link, 0.0, T_now, world.object_pose())
    )


def handles(world: ManipulationWorld) -> dict[str, np.ndarray]:
    """The handles of ``world``'s cabinet's graspable parts where they are now, world
    (3,) [m], by link (:func:`.actions.part_point`)."""
    T, qs = world.cabinet_pose(), world.part_positions()
    out = {}
    for p in world.scene.cabinet_spec.movable_parts:
        pt = part_point(p, qs[world.scene.cabinet_prefix + p.joint], T)
        if pt is not None:
            out[p.link] = pt
    return out


def world_point(name: str, v: Sequence[float]) -> np.ndarray:
    """``v`` as a finite world point (3,) [m].

    Raises:
        ConfigError: it is not one, naming ``name``.
    """
    arr = np.asarray(v, dtype=float).reshape(-1)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ConfigError(f"{name} must be a finite world point (x, y, z) [m], got {v!r}")
    return arr


def _cells(spec: CabinetSpec, T: np.ndarray, kinds: tuple[str, ...]) -> list[list[float]]:
    return [np.round((T @ np.r_[p.cell_center, 1.0])[:3], 3).tolist()
            for p in spec.parts if p.kind in kinds]  # fmt: skip
