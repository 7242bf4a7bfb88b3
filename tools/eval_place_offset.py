"""How far off may a believed cabinet be? Place into open parts against belief errors.

Usage::

    python tools/eval_place_offset.py --seeds 3000:3010 [--out DIR] [--json]

For every generator seed in ``A..B-1`` the drawers-only and the doors-only scene (as
``tools/eval_hinge_offset.py`` and ``tools/eval_skills.py`` draw them) are built, and
for every handled part whose cell or box can take the object: the part is set open
(``limit - limit_margin``, a drawer at most ``drawer_travel``), the full robot picks
the object, and then places it into the part once per variant (:data:`VARIANTS`), each
from the same state after the pick. In a variant the believed cabinet is the true one
moved by a few centimetres: down or up (its floors), sideways, or toward the robot or
away (its front), which is how perception's cabinets are off (a door episode's cell
floor stood 1 cm lower in the belief than in the real cabinet, its walls 1-2 cm off).
The Place's target and its motion plans come from the believed cabinet (its planning
world); the motion happens in the true one. A place succeeds as in the episodes: the
object's centre inside the part, let go, the cabinet not dragged; failures by status
(``outside``: ran to its end, the object not inside; ``dragged``: the cabinet moved
past the rules' 0.1 m over the pick and the place).

Results are appended per seed to ``OUT/results.jsonl``; a rerun with the same ``--out``
skips the seeds already there.
"""

from __future__ import annotations

import dataclasses
import functools
import sys
from collections import Counter

from strug_manip.control import ControlContext, Pick, Place, SkillParams, place_targets
from strug_manip.domains.manipulation.grounding import first_feasible
from strug_manip.domains.manipulation.rules import dragged, inside, open_enough
from strug_manip.experiments.seeds import seed_tool
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

#: (name, (dx, dy, dz)): the believed cabinet moved by this in the world [m]: x away
#: from the robot (which faces +x), y to the robot's left, z up.
VARIANTS: tuple[tuple[str, tuple[float, float, float]], ...] = (
    ("true", (0.0, 0.0, 0.0)),
    ("down 1 cm", (0.0, 0.0, -0.01)),
    ("down 2 cm", (0.0, 0.0, -0.02)),
    ("up 1 cm", (0.0, 0.0, 0.01)),
    ("up 2 cm", (0.0, 0.0, 0.02)),
    ("left 1.5 cm", (0.0, 0.015, 0.0)),
    ("right 1.5 cm", (0.0, -0.015, 0.0)),
    ("nearer 2 cm", (-0.02, 0.0, 0.0)),
    ("farther 2 cm", (0.02, 0.0, 0.0)),
)


def believed_world(config: SceneConfig, shift: tuple[float, float, float]) -> ManipulationWorld:
    """The scene of ``config`` with its cabinet (and the cabinet's table) moved by
    ``shift`` (see :data:`VARIANTS`)."""
    dx, dy, dz = shift
    moved = dataclasses.replace(
        config,
        cabinet_distance=config.cabinet_distance + dx,
        cabinet_lateral=config.cabinet_lateral + dy,
        stand_height=config.stand_height + dz,
    )
    return ManipulationWorld(moved)


def open_position(part, params: SkillParams) -> float:
    """Where an opening under the true model leaves ``part`` [m or rad]."""
    if part.joint_type == "prismatic":
        return float(min(part.upper - params.limit_margin_m, params.drawer_travel))
    return float(part.upper - params.limit_margin_rad)


def place_once(world, pw, link: str, q: float, ctx) -> dict:
    """One Place from the world's present state, planned in ``pw`` (the believed world,
    its part at ``q``): the targets in turn until one can be reached, as the robot
    goes through them (:func:`~strug_manip.domains.manipulation.grounding.first_feasible`)."""
    spec = world.scene.cabinet_spec
    out = first_feasible(
        functools.partial(Place.onto(tgt).run, world, ctx=ctx, plan_world=pw)
        for tgt in place_targets(spec, link, q, pw.scene.T_world_cabinet)
    )
    assert out is not None
    name = world.scene.cabinet_prefix + spec.part(link).joint
    T_now = world.cabinet_pose()
    q_now = world.part_positions()[name]
    placed = inside(spec, link, q_now, T_now, world.object_pose()) and not out.holding
    displacement = world.cabinet_displacement()
    if not out.ok:
        cause = str(out.status)
    elif dragged(displacement):
        cause = "dragged"
    else:
        cause = "ok" if placed else "outside"
    return {"ok": cause == "ok", "cause": cause, "cabinet": displacement}


def evaluate_part(world, config: SceneConfig, part, ctx, params: SkillParams) -> dict | None:
    """Every variant on ``part`` (None: its cell cannot take the object, or the pick
    failed; the latter is reported)."""
    T = world.scene.T_world_cabinet
    spec = world.scene.cabinet_spec
    q = open_position(part, params)
    if not open_enough(spec, part.link, q, T):
        return None
    joint = world.scene.cabinet_prefix + part.joint
    world.reset({joint: q})
    pick = Pick("object", place_targets(spec, part.link, q, T)[0].grasp).run(world, ctx=ctx)
    if not pick.ok:
        return {"part": part.link, "pick": str(pick.status), "runs": {}}
    held = world.snapshot()
    runs = {}
    for name, shift in VARIANTS:
        pw = believed_world(config, shift)
        pw.reset({joint: q})
        world.restore(held)
        runs[name] = place_once(world, pw, part.link, q, ctx)
        pw.close()
    return {"part": part.link, "kind": part.kind, "hinge": part.hinge, "pick": "ok", "runs": runs}


#: The scenes of a generator seed: its drawers-only and its doors-only cabinet.
KINDS = ("drawer", "door")


def evaluate_seed(seed: int, ctx: ControlContext) -> dict:
    """Every variant on every handled part of seed ``seed``'s scenes (:data:`KINDS`)."""
    params = SkillParams()
    parts = []
    for kind in KINDS:
        config = SceneConfig(cabinet_seed=seed, cabinet_kinds=(kind,))
        world = ManipulationWorld(config)
        for part in world.scene.cabinet_spec.movable_parts:
            if part.handle == "none" or part.interior_center is None:
                continue
            rec = evaluate_part(world, config, part, ctx, params)
            if rec is not None:
                parts.append(rec)
        world.close()
    return {"seed": seed, "parts": parts}


def table(rows: list[dict]) -> str:
    """Success and failure causes per variant, as a markdown table."""
    picked = [p for r in rows for p in r["parts"] if p["pick"] == "ok"]
    lines = ["| believed cabinet | success | failures |", "|---|---|---|"]
    for name, _ in VARIANTS:
        runs = [p["runs"][name] for p in picked]
        ok = sum(r["ok"] for r in runs)
        causes = Counter(r["cause"] for r in runs if not r["ok"])
        why = ", ".join(f"{c} {k}" for c, k in causes.most_common()) or "-"
        lines.append(f"| {name} | {ok}/{len(runs)} ({100 * ok / max(len(runs), 1):.0f}%) | {why} |")
    total = sum(p["runs"][n]["ok"] for p in picked for n, _ in VARIANTS)
    lines.append(f"| all {len(VARIANTS)} | {total}/{len(picked) * len(VARIANTS)} | |")
    failed = [f"{r['seed']}/{p['part']} {p['pick']}" for r in rows for p in r["parts"]
              if p["pick"] != "ok"]  # fmt: skip
    if failed:
        lines.append(f"\npicks that failed (no place measured): {', '.join(failed)}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    evaluate = functools.partial(evaluate_seed, ctx=ControlContext())
    title = "places against believed-cabinet errors"
    return seed_tool(argv, __doc__.split("\n")[0], evaluate, table, title)


if __name__ == "__main__":
    sys.exit(main())
