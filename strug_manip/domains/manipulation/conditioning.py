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
does not show, where its front stands it does).
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

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from planners.particles import ParticleBelief
from strug_manip.control import PlanningTwin
from strug_manip.control.skills import holds_object
from strug_manip.domains.manipulation.actions import CataloguePart
from strug_manip.domains.manipulation.grounding import position
from strug_manip.domains.manipulation.state import ManipState
from strug_manip.domains.manipulation.worlds import ParticleWorlds
from strug_manip.objects.generator import PartSpec
from strug_manip.robot.fetch import BASE_JOINTS, GRIPPER_SITE
from strug_manip.world.sim import OBJECT_JOINT, ManipulationWorld

#: A real front this near its closed position is seen shut, by joint type [m or rad]:
#: the head camera's cloud shows a front flush with the carcass to about a centimetre,
#: and 0.1 rad is 2 cm at the edge of a 0.2 m door.
SHUT = {"prismatic": 0.02, "revolute": 0.1}


def condition(
    belief: ParticleBelief,
    real: ManipulationWorld,
    w: ParticleWorlds,
    parts: Sequence[CataloguePart],
    shut: Sequence[int],
    out: Mapping[int, np.ndarray] | None = None,
) -> ParticleBelief:
    """``belief`` given what the real world ``real`` shows for certain (module
    docstring); ``shut``: the catalogued parts whose real part stands shut
    (:func:`is_shut`); ``out``: how far the real handle of each catalogued part that
    stands open is out of where it is shut, world (3,) [m] (:func:`as_seen`)."""
    out = {} if out is None else out
    base = np.array([real.robot_qpos()[j] for j in BASE_JOINTS])
    moved = real.cabinet_pose() @ np.linalg.inv(real.scene.T_world_cabinet)
    holding = holds_object(real)
    known = [] if holding else [OBJECT_JOINT]
    T_go = np.linalg.inv(real.site_pose(GRIPPER_SITE)) @ real.object_pose() if holding else None

    def edit(tw: PlanningTwin, s: ManipState) -> None:
        tw.world.set_cabinet_pose(moved @ tw.world.scene.T_world_cabinet)
        tw.world.copy_joints(real, known)
        tw.set_robot_base(base)
        opened = _opened(parts, s.origin, shut, tw.world)
        opened |= as_seen(parts, s.origin, out, tw.world)
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


def as_seen(
    parts: Sequence[CataloguePart], i: int, out: Mapping[int, np.ndarray], world: ManipulationWorld
) -> dict[str, float]:
    """Particle ``i``'s parts (in its twin's ``world``) at the catalogued parts ``out``
    (a real handle's offset from where it is shut, world (3,) [m]), each moved as far
    as its own joint takes its handle by that offset, within its limits, by joint name:
    a drawer along its own axis, a door about its own hinge.

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
    spec, R = world.scene.cabinet_spec, world.cabinet_pose()[:3, :3]
    q = {}
    for k, d in out.items():
        link = parts[k].links[i]
        if link is None:
            continue
        p = spec.part(link)
        local = R.T @ np.asarray(d, dtype=float)  # the offset in this particle's cabinet
        if p.joint_type == "prismatic":
            v = float(local @ np.asarray(p.axis))
        elif p.joint_type == "revolute" and p.handle_pos is not None:
            v = swing(p, local)
        else:
            continue
        q[p.joint] = float(np.clip(v, p.lower, p.upper))
    return q


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
