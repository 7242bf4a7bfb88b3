"""The per-pixel articulation network: targets, instances, training, shipped weights."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from perception.articulation_net import (
    CENTRE_SCALE,
    CLASSES,
    HINGE_SIDES,
    N_OUT,
    SL_CLASS,
    ArticulationNet,
    class_targets,
    hinge_side_of,
    load_network,
    pixel_points,
    prepare_input,
    view_targets,
)
from perception.parts import split_instances
from strug_manip.objects import generate_cabinet
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


def test_hinge_sides_follow_the_generators_axes() -> None:
    """Every generated door's axis maps back to its hinge side."""
    checked = 0
    for seed in range(40):
        for p in generate_cabinet(seed).parts:
            if p.kind == "door":
                assert HINGE_SIDES[hinge_side_of(p.axis)] == p.hinge
                checked += 1
    assert checked > 20


def test_pixel_points_agree_with_the_world_deprojection() -> None:
    rng = np.random.default_rng(0)
    depth = rng.uniform(0.5, 3.0, size=(24, 32)).astype(np.float32)
    pts = pixel_points(depth, math.radians(45.0)).reshape(-1, 3)
    ref, idx = depth_to_points(depth, np.eye(4), math.radians(45.0))
    np.testing.assert_allclose(pts[idx], ref, atol=1e-9)


def test_prepare_input_shapes_and_ranges() -> None:
    rgb = np.full((240, 320, 3), 255, dtype=np.uint8)
    depth = np.full((240, 320), 2.0, dtype=np.float32)
    x = prepare_input(rgb, depth)
    assert x.shape == (4, 120, 160) and x.dtype == np.float32
    assert np.allclose(x[:3], 1.0) and x[3].min() >= 0.0 and x[3].max() <= 1.0


def test_network_output_shape_and_bad_width() -> None:
    net = ArticulationNet(4).eval()
    with torch.no_grad():
        assert net(torch.zeros(2, 4, 120, 160)).shape == (2, N_OUT, 120, 160)
    with pytest.raises(ValueError, match="width must be an integer >= 4"):
        ArticulationNet(2)


def test_centre_votes_split_touching_fronts() -> None:
    """Two touching same-class rectangles (a drawer stack) with perfect centre votes come
    out as two instances; without votes (all pointing at one centre) as one."""
    h, w = 40, 60
    part = np.zeros((h, w), dtype=bool)
    part[5:20, 10:50] = part[20:35, 10:50] = True  # no gap between them
    vv, uu = np.mgrid[0:h, 0:w].astype(float)
    centre = np.zeros((2, h, w))
    for rows, cv in ((slice(5, 20), 12.0), (slice(20, 35), 27.0)):
        centre[0][rows, 10:50] = 29.5 - uu[rows, 10:50]
        centre[1][rows, 10:50] = cv - vv[rows, 10:50]
    masks = split_instances(part, centre)
    assert len(masks) == 2 and sorted(int(m.sum()) for m in masks) == [600, 600]
    assert any(m[5:20, 10:50].all() and not m[20:35].any() for m in masks)
    centre[0], centre[1] = 29.5 - uu, 19.5 - vv
    assert len(split_instances(part, centre)) == 1


def test_targets_flip_and_a_few_training_steps_reduce_the_loss() -> None:
    from train_perception import flip, losses

    views = render_cabinet(25, views=4)  # doors and a flap
    x = torch.from_numpy(np.stack([prepare_input(v.rgb, v.depth) for v in views]))
    targets = [
        view_targets(v.part_map, v.joint_type, v.axis_cam, v.T_camera_cabinet, v.handle_map)
        for v in views
    ]
    cls, centre, hinge, handle = (
        torch.from_numpy(np.stack([t[i] for t in targets])) for i in range(4)
    )
    # Centre offsets of a part's pixels point at its pixel centroid.
    pm = views[0].part_map[::2, ::2]
    k = int(np.bincount(pm[pm > 0]).argmax())
    _, uu = np.nonzero(pm == k)
    c = centre[0].numpy() * CENTRE_SCALE
    np.testing.assert_allclose((uu + c[0][pm == k]).std(), 0.0, atol=1e-3)
    assert (hinge >= 0).any() and set(torch.unique(hinge).tolist()) <= {-1, 0, 1, 2, 3}
    # Mirroring twice is the identity; once swaps left and right hinges.
    batch = (x, cls, centre, hinge, handle)
    assert all(torch.equal(a, b) for a, b in zip(flip(*flip(*batch)), batch, strict=True))
    _, _, c_f, h_f, _ = flip(*batch)
    assert torch.equal(c_f[:, 0], -centre[:, 0].flip(-1))
    side = hinge.flip(-1)
    assert torch.equal(h_f[side == 0], torch.ones_like(h_f[side == 0]))
    torch.manual_seed(0)
    net = ArticulationNet(8)
    opt = torch.optim.Adam(net.parameters(), lr=3e-3)
    first = None
    for _ in range(40):
        total, *_ = losses(net(x), cls, centre, hinge, handle)
        first = total.item() if first is None else first
        opt.zero_grad()
        total.backward()
        opt.step()
    assert total.item() < 0.6 * first


@pytest.mark.skipif(not WEIGHTS.exists(), reason="no trained weights in models/perception")
def test_shipped_weights_segment_an_unseen_cabinet() -> None:
    """The trained network on evaluation cabinets (seeds < 10,000, never trained on)."""
    net, stride = load_network(WEIGHTS)
    correct = total = 0
    for seed in (5, 9):
        for v in render_cabinet(seed, views=2):
            with torch.no_grad():
                out = net(torch.from_numpy(prepare_input(v.rgb, v.depth, stride))[None])[0]
            truth = class_targets(v.part_map[::stride, ::stride], v.joint_type)
            correct += (out[SL_CLASS].argmax(dim=0).numpy() == truth).sum()
            total += truth.size
    assert correct / total > 0.85
