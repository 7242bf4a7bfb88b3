"""Write procedurally generated cabinets in the PartNet-Mobility layout.

Each cabinet goes to ``OUT/<name>_<seed>/`` with ``mobility.urdf``, ``semantics.txt``
and ``spec.json`` (the generator's ground truth: joints, handles, interiors), for seeds
``SEED .. SEED + COUNT - 1``. The committed examples in ``models/cabinets`` were made
with::

    python tools/generate_cabinets.py --seed 11 --kinds drawer --out models/cabinets
    python tools/generate_cabinets.py --seed 7 --kinds door --out models/cabinets
    python tools/generate_cabinets.py --seed 17 --out models/cabinets

``--check`` loads every written cabinet in MuJoCo and Pinocchio and prints its size.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from planners.errors import PlannersError
from strug_manip.objects import load_articulated_object, write_partnet
from strug_manip.objects.generator import PART_KINDS, generate_cabinet

_NAMES = {("drawer",): "drawers", ("door",): "doors", ("shelf",): "shelves"}


def default_name(kinds: tuple[str, ...]) -> str:
    """Folder prefix: ``drawers``, ``doors``, ``shelves`` for one kind, else ``mixed``."""
    return _NAMES.get(kinds, "mixed")


def main(argv: list[str] | None = None) -> int:
    """Parse the command line, write the cabinets; return the exit status."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seed", type=int, default=0, help="first seed (default 0)")
    ap.add_argument("--count", type=int, default=1, help="number of cabinets (default 1)")
    ap.add_argument("--out", type=Path, required=True, help="output folder")
    ap.add_argument(
        "--kinds",
        default=",".join(PART_KINDS),
        help=f"comma-separated part kinds among {','.join(PART_KINDS)} (default: all)",
    )
    ap.add_argument("--name", default=None, help="folder prefix (default: from --kinds)")
    ap.add_argument("--check", action="store_true", help="load each one in MuJoCo + Pinocchio")
    args = ap.parse_args(argv)
    if args.count < 1 or args.seed < 0:
        ap.error("--count must be >= 1 and --seed >= 0")
    kinds = tuple(k.strip() for k in args.kinds.split(",") if k.strip())
    name = args.name or default_name(kinds)
    for seed in range(args.seed, args.seed + args.count):
        t0 = time.perf_counter()
        try:
            spec = generate_cabinet(seed, kinds=kinds)
        except PlannersError as e:
            ap.error(str(e))
        folder = write_partnet(spec, args.out / f"{name}_{seed}")
        line = (
            f"{folder}: {spec.rows}x{spec.cols} cells "
            f"({', '.join(p.kind for p in spec.parts)}), {spec.mass:.1f} kg"
        )
        if args.check:
            obj = load_articulated_object(folder)
            line += (
                f"; MuJoCo nv={obj.mj_model.nv}, Pinocchio nv={obj.pin_model.nv}, "
                f"{time.perf_counter() - t0:.3f} s"
            )
        print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
