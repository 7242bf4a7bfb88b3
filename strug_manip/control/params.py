"""Tuning constants of the skills, each with the reason for its value.

One frozen :class:`SkillParams` holds every constant the skills and their executions
use; :data:`DEFAULT_PARAMS` is what every skill uses unless given another. Units: [m],
[rad], [s], [m/s].
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from planners.errors import ConfigError


@dataclass(frozen=True)
class SkillParams:
    """Constants of the skills (defaults and the reason for each).

    Attributes:
        pregrasp_offset: distance of the pre-grasp from the grasp, against the approach
            [m]: the fingers are 7.7 cm long and must clear the handle's standoff.
        pick_offset: the same for Pick [m]: the free motion ends this far from the
            object, clear of it even where the fast arm strays a few centimetres from
            its plan (the slow approach line does the rest).
        line_step: spacing of the poses of a Cartesian line [m] (arcs: this arc
            length at the gripper): a few IK iterations each, smooth enough for the
            position servos.
        approach_speed: TCP speed of approaches [m/s] (slow: contact comes).
        retreat_speed: TCP speed of retreats and withdrawals after a release [m/s]:
            the open fingers leave the handle they straddle; faster than an approach,
            as slow as a hand backing away from furniture.
        open_speed: TCP speed of opening motions [m/s]: a household pace that the arm
            follows with its speed limits at 70 %.
        probe_speed: TCP speed of the probing motions [m/s].
        ease_distance: an opening's last this much of TCP travel is its ``ease`` line,
            slower [m]: the hand runs up to 2.4 cm past the end of a pull at
            ``open_speed`` (measured: the servos' integral, wound up by the part's
            damping), so the part reaches the end of its travel, and a stop there,
            slowly.
        ease_speed: TCP speed of that ``ease`` line [m/s]: a quarter of the opening's,
            so a part that meets its stop there meets it with a sixteenth of the
            energy, and the hand winds up a quarter as far past the end.
        grip_time: time the fingers get to close or open [s]: they close on a handle in
            0.1 s and squeeze with their full force from then on.
        settle_time: hold after a motion before the next phase [s].
        drawer_travel: how far OpenDrawer pulls by default [m] (capped before the
            believed limit): far enough to lower the 0.10 x 0.06 m object into it.
        door_angle: how far OpenDoor opens a side-hinged door by default [rad] (capped
            before the believed limit, 1.6-2.1 rad): 100 degrees, so that even a door
            of a narrow cell leaves its opening free for the object and the fingers.
        flap_angle: how far OpenDoor lifts a top-hinged flap by default [rad]: as far
            as it goes (capped before its limit, 1.20-1.57 rad): the object is carried
            in under it.
        drop_angle: how far OpenDoor lowers a bottom-hinged (drop-down) flap by default
            [rad]: as far as it goes (capped before the limit): the object is carried
            in over the open flap's edge, which a low cell leaves little room for.
        flap_wrist_share: on a flap with a bar handle the gripper turns by this share of
            the flap's angle, the bar rolling between the finger pads for the rest [-]
            (a round bar rolls under the squeeze: the flap's weight alone turns it). The
            more the wrist turns the better: the more the gripper lags the flap, the more
            the opening fingers press on the flap's face on release and push it back
            (at half the angle drop-down flaps sprang back, no longer wide enough for the
            object; close to the whole angle the wrist cannot follow).
        limit_margin_m, limit_margin_rad: an opening stops this short of the believed
            joint limit [m], [rad], so it never drives the part into its stop. 0.01 m
            gave a low drawer under another the centimetre its Place needed (oracle
            OpenDrawer episode 9823) but lost two held-out STRUG episodes of
            9920:9950 (9935, 9948, one a drag), none won: kept at 0.02 m.
        probe_distance: how far Push, PullV and PullH move the gripper [m]: enough to
            move a free part visibly (a 4 cm shift shows in the head camera's point
            cloud), little enough that a wrong direction seldom drags the cabinet.
        retreat_distance: how far the gripper backs off after releasing [m].
        withdraw_distance: then how far the hand moves level away from the cabinet
            front (against the grasp's original approach) before the arm folds [m]:
            the stow then starts clear of a part that a wrong belief left sticking out
            where the robot thinks the space is free (else the folding arm sweeps it).
        lift_height: how high Pick lifts the object [m].
        place_clearance: height from which Place lowers an object held from above [m]
            (clears a drawer's walls).
        insert_clearance: distance from which Place carries an object held level into
            a cell [m]: the whole object starts outside the front.
        place_drop: gap left under the object when it is released [m].
        tracking_tolerance: the gripper more than this behind its commanded pose along a
            line means the arm is blocked (status ``collision``) [m]: beyond the arm's
            compliance under its effort limits at line speeds (a few centimetres).
        probe_tolerance: the same for the probing lines [m]: half the probe's travel,
            so that a probe against a part that does not move that way (a closed
            drawer pushed in, a door pulled up) reports ``collision``; the arm lags
            well under a centimetre at probe speed.
        free_tolerance: the same for free motions [m]: there a fast arm lags a few
            centimetres behind its command, and only a blocked one falls far behind.
        held_clearance: a free motion carrying the object keeps it this far from
            everything but the hand where it can [m]: the motion is planned in the
            believed cabinet, whose boards perception puts a centimetre or two off,
            and the arm lags its command on the way; a carried object whose end
            grazed a board's front edge turned in the grasp (README), and the
            Place that followed caught the cell's floor and slid the cabinet. What is
            nearer than this where the motion starts or ends (an object just lifted, a
            pre-place beside an open door) counts where it touches; where the first
            planner finds no such path, the motion is planned as before, touching
            nothing.
        free_clearance: a free motion (the reach, the stow, a recovery) keeps the robot
            and what it carries this far from the scene (the cabinet, the tables, the
            object where it rests), but for what is that near
            where the motion starts or ends, where it can (else it is planned touching
            nothing, as before) [m]: the arm follows a free motion up to a few
            centimetres off its plan (its joints lag the command by up to 0.04 rad,
            measured on a stow; the checks along an edge are up to 4.4 cm apart at the
            gripper), and a plan that grazed an open drawer pushed it (an elbow on the
            stow after a Place slid the cabinet 1.6 cm; a wrist on the reach knocked a
            drawer shut and slid the cabinet 3 cm).
        wide_clearance: the full robot's own arm motions (the reach, the stow before a
            drive, a recovery's stow) first try to keep the robot, and what it carries,
            this far from the scene [m], where the ends leave that room, before
            ``free_clearance`` and ``held_clearance``: those keep the believed cabinet's
            boards at the arm's lag, but perception puts a front or an open door's edge
            1-2 cm off (a hinge up to 3.7 cm, ``comply_limit``), and a reach that kept
            its 2 cm from a believed neighbour door put the carried object on the real
            one and slid the cabinet (OpenDoor episode 10187; an upper arm on an open
            door, 10165; fingers on a lifted flap, 10180). The planning twin has no arm
            on the way to the part, so this changes no prediction.
        clear_checks: the OMPL budget per planner of a free motion kept clear
            (``free_clearance``, ``held_clearance``), before the plain plans get
            theirs [validity checks] (about 1 s on an idle core, at the 12,000 to
            15,000 checks per second measured on the demo): the fallback planner
            (LBKPIECE1) found the demo's carrying reach over an open top drawer with
            the clearance in 0.85 s (RRTConnect found none in its budget), and a narrow
            passage the clearance closes (an arm reaching into a low drawer) costs no
            more than this.
        cabinet_motion_limit: the cabinet's base more than this from where it stood
            when the skill started (horizontally) stops the skill (status
            ``cabinet_moved``) [m]: a part that does not move the way the robot
            believes (a door opened about the wrong hinge, a drawer pulled as a door)
            holds the hand back by the whole cabinet, which slides on its table
            before the arm falls the tracking tolerance behind. An opening under the
            right model moves it by millimetres, a top flap lifted open by up to 2 cm
            (README): 3 cm leaves room for that and still stops a wrong pull at a
            third of the 0.1 m at which the task counts the cabinet dragged.
        cabinet_tilt_limit: the cabinet's up axis turned more than this from where it
            was when the skill started stops the skill too (``cabinet_moved``) [rad]:
            a cabinet pulled high up tips about its front edge before its base
            slides (a drop flap's pull on a side door, episode 9101 of OpenDoor,
            tipped one 29 degrees while its base moved 1.4 cm, and it fell over). 6
            degrees: a top flap lifted open under the right model tipped its
            cabinet 4.1 degrees (generator seed 3012), and at 6 degrees the tests'
            doors swung as flaps stop with the cabinet upright, 6-10 mm from where
            it stood.
        end_share, end_give, end_lag: an opening ends where its part stops (its end, a
            stop no view shows) when the part, having followed the hand unstrained
            for the first ``end_share`` of the opening's path (the straight-line
            share from the grasp to where the path ends) [-], holds it back *along*
            the path: the cabinet gives more than ``end_give`` [m] where the hand
            pulls it (sliding or tipping), or the hand lags more than ``end_lag``
            [m], each counted along the path's direction there. The run then lets
            go, backs off and stows as after a stop, and reports ``ok`` with the
            part where it stopped. Why: a drawer's limit is not seen, and the
            belief spreads it over 0.185-0.313 m on a drawer whose real limit is
            0.213 m (issue 37); a pull planned to a particle's longer limit drove the
            real drawer into its stop and slid the cabinet 3 cm (``cabinet_moved``).
            Measured on the 40 openings of the skills' test sample: under the right
            model the cabinet gives at most 6 mm and the hand lags at most 14 mm all
            the way; under a wrong one (a drawer swung as a door, a door pulled
            straight) the cabinet gives 16-64 mm, or the hand lags 23-57 mm, within
            the first half, where a limit error seldom stops a part (a 0.185 m
            drawer opened 0.25 m stops at 74 %), and the other rules stop it. Along
            the path: a hinge or an axis a few centimetres or degrees off strains
            the hand across its path, which is no end (docs/skills.md).
        comply_gain, comply_deadband, comply_limit: the hand of an opening on the full
            robot gives way across its path (:class:`~.compliance.HandCompliance`) at
            ``comply_gain`` [m/(N s)] per newton of the cabinet's force on it above
            ``comply_deadband`` [N], up to ``comply_limit`` [m] from its plan. The gain:
            a hinge 2 cm off parts the handle from the hand at about 1.3 cm/s (a door
            0.3 m wide swung at ``open_speed``), which the hand follows at 7 N; the
            deadband: the pull's own contact forces across the path (the fingers'
            squeeze is internal); the limit: the largest hinge error perception makes
            on episode cabinets (2.6 cm radial, 2.6 cm in depth: 3.7 cm together),
            with room; a wrong kind of joint puts the handle much farther off.
        settle_limit: after a skill the robot holds still, before it reports, while
            the cabinet still moves (:func:`~.executor.at_rest`), up to this long [s]:
            what it reports is where the cabinet came to rest. A cabinet the stow
            tipped by 15 degrees was still rocking when the skill used to report
            (0.15 s after it), and settled within about a second.
        time_budget: simulated time budget of one skill [s].
        plan_checks: OMPL budget per arm motion and planner [validity checks]
            (about 4 s on an idle core): an arm reaching into a low drawer with the
            object is a narrow passage that LBKPIECE1 finds within a second or two.
            Budgets count work, not wall time, so a skill's motions (and so the
            episode) are the same on a loaded machine as on an idle one: with
            seconds, a loaded machine's RRTConnect gave up where an idle one found a
            path, and the demo's Place went another way (issue 37).
        first_planner_checks: the same for the first of several planners
            (RRTConnect) [validity checks] (about 0.5 s on an idle core): it solves the
            open arm motions in a few hundred to 6,000 checks (the demo's successes)
            and the narrow passages (an arm reaching out of an open drawer) not within
            ``plan_checks`` either, where the fallback (LBKPIECE1) takes over; waiting
            the full budget for it made most of the planning twin's time.
        plan_wall_cap: wall-clock safety cap of one planner's search [s]: far above
            what ``plan_checks`` take even on a loaded machine (about 4 s idle, twice
            that with a second process on the core), so that it never decides a plan
            (:data:`~strug_manip.control.motion.WALL_CAP_HIT` says when it did).
        drive_tolerance: the base is driven only to targets farther than this [m].
        record_period: trajectory recording period [s].
    """

    pregrasp_offset: float = 0.08
    pick_offset: float = 0.12
    line_step: float = 0.02
    approach_speed: float = 0.15
    retreat_speed: float = 0.25
    open_speed: float = 0.2
    probe_speed: float = 0.1
    ease_distance: float = 0.04
    ease_speed: float = 0.05
    grip_time: float = 0.25
    settle_time: float = 0.15
    drawer_travel: float = 0.25
    door_angle: float = 1.75
    flap_angle: float = 1.57
    drop_angle: float = 1.57
    flap_wrist_share: float = 0.7
    limit_margin_m: float = 0.02
    limit_margin_rad: float = 0.05
    probe_distance: float = 0.04
    retreat_distance: float = 0.08
    withdraw_distance: float = 0.12
    lift_height: float = 0.12
    place_clearance: float = 0.12
    insert_clearance: float = 0.2
    place_drop: float = 0.005
    tracking_tolerance: float = 0.08
    probe_tolerance: float = 0.02
    free_tolerance: float = 0.2
    held_clearance: float = 0.02
    free_clearance: float = 0.03
    wide_clearance: float = 0.05
    clear_checks: int = 12_000
    cabinet_motion_limit: float = 0.03
    cabinet_tilt_limit: float = 0.105
    end_share: float = 0.5
    end_give: float = 0.01
    end_lag: float = 0.02
    comply_gain: float = 0.002
    comply_deadband: float = 5.0
    comply_limit: float = 0.05
    settle_limit: float = 2.0
    time_budget: float = 60.0
    plan_checks: int = 50_000
    first_planner_checks: int = 6_000
    plan_wall_cap: float = 60.0
    drive_tolerance: float = 0.02
    record_period: float = 0.02

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise ConfigError(f"SkillParams.{f.name} must be a finite number, got {v!r}")
            if v <= 0 and f.name != "place_drop":
                raise ConfigError(f"SkillParams.{f.name} must be > 0, got {v!r}")
            if v < 0:
                raise ConfigError(f"SkillParams.{f.name} must be >= 0, got {v!r}")
            if f.name.endswith("_checks") and not isinstance(v, int):
                raise ConfigError(f"SkillParams.{f.name} must be an int (checks), got {v!r}")

    def planner_checks(self, i: int, n: int) -> int:
        """The OMPL budget [validity checks] of the ``i``-th of ``n`` planners tried in
        turn."""
        return self.first_planner_checks if i == 0 and n > 1 else self.plan_checks


#: The parameters every skill uses unless given others.
DEFAULT_PARAMS = SkillParams()
