"""What the full robot does after a stop rule ends a skill's run
(:class:`~.fetch_body.FullRobot`): the arm and base hold where they stopped, then

- stopped at the part (a line, a grip, the stow): the fingers open (a skill that
  carries the object and still holds it keeps it), the gripper backs off along its
  approach, and the arm stows (:meth:`Recovery._recover`);
- stopped on the way (the reach: the carried object or the arm met the cabinet): the
  arm stows from where it is (:meth:`Recovery._withdraw`).

Each motion is monitored by the cabinet guard from where the recovery starts: one that
slides or tips the cabinet stops where it is. The planning twin mirrors the first
(:meth:`~.twin_rollout.TwinRollout.recovery`); its hand enters the scene at the
pre-grasp, so it has no reach to stop."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from strug_manip.control.cabinet_guard import Mark
from strug_manip.control.executor import drive_posture, keeps_object, recovery_poses
from strug_manip.control.outcome import SkillStop
from strug_manip.robot.fetch import GRIPPER_SITE, GRIPPER_SQUEEZE


class Recovery:
    """The full robot's recoveries (a mixin of :class:`~.fetch_body.FullRobot`, whose
    driver, guard, plan and planners it uses)."""

    def _recover(self) -> str:
        """After a stop at the part: open the fingers (a skill that carries the object
        and still holds it keeps it), back the gripper off along its approach
        (:func:`recovery_poses`, IK from where the arm is), then stow (OMPL), so that the
        next skill starts from the drive posture. Returns "" or what failed (the run's
        status stays the stop's)."""
        p = self.params
        carrying = self._hold_here()
        if carrying is None:
            self.drv.grip(False, p.grip_time, GRIPPER_SQUEEZE)
        start = self._command()
        T0 = self.world.site_pose(GRIPPER_SITE)
        poses, length = recovery_poses(T0, p)
        track = self.ctx.ik.track(poses, start)
        backs_off = track.success
        if backs_off:  # checked like every executed path (the hand may touch the part)
            checker = self._checker(carrying)
            checker.allow(checker.hand_with([checker.body_id(b) for b in self._touched()]))
            base = self.drv.base
            backs_off = not checker.path([np.concatenate([base, q]) for q in track.q])
            checker.allow()
        # A recovery that slides the cabinet (an arm stowed through a part that is not
        # where the robot believes it) stops where it is, as a skill does.
        since = self._guard.here()
        if backs_off:
            try:
                seconds = max(0.3, length / p.retreat_speed)
                self.drv.follow(list(track.q), seconds, monitor=self._watch("recovery", since))
            except SkillStop as stop:
                return self._stopped_here(stop)
            self.drv.hold(p.settle_time)
        failed = self._stow(carrying, since)
        return failed or (
            "" if backs_off else "; recovery: no free IK path to back off, stowed from there"
        )

    def _withdraw(self) -> str:
        """After a stop on the way to the part (the object carried, or the arm, met
        something: ``cabinet_moved``, ``collision``): the arm and base hold where they
        stopped, then the arm stows (OMPL, monitored), what it carries kept. Without the
        hold the servos went on pushing to the stopped path's next command while the
        run settled: a ``Place`` whose carried object met the closed door beside its
        cell on the reach stopped at a 3 cm slide and left the cabinet 0.15 m from
        where it stood (OpenDoor episode 10187). Returns "" or what failed."""
        carrying = self._hold_here()
        self.drv.hold(self.params.settle_time)
        return self._stow(carrying, self._guard.here())

    def _hold_here(self) -> tuple[str, np.ndarray] | None:
        """Command the arm and base to where they stopped, not their old commands;
        returns what the hand carries and keeps (as :meth:`_carried`), or None."""
        self.drv.arm_cmd, self.drv.base_target = self.drv.q, self.drv.base
        keeps = keeps_object(self._plan, self.drv.grip_cmd, self._fingers())
        return self._carried() if keeps else None

    def _watch(self, name: str, since: Mark | None = None) -> Callable[[float], None]:
        """A monitor stopping the motion ``name`` (``cabinet_moved``) once the cabinet
        has moved past the guards' limits from ``since`` (default: the skill's start)."""

        def monitor(_: float) -> None:
            self._guard.check(name, since)

        return monitor

    def _stopped_here(self, stop: SkillStop) -> str:
        """A recovery's motion stopped by its monitor: the arm holds where it is."""
        self.drv.arm_cmd = self.drv.q
        self.drv.hold(self.params.settle_time)
        return f"; recovery: the arm stopped where it was ({stop.detail})"

    def _stow(self, carrying: tuple[str, np.ndarray] | None, since: Mark) -> str:
        """Stow the arm (OMPL, the drive posture), monitored from ``since``; returns ""
        or what failed."""
        goal = drive_posture(carrying)
        try:
            path = self._plan_arm(self.drv.q, goal, carrying, phase="recovery")
        except SkillStop as stop:
            return f"; recovery: the arm stays out ({stop.detail})"
        try:
            self.drv.follow(list(path), 0.3, monitor=self._watch("recovery", since))
        except SkillStop as stop:
            return self._stopped_here(stop)
        self.drv.hold(self.params.settle_time)
        return ""
