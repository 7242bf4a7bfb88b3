"""``tools/eval_hinge_offset.py``: the hinge errors it applies, its table and its
resumable records (one seed's doors, run for real)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from strug_manip.objects.hypotheses import BelievedJoint

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import eval_hinge_offset as H  # noqa: E402, N812

#: A left-hinged door's joint: the hinge at y = -0.2 m, the handle at y = +0.1 m.
DOOR = BelievedJoint("revolute", np.array([0.0, 0.0, 1.0]), np.array([0.9, -0.2, 0.5]), limit=1.8)
GRASP = np.eye(4)  # approaching along +x (into the front), the handle 2 cm out of it
GRASP[:3, 3] = (0.88, 0.1, 0.8)


def test_each_hinge_error_moves_the_hinge_as_named() -> None:
    toward = H.offset_joint(DOOR, GRASP, "radial", 0.02)
    assert np.allclose(toward.origin - DOOR.origin, [0.0, 0.02, 0.0])  # toward the handle
    assert np.allclose(toward.axis, DOOR.axis) and toward.limit == DOOR.limit
    out = H.offset_joint(DOOR, GRASP, "depth", 0.02)
    assert np.allclose(out.origin - DOOR.origin, [-0.02, 0.0, 0.0])  # toward the robot
    for kind, turned_about in (("tilt-in", 0), ("tilt-out", 1)):
        tilted = H.offset_joint(DOOR, GRASP, kind, 5.0)
        assert np.degrees(np.arccos(tilted.axis @ DOOR.axis)) == pytest.approx(5.0)
        # Turned about the front's normal (in the front) or its in-plane direction.
        assert abs(tilted.axis[turned_about]) < 1e-12
        # The hinge line still passes where it did at the handle's height.
        s = (GRASP[2, 3] - tilted.origin[2]) / tilted.axis[2]
        assert np.allclose(tilted.origin + s * tilted.axis, [0.9, -0.2, GRASP[2, 3]])
    assert H.offset_joint(DOOR, GRASP, "radial", 0.0).origin.tolist() == DOOR.origin.tolist()


def test_one_seed_is_measured_recorded_and_resumed(tmp_path, capsys, monkeypatch) -> None:
    monkeypatch.setattr(H, "VARIANTS", H.VARIANTS[:2])  # the true hinge and 1 cm off
    assert H.main(["--seeds", "3000:3001", "--out", str(tmp_path)]) == 0
    (row,) = [json.loads(line) for line in (tmp_path / "results.jsonl").read_text().splitlines()]
    assert row["seed"] == 3000 and len(row["parts"]) == 3
    for part in row["parts"]:
        assert set(part["runs"]) == {name for name, _, _ in H.VARIANTS}
        assert part["runs"]["true"]["ok"], part
    first = capsys.readouterr().out
    assert "| true |" in first
    # A rerun reads the record back instead of running the seed again.
    assert H.main(["--seeds", "3000:3001", "--out", str(tmp_path)]) == 0
    assert capsys.readouterr().out.split("\n", 1)[1] == first.split("\n", 1)[1]
