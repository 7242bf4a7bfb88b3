"""Evaluate the skills on generated cabinets: reach, risk, honest outcomes, probes,
chains and the planning twin.

Usage::

    python tools/eval_skills.py --seeds 1000:1030 [--json] [--out DIR] [--workers 2]
                                [--plot docs/drag.png] [--twin-steps 0.005,0.003]
                                [--only twin]

For every generator seed in ``A..B-1`` two scenes are built (a drawers-only and a
doors-only cabinet, as the OpenDrawer and OpenDoor tasks draw them), and for every
movable part with a handle (a flat front cannot be grasped):

- **open** under the true model (:class:`OpenDrawer` for a drawer, :class:`OpenDoor`
  for a door or flap; the grasps of :func:`handle_grasps` in turn until one can be
  reached, as the robot takes them: ``Outcome.cannot_reach``): a success is a run
  that ends ``ok``, with the part open enough for the object
  (:func:`~strug_manip.domains.manipulation.rules.open_enough`) and the cabinet not
  dragged (a part whose cell cannot take the object even open to its
  limit: moved 90 % of the skill's travel); failures are counted by cause;
- the **chain** from there when it opened: Pick (with the grasp the part's target
  needs) then Place into the drawer / behind the door (the targets of
  :func:`place_targets` in turn until one can be reached); a success is the
  object resting inside the part (:func:`~strug_manip.domains.manipulation.rules.inside`);
- **wrong models**: the two likeliest confusions of the part's kinematics (a drawer
  taken for a door hinged left or right; a side door for a drawer or a door hinged on
  the other side; a flap for a drawer or a flap hinged on the other edge), each
  planned in a world of the believed cabinet and executed in the true one from a fresh
  reset; per pull the cabinet's displacement, the outcome, and *false successes*: the
  task rule applied to the outcome's facts says "opened, not dragged" while the world
  itself (its joint and its base, read directly) says otherwise; and per part one
  **sequence of four wrong pulls** in a row (the two confusions, twice) without reset;
- **probes** (Push, PullV up and down, PullH out and sideways) under the true model:
  how far each moves the part, per part kind;
- the **twin**: every true-model opening and wrong-model pull (and one probe per part)
  again on a planning twin of the true cabinet; agreement = the same status, dragged or
  not alike, and the part moved within 1 cm or 0.05 rad of the full robot's motion
  unless both dragged the cabinet (the episode ends there; ``agreement_strict`` asks
  the motion of those too); the speed-up is the ratio of the full robot's to the
  twin's total wall time (the twin's placement cached, as in a search; the cold
  first runs are reported beside). ``--twin-steps`` runs twins of several physics
  steps on the same full-robot runs (the first is the one reported as ``twin``; each
  under ``twin_steps``): what a smaller step buys in agreement and costs in speed.

``--only twin`` runs just what the twin is compared on (every true-model opening,
both wrong-model pulls and the PullH probe of each handled part, on the full robot
and on the twins) and reports only ``twin`` and ``twin_steps``: about a third of the
full evaluation's time (the chains, the sequences and the other probes are left out).

Results are appended per seed to ``OUT/results.jsonl`` as they finish; a rerun with the
same ``--out`` skips the seeds already there. ``--json`` prints one JSON object (keys
in the docstring of :func:`summary`).
"""

from __future__ import annotations

import argparse
import functools
import json
import multiprocessing as mp
import os
import statistics
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

from planners.errors import ConfigError
from strug_manip.control import (
    ControlContext,
    OpenDoor,
    OpenDrawer,
    Outcome,
    Pick,
    Place,
    PlanningTwin,
    PullH,
    PullV,
    Push,
    handle_grasps,
    place_targets,
)
from strug_manip.control.params import DEFAULT_PARAMS
from strug_manip.control.twin_body import TIMESTEP as TWIN_STEP
from strug_manip.domains.manipulation.grounding import first_feasible
from strug_manip.domains.manipulation.rules import dragged, inside, open_enough
from strug_manip.experiments.seeds import seed_range
from strug_manip.objects.hypotheses import BelievedJoint, believed_spec, cell_joints, model_of
from strug_manip.objects.loader import object_folders
from strug_manip.world import ManipulationWorld, SceneConfig

#: The two likeliest confusions of each kinematic model.
CONFUSIONS: dict[str, tuple[str, str]] = {
    "drawer": ("left", "right"),
    "left": ("drawer", "right"),
    "right": ("drawer", "left"),
    "top": ("drawer", "bottom"),
    "bottom": ("drawer", "top"),
}
#: Agreement tolerances of the twin: part motion [m] for prismatic, [rad] for revolute.
AGREE_M, AGREE_RAD = 0.01, 0.05
#: The key of the default twin's rows under ``twin_steps`` (records made before there
#: were several steps hold that twin's alone).
TWIN_KEY = f"{TWIN_STEP:g}"


def category(model: str) -> str:
    """``open_drawer``, ``open_door`` (side-hinged) or ``open_flap`` (top/bottom)."""
    return {"drawer": "open_drawer", "left": "open_door", "right": "open_door"}.get(
        model, "open_flap"
    )


def opening(joint: BelievedJoint, g: np.ndarray):
    """The opening skill a belief calls for."""
    return OpenDrawer(g, joint) if joint.type == "prismatic" else OpenDoor(g, joint)


def world_joint(spec, link: str, model: str, T: np.ndarray) -> BelievedJoint:
    """Model ``model`` of part ``link``'s cell as a world-frame joint."""
    j = cell_joints(spec.part(link))[model]
    return BelievedJoint(j.type, T[:3, :3] @ j.axis, (T @ np.r_[j.origin, 1.0])[:3])


def run_opening(world, spec, link, joint, ctx, plan_world=None):
    """The first grasp of the believed part that can be reached (``cannot_reach``): (skill,
    outcome)."""
    bspec = spec if plan_world is None else plan_world.scene.cabinet_spec
    T = world.scene.T_world_cabinet
    out, skill = None, None
    for g in handle_grasps(bspec.part(link), 0.0, T):
        world.reset()
        if plan_world is not None:
            plan_world.reset()
        skill = opening(joint, g)
        out = skill.run(world, ctx=ctx, plan_world=plan_world)
        if not out.cannot_reach:
            break
    if out is None:
        raise ValueError(f"part {link!r} has a handle but no grasp (see handle_grasps)")
    return skill, out


def simulate_twice(twin, skill, plan_world=None) -> tuple[Outcome, float]:
    """``skill`` on ``twin`` from its reset, twice: the first run searches the base
    placement (cold), the second finds it cached, as a search does that simulates the
    skill again on the particle. Returns the second outcome (asserted the same as the
    first) and the first run's wall time [s]."""
    outs = []
    for _ in range(2):
        twin.reset()
        if plan_world is not None:
            plan_world.reset()
        outs.append(skill.simulate(twin, plan_world=plan_world))
    if not outs[0].same_as(outs[1]):
        raise AssertionError(f"the twin is not deterministic: {outs[0].summary()} then "
                             f"{outs[1].summary()}")  # fmt: skip
    return outs[1], outs[0].wall_seconds


def commanded(skill) -> float:
    """How far the opening ``skill`` moves its part [m or rad]: its amount (or default),
    capped before the believed limit, as its plan does."""
    p = DEFAULT_PARAMS
    want = skill.default_amount(p) if skill.amount is None else skill.amount
    prismatic = skill.joint.type == "prismatic"
    return min(want, skill.joint.limit - (p.limit_margin_m if prismatic else p.limit_margin_rad))


def compare(full: Outcome, twin: Outcome, cold: float, joint: str, unit: str) -> dict:
    """The twin's agreement with the full robot on one run (``cold``: the twin's wall
    time with an empty placement cache [s])."""
    tol = AGREE_M if unit == "m" else AGREE_RAD
    dm = abs(full.motion_of(joint) - twin.motion_of(joint))
    drags = dragged(full.cabinet_displacement), dragged(twin.cabinet_displacement)
    same = full.status == twin.status and drags[0] == drags[1]
    return {
        "full": str(full.status),
        "twin": str(twin.status),
        "motion_error": round(dm, 4),
        "dragged": drags[0],
        # Where both dragged the cabinet past 0.1 m the episode ends there (-10) and
        # the part's motion, after a cabinet that slid or fell off its table, is
        # chaotic: it does not count there (``agree_strict`` counts it everywhere).
        "agree": bool(same and (dm <= tol or all(drags))),
        "agree_strict": bool(same and dm <= tol),
        "full_wall": full.wall_seconds,
        "twin_wall": twin.wall_seconds,
        "twin_cold_wall": cold,
    }


def twin_compare(twins: dict, full: Outcome, skill, joint: str, unit: str, plan_world=None):
    """``skill`` again on every twin (by physics step): {step: :func:`compare` row}."""
    return {
        step: compare(full, *simulate_twice(tw, skill, plan_world), joint, unit)
        for step, tw in twins.items()
    }


def evaluate_part(world, twins: dict, spec, part, ctx, only_twin: bool = False) -> dict:
    """Every measurement of one part (see the module docstring); ``twins``: planning
    twins of the true cabinet by physics step (the first reported as ``twin``);
    ``only_twin``: just the runs the twins are compared on."""
    T = world.scene.T_world_cabinet
    model = model_of(part)
    joint_name = world.scene.cabinet_prefix + part.joint
    unit = world.part_units()[joint_name]
    rec: dict = {"part": part.link, "model": model, "category": category(model), "unit": unit}
    # --- open under the true model, then the chain ---------------------------------
    true = BelievedJoint.of_part(part, 0.0, T)
    skill, out = run_opening(world, spec, part.link, true, ctx)
    q = world.part_positions()[joint_name]
    T_now = world.body_pose(world.scene.cabinet_prefix + world.scene.cabinet.root)
    moved_away = dragged(out.cabinet_displacement)
    wide = open_enough(spec, part.link, q, T_now)
    # A cell that cannot take the object even with its part at the limit (too low,
    # too narrow) counts as opened when the part reached 90 % of the skill's travel.
    room = open_enough(spec, part.link, part.upper, T)
    target = commanded(skill)
    reached = abs(out.motion_of(joint_name)) >= 0.9 * abs(target)
    ok = out.ok and not moved_away and (wide if room else reached)
    cause = (
        "ok" if ok else str(out.status) if not out.ok else "dragged" if moved_away else "too little"
    )
    rec["open"] = {
        "ok": bool(ok),
        "room": bool(room),
        "wide": bool(wide),
        "cause": cause,
        "motion": out.motion_of(joint_name),
        "wall": out.wall_seconds,
        "sim": out.sim_time,
        "displacement": out.cabinet_displacement,
    }
    rows = [twin_compare(twins, out, skill, joint_name, unit)]
    if ok and wide and not only_twin:
        tgts = place_targets(spec, part.link, q, T_now)
        pick = Pick("object", tgts[0].grasp).run(world, ctx=ctx)
        chain = {"pick": str(pick.status), "place": None, "ok": False}
        if pick.ok:
            # The targets in turn, as the robot takes them (the next while one cannot
            # be reached: nothing moved).
            place = first_feasible(
                functools.partial(Place.onto(t).run, world, ctx=ctx) for t in tgts
            )
            assert place is not None
            chain["place"] = str(place.status)
            q2 = world.part_positions()[joint_name]
            T2 = world.body_pose(world.scene.cabinet_prefix + world.scene.cabinet.root)
            chain["ok"] = bool(
                inside(spec, part.link, q2, T2, world.object_pose())
                and not dragged(world.cabinet_displacement())
                and not place.holding
            )
            chain["wall"] = out.wall_seconds + pick.wall_seconds + place.wall_seconds
        rec["chain"] = chain
    # --- wrong models --------------------------------------------------------------
    wrong = []
    for belief in CONFUSIONS[model]:
        bj = world_joint(spec, part.link, belief, T)
        bspec = believed_spec(spec, part.link, bj, T)
        pw = ManipulationWorld.from_cabinet_spec(bspec, world.config)
        joint = BelievedJoint.of_part(bspec.part(part.link), 0.0, T)
        skill, out = run_opening(world, spec, part.link, joint, ctx, plan_world=pw)
        q = world.part_positions()[joint_name]
        T_now = world.body_pose(world.scene.cabinet_prefix + world.scene.cabinet.root)
        said = (
            out.ok
            and not dragged(out.cabinet_displacement)
            and open_enough(spec, part.link, out.part_positions[joint_name], T_now)
        )
        truth = not dragged(world.cabinet_displacement()) and open_enough(spec, part.link, q, T_now)
        wrong.append(
            {
                "belief": belief,
                "status": str(out.status),
                "displacement": out.cabinet_displacement,
                "opened": bool(said),
                "false_success": bool(said and not truth),
            }
        )
        rows.append(twin_compare(twins, out, skill, joint_name, unit, pw))
        pw.close()
    rec["wrong"] = wrong
    if not only_twin:
        rec["sequence"] = wrong_sequence(world, spec, part, model, ctx)
    # --- probes --------------------------------------------------------------------
    probes = {}
    grasps = handle_grasps(part, 0.0, T)
    for name, make in (
        ("push", Push),
        ("pull_up", PullV),
        ("pull_down", lambda g: PullV(g, True)),
        ("pull_out", PullH),
        ("pull_side", lambda g: PullH(g, True)),
    ):
        if only_twin and name != "pull_out":
            continue
        o = None
        for g in grasps:
            world.reset()
            o = make(g).run(world, ctx=ctx)
            if not o.cannot_reach:
                break
        probes[name] = {
            "status": str(o.status),
            "motion": o.motion_of(joint_name),
            "displacement": o.cabinet_displacement,
        }
        if name == "pull_out":
            rows.append(twin_compare(twins, o, make(g), joint_name, unit))
    if not only_twin:
        rec["probes"] = probes
    first = next(iter(twins))
    rec["twin"] = [r[first] for r in rows]
    rec["twin_steps"] = {step: [r[step] for r in rows] for step in twins}
    return rec


def wrong_sequence(world, spec, part, model: str, ctx) -> list[float]:
    """Four wrong pulls in a row (the two confusions, twice), without reset: each
    planned in a world of the believed cabinet standing where the real one now is, its
    part where the real part now is; the cabinet's displacement after each [m]."""
    world.reset()
    joint_name = world.scene.cabinet_prefix + part.joint
    root = world.scene.cabinet_prefix + world.scene.cabinet.root
    out = []
    for belief in (*CONFUSIONS[model], *CONFUSIONS[model]):
        T = world.body_pose(root)
        q_true = world.part_positions()[joint_name]
        guess = world_joint(spec, part.link, belief, T)
        # Where the part is, as this belief has it: the true position if the belief
        # has the true joint type, else closed (another coordinate altogether).
        q = q_true if guess.type == part.joint_type else 0.0
        bspec = believed_spec(spec, part.link, guess, T, q)
        pw = ManipulationWorld.from_cabinet_spec(bspec, world.config)
        pw.copy_joints(world, [world.scene.cabinet_prefix + "free"])
        pw.set_parts({joint_name: q})
        joint = BelievedJoint.of_part(bspec.part(part.link), q, T)
        try:
            for g in handle_grasps(bspec.part(part.link), q, T):
                o = opening(joint, g).run(world, ctx=ctx, plan_world=pw)
                if not o.cannot_reach:
                    break
        except ConfigError:
            pass  # the belief leaves no travel: no pull
        out.append(world.cabinet_displacement())
        pw.close()
    return out


def evaluate_seed(
    seed: int, twin_steps: tuple[float, ...] = (TWIN_STEP,), only_twin: bool = False
) -> dict:
    """Every part of the drawers-only and the doors-only cabinet of ``seed``, with
    planning twins of the physics steps ``twin_steps`` [s]."""
    configs = {
        kind: SceneConfig(cabinet_seed=seed, cabinet_kinds=(kind,)) for kind in ("drawer", "door")
    }
    return evaluate_scenes(seed, configs, twin_steps, only_twin)


def evaluate_object(
    folder: Path, twin_steps: tuple[float, ...] = (TWIN_STEP,), only_twin: bool = False
) -> dict:
    """Every part of the real object in ``folder`` (its description derived from its
    URDF, semantics and geometry: :func:`~strug_manip.objects.describe.describe_object`),
    keyed by the folder's name."""
    configs = {"object": SceneConfig(cabinet_folder=folder)}
    return evaluate_scenes(folder.name, configs, twin_steps, only_twin)


def _evaluate_named(folders: dict[str, Path], name: str, **kwargs) -> dict:
    """:func:`evaluate_object` of ``folders[name]`` (a picklable job by name)."""
    return evaluate_object(folders[name], **kwargs)


def evaluate_scenes(
    key: int | str,
    configs: dict[str, SceneConfig],
    twin_steps: tuple[float, ...],
    only_twin: bool,
) -> dict:
    """Every handled movable part of each scene of ``configs`` (scene name -> config)."""
    ctx = ControlContext()
    parts = []
    t0 = time.perf_counter()
    for kind, config in configs.items():
        world = ManipulationWorld(config)
        spec = world.scene.cabinet_spec
        twins = {f"{dt:g}": PlanningTwin(spec, world.config, ctx, timestep=dt) for dt in twin_steps}
        for part in spec.movable_parts:
            if part.handle == "none":
                continue
            rec = evaluate_part(world, twins, spec, part, ctx, only_twin)
            parts.append({"scene": kind, **rec})
        world.close()
    rec = {"seed": key, "parts": parts, "seconds": time.perf_counter() - t0}
    return {**rec, "only": "twin"} if only_twin else rec


def rate(flags: list[bool]) -> dict:
    """``{"n", "ok"}`` of a list of successes."""
    return {"n": len(flags), "ok": int(sum(bool(f) for f in flags))}


def summary(records: list[dict]) -> dict:
    """The figures, as one JSON-able object:

    - ``open_drawer``, ``open_door``, ``open_flap``: ``{"n", "ok", "no_room", "causes",
      "median_wall_s"}`` (``no_room``: parts whose cell cannot take the object even
      open to the limit; they count as opened when they reach 90 % of the travel);
    - ``wrong_model``: ``{"n", "ok"}`` (runs that did not drag the cabinet), ``"dragged"``
      (single pulls past 0.1 m, ``{"n", "ok"}`` with ``ok`` the dragged ones),
      ``"dragged_after_4"`` and ``"sequences"`` (sequences of four wrong pulls past
      0.1 m in total), ``"false_success"``, ``"opened"`` (wrong models that still
      opened the part), ``"statuses"``, ``"displacement_m"`` (percentiles 50/90/99/max);
    - ``probes``: per part kind and probe, ``{"n", "median_motion", "moved"}``;
    - ``chain_drawer``, ``chain_door``: ``{"n", "ok"}`` over the parts that opened;
    - ``twin``: ``{"agreement": {"n", "ok"}, "agreement_strict", "speedup",
      "speedup_cold", "median_full_s", "median_twin_s", "disagreements"}``: the
      speed-up is the full robot's total wall time over the twin's with its placement
      cached (a search simulates a skill on a particle many times; ``speedup_cold``:
      over the first runs, which search the placement);
    - ``twin_steps``: the same per twin physics step (``"0.005"``, ...);
    - ``seconds``: median wall time of the openings, per skill (``median_per_skill_s``)
      and the total [s].

    Records of ``--only twin`` give ``twin`` and ``twin_steps`` alone.
    """
    parts = [p for r in records for p in r["parts"]]
    out: dict = {"twin": twin_figures([t for p in parts for t in p["twin"]])}
    steps = sorted({k for p in parts for k in p.get("twin_steps", {})}, key=float, reverse=True)
    out["twin_steps"] = {
        k: twin_figures([t for p in parts for t in p["twin_steps"].get(k, [])]) for k in steps
    }
    if any(r.get("only") == "twin" for r in records):
        return out
    for cat in ("open_drawer", "open_door", "open_flap"):
        ps = [p for p in parts if p["category"] == cat]
        out[cat] = {
            **rate([p["open"]["ok"] for p in ps]),
            "no_room": int(sum(not p["open"].get("room", True) for p in ps)),
            "causes": dict(Counter(p["open"]["cause"] for p in ps)),
            "median_wall_s": statistics.median([p["open"]["wall"] for p in ps]) if ps else None,
        }
    wrong = [w for p in parts for w in p["wrong"]]
    disp = np.array([w["displacement"] for w in wrong]) if wrong else np.zeros(1)
    seqs = [p["sequence"][-1] for p in parts if p.get("sequence")]
    out["wrong_model"] = {
        **rate([not dragged(w["displacement"]) for w in wrong]),
        "dragged": rate([dragged(w["displacement"]) for w in wrong]),
        "dragged_after_4": int(sum(dragged(s) for s in seqs)),
        "sequences": len(seqs),
        "false_success": int(sum(w["false_success"] for w in wrong)),
        "opened": rate([w["opened"] for w in wrong]),
        "statuses": dict(Counter(w["status"] for w in wrong)),
        "displacement_m": {
            k: float(np.percentile(disp, v))
            for k, v in (("p50", 50), ("p90", 90), ("p99", 99), ("max", 100))
        },
        "sequence_displacement_m": {
            "p50": float(np.median(seqs)) if seqs else None,
            "max": float(np.max(seqs)) if seqs else None,
        },
    }
    probes: dict = {}
    for kind in ("drawer", "side door", "flap"):
        ps = [
            p
            for p in parts
            if {"open_drawer": "drawer", "open_door": "side door", "open_flap": "flap"}[
                p["category"]
            ]
            == kind
        ]
        probes[kind] = {}
        for name in ("push", "pull_up", "pull_down", "pull_out", "pull_side"):
            ms = [abs(p["probes"][name]["motion"]) for p in ps]
            probes[kind][name] = {
                "n": len(ms),
                "median_motion": float(np.median(ms)) if ms else None,
                "moved": int(sum(m > 0.005 for m in ms)),
            }
    out["probes"] = probes
    for name, drawer in (("chain_drawer", True), ("chain_door", False)):
        out[name] = rate(
            [
                p["chain"]["ok"]
                for p in parts
                if (p["category"] == "open_drawer") == drawer and "chain" in p
            ]
        )
    walls = [p["open"]["wall"] for p in parts]
    per: dict[str, list[float]] = {}
    for p in parts:
        opening = "OpenDrawer" if p["category"] == "open_drawer" else "OpenDoor"
        per.setdefault(opening, []).append(p["open"]["wall"])
        for t in p["twin"][1:-1]:  # the wrong-model openings
            per.setdefault("opening, wrong model", []).append(t["full_wall"])
        per.setdefault("PullH", []).append(p["twin"][-1]["full_wall"])
        if p.get("chain", {}).get("wall") is not None:
            per.setdefault("Pick + Place", []).append(p["chain"]["wall"] - p["open"]["wall"])
    out["seconds"] = {
        "median_skill_s": statistics.median(walls) if walls else None,
        "median_per_skill_s": {k: statistics.median(v) for k, v in per.items()},
        "total_s": sum(r["seconds"] for r in records),
    }
    return out


def twin_figures(tw: list[dict]) -> dict:
    """The twin's agreement and speed-up over its comparison rows (see :func:`summary`)."""
    full_wall = sum(t["full_wall"] for t in tw)
    twin_wall = sum(t["twin_wall"] for t in tw)
    cold_wall = sum(t.get("twin_cold_wall", t["twin_wall"]) for t in tw)
    return {
        "agreement": rate([t["agree"] for t in tw]),
        "agreement_strict": rate([t.get("agree_strict", t["agree"]) for t in tw]),
        "speedup": full_wall / twin_wall if twin_wall > 0 else None,
        "speedup_cold": full_wall / cold_wall if cold_wall > 0 else None,
        "median_full_s": statistics.median([t["full_wall"] for t in tw]) if tw else None,
        "median_twin_s": statistics.median([t["twin_wall"] for t in tw]) if tw else None,
        "disagreements": dict(Counter(f"{t['full']} vs {t['twin']}" for t in tw if not t["agree"])),
    }


def usable(rec: dict, steps: list[str], only_twin: bool) -> bool:
    """Whether a stored record answers this run: full if a full run is asked, with
    the twins of every step asked (else the seed is evaluated again)."""
    have = set(rec["parts"][0].get("twin_steps", {TWIN_KEY: None})) if rec["parts"] else set()
    return (only_twin or rec.get("only") is None) and (not rec["parts"] or set(steps) <= have)


def load(path: Path) -> dict[int | str, dict]:
    """The records already in ``path`` by seed (an object's: by folder name; a line
    torn by a kill is dropped)."""
    done: dict[int | str, dict] = {}
    if path.is_file():
        for line in path.read_text().splitlines():
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                continue
            key = rec["seed"]
            done[int(key) if isinstance(key, int | float) else key] = rec
    return done


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    which = ap.add_mutually_exclusive_group(required=True)
    which.add_argument("--seeds", type=seed_range, help="A:B, generator seeds A..B-1")
    which.add_argument(
        "--objects",
        type=Path,
        help="a PartNet-Mobility object folder, or a folder of them: every handled part "
        "of each (ground truth from its URDF, semantics and geometry)",
    )
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--out", type=Path, default=None, help="results folder (resumable)")
    ap.add_argument("--workers", type=int, default=1, help="processes (default 1)")
    ap.add_argument("--plot", type=Path, default=None, help="write the drag distributions (PNG)")
    ap.add_argument(
        "--twin-steps",
        type=twin_steps,
        default=(TWIN_STEP,),
        help=f"twin physics steps [s], e.g. 0.005,0.003 (default {TWIN_STEP:g})",
    )
    ap.add_argument("--only", choices=("twin",), default=None,
                    help="twin: only the runs the twin is compared on")  # fmt: skip
    args = ap.parse_args(argv)
    only_twin = args.only == "twin"
    if args.objects is not None:
        folders = {f.name: f for f in object_folders(args.objects)}
        keys: list = list(folders)
        label = f"objects {args.objects}"
        job = functools.partial(
            _evaluate_named, folders, twin_steps=args.twin_steps, only_twin=only_twin
        )
        default_out = Path(f"runs/eval_skills_objects_{args.objects.name}")
    else:
        a, b = args.seeds.start, args.seeds.stop
        keys, label = list(range(a, b)), f"{a}:{b}"
        job = functools.partial(evaluate_seed, twin_steps=args.twin_steps, only_twin=only_twin)
        default_out = Path(f"runs/eval_skills_{'twin_' if only_twin else ''}{a}_{b}")
    out_dir = args.out or default_out
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "results.jsonl"
    steps = [f"{dt:g}" for dt in args.twin_steps]
    done = {s: r for s, r in load(path).items() if usable(r, steps, only_twin)}
    todo = [s for s in keys if s not in done]
    from tqdm import tqdm

    bar = tqdm(total=len(todo), unit="cabinet", desc="eval_skills", file=sys.stderr)
    with path.open("a") as f:

        def keep(rec: dict) -> None:
            f.write(json.dumps(rec) + "\n")
            f.flush()
            os.fsync(f.fileno())
            done[rec["seed"]] = rec
            bar.update(1)

        if args.workers > 1 and len(todo) > 1:
            with mp.get_context("spawn").Pool(args.workers) as pool:
                for rec in pool.imap_unordered(job, todo):
                    keep(rec)
        else:
            for seed in todo:
                keep(job(seed))
    bar.close()
    records = [done[s] for s in keys if s in done]
    figures = summary(records)
    (out_dir / "summary.json").write_text(json.dumps(figures, indent=1) + "\n")
    if args.plot is not None and not only_twin:
        plot_drag(records, args.plot, label)
    if args.json:
        print(json.dumps(figures))
    else:
        print(report(figures, label))
    return 0


def twin_steps(text: str) -> tuple[float, ...]:
    """``--twin-steps``: comma-separated physics steps [s], each in (0, 0.01]."""
    try:
        steps = tuple(float(x) for x in text.split(","))
    except ValueError:
        steps = ()
    if not steps or any(not (0.0 < dt <= 0.01) for dt in steps):
        raise argparse.ArgumentTypeError(
            f"expected comma-separated steps in (0, 0.01] s such as 0.005,0.003, got {text!r}"
        )
    return steps


def plot_drag(records: list[dict], path: Path, seeds: str) -> None:
    """Histograms of the cabinet's displacement after single wrong-model pulls and after
    sequences of four, with the paper's 0.1 m limit marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    parts = [p for r in records for p in r["parts"]]
    single = [w["displacement"] for p in parts for w in p["wrong"]]
    four = [p["sequence"][-1] for p in parts if p.get("sequence")]
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.6), sharey=False)
    bins = np.linspace(0.0, max(0.3, max(single + four, default=0.3)), 31)
    for ax, data, title in (
        (axes[0], single, f"one wrong pull ({len(single)} pulls)"),
        (axes[1], four, f"four wrong pulls in a row ({len(four)} sequences)"),
    ):
        ax.hist(data, bins=bins, color="#4477aa")
        ax.axvline(0.1, color="#cc3311", ls="--", label="0.1 m: the episode fails (-10)")
        over = sum(d > 0.1 for d in data)
        ax.set_title(f"{title}: {over} past 0.1 m")
        ax.set_xlabel("cabinet base displacement from its start [m]")
        ax.set_ylabel("count")
        ax.legend(loc="upper right", fontsize=8)
    fig.suptitle(f"Wrong-model pulls drag the cabinet (generated cabinets {seeds})", fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def report(fig: dict, seeds: str) -> str:
    """The figures as lines a person reads (the ``--json`` object has them all)."""
    pct = lambda r: f"{r['ok']}/{r['n']} ({100 * r['ok'] / max(r['n'], 1):.0f}%)"  # noqa: E731
    lines = [
        f"eval_skills on {seeds if seeds.startswith('objects') else 'generated cabinets ' + seeds}"
    ]
    if "open_drawer" not in fig:  # --only twin
        return "\n".join(lines + twin_lines(fig, pct))
    for cat in ("open_drawer", "open_door", "open_flap"):
        r = fig[cat]
        causes = ", ".join(f"{k} {v}" for k, v in sorted(r["causes"].items()) if k != "ok")
        lines.append(f"  {cat:12s} {pct(r):14s} failures: {causes or '-'}; no room for the "
                     f"object: {r['no_room']}; median {r['median_wall_s'] or 0:.2f} s")  # fmt: skip
    w = fig["wrong_model"]
    d = w["displacement_m"]
    lines.append(f"  wrong model  {w['dragged']['ok']}/{w['dragged']['n']} single pulls "
                 f"dragged the cabinet past 0.1 m; {w['dragged_after_4']}/{w['sequences']} "
                 f"sequences of four; false successes {w['false_success']}")  # fmt: skip
    lines.append(f"               displacement per pull p50 {d['p50']:.3f} p90 {d['p90']:.3f} "
                 f"max {d['max']:.3f} m; statuses {w['statuses']}")  # fmt: skip
    for kind, probes in fig["probes"].items():
        cells = ", ".join(f"{k} {v['moved']}/{v['n']} (median {v['median_motion'] or 0:.3f})"
                          for k, v in probes.items())  # fmt: skip
        lines.append(f"  probes {kind:9s} moved: {cells}")
    lines.append(f"  chains       drawer {pct(fig['chain_drawer'])}, door {pct(fig['chain_door'])}")
    lines += twin_lines(fig, pct)
    per = ", ".join(f"{k} {v:.2f}" for k, v in fig["seconds"]["median_per_skill_s"].items())
    lines.append(f"  seconds      median wall per full-robot run [s]: {per}; "
                 f"total {fig['seconds']['total_s']:.0f} s")  # fmt: skip
    return "\n".join(lines)


def twin_lines(fig: dict, pct) -> list[str]:
    """The twin's report lines: the reported twin, then one line per physics step
    when several ran."""
    t = fig["twin"]
    lines = [f"  twin         agreement {pct(t['agreement'])} (strict "
             f"{pct(t['agreement_strict'])}), speed-up {t['speedup'] or 0:.1f}x "
             f"(cold {t['speedup_cold'] or 0:.1f}x)",
             f"               disagreements (full vs twin) {t['disagreements']}"]  # fmt: skip
    steps = fig.get("twin_steps", {})
    if len(steps) > 1:
        for k, t in steps.items():
            lines.append(f"  twin {float(k) * 1e3:4.1f} ms agreement {pct(t['agreement'])} "
                         f"(strict {pct(t['agreement_strict'])}), speed-up "
                         f"{t['speedup'] or 0:.1f}x")  # fmt: skip
    return lines


if __name__ == "__main__":
    raise SystemExit(main())
