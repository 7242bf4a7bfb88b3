"""How far off may a believed hinge be? Door openings against hinge errors (issue 37).

Usage::

    python tools/eval_hinge_offset.py --seeds 3000:3020 [--out DIR] [--json]

For every generator seed in ``A..B-1`` a doors-only scene is built (as the OpenDoor
task draws it), and every door or flap with a handle is opened by the full robot with
the true joint moved or turned (:data:`VARIANTS`): the hinge line shifted in the front
plane *toward* the handle (``radial``: the arc's radius too short; negative: too
long) or out of the front (``depth``: toward the robot), or the axis tilted about the
handle's height in the front plane (``tilt-in``) or out of it (``tilt-out``). The
skill plans against the true cabinet (its collision checks), so the joint is the only
error. An opening succeeds as in ``tools/eval_skills.py``: ``ok``, open enough for the
object (or 90 % of its travel where the cell cannot take the object), the cabinet not
dragged; failures are counted by status.

Results are appended per seed to ``OUT/results.jsonl``; a rerun with the same ``--out``
skips the seeds already there.
"""

from __future__ import annotations

import functools
import sys
from collections import Counter

import numpy as np

from strug_manip.control import ControlContext, OpenDoor, SkillParams, handle_grasps
from strug_manip.domains.manipulation.rules import dragged, open_enough
from strug_manip.experiments.seeds import seed_tool
from strug_manip.geometry import axis_angle
from strug_manip.objects.hypotheses import BelievedJoint
from strug_manip.world.scene import SceneConfig
from strug_manip.world.sim import ManipulationWorld

#: (name, kind, amount): metres for ``radial`` and ``depth``, degrees for tilts.
VARIANTS: tuple[tuple[str, str, float], ...] = (
    ("true", "radial", 0.0),
    *((f"radial {d:+.0f} cm", "radial", d / 100) for d in (1, 2, 4, -1, -2, -4)),
    *((f"depth {d:+.0f} cm", "depth", d / 100) for d in (2, -2)),
    *((f"tilt-in {a:.0f} deg", "tilt-in", a) for a in (2, 5)),
    *((f"tilt-out {a:.0f} deg", "tilt-out", a) for a in (2, 5)),
)


def offset_joint(true: BelievedJoint, grasp: np.ndarray, kind: str, amount: float) -> BelievedJoint:
    """``true`` (world frame) with its hinge moved by ``amount`` (see :data:`VARIANTS`);
    ``grasp`` (4, 4) is the handle's grasp pose (its x axis into the front)."""
    axis, origin = np.asarray(true.axis, float), np.asarray(true.origin, float)
    n = -grasp[:3, 0] - axis * (-grasp[:3, 0] @ axis)  # out of the front, toward the robot
    n /= np.linalg.norm(n)
    u = np.cross(n, axis)  # in the front plane, across the hinge
    to_handle = grasp[:3, 3] - origin
    u = u if u @ to_handle >= 0 else -u  # from the hinge toward the handle
    if kind == "radial":
        return BelievedJoint(true.type, axis, origin + amount * u, limit=true.limit)
    if kind == "depth":
        return BelievedJoint(true.type, axis, origin + amount * n, limit=true.limit)
    turn = axis_angle(n if kind == "tilt-in" else u, np.radians(amount))[:3, :3]
    h = to_handle @ axis
    new_axis = turn @ axis  # about the hinge's point at the handle's height
    return BelievedJoint(true.type, new_axis, origin + h * axis - h * new_axis, limit=true.limit)


def open_once(world: ManipulationWorld, part, joint: BelievedJoint, ctx) -> dict:
    """One opening from reset (the grasps in turn until one can be reached:
    :attr:`~strug_manip.control.Outcome.cannot_reach`)."""
    T = world.scene.T_world_cabinet
    spec = world.scene.cabinet_spec
    name = world.scene.cabinet_prefix + part.joint
    out = None
    for g in handle_grasps(part, 0.0, T):
        world.reset()
        skill = OpenDoor(g, joint)
        out = skill.run(world, ctx=ctx)
        if not out.cannot_reach:
            break
    assert out is not None
    q = world.part_positions()[name]
    T_now = world.cabinet_pose()
    p = SkillParams()
    travel = min(skill.default_amount(p), joint.limit - p.limit_margin_rad)
    room = open_enough(spec, part.link, part.upper, T)
    wide = open_enough(spec, part.link, q, T_now) if room else abs(q) >= 0.9 * travel
    moved_away = dragged(out.cabinet_displacement)
    ok = out.ok and wide and not moved_away
    cause = "ok" if ok else str(out.status) if not out.ok else "dragged" if moved_away else "little"
    return {"ok": bool(ok), "cause": cause, "q": float(q), "cabinet": out.cabinet_displacement}


def evaluate_seed(seed: int, ctx: ControlContext) -> dict:
    """Every variant on every handled door of seed ``seed``'s doors-only scene."""
    world = ManipulationWorld(SceneConfig(cabinet_seed=seed, cabinet_kinds=("door",)))
    T = world.scene.T_world_cabinet
    parts = []
    for part in world.scene.cabinet_spec.movable_parts:
        if part.handle == "none" or part.joint_type != "revolute":
            continue
        true = BelievedJoint.of_part(part, 0.0, T)
        grasps = handle_grasps(part, 0.0, T)
        if not grasps:
            continue
        runs = {}
        for name, kind, amount in VARIANTS:
            joint = offset_joint(true, grasps[0], kind, amount)
            runs[name] = open_once(world, part, joint, ctx)
        parts.append({"part": part.link, "runs": runs})
    world.close()
    return {"seed": seed, "parts": parts}


def table(rows: list[dict]) -> str:
    """Success and failure causes per variant, as a markdown table."""
    lines = ["| hinge | success | failures |", "|---|---|---|"]
    for name, _, _ in VARIANTS:
        runs = [p["runs"][name] for r in rows for p in r["parts"]]
        ok = sum(r["ok"] for r in runs)
        causes = Counter(r["cause"] for r in runs if not r["ok"])
        why = ", ".join(f"{c} {k}" for c, k in causes.most_common()) or "-"
        lines.append(f"| {name} | {ok}/{len(runs)} ({100 * ok / max(len(runs), 1):.0f}%) | {why} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    evaluate = functools.partial(evaluate_seed, ctx=ControlContext())
    title = "door openings against hinge errors"
    return seed_tool(argv, __doc__.split("\n")[0], evaluate, table, title)


if __name__ == "__main__":
    sys.exit(main())
