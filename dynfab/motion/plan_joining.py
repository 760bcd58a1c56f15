"""Where a robot that moved while its plan was made joins that plan (issue 19: plans made
off the control loop arrive late), and whether a robot sees its reference (the straight
way to it clear)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.configuration_checker import ConfigurationChecker
from dynfab.motion.guidance import Plan
from dynfab.motion.joint_planning import JointPlannerSettings

__all__ = ["JOIN_CANDIDATES", "JOIN_SAMPLE_PERIOD", "SIGHT_LOOK_BACK", "in_sight", "join_time", "sight_time"]

#: how finely a plan arriving late is searched for the point where the robot joins it [s]
JOIN_SAMPLE_PERIOD = 0.02
#: nearest points of a plan whose straight segment from the robot is checked when it joins [-]
JOIN_CANDIDATES = 8
#: how far back on its clock [s] a reference out of the robot's sight is searched for a
#: point in sight (:func:`sight_time`; set before measuring)
SIGHT_LOOK_BACK = 1.0


def join_time(plan: Plan, q: NDArray[np.float64], checker: ConfigurationChecker, resolution: float) -> float:
    """Where on ``plan``'s clock [s] the robot at ``q`` joins it: of the reference's points
    before any approach, sampled every :data:`JOIN_SAMPLE_PERIOD`, the nearest to ``q`` whose
    straight segment from ``q`` (checked every ``resolution`` rad) touches none of
    ``checker``'s obstacles (the nearest of all if none is free; the fabric's leaves then
    keep the robot clear and the clock waits for it)."""
    end = min(plan.approach_start, plan.trajectory.duration)
    times = np.linspace(0.0, end, max(2, int(np.ceil(end / JOIN_SAMPLE_PERIOD)) + 1))
    positions = plan.trajectory.sample(times)[0]
    order = np.argsort(np.linalg.norm(positions - q, axis=1), kind="stable")
    for k in order[:JOIN_CANDIDATES]:
        if checker.motion_free(q, positions[k], resolution, 0.0, -np.inf)[0]:
            return float(times[k])
    return float(times[order[0]])


def in_sight(checker: ConfigurationChecker, q: NDArray[np.float64], point: NDArray[np.float64],
             settings: JointPlannerSettings) -> bool:
    """Whether the straight joint-space segment from ``q`` to ``point`` (checked every
    ``settings.resolution`` rad, self-collision aside) keeps ``min(margin, c(q), c(point)) −
    escape_slack`` [m] from ``checker``'s obstacles: no closer than its ends (or the planner's
    margin) by more than the slack of an escaped endpoint's segment.

    A guided fabric's reference clock steps back to where the robot sees its reference
    (:func:`sight_time`), or waits, while it is not in sight of the robot among the static
    obstacles (:mod:`dynfab.motion.guided_fabric`): its attractor pulls along that segment,
    and a reference that ran on around a corner the robot was held behind left it there,
    where the obstacle leaves hold it (moving-sphere MBM bookshelf_thin/0019 stalled 0.19
    rad short after 8 plans, 19 mm from a table leg the straight way to the goal goes 9 mm
    into; as posed bookshelf_small/0036, fingers 21 mm from a shelf side the way to the
    reference touches). The plan's path and timing are kept. The guided fabric tests the
    static primitives only: the checker's distance to a mesh is a grid's lower bound, up to
    1.7 cm below the true one, too coarse for a corner at the planner's 1 cm margin (tested
    against meshes, with the floor at 0, MBM kitchen/0007, 0008, 0010 and 0011 stalled
    after 10 plans; with this floor table_bars/0008 was held every 3 s), and a camera's
    cloud is renewed every 0.5 s (its grid would be built on the control thread)."""
    return _sees(checker, q, checker.clearances(q)[0], point, settings)


def _sees(checker: ConfigurationChecker, q: NDArray[np.float64], clearance: float, point: NDArray[np.float64],
          settings: JointPlannerSettings) -> bool:
    """:func:`in_sight`, the robot's own clearance ``clearance`` = ``c(q)`` [m] given."""
    floor = min(settings.margin, clearance, checker.clearances(point)[0]) - settings.escape_slack
    return checker.motion_free(q, point, settings.resolution, floor, -np.inf)[0]


def sight_time(plan: Plan, tau: float, q: NDArray[np.float64], checker: ConfigurationChecker,
               settings: JointPlannerSettings) -> float | None:
    """The latest time on ``plan``'s clock [s], stepping back from ``tau`` every
    :data:`JOIN_SAMPLE_PERIOD` for at most :data:`SIGHT_LOOK_BACK` (not before 0), whose
    reference the robot at ``q`` sees (:func:`in_sight`); None if none.

    A reference that ran on round a corner the robot is held behind pulls it across the
    corner, into what the obstacle leaves hold it from; stepped back into sight it pulls the
    robot along the plan's way toward the corner, and runs on from there (generated seed
    22, as posed cage/0007: held behind a cage bar by four plans in turn while the clock
    waited, reached with the clock stepped back)."""
    times = tau - JOIN_SAMPLE_PERIOD * np.arange(1, int(round(SIGHT_LOOK_BACK / JOIN_SAMPLE_PERIOD)))
    times = times[times > 0.0]
    clearance = checker.clearances(q)[0]   # the robot's, the same for every point
    for earlier, point in zip(times, plan.trajectory.sample(times)[0]):
        if _sees(checker, q, clearance, point, settings):
            return float(earlier)
    return None
