"""An action made concrete: the skills to try and the world to plan them in
(:func:`skills`), where the acted part's handle is (:func:`handle_point`), and the
reward of an outcome (:func:`reward`); shared by the twins' POMDP and the real robot.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable, Sequence
from dataclasses import replace

import numpy as np

from planners.errors import ConfigError, UnknownNameError
from strug_manip.control import (
    OpenDoor,
    OpenDrawer,
    Outcome,
    Pick,
    Place,
    PullH,
    PullV,
    Push,
    handle_grasps,
    place_targets,
)
from strug_manip.control.skills import holds_object
from strug_manip.domains.manipulation.actions import TABLE, ManipAction, part_point
from strug_manip.domains.manipulation.catalogue import Catalogue, Root
from strug_manip.domains.manipulation.rules import BEFORE_MOTION, UNCHANGED, dragged, inside
from strug_manip.domains.manipulation.state import NOT_APPLICABLE, observation_key
from strug_manip.domains.manipulation.worlds import ParticleWorlds
from strug_manip.geometry import rotation_angle
from strug_manip.objects.generator import CabinetSpec, PartSpec
from strug_manip.objects.hypotheses import BelievedJoint
from strug_manip.world.sim import ManipulationWorld, WorldState

#: ``Place(table)`` with a side grasp starts this much above the object's spot and comes
#: down to it [m]: the object held level clears the table top (a top grasp comes down
#: from above anyway).
TABLE_LIFT = 0.03


def skills(
    w: ParticleWorlds,
    cat: Catalogue,
    root: Root,
    home: np.ndarray,
    i: int,
    a: ManipAction,
    sim: WorldState,
    holder: int | None = None,
) -> tuple[list, ManipulationWorld | None]:
    """The skills to try in turn (each next grasp or placement while the previous
    cannot be reached: :attr:`~strug_manip.control.Outcome.cannot_reach`) and the
    planning world, for ``a`` on particle ``i`` in ``sim`` (on the real robot: ``i``
    is the model it plans in, ``sim`` its state). An opening or a probe follows
    ``holder``'s grasp and joint and plans in its likeliest state (default: the
    hypothesis's representative, :meth:`.Root.rep`). ``home``: where
    ``Place(table)`` puts the object back, (4, 4)."""
    if a.skill == "Pick":
        # The object's table is far from the cabinet: one planning world serves
        # every model, so the base placement is found once for all of them.
        return [Pick("object", a.grasp)], w.fetch(0)
    if a.skill == "Place" and a.part == TABLE:
        return [Place("object", home, TABLE_LIFT)], None
    part = cat.parts[a.part]
    if a.skill == "Place":
        link = part.links[i]
        if link is None:
            return [], None
        tw = w.twins[i]
        tw.restore(sim)
        world = tw.world
        q = position(world, w.particles[i].spec.part(link).joint)
        T_now = world.cabinet_pose()
        try:
            tgts = place_targets(w.particles[i].spec, link, q, T_now)
        except ConfigError:
            return [], None  # the part is not open enough: no pose to place at
        return [Place.onto(t) for t in tgts], None
    holder = root.rep(a) if holder is None else holder
    spec_part = w.particles[holder].spec.part(part.links[holder])
    plan_world = w.fetch(holder, root.best.get(holder))
    # A part stands where the real front does (conditioning.as_seen): it is grasped, and
    # moved on, from there, not from where it stood at the start (a drawer opened too
    # little was grasped 0.13 m behind its handle).
    q = position(plan_world, spec_part.joint)
    T = cabinet_frame(plan_world.cabinet_pose(), w.pose(holder))
    grasps = handle_grasps(spec_part, q, T)
    if a.skill in ("OpenDrawer", "OpenDoor"):
        joint = BelievedJoint.of_part(spec_part, q, T)
        longest = longest_travel(w, part.links, q, spec_part)
        likely, joint = joint.limit, replace(joint, limit=max(joint.limit, longest))
        opening = OpenDrawer if a.skill == "OpenDrawer" else OpenDoor
        return [opening(g, joint, likely_limit=likely) for g in grasps], plan_world
    probe = {"Push": Push, "PullV": PullV, "PullH": PullH}[a.skill]
    return [probe(g) for g in grasps], plan_world


def longest_travel(
    w: ParticleWorlds, links: Sequence[str | None], q: float, like: PartSpec
) -> float:
    """The longest travel [m or rad] left from ``q`` of any particle's part at a
    catalogued part (``links``: its link per particle) that moves as ``like`` does (a
    drawer; a door hinged on the same side): how far an opening of it goes on, slowly,
    past the likeliest model's limit. A part's limit shows in no view (the particles
    spread it over the generator's range, :mod:`.belief`). An opening that stopped at
    the likeliest model's limit left the real part open too little for the object,
    and every particle without a longer limit with no way to open it more: a drawer
    out too little; a lift-up flap raised to 1.18 rad, where the likeliest model's
    limit was 1.27 rad and its object needed 1.4 rad, was opened again, moving
    nothing, to the end of the episode (OpenDoor episode 9948; the real flap's limit
    was 1.56 rad)."""
    uppers = [
        p.upper
        for i, link in enumerate(links)
        if link is not None
        and (p := w.particles[i].spec.part(link)).joint_type == like.joint_type
        and p.hinge == like.hinge
    ]
    return max(uppers, default=q) - q


def cabinet_frame(T_now: np.ndarray, T_reset: np.ndarray) -> np.ndarray:
    """The cabinet frame an opening's or a probe's grasps and joint are grounded in,
    (4, 4): the model's frame at its reset ``T_reset``, or, once the cabinet has moved
    from there by more than :data:`~.rules.UNCHANGED` (a drag the conditioning passed
    on to every particle, :mod:`.conditioning`), where it stands now, ``T_now``: a
    cabinet that settled by fractions of a millimetre keeps the model's frame, and the
    same actions simulate the same. The grasp is at
    the model's handle with its part closed; without this, every opening of a cabinet
    the robot had slid 5 cm aimed at empty space and was ``not_applicable`` to the
    end (OpenDoor episode 9328)."""
    shift = float(np.linalg.norm(T_now[:3, 3] - T_reset[:3, 3]))
    turn = rotation_angle(T_reset[:3, :3].T @ T_now[:3, :3])
    return T_reset if max(shift, turn) <= UNCHANGED else T_now


def handle_point(
    world: ManipulationWorld, a: ManipAction, link: Callable[[], str | None]
) -> np.ndarray:
    """Where the acted part's handle (or the object, for Pick and Place) is in
    ``world``, (3,); ``link()`` names the acted part in ``world``'s cabinet (a
    particle's own link, or the real part acted on)."""
    if a.skill in ("Pick", "Place"):
        return world.object_pose()[:3, 3].copy()
    spec = world.scene.cabinet_spec
    T = world.cabinet_pose()
    qs = world.part_positions()
    name = link()
    if name is None:
        return np.zeros(3)
    p = spec.part(name)
    pt = part_point(p, qs.get(world.scene.cabinet_prefix + p.joint, 0.0), T)
    return np.zeros(3) if pt is None else pt


def reward(spec: CabinetSpec, target: str | None, world: ManipulationWorld, out: Outcome) -> float:
    """-10 when dragged; +10 when a ``Place`` leaves the object resting in the target
    (only a Place can: a model that believes the object already in it, after a real
    Place that failed, earns nothing from its other actions)."""
    if dragged(out.cabinet_displacement):
        return -10.0
    if target is None or out.holding or out.skill != "Place":
        return 0.0
    q = position(world, spec.part(target).joint)
    T_now = world.cabinet_pose()
    return 10.0 if inside(spec, target, q, T_now, world.object_pose()) else 0.0


def position(world: ManipulationWorld, joint: str) -> float:
    """Cabinet joint ``joint``'s position in ``world`` [m or rad] (0 for a fixed part)."""
    return world.part_positions().get(world.scene.cabinet_prefix + joint, 0.0)


def attempt(run: Callable[[], Outcome]) -> Outcome | None:
    """``run()``, or None when the skill cannot be planned in this model (its plan
    raises: no handle at the grasp, no travel left, nothing held to place)."""
    try:
        return run()
    except (ConfigError, UnknownNameError):
        return None


def first_feasible(runs: Iterable[Callable[[], Outcome]]) -> Outcome | None:
    """The outcome of the first of ``runs`` (callables, each a skill with its next
    grasp or placement) that can be reached (``Outcome.cannot_reach``), else the last
    one's (None when it could not be planned: :func:`attempt`).

    A goal the arm cannot reach without touching the cabinet counts as unreachable
    as much as one without an IK solution: before, a ``Place`` whose first target
    put the object into the front of the drawer above at the end of the carry
    stopped there (``no_motion_plan``, the goal invalid), and the robot asked for
    the same ``Place`` again, which stopped the same way (POMCPOW, OpenDrawer episode
    9943: two steps lost; its second target placed). The twins' floating hand plans
    no motions, so only the full robot's outcomes change."""
    out = None
    for run in runs:
        out = attempt(run)
        if out is not None and not out.cannot_reach:
            break
    return out


def in_turn(
    models: Sequence[int], plan_in: Callable[[int], Outcome | None]
) -> tuple[Outcome | None, int]:
    """``plan_in(m)`` for each of ``models`` in turn while it stops before anything
    moves (:data:`~.rules.BEFORE_MOTION`) or cannot be planned (None): the last outcome
    and how many models were tried. The real robot and every twin plan an opening or a
    probe this way, in :meth:`.catalogue.Root.plan_models`."""
    out, tried = None, 0
    for m in models:
        tried += 1
        out = plan_in(m)
        if out is not None and out.status not in BEFORE_MOTION:
            break
    return out, tried


def twin_run(
    w: ParticleWorlds,
    cat: Catalogue,
    i: int,
    a: ManipAction,
    sim: WorldState,
    models: Sequence[int],
    plan_for: Callable[[int | None], tuple[list, ManipulationWorld | None]],
) -> tuple[WorldState, tuple, float, bool, str]:
    """``a`` on particle ``i``'s twin from ``sim``, planned as the real robot plans it:
    in each of ``models`` in turn (:meth:`.catalogue.Root.plan_models`, :func:`in_turn`;
    -1: none to follow) with ``plan_for(model)``'s skills and planning world
    (:func:`skills`). Returns (next sim, observation key, reward, terminal, summary)."""
    tw = w.twins[i]
    tw.restore(sim)

    def link() -> str | None:
        return cat.parts[a.part].links[i]

    before = handle_point(tw.world, a, link)

    def run(skill, plan_world: ManipulationWorld | None) -> Outcome:
        tw.restore(sim)
        return skill.simulate(tw, plan_world=plan_world)

    def plan_in(holder: int) -> Outcome | None:
        candidates, plan_world = plan_for(None if holder < 0 else holder)
        return first_feasible(functools.partial(run, sk, plan_world) for sk in candidates)

    out, _ = in_turn(models, plan_in)
    if out is None:
        key = observation_key(NOT_APPLICABLE, holds_object(tw.world), np.zeros(3))
        return sim, key, 0.0, False, f"{a.skill}: {NOT_APPLICABLE}"
    motion = handle_point(tw.world, a, link) - before
    r = reward(w.particles[i].spec, cat.targets[i], tw.world, out)
    key = observation_key(out.status, out.holding, motion)
    return tw.snapshot(), key, r, r != 0.0, out.summary()
