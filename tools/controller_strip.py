"""Save an image strip of the controllers at work: ``docs/controllers.png``.

Usage::

    python tools/controller_strip.py [--out docs/controllers.png] [--width 480]

Three rows of overview-camera frames at each run's key instants (under the true
model, generator seed 3): ``OpenDrawer`` on the top drawer of the drawer cabinet
(start, pre-grasp, grasp, pulled open), ``OpenDoor`` on the right-hinged door of the
door cabinet (same instants), and ``Pick`` of the box on the table then ``Place`` of it
into the top drawer opened 0.2 m (grasp, lifted, above the drawer, released).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from strug_manip.control.controllers import (
    OpenDoor,
    OpenDrawer,
    Pick,
    Place,
    handle_grasp,
    true_joint,
)
from strug_manip.world import ManipulationWorld, SceneConfig

ROOT = Path(__file__).resolve().parent.parent


def _place_pose(world: ManipulationWorld, q: float) -> np.ndarray:
    part = world.scene.cabinet_spec.part("link_1")
    T = world.scene.T_world_cabinet
    c = (T @ np.r_[part.point_at(part.interior_center, q), 1.0])[:3]
    s = part.interior_size
    p = np.eye(4)
    p[:3, 3] = [min(c[0] + s[0] / 2, 0.98) - 0.07, c[1], c[2] - s[2] / 2 + 0.045]
    return p


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "controllers.png")
    parser.add_argument("--width", type=int, default=480, help="frame width [px] (4:3)")
    args = parser.parse_args()
    w, h = args.width, args.width * 3 // 4
    rows: list[tuple[str, list[tuple[str, np.ndarray]]]] = []

    def grab(world: ManipulationWorld, frames: list, keep: tuple[str, ...], prefix: str = ""):
        def observe(name: str) -> None:
            if name in keep:
                frames.append((prefix + name, world.render_rgb("overview", w, h)))

        return observe

    drawers = ManipulationWorld(SceneConfig(cabinet_seed=3, cabinet_kinds=("drawer",)))
    frames: list = []
    g = handle_grasp(drawers, "link_1")
    out = OpenDrawer(g, true_joint(drawers, "link_1")).run(
        drawers, observer=grab(drawers, frames, ("start", "pre-grasp", "grasp", "end"))
    )
    rows.append((f"OpenDrawer: {out.reason}", frames))

    doors = ManipulationWorld(SceneConfig(cabinet_seed=3, cabinet_kinds=("door",)))
    frames = []
    g = handle_grasp(doors, "link_1")
    out = OpenDoor(g, true_joint(doors, "link_1")).run(
        doors, observer=grab(doors, frames, ("start", "pre-grasp", "grasp", "end"))
    )
    rows.append((f"OpenDoor: {out.reason}", frames))

    drawers.reset({"joint_1": 0.2})
    frames = []
    a = Pick("object").run(drawers, observer=grab(drawers, frames, ("grasp", "end"), "pick "))
    b = Place("object", _place_pose(drawers, 0.2)).run(
        drawers, observer=grab(drawers, frames, ("pre-place", "end"), "place ")
    )
    rows.append((f"Pick: {a.reason}, Place: {b.reason}", frames))
    drawers.close()
    doors.close()

    cols = max(len(f) for _, f in rows)
    sheet = Image.new("RGB", (cols * w, len(rows) * h), "white")
    draw = ImageDraw.Draw(sheet)
    for r, (title, frames) in enumerate(rows):
        for c, (name, rgb) in enumerate(frames):
            sheet.paste(Image.fromarray(rgb), (c * w, r * h))
            label = f"{title} | {name}" if c == 0 else name
            draw.rectangle((c * w, r * h, c * w + 8 * len(label) + 8, r * h + 16), fill="black")
            draw.text((c * w + 4, r * h + 3), label, fill="white")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(args.out, optimize=True)
    print(f"saved {args.out} ({sheet.width}x{sheet.height} px)")


if __name__ == "__main__":
    main()
