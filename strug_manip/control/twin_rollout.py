"""The planning twin's rollouts: a program's controls, the stop rules of the executor
core (:mod:`.executor`) judged on the rollout's states, what follows a stop (the full
robot's recovery) or the last release (the free steps, coarser; the coast).
:class:`TwinRollout` is the part of :class:`~strug_manip.control.twin_body.PlanningTwin`
that runs them."""

from __future__ import annotations

import mujoco
import numpy as np
from mujoco import rollout

import strug_manip.control.timing as timing
from strug_manip.control.driver import MONITOR_PERIOD
from strug_manip.control.executor import (
    OPENING_LINES,
    REST_SPEED,
    OpeningPath,
    at_part_end,
    cabinet_slid,
    cabinet_tipped,
    grasp_lost,
    held_back,
    keeps_object,
    recovery_poses,
    stop_detail,
    strained,
    tilt_of,
    tipped_detail,
)
from strug_manip.control.outcome import Status
from strug_manip.control.twin_program import COAST_TIME, Program
from strug_manip.geometry import x_axes, z_axes
from strug_manip.robot.fetch import GRIPPER_OPEN, GRIPPER_SQUEEZE
from strug_manip.world.floating_gripper import ARM_PARK

#: After the last release (the fingers open, the hand backs away in free space: the
#: retreat, the withdraw, the stow, the coast) the twin steps this many times coarser
#: [-]: those motions seldom touch anything, and they are about 40 % of a run's steps.
#: Where they do touch (an arm link knocking an open door on the stow), the coarser
#: step can knock harder (1 of 200 tuning runs changed; README).
FREE_COARSENING = 2
#: An arm link that enters the scene (after the last release) deeper than this in
#: something [m] stays parked (:meth:`PlanningTwin._arm_starts_inside`): a link
#: resting against a door is simulated, one inside a part is not.
ARM_ENTRY_DEPTH = 0.005
#: Where the TCP (the ``gripper`` site) is in the hand's frame [m] (fetch.xml).
TCP_OFFSET = 0.02
#: What a rollout's states hold (MuJoCo's full physics: time, qpos, qvel, act, ...).
ROLLOUT_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
#: What a check on the side saves and puts back: the state and the controls.
SAVED_STATE = int(mujoco.mjtState.mjSTATE_INTEGRATION)
#: What a rollout's controls set every step: the actuators' controls and the mocap
#: bodies' poses (the believed robot base, the arm links).
CONTROL = int(
    mujoco.mjtState.mjSTATE_CTRL
    | mujoco.mjtState.mjSTATE_MOCAP_POS
    | mujoco.mjtState.mjSTATE_MOCAP_QUAT
)
#: Steps of a run's head (up to the last release) rolled out between two judgements
#: (:meth:`TwinRollout.head`) [-]: 0.25 s at the twin's 5 ms step. Shorter spans skip
#: more of the steps after a stop and cost more calls; on a search's runs (OpenDrawer,
#: seed 9100) one run in six stops early, mostly at the grasp, and the steps after
#: its stop were 12 % of all head steps.
HEAD_SPAN = 50
#: A run's verdict: the step it ends at, its status, why (one line) and the phase
#: (empty for a run that went to its end; see :func:`stopped`).
Judged = tuple[int, Status, str, str]


def stopped(judged: Judged) -> bool:
    """The run stopped before its end, at a stop rule (an opening's part at its end
    too, status ``ok`` with the phase it stopped in): the recovery follows."""
    return judged[1] is not Status.OK or bool(judged[3])


class TwinRollout:
    """The planning twin's rollouts (a mixin of
    :class:`~strug_manip.control.twin_body.PlanningTwin`, whose state it uses)."""

    def controls(self, prog: Program) -> np.ndarray:
        """The twin's control vectors at every step of ``prog``, (nstep, nu + 7 nmocap):
        the actuators' controls, then the mocap bodies' positions and orientations
        (:data:`CONTROL`)."""
        return self._controls(prog.drive_pos, prog.drive_quat, prog.grip, prog.holds, prog.arm)

    def recovery(self, prog: Program, state: np.ndarray) -> np.ndarray:
        """The controls (nstep, nu) of the full robot's recovery after a stop in
        ``state`` (a rollout state): the hand holds where it is while the fingers open
        (a skill that carries the object and holds it keeps it), then backs off along
        its approach (:func:`~strug_manip.control.executor.recovery_poses`) and
        settles."""
        m, p = self.world.model, self.params
        dt = m.opt.timestep
        qpos = state[1 : 1 + m.nq]
        quat = qpos[self._ball_adr : self._ball_adr + 4].copy()
        # The hand's rotation is not read (identity: it backs off along the world's x,
        # the robot's facing direction): reading it lowers the twin's agreement with the
        # full robot, 108/160 -> 102/160 runs on seeds 1030:1034 (docs/skills.md).
        T = np.eye(4)
        T[:3, 3] = qpos[self._slide_adr] + TCP_OFFSET * T[:3, 0]
        fingers = 0.5 * (qpos[self._fingers[0]] + qpos[self._fingers[1]])
        keep = keeps_object(prog.plan, self.grip_cmd_at_stop, fingers)
        grip = GRIPPER_SQUEEZE if keep else GRIPPER_OPEN
        self._recovery_grip = grip
        n_grip = 0 if keep else max(1, round(p.grip_time / dt))
        poses, length = recovery_poses(T, p)
        seconds = max(0.3, length / p.retreat_speed)
        pts = np.vstack([T[:3, 3], poses[:, :3, 3]])
        back = timing.samples(pts, seconds, dt)
        n_settle = max(1, round(p.settle_time / dt))
        pos = np.vstack([np.repeat(T[None, :3, 3], n_grip, axis=0), back,
                         np.repeat(back[-1:], n_settle, axis=0)])  # fmt: skip
        holds = np.ones(len(pos), dtype=bool)
        holds[n_grip : n_grip + len(back)] = False
        return self._controls(pos, np.repeat(quat[None], len(pos), axis=0),
                              np.full(len(pos), grip), holds)  # fmt: skip

    def _controls(
        self,
        pos: np.ndarray,
        quat: np.ndarray,
        grip: np.ndarray,
        holds: np.ndarray,
        arm: np.ndarray | None = None,
    ) -> np.ndarray:
        dt = self.world.model.opt.timestep
        origin = pos - TCP_OFFSET * x_axes(quat)
        vel = np.zeros_like(origin)
        vel[1:] = np.diff(origin, axis=0) / dt
        vel[holds] = 0.0
        ctrl = np.repeat(self.world.data.ctrl[None].copy(), len(origin), axis=0)
        ctrl[:, self._slide_ctrl] = origin @ self._axes
        ctrl[:, self._slide_ctrl + 1] = vel @ self._axes
        ctrl[:, self._rot_ctrl : self._rot_ctrl + 4] = quat
        ctrl[:, self._grip_ctrl] = grip
        d, nm = self.world.data, self.world.model.nmocap
        mpos = np.repeat(d.mocap_pos[None].copy(), len(origin), axis=0)
        mquat = np.repeat(d.mocap_quat[None].copy(), len(origin), axis=0)
        arm = np.repeat(self._parked_arm()[None], len(origin), axis=0) if arm is None else arm
        mpos[:, self._arm_mocap] = arm[:, :, :3]
        mquat[:, self._arm_mocap] = arm[:, :, 3:]
        return np.hstack([ctrl, mpos.reshape(-1, 3 * nm), mquat.reshape(-1, 4 * nm)])

    def park_arm(self, ctrl: np.ndarray) -> np.ndarray:
        """Control rows (n, nu + 7 nmocap) with the arm links parked."""
        out = ctrl.copy()
        nu, nm = self.world.model.nu, self.world.model.nmocap
        mpos = out[:, nu : nu + 3 * nm].reshape(-1, nm, 3)
        mquat = out[:, nu + 3 * nm :].reshape(-1, nm, 4)
        mpos[:, self._arm_mocap] = ARM_PARK
        mquat[:, self._arm_mocap] = (1.0, 0.0, 0.0, 0.0)
        return out

    def head(self, prog: Program, ctrl: np.ndarray) -> tuple[np.ndarray, Judged]:
        """Roll out the program's steps before ``prog.free`` from the twin's current
        state (``ctrl``: the whole program's controls, (nstep, nu + 7 nmocap)), in
        spans of :data:`HEAD_SPAN` steps, each judged as it comes (:meth:`judge`), up to
        the span in which the monitors stop the run: the steps after a stop are
        thrown away (the recovery starts at the stop), so they need not be simulated.
        Each span starts with the solver's warm start where the last ended, so the
        states are those of one rollout of the whole head, bit for bit. Returns the
        states (n, nstate) and the verdict."""
        m, d = self.world.model, self.world.data
        head = prog.steps(slice(0, prog.free))
        monitored = self._monitored(head)
        start = np.empty(mujoco.mj_stateSize(m, ROLLOUT_STATE))
        mujoco.mj_getState(m, d, start, ROLLOUT_STATE)
        parts: list[np.ndarray] = []
        warm = None  # a rollout's first step starts cold
        self._early = False  # no opening has strained yet (carried span to span)
        self._opening = OpeningPath.of(prog.plan, self.cabinet0)  # once, not per span
        for c in range(0, prog.free, HEAD_SPAN):
            span = ctrl[None, c : min(c + HEAD_SPAN, prog.free)]
            st, _ = rollout.rollout(m, d, start[None], span,
                                    control_spec=CONTROL, initial_warmstart=warm)  # fmt: skip
            parts.append(st[0])
            stop = self._first_stop(head, monitored, st[0], c)
            if stop is not None:
                return np.concatenate(parts), stop
            start, warm = st[0][-1], d.qacc_warmstart[None].copy()
        states = np.concatenate(parts)
        return states, (len(states) - 1, Status.OK, "", "")

    def judge(self, prog: Program, states: np.ndarray) -> Judged:
        """The first step whose monitors stop the run (a lost grasp where the fingers
        should hold, the cabinet slid more than ``cabinet_motion_limit`` since the
        skill started, the hand more than the tracking tolerance behind its command,
        checked every 10 ms as on the full robot) and why; the last step if none.
        ``states``: the rollout's state after each of the program's steps, (nstep,
        nstate)."""
        self._early = False
        self._opening = OpeningPath.of(prog.plan, self.cabinet0)
        stop = self._first_stop(prog, self._monitored(prog), states, 0)
        return (len(states) - 1, Status.OK, "", "") if stop is None else stop

    def _monitored(self, prog: Program) -> tuple[np.ndarray, np.ndarray]:
        """Per step of ``prog``, (nstep,) each: whether the monitors check there (every
        :data:`~.driver.MONITOR_PERIOD`, where a phase changes, at the last step), and
        whether the tracking rule may stop it there (not inside a hold)."""
        n, every = len(prog.pos), self._check_every()
        check = np.zeros(n, dtype=bool)
        check[every - 1 :: every] = True
        check[prog.phase_ends] = True
        check[-1] = True
        holds = prog.holds
        return check, ~holds | np.r_[holds[1:] != holds[:-1], False]

    def _first_stop(
        self,
        prog: Program,
        monitored: tuple[np.ndarray, np.ndarray],
        states: np.ndarray,
        offset: int,
    ) -> Judged | None:
        """:meth:`judge` on the states (n, nstate) after the program's steps
        ``offset .. offset + n - 1`` (``monitored``: :meth:`_monitored`): the first of
        them at which a monitor stops the run (its step index in the program) and
        why, or None. Every rule is decided at its step from that step's state (and
        the program), so a span is judged as the whole would be."""
        m = self.world.model
        sl = slice(offset, offset + len(states))
        check, may_block = monitored[0][sl], monitored[1][sl]
        qpos = states[:, 1 : 1 + m.nq]
        slid = self._slid(states, self.cabinet_xy0)
        fingers = 0.5 * (qpos[:, self._fingers[0]] + qpos[:, self._fingers[1]])
        tcp = qpos[:, self._slide_adr] + TCP_OFFSET * x_axes(
            qpos[:, self._ball_adr : self._ball_adr + 4]
        )
        lag = np.linalg.norm(tcp - prog.pos[sl], axis=1)
        lost = check & grasp_lost(prog.held[sl], fingers)
        c = self._cabinet_xy
        up = z_axes(qpos[:, c + 3 : c + 7])
        tipped = check & cabinet_tipped(self.cabinet0[:3, 2], up, self.params)
        moved = check & cabinet_slid(slid, self.params)
        blocked = check & may_block & held_back(lag, prog.tol[sl])
        ended, share, early = self._part_end(prog, sl, check, states, tcp)
        stops = np.flatnonzero(lost | ended | moved | tipped | blocked)
        self._early = bool(early[stops[0]] if len(stops) else early[-1])  # for the next span
        if not len(stops):
            return None
        i = int(stops[0])
        k, name = offset + i, str(prog.names[offset + i])
        if lost[i]:
            return k, Status.GRASP_LOST, stop_detail(Status.GRASP_LOST, name), name
        if ended[i]:
            return k, Status.OK, stop_detail(Status.OK, name, float(share[i])), name
        if moved[i]:
            return k, Status.CABINET_MOVED, stop_detail(Status.CABINET_MOVED, name, slid[i]), name
        if tipped[i]:
            tilt = float(tilt_of(self.cabinet0[:3, 2], up[i]))
            return k, Status.CABINET_MOVED, tipped_detail(name, tilt), name
        return k, Status.COLLISION, stop_detail(Status.COLLISION, name, lag[i]), name

    def _part_end(
        self, prog: Program, sl: slice, check: np.ndarray, states: np.ndarray, tcp: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where in the states (n, nstate) after the program's steps ``sl`` an opening's
        part has met its end (:func:`~.executor.at_part_end`), (n,) bool; ``check``:
        the monitors check there, ``tcp``: the hand's TCP there, (n, 3) [m]. Also the
        share of the opening there (n,) and whether the opening strained in its first
        ``end_share`` up to there (n,) (``_early``: before these states; ``_opening``:
        the run's opening path, set by :meth:`head` or :meth:`judge`)."""
        n = len(states)
        path = self._opening
        if path is None:
            return np.zeros(n, dtype=bool), np.zeros(n), np.full(n, self._early)
        m, p = self.world.model, self.params
        qpos = states[:, 1 : 1 + m.nq]
        c = self._cabinet_xy
        give = path.give(qpos[:, c : c + 3], qpos[:, c + 3 : c + 7])
        cmd = prog.pos[sl]
        behind = cmd - tcp
        share = path.share(cmd)
        opening = check & np.isin(prog.names[sl], OPENING_LINES)
        strain = strained(np.linalg.norm(give, axis=1), np.linalg.norm(behind, axis=1), p)
        first = opening & (share < p.end_share) & strain
        early = np.logical_or.accumulate(first) | self._early
        t = path.tangent(cmd)
        along = strained(np.sum(give * t, axis=1), np.sum(behind * t, axis=1), p)
        return opening & at_part_end(share, early, along, p), share, early

    def after(
        self, prog: Program, ctrl: np.ndarray, states: np.ndarray, judged: tuple
    ) -> tuple[np.ndarray | None, tuple[int, Status, str, str]]:
        """What follows the rollout ``states`` of the program's steps before
        ``prog.free`` (``ctrl``: the whole program's controls), as the full robot goes
        on: after a stop the recovery; else the free steps (after the last release)
        :data:`FREE_COARSENING` times coarser, monitored, and the recovery if they stop;
        then the coast with the hand out of the scene. Returns the states that follow
        the head's judged step (None if none) and the run's verdict, its step index
        that of the head's last state when the head ran through."""
        m = self.world.model
        dt = m.opt.timestep
        k = judged[0]
        start, parts, final = states[k], [], judged
        stop_prog, stop_k, last = prog, k, ctrl[k : k + 1]
        try:
            if not stopped(judged) and prog.free < len(prog.pos):
                m.opt.timestep = dt * FREE_COARSENING
                sl = slice(prog.free, None, FREE_COARSENING)
                stop_prog, tail_ctrl = prog.steps(sl), ctrl[sl]
                if self._arm_starts_inside(start, tail_ctrl[0]):
                    tail_ctrl = self.park_arm(tail_ctrl)
                st, _ = rollout.rollout(m, self.world.data, start[None], tail_ctrl[None],
                                        control_spec=CONTROL)  # fmt: skip
                j = self.judge(stop_prog, st[0])
                stop_k, start, last = j[0], st[0][j[0]], tail_ctrl[j[0] : j[0] + 1]
                parts.append(st[0][: j[0] + 1])
                final = (k, *j[1:])
            elif not stopped(judged) and not prog.coast:
                return None, judged  # ends holding: nothing follows
            if stopped(final):
                self.grip_cmd_at_stop = float(stop_prog.grip[stop_k])
                extra = self.recovery(stop_prog, start)
                rec, _ = rollout.rollout(m, self.world.data, start[None], extra[None],
                                         control_spec=CONTROL)  # fmt: skip
                rec = self._until_slid(rec[0], start)
                parts.append(rec)
                start, last = rec[-1], extra[len(rec) - 1 : len(rec)]
            budget = 0 if stopped(final) else prog.coast
            budget = round(budget * dt / m.opt.timestep)
            parts.append(self.coast(start, self.park_arm(last), budget))
        finally:
            m.opt.timestep = dt
        return np.concatenate(parts), final

    def _arm_starts_inside(self, start: np.ndarray, row: np.ndarray) -> bool:
        """Whether the arm's links, set where control ``row`` (nu + 7 nmocap) puts them
        in rollout state ``start``, reach more than :data:`ARM_ENTRY_DEPTH` into
        anything. The links are simulated only after the last release and enter the
        scene there at once; a link inside this particle's cabinet (its parts are not
        where the model the path was planned in has them) would be pushed out with an
        impulse no arm exerts, and the twin's cabinet would fly off (README, "The
        planning twin"). The full robot's arm would have met that part on the way,
        where the twin has no arm; the twin then keeps the arm parked for the run, as
        before its release."""
        m, d = self.world.model, self.world.data
        saved = np.empty(mujoco.mj_stateSize(m, SAVED_STATE))
        mujoco.mj_getState(m, d, saved, SAVED_STATE)
        try:
            mujoco.mj_setState(m, d, start, ROLLOUT_STATE)
            mujoco.mj_setState(m, d, row, CONTROL)
            mujoco.mj_fwdPosition(m, d)
            con = d.contact[: d.ncon]
            arm = np.isin(m.geom_bodyid[con.geom1], self._arm_bodies) | np.isin(
                m.geom_bodyid[con.geom2], self._arm_bodies
            )
            return bool(np.any(arm & (con.dist < -ARM_ENTRY_DEPTH)))
        finally:
            mujoco.mj_setState(m, d, saved, SAVED_STATE)

    def _until_slid(self, states: np.ndarray, start: np.ndarray) -> np.ndarray:
        """The recovery's rollout ``states`` (n, nstate) up to the first check (as in
        :meth:`judge`) at which the cabinet has slid more than ``cabinet_motion_limit``
        or tipped more than ``cabinet_tilt_limit`` since ``start`` (all of them if it
        never does). The full robot's recovery is
        monitored so (:meth:`~strug_manip.control.recovery.Recovery._recover`): its
        arm stops where it is. Unmonitored, a hand caught on a handle as it backs off
        would drag the twin's cabinet on for the whole back-off, a drag no full robot
        makes."""
        a = 1 + self._cabinet_xy
        every = self._check_every()
        slid = self._slid(states, start[a : a + 2])
        up = z_axes(states[:, a + 3 : a + 7])
        moved = cabinet_slid(slid, self.params) | cabinet_tipped(
            z_axes(start[a + 3 : a + 7]), up, self.params
        )
        over = np.flatnonzero(moved[every - 1 :: every])
        return states if not len(over) else states[: (int(over[0]) + 1) * every]

    def _slid(self, states: np.ndarray, xy0: np.ndarray) -> np.ndarray:
        """How far the cabinet stands from ``xy0`` (2,) in each rollout state, (n,) [m]."""
        a = 1 + self._cabinet_xy
        return np.linalg.norm(states[:, a : a + 2] - xy0, axis=1)

    def _check_every(self) -> int:
        """Steps between the monitors' checks: every
        :data:`~.driver.MONITOR_PERIOD` (10 ms), as on the full robot."""
        return max(1, round(MONITOR_PERIOD / self.world.model.opt.timestep))

    def coast(self, start: np.ndarray, last: np.ndarray, budget: int) -> np.ndarray:
        """The scene from rollout state ``start`` with the hand out of it and the arm
        parked, the controls held at ``last`` (1, nu + 7 nmocap): :data:`COAST_TIME`,
        then on in such spans while a cabinet joint still moves faster than
        :data:`~.executor.REST_SPEED`, up to ``budget`` steps in all (the rest of the full robot's
        stow, during which its cabinet goes on settling); the states (n, nstate) from
        ``start`` on, just ``start`` when the cabinet is at rest already (the hand,
        clear of the cabinet by then, held nothing up)."""
        m = self.world.model
        span = max(1, round(COAST_TIME / m.opt.timestep))
        dofs = 1 + m.nq + self._cabinet_dofs  # the cabinet's velocities in a state
        out: list[np.ndarray] = [start[None]]
        done = 0
        self.ghost(True)
        try:
            while np.max(np.abs(start[dofs])) >= REST_SPEED and (done == 0 or done < budget):
                tl, _ = rollout.rollout(m, self.world.data, start[None],
                                        np.repeat(last, span, axis=0)[None],
                                        control_spec=CONTROL)  # fmt: skip
                out.append(tl[0])
                done += span
                start = tl[0][-1]
        finally:
            self.ghost(False)
        return np.concatenate(out)

    def ghost(self, on: bool) -> None:
        """Take the hand out of (``on``) or back into the scene's collisions."""
        m = self.world.model
        for g in self._hand_geoms:
            m.geom_contype[g] = 0 if on else self._hand_collide[g][0]
            m.geom_conaffinity[g] = 0 if on else self._hand_collide[g][1]
