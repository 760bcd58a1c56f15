"""Every planner command is finite and within the acceleration limits, whatever the input
(the issue's 10⁵-call check runs in bench/bench_bounded_output.py; here 400 per case)."""

import numpy as np
import pytest

from dynfab.experiments.adversarial import CASES, case_planner, run_case


@pytest.mark.parametrize("robot, dynamic", CASES, ids=[f"{r}-{'dynamic' if d else 'static'}" for r, d in CASES])
def test_adversarial_calls_give_finite_commands_within_the_limits(robot: str, dynamic: bool) -> None:
    statistics = run_case(robot, dynamic, calls=400, seed=7)
    assert statistics.non_finite == 0
    assert statistics.beyond_limits == 0
    assert 0.99 < statistics.max_acceleration_ratio <= 1.0 + 1e-9   # the bound is reached, never passed


def test_the_planner_exposes_the_limits_in_use_and_can_return_the_raw_fabric() -> None:
    import dataclasses
    from dynfab.fabric.planner import FabricPlanner
    bounded = case_planner("panda", dynamic=False)
    np.testing.assert_allclose(bounded.config.limits.acceleration, bounded.robot.limits.acceleration)
    raw = FabricPlanner(bounded.robot, dataclasses.replace(bounded.config, bound_command=False))
    q, qdot = bounded.robot.default_q, np.full(7, 2.0)
    hand = bounded.robot.sphere_centers(q)[-1]
    for planner in (bounded, raw):   # a ball 7 cm below the hand, the arm moving fast
        planner.parameters.goal_position[0][:] = [0.4, 0.3, 0.5]
        planner.parameters.obstacle_position[0] = hand + [0.0, 0.0, -0.12]
        planner.parameters.obstacle_radius[0] = 0.05
    fast = raw.compute(q, qdot)
    assert np.max(np.abs(fast) / bounded.config.limits.acceleration) > 1.0   # the raw fabric would exceed
    command = bounded.compute(q, qdot)
    assert np.max(np.abs(command) / bounded.config.limits.acceleration) <= 1.0 + 1e-12


def test_the_fallback_action_is_within_the_limits_too() -> None:
    planner = case_planner("panda", dynamic=False)
    qdot = np.full(7, 100.0)
    np.testing.assert_allclose(np.abs(planner._fallback(qdot)), planner.config.limits.acceleration)
