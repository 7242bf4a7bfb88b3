"""Handle grasps (:func:`strug_manip.control.grasps.handle_grasps`) and where the object
goes (:func:`strug_manip.control.targets.place_target`, judged by the manipulation
domain's rules).

Cabinets (object frame: +x out of the front): generator seed 11 drawers (bar handles
along y), seed 17 (a left-hinged door ``link_3`` with a vertical bar, a top flap
``link_9``), seed 2 doors (knobs: the right-hinged ``link_1``), seed 7 doors (no handles).
"""

from __future__ import annotations

import numpy as np
import pytest

from planners.errors import ConfigError, UnknownNameError
from strug_manip.control import (
    flip_fingers,
    handle_grasps,
    held_grasp,
    place_target,
    place_targets,
)
from strug_manip.control.grasps import (
    FACE_CLEARANCE,
    MIN_KNOB_GRIP,
    PAD_CORNERS,
    PITCHES,
    front_of_handle,
    knob_end,
    max_back_off,
)
from strug_manip.control.targets import CLEARANCE, FINGER_SPAN, HELD_HEIGHT
from strug_manip.domains.manipulation.rules import DRAG_LIMIT, dragged, inside, open_enough
from strug_manip.geometry import axis_angle
from strug_manip.objects.generator import generate_cabinet
from strug_manip.objects.hypotheses import check_pose
from strug_manip.world.scene import OBJECT_HALF_SIZE

FRONT = np.array([1.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def cabinets():
    return {
        "drawers_11": generate_cabinet(11, kinds=("drawer",)),
        "mixed_17": generate_cabinet(17),
        "doors_2": generate_cabinet(2, kinds=("door",)),
        "doors_7": generate_cabinet(7, kinds=("door",)),
    }


def check_grasps(part, gs, q: float = 0.0, T: np.ndarray | None = None) -> None:
    T = np.eye(4) if T is None else T
    R_part = axis_angle(part.axis, q) if part.joint_type == "revolute" else np.eye(3)
    normal = T[:3, :3] @ R_part @ FRONT
    assert gs
    for g in gs:
        check_pose("grasp", g)
        # The TCP on the handle's grasp point, or backed off it along the front's normal
        # (never more than keeps the handle inside the pads).
        off = g[:3, 3] - part.handle_at(q, T)
        np.testing.assert_allclose(off, (off @ normal) * normal, atol=1e-12)
        assert -1e-12 <= off @ normal <= max_back_off(part) + 1e-12
        # The approach (x) into the front, pitched by one of the pitches about the front's
        # horizontal axis; the fingers (y) pointing up, or level toward +y.
        pitch = float(np.arccos(np.clip(g[:3, 0] @ -normal, -1.0, 1.0)))
        assert min(abs(pitch - abs(p)) for p in (0.0, *PITCHES)) < 1e-9
        assert abs(g[2, 0]) == pytest.approx(np.sin(pitch) * np.hypot(*normal[:2]), abs=1e-9)
        assert g[2, 1] > -1e-9


def pads_clear_the_front(part, g: np.ndarray) -> bool:
    """Every corner of the open finger pads stays in front of the part's front face (the
    closed part, object frame) by at least the grasp's clearance."""
    corners = g[:3, 3] + PAD_CORNERS @ g[:3, :3].T
    return bool(np.all(corners[:, 0] >= front_of_handle(part) + FACE_CLEARANCE - 1e-9))


def test_bar_grasps_straddle_the_bar(cabinets) -> None:
    for name, link in (("drawers_11", "link_1"), ("mixed_17", "link_3"), ("mixed_17", "link_9")):
        part = cabinets[name].part(link)
        assert part.handle == "bar"
        gs = handle_grasps(part)
        check_grasps(part, gs)
        # The level grasp always; a pitched one where the open pads clear the front.
        assert 1 <= len(gs) <= 1 + len(PITCHES)
        assert abs(gs[0][2, 0]) < 1e-9  # level first
        for g in gs:
            assert abs(g[:3, 1] @ part.handle_axis) < 1e-9  # fingers across the bar
            assert pads_clear_the_front(part, g)
    # A horizontal drawer bar: the fingers open vertically; the door's vertical bar:
    # horizontally.
    assert abs(handle_grasps(cabinets["drawers_11"].part("link_1"))[0][2, 1]) == pytest.approx(1)
    assert abs(handle_grasps(cabinets["mixed_17"].part("link_3"))[0][2, 1]) < 1e-9


def test_grasps_follow_an_open_door_and_the_cabinet_frame(cabinets) -> None:
    part = cabinets["mixed_17"].part("link_3")
    T = np.eye(4)
    T[:3, :3] = axis_angle(np.array([0.0, 0.0, 1.0]), np.pi)  # facing the robot
    T[:3, 3] = (1.2, 0.1, 0.5)
    for q in (0.0, 0.6):
        gs = handle_grasps(part, q, T)
        check_grasps(part, gs, q, T)


def test_knob_grasps_offer_both_finger_directions(cabinets) -> None:
    part = cabinets["doors_2"].part("link_1")
    assert part.handle == "knob" and part.hinge == "right"
    gs = handle_grasps(part)
    check_grasps(part, gs)
    assert all(pads_clear_the_front(part, g) for g in gs)
    # First as a side door's bar is held (the fingers open horizontally: a vertical bar
    # perception took for a knob is held too), then the other way (vertically).
    assert abs(gs[0][2, 1]) < 1e-9
    assert any(abs(g[2, 1]) == pytest.approx(1.0) for g in gs[1:])


def test_a_drawers_knob_is_first_held_as_the_horizontal_bar_a_drawer_has() -> None:
    """A drawer's knob is first straddled with the fingers opening vertically, as a
    drawer's bar (always horizontal) is: a bar perception took for a knob is then held
    too (OpenDrawer 10047, 10049, 10067 closed the fingers on such a bar, opening
    horizontally along it). Then the other way, horizontally."""
    cab = generate_cabinet(11, kinds=("drawer",), handles=("knob",))
    part = cab.movable_parts[0]
    assert part.handle == "knob" and part.joint_type == "prismatic"
    gs = handle_grasps(part)
    check_grasps(part, gs)
    # The finger opening (gripper y) across a horizontal bar has no y component,
    # pitched or not; opening horizontally it is along y.
    across = [abs(g[1, 1]) < 1e-9 for g in gs]
    along = [abs(g[1, 1]) == pytest.approx(1.0) for g in gs]
    n = across.index(False)
    assert n > 0 and all(along[n:]) and all(across[:n])
    bar = generate_cabinet(11, kinds=("drawer",), handles=("bar",)).movable_parts[0]
    assert abs(bar.handle_axis[1]) > 0.99  # the bar the knob's first grasps are as
    assert all(abs(g[1, 1]) < 1e-9 for g in handle_grasps(bar))


def test_every_handle_the_generator_makes_can_be_grasped() -> None:
    # Short knobs (0.02 m) once had no grasp: the pads reached the front before the
    # TCP reached the grasp point, and backing off left the grasp point outside them.
    for seed in range(120):
        for kind in ("drawer", "door"):
            for part in generate_cabinet(seed, kinds=(kind,)).movable_parts:
                if part.handle == "none":
                    continue
                gs = handle_grasps(part)
                assert gs, f"seed {seed} {kind} {part.link}: no grasp of its {part.handle}"
                if part.handle == "knob":
                    # The level grasp keeps MIN_KNOB_GRIP of the knob between the tips
                    # (PAD_CORNERS[0, 0] in front of the TCP) and the knob's end.
                    tips = gs[0][0, 3] + PAD_CORNERS[0, 0] * gs[0][0, 0]
                    assert knob_end(part) - tips >= MIN_KNOB_GRIP - 1e-12


def test_a_flat_front_has_no_grasp_and_flips_keep_the_grasp(cabinets) -> None:
    assert all(handle_grasps(p) == [] for p in cabinets["doors_7"].movable_parts)
    g = handle_grasps(cabinets["drawers_11"].part("link_1"))[0]
    f = flip_fingers(g)
    np.testing.assert_array_equal(f[:3, 0], g[:3, 0])
    np.testing.assert_array_equal(f[:3, 1:3], -g[:3, 1:3])
    np.testing.assert_array_equal(flip_fingers(f), g)
    top = np.eye(4)
    top[:3, :3] = axis_angle(np.array([0.0, 1.0, 0.0]), -np.pi / 2)  # its up: -approach
    assert held_grasp(top) == "top" and held_grasp(np.eye(4)) == "side"


def test_place_targets_are_inside_and_open_enough_is_the_targets_rule(cabinets) -> None:
    spec = cabinets["drawers_11"]
    T = np.eye(4)
    t = place_target(spec, "link_1", 0.2, T)
    assert t.grasp == "top" and t.lift > 0.0  # lowered from above the walls
    assert inside(spec, "link_1", 0.2, T, t.p) and open_enough(spec, "link_1", 0.2, T)
    assert not inside(spec, "link_1", 0.0, T, t.p)  # the drawer took it out with it
    with pytest.raises(ConfigError, match=r"drawer link_1 is out -?0\.0\d\d m"):
        place_target(spec, "link_1", 0.0, T)
    assert not open_enough(spec, "link_1", 0.0, T)
    door = cabinets["mixed_17"]
    t = place_target(door, "link_5", 1.4, T)
    assert t.grasp == "side" and t.lift >= 0.0
    assert inside(door, "link_5", 1.4, T, t.p)
    # Carried in midway up the opening: the palm as far under the cell's top as the
    # object's bottom over its floor (a side door swung open leaves the full height).
    cell = door.part("link_5")
    top = cell.interior_center[2] + cell.interior_size[2] / 2
    bottom = t.p[2, 3] - OBJECT_HALF_SIZE[2]  # where it rests (the cell's floor)
    palm = bottom + t.lift + HELD_HEIGHT
    assert top - palm == pytest.approx(t.lift, abs=1e-9) and t.lift > CLEARANCE
    with pytest.raises(ConfigError, match="cell link_5 leaves"):
        place_target(door, "link_5", 0.1, T)
    with pytest.raises(UnknownNameError):
        place_target(door, "link_99", 0.1, T)
    assert not dragged(DRAG_LIMIT) and dragged(DRAG_LIMIT + 1e-6)


def test_a_drawer_offers_a_second_place_nearer_its_front_wall(cabinets) -> None:
    """The second target of an open drawer keeps the object inside, CLEARANCE from the
    front wall (farther from the fronts above); both are lowered into from ABOVE_WALLS
    over the drawer's front where it stands over the walls, then from ABOVE_WALLS over
    the box's walls, then again from place_clearance (lift 0), then skimming the
    walls (their own test); a cell offers one target."""
    from strug_manip.control.targets import ABOVE_WALLS, rim

    spec, T = cabinets["drawers_11"], np.eye(4)
    part = spec.part("link_1")
    q = 0.9 * part.upper
    high, low_front, first, second, *low = place_targets(spec, "link_1", q, T)[:6]
    walls = part.point_at(part.interior_center, q)[2] + part.interior_size[2] / 2
    bottom = first.p[2, 3] - OBJECT_HALF_SIZE[2]
    assert rim(part) > walls + 0.01  # this drawer's front stands over its box
    assert high.lift == low_front.lift == pytest.approx(rim(part) + ABOVE_WALLS - bottom)
    assert [high.p.tobytes(), low_front.p.tobytes()] == [first.p.tobytes(), second.p.tobytes()]
    assert first.lift == second.lift == pytest.approx(walls + ABOVE_WALLS - bottom)
    assert [t.lift for t in low] == [0.0, 0.0]
    assert not any(t.skim for t in (first, second, *low))
    assert [t.p.tobytes() for t in low] == [first.p.tobytes(), second.p.tobytes()]
    assert first.grasp == second.grasp == "top"
    np.testing.assert_array_equal(first.p[:3, :3], second.p[:3, :3])
    # The cabinet's x points out of its front: the second is nearer the drawer's front.
    assert second.p[0, 3] > first.p[0, 3] + 1e-3
    assert second.p[1:3, 3] == pytest.approx(first.p[1:3, 3])
    assert inside(spec, "link_1", q, T, second.p)
    front_wall = part.point_at(part.interior_center, q)[0] + part.interior_size[0] / 2
    reach = 0.05 if abs(second.p[0, 0]) > 0.5 else FINGER_SPAN / 2  # along or across
    assert second.p[0, 3] == pytest.approx(front_wall - CLEARANCE - reach)
    assert place_target(spec, "link_1", q, T).p.tobytes() == first.p.tobytes()
    assert len(place_targets(cabinets["mixed_17"], "link_5", 1.4, T)) == 1


def test_a_drawer_out_of_reach_from_above_is_skimmed_then_dropped_into() -> None:
    """After the targets lowered from high up, a drawer's places follow lowered from
    just over its walls (SKIM_OVER, ``skim``: from exactly that height); a deep box adds
    its places let go DROPS above the floor, the object's top DROP_BELOW_WALLS or more
    under the walls' top, lowered into from as high as the first over the walls; a
    shallower box adds
    fewer or none; then come the same heights with the object TIGHT_GAP from the front
    wall; last, the object leaning (LEAN) from each height but the drops; every target's
    object centre is inside the drawer."""
    from strug_manip.control.targets import DROP_BELOW_WALLS, DROPS, SKIM_OVER, TIGHT_GAP, rim

    spec, T = generate_cabinet(88, kinds=("drawer",)), np.eye(4)  # 8.5 to 29 cm deep
    h = 2 * OBJECT_HALF_SIZE[2]
    added, tights, leans = [], [], []
    for part in spec.movable_parts:
        q = 0.9 * part.upper
        everything = place_targets(spec, part.link, q, T)
        level = [t.p[2, 2] > 1.0 - 1e-9 for t in everything]
        targets = everything[: sum(level)]
        assert all(level[: len(targets)])  # the leaning ones come last
        n = 2 if targets[1].p[0, 3] > targets[0].p[0, 3] else 1  # places per height
        walls = float(part.interior_size[2])
        floor = part.point_at(part.interior_center, q)[2] - walls / 2
        high = 3 if rim(part) - floor > walls + 1e-3 else 2  # over the front, the walls, 0
        skims = targets[high * n : (high + len(SKIM_OVER)) * n]
        assert [t.skim for t in skims] == [True] * len(skims)
        assert [t.lift for t in skims] == pytest.approx(
            [walls + o for o in SKIM_OVER for _ in range(n)]
        )
        deep = [r for r in DROPS if r + h <= walls - DROP_BELOW_WALLS]
        starts = high + len(SKIM_OVER) + len(deep)  # heights, each with n places
        drops = targets[(high + len(SKIM_OVER)) * n : starts * n]
        assert len(drops) == len(deep) * n
        # Last, one place per height TIGHT_GAP from the front wall (nearer than the rest).
        tight = targets[starts * n :]
        assert len(tight) in (0, starts)
        tights.append(len(tight))
        front_wall = part.point_at(part.interior_center, q)[0] + part.interior_size[0] / 2
        for t, same in zip(tight, targets[n - 1 :: n], strict=False):
            reach = OBJECT_HALF_SIZE[0] if abs(t.p[0, 0]) > 0.5 else FINGER_SPAN / 2
            assert t.p[0, 3] == pytest.approx(front_wall - TIGHT_GAP - reach)
            assert t.p[0, 3] > same.p[0, 3] + 1e-3
            assert t.p[2, 3] + t.lift == pytest.approx(same.p[2, 3] + same.lift)
            assert t.skim == same.skim
        added.append(len(deep))
        for k, t in enumerate(drops):
            assert not t.skim
            assert t.p[2, 3] - OBJECT_HALF_SIZE[2] == pytest.approx(floor + deep[k // n])
            start = t.p[2, 3] + t.lift
            walls_first = targets[(high - 2) * n]  # lowered from ABOVE_WALLS over them
            assert start == pytest.approx(walls_first.p[2, 3] + walls_first.lift)
        for t in everything:
            assert inside(spec, part.link, q, T, t.p)
        leaning = everything[len(targets) :]
        check_leaning(leaning, targets[: (high + len(SKIM_OVER)) * n : n], floor, front_wall)
        leans.append(len(leaning))
    assert min(added) == 0 and max(added) == len(DROPS), added
    assert max(tights) > 0, tights
    assert max(leans) > 0, leans


def check_leaning(leaning: tuple, level: tuple, floor: float, front_wall: float) -> None:
    """Leaning places: one per level start but the drops (from the same heights), the
    object tilted LEAN with its top toward the front (+x), its lowest edge LEAN_LOWEST
    over the floor and its tilted footprint CLEARANCE inside the front wall."""
    from strug_manip.control.targets import LEAN, LEAN_LOWEST

    if not leaning:
        return
    hx, _, hz = OBJECT_HALF_SIZE
    assert len(leaning) == len(level)
    for t, same in zip(leaning, level, strict=True):
        up = t.p[:3, 2]
        assert up == pytest.approx([np.sin(LEAN), 0.0, np.cos(LEAN)])
        assert t.p[2, 3] - hx * np.sin(LEAN) - hz * np.cos(LEAN) == pytest.approx(
            floor + LEAN_LOWEST
        )
        assert t.p[0, 3] + hx * np.cos(LEAN) + hz * np.sin(LEAN) == pytest.approx(
            front_wall - CLEARANCE
        )
        assert t.p[2, 3] + t.lift == pytest.approx(max(same.p[2, 3] + same.lift, t.p[2, 3]))
        assert (t.grasp, t.skim) == ("top", same.skim)


def _drop_down_flaps(seeds: range) -> list:
    """(spec, part) of every drop-down flap the generator makes on ``seeds``."""
    out = []
    for s in seeds:
        spec = generate_cabinet(s, kinds=("door",))
        out += [(spec, p) for p in spec.parts if p.hinge == "bottom"]
    return out


def test_behind_a_drop_down_flap_the_object_comes_in_just_over_its_edge() -> None:
    """The pitched object comes in CLEARANCE over the open flap's edge (higher, the
    pitched wrist meets the cell's top), and a cell too low for the pitched object and
    the palm over it cannot take it (ConfigError naming the heights)."""
    from strug_manip.control.targets import (
        CLEARANCE,
        FLAP_DROP,
        FLAP_PITCH,
        HELD_HEIGHT,
        PALM_ABOVE,
    )
    from strug_manip.world.scene import OBJECT_HALF_SIZE

    hx, _, hz = OBJECT_HALF_SIZE
    pitched = 0.02 + 2 * (hx * np.sin(FLAP_PITCH) + hz * np.cos(FLAP_PITCH)) + PALM_ABOVE
    assert pitched > HELD_HEIGHT  # a pitched object stands taller than a level one
    fitted = low = 0
    for spec, part in _drop_down_flaps(range(40)):
        q = part.upper - 0.05
        height = float(part.interior_size[2])
        if height < pitched + CLEARANCE:
            with pytest.raises(ConfigError, match=f"x {pitched + CLEARANCE:.3f} m$"):
                place_target(spec, part.link, q, np.eye(4))
            low += 1
            continue
        panel = part.geoms[0].size
        edge = float(panel[2]) * max(np.cos(q), 0.0) + float(panel[0])
        try:
            t = place_target(spec, part.link, q, np.eye(4))
        except ConfigError as e:  # too narrow, too shallow, or the flap's edge too high
            assert "does not pass over it" in str(e) or "free width" in str(e)
            continue
        assert t.grasp == "side"
        assert t.lift == pytest.approx(max(edge + CLEARANCE - FLAP_DROP, 0.0))
        fitted += 1
    assert fitted > 0 and low > 0


def test_under_a_top_flap_the_object_comes_in_lifted_below_its_edge() -> None:
    """Under a lift-up flap open near its limit the object is carried in lifted over the
    floor (a believed floor a centimetre low no longer puts it on the cell's front
    edge), the palm CLEARANCE or more below the flap's hanging edge."""
    flaps = [
        (spec, p)
        for s in range(3000, 3040)
        for spec in [generate_cabinet(s, kinds=("door",))]
        for p in spec.parts
        if p.hinge == "top"
    ]
    lifted = 0
    for spec, part in flaps:
        q = part.upper - 0.05
        try:
            t = place_target(spec, part.link, q, np.eye(4))
        except ConfigError:
            continue  # too low a cell for the object under this flap
        thickness, _, height = part.geoms[0].size
        top = part.interior_center[2] + part.interior_size[2] / 2
        edge = top - height * max(np.cos(q), 0.0) - thickness
        palm = t.p[2, 3] - OBJECT_HALF_SIZE[2] + t.lift + HELD_HEIGHT
        assert palm <= edge - CLEARANCE + 1e-9
        lifted += t.lift > CLEARANCE
    assert len(flaps) >= 5 and lifted >= len(flaps) // 2, (len(flaps), lifted)
