"""The checker's exact test of a configuration (inverse kinematics' second search, issue 20):
the spheres against a mesh's triangles, not the grid's lower bound, so a goal the spheres
clear by millimetres is free although the grid (up to 1.7 cm low) reads it blocked, and one
they enter is not."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.motion.configuration_checker import ConfigurationChecker
from dynfab.robots import load_robot
from wall_scene import MESH_WALL, WALL, goal_near_the_wall


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


def test_a_configuration_the_grid_blocks_and_the_spheres_clear_is_exactly_free(panda) -> None:
    on_grid = ConfigurationChecker(panda, [MESH_WALL])
    exact = ConfigurationChecker(panda, [WALL])   # the same wall as a box: exact distances
    refused_by_the_grid = 0
    for clearance in np.linspace(0.001, 0.015, 15):
        q = goal_near_the_wall(panda, clearance)
        true = exact.clearances(q)[0]
        assert on_grid.clearances(q)[0] <= true + 1e-9
        assert on_grid.exact_free(q, 0.0, 0.0) == (true >= 0.0)
        assert on_grid.exact_free(q, true + 0.001, 0.0) is False
        if not on_grid.free(q, 0.0, 0.0):
            refused_by_the_grid += 1
            assert on_grid.exact_free(q, 0.0, 0.0)
    assert refused_by_the_grid > 0


def test_a_configuration_in_the_mesh_is_not_exactly_free(panda) -> None:
    checker = ConfigurationChecker(panda, [MESH_WALL])
    q = goal_near_the_wall(panda, 0.0)
    q[0] += 0.05                                   # further into the wall
    assert ConfigurationChecker(panda, [WALL]).clearances(q)[0] < 0.0
    assert not checker.exact_free(q, 0.0, 0.0)
