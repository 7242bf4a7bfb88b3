"""The rerun recordings of the toy domains: geometry, observations, labelled Q bars."""

from __future__ import annotations

from pathlib import Path

import pytest

from strug_manip.cli import main


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
