"""Log a MuJoCo manipulation episode to rerun: the scene, body poses, camera frames and
believed joints; and a PNG strip of camera images for reports.

Everything goes to a caller-given ``rr.RecordingStream`` (never the global recording),
in the world frame (z up, [m]). Layout, under ``root`` (default ``world``):

* ``world/<body>/<geom>`` (static): every visual geom (group < 3, alpha > 0) in its
  body's frame: boxes as ``Boxes3D``, spheres and ellipsoids as ``Ellipsoids3D``,
  capsules as ``Capsules3D``, cylinders as ``Cylinders3D``, meshes (the Fetch's) as
  ``Mesh3D``, the floor plane as a large flat box; coloured like MuJoCo draws them;
* ``world/<body>``: the body's pose (``Transform3D``): static for bodies welded to the
  world, at the stream's current time for the others (:meth:`WorldLogger.log_pose`,
  :meth:`WorldLogger.log_replay`, which sets the ``sim_time`` timeline);
* :func:`log_camera`: ``<entity>`` (camera pose), ``<entity>/image`` (pinhole),
  ``<entity>/image/rgb``, ``<entity>/image/depth`` [m], ``<entity>_cloud`` (world
  points);
* :func:`log_joints`: one arrow per believed joint, darker for heavier weight.

Body and geom names are sanitised into entity-path parts (``cabinet/link_1`` becomes
``cabinet_link_1``: one level per body, every body's pose in the world frame).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import mujoco
import numpy as np
import pyarrow as pa
import rerun as rr

from planners.errors import ConfigError, check_positive_int
from strug_manip.geometry import mat_of
from strug_manip.world.sim import MAX_DEPTH  # background depths: logged as 0, "no depth"

if TYPE_CHECKING:
    from strug_manip.control.outcome import Outcome
    from strug_manip.objects.hypotheses import BelievedJoint
    from strug_manip.world.sim import CameraFrame, ManipulationWorld

#: Half extent of the floor box drawn for an infinite plane (MuJoCo size 0) [m].
FLOOR_HALF = 3.0
#: Thickness of the floor box (its top face is the plane) [m].
FLOOR_THICKNESS = 0.002
#: Colour ramp of :func:`log_joints`, light (weight 0) to dark (the heaviest), RGB.
LIGHT, DARK = np.array([198, 219, 239]), np.array([8, 48, 107])
#: Colour of a logged point cloud, RGB.
CLOUD = [240, 150, 20]
#: MuJoCo's default geom colour: a geom with a material and this rgba takes the
#: material's colour (``setMaterial`` in MuJoCo's visualiser).
_DEFAULT_RGBA = np.array([0.5, 0.5, 0.5, 1.0], dtype=np.float32)
_SOLID = rr.components.FillMode.Solid


def _part(name: str, fallback: str) -> str:
    """An entity-path part for a MuJoCo name (``fallback`` if it is empty)."""
    return re.sub(r"[^A-Za-z0-9_-]+", "_", name).strip("_") or fallback


def _unique(part: str, taken: set[str]) -> str:
    """``part``, or ``part_2``, ``part_3``, ... if it is taken; marks it taken."""
    out, k = part, 2
    while out in taken:
        out, k = f"{part}_{k}", k + 1
    taken.add(out)
    return out


def _xyzw(wxyz: np.ndarray) -> rr.Quaternion:
    """MuJoCo's (w, x, y, z) quaternion as rerun's."""
    return rr.Quaternion(xyzw=[wxyz[1], wxyz[2], wxyz[3], wxyz[0]])


def _rgba8(m: mujoco.MjModel, g: int) -> np.ndarray:
    """Geom ``g``'s colour as MuJoCo draws it (its rgba, or its material's if the rgba
    is the default), (4,) uint8."""
    rgba, mat = m.geom_rgba[g], int(m.geom_matid[g])
    if mat >= 0 and np.array_equal(rgba, _DEFAULT_RGBA):
        rgba = m.mat_rgba[mat]
    return np.round(np.clip(rgba, 0.0, 1.0) * 255).astype(np.uint8)


def _vertex_normals(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Unit vertex normals (V, 3) of a triangle mesh: area-weighted face normals summed
    at each vertex (rerun shades a mesh without normals flat-unlit)."""
    face_n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n = np.zeros_like(v)
    for k in range(3):
        np.add.at(n, f[:, k], face_n)
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.where(norm > 0, norm, 1.0)


def _geom_archetype(m: mujoco.MjModel, g: int, rgba: np.ndarray) -> rr.AsComponents | None:
    """Geom ``g`` as a rerun archetype in its body's frame (None: a type not drawn)."""
    T = mujoco.mjtGeom
    kind, size = int(m.geom_type[g]), m.geom_size[g]
    pos, wxyz = m.geom_pos[g], m.geom_quat[g]
    R = mat_of(wxyz)
    q = [_xyzw(wxyz)]
    if kind == T.mjGEOM_BOX:
        return rr.Boxes3D(
            half_sizes=[size], centers=[pos], quaternions=q, colors=[rgba], fill_mode=_SOLID
        )
    if kind == T.mjGEOM_PLANE:  # infinite if size 0; the box's top face is the plane
        half = [size[0] or FLOOR_HALF, size[1] or FLOOR_HALF, 0.5 * FLOOR_THICKNESS]
        center = pos - R[:, 2] * half[2]
        return rr.Boxes3D(
            half_sizes=[half], centers=[center], quaternions=q, colors=[rgba], fill_mode=_SOLID
        )
    if kind in (T.mjGEOM_SPHERE, T.mjGEOM_ELLIPSOID):
        half = [size[0]] * 3 if kind == T.mjGEOM_SPHERE else size
        return rr.Ellipsoids3D(
            half_sizes=[half], centers=[pos], quaternions=q, colors=[rgba], fill_mode=_SOLID
        )
    if kind == T.mjGEOM_CAPSULE:  # rerun's runs from its origin along +z
        return rr.Capsules3D(
            lengths=[2 * size[1]],
            radii=[size[0]],
            translations=[pos - R[:, 2] * size[1]],
            quaternions=q,
            colors=[rgba],
            fill_mode=_SOLID,
        )
    if kind == T.mjGEOM_CYLINDER:
        return rr.Cylinders3D(
            lengths=[2 * size[1]],
            radii=[size[0]],
            centers=[pos],
            quaternions=q,
            colors=[rgba],
            fill_mode=_SOLID,
        )
    if kind == T.mjGEOM_MESH:  # vertices are in the geom's frame: put them in the body's
        mesh = int(m.geom_dataid[g])
        va, vn = m.mesh_vertadr[mesh], m.mesh_vertnum[mesh]
        fa, fn = m.mesh_faceadr[mesh], m.mesh_facenum[mesh]
        v = m.mesh_vert[va : va + vn].astype(np.float64) @ R.T + pos
        f = m.mesh_face[fa : fa + fn]
        return rr.Mesh3D(
            vertex_positions=v.astype(np.float32),
            triangle_indices=f.astype(np.uint32),
            vertex_normals=_vertex_normals(v, f).astype(np.float32),
            albedo_factor=rgba,
        )
    return None  # height fields, SDFs: none in the scene


class _Arrow:
    """A ready pyarrow array as a rerun component batch (``stream.log`` takes these,
    wrapped in ``rr.DescribedComponentBatch``)."""

    __slots__ = ("array",)

    def __init__(self, array: pa.Array) -> None:
        self.array = array

    def as_arrow_array(self) -> pa.Array:
        return self.array


class WorldLogger:
    """Logs a ManipulationWorld's geometry to a rerun stream.

    On construction, every visual geom once (static, in its body's frame) and the poses
    of the bodies welded to the world (static); then :meth:`log_pose` logs the other
    bodies' poses at the stream's current time (call it at least once: until then
    they sit at the origin).

    Args:
        stream: the recording to log to.
        world: the world to draw (its model's geometry; its state for the poses).
        root: entity path of the scene (its view coordinates: z up).

    Attributes:
        entities: entity path of every logged geom, in geom order.
        kinds: the rerun archetype of each of ``entities`` (``"Mesh3D"``, ...).
        body_paths: entity path of every body with logged geoms, by body name.
    """

    def __init__(
        self, stream: rr.RecordingStream, world: ManipulationWorld, root: str = "world"
    ) -> None:
        self.stream, self.world, self.root = stream, world, root
        m, d = world.model, world.data
        stream.log(root, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        self.entities: list[str] = []
        self.kinds: dict[str, str] = {}
        self.body_paths: dict[str, str] = {}
        body_part: dict[int, str] = {}
        taken_bodies: set[str] = set()
        taken_geoms: dict[int, set[str]] = {}
        for g in range(m.ngeom):
            rgba = _rgba8(m, g)
            if m.geom_group[g] >= 3 or rgba[3] == 0:  # collision-only
                continue
            archetype = _geom_archetype(m, g, rgba)
            if archetype is None:
                continue
            b = int(m.geom_bodyid[g])
            if b not in body_part:
                body_part[b] = _unique(_part(m.body(b).name, f"body{b}"), taken_bodies)
                self.body_paths[m.body(b).name] = f"{root}/{body_part[b]}"
            geom = _unique(_part(m.geom(g).name, f"geom{g}"), taken_geoms.setdefault(b, set()))
            path = f"{root}/{body_part[b]}/{geom}"
            stream.log(path, archetype, static=True)
            self.entities.append(path)
            self.kinds[path] = type(archetype).__name__
        # A body moves if a joint or a mocap pose is on its chain to the world (bodies
        # come after their parents); the others are logged once, static.
        moves = np.zeros(m.nbody, dtype=bool)
        for b in range(1, m.nbody):
            own = m.body_jntnum[b] > 0 or m.body_mocapid[b] >= 0
            moves[b] = own or moves[m.body_parentid[b]]
        self._moving = np.array([b for b in sorted(body_part) if moves[b]], dtype=int)
        self._moving_paths = [f"{root}/{body_part[b]}" for b in self._moving]
        for b in sorted(body_part):
            if b > 0 and not moves[b]:
                stream.log(
                    f"{root}/{body_part[b]}",
                    rr.Transform3D(translation=d.xpos[b], quaternion=_xyzw(d.xquat[b])),
                    static=True,
                )
        # log_pose builds two arrow arrays per call and hands out one-row slices:
        # ~2.5x faster than a Transform3D per body (rerun takes one transform per row).
        sample = rr.Transform3D(translation=[0, 0, 0], quaternion=rr.Quaternion(xyzw=[0, 0, 0, 1]))
        types = {
            b.component_descriptor(): b.as_arrow_array().type for b in sample.as_component_batches()
        }
        self._t_desc = rr.Transform3D.descriptor_translation()
        self._q_desc = rr.Transform3D.descriptor_quaternion()
        self._t_type, self._q_type = types[self._t_desc], types[self._q_desc]

    def log_pose(self) -> None:
        """Log every moving body's pose (``world.data.xpos``, ``xquat``: as of the last
        kinematics update) at the stream's current time."""
        d, n = self.world.data, len(self._moving)
        if n == 0:
            return
        xyz = pa.array(d.xpos[self._moving].astype(np.float32).ravel())
        xyzw = pa.array(d.xquat[self._moving][:, [1, 2, 3, 0]].astype(np.float32).ravel())
        t = pa.FixedSizeListArray.from_arrays(xyz, type=self._t_type)
        q = pa.FixedSizeListArray.from_arrays(xyzw, type=self._q_type)
        for i, path in enumerate(self._moving_paths):
            self.stream.log(
                path,
                [
                    rr.DescribedComponentBatch(_Arrow(t.slice(i, 1)), self._t_desc),
                    rr.DescribedComponentBatch(_Arrow(q.slice(i, 1)), self._q_desc),
                ],
            )

    def log_replay(self, outcome: Outcome, t0: float = 0.0, every: int = 1) -> float:
        """Replay a run's recorded ``qpos`` frames: every ``every``-th frame (and the
        last) put into the world, kinematics updated, and the poses logged at
        ``sim_time`` = ``t0 + outcome.times[k]`` [s] (other timelines as the caller
        set them). The world is left exactly as it was (state restored).

        Returns:
            ``t0`` + the run's last recording time [s] (``t0`` if it recorded nothing):
            where the next run's replay starts.

        Raises:
            ConfigError: ``every`` is not an integer >= 1, or ``outcome``'s ``times``
                (T,) and ``qpos`` (T, nq) do not fit this world.
        """
        every = check_positive_int("every", every)
        m, d = self.world.model, self.world.data
        times, qpos = np.asarray(outcome.times, dtype=float), np.asarray(outcome.qpos)
        if times.ndim != 1 or qpos.shape != (len(times), m.nq):
            raise ConfigError(
                f"outcome must hold times (T,) and qpos (T, {m.nq}) for this world, got "
                f"times {times.shape} and qpos {qpos.shape}"
            )
        if len(times) == 0:
            return float(t0)
        frames = list(range(0, len(times), every))
        if frames[-1] != len(times) - 1:
            frames.append(len(times) - 1)
        saved = self.world.snapshot()
        try:
            for k in frames:
                d.qpos[:] = qpos[k]
                mujoco.mj_kinematics(m, d)
                self.stream.set_time("sim_time", duration=float(t0 + times[k]))
                self.log_pose()
        finally:
            self.world.restore(saved)
        return float(t0 + times[-1])


def scene_eye(world: ManipulationWorld) -> tuple[np.ndarray, np.ndarray]:
    """Where a 3D view of the scene looks from and at, world (3,) [m] each: at the point
    between the robot's base and the cabinet, from behind the robot's left shoulder
    and above, so the robot, the cabinet's front and the table beside them are all in
    view (no ``base_link`` body: the robot at the origin; no ``cabinet/`` bodies: the
    cabinet 1 m ahead along +x)."""
    m, d = world.model, world.data
    names = [m.body(b).name for b in range(m.nbody)]
    base = d.xpos[names.index("base_link")] if "base_link" in names else np.zeros(3)
    cab = [d.xpos[b] for b, n in enumerate(names) if n.startswith("cabinet/")]
    ahead = np.mean(cab, axis=0) if cab else base + np.array([1.0, 0.0, 0.0])
    u = np.r_[(ahead - base)[:2], 0.0]
    norm = float(np.linalg.norm(u))
    u = u / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])
    reach = max(norm, 0.5)  # [m]: the view's scale
    left = np.array([-u[1], u[0], 0.0])
    target = np.r_[(0.4 * base + 0.6 * ahead)[:2], 0.7]
    eye = target + reach * (-1.5 * u + 1.1 * left) + [0.0, 0.0, 1.0]
    return eye, target


def log_camera(
    stream: rr.RecordingStream, entity: str, frame: CameraFrame, cloud: np.ndarray | None
) -> None:
    """Log a camera frame at the stream's current time: its pose at ``entity``, the
    pinhole (MuJoCo's convention: looking along -z, y up) at ``entity/image``, the
    colour image at ``entity/image/rgb`` and the depth [m] at ``entity/image/depth``
    (background, beyond :data:`MAX_DEPTH`, as 0: no depth); and, if given, ``cloud``
    (N, 3) world points [m] at ``entity_cloud`` (beside the camera, not under its
    transform).

    Raises:
        ConfigError: ``cloud`` is not (N, 3).
    """
    T = np.asarray(frame.T_world_camera, dtype=float)
    h, w = frame.depth.shape
    stream.log(entity, rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]))
    stream.log(
        f"{entity}/image",
        rr.Pinhole(
            focal_length=0.5 * h / math.tan(0.5 * frame.fovy),
            width=w,
            height=h,
            camera_xyz=rr.ViewCoordinates.RUB,
            image_plane_distance=0.1,
        ),
    )
    stream.log(f"{entity}/image/rgb", rr.Image(frame.rgb))
    depth = np.where(frame.depth < MAX_DEPTH, frame.depth, 0.0).astype(np.float32)
    stream.log(f"{entity}/image/depth", rr.DepthImage(depth, meter=1.0))
    if cloud is not None:
        pts = np.asarray(cloud, dtype=np.float32)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise ConfigError(f"cloud must be (N, 3) world points [m], got shape {pts.shape}")
        stream.log(f"{entity}_cloud", rr.Points3D(pts, radii=0.003, colors=CLOUD))


def log_joints(
    stream: rr.RecordingStream,
    entity: str,
    joints: Sequence[BelievedJoint],
    weights: np.ndarray,
    length: float = 0.25,
    *,
    origins: np.ndarray | None = None,
) -> None:
    """Log believed joints at the stream's current time: each an arrow ``length`` [m]
    long from its ``origin`` (or the row of ``origins``, (N, 3) [m], e.g. the handle of a
    prismatic part, whose joint has no meaningful origin) along its axis, labelled
    with its type, coloured from light to dark by its weight over the largest weight.

    Raises:
        ConfigError: ``weights`` is not (N,) finite and >= 0, ``origins`` not (N, 3),
            or ``length`` not > 0.
    """
    n = len(joints)
    wts = np.asarray(weights, dtype=float).reshape(-1)
    if wts.shape != (n,) or not np.all(np.isfinite(wts)) or np.any(wts < 0):
        raise ConfigError(f"weights must be {n} finite values >= 0, got {weights!r}")
    if not length > 0:
        raise ConfigError(f"length must be > 0 [m], got {length!r}")
    starts = np.array([j.origin for j in joints], dtype=float).reshape(n, 3)
    if origins is not None:
        starts = np.asarray(origins, dtype=float)
        if starts.shape != (n, 3):
            raise ConfigError(f"origins must be ({n}, 3) [m], got shape {starts.shape}")
    top = wts.max() if n and wts.max() > 0 else 1.0
    shade = (wts / top)[:, None]
    colors = np.round(LIGHT + shade * (DARK - LIGHT)).astype(np.uint8)
    stream.log(
        entity,
        rr.Arrows3D(
            origins=starts,
            vectors=np.array([j.axis for j in joints], dtype=float).reshape(n, 3) * length,
            colors=colors,
            labels=[j.type for j in joints],
            radii=0.005,
        ),
    )


def episode_strip(
    images: Sequence[np.ndarray], path: Path, labels: Sequence[str] | None = None
) -> Path:
    """Write RGB images side by side as one PNG at ``path`` (parent folders created),
    each at its native resolution scaled to the tallest's height, ``labels`` as titles
    in a band above.

    Returns:
        ``path``.

    Raises:
        ConfigError: no images, an image not (H, W, 3) or (H, W, 4), or ``labels`` of
            another length.
    """
    from matplotlib.figure import Figure  # no pyplot: no global figure state

    if len(images) == 0:
        raise ConfigError("episode_strip needs at least one image")
    shapes = [np.shape(im) for im in images]
    if any(len(s) != 3 or s[2] not in (3, 4) or s[0] == 0 or s[1] == 0 for s in shapes):
        raise ConfigError(f"images must be (H, W, 3) or (H, W, 4), got shapes {shapes}")
    if labels is not None and len(labels) != len(images):
        raise ConfigError(f"{len(images)} images but {len(labels)} labels")
    dpi, band = 100, (28 if labels is not None else 0)  # title band [px]
    h = max(s[0] for s in shapes)
    widths = [s[1] * h / s[0] for s in shapes]
    total_w, total_h = sum(widths), h + band
    fig = Figure(figsize=(total_w / dpi, total_h / dpi), dpi=dpi)
    left = 0.0
    for k, (im, w) in enumerate(zip(images, widths, strict=True)):
        ax = fig.add_axes((left / total_w, 0.0, w / total_w, h / total_h))
        ax.imshow(im, aspect="auto", interpolation="nearest")
        ax.set_axis_off()
        if labels is not None:
            ax.set_title(labels[k], fontsize=10, pad=4)
        left += w
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path
