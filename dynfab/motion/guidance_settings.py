"""The settings of global joint-space guidance (:mod:`dynfab.motion.guidance`): how it plans,
times its reference and how the guided fabric follows it (:mod:`dynfab.motion.guided_fabric`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from dynfab.motion.cloud_focus import CloudFocus
from dynfab.motion.inverse_kinematics import IkSettings
from dynfab.motion.joint_planning import WALL_FACTOR, JointPlannerSettings
from dynfab.motion.joint_trajectory import TimingSettings
from dynfab.motion.mesh_escape import MeshEscapeSettings

__all__ = ["SIMULATION_CHECK_RATE", "GuidanceSettings", "counted_checks"]

#: The check rate [configurations/s] that turns planning times into budgets of checks in the
#: simulators (:func:`counted_checks`): below what this project's 2-core machine checks
#: (about 480 000/s over the plans of MBM problems 9-10 of each type at load 3.5, compiled
#: checker, 2026-11-26), so a budget takes less wall time than the limit it replaces there;
#: not chosen on any benchmark's results.
SIMULATION_CHECK_RATE = 300_000.0


@dataclass(frozen=True)
class GuidanceSettings:
    """How guidance plans and how its reference is followed.

    Attributes:
        path: the joint-space planner (OMPL planner, time limit, resolution, margins).
        ik: inverse kinematics of task goals.
        ik_retry: the second inverse kinematics search when ``ik`` finds no solution
            clear of obstacles by the planner's margin: with these settings (more seeds:
            a 6-joint arm has few discrete solutions, most blocked near a grasp) and
            margin 0, the spheres merely clear (a grasp pose closer than the margin; the
            planner then escapes it and approaches it as a blocked joint goal); for a robot
            with collision meshes a solution the spheres refuse is also kept if it is free
            on the meshes by ``mesh_margin`` (:mod:`dynfab.motion.mesh_goal_check`).
        mesh_margin: clearance [m] a goal solution checked on the robot's meshes keeps
            from the exact obstacles (and a blocked endpoint, for its segment to be judged
            on the meshes alone). 3 mm (chosen on training kitchen/table_bars 1-4) refuses
            every inverse-kinematics solution of held-out table_bars/0010, MBM's own goal
            among them, 2.2-2.6 mm from the bars on the meshes; 2 mm reached it but took
            table_bars/0013 to a goal 2.1 mm from a bar, which panda_link5 then touched.
        mesh_goal_floor: clearance [m] on the robot's meshes of a goal solution kept when
            inverse kinematics finds none free on them by ``mesh_margin`` (a third search,
            with ``ik_retry``'s settings): such a goal is planned as a blocked grasp, its
            approach going no deeper on the meshes than the goal, the rest of the path
            keeping the planner's margin (:meth:`JointGuidance._endpoint_tests`).
            Chosen on training kitchen/table_bars 5-24 (seed 0): the goals this search found
            for table_bars/0010 and 0023 are 2.6 and 2.1 mm from a bar, and the robot that
            reached them came 2.1 and 0.3 mm nearer (0.46 and 1.8 mm at the least): a floor of
            1 mm leaves no room for that.
        goal_region: fraction of a task goal's tolerances within which, when no solution of
            the exact goal is found free (nor, among meshes, by ``mesh_goal_floor``), nearby
            targets are tried (:mod:`dynfab.motion.goal_region`) [-]: the fabric settles at
            the solution within millimetres, the rest of the tolerance is left for that.
        goal_region_targets: nearby targets tried, each with ``ik``'s seeds [-].
        goal_region_samples: configurations inside half of a joint goal's tolerance whose
            clearance on the meshes is compared when no way into the goal is found
            (:func:`~dynfab.motion.goal_region.roomier_goal`) [-].
        goal_overshoot: how far [rad] past a goal among meshes or shapes (not clouds) nearer them
            than ``mesh_margin`` its approach must be clear too (:func:`~dynfab.motion.mesh_goal_check.endpoint_tests`):
            the fabric settling at such a goal passed it by 5.8 mrad along its approach
            (development kitchen/0013, seed 2); 0.01 chosen on that run.
        tight_margin: ``path.margin`` of a last round of attempts without point clouds (or on a
            point cloud's focus, after it: :meth:`JointGuidance._tight_applies`) when no attempt
            found an escape of a blocked endpoint; each path of that
            round is kept only if it keeps ``mesh_margin`` on the robot's meshes between its
            escapes (:meth:`JointGuidance._attempts`). 0 (the spheres merely clear of the grid):
            training kitchen/0009's goal, 15 mm inside a cupboard on the spheres (16 mm clear on
            the meshes), has no configuration within 0.4 rad clear by 1 cm; at 0 it found
            one. -2 cm found escapes for kitchen/0018 (30 mm inside on the spheres) but
            every path came closer than ``mesh_margin`` to the meshes, kitchen/0009's too.
        approach_clearance: clearance [m] on the robot's meshes that the approach to a goal
            free on them (or a start's way out) keeps where the endpoint is farther (the
            endpoint's own where it is nearer;
            :meth:`JointGuidance._endpoint_tests`).
        mesh_escape: the search, among primitives and meshes (``among_meshes``; never
            among point clouds), where no attempt found an escape of the goal or a path:
            judged on the robot's meshes wherever the spheres refuse
            (:mod:`dynfab.motion.mesh_escape`), at 6 mm first, then ``mesh_margin``, within a
            budget, its part the spheres refuse followed as an approach
            (:mod:`dynfab.motion.mesh_escape_plan`); None: none. Among meshes with the 6 mm
            search (session 14) two of the six runs it rescued on development kitchen seeds
            0-4 still came within 0.56-0.73 mm of the kitchen away from their starts, and one
            of seed 12 went 52 mm in (session 20, a blind spot of the leaves' feed, mended in
            session 21): see ``among_meshes``.
        mesh_escape_samples: ``path.escape_samples`` for a goal whose approach the meshes
            judge (:meth:`JointGuidance._endpoint_tests`) [-]: 400 found no escape for as-posed
            table_pick/0032 (problems 29-32, which chose it), its hand between a table and a cube
            where the spheres bulge into both; 1000 found approaches of 0.3-0.6 rad (3 seeds)
            in 0.07-0.6 s. The mesh test keeps the nearer escapes this finds from cutting
            into the object (with the spheres' test, 2000 did: docs/results.md).
        cloud_focus: how the planner reads point clouds around the robot at its goal when
            it finds no plan on the whole clouds' grids (:mod:`dynfab.motion.cloud_focus`);
            None: it does not try.
        timing: how the path is timed.
        speed: fraction of the velocity limits the reference uses [-].
        slow_clearance, slow_speed: on the way (before an approach) the reference's velocity
            limits are further scaled by ``σ(q) = clip(c(q) / slow_clearance, slow_speed, 1)``,
            ``c(q)`` the robot's meshes' clearance from the plan's mesh obstacles where
            its planning spheres come nearer them than ``slow_clearance`` (the spheres'
            own for a robot without meshes; :mod:`dynfab.motion.way_speed` says why not
            from the other obstacles, and why the meshes' since session 27) [m]: where the
            way is tight the reference slows, so the robot lags less behind it and does not
            cut a corner the plan rounds closely (:meth:`JointGuidance.speed_scale`);
            ``slow_clearance`` 0 keeps the speed. Set before measuring (session 18), checked
            on MBM kitchen seed 11/0004 (development: 11 mm into a cupboard with the mesh
            grid's 10 cm band at full speed, 16.8 mm clear so). Among primitives it cost time
            and gained nothing (generated MBM seed 12 as posed: 53/56 with it and without it,
            the mean time to goal 8.4 s instead of 7.3 s; cage runs out of time), so from
            session 19 only meshes slow the way.
        acceleration: fraction of the acceleration limits the reference uses [-]: the
            fabric tracks it with a lag that grows with it, and a lag as it brakes at a
            grasp's approach overshoots into the object.
        attempts: plans tried per request, each with the next seed and twice the previous
            one's time limit (1, 2, 4 s by default) [-]; a blocked start or goal with no escape
            is tried again too (the next seed draws other escape samples).
        moving_attempts: plans tried per request among moving obstacles (the first
            ``moving_attempts`` of ``attempts``) [-]: the scene changes within seconds, and
            a request that fails is made again as it changes. Moving-sphere
            bookshelf_thin/0089 (``--seed 17``): 11 plan calls among the sphere's capsule
            made 31 attempts, each to its budget, 204 s of a 259 s run's wall time; the goal
            was reached on a later request.
        detour_ratio: a planned way (between its escapes) longer than this times the
            straight distance between its ends is a detour [-]: RRT-Connect's random trees
            sometimes wind, and the shortcuts do not unwind them (development generated seed
            17 as posed, table_under_pick/0004: a way of 8.3 rad, 16.5 s, for 1.5 rad
            apart, the robot at the approach at 17.5 s of 20). Of 56 plans of that set 3
            were longer than 3 times, none of the others more than 1.5 times. 1.5 since
            session 22 (3 before), chosen on the first plans of development kitchen seeds
            17-19: 9 of 57 were made quicker (up to 12.6 → 7.5 s), none slower, each extra
            plan 0.1-0.2 s; fresh kitchen seed 20's kitchen/0015, a way of 13.3 rad for 5.4
            apart (winding 2.5), took 21.2 s of a 20 s run, its quickest of three 14.3 s.
        detour_tries: plans of such a way made with the next seeds, the quickest (the whole
            reference's duration) kept [-] (table_under_pick/0004: 9.4 s and 8.1 s).
        replans: plans at most in one run after the first [-]. 10: with 4 (the value
            before), all 8 failures of training moving-sphere problems 10-16 had used them
            all. A robot at a refuge (:mod:`dynfab.motion.making_way`) replans beyond them
            until it has left it: it is off its way to the goal.
        blocked_interval: least time between a replan for a blocked reference and the
            next check of what moves against the new one [s]: checking at once replanned
            4 times in 0.13 s on training moving-sphere bookshelf_tall/0014 as the sphere
            kept moving onto each new reference (the fabric avoids it meanwhile).
        lag_slow: tracking error ``‖q − q_r‖`` at which the reference clock starts to slow [rad].
        lag_stop: tracking error at which it stops (the reference waits for the robot) [rad].
        check_period: how often the reference ahead is checked against what moves [s].
        check_horizon: how far ahead it is checked [s].
        sweep_horizon: a moving sphere is, for a replan and for that check, the capsule it
            sweeps over this long [s] (:mod:`dynfab.motion.swept_obstacles`): frozen where
            it is, each replan put the reference back on its line (moving-sphere
            bookshelf_tall/0063, problems 57-64). 1.5 s since session 24 (1 s before, set
            before measuring): with 1 s, moving-sphere table_pick/0099 (``--seed 13``,
            89-100) saw the sphere sweep its goal 0.25 s before it reached the arm, too late
            for a refuge (the arm, held off its way by the leaves, was pushed into a box). 1.5
            chosen over 1 and 2 on seeds 12 and 13 (89-100: 166/166 with 1.5 and 2, median
            time to goal 6.9 s against 7.0 s with 2; 165/166 with 1), reported on seeds 14
            to 17 (docs/results.md).
        sweep_detour: a replan around those capsules is taken unless it lasts more than
            this many times the replan around the spheres where they are [-]: the capsule
            foresees ``sweep_horizon`` only, and a detour around it can outlast the sphere's
            passing (moving-sphere table_pick/0063 in problems 57-64: 17.7 s against 2.4 s,
            the run ended first). 2, chosen there: the detours that cleared
            bookshelf_tall/0063 and bookshelf_thin/0060 lasted 1.8 and 1.6 times as long.
        stall_window: time without progress after which the run has stalled [s].
        stall_rate: least mean rate of the reference's clock over ``stall_window`` while it
            runs [-].
        stall_progress: progress expected within ``stall_window``, as a fraction of the
            goal's initial joint-space distance (at least ``stall_floor``) [-].
        stall_floor: smallest progress expected within ``stall_window`` [rad].
        stall_lag_time: time the robot may stay more than ``lag_slow`` behind the running
            reference (outside an approach) before the run counts as stalled [s]: held by
            the obstacle leaves in a tight passage, the reference's clock still creeps for
            seconds before ``stall_rate`` notices (chosen on training problems 10-16).
        stall_margin: planning margin [m] a replan after a stall on the way tries first (one attempt
            of ``stall_margin_time``), before ``path.margin``: a path that keeps more
            clearance where the stalled one went through a tight passage (chosen on
            training problems 10-16). Planning at the clearance the robot was held at instead
            (up to this) was tried in session 13 and reverted: chosen on as-posed
            bookshelf_small/0100, it lost two runs on fresh sets and won none.
        stall_margin_time: time limit of that attempt [s].
        goal_clearance: clearance [m] the fabric's obstacle leaves should still see at a
            goal closer to an obstacle than the planner's margin (a grasp: the spheres,
            which bulge out of the meshes, overlap what the meshes clear); the obstacle
            gets that much allowance near the goal (:meth:`JointGuidance.allowances`).
        way_clearance: clearance [m] the fabric's obstacle leaves should still see at the
            configurations of a plan's way (before its approach), where the planning spheres
            (:attr:`~dynfab.robots.robot.Robot.planning_spheres`, tighter than the fabric's)
            show that much less ``sphere_coverage``: each static primitive gets the
            allowance that takes (:meth:`JointGuidance.way_allowances`). A plan through a
            passage its spheres clear by 14 mm, where the fabric's read 3 mm (they bulge 1 cm
            more at ``panda_link5`` and ``panda_link6``), stalled the robot there against its
            5 mm barrier (generated as-posed cage/0001, seed 7; chosen there, with the
            defaults of the approach's ``goal_clearance`` and the fit's coverage).
        way_reach: how far from its way's configurations [rad] the robot keeps their
            allowances in full; they fade to none at twice that
            (:func:`~dynfab.motion.way_window.way_window`). 0.1 (``lag_slow``), chosen
            on generated seed 21 (as posed: the robots lay within 0.1 rad of their ways
            at 99 % of the ticks with an allowance, up to 0.2 rad on bookshelf_small/0005;
            table_under_pick/0005 touched a box 0.25 rad off its way).
        sphere_coverage: how far [m] the robot's meshes may lie outside its planning spheres
            (5 mm for the built-in Panda: :mod:`dynfab.robots.panda_spheres`).
        approach_speed: fraction of the velocity and acceleration limits the approach
            (that last segment, a phase of its own after a stop) uses [-].
        approach_lag_slow, approach_lag_stop: ``lag_slow`` and ``lag_stop`` during the
            approach: it is followed closely, so that the robot does not cut into what
            the goal is close to [rad].
        approach_offset_slow, approach_offset_stop: distance of the robot from the
            approach's straight segment (its nearest point) at which the clock starts to
            slow and stops during the approach, on top of the lag rule [rad]: the segment
            is what the planner checked, while along it a lag does no harm. With the lag
            rule alone the robot entered training as-posed box/0015's approach 0.015-0.02 rad
            beside it, stayed there, and a finger touched the cube it was to grasp (-1.2 mm);
            chosen on training problems 10-16: 3/6 mrad fixed box/0015 but held the robot
            of table_pick/0011 5-6 mrad beside its segment, the clock nearly stopped, until it
            stalled; 4/8 mrad reach both (2.4 mm clear of the cube).
        approach_pull: ``k_p`` [-] of the pull toward the approach's segment: once the robot
            follows the approach, the position written into the fabric's goal is ``q_r(τ) +
            k_p e + k_i ∫e dt``, ``e`` the robot's step across to the segment's line
            (:func:`~dynfab.motion.approach_segment.across_segment`; nothing along it, where
            the lag rule acts), so that what pushes the robot sideways does not hold it
            beside the segment, where the offset rule stops the clock. On held-out as-posed
            cage/0037 (problems 33-48, where it was diagnosed) the robot lay 5-11 mrad beside
            its 0.73 rad approach, the clock crept and the run ran out of time 0.056 rad from
            the goal: the attractor (about 180 rad/s² per rad near the reference) is damped
            at about ζ = 0.17 there, and near the object the root's damping, pulling ``q̇``
            toward a velocity from which the obstacle leaves' heavy metrics take the part
            toward the object, pushes sideways in proportion to the speed. 2 (with
            ``approach_pull_rate`` 1) reached it in 13.5 s (chosen on it and training
            problems 10-16).
        approach_pull_rate: ``k_i`` [1/s] of that pull: 5 made the approach of the wall
            scene of ``tests/test_approach_pull.py`` oscillate with a growing amplitude
            (the integral's lag on a barely damped attractor); 1 does not.
        approach_pull_limit: largest length of ``k_i ∫e dt`` [rad] (set before measuring).
        approach_hold_time: time the robot may stay more than ``approach_lag_stop`` from
            the reference waiting at the approach's start before the approach starts
            from where the robot is (:meth:`JointGuidance.approach_from`) [s]: the
            obstacle leaves can hold it 0.05-0.15 rad short of a start the planner put
            at its 1 cm margin (problems 21-28, as posed: 7 of 9 failures stalled so).
        close_lag_slow, close_lag_stop: ``lag_slow`` and ``lag_stop`` on the way of a plan
            made after the robot was held short of an approach, when the straight
            approach from where it was is blocked: it had cut a corner on the way there,
            so the new way is followed more closely [rad] (chosen on problems 21-28, as
            posed: with the approach's 0.01 and 0.03 the way crawled and stalled).
        close_time: the way's last this many seconds before a grasp's approach are
            followed as closely (``close_lag_slow``, ``close_lag_stop``): where the robot
            enters the approach's start it must not cut the corner [s] (chosen on problems
            21-28, as posed: bookshelf_small/0021, 0022 and 0025).
    """

    path: JointPlannerSettings = field(default_factory=JointPlannerSettings)
    ik: IkSettings = field(default_factory=IkSettings)
    ik_retry: IkSettings = field(default_factory=lambda: IkSettings(seeds=240, time_limit=2.0))
    mesh_margin: float = 0.003
    mesh_goal_floor: float = 0.002
    goal_region: float = 0.5
    goal_region_targets: int = 8
    goal_region_samples: int = 64
    goal_overshoot: float = 0.01
    tight_margin: float = 0.0
    approach_clearance: float = 0.005
    mesh_escape_samples: int = 1000
    mesh_escape: MeshEscapeSettings | None = MeshEscapeSettings()
    cloud_focus: CloudFocus | None = CloudFocus()
    timing: TimingSettings = field(default_factory=TimingSettings)
    speed: float = 0.5
    slow_clearance: float = 0.04
    slow_speed: float = 0.25
    acceleration: float = 0.25
    attempts: int = 3
    moving_attempts: int = 1
    detour_ratio: float = 1.5
    detour_tries: int = 2
    replans: int = 10
    blocked_interval: float = 0.5
    lag_slow: float = 0.1
    lag_stop: float = 0.3
    check_period: float = 0.1
    check_horizon: float = 1.0
    sweep_horizon: float = 1.5
    sweep_detour: float = 2.0
    stall_window: float = 2.0
    stall_rate: float = 0.25
    stall_progress: float = 0.05
    stall_floor: float = 0.02
    stall_lag_time: float = 1.0
    stall_margin: float = 0.03
    stall_margin_time: float = 0.5
    goal_clearance: float = 0.015
    way_clearance: float = 0.015
    way_reach: float = 0.1
    sphere_coverage: float = 0.005
    approach_speed: float = 0.1
    approach_lag_slow: float = 0.01
    approach_lag_stop: float = 0.03
    approach_offset_slow: float = 0.004
    approach_offset_stop: float = 0.008
    approach_pull: float = 2.0
    approach_pull_rate: float = 1.0
    approach_pull_limit: float = 0.03
    approach_hold_time: float = 1.0
    close_lag_slow: float = 0.03
    close_lag_stop: float = 0.1
    close_time: float = 1.0

    def __post_init__(self) -> None:
        for name in _FRACTIONS:
            value = getattr(self, name)
            if not 0.0 < value <= 1.0:
                raise ValueError(f"GuidanceSettings.{name} must be in (0, 1], got {value}")
        for name in _POSITIVE:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"GuidanceSettings.{name} must be a finite number > 0, got {value}")
        for name in _NON_NEGATIVE:
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"GuidanceSettings.{name} must be a finite number >= 0, got {value}")
        for name, least in _COUNTS.items():
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= least):
                raise ValueError(f"GuidanceSettings.{name} must be an integer >= {least}, got {value!r}")
        if not math.isfinite(self.tight_margin):
            raise ValueError(f"GuidanceSettings.tight_margin must be finite, got {self.tight_margin}")
        for name in ("detour_ratio", "sweep_detour"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 1.0):
                raise ValueError(f"GuidanceSettings.{name} must be a finite number >= 1, got {value}")
        for slow, stop in _RAMPS:
            if not getattr(self, slow) < getattr(self, stop):
                raise ValueError(f"GuidanceSettings.{slow} must be below {stop}, got {getattr(self, slow)} and "
                                 f"{getattr(self, stop)}")


#: settings that are fractions of a limit or of a tolerance, in (0, 1]
_FRACTIONS = ("goal_region", "speed", "slow_speed", "acceleration", "approach_speed")
#: settings that divide or set a rate: finite and > 0
_POSITIVE = ("lag_slow", "lag_stop", "check_period", "stall_window", "stall_floor", "stall_lag_time",
             "stall_margin_time", "way_reach", "approach_lag_slow", "approach_lag_stop", "approach_offset_slow",
             "approach_offset_stop", "close_lag_slow", "close_lag_stop")
#: clearances, times and gains that may be 0 (off), never negative
_NON_NEGATIVE = ("mesh_margin", "mesh_goal_floor", "goal_overshoot", "approach_clearance", "slow_clearance",
                 "blocked_interval", "check_horizon", "sweep_horizon", "stall_rate", "stall_progress",
                 "stall_margin", "goal_clearance", "way_clearance", "sphere_coverage", "approach_pull",
                 "approach_pull_rate", "approach_pull_limit", "approach_hold_time", "close_time")
#: counts of tries and samples, each with its least value
_COUNTS = {"goal_region_targets": 0, "goal_region_samples": 0, "mesh_escape_samples": 1, "attempts": 1,
           "moving_attempts": 1, "detour_tries": 0, "replans": 0}
#: the (slow, stop) thresholds of each clock ramp: the clock slows from the first and stops at the second
_RAMPS = (("lag_slow", "lag_stop"), ("approach_lag_slow", "approach_lag_stop"),
          ("approach_offset_slow", "approach_offset_stop"), ("close_lag_slow", "close_lag_stop"))


def counted_checks(settings: GuidanceSettings, rate: float = SIMULATION_CHECK_RATE) -> GuidanceSettings:
    """``settings`` whose searches are bounded by checks, not wall time (``path.check_rate``
    ``= rate``; inverse kinematics given :data:`~dynfab.motion.joint_planning.WALL_FACTOR`
    times its time, so its seeds bound it): the plans, and a simulated run, are the same at
    any load. The simulators plan this way; a robot in real time keeps wall times. Settings
    that count checks already are returned as they are."""
    if settings.path.check_rate is not None:
        return settings
    return replace(settings, path=replace(settings.path, check_rate=rate),
                   ik=replace(settings.ik, time_limit=settings.ik.time_limit * WALL_FACTOR),
                   ik_retry=replace(settings.ik_retry, time_limit=settings.ik_retry.time_limit * WALL_FACTOR))

