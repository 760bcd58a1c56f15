"""A grasp goal the spheres refuse and the robot's meshes find free: its approach is judged
on the meshes instead of the spheres (issue 19: such a goal must not be refused, and the
spheres accept approaches the meshes find inside a board)."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.geometry.shapes import Box, Placement
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.guidance import GuidanceError, JointGuidance, JointTarget, robot_mesh_model
from dynfab.motion.joint_planning import ApproachTest, JointPlannerSettings, NoPathError, plan_joint_path
from dynfab.motion.mesh_goal_check import MeshGoalCheck
from dynfab.robots import load_robot

WALL = PlacedObstacle(Box((0.6, 0.04, 0.7)), Placement((0.45, 0.0, 0.35)))
START = np.array([-1.3, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])
FAST = JointPlannerSettings(time_limit=0.5)


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


@pytest.fixture(scope="module")
def grasp(panda) -> np.ndarray:
    """START turned about joint 1 toward the wall until its spheres touch it (the planner's
    margin is 10 mm); the meshes are farther."""
    checker = ConfigurationChecker(panda, [WALL])
    goal = START.copy()
    for q1 in np.linspace(-1.3, 0.0, 1301):
        goal[0] = q1
        if checker.clearances(goal)[0] < 0.0:
            return goal
    raise AssertionError("the wall is never that close")


def _plan(panda, grasp, approach: ApproachTest | None):
    checker = ConfigurationChecker(panda, [WALL])
    kin = panda.kinematics
    return plan_joint_path(checker, START, grasp, kin.lower, kin.upper, FAST, 0, approach)


def test_an_approach_test_instead_of_the_spheres_decides_alone(panda, grasp) -> None:
    assert _plan(panda, grasp, None).escaped_goal   # the spheres accept an approach
    with pytest.raises(NoPathError) as refused:
        _plan(panda, grasp, ApproachTest(lambda free, goal: False, instead_of_spheres=True))
    assert refused.value.reason == "goal_in_collision"
    asked = []
    path = _plan(panda, grasp, ApproachTest(lambda free, goal: asked.append(free) is None, instead_of_spheres=True))
    np.testing.assert_array_equal(path.waypoints[-2], asked[0])   # the first it was asked about


def test_an_approach_test_beside_the_spheres_needs_both(panda, grasp) -> None:
    with pytest.raises(NoPathError):
        _plan(panda, grasp, ApproachTest(lambda free, goal: False))
    assert _plan(panda, grasp, ApproachTest(lambda free, goal: True)).escaped_goal


def test_a_goal_free_on_the_meshes_is_approached_clear_of_them(panda, grasp) -> None:
    guidance = JointGuidance(panda)
    plan = guidance.plan(START, JointTarget(tuple(grasp)), [WALL])
    meshes = guidance._meshes()
    assert meshes is not None
    at_goal = meshes.clearance(grasp)[0]
    assert at_goal >= meshes.margin and guidance.checker.clearances(grasp)[0] < 0.0   # refused by the spheres alone
    assert plan.approach > 0.0
    approach = plan.trajectory.phases[-1].waypoints
    line = approach[0] + np.linspace(0.0, 1.0, 101)[:, None] * (approach[-1] - approach[0])
    floor = min(guidance.settings.approach_clearance, at_goal)
    assert meshes.clearance(line)[0] >= floor - 1e-4   # checked every path.resolution / 2, here every 1 % of it


def test_the_meshes_decide_the_approach_of_a_goal_they_find_free(panda, grasp, monkeypatch) -> None:
    monkeypatch.setattr(MeshGoalCheck, "segment_free", lambda self, a, b, step, floor=None: False)
    with pytest.raises(GuidanceError) as refused:
        JointGuidance(panda).plan(START, JointTarget(tuple(grasp)), [WALL])
    assert refused.value.reason == "goal_in_collision"


def test_guidance_instances_of_one_robot_share_its_mesh_model(panda) -> None:
    first, second = JointGuidance(panda), JointGuidance(panda)
    first.checker.set_obstacles([WALL])
    second.checker.set_obstacles([WALL])
    model = robot_mesh_model(panda)
    assert model is not None and first._meshes().model is model and second._meshes().model is model
