"""``tools/eval_place_offset.py``: the believed cabinets it moves, its table and its
resumable records (one seed's doors, run for real)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import eval_place_offset as P  # noqa: E402, N812


def test_each_variant_moves_the_believed_cabinet_as_named() -> None:
    config = SceneConfig(cabinet_seed=3000, cabinet_kinds=("door",))
    true = ManipulationWorld(config)
    T = true.scene.T_world_cabinet
    for name, shift in P.VARIANTS[1:]:
        pw = P.believed_world(config, shift)
        moved = pw.scene.T_world_cabinet
        np.testing.assert_allclose(moved[:3, 3] - T[:3, 3], shift, atol=1e-9, err_msg=name)
        np.testing.assert_allclose(moved[:3, :3], T[:3, :3], atol=1e-12)
        assert pw.scene.cabinet_spec.seed == true.scene.cabinet_spec.seed
        pw.close()
    true.close()
    names = [n for n, _ in P.VARIANTS]
    assert names[0] == "true" and len(set(names)) == len(names)


def test_one_seed_is_measured_recorded_and_resumed(tmp_path, capsys, monkeypatch) -> None:
    monkeypatch.setattr(P, "VARIANTS", P.VARIANTS[:2])  # the true cabinet and 1 cm low
    monkeypatch.setattr(P, "KINDS", ("door",))
    assert P.main(["--seeds", "3000:3001", "--out", str(tmp_path)]) == 0
    (row,) = [json.loads(line) for line in (tmp_path / "results.jsonl").read_text().splitlines()]
    assert row["seed"] == 3000 and len(row["parts"]) >= 2
    for part in row["parts"]:
        assert part["pick"] == "ok" and set(part["runs"]) == {n for n, _ in P.VARIANTS}
        assert part["runs"]["true"]["ok"], part
    first = capsys.readouterr().out
    assert "| true |" in first and "| down 1 cm |" in first
    # A rerun reads the record back instead of running the seed again.
    assert P.main(["--seeds", "3000:3001", "--out", str(tmp_path)]) == 0
    assert capsys.readouterr().out.split("\n", 1)[1] == first.split("\n", 1)[1]
