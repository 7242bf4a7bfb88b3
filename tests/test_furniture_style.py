"""The generator's furniture style (what perception learns real furniture from), the
plain style unchanged, and the wood-grain finishes through URDF into MuJoCo."""

from __future__ import annotations

import hashlib
import warnings
from pathlib import Path

import mujoco
import numpy as np
import pytest

from planners.errors import ConfigError, UnknownNameError
from strug_manip.objects import generator as gen
from strug_manip.objects.finishes import GRAIN_COUNT, grain_image, grain_texture
from strug_manip.objects.generator import generate_cabinet, merge_cells
from strug_manip.objects.loader import load_articulated_object, load_cabinet_spec
from strug_manip.objects.partnet import cabinet_urdf, write_partnet
from strug_manip.world.perception_data import cabinet_style

#: sha256 of the plain cabinets' URDF texts, seeds 0-39 (all kinds, then drawers only),
#: taken before the furniture style existed: the tasks' cabinets must not change.
PLAIN_DIGEST = "5dad10a5471ee410c03c17818ce3372b10983fb0d635763eb93e3349a38053bd"


def _plain_digest() -> str:
    h = hashlib.sha256()
    for s in range(40):
        for kinds in (gen.PART_KINDS, ("drawer",)):
            h.update(cabinet_urdf(generate_cabinet(s, kinds=kinds)).encode())
    return h.hexdigest()


def test_the_plain_style_is_the_cabinets_of_before() -> None:
    assert _plain_digest() == PLAIN_DIGEST
    assert cabinet_urdf(generate_cabinet(7)) == cabinet_urdf(generate_cabinet(7, style="plain"))


def test_furniture_is_deterministic_and_differs_from_plain() -> None:
    a, b = generate_cabinet(11, style="furniture"), generate_cabinet(11, style="furniture")
    assert cabinet_urdf(a) == cabinet_urdf(b)
    assert cabinet_urdf(a) != cabinet_urdf(generate_cabinet(11))
    assert cabinet_urdf(a) != cabinet_urdf(generate_cabinet(12, style="furniture"))


def test_an_unknown_style_names_the_valid_ones() -> None:
    with pytest.raises(UnknownNameError, match="plain"):
        generate_cabinet(1, style="rococo")


@pytest.mark.parametrize("merge", list(gen.MERGES))
@pytest.mark.parametrize("rows, cols", [(1, 1), (1, 3), (2, 1), (3, 2), (4, 3)])
def test_merged_cells_cover_the_grid_once(merge: str, rows: int, cols: int) -> None:
    look = gen.draw_look(np.random.default_rng(0))
    for at in ((0.0, 0.0), (0.5, 0.5), (0.999, 0.999)):
        cells = merge_cells(look.__class__(**{**vars(look), "merge": merge, "merge_at": at}),
                            rows, cols)  # fmt: skip
        cover = np.zeros((rows, cols), dtype=int)
        for i, j, rs, cs in cells:
            cover[i : i + rs, j : j + cs] += 1
        assert (cover == 1).all(), (merge, at, cells)


def test_furniture_cabinets_are_real_furniture_and_stand_still() -> None:
    """Forty cabinets: what the style promises shows up, every part keeps its handle on
    its front, the mass stays in range, and each compiles and stands 0.5 s still."""
    seen = {"countertop": 0, "framed": 0, "merged": 0, "grain": 0, "finials": 0}
    for seed in range(40):
        spec = generate_cabinet(seed, style="furniture")
        names = [g.name for g in spec.body_geoms] + [g.name for p in spec.parts for g in p.geoms]
        seen["countertop"] += "countertop" in names
        seen["framed"] += any("_rail_" in n for n in names)
        tallest, widest = max(spec.row_heights) + 1e-9, max(spec.col_widths) + 1e-9
        seen["merged"] += any(
            p.cell_size[1] > tallest or p.cell_size[0] > widest for p in spec.parts
        )
        seen["grain"] += any(g.finish for g in spec.body_geoms)
        seen["finials"] += any(n.startswith("handle_end") for n in names)
        assert gen.TOTAL_MASS[0] - 1e-6 <= spec.mass <= gen.TOTAL_MASS[1] + 1e-6
        for p in spec.movable_parts:
            assert p.kind != "drawer" or p.cell_size[1] <= tallest, seed  # one row at most
            face = p.cell_center[0]
            if p.handle_pos is not None:  # on or in front of the closed front
                assert face - 0.03 <= p.handle_pos[0] <= face + 0.06
        obj = load_cabinet_spec(spec)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            data = mujoco.MjData(obj.mj_model)
            mujoco.mj_forward(obj.mj_model, data)
            start = data.qpos[:3].copy()
            for _ in range(250):
                mujoco.mj_step(obj.mj_model, data)
        assert np.linalg.norm(data.qpos[:3] - start) < 0.005, seed
        assert not any(data.warning[w].number for w in range(len(data.warning))), seed
    assert all(v >= 5 for v in seen.values()), seen


def test_grain_images_are_fixed_by_their_index(tmp_path: Path) -> None:
    a = grain_image(3)
    assert a.shape == (256, 256, 3) and a.dtype == np.uint8
    assert np.array_equal(a, grain_image(3)) and not np.array_equal(a, grain_image(4))
    assert grain_image(0).std() < grain_image(GRAIN_COUNT - 1).std()  # plain to figured
    path = grain_texture("grain_3", tmp_path)
    assert path.is_file() and path.suffix == ".png"
    with pytest.raises(ConfigError, match="grain_0"):
        grain_texture("marble", tmp_path)
    with pytest.raises(ConfigError, match=r"\[0, 8\)"):
        grain_image(GRAIN_COUNT)


def test_finishes_reach_mujoco_from_memory_and_from_a_written_folder(tmp_path: Path) -> None:
    spec = next(
        s for s in (generate_cabinet(k, style="furniture") for k in range(20))
        if any(g.finish for g in s.body_geoms)
    )  # fmt: skip
    assert load_cabinet_spec(spec).mj_model.ntex > 0
    folder = write_partnet(spec, tmp_path / "furniture")
    assert any((folder / "textures").glob("grain_*.png"))
    assert 'texture filename="textures/' in (folder / "mobility.urdf").read_text()
    obj = load_articulated_object(folder, progress=False, cache_dir=tmp_path / "cache")
    assert obj.mj_model.ntex > 0 and not obj.warnings


def test_training_styles_are_drawn_per_seed() -> None:
    styles = [cabinet_style(s, 0.5) for s in range(100_000, 100_400)]
    assert styles == [cabinet_style(s, 0.5) for s in range(100_000, 100_400)]
    assert 150 < styles.count("furniture") < 250
    assert {cabinet_style(s, 0.0) for s in range(50)} == {"plain"}
    with pytest.raises(ConfigError, match="furniture share"):
        cabinet_style(1, 1.5)


def test_furniture_drawers_are_short_and_wide_and_doors_tall() -> None:
    """The layout of real furniture: over 60 cabinets a drawer's front is wider than
    tall more often than a door's, and a short top row of drawers shows up."""
    aspects: dict[str, list[float]] = {"drawer": [], "door": []}
    short_top = 0
    for seed in range(60):
        spec = generate_cabinet(seed, style="furniture")
        for p in spec.movable_parts:
            if p.kind == "door" and p.hinge not in ("left", "right"):
                continue  # flaps are wide by nature
            aspects[p.kind].append(p.cell_size[1] / p.cell_size[0])
        short_top += spec.rows > 1 and spec.row_heights[0] <= gen.DRAWER_ROW[1] + 1e-9
    assert np.median(aspects["drawer"]) < 0.6 < np.median(aspects["door"]), {
        k: float(np.median(v)) for k, v in aspects.items()
    }
    assert short_top >= 10
    assert gen.kind_weights(0.3)["drawer"] > gen.kind_weights(1.5)["drawer"]


def _pull_offset(p: gen.PartSpec) -> tuple[float, float]:
    """A part's grasp point from its front's centre, in half-widths and half-heights."""
    c, s = p.cell_center, p.cell_size
    return (p.handle_pos[1] - c[1]) / (0.5 * s[0]), (p.handle_pos[2] - c[2]) / (0.5 * s[1])


def test_furniture_pulls_sit_where_real_furniture_puts_them() -> None:
    """Over 60 cabinets: drawer pulls raised toward the top edge (41083's) and side
    doors' horizontal pulls centred by the top edge (41083's) both show up; every bar
    stays on its front, and the grasp point is the bar's centre (as the plain style)."""
    raised = top_doors = 0
    for seed in range(60):
        spec = generate_cabinet(seed, style="furniture")
        for p in spec.movable_parts:
            if p.handle == "none" or (p.kind == "door" and p.hinge not in ("left", "right")):
                continue
            u, v = _pull_offset(p)
            horizontal = p.handle == "bar" and abs(p.handle_axis[1]) > 0.99
            raised += p.kind == "drawer" and v > 0.3
            top_doors += p.kind == "door" and horizontal and abs(u) < 0.05 and v > 0.3
            bars = [g for g in p.geoms if g.name == "handle_bar"]
            for g in bars:  # half extents (y, z) on the front
                if g.shape == "box":
                    extent = 0.5 * np.asarray(g.size[1:])
                else:
                    extent = np.where(np.array(["y", "z"]) == g.axis, 0.5 * g.size[1], g.size[0])
                at = np.asarray(g.pos) + p.origin - p.cell_center
                assert np.all(np.abs(at[1:]) + extent <= 0.5 * p.cell_size + 1e-9), (seed, p.link)
            if bars and g.shape == "cylinder":
                np.testing.assert_allclose(np.asarray(g.pos)[1:] + p.origin[1:], p.handle_pos[1:])
    assert raised >= 5 and top_doors >= 3, (raised, top_doors)


def test_raised_drawer_pulls_only_on_fronts_that_read_as_furniture() -> None:
    """A raised drawer pull on a flat-coloured slab is what a plain flap's pull looks
    like; over 80 cabinets every raised drawer pull sits on a framed or figured-grain
    front, and looks that raise pulls keep them centred on their plain-looking fronts."""
    raised = kept_centred = 0
    for seed in range(80):
        spec = generate_cabinet(seed, style="furniture")
        look = gen.draw_look(np.random.default_rng([seed, 1]))
        for p in spec.movable_parts:
            if p.kind != "drawer" or p.handle == "none":
                continue
            _, v = _pull_offset(p)
            furniture = look.reads_as_furniture(*(float(x) for x in p.cell_size))
            if v > 0.3:
                raised += 1
                assert furniture, (seed, p.link, look.drawer_design, look.finishes["front"])
            elif look.drawer_pull_v > 0.0 and not furniture:
                kept_centred += 1
    assert raised >= 5 and kept_centred >= 3, (raised, kept_centred)
