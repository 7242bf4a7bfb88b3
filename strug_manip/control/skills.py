"""The paper's seven parameterised skills, as short phase sequences.

Each skill is a frozen dataclass of its parameters. :meth:`Skill.plan` turns them into
a :class:`~strug_manip.control.plan.SkillPlan` (gripper poses and grip commands, world
frame) against the world the robot *believes* in (the planning world); :meth:`Skill.run`
executes that plan on the full robot (:class:`~strug_manip.control.fetch_body.FullRobot`)
and :meth:`Skill.simulate` on the planning twin
(:class:`~strug_manip.control.twin_body.PlanningTwin`). Both return the same
:class:`~strug_manip.control.outcome.Outcome`: facts, not a verdict.

=================  ==========================================================================
skill              phases after the free motion to ``pre`` (``g`` the grasp pose)
=================  ==========================================================================
``OpenDrawer``     approach g, grasp, pull along the believed joint, release, retreat
``OpenDoor``       approach g, grasp, swing along the believed joint, release, retreat
``Push``           approach g, grasp, push ``probe_distance`` along the approach, release,
                   retreat
``PullV``          approach g, grasp, pull ``probe_distance`` up (``down``: down), release,
                   retreat
``PullH``          approach g, grasp, pull ``probe_distance`` out of the front, horizontally
                   (``sideways``: along the front), release, retreat
``Pick``           approach the object (``top``: from above; ``side``: level from the
                   robot's side), grasp, lift ``lift_height``; the robot then carries it
``Place``          carry the held object to ``p`` from above (top grasp) or from in front
                   (side grasp), release ``place_drop`` above ``p``, retreat
=================  ==========================================================================

After its retreat, a skill that moved a part by its handle also *withdraws* the hand
level away from the cabinet front (``withdraw_distance``), so the arm folds clear of
whatever a wrong belief left sticking out.

Openings follow whatever joint they are given (:class:`~strug_manip.objects.hypotheses.
BelievedJoint`): ``OpenDrawer`` with a revolute belief swings, ``OpenDoor`` with a
prismatic one pulls straight; the two differ in their default amount. An opening stops
``limit_margin`` short of the believed limit. The probes leave the part where they
moved it and let go: a drawer stays out, a side door stays ajar (hinge friction), a
top flap swings back shut under gravity unless its stay holds it, a bottom flap stays
(its friction stay). Every skill ends with the arm tucked (carrying the object: in its
carry posture), so the next may drive.

Bad parameters (a pose that is not a rigid transform, an unknown part or object, an
impossible travel) raise :class:`~planners.errors.ConfigError` /
:class:`~planners.errors.UnknownNameError` naming the value, before anything moves.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np

from planners.errors import ConfigError, UnknownNameError
from strug_manip.control.context import ControlContext
from strug_manip.control.executor import Body
from strug_manip.control.fetch_body import FullRobot, Observer
from strug_manip.control.grasps import held_grasp
from strug_manip.control.outcome import Outcome
from strug_manip.control.params import DEFAULT_PARAMS, SkillParams
from strug_manip.control.plan import (
    Grip,
    Line,
    SkillPlan,
    along,
    line_of,
    retreat_poses,
    straight,
)
from strug_manip.control.targets import PlaceTarget
from strug_manip.control.twin_body import BoundTwin, PlanningTwin
from strug_manip.objects.hypotheses import BelievedJoint, check_pose
from strug_manip.robot.fetch import GRIPPER_SITE
from strug_manip.world.scene import OBJECT_HALF_SIZE
from strug_manip.world.sim import ManipulationWorld

#: The graspable objects of the scene (body names).
OBJECTS: tuple[str, ...] = ("object",)
#: A handle is "at" g when its grasp point is this close to g's position [m].
HANDLE_RADIUS = 0.05
#: The object is held when its centre is this close to the TCP [m] (the box's half
#: diagonal is 0.06 m; a dropped object lies 0.2 m or more away).
HELD_RADIUS = 0.1
#: Grasps of :class:`Pick`.
GRASPS: tuple[str, ...] = ("top", "side")
#: An object held from the side higher in the fingers than :class:`Pick` took it (the
#: TCP at its centre), by more than this [m], is let go that much above its target
#: (:func:`held_rise`); below it, the fingers' give.
RISE_TOLERANCE = 0.003


class Skill:
    """Shared behaviour of the skills: plan, then run (full robot) or simulate (twin)."""

    #: The skill closes the fingers on something (a handle, the object), so it needs an
    #: empty gripper: the Fetch has one hand. ``Place`` carries what it holds instead.
    grasps: ClassVar[bool] = True

    def plan(self, world: ManipulationWorld, params: SkillParams = DEFAULT_PARAMS) -> SkillPlan:
        """The skill's gripper motions against ``world`` (the believed one)."""
        raise NotImplementedError

    @property
    def name(self) -> str:
        """The skill's name (its class name)."""
        return type(self).__name__

    def run(
        self,
        world: ManipulationWorld,
        *,
        ctx: ControlContext | None = None,
        params: SkillParams = DEFAULT_PARAMS,
        plan_world: ManipulationWorld | None = None,
        seed: int = 0,
        observer: Observer | None = None,
    ) -> Outcome:
        """Execute on the full robot in ``world`` (physics advances there), planning
        against ``plan_world`` (default ``world``; e.g. the believed cabinet).

        Raises:
            ConfigError, UnknownNameError: bad parameters, or a grasping skill with
                the object already in the gripper (:meth:`check_hand`; before anything
                moves).
        """
        # The robot first: it checks the worlds and the seed before anything is planned.
        robot = FullRobot(world, ctx, params, plan_world=plan_world, seed=seed, observer=observer)
        return self._execute(robot, params)

    def simulate(
        self,
        twin: PlanningTwin,
        params: SkillParams = DEFAULT_PARAMS,
        plan_world: ManipulationWorld | None = None,
    ) -> Outcome:
        """Execute on a planning twin (:class:`~strug_manip.control.twin_body.PlanningTwin`):
        physics in the twin's cabinet, the plan made against ``plan_world`` (the world
        the robot believes in, as for :meth:`run`; default: the twin's own cabinet)."""
        if not isinstance(twin, PlanningTwin):
            raise ConfigError(f"twin must be a PlanningTwin, got {twin!r}")
        if plan_world is not None and not isinstance(plan_world, ManipulationWorld):
            raise ConfigError(f"plan_world must be a ManipulationWorld or None, got {plan_world!r}")
        return self._execute(BoundTwin(twin, plan_world), params)

    def _execute(self, body: Body, params: SkillParams) -> Outcome:
        """Plan against the body's believed world and run the plan on the body: the one
        path of :meth:`run` (the full robot) and :meth:`simulate` (the planning twin)."""
        self.check_hand(body.world)  # where physics runs, before anything is planned
        return body.run(self.plan(body.believed(), params))

    def check_hand(self, world: ManipulationWorld) -> None:
        """Raise :class:`ConfigError` when the skill grasps (:attr:`grasps`) and the
        gripper of ``world`` (where physics runs, not the believed world) already holds
        the object: it would close on nothing, or knock the object out."""
        if self.grasps and holds_object(world):
            raise ConfigError(f"{self.name} needs an empty gripper; it holds the object")


# --- helpers --------------------------------------------------------------------------


def _positive(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.number):
        raise ConfigError(f"{name} must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v) or v <= 0:
        raise ConfigError(f"{name} must be a finite number > 0, got {value!r}")
    return v


def _nonnegative(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.number):
        raise ConfigError(f"{name} must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v) or v < 0:
        raise ConfigError(f"{name} must be a finite number >= 0, got {value!r}")
    return v


def part_at(world: ManipulationWorld, g: np.ndarray) -> tuple[str, str, float]:
    """The movable part whose handle is at ``g`` in ``world`` (its cabinet as the world
    models it): ``(link, joint name in the world, its position [m or rad])``.

    Raises:
        UnknownNameError: no handle within :data:`HANDLE_RADIUS` of g (lists the
            handles and where they are).
        ConfigError: the world's cabinet has no ground truth (a loaded folder).
    """
    spec = world.scene.cabinet_spec
    if spec is None:
        raise ConfigError("the world's cabinet has no part descriptions (cabinet_spec is None)")
    T = world.body_pose(world.scene.cabinet_prefix + world.scene.cabinet.root)
    qs = world.part_positions()
    best, where = None, []
    for p in spec.movable_parts:
        if p.handle_pos is None:
            continue
        joint = world.scene.cabinet_prefix + p.joint
        h = p.handle_at(qs[joint], T)
        where.append(f"{p.link} at {np.round(h, 3).tolist()}")
        dist = float(np.linalg.norm(h - g[:3, 3]))
        if dist < HANDLE_RADIUS and (best is None or dist < best[0]):
            best = (dist, p.link, joint, qs[joint])
    if best is None:
        raise UnknownNameError(
            f"cabinet part with a handle within {HANDLE_RADIUS} m of g's position "
            f"{np.round(g[:3, 3], 3).tolist()} (handles)",
            "g",
            where,
        )
    return best[1], best[2], best[3]


def _approach(g: np.ndarray, link_body: str, p: SkillParams) -> tuple[np.ndarray, Line]:
    """The pre-grasp and the approach line to ``g`` (the hand may touch the part)."""
    pre = g.copy()
    pre[:3, 3] -= p.pregrasp_offset * g[:3, 0]
    poses = straight(pre, g[:3, 3] - pre[:3, 3], p.line_step)
    return pre, line_of("approach", poses, p.approach_speed, touch=frozenset({link_body}))


def _grasp_and_move(
    skill: str,
    world: ManipulationWorld,
    g: np.ndarray,
    poses: tuple[np.ndarray, float],
    speed: float,
    name: str,
    part_q: np.ndarray | None,
    p: SkillParams,
    ease: float | None = None,
) -> SkillPlan:
    """Approach g, grasp, move along ``poses``, release, retreat, withdraw (level, away
    from the front, for a grasp that is not from above): the plan of every skill that
    moves a part by its handle. An opening (``name`` ``move``) eases its last ``ease``
    of TCP travel [m] (default ``p.ease_distance``, :func:`_eased`)."""
    link, joint, _ = part_at(world, g)
    body = world.scene.cabinet_prefix + link
    pre, approach = _approach(g, body, p)
    touch = frozenset({body})
    tol = p.probe_tolerance if name == "probe" else None
    # A probe presses wherever the part lets it (a push into a closed front): the hand
    # may touch the carcass around the part too.
    carcass = world.scene.cabinet_prefix + world.scene.cabinet_spec.carcass
    probe_touch = touch | {carcass} if name == "probe" else touch
    moving = line_of(
        name, poses, speed, touch=probe_touch, holding=True, part_joint=joint, part_q=part_q,
        tolerance=tol,
    )  # fmt: skip
    moves = _eased(moving, p, ease) if name == "move" else (moving,)
    end = moving.poses[-1]
    q_end = None if part_q is None else np.full(1, part_q[-1])
    back = retreat_poses(end, p.retreat_distance, p.line_step)
    retreat = line_of(
        "retreat", back, p.retreat_speed, touch=probe_touch, part_joint=joint,
        part_q=None if q_end is None else np.repeat(q_end, len(back[0])),
    )  # fmt: skip
    phases = (approach, Grip(True), *moves, Grip(False), retreat)
    away = -g[:3, 0].copy()
    away[2] = 0.0
    if np.linalg.norm(away) > 0.3:  # a level-ish grasp: back away from the front
        start = retreat.poses[-1]
        steps = straight(start, p.withdraw_distance * away / np.linalg.norm(away), p.line_step)
        withdraw = line_of(
            "withdraw", steps, p.retreat_speed, part_joint=joint,
            part_q=None if q_end is None else np.repeat(q_end, len(steps[0])),
        )  # fmt: skip
        phases = (*phases, withdraw)
    return SkillPlan(skill, pre, phases, part=link)


def _eased(line: Line, p: SkillParams, ease: float | None = None) -> tuple[Line, ...]:
    """An opening's ``move`` line as two: ``move`` up to ``ease`` of TCP travel [m]
    (default ``p.ease_distance``) before its end, then ``ease``, the rest at
    ``ease_speed`` (a path no longer than twice ``p.ease_distance`` stays one line; an
    ``ease`` as long as the path eases all of it). The part comes to rest slowly where
    the opening ends: the arm's servos, wound up by the part's damping at the opening's
    speed, carry the hand up to 2.4 cm beyond the end of a line, and a part whose stop
    lies there (a believed limit a centimetre or two too far out) hit it at full speed
    and tipped the cabinet, which slid the drawer back 6 cm into the carcass as it came
    down."""
    n = len(line.poses)
    ease = p.ease_distance if ease is None else ease
    k = min(round(n * ease / line.length), n) if line.length > 0 else 0
    if line.length <= 2 * p.ease_distance or k <= 0:
        return (line,)
    if k == n:
        return (dataclasses.replace(line, name="ease", speed=p.ease_speed),)
    q = line.part_q
    head = dataclasses.replace(
        line, poses=line.poses[: n - k], length=line.length * (n - k) / n,
        part_q=None if q is None else q[: n - k],
    )  # fmt: skip
    tail = dataclasses.replace(
        line, name="ease", poses=line.poses[n - k :], length=line.length * k / n,
        speed=p.ease_speed, part_q=None if q is None else q[n - k :],
    )  # fmt: skip
    return (head, tail)


# --- openings -------------------------------------------------------------------------


@dataclass(frozen=True)
class _Opening(Skill):
    """Grasp the handle at ``g`` and open the part along ``joint`` by ``amount``.

    ``likely_limit``: the travel left [m or rad] under the likeliest model, where
    ``joint.limit`` is a longer model's: the opening goes at its speed to
    ``params.ease_distance`` before that (less ``params.limit_margin_*``) and on from
    there at ``params.ease_speed``, so that whichever of the two the part's end is, it
    meets it slowly (None: ``joint.limit`` is the likeliest's)."""

    g: np.ndarray
    joint: BelievedJoint
    amount: float | None = None
    likely_limit: float | None = None

    def default_amount(self, p: SkillParams) -> float:
        raise NotImplementedError

    def plan(self, world: ManipulationWorld, params: SkillParams = DEFAULT_PARAMS) -> SkillPlan:
        g = check_pose("g (T_world_gripper)", self.g)
        if not isinstance(self.joint, BelievedJoint):
            raise ConfigError(f"joint must be a BelievedJoint, got {self.joint!r}")
        want = self.default_amount(params) if self.amount is None else self.amount
        want = _positive("amount", want)
        prismatic = self.joint.type == "prismatic"
        margin = params.limit_margin_m if prismatic else params.limit_margin_rad
        amount = min(want, self.joint.limit - margin)
        if amount <= 0:
            raise ConfigError(
                f"impossible travel: the believed joint has {self.joint.limit:.3f} "
                f"{'m' if prismatic else 'rad'} left, less than the margin {margin}"
            )
        radius = 1.0
        move = self.joint.move
        if not prismatic:
            radius = float(np.linalg.norm(np.cross(self.joint.axis, g[:3, 3] - self.joint.origin)))
            link = part_at(world, g)[0]
            part = world.scene.cabinet_spec.part(link)
            flap = abs(self.joint.axis[2]) < 0.3
            if flap and part.handle == "bar":
                move = _rolling(self.joint, params.flap_wrist_share)
        poses = along(move, g, amount, max(radius, 1e-3), params.line_step)
        _, world_joint, q0 = part_at(world, g)
        n = len(poses[0])
        part_q = q0 + amount * np.arange(1, n + 1) / n
        if world.part_units()[world_joint] != ("m" if prismatic else "rad"):
            # The world holds the part on another kind of joint (a twin of the true
            # cabinet simulating a wrong belief): its checks cannot move it along.
            part_q = None
        ease = params.ease_distance
        if self.likely_limit is not None:
            slow = amount - min(amount, max(self.likely_limit - margin, 0.0))
            ease += slow * max(radius, 1e-3)
        return _grasp_and_move(
            self.name, world, g, poses, params.open_speed, "move", part_q, params, ease
        )


def _rolling(joint: BelievedJoint, share: float):
    """A flap's swing with its bar rolling in the fingers: the TCP follows the handle's
    arc while the gripper turns by only ``share`` of the flap's angle (the wrist cannot
    follow a drop-down flap that turns the handle down by 70-90 degrees)."""

    def move(T: np.ndarray, q: float) -> np.ndarray:
        out = joint.move(T, share * q)
        out[:3, 3] = joint.move(T, q)[:3, 3]
        return out

    return move


@dataclass(frozen=True)
class OpenDrawer(_Opening):
    """Grasp at ``g`` and pull along the believed joint (straight for a prismatic one).

    Attributes:
        g: grasp pose ``T_world_gripper``, (4, 4) [m] (a handle must be there).
        joint: the believed joint (world frame).
        amount: how far [m] (None: ``params.drawer_travel``), capped before the
            believed limit.
    """

    def default_amount(self, p: SkillParams) -> float:
        return p.drawer_travel


@dataclass(frozen=True)
class OpenDoor(_Opening):
    """Grasp at ``g`` and swing about the believed hinge (a prismatic belief: pull).

    Attributes:
        g: grasp pose ``T_world_gripper``, (4, 4) [m].
        joint: the believed joint (world frame).
        amount: how far [rad] (None: ``params.door_angle`` for a vertical hinge,
            ``params.flap_angle`` for a lift-up flap, ``params.drop_angle`` for a
            drop-down one), capped before the believed limit.
    """

    def default_amount(self, p: SkillParams) -> float:
        if self.joint.type == "prismatic":
            return p.drawer_travel
        if abs(self.joint.axis[2]) > 0.7:
            return p.door_angle
        # A flap: the hinge below the handle (drop-down) or above it (lift-up).
        return p.drop_angle if self.joint.origin[2] < self.g[2, 3] else p.flap_angle


# --- probes ---------------------------------------------------------------------------


def _probe(skill: Skill, world: ManipulationWorld, g: object, d: np.ndarray, p: SkillParams):
    g = check_pose("g (T_world_gripper)", g)
    poses = straight(g, p.probe_distance * d, p.line_step)
    return _grasp_and_move(skill.name, world, g, poses, p.probe_speed, "probe", None, p)


@dataclass(frozen=True)
class Push(Skill):
    """Grasp at ``g`` and push ``probe_distance`` along the approach (into the front)."""

    g: np.ndarray

    def plan(self, world: ManipulationWorld, params: SkillParams = DEFAULT_PARAMS) -> SkillPlan:
        g = check_pose("g (T_world_gripper)", self.g)
        return _probe(self, world, g, g[:3, 0], params)


@dataclass(frozen=True)
class PullV(Skill):
    """Grasp at ``g`` and pull ``probe_distance`` up (world +z; ``down``: -z)."""

    g: np.ndarray
    down: bool = False

    def plan(self, world: ManipulationWorld, params: SkillParams = DEFAULT_PARAMS) -> SkillPlan:
        return _probe(self, world, self.g, np.array([0.0, 0.0, -1.0 if self.down else 1.0]), params)


@dataclass(frozen=True)
class PullH(Skill):
    """Grasp at ``g`` and pull ``probe_distance`` horizontally out of the front (against
    the approach, made level; ``sideways``: along the front, z x out)."""

    g: np.ndarray
    sideways: bool = False

    def plan(self, world: ManipulationWorld, params: SkillParams = DEFAULT_PARAMS) -> SkillPlan:
        g = check_pose("g (T_world_gripper)", self.g)
        out = -g[:3, 0].copy()
        out[2] = 0.0
        n = float(np.linalg.norm(out))
        if n < 1e-6:
            raise ConfigError("PullH needs a grasp whose approach is not vertical")
        out /= n
        if self.sideways:
            out = np.cross([0.0, 0.0, 1.0], out)
        return _probe(self, world, g, out, params)


# --- pick and place -------------------------------------------------------------------


def _check_object(o: str) -> None:
    if o not in OBJECTS:
        raise UnknownNameError("graspable object", o, OBJECTS)


def object_grasp(T_world_object: np.ndarray, grasp: str, toward: np.ndarray) -> np.ndarray:
    """``T_world_gripper`` (4, 4) grasping the box at ``T_world_object``.

    ``top``: the approach straight down, the fingers across the box's y side (0.06 m),
    the TCP 1 cm above its centre. ``side``: level, along the box's x axis (the sign
    that points toward ``toward`` (2,): the middle of the table it stands on, so the
    hand comes in from beside the table, not across it), the fingers across its y
    side, the TCP at its centre.
    """
    T = np.eye(4)
    y = T_world_object[:3, 1].copy()
    y[2] = 0.0
    y /= np.linalg.norm(y)
    if grasp == "top":
        x = np.array([0.0, 0.0, -1.0])
        T[:3, 3] = T_world_object[:3, 3] + [0.0, 0.0, 0.01]
    else:
        x = T_world_object[:3, 0].copy()
        x[2] = 0.0
        x /= np.linalg.norm(x)
        if x[:2] @ (np.asarray(toward, dtype=float) - T_world_object[:2, 3]) < 0:
            x = -x
        T[:3, 3] = T_world_object[:3, 3]
    T[:3, :3] = np.column_stack([x, y, np.cross(x, y)])
    return T


def holds_object(world: ManipulationWorld) -> bool:
    """The object is in the hand: its centre within :data:`HELD_RADIUS` of the TCP (the
    full Fetch's or the twin's hand alike)."""
    tcp = world.site_pose(GRIPPER_SITE)[:3, 3]
    return bool(np.linalg.norm(tcp - world.object_pose()[:3, 3]) <= HELD_RADIUS)


def held_rise(T_world_gripper: np.ndarray, T_world_object: np.ndarray) -> float:
    """How much higher an object held from the side stands in the hand than
    :class:`Pick` took it (its centre at the TCP) [m], if more than
    :data:`RISE_TOLERANCE`, else 0; 0 for an object held from above.

    An object that rose in the fingers (the oracle's OpenDoor 10053: 2.5 cm after a
    side grasp) would take the hand below its own bottom when set down, the palm into
    the shelf or the table at every base (``ik_infeasible``, the table's place too). A
    place then stops the hand where the hold Pick made would put it, and the object
    drops the rest. Held from above, the fingertips hang 3.4 cm above the object's
    bottom as Pick takes it, and the full robot's hold routinely rises 4-7 mm (its
    twin's does not): letting those go higher changed episodes that had nothing to
    gain (OpenDrawer 10087), so they keep their place."""
    T_go = np.linalg.inv(T_world_gripper) @ T_world_object
    if held_grasp(T_go) == "top":
        return 0.0
    rise = float(T_world_object[2, 3] - T_world_gripper[2, 3])
    return rise if rise > RISE_TOLERANCE else 0.0


@dataclass(frozen=True)
class Pick(Skill):
    """Pick the object ``o`` where it lies and lift it; the robot then carries it.

    Attributes:
        o: the object's body name (:data:`OBJECTS`).
        grasp: ``top`` (from above: for placing into drawers) or ``side`` (level: for
            placing into a cell behind a door).
    """

    o: str = "object"
    grasp: Literal["top", "side"] = "top"

    def plan(self, world: ManipulationWorld, params: SkillParams = DEFAULT_PARAMS) -> SkillPlan:
        _check_object(self.o)
        if self.grasp not in GRASPS:
            raise UnknownNameError("grasp", self.grasp, GRASPS)
        g = object_grasp(world.object_pose(), self.grasp, np.array(world.config.table_xy))
        touch = frozenset({self.o})
        pre = g.copy()
        pre[:3, 3] -= params.pick_offset * g[:3, 0]
        if self.grasp == "side":
            pre[:3, 3] -= OBJECT_HALF_SIZE[0] * g[:3, 0]  # the fingers clear the box
        approach = line_of(
            "approach", straight(pre, g[:3, 3] - pre[:3, 3], params.line_step),
            params.approach_speed, touch=touch,
        )  # fmt: skip
        lift = line_of(
            "lift", straight(g, np.array([0.0, 0.0, params.lift_height]), params.line_step),
            params.approach_speed, touch=touch, holding=True,
        )  # fmt: skip
        return SkillPlan(self.name, pre, (approach, Grip(True), lift))


@dataclass(frozen=True)
class Place(Skill):
    """Carry the held object ``o`` to pose ``p``, release it there and retreat.

    Attributes:
        o: the object's body name.
        p: target ``T_world_object``, (4, 4) [m]; the gripper keeps its grasp, so p's
            orientation must be reachable with it (a top grasp: any yaw).
        lift: a level-held object starts this much higher than ``p`` and comes down to
            it on the way in [m] (:func:`~strug_manip.control.targets.place_target`
            says how much a cell leaves room for); an object held from above is lowered
            onto ``p`` from this high, or from ``place_clearance`` if that is higher (a
            drawer's target asks for more: from above the drawer's cell), and the hand
            retreats as high.
        skim: an object held from above is lowered from exactly ``lift`` (> 0), even
            below ``place_clearance``: a drawer too high up for the hand to start
            higher, its walls skimmed (:data:`~strug_manip.control.targets.SKIM_OVER`).

    The object is let go ``SkillParams.place_drop`` above ``p``, and, held from the
    side, higher by as much as it rose in the fingers since :class:`Pick` took it
    (:func:`held_rise`).
    """

    o: str
    p: np.ndarray
    lift: float = 0.0
    skim: bool = False
    grasps: ClassVar[bool] = False

    @classmethod
    def onto(cls, target: PlaceTarget, o: str = "object") -> Place:
        """The Place that puts ``o`` where ``target`` says, as it says
        (:func:`~strug_manip.control.targets.place_targets`)."""
        return cls(o, target.p, target.lift, target.skim)

    def plan(self, world: ManipulationWorld, params: SkillParams = DEFAULT_PARAMS) -> SkillPlan:
        _check_object(self.o)
        p = check_pose("p (T_world_object)", self.p)
        if not holds_object(world):
            raise ConfigError(f"Place needs {self.o!r} in the gripper; it is not held")
        T_wg, T_wo = world.site_pose(GRIPPER_SITE), world.object_pose()
        T_go = np.linalg.inv(T_wg) @ T_wo
        g = p @ np.linalg.inv(T_go)
        g[2, 3] += params.place_drop + held_rise(T_wg, T_wo)
        top = g[2, 0] < -0.7  # the approach points down
        d = np.array([0.0, 0.0, -1.0]) if top else g[:3, 0].copy()
        if not top:
            d[2] = 0.0
            d /= np.linalg.norm(d)
        lift = _nonnegative("lift", self.lift)
        clearance = params.insert_clearance
        if top:
            clearance = lift if self.skim and lift > 0.0 else max(params.place_clearance, lift)
        touch = frozenset({self.o})
        above = g.copy()  # level: in at the lifted height, then down inside the cell
        if not top:
            above[2, 3] += lift
        pre = above.copy()
        pre[:3, 3] -= clearance * d
        lines = [
            line_of(
                "place", straight(pre, above[:3, 3] - pre[:3, 3], params.line_step),
                params.approach_speed, touch=touch, holding=True,
            )
        ]  # fmt: skip
        if above[2, 3] > g[2, 3]:
            lines.append(
                line_of(
                    "lower", straight(above, g[:3, 3] - above[:3, 3], params.line_step),
                    params.approach_speed, touch=touch, holding=True,
                )
            )  # fmt: skip
        back = -d if top else -g[:3, 0]
        retreat = line_of(
            "retreat", straight(g, clearance * back, params.line_step),
            params.retreat_speed, touch=touch,
        )  # fmt: skip
        phases = (*lines, Grip(False), retreat)
        return SkillPlan(self.name, pre, phases, carrying=(self.o, T_go))
