"""The Fetch's commands, stepped with MuJoCo physics: the one driver of the skills.

:class:`JointDriver` holds the robot's targets and writes them to the actuators at
every physics step. The servos themselves are the MJCF's (``models/fetch``): position
servos with integral action (MuJoCo's PID actuators) on the planar base, the torso and
the arm, each clamped at the Fetch's effort limit, and the finger servo, which either
opens (:data:`~strug_manip.robot.fetch.GRIPPER_OPEN`) or squeezes
(:data:`~strug_manip.robot.fetch.GRIPPER_SQUEEZE`: saturated at 60 N per finger,
whatever is held).

Motions follow the one timing law (:mod:`.timing`) within the joint speed limits
(:func:`~strug_manip.robot.fetch.speed_limits`) and the base speed limits
(:data:`BASE_SPEED`). The driver records the world's ``qpos`` every ``record_period``
and the wall time spent stepping physics, stops a run that exceeds its simulated time
budget (``timeout``), and calls a *monitor* every :data:`MONITOR_PERIOD` during a
motion, which may stop it (a lost grasp, a blocked arm).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import mujoco
import numpy as np

import strug_manip.control.timing as timing
from strug_manip.control.outcome import SkillStop, Status
from strug_manip.robot.fetch import (
    ACTUATORS,
    ARM_TORSO_JOINTS,
    BASE_JOINTS,
    GRIPPER_OPEN,
    speed_limits,
)
from strug_manip.world.sim import ManipulationWorld

#: Base speed limits (x, y [m/s], yaw [rad/s]): the Fetch's 1.0 m/s, slowed indoors.
BASE_SPEED = (0.3, 0.3, 0.9)
#: Period of the monitor calls during a motion [s].
MONITOR_PERIOD = 0.01

#: A monitor: called during motions with the time [s] since the motion started; it
#: raises :class:`SkillStop` to stop the run.
Monitor = Callable[[float], None]


class JointDriver:
    """Commands the Fetch in ``world`` while stepping its physics.

    Args:
        world: the scene (its state advances).
        time_budget: simulated time after which a run stops with ``timeout`` [s].
        record_period: period of the recorded ``qpos`` [s].
    """

    def __init__(
        self, world: ManipulationWorld, time_budget: float = 60.0, record_period: float = 0.02
    ) -> None:
        m = world.model
        self.world, self.m, self.d = world, m, world.data

        self.base_act = np.array([world.ctrl_index(ACTUATORS[j]) for j in BASE_JOINTS])
        self.base_adr = np.array([m.jnt_qposadr[m.joint(j).id] for j in BASE_JOINTS])
        self.arm_act = np.array([world.ctrl_index(ACTUATORS[j]) for j in ARM_TORSO_JOINTS])
        self.arm_adr = np.array([m.jnt_qposadr[m.joint(j).id] for j in ARM_TORSO_JOINTS])
        self.grip_act = world.ctrl_index("gripper")
        # Where the commands go in ``ctrl``, as slices where the actuators are evenly
        # spaced (they are in the Fetch's model: a step spends less time indexing).
        self._ctrl_at = tuple(
            _as_index(i) for i in (self.base_act, self.base_act + 1, self.arm_act, self.arm_act + 1)
        )
        self.vmax = speed_limits(m)
        self.base_speed = np.array(BASE_SPEED)
        self.base_target = self.base
        self.arm_cmd = self.q
        # Velocity targets of the servos (their second control): the motion's own
        # velocity, so the damping term does not brake the arm behind its path.
        self.base_vel = np.zeros(3)
        self.arm_vel = np.zeros(len(ARM_TORSO_JOINTS))
        self.grip_cmd = float(self.d.ctrl[self.grip_act])
        self.t0 = float(self.d.time)
        self.time_budget = time_budget
        self.every = max(1, round(record_period / m.opt.timestep))
        self.count = 0
        self.times: list[float] = []
        self.rows: list[np.ndarray] = []
        self.physics_seconds = 0.0

    # -- state -------------------------------------------------------------------------
    @property
    def base(self) -> np.ndarray:
        """Measured base pose (x [m], y [m], yaw [rad]), (3,)."""
        return self.d.qpos[self.base_adr].copy()

    @property
    def q(self) -> np.ndarray:
        """Measured torso + arm positions, (8,) [m, rad]."""
        return self.d.qpos[self.arm_adr].copy()

    @property
    def elapsed(self) -> float:
        """Simulated time since the driver was made [s]."""
        return float(self.d.time) - self.t0

    # -- stepping ----------------------------------------------------------------------
    def _step(self) -> None:
        d = self.d
        if d.time - self.t0 > self.time_budget:
            raise SkillStop(Status.TIMEOUT, f"the run exceeded its {self.time_budget:.0f} s budget")
        ctrl = d.ctrl
        base, base_vel, arm, arm_vel = self._ctrl_at
        ctrl[base] = self.base_target
        ctrl[base_vel] = self.base_vel
        ctrl[arm] = self.arm_cmd
        ctrl[arm_vel] = self.arm_vel
        ctrl[self.grip_act] = self.grip_cmd
        t = time.perf_counter()
        mujoco.mj_step(self.m, d)
        self.physics_seconds += time.perf_counter() - t
        if self.count % self.every == 0:
            self.times.append(self.elapsed)
            self.rows.append(d.qpos.copy())
        self.count += 1

    def hold(self, seconds: float) -> None:
        """Keep every command and step ``seconds`` [s]."""
        for _ in range(max(1, round(seconds / self.m.opt.timestep))):
            self._step()

    def follow(
        self,
        path: Sequence[np.ndarray],
        seconds: float,
        base_path: Sequence[np.ndarray] | None = None,
        monitor: Monitor | None = None,
        comply: Callable[[], np.ndarray] | None = None,
    ) -> float:
        """Move torso + arm through ``path`` (each (8,)) under the timing law, in at
        least ``seconds`` [s] (longer where a speed limit needs it), the base along
        ``base_path`` (each (3,)) if given; returns the duration used [s]. ``comply``,
        called every :data:`MONITOR_PERIOD` before the monitor, returns an offset (8,)
        added to the torso and arm commands from then on (a hand that gives way,
        :class:`~.compliance.HandCompliance`)."""
        n = len(self.arm_cmd)
        # A hand that has given way goes on from the plan's pose, the offset added.
        offset = comply() if comply is not None else np.zeros(n)
        pts = timing.polyline(self.arm_cmd - offset, path)
        limits = self.vmax
        if base_path is not None:  # one timing for both, so they stay in step
            pts = np.hstack([pts, timing.polyline(self.base_target, base_path)])
            limits = np.concatenate([self.vmax, self.base_speed])
        T = timing.duration(pts, limits, seconds)
        dt = self.m.opt.timestep
        cmds = timing.samples(pts, T, dt, limits)
        vels = np.diff(np.vstack([pts[:1], cmds]), axis=0) / dt
        vels[-1] = 0.0  # the motion ends at rest
        every = max(1, round(MONITOR_PERIOD / dt))
        try:
            for k in range(len(cmds)):
                self.arm_cmd, self.arm_vel = cmds[k, :n] + offset, vels[k, :n]
                if base_path is not None:
                    self.base_target, self.base_vel = cmds[k, n:], vels[k, n:]
                self._step()
                if k % every == every - 1:
                    if comply is not None:
                        offset = comply()
                    if monitor is not None:
                        monitor((k + 1) * dt)
        finally:  # a monitor's stop too: the servos stop feeding the path's velocity
            # forward (a hand stopped at a door's hinge stop kept pulling at it through
            # the grip's release and twisted the cabinet 10 degrees)
            self.arm_vel = np.zeros(n)
            self.base_vel = np.zeros(3)
        return T

    def move(self, q_goal: np.ndarray, seconds: float, monitor: Monitor | None = None) -> float:
        """Torso + arm straight (joint space) to ``q_goal`` (8,) in at least ``seconds``."""
        return self.follow([np.asarray(q_goal, dtype=float)], seconds, monitor=monitor)

    def drive(
        self,
        route: Sequence[np.ndarray],
        torso: float | None = None,
        monitor: Monitor | None = None,
    ) -> None:
        """Drive the base through the poses of ``route`` (each (3,): x, y, yaw) and wait
        until it stands within 5 mm and 5 mrad of the last (at most 3 s more); the torso
        moves to ``torso`` [m] on the way if given. ``monitor`` is called every
        :data:`MONITOR_PERIOD` with the time driven [s] (a stop it raises ends the drive
        where the base is; the servos stop feeding the route's velocity forward)."""
        goal_arm = self.arm_cmd.copy()
        if torso is not None:
            goal_arm[0] = torso
        dt = self.m.opt.timestep
        every = max(1, round(MONITOR_PERIOD / dt))
        n = 0  # steps driven

        def step() -> None:
            nonlocal n
            self._step()
            n += 1
            if monitor is not None and n % every == 0:
                monitor(n * dt)

        try:
            for k, target in enumerate(route):
                start = self.base_target.copy()
                pts = np.array([start, np.asarray(target, dtype=float)])
                T = max(0.5, timing.duration(pts, self.base_speed, 0.0))
                arm_pts = np.array([self.arm_cmd, goal_arm])
                if k == 0:  # the torso rises on the way, within its (slow) speed limit
                    T = timing.duration(arm_pts, self.vmax, T)
                base = timing.samples(pts, T, dt)
                bvel = np.diff(np.vstack([pts[:1], base]), axis=0) / dt
                arm = timing.samples(arm_pts, T, dt) if k == 0 else None
                for i in range(len(base)):
                    self.base_target, self.base_vel = base[i], bvel[i]
                    if arm is not None:
                        self.arm_cmd = arm[i]
                    step()
                self.base_vel = np.zeros(3)
            for _ in range(30):
                err = np.abs(self.base_target - self.base)
                if err[0] < 0.005 and err[1] < 0.005 and err[2] < 0.005:
                    return
                for _ in range(max(1, round(0.1 / dt))):
                    step()
        finally:
            self.base_vel = np.zeros(3)

    def grip(self, closed: bool, seconds: float, squeeze: float) -> None:
        """Close (command ``squeeze``) or open the fingers and step ``seconds`` [s]."""
        self.grip_cmd = squeeze if closed else GRIPPER_OPEN
        self.hold(seconds)

    def recording(self) -> tuple[np.ndarray, np.ndarray]:
        """(times (T,) [s], qpos (T, nq)) recorded so far."""
        if not self.rows:
            return np.zeros(0), np.zeros((0, self.m.nq))
        return np.array(self.times), np.vstack(self.rows)


def _as_index(idx: np.ndarray) -> slice | np.ndarray:
    """``idx`` (k,) as a slice where its entries are evenly spaced and increasing, else
    itself (the same elements of an array either way)."""
    if len(idx) > 1:
        step = int(idx[1] - idx[0])
        if step > 0 and np.all(np.diff(idx) == step):
            return slice(int(idx[0]), int(idx[-1]) + 1, step)
    elif len(idx) == 1:
        return slice(int(idx[0]), int(idx[0]) + 1)
    return idx
