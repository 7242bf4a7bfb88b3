"""Per-view joint-type cues, the association of readings across views, open panels with
hidden hinges, and grasps on a handle's middle (issue 10, follow-up). Synthetic
instances only: no rendering, no network."""

from __future__ import annotations

import math
from dataclasses import replace as dataclass_replace
from types import SimpleNamespace

import numpy as np

from perception.affordance import BAR_MIDDLE, sample_grasps
from perception.fusion import (
    FRONT_GAP,
    FrontFrame,
    FusedCabinet,
    PartHypothesis,
    Reading,
    _apart,
    _associate,
    _summarise,
    _weighted_median,
    cut_sides,
    front_frame,
    fuse_sides,
    handle_shape,
    read_instance,
)
from perception.instances import Instance, ViewParts
from perception.joint_cues import (
    CUE_EVIDENCE,
    HandleSeen,
    closed_front_evidence,
    reads_as_furniture,
)
from perception.parts import texture_map

FRONT = FrontFrame(np.eye(4), 0.8, 0.8, 0.4, True, 1000)


def _instance(points: np.ndarray, pixels: int, pull: np.ndarray | None = None) -> Instance:
    mask = np.zeros(pixels, dtype=bool)
    mask[:] = True
    return Instance(
        mask=mask,
        points=points,
        class_prob=np.array([0.1, 0.2, 0.7]),
        part_prob=0.9,
        hinge_prob=np.full(4, 0.25),
        handle=None,
        handle_score=0.0,
        pull=np.zeros(len(points)) if pull is None else pull,
        net_class_prob=np.array([0.1, 0.2, 0.7]),
    )


def _reading(view: int, rect, pixels: int) -> Reading:
    rect = np.asarray(rect, dtype=float)
    return Reading(
        view, _instance(np.zeros((1, 3)), pixels), rect, rect, 0.0, np.tile(rect, (4, 1)),
        np.zeros(4), np.ones(4, dtype=bool), True, 0.0,
    )  # fmt: skip


def test_closed_front_handle_cues() -> None:
    g = CUE_EVIDENCE
    centred = closed_front_evidence(HandleSeen(0.05, 0.1, 0.15, 0.01, 30), True)
    assert np.allclose(centred, [g, 1.0, g])  # a drawer's handle
    off = closed_front_evidence(HandleSeen(0.7, 0.0, 0.01, 0.15, 30), True)
    assert off[2] == 1.0 and off[1] <= g * g  # a side door's upright bar, by its free edge
    bare = closed_front_evidence(None, True)
    assert bare[0] > bare[1] == bare[2]  # handles elsewhere: a bare front is a panel
    assert closed_front_evidence(None, False)[0] == g  # no handles anywhere: no panel cue


def test_an_edge_pull_rules_out_a_drawer_only_on_a_plain_front() -> None:
    """A bar centred across by the top edge: a flap's on a flat-coloured front (the plain
    style), a drawer's or a door's on a front that reads as furniture (41083's drawers)
    or whose look is unknown."""
    g = CUE_EVIDENCE
    edge = HandleSeen(0.05, 0.7, 0.2, 0.01, 30)
    assert np.allclose(closed_front_evidence(edge, True, furniture=False), [g, g, 1.0])
    assert np.allclose(closed_front_evidence(edge, True, furniture=True), [g, 1.0, 1.0])
    assert np.allclose(closed_front_evidence(edge, True), [g, 1.0, 1.0])


def test_a_front_reads_as_furniture_by_its_texture() -> None:
    """Grain lines (a luminance ramp every 4 pixels) read as furniture, a flat colour
    with smooth shading does not; a front too small to judge, or a view without a
    texture map, is unknown."""
    h, w = 120, 160
    mask = np.zeros((h, w), bool)
    mask[20:80, 30:120] = True
    shade = np.tile(np.linspace(80.0, 140.0, w * 2, dtype=np.float32), (h * 2, 1))
    grain = shade.copy()
    grain[::4] += 40.0  # one-pixel dark-light lines across the board
    views = {}
    for name, grey in (("flat", shade), ("grain", grain)):
        rgb = np.repeat(np.clip(grey, 0, 255).astype(np.uint8)[..., None], 3, axis=2)
        views[name] = SimpleNamespace(
            texture=texture_map(rgb, 2, (h, w)), handle_prob=np.zeros((h, w))
        )
    assert reads_as_furniture(views["grain"], mask) is True
    assert reads_as_furniture(views["flat"], mask) is False
    tiny = np.zeros((h, w), bool)
    tiny[10:14, 10:14] = True
    assert reads_as_furniture(views["grain"], tiny) is None
    assert reads_as_furniture(SimpleNamespace(texture=None), mask) is None


def test_weighted_median_and_dividers() -> None:
    assert _weighted_median(np.array([0.0, 0.13, 0.14]), np.array([0.1, 0.5, 0.4])) == 0.13
    # Two cells with a divider between them lie apart; two pieces of one front do not.
    assert _apart(np.array([-0.3, -0.01, 0, 0.2]), np.array([0.01, 0.3, 0, 0.2]))
    assert not _apart(np.array([-0.3, 0.002, 0, 0.2]), np.array([0.0, 0.3, 0, 0.2]))


def test_a_front_displaces_a_fragment_of_its_view() -> None:
    """A strip seen in view 0 joined the group first (smallest first); view 0's whole
    front then takes its place, so the part is one hypothesis seen in every view."""
    front = [-0.2, 0.2, 0.3, 0.5]
    strip = _reading(0, [-0.2, 0.2, 0.3, 0.4], 50)  # IoU 0.5 with the front
    one, two = _reading(1, front, 800), _reading(2, front, 1000)
    mine = _reading(0, front, 900)
    groups, merged = _associate([strip, one, mine, two])  # smallest first
    big = max(groups, key=len)
    assert sorted(r.view for r in big) == [0, 1, 2] and any(r is mine for r in big)
    assert [r for g in groups for r in g if r is strip]  # the strip is kept, elsewhere
    assert merged == [0] * len(groups)


def test_hidden_hinge_is_extrapolated_to_the_front_plane() -> None:
    """A left-hinged door open by 60 deg whose hinge half is shaded: the hinge is where
    the panel's plane meets the front plane, not at the seen end."""
    theta, width, y_hinge = math.radians(60.0), 0.3, -0.1
    e = np.array([math.sin(theta), math.cos(theta), 0.0])  # hinge -> free edge
    s, z = np.meshgrid(np.linspace(0.15, width, 40), np.linspace(0.2, 0.5, 30))
    pts = np.array([0.0, y_hinge, 0.0]) + s.reshape(-1, 1) * e
    pts[:, 2] = z.ravel()
    r = read_instance(0, _instance(pts, len(pts)), FRONT)
    assert not r.closed_door and r.door_ok[0]
    assert abs(r.door_rect[0][0] + FRONT_GAP - y_hinge) < 0.01
    assert abs(r.door_rect[0][1] - r.door_rect[0][0] - width - 2 * FRONT_GAP) < 0.02
    assert abs(r.door_q[0] - theta) < 0.02


def test_affordance_grasps_take_a_bar_near_its_middle() -> None:
    """Grasps drawn on a 20 cm bar lie within BAR_MIDDLE of its middle; uniform ones
    spread over the front."""
    y, z = np.meshgrid(np.linspace(-0.2, 0.2, 41), np.linspace(0.2, 0.4, 21))
    face = np.stack([np.zeros(y.size), y.ravel(), z.ravel()], axis=1)
    bar_y = np.linspace(-0.1, 0.1, 40)
    bar = np.stack([np.full(40, 0.035), bar_y, np.full(40, 0.3)], axis=1)
    pts = np.concatenate([face, bar])
    pull = np.r_[np.zeros(len(face)), np.full(len(bar), 0.9)]
    inst = _instance(pts, len(pts), pull)
    rect = np.array([-0.2, 0.2, 0.2, 0.4])
    r = Reading(0, inst, rect, rect, 0.0, np.tile(rect, (4, 1)), np.zeros(4),
                np.ones(4, dtype=bool), True, 0.0)  # fmt: skip
    h = PartHypothesis(
        rect=rect, rect_std=np.zeros(4), class_prob=np.array([0.0, 1.0, 0.0]), existence=1.0,
        hinge_prob=np.full(4, 0.25), door_rect=np.tile(rect, (4, 1)), door_q=np.zeros(4),
        q_drawer=0.0, q_std=0.0, handle=None, handle_score=0.9, views=1, visible=1, merged=0,
        shelf=False, readings=[r],
    )  # fmt: skip
    fused = FusedCabinet(FRONT, [h], 0.0)
    T, p = sample_grasps(fused, 0, 50, np.random.default_rng(0))
    assert (p > 0.5).mean() > 0.9
    on = p > 0.5
    assert np.all(np.abs(T[on, 1, 3]) <= BAR_MIDDLE + 1e-6)
    assert np.allclose(T[on, 2, 3], 0.3)
    assert np.allclose(T[:, :3, 0], [[-1.0, 0.0, 0.0]])  # into the front
    U, _ = sample_grasps(fused, 0, 50, np.random.default_rng(0), sharpness=0.0)
    assert np.abs(U[:, 1, 3]).max() > 0.1


def test_the_handle_shape_tells_a_bar_from_a_knob() -> None:
    """A view's handle pixels stretched along a line read as a bar in that direction, a
    round blob as a knob; views vote by pixel count, and too few pixels say nothing."""
    rng = np.random.default_rng(0)

    def blob(long: float, across: float, along: int, n: int = 40) -> np.ndarray:
        p = np.zeros((n, 3))
        p[:, 0] = rng.uniform(0.0, 0.045, n)  # the face to the bar: posts and standoff
        p[:, along] = rng.uniform(-long / 2, long / 2, n)
        p[:, 3 - along] = rng.uniform(-across / 2, across / 2, n)
        return p

    bar_z, bar_y, knob = blob(0.14, 0.012, 2), blob(0.10, 0.015, 1), blob(0.035, 0.03, 1)
    assert handle_shape([bar_z, bar_z[:20]], FRONT) == ("bar", "z")
    assert handle_shape([bar_y], FRONT) == ("bar", "y")
    assert handle_shape([knob, knob[:30]], FRONT) == ("knob", None)
    assert handle_shape([bar_z[:10], knob], FRONT) == ("knob", None)  # 10 of 50 pixels
    assert handle_shape([bar_z[:3]], FRONT) == ("bar", None)  # too few: the prior
    assert handle_shape([], FRONT) == ("bar", None)


def test_a_bars_grasp_point_is_its_middle_at_the_peaks_standoff() -> None:
    """Two views whose pull peaks near a 16 cm upright bar's ends (0.05 m and 0.065 m
    below its middle at 0.72 m) and on it (3.5 cm out): the part's grasp point is the
    bar's middle, at the peaks' standoff, though the bar's pixels spill onto the face
    (x = 0) around it; with too few handle pixels it stays the peaks' median."""
    bar = np.stack([np.full(40, 0.035), np.full(40, 0.3), np.linspace(0.64, 0.80, 40)], axis=1)
    side = np.tile([0.28, 0.32], 10)
    spill = np.stack([np.zeros(20), side, np.linspace(0.64, 0.80, 20)], axis=1)
    rect = [0.1, 0.35, 0.5, 0.9]
    group = []
    for k, peak_z in enumerate((0.67, 0.655)):
        r = _reading(k, rect, 500)
        peak = np.array([0.035, 0.3, peak_z])
        pixels = np.concatenate([bar, spill])
        inst = dataclass_replace(r.instance, handle=peak, handle_score=0.9, handle_points=pixels)
        group.append(dataclass_replace(r, instance=inst))
    h = _summarise(group, 0, 2, FRONT).handle
    assert h is not None
    assert abs(h[2] - 0.72) < 0.005 and abs(h[1] - 0.3) < 0.005
    assert abs(h[0] - 0.035) < 1e-9  # the standoff is the peaks', not the spill's
    few = [dataclass_replace(r, instance=dataclass_replace(r.instance, handle_points=bar[:2]))
           for r in group]  # fmt: skip
    h = _summarise(few, 0, 2, FRONT).handle
    assert h is not None and abs(h[2] - 0.6625) < 1e-9


def _grid(y: tuple[float, float], z: tuple[float, float], x: float, step: float = 0.005):
    """Points of a front-facing rectangle at ``x`` (world +x toward the camera) [m]."""
    ys, zs = np.meshgrid(np.arange(*y, step), np.arange(*z, step))
    return np.stack([np.full(ys.size, x), ys.ravel(), zs.ravel()], axis=1)


def test_the_front_takes_in_overlay_fronts_on_a_face_frame() -> None:
    """SAPIEN's 40147, as its views showed it: a large blind carcass panel 8 mm behind the
    face frame, a narrow face frame, and overlay door and drawer fronts 15 mm in front of
    the panel over the other half. The panel is the front plane (most carcass on it);
    the front's extent must still span the whole face, or the parts fall outside it."""
    panel = _grid((0.05, 0.40), (0.05, 0.65), 0.0)
    frame = np.concatenate([_grid((-0.42, -0.40), (0.05, 0.65), 0.008),
                            _grid((-0.42, 0.05), (0.63, 0.65), 0.008),
                            _grid((0.00, 0.05), (0.05, 0.65), 0.008)])  # fmt: skip
    # Fewer points on the fronts than on the panel (seen aslant, as in 40147's views).
    door = _grid((-0.39, -0.01), (0.05, 0.45), 0.015, step=0.01)
    drawer = _grid((-0.39, -0.01), (0.47, 0.62), 0.015, step=0.01)
    xs, zs = np.meshgrid(np.arange(-0.45, 0.0, 0.01), np.arange(0.05, 0.65, 0.01))
    side = np.stack([xs.ravel(), np.full(xs.size, 0.41), zs.ravel()], axis=1)  # seen aslant
    pts = np.concatenate([panel, frame, door, drawer, side])
    cls = np.concatenate([np.ones(len(panel) + len(frame)), np.full(len(door), 4),
                          np.full(len(drawer), 3), np.ones(len(side))]).astype(int)  # fmt: skip
    normals = np.tile([1.0, 0.0, 0.0], (len(pts), 1))
    normals[-len(side) :] = [0.0, 1.0, 0.0]
    T = np.eye(4)
    T[:3, 3] = [1.5, 0.0, 0.4]
    view = ViewParts(T, 0.8, (120, 160), pts, cls, normals, [], np.zeros((120, 160)),
                     np.zeros((120, 160, 3)), np.zeros((120, 160), bool),
                     np.zeros((120, 160, 3)), 0.0)  # fmt: skip
    front = front_frame([view])
    assert front.width > 0.78, front.width  # the whole face, 0.82 m
    assert abs(front.to_front(np.array([0.0, -0.2, 0.3]))[1] + 0.19) < 0.03  # centred on it


def _camera_facing_front(x: float, z: float) -> np.ndarray:
    """``T_world_camera`` of a camera at (x, 0, z) looking along -x (at the front of
    :data:`FRONT`), image right = +y, image up = +z."""
    T = np.eye(4)
    T[:3, :3] = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    T[:3, 3] = [x, 0.0, z]
    return T


def test_a_part_that_runs_off_an_image_is_bounded_there_not_ended() -> None:
    """A tall drawer's front, 0.9-1.3 m up, runs off the top of three views, which see
    it to 1.2 m, and one view sees all of it: the fused front reaches 1.3 m (the three
    views' median put it 10 cm low), and a side no view sees end is the farthest seen."""
    h, w = 120, 160
    view = ViewParts(_camera_facing_front(2.0, 1.0), 0.8, (h, w), np.zeros((0, 3)),
                     np.zeros(0, int), np.zeros((0, 3)), [], np.zeros((h, w)),
                     np.zeros((h, w, 3)), np.zeros((h, w), bool), np.zeros((h, w, 3)),
                     0.0)  # fmt: skip
    y, z = np.meshgrid(np.linspace(-0.2, 0.2, 20), np.linspace(0.9, 1.2, 20))
    pts = np.stack([np.zeros(y.size), y.ravel(), z.ravel()], axis=1)
    top = np.zeros((h, w), dtype=bool)
    top[:40, 60:100] = True  # the instance touches the image's top row
    inst = _instance(pts, len(pts))
    cut_inst = Instance(**{**inst.__dict__, "mask": top})
    r = read_instance(0, cut_inst, FRONT, view)
    assert list(r.cut) == [False, False, False, True]  # y0, y1, z0, z1
    assert list(r.door_cut[0]) == [False, False, False, True]  # closed: every door row
    left = np.zeros((h, w), dtype=bool)
    left[40:80, :30] = True
    assert list(cut_sides(left, r.face_rect, 0.0, FRONT, view)) == [True, False, False, False]
    inside = np.zeros((h, w), dtype=bool)
    inside[40:80, 60:100] = True
    assert not cut_sides(inside, r.face_rect, 0.0, FRONT, view).any()
    assert not read_instance(0, cut_inst, FRONT).cut.any()  # no view given: no bounds

    cut_rect, whole = [-0.2, 0.2, 0.9, 1.2], [-0.19, 0.21, 0.9, 1.3]
    group = [dataclass_replace(_reading(k, cut_rect, 900), cut=np.array([0, 0, 0, 1], bool))
             for k in range(3)] + [_reading(3, whole, 300)]  # fmt: skip
    fused = _summarise(group, 0, 4, FRONT).rect
    assert abs(fused[3] - 1.3) < 1e-9 and abs(fused[2] - 0.9) < 1e-9
    assert abs(fused[1] - 0.2) < 1e-9  # the other sides: the median of all four
    rects = np.array([cut_rect, cut_rect, [-0.2, 0.2, 0.9, 1.25]])
    cut = np.zeros((3, 4), dtype=bool)
    cut[:, 3] = True
    assert fuse_sides(rects, cut, None)[3] == 1.25  # no view ends it: the farthest bound
