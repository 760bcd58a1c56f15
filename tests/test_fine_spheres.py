"""Guidance's second look on the fine spheres (dynfab.robots.panda_fine_spheres): a goal that
the planning spheres find within the planner's margin of a wall, the fine spheres and the
meshes farther, is planned to as a free goal (no escape, no approach); on the planning
spheres alone it is escaped and approached."""

from __future__ import annotations

import numpy as np
import pytest

from coarse_panda import panda_on_planning_spheres
from dynfab.motion.configuration_checker import ConfigurationChecker
from dynfab.motion.guidance import JointGuidance, JointTarget
from dynfab.motion.mesh_goal_check import MeshGoalCheck, robot_mesh_model
from dynfab.robots import load_robot
from wall_scene import MESH_WALL, START, WALL

MARGIN = 0.01   # the planner's (JointPlannerSettings.margin)


@pytest.fixture(scope="module")
def goal() -> np.ndarray:
    """START turned toward the wall until the planning spheres are 7 mm from it."""
    coarse = ConfigurationChecker(panda_on_planning_spheres().planning_robot, [WALL])
    goal = START.copy()
    for q1 in np.linspace(-1.3, 0.0, 1301):
        goal[0] = q1
        if coarse.clearances(goal)[0] < 0.007:
            return goal
    raise AssertionError("the wall is never that close")


def test_the_fine_spheres_free_a_goal_the_planning_spheres_hold_within_the_margin(goal: np.ndarray) -> None:
    panda = load_robot("panda")
    planning = ConfigurationChecker(panda.planning_robot, [WALL])
    fine = ConfigurationChecker(panda.planning_robot.fine_robot, [WALL])
    coarse = ConfigurationChecker(panda_on_planning_spheres().planning_robot, [WALL])
    assert coarse.clearances(goal)[0] < MARGIN <= fine.clearances(goal)[0]
    assert planning.clearances(goal)[0] == fine.clearances(goal)[0]
    assert planning.free(goal, MARGIN, 0.0) and not coarse.free(goal, MARGIN, 0.0)
    model = robot_mesh_model(panda)
    assert model is not None
    meshes = MeshGoalCheck(model, 0.0)
    meshes.set_obstacles([MESH_WALL])
    assert meshes.clearance(goal)[0] >= fine.clearances(goal)[0] - 0.005   # the fine spheres leave 5 mm outside at most


def test_guidance_plans_to_it_as_a_free_goal_and_on_the_planning_spheres_alone_escapes_it(goal: np.ndarray) -> None:
    second_look = JointGuidance(load_robot("panda")).plan(START, JointTarget(tuple(goal)), [WALL])
    assert second_look.approach == 0.0
    np.testing.assert_allclose(second_look.trajectory.evaluate(second_look.trajectory.duration).position, goal,
                               atol=1e-6)
    alone = JointGuidance(panda_on_planning_spheres()).plan(START, JointTarget(tuple(goal)), [WALL])
    assert alone.approach > 0.0
