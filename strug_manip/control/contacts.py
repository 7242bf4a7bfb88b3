"""Robot contacts at kinematic configurations: the one collision check of the controllers.

:class:`ContactChecker` sets joint values into a scratch ``MjData`` of a world's model
(``mj_kinematics`` + ``mj_collision``, no physics) and reports the contacts of robot
bodies that are not allowed. The OMPL validity check (:mod:`.motion`), the checks of
the Cartesian lines of every skill and the base placement search (:mod:`.placement`)
all use it.

- *Robot bodies* are the subtree of the robot's root body; a contact counts if one of
  its two bodies is a robot body and the pair is not allowed. Self-contacts count too,
  though the simulation leaves them out (the scene's ``ROBOT_CONTYPE``).
- The checker works on a copy of the model whose collision bits (:data:`ENV_BIT`,
  :data:`ROBOT_BIT`) keep exactly the pairs that can count: robot with robot, and
  robot with every geom of the scene that collides with the robot in the simulation.
  The scene's own contacts (a cabinet on the floor, drawers in their carcass, the
  object on the table: about a dozen per check, none of which can count) are never
  computed: the narrow phase of ``mj_collision`` sees only what the robot touches.
- *Allowed pairs* are body ids, e.g. the fingers with the handle they are about to grasp
  (:meth:`ContactChecker.allow`).
- An *attached* body (a held object) follows the gripper: before each check its free
  joint is set so that ``T_world_body = T_world_gripper @ T_gripper_body``; its contacts
  with the gripper are allowed, its contacts with anything else count as the robot's.
- Other coordinates (the base, the cabinet parts, the object when not held) stay as the
  caller sets them (:meth:`ContactChecker.load`, :meth:`ContactChecker.set`).
- *Clearance*: scene bodies may count the robot's contacts from a distance
  (:meth:`ContactChecker.keep_clear_of`: their geoms' margin, so the robot's contacts
  among themselves stay as they are), and *excused* pairs count only where they touch
  (:meth:`ContactChecker.excuse`: what a motion starts or ends near).
"""

from __future__ import annotations

import copy
import itertools
import math
from collections.abc import Iterable, Sequence

import mujoco
import numpy as np

from planners.errors import ConfigError, UnknownNameError
from strug_manip.geometry import quat_of
from strug_manip.robot.fetch import GRIPPER_SITE

#: Largest joint step between two checks along a joint-space segment [rad or m].
CHECK_STEP = 0.04
#: Collision bits of the checker's model copy: the scene's geoms have contype ENV_BIT
#: and conaffinity 0 (no contact among themselves), the robot's (and an attached
#: body's) contype ROBOT_BIT and conaffinity ENV_BIT | ROBOT_BIT.
ENV_BIT, ROBOT_BIT = 1, 2
#: Bodies of the Fetch's hand: they may touch what they grasp.
HAND_BODIES: tuple[str, ...] = ("gripper_link", "r_gripper_finger_link", "l_gripper_finger_link")


class ContactChecker:
    """Forbidden robot contacts of a model at kinematic configurations.

    Args:
        model: a MuJoCo model holding the robot (and the scene).
        joints: the joints whose values the checks set, in the order of the vectors
            given to :meth:`contacts` (e.g. torso + arm, or base + torso + arm).
        robot_root: the robot's root body (default: the root of ``joints[0]``'s body).

    Raises:
        UnknownNameError: a joint or body name is not in the model.
        ConfigError: ``joints`` is empty or a joint is not a hinge or slide.
    """

    def __init__(
        self, model: mujoco.MjModel, joints: Sequence[str], robot_root: str | None = None
    ) -> None:
        m = self.model = model
        names = [m.joint(j).name for j in range(m.njnt)]
        if isinstance(joints, str) or not joints:
            raise ConfigError(f"joints must be a non-empty sequence of names, got {joints!r}")
        ids = []
        for j in joints:
            jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j)
            if jid < 0:
                raise UnknownNameError("joint", j, names)
            if int(m.jnt_type[jid]) not in (
                int(mujoco.mjtJoint.mjJNT_HINGE),
                int(mujoco.mjtJoint.mjJNT_SLIDE),
            ):
                raise ConfigError(f"joint {j!r} must be a hinge or slide joint")
            ids.append(jid)
        self.joints = tuple(joints)
        self.qadr = np.array([m.jnt_qposadr[j] for j in ids])
        root = (
            int(m.body_rootid[m.jnt_bodyid[ids[0]]])
            if robot_root is None
            else self.body_id(robot_root)
        )
        self.robot = np.array([b != 0 and int(m.body_rootid[b]) == root for b in range(m.nbody)])
        self.model = m = copy.copy(model)  # its collision bits become the checker's own
        self._margin0 = np.asarray(m.geom_margin).copy()
        self._body_margin0 = np.asarray(m.body_margin).copy()
        self.geom_body = np.asarray(m.geom_bodyid).copy()
        self._env_bits = _checker_bits(m, self.robot[self.geom_body])
        self.hand = np.array([self.body_id(b) for b in HAND_BODIES])
        self._hand_rigid = np.zeros(m.nbody, dtype=bool)
        self._hand_rigid[self.hand] = True
        b = self.body_id(HAND_BODIES[0])  # up from the gripper to its first joint
        while b > 0:
            self._hand_rigid[b] = True
            if m.body_jntnum[b] > 0:  # it turns about its own joint; its parent does not
                break
            b = int(m.body_parentid[b])
        self.data = mujoco.MjData(m)
        self._site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, GRIPPER_SITE)
        self._allowed = np.zeros((m.nbody, m.nbody), dtype=bool)
        # Bodies whose contacts count: the robot's, and an attached body.
        self._counts = self.robot.copy()
        self._attached: tuple[int, int, np.ndarray] | None = None  # body, qpos adr, T_g_b
        # Geom pairs that count only nearer than their own distance [m] (not within the
        # margin), either order; NaN: not excused.
        self._excused = np.full((m.ngeom, m.ngeom), np.nan)

    def body_id(self, name: str) -> int:
        """Id of the body ``name``; raises :class:`UnknownNameError`."""
        bid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, name)
        if bid < 0:
            names = [self.model.body(i).name for i in range(self.model.nbody)]
            raise UnknownNameError("body", name, names)
        return int(bid)

    # -- state -------------------------------------------------------------------------
    def load(self, data: mujoco.MjData) -> ContactChecker:
        """Copy ``data``'s positions (and mocap poses) into the scratch data."""
        self.data.qpos[:] = data.qpos
        if self.model.nmocap:
            self.data.mocap_pos[:] = data.mocap_pos
            self.data.mocap_quat[:] = data.mocap_quat
        return self

    def set(self, values: dict[str, float]) -> ContactChecker:
        """Set joints of the scratch data by name (e.g. the base, or a part's joint)."""
        m = self.model
        for name, v in values.items():
            jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
            if jid < 0:
                raise UnknownNameError("joint", name, [m.joint(j).name for j in range(m.njnt)])
            self.data.qpos[m.jnt_qposadr[jid]] = v
        return self

    def set_pose(self, body: str, T_world_body: np.ndarray) -> ContactChecker:
        """Put the free body ``body`` (e.g. the object) at ``T_world_body`` (4, 4) in the
        scratch data."""
        m = self.model
        jnt = int(m.body_jntadr[self.body_id(body)])
        if jnt < 0 or int(m.jnt_type[jnt]) != int(mujoco.mjtJoint.mjJNT_FREE):
            raise ConfigError(f"only a body on a free joint can be placed, got {body!r}")
        adr = int(m.jnt_qposadr[jnt])
        T = np.asarray(T_world_body, dtype=float)
        self.data.qpos[adr : adr + 3] = T[:3, 3]
        self.data.qpos[adr + 3 : adr + 7] = quat_of(T[:3, :3])
        return self

    def get(self, joint: str) -> float:
        """A hinge or slide joint's position in the scratch data [m or rad]."""
        jid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, joint)
        if jid < 0:
            names = [self.model.joint(j).name for j in range(self.model.njnt)]
            raise UnknownNameError("joint", joint, names)
        return float(self.data.qpos[self.model.jnt_qposadr[jid]])

    def allow(self, pairs: Iterable[tuple[int, int]] = ()) -> ContactChecker:
        """Replace the allowed body pairs (ids, either order)."""
        self._allowed[:] = False
        for a, b in pairs:
            self._allowed[a, b] = self._allowed[b, a] = True
        if self._attached is not None:
            for h in self.hand:
                self._allowed[self._attached[0], h] = self._allowed[h, self._attached[0]] = True
        return self

    def hand_with(self, bodies: Iterable[int]) -> list[tuple[int, int]]:
        """Pairs (hand body, body) for every hand body and each of ``bodies``."""
        return [(int(h), int(b)) for h in self.hand for b in bodies]

    def attach(self, body: str | None, T_gripper_body: np.ndarray | None = None) -> None:
        """Make ``body`` (a free body, e.g. the held object) follow the gripper at
        ``T_gripper_body`` (4, 4); ``None`` detaches."""
        if body is None:
            self._detach()
            return
        m = self.model
        bid = self.body_id(body)
        jnt = int(m.body_jntadr[bid])
        if jnt < 0 or int(m.jnt_type[jnt]) != int(mujoco.mjtJoint.mjJNT_FREE):
            raise ConfigError(f"only a body on a free joint can be attached, got {body!r}")
        self._detach()
        self._attached = (bid, int(m.jnt_qposadr[jnt]), np.asarray(T_gripper_body, float))
        for h in self.hand:
            self._allowed[bid, h] = self._allowed[h, bid] = True
        # Held, it collides as the robot does: with the scene and with the robot.
        geoms = (self.geom_body == bid) & (self._env_bits[:, 0] != 0)
        m.geom_contype[geoms] = ROBOT_BIT
        m.geom_conaffinity[geoms] = ENV_BIT | ROBOT_BIT
        self._counts[bid] = True

    def keep_clear(self, distance: float) -> None:
        """Count the attached body's contacts from ``distance`` [m] apart (0: touching,
        the default): its geoms' MuJoCo margin, which the narrow phase honours for box,
        plane, sphere and capsule pairs (the cabinet's boards), not for the general
        convex ones (cylinder handles, meshes: those count from touching). Detaching
        resets it. Raises :class:`ConfigError` when nothing is attached."""
        if self._attached is None:
            raise ConfigError("keep_clear needs an attached body (attach one first)")
        if not (math.isfinite(distance) and distance >= 0.0):
            raise ConfigError(f"distance must be a finite length >= 0 [m], got {distance!r}")
        bid = self._attached[0]
        self.model.geom_margin[self.geom_body == bid] = distance
        # The broad phase bounds each body by its largest geom margin, set at compile time.
        self.model.body_margin[bid] = max(distance, float(self._body_margin0[bid]))

    def keep_clear_of(self, bodies: Iterable[int], distance: float) -> None:
        """Count the robot's (and an attached body's) contacts with the scene bodies
        ``bodies`` (ids) from ``distance`` [m] apart (0: touching, their default): those
        bodies' geoms' MuJoCo margin, so pairs within the robot are unaffected.

        Raises:
            ConfigError: ``distance`` is negative or not finite, or a body belongs to
                the robot.
        """
        if not (math.isfinite(distance) and distance >= 0.0):
            raise ConfigError(f"distance must be a finite length >= 0 [m], got {distance!r}")
        ids = np.asarray(list(bodies), dtype=int)
        if np.any(self.robot[ids]):
            raise ConfigError("keep_clear_of takes scene bodies, not the robot's")
        geoms = np.isin(self.geom_body, ids) & (self._env_bits[:, 0] != 0)
        self.model.geom_margin[geoms] = np.maximum(distance, self._margin0[geoms])
        self.model.body_margin[ids] = np.maximum(distance, self._body_margin0[ids])

    def excuse(
        self, pairs: Iterable[tuple[int, int]] = (), within: Iterable[float] | None = None
    ) -> ContactChecker:
        """Replace the excused geom pairs (ids, either order; e.g. :meth:`geom_pairs`):
        each counts only nearer than its ``within`` [m] (default 0: where they touch),
        not within a margin (:meth:`keep_clear_of`, :meth:`keep_clear`). Geoms, not
        bodies: a hand near a drawer's side wall where a motion ends is no reason to let
        it graze the drawer's front on the way."""
        self._excused[:] = np.nan
        pairs = list(pairs)
        floors = [0.0] * len(pairs) if within is None else list(within)
        if len(floors) != len(pairs):
            raise ConfigError(f"excuse: {len(pairs)} pairs but {len(floors)} distances")
        for (a, b), f in zip(pairs, floors, strict=True):
            self._excused[a, b] = self._excused[b, a] = max(float(f), 0.0)
        return self

    def _detach(self) -> None:
        if self._attached is None:
            return
        bid = self._attached[0]
        geoms = self.geom_body == bid
        self.model.geom_margin[geoms] = self._margin0[geoms]
        self.model.body_margin[bid] = self._body_margin0[bid]
        self.model.geom_contype[geoms] = self._env_bits[geoms, 0]
        self.model.geom_conaffinity[geoms] = self._env_bits[geoms, 1]
        self._counts[bid] = self.robot[bid]
        self._attached = None

    @property
    def attached_body(self) -> int:
        """Id of the attached body (-1 if none)."""
        return -1 if self._attached is None else self._attached[0]

    # -- checks ------------------------------------------------------------------------
    def _place_attached(self) -> None:
        m, d = self.model, self.data
        _, adr, T_gb = self._attached  # type: ignore[misc]
        T = np.eye(4)
        T[:3, :3] = d.site_xmat[self._site].reshape(3, 3)
        T[:3, 3] = d.site_xpos[self._site]
        T = T @ T_gb
        d.qpos[adr : adr + 3] = T[:3, 3]
        d.qpos[adr + 3 : adr + 7] = quat_of(T[:3, :3])
        mujoco.mj_kinematics(m, d)

    def _collide(self, q: np.ndarray) -> int:
        """Pose the scratch data at ``q`` and find its contacts; their number."""
        m, d = self.model, self.data
        d.qpos[self.qadr] = q
        mujoco.mj_kinematics(m, d)
        if self._attached is not None:
            self._place_attached()
        mujoco.mj_collision(m, d)
        return d.ncon

    def pairs(self, q: np.ndarray) -> np.ndarray:
        """Forbidden contacts at ``q`` (values of :attr:`joints`): (k, 2) body ids."""
        if self._collide(q) == 0:
            return np.zeros((0, 2), dtype=int)
        return self._forbidden()

    def _forbidden(self, with_geoms: bool = False) -> np.ndarray:
        bad = self._forbidden_mask()
        if with_geoms:
            return self.data.contact.geom[bad]
        return self.geom_body[self.data.contact.geom][bad]

    def _forbidden_mask(self) -> np.ndarray:
        """Which of the scratch data's contacts are forbidden, (ncon,) bool."""
        bodies = self.geom_body[self.data.contact.geom]
        a, b = bodies[:, 0], bodies[:, 1]
        # (The model's bits leave out the scene's contacts among themselves, except
        # an explicit <pair>: the robot test stays.)
        bad = (self._counts[a] | self._counts[b]) & ~self._allowed[a, b]
        geoms = self.data.contact.geom
        floor = self._excused[geoms[:, 0], geoms[:, 1]]
        excused = ~np.isnan(floor)
        if excused.any():  # within a margin but no nearer than excused
            bad &= ~(excused & (self.data.contact.dist >= np.nan_to_num(floor)))
        return bad

    def geom_pairs(self, q: np.ndarray) -> np.ndarray:
        """Forbidden contacts at ``q`` as geom ids, (k, 2)."""
        return self.geom_gaps(q)[0]

    def geom_gaps(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forbidden contacts at ``q``: geom ids (k, 2) and their distances (k,) [m]
        (negative: penetrating; a pair may come more than once)."""
        if self._collide(q) == 0:
            return np.zeros((0, 2), dtype=int), np.zeros(0)
        bad = self._forbidden_mask()
        return self.data.contact.geom[bad], self.data.contact.dist[bad]

    def hand_in_scene(self, pairs: np.ndarray) -> bool:
        """Some pair of ``pairs`` (k, 2) (:meth:`pairs`) is the hand against the scene:
        a body that moves with the gripper whatever the arm's joints (the fingers, and
        up the chain to the first jointed body, the wrist's roll link) or the attached
        body. Such a contact depends on where the hand is, not on how the arm or the
        base got it there."""
        a, b = pairs[:, 0], pairs[:, 1]
        hand = self._hand_rigid.copy()
        if self._attached is not None:
            hand[self._attached[0]] = True
        scene = ~self._counts
        return bool(np.any((hand[a] & scene[b]) | (hand[b] & scene[a])))

    def hand_depth(self) -> float:
        """How deep [m] the hand (as in :meth:`hand_in_scene`) is in the scene at the
        configuration of the last check (:meth:`free`, :meth:`pairs`): the deepest
        forbidden contact between them (0 if none; MuJoCo's ``-dist``)."""
        d = self.data
        if d.ncon == 0:
            return 0.0
        bodies = self.geom_body[d.contact.geom]
        a, b = bodies[:, 0], bodies[:, 1]
        hand = self._hand_rigid.copy()
        if self._attached is not None:
            hand[self._attached[0]] = True
        scene = ~self._counts
        bad = ((hand[a] & scene[b]) | (hand[b] & scene[a])) & ~self._allowed[a, b]
        return float(max(0.0, np.max(-d.contact.dist[bad], initial=0.0)))

    def contacts(self, q: np.ndarray) -> list[str]:
        """Forbidden contacts at ``q`` as sorted ``body1/body2`` names ([] if none)."""
        m = self.model
        return sorted({f"{m.body(a).name}/{m.body(b).name}" for a, b in self.pairs(q).tolist()})

    def free(self, q: np.ndarray) -> bool:
        """No forbidden contact at ``q``."""
        return self._collide(q) == 0 or len(self._forbidden()) == 0

    def segment(self, qa: np.ndarray, qb: np.ndarray) -> list[str]:
        """Forbidden contacts anywhere on the straight joint-space segment ``qa -> qb``
        (checked every :data:`CHECK_STEP`); [] if free."""
        n = max(1, math.ceil(float(np.max(np.abs(qb - qa))) / CHECK_STEP))
        for k in range(n + 1):
            q = qa + (k / n) * (qb - qa)
            if not self.free(q):
                return self.contacts(q)
        return []

    def path(self, qs: Sequence[np.ndarray]) -> list[str]:
        """Forbidden contacts anywhere along the joint-space polyline ``qs``."""
        if len(qs) == 1:
            return [] if self.free(qs[0]) else self.contacts(qs[0])
        for qa, qb in itertools.pairwise(qs):
            hits = self.segment(qa, qb)
            if hits:
                return hits
        return []


def _checker_bits(m: mujoco.MjModel, robot_geom: np.ndarray) -> np.ndarray:
    """Set the checker's collision bits in ``m`` (:data:`ENV_BIT`, :data:`ROBOT_BIT`)
    and return the scene geoms' bits, (ngeom, 2) (contype, conaffinity; zeros for the
    robot's), to restore a body when it is detached.

    A scene geom keeps colliding if the simulation lets it touch one of the robot's
    geoms; a robot geom if it collides with anything; the rest collide with nothing.
    ``robot_geom`` (ngeom,) marks the robot's geoms.
    """
    ct, ca = np.asarray(m.geom_contype).copy(), np.asarray(m.geom_conaffinity).copy()
    r_ct = np.bitwise_or.reduce(ct[robot_geom]) if robot_geom.any() else 0
    r_ca = np.bitwise_or.reduce(ca[robot_geom]) if robot_geom.any() else 0
    touches_robot = ~robot_geom & (((ct & r_ca) != 0) | ((ca & r_ct) != 0))
    robot = robot_geom & ((ct != 0) | (ca != 0))
    env = np.zeros((m.ngeom, 2), dtype=ct.dtype)
    env[touches_robot] = (ENV_BIT, 0)
    m.geom_contype[:] = np.where(robot, ROBOT_BIT, env[:, 0])
    m.geom_conaffinity[:] = np.where(robot, ENV_BIT | ROBOT_BIT, env[:, 1])
    return env
