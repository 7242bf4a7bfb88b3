"""What perception reads off one view: the part instances and the view's points.

Data only (numpy): :mod:`perception.parts` makes them, :mod:`perception.joint_cues` and
:mod:`perception.fusion` read them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: Fewer cabinet pixels than this (network resolution) is "no cabinet in view".
MIN_CABINET_PIXELS = 150


@dataclass(frozen=True)
class Instance:
    """One part seen in one view.

    Attributes:
        mask: (h, w) bool at the network's resolution.
        points: (N, 3) world points of its valid pixels [m].
        class_prob: (3,) probability of fixed, prismatic, revolute: the network's
            (``net_class_prob``) times this view's geometric evidence
            (:mod:`perception.joint_cues`).
        part_prob: mean probability that its pixels are a part at all (not carcass or
            background), the instance's confidence.
        hinge_prob: (4,) mean hinge-side probabilities (left, right, top, bottom).
        handle: (3,) world point of its highest pull affordance [m], or None if no
            pixel of it exceeds probability 0.5.
        handle_score: that highest pull-affordance probability.
        pull: (N,) pull-affordance probability of each of ``points``.
        net_class_prob: (3,) the network's mean probability of fixed, prismatic,
            revolute over its pixels, renormalised over those three classes.
        handle_points: (K, 3) world points of its pixels whose pull affordance exceeds
            0.5 [m] (the handle's seen shape: fusion tells a bar from a knob by it).
    """

    mask: np.ndarray
    points: np.ndarray
    class_prob: np.ndarray
    part_prob: float
    hinge_prob: np.ndarray
    handle: np.ndarray | None
    handle_score: float
    pull: np.ndarray
    net_class_prob: np.ndarray
    handle_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    @property
    def pixels(self) -> int:
        """Pixel count at the network's resolution."""
        return int(self.mask.sum())


@dataclass(frozen=True)
class ViewParts:
    """What one view shows.

    Attributes:
        T_world_camera: (4, 4); fovy [rad]; shape: (h, w) at the network's resolution.
        cabinet_points: (N, 3) world points of the pixels classed carcass or part [m].
        cabinet_class: (N,) their class index (1 carcass, 2-4 parts).
        cabinet_normals: (N, 3) unit surface normals there, facing the camera (from
            neighbouring pixels' points; zero where a neighbour is a depth edge).
        instances: the parts seen.
        handle_prob: (h, w) pull-affordance probability.
        points: (h, w, 3) world points of every pixel [m]; valid: (h, w) bool;
            normals: (h, w, 3) their unit surface normals (zero where unknown).
        seconds: wall time of the network and the extraction [s].
        texture: (h, w) the RGB image's luminance gradient magnitude (3x3 Sobel, 0-255
            grey levels per pixel), the largest over each pixel's stride x stride
            block: wood grain and a framed front's rails show, a flat colour does not
            (:func:`perception.joint_cues.reads_as_furniture`); None if not computed.
    """

    T_world_camera: np.ndarray
    fovy: float
    shape: tuple[int, int]
    cabinet_points: np.ndarray
    cabinet_class: np.ndarray
    cabinet_normals: np.ndarray
    instances: list[Instance]
    handle_prob: np.ndarray
    points: np.ndarray
    valid: np.ndarray
    normals: np.ndarray
    seconds: float
    texture: np.ndarray | None = None

    @property
    def sees_cabinet(self) -> bool:
        """Whether enough cabinet pixels were found to call it a cabinet."""
        return len(self.cabinet_points) >= MIN_CABINET_PIXELS
