"""The skills as actions: discrete parameters (which part, which object grasp) and the
continuous ones drawn from the belief (the grasp ``g``, the believed joint an opening
follows, the placement ``p``).

Parts are named across particles by *where they are*: every particle's parts with a
handle (and, for Shelf, its open cells) are grouped by the world position of their
handle (cell centre for a shelf) within :data:`SAME_PART` (:func:`catalogue`). A
group is one :class:`CataloguePart`: a point on the cabinet front and the distinct
kinematic hypotheses the particles hold for it (``drawer``, ``door left``, ...), each
represented by the first particle that holds it. An opening of part ``k`` under
hypothesis ``h`` grasps where that particle's handle is and follows that particle's
joint; the continuous parameters are therefore drawn from the particles' hypotheses,
one per distinct hypothesis. That makes the action set finite (at most one opening
per part and hypothesis, where HPW would draw them one at a time from the same
particles), so every solver, POMCP included, sees the same list
(:attr:`~planners.pomdp.ActionSpace.discretized`).

The placement pose ``p`` of ``Place(k)`` is not fixed in advance: it is where the
model being simulated (or, on the real robot, the likeliest particle that has part
``k``) says the object fits into part ``k`` as it now stands
(:func:`~strug_manip.control.targets.place_targets`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from strug_manip.objects.generator import CabinetSpec, PartSpec
from strug_manip.objects.hypotheses import model_of

#: Two particles' handles closer than this are the same part [m] (handles of
#: neighbouring cells are at least a cell, 0.12 m, apart; perception's handle error is
#: about 1-2 cm).
SAME_PART = 0.06
#: The skills (schema order of the action space).
SKILLS: tuple[str, ...] = ("OpenDrawer", "OpenDoor", "Pick", "Place", "Push", "PullV", "PullH")
#: The probes offered per part (the others can be asked for: ``probes=``). PullH moves
#: every kind of part (a drawer out, a door and a flap ajar), so one probe per part
#: tells the kinds apart; Push and PullV mostly do nothing to a closed part.
DEFAULT_PROBES: tuple[str, ...] = ("PullH",)


#: ``ManipAction.part`` of the ``Place`` back onto the table, where the object was
#: picked from.
TABLE = -1


class ManipAction(NamedTuple):
    """One action.

    Attributes:
        skill: one of :data:`SKILLS`.
        part: index of the :class:`CataloguePart` (-1: none, for Pick; :data:`TABLE`
            for a Place).
        hypothesis: index into that part's hypotheses (openings), else -1.
        grasp: ``top`` or ``side`` for Pick, else "".
    """

    skill: str
    part: int = -1
    hypothesis: int = -1
    grasp: str = ""


@dataclass(frozen=True)
class CataloguePart:
    """One part as the particles see it.

    Attributes:
        point: where it is: the handle (a shelf: the cell's centre), world (3,) [m].
        links: per initial particle, its link at this point (None: it has none).
        hypotheses: the distinct kinematic models held for it (``drawer``, ``left``,
            ``right``, ``top``, ``bottom``; ``shelf`` for an open cell).
        holders: per hypothesis, the first particle holding it (its grasp and joint
            are the action's).
    """

    point: np.ndarray
    links: tuple[str | None, ...]
    hypotheses: tuple[str, ...]
    holders: tuple[int, ...]

    def describe(self) -> str:
        y, z = self.point[1], self.point[2]
        return f"part@(y={y:+.2f}, z={z:.2f})"


def part_point(part: PartSpec, q: float, T: np.ndarray) -> np.ndarray | None:
    """Where ``part`` is named from: its handle at joint position ``q`` (a shelf cell:
    its centre), world (3,) [m]; None for a part that can be neither grasped nor
    filled from the front (a flat door, a panel)."""
    if part.kind == "shelf":
        return (T @ np.r_[part.cell_center, 1.0])[:3]
    if part.movable and part.handle != "none" and part.handle_pos is not None:
        return part.handle_at(q, T)
    return None


def part_kind(part: PartSpec) -> str:
    """A part's kinematic model (``drawer``, ``left``, ... as :func:`model_of`), or ``shelf``."""
    return "shelf" if part.kind == "shelf" else model_of(part)


def catalogue(
    specs: Sequence[CabinetSpec],
    qs: Sequence[dict[str, float]],
    poses: Sequence[np.ndarray],
    kinds: tuple[str, ...],
) -> tuple[CataloguePart, ...]:
    """Group the particles' parts of ``kinds`` (generator part kinds) by where they
    are (module docstring). ``specs``, ``qs`` (joint positions by joint name) and
    ``poses`` (``T_world_cabinet``, (4, 4)) are per initial particle. Parts are ordered
    top to bottom, then left to right as the robot sees them."""
    groups: list[dict] = []
    for i, (spec, q, T) in enumerate(zip(specs, qs, poses, strict=True)):
        for part in spec.parts:
            if part.kind not in kinds:
                continue
            pt = part_point(part, q.get(part.joint, 0.0), T)
            if pt is None:
                continue
            near = [g for g in groups if np.linalg.norm(g["point"] - pt) < SAME_PART]
            g = min(near, key=lambda g: np.linalg.norm(g["point"] - pt)) if near else None
            if g is None:
                g = {"point": pt, "links": {}, "hyp": {}}
                groups.append(g)
            if i in g["links"]:
                continue  # two parts of one particle at one place: the first names it
            g["links"][i] = part.link
            g["hyp"].setdefault(part_kind(part), i)
    groups.sort(key=lambda g: (-round(g["point"][2], 2), -g["point"][1]))
    return tuple(
        CataloguePart(
            point=g["point"],
            links=tuple(g["links"].get(i) for i in range(len(specs))),
            hypotheses=tuple(g["hyp"]),
            holders=tuple(g["hyp"].values()),
        )
        for g in groups
    )


def action_list(
    parts: Sequence[CataloguePart], task: str, probes: tuple[str, ...]
) -> tuple[ManipAction, ...]:
    """Every action of an episode: per part, an opening per hypothesis (``OpenDrawer``
    for a drawer hypothesis, ``OpenDoor`` for a hinge) and the probes; per part a
    ``Place``; ``Pick`` with the grasps the task needs (``top`` into drawers, ``side``
    into cells behind doors and onto shelves); ``Place`` back onto the table
    (:data:`TABLE`: a robot with one hand that picked before the part was open puts the
    object down to open it)."""
    out: list[ManipAction] = []
    for k, part in enumerate(parts):
        for h, kind in enumerate(part.hypotheses):
            if kind == "shelf":
                continue
            out.append(ManipAction("OpenDrawer" if kind == "drawer" else "OpenDoor", k, h))
        if any(kind != "shelf" for kind in part.hypotheses):
            out.extend(ManipAction(p, k) for p in probes)
    grasps = {"opendrawer": ("top",), "opendoor": ("side",), "shelf": ("side",)}[task]
    out.extend(ManipAction("Pick", grasp=g) for g in grasps)
    out.extend(ManipAction("Place", k) for k in range(len(parts)))
    out.append(ManipAction("Place", TABLE))
    return tuple(out)


def describe(a: ManipAction, parts: Sequence[CataloguePart]) -> str:
    """``OpenDrawer(part@(y=+0.10, z=0.62) as drawer)``, ``Pick(top)``, ..."""
    if a.skill == "Pick":
        return f"Pick({a.grasp})"
    if a.skill == "Place" and a.part == TABLE:
        return label(a)
    name = parts[a.part].describe() if 0 <= a.part < len(parts) else f"part {a.part}"
    if a.hypothesis >= 0:
        return f"{a.skill}({name} as {parts[a.part].hypotheses[a.hypothesis]})"
    return f"{a.skill}({name})"


def label(a: ManipAction) -> str:
    """The skill of ``a`` as reports name it: ``Place(table)`` for the Place back onto
    the table, else the skill's name."""
    return "Place(table)" if a.skill == "Place" and a.part == TABLE else a.skill


def part_at_point(
    spec: CabinetSpec, T: np.ndarray, point: np.ndarray, kinds: tuple[str, ...]
) -> str | None:
    """The part of ``kinds`` whose front cell contains ``point`` seen from the front
    (the cabinet frame's y, z), or None."""
    c = (np.linalg.inv(T) @ np.r_[point, 1.0])[:3]
    for p in spec.parts:
        if p.kind not in kinds:
            continue
        half = np.asarray(p.cell_size) / 2
        if abs(c[1] - p.cell_center[1]) <= half[0] and abs(c[2] - p.cell_center[2]) <= half[1]:
            return p.link
    return None
