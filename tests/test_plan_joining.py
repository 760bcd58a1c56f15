"""Where a robot sees its reference (``dynfab.motion.plan_joining``): a reference that ran
on round a corner steps back on its clock to the latest point the robot sees."""

from __future__ import annotations

import numpy as np

from dynfab.motion.joint_planning import JointPlannerSettings
from dynfab.motion.joint_trajectory import time_path
from dynfab.motion.plan_joining import JOIN_SAMPLE_PERIOD, SIGHT_LOOK_BACK, in_sight, sight_time
from dynfab.motion.plan_values import Plan

CORNER = np.array([1.0, 0.9])   # a round obstacle in a 2-joint configuration space
RADIUS = 0.6
SETTINGS = JointPlannerSettings(margin=0.01, resolution=0.01)


class _Disc:
    """A configuration checker of one disc of configurations (the two calls ``in_sight`` makes)."""

    def clearances(self, q: np.ndarray) -> tuple[float, float]:
        return float(np.linalg.norm(np.asarray(q) - CORNER) - RADIUS), np.inf

    def motion_free(self, a, b, step, margin, self_margin) -> tuple[bool, int]:
        count = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        samples = [a + (b - a) * k / count for k in range(1, count + 1)]
        return all(self.clearances(q)[0] >= margin for q in samples), count


def _plan() -> Plan:
    """Round the disc: along y = 0 to x = 2, then up to y = 2."""
    waypoints = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]])
    trajectory = time_path(waypoints, np.full(2, 1.0), np.full(2, 2.0))
    return Plan(trajectory, waypoints[-1], 0.0, 0)


def test_a_reference_round_the_corner_steps_back_to_the_latest_point_in_sight() -> None:
    plan, disc = _plan(), _Disc()
    robot = np.array([0.8, 0.15])   # below the disc, held there
    tau = next(t for t in np.arange(0.0, plan.trajectory.duration, 0.01)
               if plan.trajectory.evaluate(t).position[1] > 1.5)   # up the far side
    assert not in_sight(disc, robot, plan.trajectory.evaluate(tau).position, SETTINGS)
    seen = sight_time(plan, tau, robot, disc, SETTINGS)
    assert seen is not None and tau - SIGHT_LOOK_BACK < seen < tau
    assert in_sight(disc, robot, plan.trajectory.evaluate(seen).position, SETTINGS)
    later = np.arange(seen + JOIN_SAMPLE_PERIOD, tau, JOIN_SAMPLE_PERIOD)
    assert not any(in_sight(disc, robot, plan.trajectory.evaluate(t).position, SETTINGS) for t in later)


def test_no_point_in_sight_within_the_look_back_leaves_the_clock_where_it_is() -> None:
    plan, disc = _plan(), _Disc()
    robot = np.array([0.2, 1.0])   # left of the disc: the way's last leg is behind it
    tau = plan.trajectory.duration - 0.01
    assert not in_sight(disc, robot, plan.trajectory.evaluate(tau).position, SETTINGS)
    assert sight_time(plan, tau, robot, disc, SETTINGS) is None
    assert sight_time(plan, 0.5 * JOIN_SAMPLE_PERIOD, robot, disc, SETTINGS) is None   # not before 0
