"""Save an image strip of the skills at work: ``docs/controllers.png``.

Usage::

    python tools/controller_strip.py [--out docs/controllers.png] [--width 480]

Three rows of overview-camera frames at each run's key instants, full robot, true
models: ``OpenDrawer`` on the top drawer ``link_1`` of ``models/cabinets/drawers_11``
(generator seed 11: start, pre-grasp, grasped, pulled open, back in its tuck),
``OpenDoor`` on the right-hinged door ``link_1`` of the doors-only cabinet of seed 25
(the same instants; the overview camera sees its swing past the robot), and the chain
that follows the first row: ``Pick`` of the box on its table (grasped, lifted) then
``Place`` of it into the open drawer (above it, released, back in the tuck). Each row's
title gives the outcomes' statuses.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from strug_manip.control import (
    ControlContext,
    OpenDoor,
    OpenDrawer,
    Pick,
    Place,
    handle_grasps,
    place_target,
)
from strug_manip.objects.hypotheses import BelievedJoint
from strug_manip.world import ManipulationWorld, SceneConfig

ROOT = Path(__file__).resolve().parent.parent
#: Key instants shown for an opening (the observer's names).
OPENING_KEYS = ("start", "pre-grasp", "grasp", "move", "end")


def opening(world: ManipulationWorld, link: str):
    """The true-model opening of ``link`` with its first handle grasp."""
    part = world.scene.cabinet_spec.part(link)
    T = world.scene.T_world_cabinet
    g = handle_grasps(part, 0.0, T)[0]
    joint = BelievedJoint.of_part(part, 0.0, T)
    return OpenDrawer(g, joint) if joint.type == "prismatic" else OpenDoor(g, joint)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "controllers.png")
    parser.add_argument("--width", type=int, default=480, help="frame width [px] (4:3)")
    args = parser.parse_args()
    w, h = args.width, args.width * 3 // 4
    ctx = ControlContext()
    rows: list[tuple[str, list[tuple[str, np.ndarray]]]] = []

    def grab(world: ManipulationWorld, frames: list, keep: tuple[str, ...], prefix: str = ""):
        def observe(name: str) -> None:
            if name in keep:
                frames.append((prefix + name, world.render_rgb("overview", w, h)))

        return observe

    drawers = ManipulationWorld(SceneConfig(cabinet_seed=11, cabinet_kinds=("drawer",)))
    frames: list = []
    out = opening(drawers, "link_1").run(
        drawers, ctx=ctx, observer=grab(drawers, frames, OPENING_KEYS)
    )
    rows.append((f"OpenDrawer: {out.status}", frames))

    doors = ManipulationWorld(SceneConfig(cabinet_seed=25, cabinet_kinds=("door",)))
    frames = []
    out = opening(doors, "link_1").run(doors, ctx=ctx, observer=grab(doors, frames, OPENING_KEYS))
    rows.append((f"OpenDoor: {out.status}", frames))
    doors.close()

    spec = drawers.scene.cabinet_spec
    joint = drawers.scene.cabinet_prefix + spec.part("link_1").joint
    root = drawers.scene.cabinet_prefix + drawers.scene.cabinet.root
    target = place_target(spec, "link_1", drawers.part_positions()[joint], drawers.body_pose(root))
    frames = []
    a = Pick("object", target.grasp).run(
        drawers, ctx=ctx, observer=grab(drawers, frames, ("grasp", "lift"), "pick ")
    )
    b = Place.onto(target).run(
        drawers, ctx=ctx, observer=grab(drawers, frames, ("pre-grasp", "release", "end"), "place ")
    )
    rows.append((f"Pick: {a.status}, Place: {b.status}", frames))
    drawers.close()

    cols = max(len(f) for _, f in rows)
    sheet = Image.new("RGB", (cols * w, len(rows) * h), "white")
    draw = ImageDraw.Draw(sheet)
    for r, (title, frames) in enumerate(rows):
        for c, (name, rgb) in enumerate(frames):
            sheet.paste(Image.fromarray(rgb), (c * w, r * h))
            label = f"{title} | {name}" if c == 0 else name
            draw.rectangle((c * w, r * h, c * w + 7 * len(label) + 8, r * h + 16), fill="black")
            draw.text((c * w + 4, r * h + 3), label, fill="white")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(args.out, optimize=True)
    print(f"saved {args.out} ({sheet.width}x{sheet.height} px)")


if __name__ == "__main__":
    main()
