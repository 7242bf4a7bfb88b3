"""The full robot's watch on the cabinet while a skill runs.

:class:`CabinetGuard` applies the executor core's cabinet rules (:mod:`.executor`) to
the full robot's world at every control tick: the slide and tilt guards
(:func:`~.executor.cabinet_slid`, :func:`~.executor.cabinet_tipped`: ``cabinet_moved``)
and an opening's end (:func:`~.executor.at_part_end`: ``ok``). The planning twin
applies the same rules to its rollouts' states (:mod:`.twin_rollout`)."""

from __future__ import annotations

import numpy as np

from strug_manip.control.executor import (
    OpeningPath,
    at_part_end,
    cabinet_slid,
    cabinet_tipped,
    stop_detail,
    strained,
    tilt_of,
    tipped_detail,
)
from strug_manip.control.outcome import SkillStop, Status
from strug_manip.control.params import SkillParams
from strug_manip.control.plan import SkillPlan
from strug_manip.geometry import quat_of
from strug_manip.world.sim import ManipulationWorld

#: Where the cabinet stood: its base's horizontal displacement (2,) [m] and up axis (3,).
Mark = tuple[np.ndarray, np.ndarray]


class CabinetGuard:
    """Watches the cabinet of ``world`` from where it stands now (the skill's start).

    Args:
        world: the full robot's world.
        params: the skills' constants (the guards' limits).
    """

    def __init__(self, world: ManipulationWorld, params: SkillParams) -> None:
        self.world, self.params = world, params
        self.pose0 = world.cabinet_pose()  # the cabinet base where the skill started
        self.start = self.here()
        self.early = False  # the opening's part strained in its first end_share

    def here(self) -> Mark:
        """Where the cabinet stands now (e.g. as a recovery starts)."""
        return self.world.cabinet_displacement_vector(), self.world.cabinet_pose()[:3, 2]

    def opening(self, plan: SkillPlan) -> OpeningPath | None:
        """``plan``'s opening path, against the cabinet where the skill started."""
        return OpeningPath.of(plan, self.pose0)

    def check(self, name: str, since: Mark | None = None) -> None:
        """Stop ``cabinet_moved`` when the cabinet has slid more than
        ``cabinet_motion_limit`` or tipped more than ``cabinet_tilt_limit`` since
        ``since`` (default: the skill's start), in the motion ``name``."""
        ref, up0 = self.start if since is None else since
        slid = float(np.linalg.norm(self.world.cabinet_displacement_vector() - ref))
        if cabinet_slid(slid, self.params):
            raise SkillStop(Status.CABINET_MOVED, stop_detail(Status.CABINET_MOVED, name, slid))
        up = self.world.cabinet_pose()[:3, 2]
        if cabinet_tipped(up0, up, self.params):
            raise SkillStop(Status.CABINET_MOVED, tipped_detail(name, float(tilt_of(up0, up))))

    def check_end(self, path: OpeningPath, cmd: np.ndarray, behind: np.ndarray, name: str) -> None:
        """Stop ``ok`` where the opening's part has met its end (:func:`at_part_end`):
        ``cmd`` the commanded TCP, ``behind`` how far the TCP is behind it, (3,) [m]."""
        p = self.params
        T = self.world.cabinet_pose()
        give = path.give(T[:3, 3], quat_of(T[:3, :3]))
        share = float(path.share(cmd))
        if share < p.end_share:
            self.early |= bool(strained(np.linalg.norm(give), np.linalg.norm(behind), p))
            return
        t = path.tangent(cmd)
        if at_part_end(share, self.early, strained(give @ t, behind @ t, p), p):
            raise SkillStop(Status.OK, stop_detail(Status.OK, name, share), name)
