"""Tests of the OMPL-based global path planner for the goal link."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from numpy.typing import NDArray

from dynfab.motion.global_planning import GlobalPlanningError, path_duration, plan_path

CENTER = np.array([0.5, 0.0, 0.5])
RADIUS = 0.2
MARGIN = 0.1
START = np.array([0.5, -0.5, 0.5])
GOAL = np.array([0.5, 0.5, 0.5])
LOW = np.array([-1.0, -1.0, 0.0])
HIGH = np.array([1.0, 1.0, 1.2])


def _plan(**overrides: object) -> NDArray[np.float64]:
    """Plans around the sphere between START and GOAL, whose straight segment hits it."""
    arguments: dict[str, object] = {
        "start": START,
        "goal": GOAL,
        "spheres": [(CENTER, RADIUS)],
        "margin": MARGIN,
        "bounds_low": LOW,
        "bounds_high": HIGH,
    }
    arguments.update(overrides)
    return plan_path(**arguments)  # type: ignore[arg-type]


def _dense_points(waypoints: NDArray[np.float64], per_segment: int = 400) -> NDArray[np.float64]:
    """Points sampled densely along every segment of a polyline, vertices included."""
    fractions = np.linspace(0.0, 1.0, per_segment + 1)[:, None]
    return np.concatenate(
        [a + fractions * (b - a) for a, b in itertools.pairwise(waypoints)], axis=0
    )


@pytest.mark.parametrize("planner", ["RRTConnect", "RRT"])
def test_path_keeps_margin_along_every_segment(planner: str) -> None:
    waypoints = _plan(planner=planner)
    assert waypoints.ndim == 2 and waypoints.shape[1] == 3 and waypoints.shape[0] >= 3
    np.testing.assert_array_equal(waypoints[0], START)
    np.testing.assert_array_equal(waypoints[-1], GOAL)
    points = _dense_points(waypoints)
    assert np.min(np.linalg.norm(points - CENTER, axis=1)) >= RADIUS + MARGIN
    assert np.all(points >= LOW) and np.all(points <= HIGH)
    # Simplified: few waypoints, not much longer than the shortest way around.
    assert waypoints.shape[0] <= 12
    assert path_duration(waypoints, 1.0) < 2.0


def test_same_seed_gives_same_path() -> None:
    first = _plan(seed=3)
    _plan(seed=4)
    np.testing.assert_array_equal(_plan(seed=3), first)


def test_start_in_collision_is_named() -> None:
    with pytest.raises(GlobalPlanningError, match=r"^start .* in collision with sphere 0"):
        _plan(start=CENTER + np.array([0.0, -0.25, 0.0]))


def test_goal_outside_bounds_is_named() -> None:
    with pytest.raises(GlobalPlanningError, match=r"^goal .* outside the planning bounds"):
        _plan(goal=np.array([0.5, 0.5, 1.5]))


def test_planar_path() -> None:
    center = np.array([0.0, 0.0])
    start = np.array([-1.0, 0.1])
    goal = np.array([1.0, -0.1])
    waypoints = plan_path(
        start,
        goal,
        [(center, 0.4)],
        bounds_low=[-2.0, -2.0],
        bounds_high=[2.0, 2.0],
        seed=1,
    )
    assert waypoints.shape[1] == 2
    np.testing.assert_array_equal(waypoints[[0, -1]], [start, goal])
    distances = np.linalg.norm(_dense_points(waypoints) - center, axis=1)
    assert np.min(distances) >= 0.4 + 0.1


def test_enclosed_goal_fails_after_time_limit() -> None:
    spacing = 0.3
    cage = [
        (GOAL + spacing * np.array(offset), 0.15)
        for offset in itertools.product((-1.0, 0.0, 1.0), repeat=3)
        if any(offset)
    ]
    with pytest.raises(GlobalPlanningError, match="no collision-free path .* within 0.2 s"):
        plan_path(START, GOAL, cage, bounds_low=LOW, bounds_high=HIGH, time_limit=0.2)


def test_invalid_arguments() -> None:
    with pytest.raises(ValueError, match="sphere 0: centre must have shape"):
        _plan(spheres=[([0.5, 0.0], RADIUS)])
    with pytest.raises(ValueError, match="planner must be one of"):
        _plan(planner="PRM")


def test_path_duration() -> None:
    waypoints = np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 0.0]])
    assert path_duration(waypoints, 2.0) == pytest.approx(4.5)
    with pytest.raises(ValueError, match="speed must be positive"):
        path_duration(waypoints, 0.0)
