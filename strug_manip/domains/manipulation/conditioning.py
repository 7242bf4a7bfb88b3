"""The real belief given what the robot knows for certain after a real step
(:func:`condition`, which the real robot's environment applies after every update).

Known in every particle alike: where the robot's base stands (its odometry), how far
the cabinet's base has moved since the start (the carcass, which the head camera's cloud
shows to millimetres; taken from the simulator as a perfect localisation; each
particle's own cabinet moves by that rigid motion from where it stood, its own front
where perception put it) and, when the hand is empty, where the object rests (it is
tracked as well), which parts stand shut (a front flush with the carcass) and where
the open ones' handles are (each particle's part is moved there along its own joint,
a drawer along its axis, a door about its hinge: which way a part opens the camera
does not show, where its front stands it does; a particle whose limit the real front
has passed gets that limit moved to the front, as no view shows a part's limit, and so
does a particle's drawer whose real opening met its end short of that limit).
Each particle keeps its other parts' joints and, when the real hand holds the object,
its own idea of the grasp; a particle whose hand is empty while the real one holds the
object (its twin's Place went through where the real one stopped) gets the object back
in its hand, in the real grasp. Without this a cabinet the real robot dragged by 5 cm
stays put in every particle, and the next Place aims 5 cm off; and after a real Place
that stopped, every particle believes the object placed and none plans to place it
again; and a drawer the arm pushed shut on its way to the cell stays open in every
particle, and every later Place aims into it.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from planners.particles import ParticleBelief
from strug_manip.control import PlanningTwin
from strug_manip.control.skills import holds_object
from strug_manip.domains.manipulation.actions import CataloguePart
from strug_manip.domains.manipulation.grounding import position
from strug_manip.domains.manipulation.state import ManipState
from strug_manip.domains.manipulation.worlds import ParticleWorlds
from strug_manip.objects import generator as gen
from strug_manip.objects.generator import CabinetSpec, PartSpec
from strug_manip.robot.fetch import BASE_JOINTS, GRIPPER_SITE
from strug_manip.world.sim import OBJECT_JOINT, ManipulationWorld

#: A real front this near its closed position is seen shut, by joint type [m or rad]:
#: the head camera's cloud shows a front flush with the carcass to about a centimetre,
#: and 0.1 rad is 2 cm at the edge of a 0.2 m door.
SHUT = {"prismatic": 0.02, "revolute": 0.1}
#: A particle's hinge counts as the real front's turning axis within 15 degrees
#: (cosine): its part then takes the front's angle, not the handle's.
SAME_HINGE = float(np.cos(np.radians(15.0)))
#: A real front this far beyond a particle's limit has passed it, by joint type [m or
#: rad]: the cloud places a front to about a centimetre, 0.05 rad at 0.2 m from a hinge.
PASSED = {"prismatic": 0.01, "revolute": 0.05}


@dataclass(frozen=True)
class Front:
    """A real front that stands open, as the head camera shows it, in the cabinet as it
    stands now.

    Attributes:
        offset: how far its handle is out of where it is shut, world (3,) [m].
        turn: for a front that turns (a door or a flap), the axis, world (3,) unit,
            and the angle [rad] that take the shut front's outward normal to the open
            front's; None for a drawer's (it is not turned).
    """

    offset: np.ndarray
    turn: tuple[np.ndarray, float] | None = None


def condition(
    belief: ParticleBelief,
    real: ManipulationWorld,
    w: ParticleWorlds,
    parts: Sequence[CataloguePart],
    shut: Sequence[int],
    fronts: Mapping[int, Front] | None = None,
    ended: Collection[int] = (),
) -> ParticleBelief:
    """``belief`` given what the real world ``real`` shows for certain (module
    docstring); ``shut``: the catalogued parts whose real part stands shut
    (:func:`is_shut`); ``fronts``: the real fronts of the catalogued parts that stand
    open (:func:`as_seen`); ``ended``: the catalogued parts whose real opening in the
    last step met its part's end (:attr:`.Outcome.met_end`). A particle whose part a
    real front has passed the limit of gets the limit the front showed first
    (:func:`passed_limits`), and one whose drawer's real opening ended short of its
    limit gets the limit where the front stopped (:func:`ended_limits`,
    :meth:`.ParticleWorlds.set_uppers`): its twin is rebuilt."""
    fronts = {} if fronts is None else fronts
    base = np.array([real.robot_qpos()[j] for j in BASE_JOINTS])
    moved = real.cabinet_pose() @ np.linalg.inv(real.scene.T_world_cabinet)
    holding = holds_object(real)
    known = [] if holding else [OBJECT_JOINT]
    T_go = np.linalg.inv(real.site_pose(GRIPPER_SITE)) @ real.object_pose() if holding else None
    # Where each particle's parts stand by the real fronts (a limit does not change it).
    seen = {}
    for i in sorted({s.origin for s in belief.states}):
        spec = w.particles[i].spec
        seen[i] = seen_positions(parts, i, fronts, spec, (moved @ w.pose(i))[:3, :3])
        ends = {link for k in ended if (link := parts[k].links[i]) is not None}
        uppers = passed_limits(seen[i], spec) | ended_limits(seen[i], spec, ends)
        if uppers:
            w.set_uppers(i, uppers, [k for k, c in enumerate(parts) if c.links[i] in uppers])

    def edit(tw: PlanningTwin, s: ManipState) -> None:
        tw.world.set_cabinet_pose(moved @ tw.world.scene.T_world_cabinet)
        tw.world.copy_joints(real, known)
        tw.set_robot_base(base)
        opened = _opened(parts, s.origin, shut, tw.world)
        opened |= as_seen(seen[s.origin], tw.world.scene.cabinet_spec)
        if opened:
            tw.world.set_parts(opened)
        if T_go is not None and not holds_object(tw.world):
            tw.world.set_object_pose(tw.world.site_pose(GRIPPER_SITE) @ T_go)

    return edit_states(belief, w, edit)


def edit_states(
    belief: ParticleBelief, w: ParticleWorlds, edit: Callable[[PlanningTwin, ManipState], None]
) -> ParticleBelief:
    """``belief`` with ``edit(twin, state)`` applied once to each distinct particle
    state, in its particle's twin restored to it; the twin's snapshot is the new state
    (same weights, same origins)."""
    done: dict[ManipState, ManipState] = {}
    states = []
    for s in belief.states:
        if s not in done:
            tw = w.twins[s.origin]
            tw.restore(s.sim)
            edit(tw, s)
            done[s] = ManipState(s.origin, tw.snapshot(), s.t, s.last)
        states.append(done[s])
    return ParticleBelief(states, belief.weights, belief.origin)


def _opened(
    parts: Sequence[CataloguePart], i: int, shut: Sequence[int], world: ManipulationWorld
) -> dict[str, float]:
    """Particle ``i``'s joints (in its twin's ``world``) of the parts ``shut`` that it
    holds open, each at 0 (closed), by joint name."""
    spec = world.scene.cabinet_spec
    held = [spec.part(link) for k in shut if (link := parts[k].links[i]) is not None]
    return {p.joint: 0.0 for p in held if not is_shut(world, p)}


def as_seen(seen: Mapping[str, float], spec: CabinetSpec) -> dict[str, float]:
    """The joint positions of a particle's parts (of its cabinet ``spec``) where the
    real fronts stand (``seen``, by link: :func:`seen_positions`), within their limits,
    by joint name.

    A twin ends an opening where its own limit or its own model of the pull stops it,
    and a real part may move after (a door the arm swung back as it went for the
    object); the real front stands where it stands. Where the two differed, the
    particle kept its own: after a real opening that its twin had stop short (or that
    its limit, short of the real one, capped), every particle held the drawer too
    little out for the object and planned no Place, and the robot opened other parts
    to the end of the episode (OpenDrawer episodes 9605, 9513); a door swung back from
    1.31 to 0.73 rad while the robot picked the object, every particle held it wide
    open, and the Place struck it and slid the cabinet (OpenDoor episode 9626).
    """
    return {(p := spec.part(k)).joint: float(np.clip(v, p.lower, p.upper)) for k, v in seen.items()}


def seen_positions(
    parts: Sequence[CataloguePart],
    i: int,
    fronts: Mapping[int, Front],
    spec: CabinetSpec,
    R: np.ndarray,
) -> dict[str, float]:
    """How far particle ``i``'s own joints (of ``spec``, its cabinet turned by ``R``
    (3, 3) in the world) take its parts to where the real ``fronts`` stand [m or rad],
    limits aside, by link: a drawer along its own axis as far as the real handle is
    out; a door about its own hinge by the real front's angle where the front turned
    about that hinge's line (within :data:`SAME_HINGE`), else as far as the turn takes
    its handle by the real handle's offset (:func:`swing`). A particle whose hinge is a
    few centimetres off the real one gets the real angle from the front's plane; from
    the handle alone it got angles 0.1-0.15 rad short (a flap the robot raised to 1.50
    rad stood at 1.35-1.39 rad in the particles hinged on its line whose limits
    allowed more, OpenDoor episode 9950), short of what the object needs."""
    q = {}
    for k, f in fronts.items():
        link = parts[k].links[i]
        if link is None:
            continue
        p = spec.part(link)
        local = R.T @ np.asarray(f.offset, dtype=float)  # in this particle's cabinet
        if p.joint_type == "prismatic":
            q[link] = float(local @ np.asarray(p.axis))
        elif p.joint_type == "revolute" and p.handle_pos is not None:
            q[link] = swing(p, local)
            if f.turn is not None:
                along = float((R.T @ f.turn[0]) @ np.asarray(p.axis))
                if abs(along) >= SAME_HINGE:  # hinged on the front's line: its angle
                    q[link] = f.turn[1] * float(np.sign(along))
    return q


def passed_limits(seen: Mapping[str, float], spec: CabinetSpec) -> dict[str, float]:
    """The limits a particle's parts (of its cabinet ``spec``) need where the real
    fronts stand beyond them (``seen``, by link: :func:`seen_positions`, more than
    :data:`PASSED` over the part's upper limit), by link [m or rad]: the front's
    position, up to the longest limit such a part has (:func:`longest_limit`).

    No view shows how far a part goes; the particles draw it from the generator's
    range. A real front seen beyond a particle's limit shows that limit wrong and
    nothing about the rest of the particle (its hinge, its handle), so the limit moves
    to what the front showed and the particle keeps its weight. Clipped to its own
    limit, the part stood short of where the real one did: a flap the robot raised to
    1.50 rad (its limit 1.55) stood at 1.25-1.30 rad in the particles hinged on its line
    with those limits (half the weight), short of what the object needs, and the robot
    opened it again to the end of the episode, moving nothing (OpenDoor episode 9950)."""
    out = {}
    for link, v in seen.items():
        p = spec.part(link)
        if v > p.upper + PASSED[p.joint_type]:
            out[link] = min(v, max(longest_limit(p), p.upper))
    return out


def ended_limits(
    seen: Mapping[str, float], spec: CabinetSpec, ended: Collection[str]
) -> dict[str, float]:
    """The limits a particle's drawers (of its cabinet ``spec``) get where a real
    opening met its part's end (``ended``: their links) and the real front stands
    (``seen``, by link: :func:`seen_positions`) more than :data:`PASSED` short of the
    drawer's upper limit, open (beyond :data:`SHUT`), by link [m]: the front's position,
    as far as an opening takes that drawer.

    The counterpart of :func:`passed_limits`. A real opening goes on past the likeliest
    model's limit (:func:`~.grounding.longest_travel`) until its part stops following
    the hand; where the drawer stands after it is as far as the robot's opening leaves
    it. A particle that kept its longer limit believed a second opening would take the
    drawer further, and the search opened it again. In OpenDrawer episode 10231 the
    first opening met the drawer's end at 0.182 m, and the drawer slid back to 0.137 m
    after the hand stopped (the cabinet had lifted 3 mm at the stop); the second pulled
    it to its end again, tipped the cabinet 6 degrees, drew out a drawer of the other
    column, and the next opening dragged the cabinet. Over the OpenDrawer runs on
    10190:10250, of 9 openings of a drawer an earlier opening had left ``ok``, 6 moved
    the cabinet and 3 left the drawer where it stood. Only drawers: a door's opening
    that stops along its arc may have met a hinge a little off, not the door's limit,
    and a door's limit capped short of the real one would leave the right hinge no way
    to open it further."""
    out = {}
    for link in ended:
        p = spec.part(link)
        v = seen.get(link)
        if p.joint_type != "prismatic" or v is None or v <= SHUT["prismatic"]:
            continue
        if v < p.upper - PASSED["prismatic"]:
            out[link] = max(v, p.lower)
    return out


def longest_limit(part: PartSpec) -> float:
    """The longest limit the generator gives a part like ``part`` [m or rad]: a
    drawer's travel cannot exceed its box's depth (:attr:`PartSpec.interior_size`
    along x), a door's and a flap's limits are drawn from ranges
    (:data:`~strug_manip.objects.generator.DOOR_SIDE_LIMIT`,
    :data:`~strug_manip.objects.generator.DOOR_FLAP_LIMIT`)."""
    if part.joint_type == "prismatic":
        return float(part.interior_size[0]) if part.interior_size is not None else part.upper
    side = part.hinge in ("left", "right")
    return (gen.DOOR_SIDE_LIMIT if side else gen.DOOR_FLAP_LIMIT)[1]


def swing(part: PartSpec, d: np.ndarray) -> float:
    """The angle [rad] about revolute ``part``'s hinge that moves its shut handle by
    ``d`` (3,) [m] (cabinet frame), or as near as a turn does (the turn between the
    two handle points seen along the hinge)."""
    a = np.asarray(part.axis, dtype=float)
    u = np.asarray(part.handle_pos, dtype=float) - np.asarray(part.origin, dtype=float)
    v = u + np.asarray(d, dtype=float)
    u, v = u - (u @ a) * a, v - (v @ a) * a
    return float(np.arctan2(a @ np.cross(u, v), u @ v))


def unmoved(belief: ParticleBelief, prior: ParticleBelief | None) -> ParticleBelief:
    """After a real step that stopped before anything moved, ``belief`` with every
    particle back in its state in ``prior`` (the belief before the step; its step count
    advanced): a twin that went through moved what the real robot did not touch.
    Particles correspond by position (the real belief is never resampled); ``belief``
    as it is when they do not."""
    if prior is None or len(prior) != len(belief):
        return belief
    if not np.array_equal(prior.origin, belief.origin):
        return belief
    states = [ManipState(p.origin, p.sim, s.t, s.last)
              for p, s in zip(prior.states, belief.states, strict=True)]  # fmt: skip
    return ParticleBelief(states, belief.weights, belief.origin)


def is_shut(world: ManipulationWorld, part: PartSpec) -> bool:
    """``part`` stands within :data:`SHUT` of closed in ``world`` (a fixed part always)."""
    kind = part.joint_type
    return kind == "fixed" or abs(position(world, part.joint)) <= SHUT[kind]
