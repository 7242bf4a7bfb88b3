"""Labelled RGB-D of articulated cabinets, seen by the Fetch's head camera: perception's
training and test data.

One *view* is: the scene of a cabinet (generated from a seed, or any PartNet-Mobility
folder, through the same loader) with its movable parts opened at random, the robot's
base placed at random in front of it, and the head turned to look at the cabinet. Per
view it stores

* ``rgb`` (H, W, 3) uint8, ``depth`` (H, W) float32 [m] (distance along the optical
  axis; MuJoCo's far plane where nothing is hit);
* ``handle_map`` (H, W) bool: the pixels of handle geometry (bars, their posts,
  knobs; geoms named ``handle*``), where a pull grasps (the pull-affordance labels);
* ``part_map`` (H, W) int16: ``-1`` not the cabinet, ``0`` the carcass (root link and
  every link rigidly fixed to it through a joint without a label), ``k >= 1`` the part
  of the k-th labelled joint (see below);
* per part k (arrays of length P, index k - 1): ``joint_type`` (0 fixed, 1 prismatic,
  2 revolute; continuous joints count as revolute), ``axis_cam`` (P, 3) unit joint axis
  (zeros for fixed parts) and ``origin_cam`` (P, 3) [m] joint origin in the *camera*
  frame: the URDF joint origin, i.e. where the joint frame sits in its (current) parent
  at q = 0, so a drawer's origin does not move as it slides and a hinge's is on its axis
  (fixed parts: the link frame's origin); ``q`` (P,)
  joint position [m or rad], ``lower``/``upper`` (P,) limits,
  ``pixels`` (P,) visible pixel count, ``semantic`` (P,) the semantics.txt label;
* ``T_world_camera`` (4, 4) and ``fovy`` [rad], so depth deprojects with
  :func:`strug_manip.world.sim.depth_to_points`; ``T_camera_cabinet`` (4, 4).

The camera frame is MuJoCo's: the camera looks along its -z, +x right, +y up.

Labelled joints are every joint of the object except the one joining the root link to
the carcass link (PartNet's ``joint_0``, fixed): fixed panels and shelves are parts too
(joint type 0), so a network learns to tell a fixed front from a movable one.

Splits: the generator's seeds 0..9,999 are reserved for evaluation and the rest of the
code base (scenes, tests, Table I); training data comes from seeds >= 100,000, so
evaluation cabinets are never seen in training (:data:`TRAIN_SEED_START`).

Data is written one ``.npz`` shard per cabinet seed (``views`` views each), atomically
(a temporary file renamed), so an interrupted run resumes where it stopped without
repeating or losing a finished cabinet.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from planners.errors import ConfigError, check_positive_int
from strug_manip.robot.fetch import BASE_JOINTS, HEAD_CAMERA, HEAD_JOINTS, TORSO_JOINT
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import CameraFrame, ManipulationWorld
from strug_manip.world.views import aim_head, look_poses, place_robot

#: First generator seed of the training split; seeds below 10,000 are evaluation's.
TRAIN_SEED_START = 100_000
#: Joint type codes of ``joint_type``.
JOINT_TYPES = ("fixed", "prismatic", "revolute")
#: Views per cabinet (default).
DEFAULT_VIEWS = 8


@dataclass(frozen=True)
class ViewRanges:
    """Where the robot stands and how far the parts are open, per view (uniform draws).

    Attributes:
        distance: gap between the robot's origin and the cabinet front [m].
        lateral: sideways offset of the robot from the cabinet's centre line [m].
        yaw: base heading error from facing the cabinet [rad].
        torso: torso lift [m] (the joint's range is 0..0.386).
        open_prob: probability that a movable part is opened at all.
        open_frac: opening as a fraction of the joint's range, when opened.
        empty_prob: probability that a view shows the scene without its cabinet (the
            cabinet moved far away before rendering; every pixel is labelled -1), so a
            network learns that an empty table is no cabinet.
        aim_jitter: the head aims this far [m] (uniform per axis) off the cabinet's
            centre, so the cabinet is not always at the image centre.
    """

    distance: tuple[float, float] = (0.6, 1.6)
    lateral: tuple[float, float] = (-0.4, 0.4)
    yaw: tuple[float, float] = (-0.3, 0.3)
    torso: tuple[float, float] = (0.0, 0.38)
    open_prob: float = 0.5
    open_frac: tuple[float, float] = (0.1, 1.0)
    empty_prob: float = 0.0
    aim_jitter: float = 0.1

    def __post_init__(self) -> None:
        for name in ("distance", "lateral", "yaw", "torso", "open_frac"):
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
                raise ConfigError(f"ViewRanges.{name} must be (low, high) with low <= high")
        if self.distance[0] <= 0.0:
            raise ConfigError(f"ViewRanges.distance must be > 0 m, got {self.distance}")
        if not (math.isfinite(self.aim_jitter) and self.aim_jitter >= 0.0):
            raise ConfigError(f"ViewRanges.aim_jitter must be >= 0 m, got {self.aim_jitter}")
        if not 0.0 <= self.empty_prob <= 1.0:
            raise ConfigError(f"ViewRanges.empty_prob must be in [0, 1], got {self.empty_prob}")
        if not 0.0 <= self.open_prob <= 1.0:
            raise ConfigError(f"ViewRanges.open_prob must be in [0, 1], got {self.open_prob}")
        if not 0.0 <= self.open_frac[0] <= self.open_frac[1] <= 1.0:
            raise ConfigError(f"ViewRanges.open_frac must lie in [0, 1], got {self.open_frac}")


@dataclass(frozen=True)
class LabelledView:
    """One rendered, labelled view (fields as in the module docstring)."""

    rgb: np.ndarray
    depth: np.ndarray
    part_map: np.ndarray
    handle_map: np.ndarray
    joint_type: np.ndarray
    axis_cam: np.ndarray
    origin_cam: np.ndarray
    q: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    pixels: np.ndarray
    semantic: tuple[str, ...]
    joint_names: tuple[str, ...]
    T_world_camera: np.ndarray
    T_camera_cabinet: np.ndarray
    fovy: float


class CabinetViewer:
    """Renders labelled views of one scene's cabinet from the robot's head camera.

    Args:
        world: the scene (its cabinet is the one labelled).
        ranges: view distribution.
    """

    def __init__(self, world: ManipulationWorld, ranges: ViewRanges | None = None) -> None:
        self.world = world
        self.ranges = ranges or ViewRanges()
        m, obj, pre = world.model, world.scene.cabinet, world.scene.cabinet_prefix
        carcass = {obj.root}
        self.joints = []
        for j in obj.joints:
            if j.parent == obj.root and j.type == "fixed" and len(carcass) == 1:
                carcass.add(j.child)  # PartNet's joint_0: root -> carcass link
            else:
                self.joints.append(j)
        # Every link belongs to the part of its nearest labelled joint above it.
        part_of_link = {link: 0 for link in carcass}
        for k, j in enumerate(self.joints, start=1):
            part_of_link[j.child] = k
        for j in obj.joints:  # tree order: parents come first
            if j.child not in part_of_link:
                part_of_link[j.child] = part_of_link.get(j.parent, 0)
        self._geom_part = np.full(m.ngeom + 1, -1, dtype=np.int16)  # last slot: background
        self._geom_handle = np.zeros(m.ngeom + 1, dtype=bool)
        for g in range(m.ngeom):
            name = m.body(m.geom_bodyid[g]).name
            if name.startswith(pre) and name[len(pre) :] in part_of_link:
                self._geom_part[g] = part_of_link[name[len(pre) :]]
                self._geom_handle[g] = m.geom(g).name.rsplit("/", 1)[-1].startswith("handle")
        self._root_body = m.body(pre + obj.root).id
        self._jid = {j.name: m.joint(pre + j.name).id for j in self.joints if j.movable}
        self._qadr = {name: m.jnt_qposadr[jid] for name, jid in self._jid.items()}
        # Fixed links may be merged into their parent body by the loader: fall back to it.
        self._body = {}
        for j in self.joints:
            bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, pre + j.child)
            self._body[j.child] = bid if bid >= 0 else self._root_body
        self._robot_qadr = {
            n: m.jnt_qposadr[m.joint(n).id] for n in (*BASE_JOINTS, TORSO_JOINT, *HEAD_JOINTS)
        }

    # --- sampling ------------------------------------------------------------------------
    def _open_parts(self, rng: np.random.Generator) -> dict[str, float]:
        r, out = self.ranges, {}
        for j in self.joints:
            if not j.movable:
                continue
            lo, hi = (j.lower, j.upper) if j.type != "continuous" else (0.0, math.pi)
            q = 0.0
            if rng.random() < r.open_prob:
                q = lo + (hi - lo) * float(rng.uniform(*r.open_frac))
            out[self.world.scene.cabinet_prefix + j.name] = q
        return out

    def _place_robot(self, rng: np.random.Generator) -> None:
        r, w = self.ranges, self.world
        d, adr = w.data, self._robot_qadr
        front = w.config.cabinet_distance
        x = front - float(rng.uniform(*r.distance))
        y = w.config.cabinet_lateral + float(rng.uniform(*r.lateral))
        d.qpos[adr[BASE_JOINTS[0]]] = x
        d.qpos[adr[BASE_JOINTS[1]]] = y
        d.qpos[adr[BASE_JOINTS[2]]] = math.atan2(w.config.cabinet_lateral - y, front - x) + float(
            rng.uniform(*r.yaw)
        )
        d.qpos[adr[TORSO_JOINT]] = float(rng.uniform(*r.torso))
        jitter = rng.uniform(-r.aim_jitter, r.aim_jitter, size=3)
        aim_head(self.world, self._cabinet_centre() + jitter)

    def _cabinet_centre(self) -> np.ndarray:
        d, obj = self.world.data, self.world.scene.cabinet
        R = d.xmat[self._root_body].reshape(3, 3)
        return R @ obj.bounds.mean(axis=0) + d.xpos[self._root_body]

    # --- rendering ---------------------------------------------------------------------
    def view(self, rng: np.random.Generator) -> LabelledView:
        """A new random view (parts opened, robot placed, head aimed) and its labels."""
        w = self.world
        w.reset(self._open_parts(rng))
        self._place_robot(rng)
        if rng.random() < self.ranges.empty_prob:
            return self._empty_view()
        return self.label(w.render(HEAD_CAMERA))

    def look_around(self, rng: np.random.Generator, k: int = 4) -> list[LabelledView]:
        """One cabinet state (parts opened at random, as :meth:`view` does), seen from
        the robot's ``k`` standard head poses (:func:`strug_manip.world.views.look_poses`):
        what the robot perceives before its first skill."""
        w = self.world
        w.reset(self._open_parts(rng))
        out = []
        for pose in look_poses(w, k):
            place_robot(w, pose)
            out.append(self.label(w.render(HEAD_CAMERA)))
        return out

    def _empty_view(self) -> LabelledView:
        """The same head pose with the cabinet moved 100 m away (an empty table)."""
        m, d = self.world.model, self.world.data
        adr = m.jnt_qposadr[m.joint(self.world.scene.cabinet_prefix + "free").id]
        d.qpos[adr : adr + 2] += 100.0
        mujoco.mj_forward(m, d)
        try:
            return self.label(self.world.render(HEAD_CAMERA))
        finally:
            d.qpos[adr : adr + 2] -= 100.0
            mujoco.mj_forward(m, d)

    def label(self, frame: CameraFrame) -> LabelledView:
        """The labels of ``frame``, rendered from the world's current state."""
        d = self.world.data
        seg = np.where(frame.segmentation < 0, self._geom_part.size - 1, frame.segmentation)
        part_map = self._geom_part[seg]
        handle_map = self._geom_handle[seg]
        T_cw = np.linalg.inv(frame.T_world_camera)
        T_world_cab = np.eye(4)
        T_world_cab[:3, :3] = d.xmat[self._root_body].reshape(3, 3)
        T_world_cab[:3, 3] = d.xpos[self._root_body]
        T_cam_cab = T_cw @ T_world_cab
        n = len(self.joints)
        axis, origin = np.zeros((n, 3)), np.zeros((n, 3))
        q, lower, upper = np.zeros(n), np.zeros(n), np.zeros(n)
        jtype = np.zeros(n, dtype=np.int8)
        R_cw, t_cw = T_cw[:3, :3], T_cw[:3, 3]
        for k, j in enumerate(self.joints):
            jtype[k] = {"fixed": 0, "prismatic": 1}.get(j.type, 2)
            if j.movable:
                # MuJoCo's anchor (placed before the joint's own motion) and axis, with
                # the parents at their current configuration: right also for a joint
                # below another movable one (PartNet has such chains).
                jid = self._jid[j.name]
                origin[k] = R_cw @ d.xanchor[jid] + t_cw
                axis[k] = R_cw @ d.xaxis[jid]
                q[k] = float(d.qpos[self._qadr[j.name]])
                lower[k], upper[k] = j.lower, j.upper
            else:  # a fixed part: its link frame's origin
                origin[k] = R_cw @ d.xpos[self._body[j.child]] + t_cw
        counts = np.bincount(part_map.reshape(-1).astype(np.int64) + 1, minlength=n + 2)
        return LabelledView(
            rgb=frame.rgb,
            depth=frame.depth.astype(np.float32),
            part_map=part_map,
            handle_map=handle_map,
            joint_type=jtype,
            axis_cam=axis,
            origin_cam=origin,
            q=q,
            lower=lower,
            upper=upper,
            pixels=counts[2 : n + 2].astype(np.int64),
            semantic=tuple(j.semantic for j in self.joints),
            joint_names=tuple(j.name for j in self.joints),
            T_world_camera=frame.T_world_camera,
            T_camera_cabinet=T_cam_cab,
            fovy=frame.fovy,
        )


def render_cabinet(
    seed: int,
    views: int = DEFAULT_VIEWS,
    ranges: ViewRanges | None = None,
    config: SceneConfig | None = None,
) -> list[LabelledView]:
    """``views`` labelled views of the cabinet generated from ``seed``.

    The same seed gives the same views, bit for bit (one ``np.random.Generator`` seeded
    with ``seed`` draws every view).
    """
    check_positive_int("views", views)
    world = ManipulationWorld(dataclasses.replace(config or SceneConfig(), cabinet_seed=int(seed)))
    try:
        viewer = CabinetViewer(world, ranges)
        rng = np.random.default_rng([int(seed), 0x5EED])
        return [viewer.view(rng) for _ in range(views)]
    finally:
        world.close()


def render_episode(
    seed: int,
    views: int = 4,
    ranges: ViewRanges | None = None,
    config: SceneConfig | None = None,
) -> list[LabelledView]:
    """The cabinet of ``seed`` in one random state, from the ``views`` standard head
    poses (:meth:`CabinetViewer.look_around`); the same seed gives the same views."""
    world = ManipulationWorld(dataclasses.replace(config or SceneConfig(), cabinet_seed=int(seed)))
    try:
        viewer = CabinetViewer(world, ranges)
        return viewer.look_around(np.random.default_rng([int(seed), 0xE715]), views)
    finally:
        world.close()


def cabinet_style(seed: int, furniture: float) -> str:
    """The generator style of training cabinet ``seed`` when a share ``furniture`` in
    [0, 1] of them is drawn in the furniture style (one draw per seed, so a resumed
    render and a re-render agree)."""
    if not 0.0 <= furniture <= 1.0:
        raise ConfigError(f"the furniture share must be in [0, 1], got {furniture!r}")
    draw = np.random.default_rng([int(seed), 0xF0C]).random()
    return "furniture" if draw < furniture else "plain"


def shard_path(out: Path, seed: int) -> Path:
    """Where the views of cabinet ``seed`` are stored."""
    return Path(out) / f"cabinet_{int(seed):06d}.npz"


def save_views(path: Path, views: Sequence[LabelledView]) -> None:
    """Write ``views`` to ``path`` atomically (stacked arrays, compressed)."""
    if not views:
        raise ConfigError("no views to save")
    first = views[0]
    arrays = {
        name: np.stack([getattr(v, name) for v in views])
        for name in (
            "rgb", "depth", "part_map", "handle_map", "joint_type", "axis_cam", "origin_cam", "q",
            "lower", "upper", "pixels", "T_world_camera", "T_camera_cabinet",
        )
    }  # fmt: skip
    arrays["fovy"] = np.array([v.fovy for v in views])
    arrays["semantic"] = np.array(first.semantic, dtype=str)
    arrays["joint_names"] = np.array(first.joint_names, dtype=str)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    with tmp.open("wb") as fh:
        np.savez_compressed(fh, **arrays)
        fh.flush()
        os.fsync(fh.fileno())
    tmp.replace(path)


def load_views(path: Path) -> dict[str, np.ndarray]:
    """The arrays of one shard (leading axis: view), as written by :func:`save_views`."""
    with np.load(path) as data:
        return {k: data[k] for k in data.files}
