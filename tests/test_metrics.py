"""Run metrics against hand-computed values (docs/design.md section 6)."""

from __future__ import annotations

import dataclasses

import json

import numpy as np
import pytest
from numpy.typing import NDArray

from dynfab.scenario.metrics import (
    Metrics,
    clearance_over_time,
    compute_metrics,
    path_length,
    summed_error,
    with_contacts,
)
from dynfab.sim import Record

JSON_KEYS = [
    "success", "goal_reached", "collision", "time_to_goal", "clearance",
    "path_length", "summed_error", "solver_time_ms", "steps", "orientation_error", "sphere_clearance",
    "self_collision", "min_self_distance", "max_velocity_ratio", "max_acceleration_ratio", "contacts",
    "link_contacts",
    "guided", "plans", "plan_time_ms", "recovered", "fallbacks", "goal_moved", "failure", "final_distance",
]


def _record(n_samples: int, dt: float = 1.0, solver_time: float = 0.002) -> Record:
    """A record of n_samples states 1-D robot, only t and solver_time matter here."""
    steps = n_samples - 1
    return Record(
        t=np.arange(n_samples) * dt,
        q=np.zeros((n_samples, 1)),
        qdot=np.zeros((n_samples, 1)),
        qddot=np.zeros((steps, 1)),
        solver_time=np.full(steps, solver_time),
    )


# Goal-link path: segments of length 5, 0 and 12 -> path length 17.
PATH = np.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0], [3.0, 4.0, 0.0], [3.0, 4.0, 12.0]])


def _no_obstacles(n_samples: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    return np.zeros((n_samples, 0, 3)), np.zeros(0)


def test_clearance_is_min_over_time_spheres_and_obstacles() -> None:
    spheres = np.stack([PATH, PATH + [0.0, 0.0, -1.0]], axis=1)  # (4, 2, 3)
    sphere_radii = np.array([0.1, 0.2])
    obstacles = np.zeros((4, 2, 3))
    obstacles[:, 0] = [[3.0, 4.0, 2.0], [3.0, 4.0, 2.0], [3.0, 4.0, 30.0], [3.0, 4.0, 30.0]]
    obstacles[:, 1] = [[10.0, 0.0, 0.0], [10.0, 0.0, 0.0], [3.0, 0.0, -1.0], [3.0, 4.0, 20.0]]
    obstacle_radii = np.array([0.5, 1.0])
    per_time = clearance_over_time(spheres, sphere_radii, obstacles, obstacle_radii)
    expected = [
        np.sqrt(9 + 16 + 4) - 0.6,  # t0: sphere 0 to obstacle 0
        2.0 - 0.6,  # t1: sphere 0 to obstacle 0 (sphere 1 is 3 away: 3 - 0.7)
        4.0 - 1.2,  # t2: sphere 1 at (3, 4, -1) to obstacle 1 at (3, 0, -1)
        8.0 - 1.1,  # t3: sphere 0 at z=12 to obstacle 1 at z=20
    ]
    np.testing.assert_allclose(per_time, expected)
    metrics = compute_metrics(
        _record(4), PATH, [3.0, 4.0, 0.5], 0.6, spheres, sphere_radii, obstacles, obstacle_radii
    )
    assert metrics.clearance == pytest.approx(1.4)
    assert metrics.collision is False
    assert metrics.time_to_goal == 1.0
    assert metrics.goal_reached is True and metrics.success is True
    assert metrics.path_length == pytest.approx(17.0)
    assert metrics.summed_error is None
    assert metrics.solver_time_ms == pytest.approx(2.0)
    assert metrics.steps == 3


def test_collision_makes_the_run_fail_even_at_the_goal() -> None:
    spheres = PATH[:, None, :]
    obstacles = np.tile([3.0, 4.0, 0.3], (4, 1, 1))  # 0.3 from the goal link at t1, t2
    metrics = compute_metrics(
        _record(4), PATH, [3.0, 4.0, 0.0], 0.05, spheres, [0.1], obstacles, [0.15]
    )
    assert metrics.clearance == pytest.approx(0.3 - 0.25)
    assert metrics.collision is False
    metrics = compute_metrics(
        _record(4), PATH, [3.0, 4.0, 0.0], 0.05, spheres, [0.1], obstacles, [0.25]
    )
    assert metrics.clearance == pytest.approx(-0.05)
    assert metrics.collision is True
    assert metrics.goal_reached is True and metrics.time_to_goal == 1.0
    assert metrics.success is False


def test_goal_never_reached_is_a_deadlock() -> None:
    metrics = compute_metrics(
        _record(4), PATH, [0.0, 0.0, 5.0], 0.05, PATH[:, None, :], [0.1], *_no_obstacles(4)
    )
    assert metrics.goal_reached is False
    assert metrics.time_to_goal is None
    assert metrics.success is False and metrics.collision is False


def test_tolerance_is_strict() -> None:
    # At t1 the distance is exactly 0.5: not "closer than" a 0.5 tolerance.
    metrics = compute_metrics(
        _record(4), PATH, [3.0, 4.0, 0.5], 0.5, PATH[:, None, :], [0.1], *_no_obstacles(4)
    )
    assert metrics.goal_reached is False


def test_time_to_goal_uses_record_times() -> None:
    metrics = compute_metrics(
        _record(4, dt=0.01), PATH, [3.0, 4.0, 12.0], 0.05, PATH[:, None, :], [0.1],
        *_no_obstacles(4),
    )
    assert metrics.time_to_goal == pytest.approx(0.03)


def test_planar_distances_ignore_z() -> None:
    positions = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 5.0], [1.0, 1.0, -5.0]])
    spheres = positions[:, None, :]
    obstacles = np.tile([4.0, 4.0, 10.0], (3, 1, 1))  # z must not count
    metrics = compute_metrics(
        _record(3), positions, [1.0, 1.0], 0.01, spheres, [0.5], obstacles, [1.0], planar=True
    )
    # closest at t2: ||(1,1) - (4,4)|| = 3 sqrt(2)
    assert metrics.clearance == pytest.approx(3.0 * np.sqrt(2.0) - 1.5)
    assert metrics.path_length == pytest.approx(2.0)
    assert metrics.time_to_goal == 2.0
    planar_obstacles_2d = np.tile([4.0, 4.0], (3, 1, 1))
    np.testing.assert_allclose(
        clearance_over_time(spheres, [0.5], planar_obstacles_2d, [1.0], planar=True),
        clearance_over_time(spheres, [0.5], obstacles, [1.0], planar=True),
    )
    spatial = compute_metrics(
        _record(3), positions, [1.0, 1.0, -5.0], 0.01, spheres, [0.5], obstacles, [1.0]
    )
    # in 3-D the closest approach is at t1: ||(1, 0, 5) - (4, 4, 10)|| = sqrt(50)
    assert spatial.clearance == pytest.approx(np.sqrt(50.0) - 1.5)


def test_no_obstacles_gives_null_clearance() -> None:
    metrics = compute_metrics(
        _record(4), PATH, [3.0, 4.0, 0.0], 0.05, PATH[:, None, :], [0.1], *_no_obstacles(4)
    )
    assert metrics.clearance is None and metrics.collision is False
    assert np.all(np.isinf(clearance_over_time(PATH[:, None, :], [0.1], *_no_obstacles(4))))
    assert json.loads(json.dumps(metrics.to_dict()))["clearance"] is None


def test_path_length_of_a_sampled_circle() -> None:
    angles = np.linspace(0.0, 2.0 * np.pi, 10001)
    circle = np.stack([2.0 * np.cos(angles), 2.0 * np.sin(angles)], axis=1)
    assert path_length(circle) == pytest.approx(4.0 * np.pi, rel=1e-6)
    assert path_length(circle[:1]) == 0.0


def test_summed_error_is_mean_from_first_time_within_tolerance() -> None:
    reference = np.zeros((5, 2))
    positions = np.array([[1.0, 0.0], [0.0, 0.2], [0.04, 0.0], [0.0, -0.1], [0.3, 0.0]])
    assert summed_error(positions, reference, 0.05) == pytest.approx((0.04 + 0.1 + 0.3) / 3)
    assert summed_error(positions, reference, 0.01) is None
    assert summed_error(positions, reference, 2.0) == pytest.approx((1.0 + 0.2 + 0.04 + 0.1 + 0.3) / 5)


def test_path_goal_reports_summed_error_against_moving_reference() -> None:
    t = np.arange(5) * 0.1
    reference = np.stack([t, np.zeros(5), np.ones(5)], axis=1)
    positions = reference + np.array([[0.5, 0, 0], [0.2, 0, 0], [0.03, 0, 0], [0, 0.04, 0], [0, 0, 0.1]])
    metrics = compute_metrics(
        _record(5, dt=0.1), positions, reference, 0.05, positions[:, None, :], [0.05],
        *_no_obstacles(5), path_goal=True,
    )
    assert metrics.time_to_goal == pytest.approx(0.2)
    assert metrics.goal_reached is True
    assert metrics.summed_error == pytest.approx((0.03 + 0.04 + 0.1) / 3)


def test_a_path_that_ends_at_rest_is_reached_only_if_its_end_is() -> None:
    t = np.arange(5) * 0.1
    reference = np.stack([t, np.zeros(5), np.ones(5)], axis=1)
    followed = reference + np.array([[0.5, 0, 0], [0.02, 0, 0], [0.03, 0, 0], [0.2, 0, 0], [0.0, 0.01, 0]])
    left_behind = followed.copy()
    left_behind[-1] += [0.0, 0.3, 0.0]   # within tolerance early, 0.3 m off the end at the last sample
    common = (_record(5, dt=0.1),)
    for positions, reached in ((followed, True), (left_behind, False)):
        metrics = compute_metrics(*common, positions, reference, 0.05, positions[:, None, :], [0.05],
                                  *_no_obstacles(5), path_goal=True, end_required=True)
        assert metrics.goal_reached is reached and metrics.success is reached
    loose = compute_metrics(*common, left_behind, reference, 0.05, left_behind[:, None, :], [0.05],
                            *_no_obstacles(5), path_goal=True)
    assert loose.goal_reached is True   # a path without an end at rest: reached once followed


def test_to_dict_has_exactly_the_contract_keys() -> None:
    metrics = Metrics(
        success=True, goal_reached=True, collision=False, time_to_goal=4.31, clearance=0.12,
        path_length=0.93, summed_error=None, solver_time_ms=0.05, steps=3000,
    )
    data = metrics.to_dict()
    assert list(data) == JSON_KEYS
    assert json.loads(json.dumps(data)) == data
    computed = compute_metrics(
        _record(4), PATH, [3.0, 4.0, 0.0], 0.05, PATH[:, None, :], [0.1],
        np.tile([9.0, 9.0, 9.0], (4, 1, 1)), [0.1],
    ).to_dict()
    assert list(computed) == JSON_KEYS
    assert json.loads(json.dumps(computed)) == computed
    assert all(type(computed[key]) is bool for key in ("success", "goal_reached", "collision"))
    assert type(computed["steps"]) is int
    assert computed["sphere_clearance"] == computed["clearance"]  # spheres only: the same figure
    assert computed["self_collision"] is None and computed["min_self_distance"] is None


def test_mismatched_samples_raise() -> None:
    with pytest.raises(ValueError, match="3 samples, the record 4"):
        compute_metrics(_record(4), PATH[:3], [0.0, 0.0, 0.0], 0.05, PATH[:, None, :], [0.1],
                        *_no_obstacles(4))
    with pytest.raises(ValueError, match="expected centres"):
        clearance_over_time(PATH[:, None, :], [0.1], np.zeros((3, 1, 3)), [0.1])


@dataclasses.dataclass(frozen=True)
class _Contact:
    """A MuJoCo contact as dynfab.sim.mujoco_sim reports it (time [s], robot link, what it touched)."""

    time: float
    body: str
    other: str


def test_mujoco_contacts_are_collisions_and_link_contacts_self_collisions() -> None:
    clean = Metrics(success=True, goal_reached=True, collision=False, time_to_goal=1.0, clearance=0.1,
                    path_length=1.0, summed_error=None, solver_time_ms=0.05, steps=100, self_collision=False)
    assert with_contacts(clean, ()) == dataclasses.replace(clean, contacts=0, link_contacts=0)
    touched = with_contacts(clean, (_Contact(0.1, "panda_hand_body", "obstacles[0]"),
                                    _Contact(0.2, "panda_link1", "obstacles[1]")))
    assert touched.contacts == 2 and touched.link_contacts == 0 and touched.collision and not touched.success
    assert touched.self_collision is False
    folded = with_contacts(clean, (_Contact(0.3, "panda_leftfinger", "panda_link5"),))
    assert folded.contacts == 1 and folded.link_contacts == 1
    assert folded.self_collision and not folded.collision and not folded.success
    spheres = dataclasses.replace(clean, self_collision=None)   # a robot measured by spheres
    assert with_contacts(spheres, ()).self_collision is None
    assert with_contacts(spheres, (_Contact(0.3, "link3", "link1"),)).self_collision is True
