"""Finite joint bounds: the limits where finite, one turn about zero where a joint has none."""

from __future__ import annotations

import numpy as np

from dynfab.robots.joint_bounds import finite_joint_bounds


def test_an_unlimited_side_is_bounded_at_one_turn_and_a_limited_one_is_kept() -> None:
    lower, upper = finite_joint_bounds([-1.0, -np.inf, -0.5], [np.inf, 2.0, 0.5])
    np.testing.assert_array_equal(lower, [-1.0, -np.pi, -0.5])
    np.testing.assert_array_equal(upper, [np.pi, 2.0, 0.5])


def test_bounds_of_finite_limits_are_new_arrays_and_the_limits_are_left_alone() -> None:
    lower_limits, upper_limits = np.array([-1.0, -2.0]), np.array([1.0, 2.0])
    lower, upper = finite_joint_bounds(lower_limits, upper_limits)
    lower[0] = upper[0] = 0.0
    np.testing.assert_array_equal(lower_limits, [-1.0, -2.0])
    np.testing.assert_array_equal(upper_limits, [1.0, 2.0])
