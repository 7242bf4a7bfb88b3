"""Issue 37: the full robot's arm motions try a wide berth first, then the usual
clearances, then touching nothing (:func:`~strug_manip.control.executor.clear_first`).

A reach that kept its 2 cm from a believed neighbour door put the carried object on the
real one and slid the cabinet (OpenDoor episode 10187); ``wide_clearance`` is tried
before the clearances that keep only the arm's lag.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import numpy as np
import pytest

from strug_manip.control import Outcome, Pick, fetch_body
from strug_manip.control.executor import clear_first
from strug_manip.control.motion import NO_PLAN, MotionPlan
from strug_manip.control.navigation import plan_route
from strug_manip.control.params import DEFAULT_PARAMS
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

#: Two planners' stand-ins (only their order matters here).
PLANNERS = ("first", "second")


def plan(success: bool) -> MotionPlan:
    """A plan that succeeded, or ran out of its budget."""
    if success:
        return MotionPlan(True, ("j",), np.zeros((2, 1)), 0.0, 0.0)
    return MotionPlan(False, ("j",), np.zeros((0, 1)), float("nan"), 0.0, NO_PLAN)


def rounds_tried(succeeds_in: str, wide: bool) -> list[tuple[str, str, int]]:
    """(round, planner, budget) in the order :func:`clear_first` tries them, each plan
    failing for its budget until the round ``succeeds_in``."""
    tried: list[tuple[str, str, int]] = []
    now = ["plain"]

    @contextlib.contextmanager
    def inside(name: str) -> Iterator[None]:
        now[0] = name
        try:
            yield
        finally:
            now[0] = "plain"

    def run(i: int, planner: str, checks: int, in_wide: bool) -> MotionPlan:
        tried.append((now[0], planner, checks))
        return plan(now[0] == succeeds_in)

    def clear(room: bool) -> contextlib.AbstractContextManager[None]:
        return inside("room" if room else "touch at the ends")

    clear_first(PLANNERS, run, clear, DEFAULT_PARAMS, (lambda: inside("wide")) if wide else None)
    return tried


def test_the_wide_berth_is_tried_first_and_capped() -> None:
    cap = DEFAULT_PARAMS.clear_checks
    tried = rounds_tried("room", wide=True)
    assert [(r, p) for r, p, _ in tried] == [
        ("wide", "first"), ("wide", "second"), ("room", "first"),
    ]  # fmt: skip
    assert all(checks <= cap for _, _, checks in tried)


def test_the_rounds_without_a_wide_berth_are_unchanged() -> None:
    tried = rounds_tried("plain", wide=False)
    assert [r for r, _, _ in tried] == ["room"] * 2 + ["touch at the ends"] * 2 + ["plain"]
    assert tried[-1][2] == DEFAULT_PARAMS.planner_checks(0, len(PLANNERS))


def test_a_wide_berth_that_finds_nothing_falls_back_to_touching_nothing() -> None:
    tried = rounds_tried("plain", wide=True)
    assert [r for r, _, _ in tried] == (
        ["wide"] * 2 + ["room"] * 2 + ["touch at the ends"] * 2 + ["plain"]
    )


def pick_at_the_table(ctx) -> Outcome:
    """The full robot's side Pick from its start, in the doors-only scene of generator
    seed 25 (it drives to the object's table, then reaches)."""
    world = ManipulationWorld(SceneConfig(cabinet_seed=25, cabinet_kinds=("door",)))
    try:
        world.reset()
        return Pick("object", "side").run(world, ctx=ctx)
    finally:
        world.close()


def test_the_full_robots_arm_motions_ask_for_the_wide_berth(monkeypatch, ctx) -> None:
    """The reach (and the stow before the drive) of a Pick plan with the wide round."""
    asked: list[bool] = []

    def spy(planners, run, clear, params, wide=None) -> MotionPlan:
        asked.append(wide is not None)
        return clear_first(planners, run, clear, params, wide)

    monkeypatch.setattr(fetch_body, "clear_first", spy)
    out = pick_at_the_table(ctx)
    assert out.ok, out.summary()
    assert asked and all(asked), asked


def test_the_full_robots_route_keeps_the_wide_berth_where_it_can(monkeypatch, ctx) -> None:
    """The base's route is planned first with the scene's geoms kept ``wide_clearance``
    off (their collision margin): it passes the doors the robot swung open, which
    perception puts centimetres off."""
    margins: list[float] = []

    def spy(checker, start, goal, arm):
        margins.append(float(checker.model.geom_margin.max()))
        return plan_route(checker, start, goal, arm)

    monkeypatch.setattr(fetch_body, "plan_route", spy)
    out = pick_at_the_table(ctx)
    assert out.ok, out.summary()
    assert margins and margins[0] == pytest.approx(DEFAULT_PARAMS.wide_clearance), margins
