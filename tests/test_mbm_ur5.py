"""MotionBenchMaker on the UR5 (``dynfab benchmark mbm --robot ur5``): the Panda's grasp
pose converted into a pose goal for the UR5's tool, a goal it cannot reach marked invalid,
and one converted problem run to its goal without touching the scene on the UR5's meshes."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.problem_run import run_case
from dynfab.benchmarks.mbm.problems import Problem, load_problems
from dynfab.benchmarks.mbm.ur5 import HOME, GraspPose, panda_grasp_pose, ur5
from dynfab.benchmarks.mbm.ur5_case import IK_SETTINGS, TOLERANCE, VARIANT, prepare_ur5_case
from dynfab.benchmarks.mbm.validity import static_shapes
from dynfab.cli import main
from dynfab.scenario.schema import scenario_from_dict


@pytest.fixture(scope="module")
def box_problem() -> Problem:
    """box/0017: a can in an open box in front of the arm."""
    return load_problems(["box"], per_type=1, skip=8)[0]


def _rotation_angle(a: GraspPose, b: GraspPose) -> float:
    cosine = (np.trace(a.rotation.T @ b.rotation) - 1.0) / 2.0
    return float(np.arccos(np.clip(cosine, -1.0, 1.0)))


def test_goal_is_the_pandas_grasp_pose_and_free_on_the_ur5_meshes(box_problem: Problem) -> None:
    panda, arm = franka(), ur5()
    case = prepare_ur5_case(box_problem, panda, arm)
    assert case.variant == VARIANT and case.invalid is None and case.removed == "Can1"
    assert case.mapping["initial_state"]["q"] == list(HOME)
    grasp = panda_grasp_pose(panda, panda.clipped(box_problem.goal))
    shapes = static_shapes(scenario_from_dict(case.mapping))
    q = arm.free_ik(grasp, shapes, IK_SETTINGS).q
    assert q is not None
    reached = arm.grasp_pose(q)
    assert np.linalg.norm(reached.position - grasp.position) < 1e-3  # [m]
    assert _rotation_angle(reached, grasp) < 1e-3  # [rad]: approach (z) and closing axes on the Panda's
    assert arm.contact(q, shapes) is None
    goal = case.mapping["goal"][0]
    assert goal["type"] == "pose" and goal["tolerance"] == TOLERANCE
    assert np.allclose(goal["position"], grasp.position, atol=1e-5)


def test_unreachable_goal_is_invalid() -> None:
    problem = load_problems(["bookshelf_tall"], per_type=1, skip=8)[0]  # top shelf, 1.05 m from the UR5's shoulder
    case = prepare_ur5_case(problem, franka(), ur5())
    assert case.invalid == "goal: no IK solution of the grasp pose within the UR5's limits (out of reach)"


def test_converted_problem_runs_to_its_goal_without_mesh_collision(box_problem: Problem) -> None:
    case = prepare_ur5_case(box_problem, franka(), ur5())
    outcome = run_case(case.mapping)
    assert outcome["refused"] is None
    metrics, check = outcome["metrics"], outcome["check"]
    assert metrics["goal_reached"], metrics
    assert check["ok"] and not check["collisions"] and not check["self_collisions"], check


def test_ur5_runs_object_removed_only(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["benchmark", "mbm", "--robot", "ur5", "--variant", "moving-sphere"]) == 2
    assert "object-removed variant only" in capsys.readouterr().err


def test_guidance_finds_a_grasp_pose_closer_to_the_scene_than_its_margin() -> None:
    """bookshelf_thin/0017: the UR5's wrist clears the thin shelf by 4 mm on its meshes at
    the goal; guidance's IK retries at margin 0 when none clears by the planner's margin."""
    from dynfab.motion.configuration_checker import PlacedObstacle
    from dynfab.motion.guidance import JointGuidance
    from dynfab.scenario.guided_controller import goal_targets

    problem = load_problems(["bookshelf_thin"], per_type=1, skip=8)[0]
    case = prepare_ur5_case(problem, franka(), ur5())
    assert case.invalid is None
    scenario = scenario_from_dict(case.mapping)
    guidance = JointGuidance(ur5().robot)
    guidance.checker.set_obstacles([PlacedObstacle(s.shape, s.placements[0]) for s in static_shapes(scenario)])
    q = guidance.goal_configuration(goal_targets(scenario, ur5().robot), np.array(HOME))
    assert 0.0 <= guidance.checker.clearances(q)[0] < guidance.settings.path.margin
    reached = ur5().grasp_pose(q)
    assert np.linalg.norm(reached.position - panda_grasp_pose(franka(), franka().clipped(problem.goal)).position) < 1e-3
