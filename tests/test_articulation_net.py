"""The per-pixel articulation network: targets, geometry, part extraction, training."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from perception.articulation_net import (
    CLASSES,
    N_OUT,
    ArticulationNet,
    class_targets,
    extract_parts,
    pixel_points,
    prepare_input,
    view_targets,
)
from strug_manip.world.perception_data import render_cabinet
from strug_manip.world.sim import depth_to_points

ROOT = Path(__file__).resolve().parents[1]
WEIGHTS = ROOT / "models" / "perception" / "articulation_net.pt"
sys.path.insert(0, str(ROOT / "tools"))


def test_class_targets() -> None:
    part_map = np.array([[-1, 0, 1], [2, 3, 3]])
    joint_type = np.array([0, 1, 2])  # part 1 fixed, 2 prismatic, 3 revolute
    assert class_targets(part_map, joint_type).tolist() == [[0, 1, 2], [3, 4, 4]]
    assert CLASSES[4] == "revolute"


def test_pixel_points_agree_with_the_world_deprojection() -> None:
    rng = np.random.default_rng(0)
    depth = rng.uniform(0.5, 3.0, size=(24, 32)).astype(np.float32)
    pts = pixel_points(depth, math.radians(45.0)).reshape(-1, 3)
    ref, idx = depth_to_points(depth, np.eye(4), math.radians(45.0))
    np.testing.assert_allclose(pts[idx], ref, atol=1e-9)


def test_prepare_input_shapes_and_ranges() -> None:
    rgb = np.full((240, 320, 3), 255, dtype=np.uint8)
    depth = np.full((240, 320), 2.0, dtype=np.float32)
    depth[0, 0] = np.nan
    x = prepare_input(rgb, depth)
    assert x.shape == (4, 120, 160) and x.dtype == np.float32
    assert np.allclose(x[:3], 1.0) and x[3].min() >= 0.0 and x[3].max() <= 1.0
    assert np.isfinite(x).all()


def test_network_output_shape_and_bad_width() -> None:
    net = ArticulationNet(4).eval()
    with torch.no_grad():
        assert net(torch.zeros(2, 4, 120, 160)).shape == (2, N_OUT, 120, 160)
    with pytest.raises(ValueError, match="width must be an integer >= 4"):
        ArticulationNet(2)


def test_extract_parts_recovers_a_door_from_perfect_maps() -> None:
    h, w = 40, 60
    points = pixel_points(np.full((h, w), 2.0), math.radians(45.0))
    out = np.zeros((N_OUT, h, w))
    out[0] = 5.0  # background everywhere ...
    door = np.zeros((h, w), dtype=bool)
    door[10:30, 20:40] = True
    out[0][door], out[4][door] = 0.0, 5.0  # ... but a door
    axis = np.array([0.0, 1.0, 0.0])
    hinge = np.array([0.3, 0.0, -2.0])
    out[5:8][:, door] = axis[:, None]
    out[8:11][:, door] = (hinge - points[door]).T
    (part,) = extract_parts(out, points)
    assert part.joint_type == "revolute" and part.pixels == door.sum()
    assert part.confidence > 0.9
    np.testing.assert_allclose(part.axis, axis)
    np.testing.assert_allclose(part.origin, hinge, atol=1e-9)


def test_a_few_training_steps_reduce_the_loss() -> None:
    from train_perception import flip, losses

    views = render_cabinet(25, views=4)
    x = torch.from_numpy(np.stack([prepare_input(v.rgb, v.depth) for v in views]))
    targets = [
        view_targets(v.part_map, v.joint_type, v.axis_cam, v.origin_cam, v.depth, v.fovy)
        for v in views
    ]
    cls_t, axis_t, off_t = (torch.from_numpy(np.stack([t[i] for t in targets])) for i in range(3))
    # Mirroring twice is the identity; mirroring negates x of axes and offsets.
    twice = flip(*flip(x, cls_t, axis_t, off_t))
    assert all(torch.equal(a, b) for a, b in zip(twice, (x, cls_t, axis_t, off_t), strict=True))
    _, cls_f, axis_f, off_f = flip(x, cls_t, axis_t, off_t)
    assert torch.equal(off_f[:, 0], -off_t[:, 0].flip(-1))
    drawer, door = cls_f == 3, cls_f == 4
    assert drawer.any() and door.any()
    assert torch.equal(axis_f[:, 0][drawer], -axis_t[:, 0].flip(-1)[drawer])
    assert torch.equal(
        axis_f[:, 1:][door.unsqueeze(1).expand(-1, 2, -1, -1)],
        -axis_t[:, 1:].flip(-1)[door.unsqueeze(1).expand(-1, 2, -1, -1)],
    )
    torch.manual_seed(0)
    net = ArticulationNet(8)
    opt = torch.optim.Adam(net.parameters(), lr=3e-3)
    first = None
    for _ in range(25):
        total, *_ = losses(net(x), cls_t, axis_t, off_t)
        first = total.item() if first is None else first
        opt.zero_grad()
        total.backward()
        opt.step()
    assert total.item() < 0.5 * first


@pytest.mark.skipif(not WEIGHTS.exists(), reason="no trained weights in models/perception")
def test_shipped_weights_segment_an_unseen_cabinet() -> None:
    """The trained network on evaluation cabinets (seeds < 10,000, never trained on)."""
    ckpt = torch.load(WEIGHTS, weights_only=True)
    net = ArticulationNet(ckpt["width"])
    net.load_state_dict(ckpt["state_dict"])
    net.eval()
    correct = total = 0
    for seed in (5, 9):
        for v in render_cabinet(seed, views=2):
            with torch.no_grad():
                out = net(torch.from_numpy(prepare_input(v.rgb, v.depth))[None])[0].numpy()
            truth = class_targets(v.part_map[::2, ::2], v.joint_type)
            correct += (out[: len(CLASSES)].argmax(axis=0) == truth).sum()
            total += truth.size
    assert correct / total > 0.85


@pytest.mark.parametrize(("hinge_x", "expected_y"), [(0.5, 1.0), (-0.5, -1.0)])
def test_door_axis_sign_comes_from_the_geometry(hinge_x: float, expected_y: float) -> None:
    """Sign-free votes (half of them flipped); the sign that swings the door towards the
    camera is chosen: the hinge's side decides it."""
    h, w = 40, 60
    points = pixel_points(np.full((h, w), 2.0), math.radians(45.0))
    out = np.zeros((N_OUT, h, w))
    out[0] = 5.0
    door = np.zeros((h, w), dtype=bool)
    door[10:30, 20:40] = True
    out[0][door], out[4][door] = 0.0, 5.0
    votes = np.tile(np.array([[0.0], [1.0], [0.0]]), (1, int(door.sum())))
    votes[:, ::2] *= -1.0
    out[5:8][:, door] = votes
    hinge = np.array([hinge_x, 0.0, -2.0])
    out[8:11][:, door] = (hinge - points[door]).T
    (part,) = extract_parts(out, points)
    np.testing.assert_allclose(part.axis, [0.0, expected_y, 0.0], atol=1e-9)
    # A small positive turn about the axis brings the centroid closer to the camera.
    turned = part.centroid + 0.01 * np.cross(part.axis, part.centroid - part.origin)
    assert np.linalg.norm(turned) < np.linalg.norm(part.centroid)
