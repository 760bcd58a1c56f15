"""Stall recovery: detection, the carrot on the path, and a Boxer that deadlocks without
it and reaches its goal with it."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from dynfab.scenario import recovering_controller
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import load_scenario
from dynfab.scenario.stall_recovery import GlobalPlanningError, PathFollower, StallMonitor, StallRecovery

STALL = Path(__file__).parent / "data" / "boxer_stall.yaml"


def test_a_distance_that_stops_improving_is_a_stall_after_the_window() -> None:
    monitor = StallMonitor(StallRecovery(window=3.0))   # from 2 m: 0.25 * 2 m capped at 0.2 m
    times = np.arange(0.0, 10.0, 0.1)
    stalled = [monitor.stalled(t, max(2.0 - 0.5 * t, 1.0)) for t in times]   # approaches, then stops at 1 m
    first = times[stalled.index(True)]
    assert first == pytest.approx(2.0 + 3.0, abs=0.11)   # the last 0.2 m gain ends at t = 2 s, then 3 s


def test_the_progress_expected_scales_with_the_robot_and_the_goal_distance() -> None:
    recovery = StallRecovery()
    assert recovery.progress(initial_distance=2.0, reach=0.9) == pytest.approx(0.2)     # a Panda far away: the cap
    assert recovery.progress(initial_distance=0.2, reach=0.9) == pytest.approx(0.05)    # a Panda near its goal
    assert recovery.progress(initial_distance=0.5, reach=0.3) == pytest.approx(0.075)   # an SO-100-sized arm
    small = StallMonitor(recovery, reach=0.3)
    times = np.arange(0.0, 10.0, 0.01)
    # 3 cm/s toward a goal 0.3 m away: 9 cm in 3 s is progress for a 30 cm arm (it was a stall at 0.2 m)
    assert not any(small.stalled(t, 0.3 - 0.03 * t) for t in times[:1000])
    stuck = StallMonitor(recovery, reach=0.3)
    assert any(stuck.stalled(t, max(0.25 - 0.05 * t, 0.1)) for t in times)   # stops 10 cm short: a stall


def test_oscillating_is_a_stall_and_steady_progress_is_not() -> None:
    oscillating, steady = (StallMonitor(StallRecovery()) for _ in range(2))
    times = np.arange(0.0, 10.0, 0.01)
    assert any(oscillating.stalled(t, 1.0 + 0.3 * np.sin(2 * t)) for t in times)
    assert not any(steady.stalled(t, 10.0 - 0.1 * t) for t in times)   # 0.1 m/s: 0.2 m in 2 s < 3 s


def test_the_carrot_runs_ahead_on_the_path_and_never_back() -> None:
    follower = PathFollower(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]), lookahead=0.3)
    carrot, at_end = follower.carrot(np.array([0.5, 0.1]))
    np.testing.assert_allclose(carrot, [0.8, 0.0])
    assert not at_end
    carrot, _ = follower.carrot(np.array([0.0, 0.0]))   # pushed back: the carrot stays
    np.testing.assert_allclose(carrot, [0.8, 0.0])
    carrot, _ = follower.carrot(np.array([0.95, 0.2]))
    np.testing.assert_allclose(carrot, [1.0, 0.5])
    carrot, at_end = follower.carrot(np.array([1.0, 0.9]))
    np.testing.assert_allclose(carrot, [1.0, 1.0])
    assert at_end


def test_a_boxer_that_deadlocks_reaches_its_goal_with_recovery() -> None:
    scenario = load_scenario(STALL)
    without = run_scenario(dataclasses.replace(scenario, recovery=False))
    assert not without.metrics.goal_reached and not without.metrics.collision
    assert (without.metrics.recovered, without.metrics.plans, without.metrics.failure) == (0, 0, "stalled")
    recovered = run_scenario(dataclasses.replace(scenario, recovery=True))
    assert recovered.metrics.success and not recovered.metrics.collision
    paths = len(recovered.controller.recovery_times)   # it was the recovery that got it there ...
    assert paths >= 1 and recovered.metrics.recovered == recovered.metrics.plans == paths   # ... and the JSON says so
    assert recovered.metrics.guided is False and recovered.metrics.fallbacks == 0


def test_a_recovery_that_finds_no_path_is_not_reported_as_one(monkeypatch: pytest.MonkeyPatch) -> None:
    attempts: list[int] = []

    def no_path(start, goal, spheres, margin, seed):
        attempts.append(seed)
        raise GlobalPlanningError("no path")

    monkeypatch.setattr(recovering_controller, "rrt_path_planner", lambda: no_path)
    result = run_scenario(dataclasses.replace(load_scenario(STALL), recovery=True))
    assert attempts and not result.metrics.goal_reached   # recovery was tried and failed: the fabric went on alone
    assert (result.metrics.recovered, result.metrics.plans, result.metrics.failure) == (0, 0, "stalled")
