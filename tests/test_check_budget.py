"""Plans bounded by checks, not wall time (``JointPlannerSettings.check_rate``, the
simulators' :func:`~dynfab.motion.guidance_settings.counted_checks`): the search stops at
its budget of configuration checks, and the same seed gives the same path on a machine
whose clock runs faster or slower than this one's."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import pytest

from dynfab.motion import ompl_problem
from dynfab.motion.configuration_checker import ConfigurationChecker
from dynfab.motion.guidance_settings import SIMULATION_CHECK_RATE, GuidanceSettings, counted_checks
from dynfab.motion.joint_planning import WALL_FACTOR, JointPlannerSettings, NoPathError, plan_joint_path
from dynfab.robots import load_robot
from wall_scene import START, WALL

GOAL = np.array([-1.3, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])   # behind the wall: a search, not a straight line


@pytest.fixture(scope="module")
def problem():
    panda = load_robot("panda")
    return ConfigurationChecker(panda, [WALL]), panda.kinematics.lower, panda.kinematics.upper


def test_a_budget_of_checks_stops_the_search_whatever_its_time(problem) -> None:
    checker, lower, upper = problem
    with pytest.raises(NoPathError) as failure:   # 1 s stands for 20 checks: far too few to go round
        plan_joint_path(checker, START, GOAL, lower, upper, JointPlannerSettings(check_rate=20.0))
    assert failure.value.reason == "no_path" and "within 20 checks" in str(failure.value)
    found = plan_joint_path(checker, START, GOAL, lower, upper, JointPlannerSettings(check_rate=1e6))
    assert found.checks > 20


def test_the_same_seed_gives_the_same_path_whatever_the_clock(problem, monkeypatch: pytest.MonkeyPatch) -> None:
    checker, lower, upper = problem
    settings = JointPlannerSettings(check_rate=100_000.0)
    here = plan_joint_path(checker, START, GOAL, lower, upper, settings, seed=7)
    real = time.perf_counter
    origin = real()
    for clock in (lambda: origin + 4.0 * (real() - origin), lambda: origin):   # 4x slower; stopped
        monkeypatch.setattr(ompl_problem.time, "perf_counter", clock)
        other = plan_joint_path(checker, START, GOAL, lower, upper, settings, seed=7)
        np.testing.assert_array_equal(here.waypoints, other.waypoints)
        assert here.checks == other.checks


def test_the_simulators_settings_count_checks_and_widen_wall_times() -> None:
    settings = GuidanceSettings()
    counted = counted_checks(settings, rate=1000.0)
    assert counted.path == replace(settings.path, check_rate=1000.0)
    assert counted.ik.time_limit == WALL_FACTOR * settings.ik.time_limit
    assert counted.ik_retry.time_limit == WALL_FACTOR * settings.ik_retry.time_limit


def test_counting_checks_twice_changes_nothing() -> None:
    once = counted_checks(GuidanceSettings(), rate=1000.0)
    assert counted_checks(once) == once and counted_checks(once, rate=5.0) == once


@pytest.mark.parametrize("latency", [None, 0.05])
def test_a_guided_fabric_with_a_plan_latency_counts_checks(latency: float | None) -> None:
    """A plan latency means the caller's clock is simulated: the searches are bounded by
    checks, as the scenario runner's are, whoever builds the guided fabric; real time keeps
    wall-time limits."""
    from dynfab.fabric.planner import FabricPlanner, PlannerConfig
    from dynfab.motion.guided_fabric import GuidedFabric, guided_goal_config

    robot = load_robot("panda")
    fabric = FabricPlanner(robot, PlannerConfig.for_robot(robot, (guided_goal_config(),), 0, dynamic=True))
    guided = GuidedFabric(fabric, GuidanceSettings(), plan_latency=latency)
    try:
        expected = None if latency is None else SIMULATION_CHECK_RATE
        assert guided.guidance.settings.path.check_rate == expected
    finally:
        guided.close()
