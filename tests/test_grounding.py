"""Which grasp or placement of an action the robot goes on with
(:func:`strug_manip.domains.manipulation.grounding.first_feasible`), and how far an
opening goes (:func:`~strug_manip.domains.manipulation.grounding.longest_travel`)."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from strug_manip.control import Outcome, Status
from strug_manip.control.motion import GOAL_INVALID, NO_PLAN, START_INVALID, WALL_CAP_HIT
from strug_manip.domains.manipulation.grounding import (
    first_feasible,
    longest_travel,
)
from strug_manip.objects.generator import generate_cabinet


def outcome(status: Status, detail: str = "") -> Outcome:
    return Outcome(
        skill="Place", status=status, detail=detail, phase="reach", part_motion={},
        part_units={}, part_positions={}, cabinet_displacement=0.0, cabinet_motion=0.0,
        object_pose=np.eye(4), holding=True, times=np.zeros(1), qpos=np.zeros((1, 3)),
    )  # fmt: skip


def tried(outcomes: list[Outcome]) -> tuple[Outcome | None, int]:
    """first_feasible over runs returning ``outcomes`` in turn; the runs it made."""
    calls = []

    def run(o: Outcome) -> Outcome:
        calls.append(o)
        return o

    out = first_feasible((lambda o=o: run(o)) for o in outcomes)
    return out, len(calls)


def test_a_goal_that_touches_the_cabinet_passes_to_the_next_placement() -> None:
    blocked = outcome(Status.NO_MOTION_PLAN, f"{GOAL_INVALID}: contacts: cabinet/link_1/object")
    ok = outcome(Status.OK)
    assert blocked.cannot_reach and outcome(Status.IK_INFEASIBLE).cannot_reach
    assert tried([blocked, outcome(Status.IK_INFEASIBLE), ok, blocked]) == (ok, 3)
    # None reached: the last one's outcome says why.
    assert tried([outcome(Status.IK_INFEASIBLE), blocked]) == (blocked, 2)


def test_a_search_out_of_checks_passes_to_the_next_placement() -> None:
    # A goal in a narrow gap: the next placement may be reached (oracle OpenDrawer 9983).
    timeout = outcome(Status.NO_MOTION_PLAN, f"{NO_PLAN}: OMPL status: Timeout")
    ok = outcome(Status.OK)
    assert timeout.cannot_reach
    assert tried([timeout, timeout, ok]) == (ok, 3)


def test_a_plan_that_fails_for_another_reason_ends_the_action() -> None:
    # A start in contact is no fault of the placement, and a search the wall-clock cap
    # stopped is the load's: the robot stops there.
    capped = f"{NO_PLAN}: OMPL status: Timeout; {WALL_CAP_HIT}"
    for detail in (f"{START_INVALID}: contacts: a/b", capped):
        stop = outcome(Status.NO_MOTION_PLAN, detail)
        assert not stop.cannot_reach
        assert tried([stop, outcome(Status.OK)]) == (stop, 1)
    moved = outcome(Status.COLLISION)
    assert tried([moved, outcome(Status.OK)]) == (moved, 1)


def test_an_opening_goes_on_to_the_longest_limit_among_parts_that_move_alike() -> None:
    doors = generate_cabinet(7, kinds=("door",))
    door = next(p for p in doors.parts if p.joint_type == "revolute" and p.hinge == "left")
    drawer = next(
        p for p in generate_cabinet(11, kinds=("drawer",)).parts if p.joint_type == "prismatic"
    )
    variants = [
        dataclasses.replace(door, upper=1.6),
        dataclasses.replace(door, upper=1.9),
        dataclasses.replace(door, hinge="top", upper=2.5),  # another hinge: not counted
        dataclasses.replace(drawer, upper=0.4),
        door,
    ]
    w = SimpleNamespace(
        particles=[SimpleNamespace(spec=SimpleNamespace(part=lambda _l, p=p: p)) for p in variants]
    )
    links = ["link", "link", "link", "link", None]  # the last particle has no part there
    assert longest_travel(w, links, 0.5, variants[0]) == pytest.approx(1.4)
    assert longest_travel(w, links, 0.1, variants[3]) == pytest.approx(0.3)
    # No particle holds such a part: no travel beyond q.
    assert longest_travel(w, [None] * 5, 0.5, door) == 0.0
