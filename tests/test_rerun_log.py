"""The rerun recordings of the toy domains: geometry, observations, labelled Q bars, the
Q table and the blueprint (the layout the viewer opens with)."""

from __future__ import annotations

from pathlib import Path

import pytest

from strug_manip.cli import main
from strug_manip.experiments.episode import StepRecord
from strug_manip.experiments.rerun_log import BAR_WIDTH, TOY_VIEWS, q_table, text_bar


def _entities(path: Path) -> dict[str, dict[str, list]]:
    """entity path -> component column -> the values of its first row."""
    from rerun.chunk import RrdReader

    out: dict[str, dict[str, list]] = {}
    for chunk in RrdReader(path).stream().to_chunks():
        batch = chunk.to_record_batch()
        cols = out.setdefault(chunk.entity_path, {})
        for name in batch.schema.names:
            if ":" in name and name not in cols and batch.num_rows:
                cols[name] = batch.column(name)[0].as_py()
    return out


@pytest.mark.parametrize(
    ("domain", "geometry"),
    [
        ("lightdark2d", {"/world/room", "/world/goal", "/world/x_light", "/world/y_light"}),
        ("lightdark1d", {"/world/goal", "/world/light"}),
        ("tiger", {"/world/doors"}),
    ],
)
def test_recording_has_geometry_observations_and_labelled_bars(
    domain: str, geometry: set[str], tmp_path: Path, capsys
) -> None:
    path = tmp_path / f"{domain}.rrd"
    assert main(["run", "--domain", domain, "--solver", "pomcpow", "--sims", "100",
                 "--rerun", str(path)]) == 0  # fmt: skip
    ents = _entities(path)
    assert geometry <= set(ents), sorted(ents)
    assert "/world/observation" in ents and "/world/true_state" in ents
    labels = ents["/search/q_root"]["Boxes2D:labels"]
    q_lines = [x for x in capsys.readouterr().out.splitlines() if "Q/N at root" in x]
    first_action = q_lines[0].split("Q/N at root: ")[1].split(":")[0]
    assert labels[0].startswith(first_action)  # the bars carry the action names
    if domain == "lightdark2d":
        assert ents["/world/goal"]["Boxes2D:labels"] == ["goal |x-5|<0.5"]
        assert ents["/world/observation"]["Points2D:labels"][0].startswith("observed (")


def _blueprint_views(path: Path) -> dict[str, tuple[str, str]]:
    """The recording's blueprint: view title -> (view class, origin)."""
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    (store,) = reader.blueprints()
    views: dict[str, tuple[str, str]] = {}
    for chunk in reader.stream(store=store).to_chunks():
        batch = chunk.to_record_batch()
        if "ViewBlueprint:display_name" in batch.schema.names:
            name, kind, origin = (
                batch.column(f"ViewBlueprint:{c}")[-1].as_py()[0]
                for c in ("display_name", "class_identifier", "space_origin")
            )
            views[name] = (kind, "/" + origin.strip("/"))
    return views


def _timelines(path: Path) -> set[str]:
    """The names of the recording's timelines."""
    from rerun.chunk import RrdReader

    out: set[str] = set()
    for chunk in RrdReader(path).stream().to_chunks():
        names = chunk.to_record_batch().schema.names  # components: Archetype:field
        out |= {n for n in names if ":" not in n and not n.startswith("rerun.")}
    return out


def test_recording_carries_a_blueprint_with_named_views_and_a_q_table(tmp_path: Path) -> None:
    path = tmp_path / "tiger.rrd"
    assert main(["run", "--domain", "tiger", "--solver", "pomcpow", "--sims", "50",
                 "--seed", "0", "--rerun", str(path)]) == 0  # fmt: skip
    views = _blueprint_views(path)
    assert set(views) == set(TOY_VIEWS), sorted(views)  # the Tiger has them all
    assert views["world"] == ("2D", "/world")
    assert views["step log"] == ("TextLog", "/log")
    assert views["Q per action"] == ("TextDocument", "/search/q_table")
    assert _timelines(path) == {"step"}  # no wall-clock log_time
    table = _entities(path)["/search/q_table"]["TextDocument:text"][0]
    assert "| listen |" in table.replace("**", "") and "\u25b6" in table


def test_text_bar_and_q_table() -> None:
    assert text_bar(1.0, 1.0) == "\u2588" * BAR_WIDTH
    assert text_bar(0.0, 1.0) == text_bar(0.3, 0.0) == "\u00b7"
    assert text_bar(-0.5, 1.0) == "\u2212" + "\u2588" * (BAR_WIDTH // 2)
    assert text_bar(5.0, 1.0) == text_bar(1.0, 1.0)  # clipped at the top
    rec = StepRecord(step=3, action="b|c", observation="o", reward=0.0, sims=1,
                     plan_seconds=0.0, tree_nodes=1, belief="",
                     q={"a": -2.0, "b|c": 1.0}, visits={"a": 4}, bonus={"b|c": 0.5})  # fmt: skip
    lines = q_table(rec).splitlines()
    assert lines[0].startswith("step 3")
    assert lines[-2].startswith("|  | a | \u2212" + "\u2588" * BAR_WIDTH + " | -2.00 | 4 |  |")
    assert lines[-1].startswith("| \u25b6 | **b\\|c** |") and lines[-1].endswith("| 0 | +0.500 |")
