"""Joint-space planning to an endpoint whose own self-collision spheres overlap (a folded
wrist in a MotionBenchMaker grasp, free on the meshes)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.problems import load_problems
from dynfab.benchmarks.mbm.variants import prepare_case
from dynfab.motion.configuration_checker import ConfigurationChecker
from dynfab.motion.joint_planning import JointPlannerSettings, NoPathError, plan_joint_path, polyline_samples
from dynfab.robots import load_robot
from dynfab.scenario.guided_controller import placed_obstacles
from dynfab.scenario.references import scenario_references
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


@pytest.fixture(scope="module")
def grasp(panda):
    """As-posed MBM bookshelf_small/0009 (a training problem): its start, its goal (whose
    panda_link5 and panda_link7 spheres overlap by 3.5 mm, free on the meshes) and the
    checker with its scene."""
    case = prepare_case(load_problems(["bookshelf_small"], per_type=1)[0], "as-posed", franka())
    scenario = validate_for_robot(scenario_from_dict(case.mapping), panda)
    obstacles = placed_obstacles(scenario, scenario_references(scenario, panda), 0.0, static=True)
    goal = np.array(case.mapping["goal"][0]["position"])
    return np.array(scenario.initial_state.q), goal, ConfigurationChecker(panda, obstacles)


def test_a_goal_with_its_own_self_overlap_is_planned_to_within_that_overlap(panda, grasp) -> None:
    kin = panda.kinematics
    start, goal, checker = grasp
    overlap = checker.clearances(goal)[1]
    assert -0.005 < overlap < 0.0 and checker.clearances(start)[1] > 0.0
    strict = JointPlannerSettings(self_tolerance=0.0)
    with pytest.raises(NoPathError) as failure:   # no configuration within 0.4 rad is free of the overlap
        plan_joint_path(checker, start, goal, kin.lower, kin.upper, strict)
    assert failure.value.reason == "goal_in_collision"
    settings = JointPlannerSettings()
    path = plan_joint_path(checker, start, goal, kin.lower, kin.upper, settings)
    np.testing.assert_array_equal(path.waypoints[-1], goal)
    along = checker.batch(polyline_samples(path.waypoints, settings.resolution / 2))
    assert along[:, 1].min() >= overlap - settings.escape_slack - 1e-9   # never deeper than the goal's own


def test_the_tolerated_overlap_is_bounded(panda, grasp) -> None:
    kin = panda.kinematics
    start, goal, checker = grasp
    overlap = checker.clearances(goal)[1]
    # half the goal's overlap; looked for within 0.4 rad only (the overlap changes slowly: 0.8 rad away it is gone)
    bounded = replace(JointPlannerSettings(), self_tolerance=-overlap / 2, escape_far_radius=0.4)
    with pytest.raises(NoPathError) as failure:
        plan_joint_path(checker, start, goal, kin.lower, kin.upper, bounded)
    assert failure.value.reason == "goal_in_collision"


def test_a_goal_with_no_escape_within_the_radius_is_escaped_farther_out(panda, grasp) -> None:
    kin = panda.kinematics
    start, goal, checker = grasp
    overlap = checker.clearances(goal)[1]
    settings = replace(JointPlannerSettings(), self_tolerance=-overlap / 2)   # none within 0.4 rad (above)
    path = plan_joint_path(checker, start, goal, kin.lower, kin.upper, settings)
    assert path.escaped_goal
    reach = float(np.linalg.norm(path.waypoints[-2] - goal))
    assert settings.escape_radius < reach <= settings.escape_far_radius
    approach = checker.batch(polyline_samples(path.waypoints[-2:], settings.resolution / 2))
    assert approach[:, 1].min() >= overlap - settings.escape_slack - 1e-9   # never deeper than the goal's own


def test_a_blocked_goal_without_an_escape_is_tried_again_with_the_next_seed(panda, monkeypatch) -> None:
    """The escape's samples are random: an attempt that found no escape for a blocked goal
    does not end the request; the next attempt draws others (its seed + 1)."""
    from dynfab.motion import guidance as guidance_module
    from dynfab.motion.guidance import JointGuidance, JointTarget

    seeds = []
    real = guidance_module.plan_joint_path

    def first_escape_fails(*args, **kwargs):
        seeds.append(args[6])
        if len(seeds) == 1:
            raise NoPathError("goal_in_collision", "no escape among this seed's samples (test)")
        return real(*args, **kwargs)

    monkeypatch.setattr(guidance_module, "plan_joint_path", first_escape_fails)
    start = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785])
    plan = JointGuidance(panda).plan(start, JointTarget(tuple(start + 0.2)), [], seed=5)
    assert seeds == [5, 6] and np.allclose(plan.goal, start + 0.2)
