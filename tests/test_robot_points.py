"""The point cloud's robot filter (dynfab.perception.self_filter.robot_points): the lifted
power-distance query finds exactly the points within some ball, as the distances to every
ball do."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.perception.self_filter import robot_points


@pytest.mark.parametrize("seed", range(8))
def test_it_finds_exactly_the_points_within_some_ball(seed: int) -> None:
    rng = np.random.default_rng(seed)
    count = int(rng.integers(1, 80))
    centres = rng.uniform(-0.5, 0.5, (count, 3))
    radii = rng.uniform(0.0, 0.15, count)
    points = rng.uniform(-0.8, 0.8, (20_000, 3))
    brute = (np.linalg.norm(points[:, None, :] - centres[None, :, :], axis=2) <= radii).any(axis=1)
    assert brute.sum() > 0
    assert np.array_equal(robot_points(points, centres, radii), brute)


def test_nothing_is_the_robot_without_points_or_balls() -> None:
    assert robot_points(np.zeros((0, 3)), np.zeros((2, 3)), np.ones(2)).shape == (0,)
    assert not robot_points(np.zeros((5, 3)), np.zeros((0, 3)), np.zeros(0)).any()
    assert not robot_points(np.full((5, 3), 9.0), np.zeros((2, 3)), np.ones(2)).any()  # outside the balls' box
