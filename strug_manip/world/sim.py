"""Simulate and sense the manipulation scene.

:class:`ManipulationWorld` resets the scene (robot at home, cabinet parts at given
joint positions), steps MuJoCo, reads every part's joint position, the cabinet base's
displacement and the object's pose, and renders RGB, depth [m] and segmentation from
the robot's head camera; :func:`depth_to_points` deprojects a depth image to a
world-frame point cloud.

Camera convention (MuJoCo's): the camera looks along its -z axis, +x to the right of
the image, +y up. A pixel (u, v) (column, row from the top-left) at depth d (distance
along the optical axis) sits at ``((u + 0.5 - W/2) d / f, -(v + 0.5 - H/2) d / f, -d)``
in the camera frame, with ``f = (H / 2) / tan(fovy / 2)`` [px].
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import mujoco
import numpy as np

from planners.errors import ConfigError, UnknownNameError
from strug_manip.geometry import quat_of
from strug_manip.objects import CabinetSpec
from strug_manip.robot.fetch import GRIPPER_OPEN
from strug_manip.world.floating_gripper import PARK, SLIDES
from strug_manip.world.rendering import RenderContext
from strug_manip.world.scene import SceneConfig, SceneModel, build_scene

#: The graspable object's free joint (its pose is observed, not believed).
OBJECT_JOINT = "object/free"
#: Depths at or beyond this are background (the renderer's far plane) [m].
MAX_DEPTH = 10.0
#: What a snapshot holds: MuJoCo's full integration state (time, qpos, qvel, act,
#: warm start, controls, applied forces, mocap poses, equality activations).
_STATE = mujoco.mjtState.mjSTATE_INTEGRATION


@dataclass(frozen=True, eq=False)
class WorldState:
    """A :meth:`ManipulationWorld.snapshot`: compared and hashed by value, so it can key
    a cache.

    Attributes:
        physics: MuJoCo's integration state (``mj_getState``), shape (n,).
        cabinet_start: where the cabinet base stood at the episode's reset, (3,) [m]
            (what :meth:`ManipulationWorld.cabinet_displacement` measures from).
    """

    physics: np.ndarray
    cabinet_start: np.ndarray

    @property
    def key(self) -> bytes:
        """The state's bytes (equal states, equal keys)."""
        return self.physics.tobytes() + self.cabinet_start.tobytes()

    def __eq__(self, other: object) -> bool:
        return isinstance(other, WorldState) and self.key == other.key

    def __hash__(self) -> int:
        return hash(self.key)


@dataclass(frozen=True)
class CameraFrame:
    """One RGB-D frame.

    Attributes:
        rgb: colour, shape (H, W, 3), uint8.
        depth: distance along the optical axis [m], shape (H, W), float32.
        segmentation: MuJoCo geom id per pixel (-1: background), shape (H, W), int32.
        T_world_camera: camera pose, 4x4 (camera looks along its -z).
        fovy: vertical field of view [rad].
    """

    rgb: np.ndarray
    depth: np.ndarray
    segmentation: np.ndarray
    T_world_camera: np.ndarray
    fovy: float


def _pose(xmat: np.ndarray, xpos: np.ndarray) -> np.ndarray:
    """4x4 pose from MuJoCo's flat (9,) rotation and (3,) position."""
    T = np.eye(4)
    T[:3, :3] = np.asarray(xmat).reshape(3, 3)
    T[:3, 3] = xpos
    return T


def depth_to_points(
    depth: np.ndarray, T_world_camera: np.ndarray, fovy: float, max_depth: float = MAX_DEPTH
) -> tuple[np.ndarray, np.ndarray]:
    """World-frame points of a depth image.

    Args:
        depth: (H, W) depth along the optical axis [m].
        T_world_camera: 4x4 camera pose (MuJoCo convention, looking along -z).
        fovy: vertical field of view [rad].
        max_depth: pixels at or beyond this depth (background) are dropped [m].

    Returns:
        ``(points (N, 3) [m], pixel indices (N,) into the flattened image)``.
    """
    h, w = depth.shape
    f = 0.5 * h / math.tan(0.5 * fovy)
    flat = depth.reshape(-1).astype(np.float64)
    keep = np.flatnonzero((flat > 0) & (flat < max_depth))
    v, u = np.divmod(keep, w)
    d = flat[keep]
    p_cam = np.stack([(u + 0.5 - 0.5 * w) * d / f, -(v + 0.5 - 0.5 * h) * d / f, -d], axis=1)
    return p_cam @ T_world_camera[:3, :3].T + T_world_camera[:3, 3], keep


#: The fingers' servo (on their tendon): commanded open or squeezing, never "held".
FINGER_SERVO = "gripper"


class ManipulationWorld:
    """The scene, with reset, stepping, state read-out and rendering.

    Args:
        config: what to build (default: the built-in scene, cabinet seed 3); built in
            memory (:func:`~strug_manip.world.scene.build_scene`).
        render_context: render on this shared OpenGL context (worlds rendered by turns,
            e.g. an episode's belief particles); default: a context of its own.
    """

    def __init__(
        self, config: SceneConfig | None = None, render_context: RenderContext | None = None
    ) -> None:
        self.config = config or SceneConfig()
        self._render_context = render_context
        self.scene: SceneModel = build_scene(self.config)
        self.model = self.scene.model
        self.data = mujoco.MjData(self.model)
        m = self.model
        pre = self.scene.cabinet_prefix
        self.part_joints = [
            m.joint(j).name for j in range(m.njnt)
            if m.joint(j).name.startswith(pre) and m.jnt_type[j] != mujoco.mjtJoint.mjJNT_FREE
        ]  # fmt: skip
        #: The Fetch's joints (base, torso, arm, head, fingers), by name.
        self.robot_joints: list[str] = list(self.scene.home_qpos)
        self._cabinet_body = m.body(pre + self.scene.cabinet.root).id
        self._object_body = m.body("object").id
        self._cabinet_qpos = self.cabinet_qpos_indices()
        self._renderer: mujoco.Renderer | None = None
        self.reset()

    @classmethod
    def from_cabinet_spec(
        cls,
        spec: CabinetSpec,
        config: SceneConfig | None = None,
        render_context: RenderContext | None = None,
    ) -> ManipulationWorld:
        """The scene of ``config`` (default: the built-in one) with the cabinet ``spec``
        instead of a generated one, e.g. a *planning world* for a believed cabinet
        (a belief particle: see :func:`strug_manip.objects.hypotheses.believed_spec`).

        Raises:
            ConfigError: ``spec`` is not a :class:`CabinetSpec`.
        """
        base = config or SceneConfig()
        # The spec replaces the config's cabinet, generated or loaded from a folder (a
        # belief particle of a real object's scene).
        return cls(
            dataclasses.replace(base, cabinet_spec=spec, cabinet_folder=None), render_context
        )

    # --- state -------------------------------------------------------------------------
    def reset(self, part_positions: dict[str, float] | None = None) -> None:
        """Robot at home, object on the table, cabinet at rest with ``part_positions``."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        for name, q in self.scene.home_qpos.items():
            d.qpos[m.jnt_qposadr[m.joint(name).id]] = q
        for name, q in (part_positions or {}).items():
            self._set_joint(name, q)
        if self.config.robot == "gripper":
            adr = [m.jnt_qposadr[m.joint(j).id] for j in SLIDES]
            d.qpos[adr] = PARK
        self.hold_position()
        self._fill_gripper_ctrl()
        mujoco.mj_forward(m, d)
        self._cabinet_start = d.xpos[self._cabinet_body].copy()

    def set_parts(self, part_positions: dict[str, float]) -> None:
        """Put cabinet part joints at ``part_positions`` (by name, [m or rad]), at rest,
        the rest of the state as it is; then update the kinematics.

        Raises:
            UnknownNameError: a name is not a cabinet joint (lists them).
        """
        m, d = self.model, self.data
        for name, q in part_positions.items():
            self._set_joint(name, q)
            full = name if name in self.part_joints else self.scene.cabinet_prefix + name
            d.qvel[m.jnt_dofadr[m.joint(full).id]] = 0.0
        mujoco.mj_forward(m, d)

    def snapshot(self) -> WorldState:
        """The whole simulation state (physics, controls, time) and the episode's cabinet
        reference position, to :meth:`restore` later (e.g. a search's node state)."""
        m, d = self.model, self.data
        state = np.empty(mujoco.mj_stateSize(m, _STATE))
        mujoco.mj_getState(m, d, state, _STATE)
        return WorldState(state, self._cabinet_start.copy())

    def restore(self, state: WorldState) -> None:
        """Return to a :meth:`snapshot` of this world (or of a world of the same scene
        model) and update the kinematics.

        Raises:
            ConfigError: ``state`` is not a :class:`WorldState` of this model's size.
        """
        m, d = self.model, self.data
        n = mujoco.mj_stateSize(m, _STATE)
        if not isinstance(state, WorldState) or state.physics.shape != (n,):
            raise ConfigError(
                f"state must be a WorldState of this world (physics size {n}), got {state!r}"
            )
        mujoco.mj_setState(m, d, state.physics, _STATE)
        self._cabinet_start = state.cabinet_start.copy()
        mujoco.mj_forward(m, d)

    def hold_position(self) -> None:
        """Set every servo's target to where its joint is now (velocity targets 0), so
        the robot holds still."""
        m, d = self.model, self.data
        joint_trn = int(mujoco.mjtTrn.mjTRN_JOINT)
        ball = int(mujoco.mjtJoint.mjJNT_BALL)
        tendon_trn = int(mujoco.mjtTrn.mjTRN_TENDON)
        for a in range(m.nactuator):
            c = m.actuator_ctrladr[a]
            servo = m.actuator_biastype[a] != 0 and m.actuator(a).name != FINGER_SERVO
            if int(m.actuator_trntype[a]) == tendon_trn and servo:  # (the fingers: below)
                length = self._fixed_tendon_length(int(m.actuator_trnid[a, 0]))
                if length is not None:  # a servo on a combination of joints (the twin's)
                    d.ctrl[c : c + m.actuator_ctrlnum[a]] = 0.0
                    d.ctrl[c] = length
                continue
            if int(m.actuator_trntype[a]) != joint_trn or m.actuator_biastype[a] == 0:
                continue  # not a servo on a joint (e.g. the finger tendon: set below)
            jid = m.actuator_trnid[a, 0]
            q = m.jnt_qposadr[jid]
            n = 4 if int(m.jnt_type[jid]) == ball else 1
            d.ctrl[c : c + m.actuator_ctrlnum[a]] = 0.0
            d.ctrl[c : c + n] = d.qpos[q : q + n]

    def _fixed_tendon_length(self, tendon: int) -> float | None:
        """The length of a fixed tendon (a linear combination of joint positions) from
        ``qpos``; None for a spatial one."""
        m, d = self.model, self.data
        adr, num = m.tendon_adr[tendon], m.tendon_num[tendon]
        if np.any(m.wrap_type[adr : adr + num] != int(mujoco.mjtWrap.mjWRAP_JOINT)):
            return None
        q = d.qpos[m.jnt_qposadr[m.wrap_objid[adr : adr + num]]]
        return float(m.wrap_prm[adr : adr + num] @ q)

    def ctrl_index(self, actuator: str) -> int:
        """Index in ``data.ctrl`` of ``actuator``'s first control (MuJoCo 4 actuators may
        take several: a PID servo a position and a velocity target, an orientation servo
        a quaternion).

        Raises:
            UnknownNameError: no actuator of that name.
        """
        aid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_ACTUATOR, actuator)
        if aid < 0:
            names = [self.model.actuator(i).name for i in range(self.model.nactuator)]
            raise UnknownNameError("actuator", actuator, names)
        return int(self.model.actuator_ctrladr[aid])

    def _fill_gripper_ctrl(self) -> None:
        m = self.model
        aid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, FINGER_SERVO)
        if aid >= 0:
            self.data.ctrl[m.actuator_ctrladr[aid]] = GRIPPER_OPEN

    def _set_joint(self, name: str, q: float) -> None:
        m = self.model
        full = name if name in self.part_joints else self.scene.cabinet_prefix + name
        if full not in self.part_joints:
            raise UnknownNameError("cabinet joint", name, self.part_joints)
        self.data.qpos[m.jnt_qposadr[m.joint(full).id]] = q

    def copy_robot_state(self, source: ManipulationWorld, include_object: bool = True) -> None:
        """Copy the robot's joint positions [m, rad] and velocities [m/s, rad/s] (and the
        object's pose and twist if ``include_object``) from ``source``, matching joints
        by NAME (the two models may order their coordinates differently); the cabinet
        (base pose and parts) keeps this world's state. Then update the kinematics.

        Raises:
            UnknownNameError: a robot joint of ``source`` is missing here.
        """
        names = list(source.robot_joints) + ([OBJECT_JOINT] if include_object else [])
        self.copy_joints(source, names)

    def copy_joints(self, source: ManipulationWorld, names: list[str]) -> None:
        """Copy the positions and velocities of the joints ``names`` from ``source`` by
        name (a joint ``source`` lacks is skipped), then update the kinematics; e.g. the
        cabinet's free joint ``cabinet/free`` into a planning world, where the real
        cabinet has been dragged to.

        Raises:
            UnknownNameError: a joint is missing here.
        """
        if source is self:
            return
        dst_m, dst_d = self.model, self.data
        src_m, src_d = source.model, source.data
        all_names = [dst_m.joint(j).name for j in range(dst_m.njnt)]
        for name in names:
            jd = mujoco.mj_name2id(dst_m, mujoco.mjtObj.mjOBJ_JOINT, name)
            js = mujoco.mj_name2id(src_m, mujoco.mjtObj.mjOBJ_JOINT, name)
            if jd < 0:
                raise UnknownNameError("joint of the destination world", name, all_names)
            if js < 0:
                continue
            nq = {0: 7, 1: 4}.get(int(src_m.jnt_type[js]), 1)  # free, ball, slide/hinge
            nv = {0: 6, 1: 3}.get(int(src_m.jnt_type[js]), 1)
            qa, qb = dst_m.jnt_qposadr[jd], src_m.jnt_qposadr[js]
            va, vb = dst_m.jnt_dofadr[jd], src_m.jnt_dofadr[js]
            dst_d.qpos[qa : qa + nq] = src_d.qpos[qb : qb + nq]
            dst_d.qvel[va : va + nv] = src_d.qvel[vb : vb + nv]
        mujoco.mj_kinematics(dst_m, dst_d)

    def robot_qpos(self) -> dict[str, float]:
        """Every robot joint's position [m or rad], by joint name."""
        m, d = self.model, self.data
        return {n: float(d.qpos[m.jnt_qposadr[m.joint(n).id]]) for n in self.robot_joints}

    def step(self, seconds: float) -> None:
        """Advance physics by ``seconds`` of simulated time (whole steps)."""
        if not seconds >= 0:
            raise ConfigError(f"seconds must be >= 0, got {seconds!r}")
        mujoco.mj_step(
            self.model, self.data, nstep=max(1, round(seconds / self.model.opt.timestep))
        )

    def cabinet_qpos_indices(self) -> np.ndarray:
        """Indices into ``qpos`` of the cabinet's coordinates: its free joint (7) and
        every part joint, (7 + n_parts,)."""
        m = self.model
        free = int(m.jnt_qposadr[m.joint(self.scene.cabinet_prefix + "free").id])
        parts = [int(m.jnt_qposadr[m.joint(n).id]) for n in self.part_joints]
        return np.array([*range(free, free + 7), *parts])

    def cabinet_key(self) -> bytes:
        """The cabinet's coordinates (base and parts) rounded to 1e-3 (mm, mrad), as
        bytes: equal keys, the same cabinet state to the millimetre (a cache key)."""
        return np.round(self.data.qpos[self._cabinet_qpos], 3).tobytes()

    def part_positions(self) -> dict[str, float]:
        """Every cabinet part joint's position [m or rad], by joint name."""
        m, d = self.model, self.data
        return {n: float(d.qpos[m.jnt_qposadr[m.joint(n).id]]) for n in self.part_joints}

    def part_units(self) -> dict[str, str]:
        """``"m"`` (prismatic) or ``"rad"`` (revolute) per cabinet part joint."""
        m = self.model
        slide = int(mujoco.mjtJoint.mjJNT_SLIDE)
        return {
            n: "m" if int(m.jnt_type[m.joint(n).id]) == slide else "rad" for n in self.part_joints
        }

    def cabinet_displacement_vector(self) -> np.ndarray:
        """Horizontal displacement (x, y) of the cabinet base since reset [m], (2,)."""
        return self.data.xpos[self._cabinet_body][:2] - self._cabinet_start[:2]

    def cabinet_displacement(self) -> float:
        """Horizontal distance the cabinet base moved since reset [m]."""
        return float(
            np.linalg.norm(self.data.xpos[self._cabinet_body][:2] - self._cabinet_start[:2])
        )

    @property
    def cabinet_root_body(self) -> int:
        """The id of the cabinet's base body (its parts are the bodies below it)."""
        return int(self._cabinet_body)

    def cabinet_pose(self) -> np.ndarray:
        """The cabinet frame now (its base's body pose), 4x4 (``scene.T_world_cabinet``
        is where it stood at reset)."""
        return _pose(self.data.xmat[self._cabinet_body], self.data.xpos[self._cabinet_body])

    def set_cabinet_pose(self, T_world_cabinet: np.ndarray) -> None:
        """Put the cabinet's base (its free joint) at ``T_world_cabinet`` (4, 4), at rest,
        its parts as they are; then update the kinematics."""
        self._set_free(self.scene.cabinet_prefix + "free", T_world_cabinet)

    def set_object_pose(self, T_world_object: np.ndarray) -> None:
        """Put the object at ``T_world_object`` (4, 4), at rest; then update the
        kinematics."""
        self._set_free(OBJECT_JOINT, T_world_object)

    def _set_free(self, joint: str, T: np.ndarray) -> None:
        m, d = self.model, self.data
        j = m.joint(joint).id
        a, v = m.jnt_qposadr[j], m.jnt_dofadr[j]
        T = np.asarray(T, dtype=float)
        d.qpos[a : a + 3] = T[:3, 3]
        d.qpos[a + 3 : a + 7] = quat_of(T[:3, :3])
        d.qvel[v : v + 6] = 0.0
        mujoco.mj_kinematics(m, d)

    def object_pose(self) -> np.ndarray:
        """``T_world_object``, 4x4."""
        return _pose(self.data.xmat[self._object_body], self.data.xpos[self._object_body])

    def body_pose(self, name: str) -> np.ndarray:
        """``T_world_body`` (4, 4) of a named body (as of the last kinematics update).

        Raises:
            UnknownNameError: no body of that name.
        """
        bid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, name)
        if bid < 0:
            names = [self.model.body(i).name for i in range(self.model.nbody)]
            raise UnknownNameError("body", name, names)
        return _pose(self.data.xmat[bid], self.data.xpos[bid])

    def site_pose(self, name: str) -> np.ndarray:
        """``T_world_site`` of a named site, 4x4."""
        sid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, name)
        if sid < 0:
            names = [self.model.site(i).name for i in range(self.model.nsite)]
            raise UnknownNameError("site", name, names)
        return _pose(self.data.site_xmat[sid], self.data.site_xpos[sid])

    # --- sensing -----------------------------------------------------------------------
    def _renderer_for(self) -> mujoco.Renderer:
        if self._renderer is None:
            h, w = self.config.height, self.config.width
            if self._render_context is not None:
                self._renderer = self._render_context.renderer(self.model, h, w)
            else:
                self._renderer = mujoco.Renderer(self.model, h, w)
        return self._renderer

    def camera_pose(self, camera: str) -> tuple[np.ndarray, float]:
        """``(T_world_camera 4x4, fovy [rad])`` of a named camera."""
        cid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
        if cid < 0:
            names = [self.model.camera(i).name for i in range(self.model.ncam)]
            raise UnknownNameError("camera", camera, names)
        T = _pose(self.data.cam_xmat[cid], self.data.cam_xpos[cid])
        return T, math.radians(float(self.model.cam_fovy[cid]))

    def render_rgb(
        self, camera: str = "head_camera", width: int | None = None, height: int | None = None
    ) -> np.ndarray:
        """Colour image (H, W, 3) uint8 (size: the config's unless given, e.g. for pictures)."""
        if width is None and height is None:
            r = self._renderer_for()
            r.update_scene(self.data, camera=camera)
            return r.render().copy()
        h, w = height or self.config.height, width or self.config.width
        vis = self.model.vis.global_
        if not (0 < w <= vis.offwidth and 0 < h <= vis.offheight):
            raise ConfigError(
                f"image size {w}x{h} must be within the offscreen buffer "
                f"{vis.offwidth}x{vis.offheight} px"
            )
        with mujoco.Renderer(self.model, h, w) as r:
            r.update_scene(self.data, camera=camera)
            return r.render().copy()

    def render_rgbd(self, camera: str = "head_camera") -> tuple[np.ndarray, np.ndarray]:
        """Colour (H, W, 3) uint8 and depth [m] (H, W) float32: what the robot's sensor gives."""
        r = self._renderer_for()
        r.update_scene(self.data, camera=camera)
        rgb = r.render().copy()
        r.enable_depth_rendering()
        depth = r.render().copy()
        r.disable_depth_rendering()
        return rgb, depth

    def render(self, camera: str = "head_camera", colour: bool = True) -> CameraFrame:
        """RGB, depth [m] and geom segmentation from ``camera``.

        ``colour=False`` skips the colour pass (about 45 % of the time) and leaves
        ``rgb`` empty, shape (0, 0, 3): for point clouds, which need depth and
        segmentation only (:meth:`point_cloud`)."""
        T, fovy = self.camera_pose(camera)
        r = self._renderer_for()
        r.update_scene(self.data, camera=camera)
        rgb = r.render().copy() if colour else np.zeros((0, 0, 3), dtype=np.uint8)
        r.enable_depth_rendering()
        depth = r.render().copy()
        r.disable_depth_rendering()
        r.enable_segmentation_rendering()
        seg = r.render()[:, :, 0].astype(np.int32)
        r.disable_segmentation_rendering()
        return CameraFrame(rgb, depth, seg, T, fovy)

    def point_cloud(self, frame: CameraFrame) -> tuple[np.ndarray, np.ndarray]:
        """World points (N, 3) [m] of ``frame`` and the geom id (N,) each one belongs to."""
        pts, idx = depth_to_points(frame.depth, frame.T_world_camera, frame.fovy)
        return pts, frame.segmentation.reshape(-1)[idx]

    def close(self) -> None:
        """Free the renderer."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
