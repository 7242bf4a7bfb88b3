"""The command line without rough edges: one-line errors, Ctrl-C, --help, the run header."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import strug_manip.cli as cli
import strug_manip.experiments.bench as bench
from strug_manip.cli import build_parser, main

REPO = Path(__file__).resolve().parents[1]


def _one_error_line(argv: list[str], capsys) -> str:
    """Run ``strug argv``; assert exit 2 and exactly one ``strug: error:`` line on stderr."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's errors
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("strug: error: "), err
    assert "Traceback" not in err and "usage:" not in err
    return lines[0]


@pytest.fixture
def odd_dirs(tmp_path: Path) -> Path:
    (tmp_path / "a_file.md").write_text("not a directory\n")
    (tmp_path / "corrupt").mkdir()
    (tmp_path / "corrupt" / "run.json").write_text('{"overrides": ')
    (tmp_path / "foreign").mkdir()
    (tmp_path / "foreign" / "results.jsonl").write_text('{"loss": 0.1, "epoch": 3}\n')
    (tmp_path / "a_dir").mkdir()
    return tmp_path


BENCH = ["bench", "--domains", "tiger", "--solvers", "random", "--seeds", "1", "--no-progress"]
RUN = ["run", "--domain", "tiger", "--solver", "random"]

ERROR_CASES = {
    "bench --out FILE": ([*BENCH, "--out", "{d}/a_file.md"], "a_file.md is a file"),
    "bench --out FILE/sub": ([*BENCH, "--out", "{d}/a_file.md/sub"], "a_file.md is a file"),
    "run --rerun DIR": ([*RUN, "--rerun", "{d}/a_dir"], "a_dir/out.rrd"),
    "run --rerun x.txt": ([*RUN, "--rerun", "{d}/x.txt"], ".rrd"),
    "run --rerun FILE/x.rrd": ([*RUN, "--rerun", "{d}/a_file.md/x.rrd"], "a_file.md is a file"),
    "scene --out DIR": (["scene", "--out", "{d}/a_dir"], "is a directory"),
    "scene --out x.txt": (["scene", "--out", "{d}/x.txt"], ".png"),
    "resume corrupt run.json": ([*BENCH, "--out", "{d}/corrupt", "--resume"], "run.json"),
    "resume foreign results": ([*BENCH, "--out", "{d}/foreign", "--resume"], "not a bench"),
    "--sims x": ([*RUN, "--sims", "x"], "--sims"),
    "--sims 0": ([*RUN, "--sims", "0"], "--sims"),
    "--time -1": ([*RUN, "--time", "-1"], "--time"),
    "--time nan": ([*RUN, "--time", "nan"], "--time"),
    "--particles 0": ([*RUN, "--particles", "0"], "--particles"),
    "--seed -1": ([*RUN, "--seed", "-1"], "--seed"),
    "bench --workers 0": ([*BENCH, "--out", "{d}/w", "--workers", "0"], "--workers"),
    "bench --seeds 0": (
        ["bench", "--domains", "tiger", "--solvers", "random", "--seeds", "0", "--out", "{d}/s"],
        "--seeds",
    ),
    "missing --solver": (["run", "--domain", "tiger"], "--solver"),
    "unknown command": (["frobnicate"], "invalid choice"),
    "unknown domain": (["run", "--domain", "nope", "--solver", "random"], "package.module:Class"),
    "user domain not a class": (
        ["run", "--domain", "os.path:join", "--solver", "random"],
        "not a GenerativePOMDP",
    ),
    "user domain no module": (
        ["run", "--domain", "no_such_mod:X", "--solver", "random"],
        "cannot import",
    ),
    "--set without =": ([*RUN, "--set", "depth"], "NAME=VALUE"),
    "--address without ray": ([*BENCH, "--out", "{d}/a", "--address", "auto"], "--executor ray"),
    "ray --address nobody": (
        [*BENCH, "--out", "{d}/r", "--executor", "ray", "--address", "127.0.0.1:1"],
        "Ray",  # no cluster there, or Ray not installed: one line either way
    ),
}


@pytest.mark.parametrize("case", list(ERROR_CASES))
def test_bad_input_is_one_line_and_exit_2(case: str, odd_dirs: Path, capsys) -> None:
    argv, needle = ERROR_CASES[case]
    line = _one_error_line([a.replace("{d}", str(odd_dirs)) for a in argv], capsys)
    assert needle in line
    for field in ("n_particles", "time_limit"):  # the flags, not the config fields
        assert field not in line


@pytest.mark.slow
def test_scene_unknown_camera_lists_the_cameras(tmp_path: Path, capsys) -> None:
    """Slow only because it builds the robot world (a few seconds)."""
    line = _one_error_line(["scene", "--camera", "foo", "--out", str(tmp_path / "s.png")], capsys)
    assert "--camera" in line and "overview" in line and "head_camera" in line


def test_scene_camera_is_checked_before_rendering(tmp_path: Path, capsys, monkeypatch) -> None:
    """The camera check runs on the built world, before any image is rendered or written."""

    class FakeWorld:
        def __init__(self, config) -> None:
            pass

        def camera_pose(self, camera: str):
            from planners.errors import UnknownNameError

            raise UnknownNameError("camera", camera, ["overview", "head_camera"])

        def close(self) -> None:
            pass

    import strug_manip.world as world

    monkeypatch.setattr(world, "ManipulationWorld", FakeWorld)
    out = tmp_path / "s.png"
    line = _one_error_line(["scene", "--camera", "foo", "--out", str(out)], capsys)
    assert line == (
        "strug: error: --camera: unknown camera 'foo'; expected one of: overview, head_camera"
    )
    assert not out.exists()


def test_ctrl_c_in_run_does_not_offer_resume(capsys, monkeypatch) -> None:
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "run_episode", interrupted)
    assert main([*RUN, "--sims", "10"]) == 130
    err = capsys.readouterr().err
    assert "the episode did not finish" in err and "--resume" not in err


def test_ctrl_c_in_bench_says_what_was_kept(tmp_path: Path, capsys, monkeypatch) -> None:
    real, calls = bench.run_task, []

    def two_then_interrupt(*args, **kwargs):
        calls.append(1)
        if len(calls) > 2:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(bench, "run_task", two_then_interrupt)
    argv = ["bench", "--domains", "tiger", "--solvers", "random", "--seeds", "5",
            "--out", str(tmp_path), "--workers", "1", "--no-progress"]  # fmt: skip
    assert main(argv) == 130
    err = capsys.readouterr().err
    assert f"2 finished episodes are kept in {tmp_path / 'results.jsonl'}" in err
    assert "--resume" in err
    assert len(bench.load_results(tmp_path)) == 2


def test_help_lists_every_command_and_option_without_rst(capsys) -> None:
    parser = build_parser()
    with pytest.raises(SystemExit):
        main(["--help"])
    top = capsys.readouterr().out
    sub = next(a for a in parser._actions if a.dest == "command")
    for name, subparser in sub.choices.items():
        assert f"strug {name}" in top
        for action in subparser._actions:
            for flag in action.option_strings:
                assert flag in top, (name, flag)
        with pytest.raises(SystemExit):
            main([name, "--help"])
        assert "``" not in capsys.readouterr().out
    assert "``" not in top and ":func:" not in top


def test_sims_with_time_stops_at_the_first(capsys) -> None:
    """Documented in --help: with both budgets a decision stops at whichever comes first."""
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert "whichever comes first" in " ".join(sub.choices["run"].format_help().split())
    argv = [*RUN[:-1], "pomcp", "--sims", "50", "--time", "30", "--json"]
    assert main(argv) == 0
    steps = [json.loads(x) for x in capsys.readouterr().out.splitlines()][:-1]
    assert steps and all(s["sims"] == 50 for s in steps)


def test_run_header_shows_resolved_values(capsys) -> None:
    assert main(["run", "--domain", "tigerclassic", "--solver", "pomcp", "--sims", "20"]) == 0
    header = capsys.readouterr().out.splitlines()[0]
    assert "=None" not in header.replace("time_limit=None", "")
    assert "depth=10 (domain's)" in header and "c=100 (domain's)" in header
    assert "discount=0.95 (domain's)" in header
    assert main(["run", "--domain", "tigerclassic", "--solver", "pomcp", "--sims", "20",
                 "--set", "depth=4", "--set", "exploration=normalized"]) == 0  # fmt: skip
    header = capsys.readouterr().out.splitlines()[0]
    assert "depth=4," in header and "c=unused" in header


def test_demo_closing_hint_is_a_valid_command() -> None:
    argv = cli.FULL_TABLE_COMMAND.split()[1:]
    args = build_parser().parse_args(argv)
    assert args.command == "bench" and args.seeds == 100
    bench.BenchSpec(tuple(args.domains.split(",")), tuple(args.solvers.split(",")), args.seeds)
