"""The straight joint-space motion a guided fabric follows while its plan is made."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.motion.straight_motion import StraightMotion

VELOCITY = np.array([1.0, 0.5, 2.0])
ACCELERATION = np.array([2.0, 4.0, 1.0])


@pytest.mark.parametrize("goal", [np.array([0.8, -0.3, 0.2]), np.array([0.01, 0.0, -0.005]), np.zeros(3)])
def test_it_goes_from_rest_to_rest_at_the_goal_within_every_joints_limits(goal) -> None:
    start = np.array([0.0, 0.0, 0.0])
    motion = StraightMotion(start, goal, VELOCITY, ACCELERATION)
    times = np.linspace(-0.1, motion.duration + 0.1, 4001)
    q, qdot, qddot = motion.sample(times)
    np.testing.assert_allclose(q[0], start)
    np.testing.assert_allclose(q[-1], goal, atol=1e-12)
    np.testing.assert_allclose(qdot[[0, -1]], 0.0, atol=1e-12)
    assert np.all(np.abs(qdot) <= VELOCITY + 1e-12) and np.all(np.abs(qddot) <= ACCELERATION + 1e-12)
    step = times[1] - times[0]   # the derivatives are those of the positions
    np.testing.assert_allclose(np.gradient(q, step, axis=0), qdot, atol=4 * step * ACCELERATION.max())
    along = (q - start) @ (goal - start)   # on the segment, moving one way
    assert np.all(np.diff(along) >= -1e-12)


def test_a_long_motion_cruises_at_the_slowest_joints_share_of_its_limit() -> None:
    goal = np.array([4.0, 4.0, 0.0])   # joint 1 (0.5 rad/s) limits the speed along the path
    motion = StraightMotion(np.zeros(3), goal, VELOCITY, ACCELERATION)
    _, qdot, _ = motion.sample(np.array([motion.duration / 2]))
    np.testing.assert_allclose(np.abs(qdot[0]), [0.5, 0.5, 0.0])


def test_limits_must_be_positive_per_joint() -> None:
    with pytest.raises(ValueError, match="StraightMotion.velocity"):
        StraightMotion(np.zeros(3), np.ones(3), np.array([1.0, 0.0, 1.0]), ACCELERATION)
