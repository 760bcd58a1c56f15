"""The compiled static fabric planner: runtime parameters, slots, robustness, errors."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.leaves.obstacle import SphereObstacleAvoidance
from dynfab.fabric.maps import DifferentialMap, difference, sphere_distance_map
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.robots import load_robot
from test_maps import check_map_against_finite_differences

Q0 = np.array([1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0])
PANDA = load_robot("panda")
HAND_GOAL = (GoalConfig(link="panda_hand"),)


@pytest.fixture(scope="module")
def panda_planner() -> FabricPlanner:
    planner = FabricPlanner(PANDA, PlannerConfig(goals=HAND_GOAL, obstacle_slots=3))
    planner.parameters.goal_position[0][:] = [0.5, -0.4, 0.3]
    return planner


def test_goal_and_obstacles_change_at_run_time_without_rebuild(panda_planner: FabricPlanner) -> None:
    function = panda_planner.function
    qdot = np.full(7, 0.1)
    before = panda_planner.compute(Q0, qdot)
    panda_planner.parameters.goal_position[0][:] = [0.3, 0.4, 0.6]
    moved_goal = panda_planner.compute(Q0, qdot)
    panda_planner.parameters.obstacle_position[0] = [0.35, 0.35, 0.6]
    panda_planner.parameters.obstacle_radius[0] = 0.1
    with_obstacle = panda_planner.compute(Q0, qdot)
    panda_planner.parameters.obstacle_radius[0] = 0.0
    panda_planner.parameters.goal_position[0][:] = [0.5, -0.4, 0.3]
    assert panda_planner.function is function
    assert np.linalg.norm(moved_goal - before) > 1e-3
    assert np.linalg.norm(with_obstacle - moved_goal) > 1e-3


def test_inactive_slots_contribute_nothing() -> None:
    without = FabricPlanner(PANDA, PlannerConfig(goals=HAND_GOAL, obstacle_slots=0))
    with_slots = FabricPlanner(PANDA, PlannerConfig(goals=HAND_GOAL, obstacle_slots=4))
    rng = np.random.default_rng(1)
    for planner in (without, with_slots):
        planner.parameters.goal_position[0][:] = [0.5, -0.4, 0.3]
    with_slots.parameters.obstacle_position[:] = rng.uniform(-1, 1, (4, 3))
    for _ in range(10):
        q, qdot = Q0 + rng.normal(0, 0.3, 7), rng.normal(0, 0.5, 7)
        np.testing.assert_allclose(with_slots.compute(q, qdot), without.compute(q, qdot), rtol=1e-12, atol=1e-12)


def test_weight_zero_deactivates_a_goal() -> None:
    planner = FabricPlanner(PANDA, PlannerConfig(goals=(GoalConfig(link="panda_hand"), GoalConfig(link="panda_link4", weight=0.0))))
    single = FabricPlanner(PANDA, PlannerConfig(goals=HAND_GOAL))
    for p in (planner, single):
        p.parameters.goal_position[0][:] = [0.5, -0.4, 0.3]
    planner.parameters.goal_position[1][:] = [0.0, 0.5, 0.5]
    qdot = np.full(7, 0.2)
    np.testing.assert_allclose(planner.compute(Q0, qdot), single.compute(Q0, qdot), atol=1e-12)
    planner.parameters.goal_weight[1] = 1.0
    assert np.linalg.norm(planner.compute(Q0, qdot) - single.compute(Q0, qdot)) > 1e-3


def test_output_finite_at_rest_with_overlapping_and_coincident_obstacles(panda_planner: FabricPlanner) -> None:
    """Zero velocity, obstacles centred exactly on robot spheres, deep overlaps, fast motion."""
    rng = np.random.default_rng(2)
    centres = PANDA.sphere_centers(Q0)
    for trial in range(300):
        q = Q0 + rng.normal(0, 0.5, 7) * (trial % 3 != 0)
        qdot = rng.normal(0, 3.0, 7) * (trial % 2)
        panda_planner.parameters.obstacle_position[:] = centres[rng.integers(0, len(centres), 3)] + rng.normal(0, 0.05, (3, 3)) * (trial % 4 != 0)
        panda_planner.parameters.obstacle_radius[:] = rng.uniform(0.05, 0.4, 3)
        out = panda_planner.compute(q, qdot)
        assert out.shape == (7,) and np.isfinite(out).all()
    assert panda_planner.fallback_count == 0
    panda_planner.parameters.obstacle_radius[:] = 0.0


def test_goal_at_current_position_at_rest_gives_zero_acceleration() -> None:
    planner = FabricPlanner(PANDA, PlannerConfig(goals=HAND_GOAL))
    hand = np.array(PANDA.kinematics.position(Q0, "panda_hand")).ravel()
    planner.parameters.goal_position[0][:] = hand
    np.testing.assert_allclose(planner.compute(Q0, np.zeros(7)), 0.0, atol=1e-9)


def test_non_finite_fabric_output_falls_back_to_braking() -> None:
    broken = SphereObstacleAvoidance(Barrier(geometry=lambda x, xdot: x * math.inf))
    planner = FabricPlanner(PANDA, PlannerConfig(goals=HAND_GOAL, obstacle_slots=1, obstacle_avoidance=broken))
    planner.parameters.obstacle_position[0] = [0.4, 0.4, 0.5]
    planner.parameters.obstacle_radius[0] = 0.1
    qdot = np.full(7, 0.3)
    out = planner.compute(Q0, qdot)
    np.testing.assert_allclose(out, -planner.config.fallback_braking * qdot)
    assert planner.fallback_count == 1


def test_user_callables_replace_geometry_and_energy() -> None:
    default = FabricPlanner(PANDA, PlannerConfig(goals=HAND_GOAL, obstacle_slots=1))
    custom = FabricPlanner(PANDA, PlannerConfig(goals=HAND_GOAL, obstacle_slots=1, obstacle_avoidance=SphereObstacleAvoidance(
        Barrier(geometry=lambda x, xdot: -2.0 / x**2 * xdot**2, energy=lambda x, xdot: 1.0 / x * xdot**2))))
    for p in (default, custom):
        p.parameters.obstacle_position[0] = [0.45, 0.45, 0.55]
        p.parameters.obstacle_radius[0] = 0.1
    qdot = np.array([0.5, 0.2, 0.0, 0.1, 0.0, 0.0, 0.0])
    assert np.linalg.norm(default.compute(Q0, qdot) - custom.compute(Q0, qdot)) > 1e-3


@pytest.mark.parametrize(("q", "qdot", "message"), [
    (np.zeros(6), np.zeros(7), r"q must have shape \(7,\)"),
    (np.zeros(7), np.zeros((7, 1)), r"qdot must have shape \(7,\)"),
    (np.full(7, np.nan), np.zeros(7), "q contains NaN"),
    (np.zeros(7), np.array([0, 0, np.inf, 0, 0, 0, 0.0]), "qdot contains NaN or infinity"),
])
def test_invalid_state_raises_clear_error(panda_planner: FabricPlanner, q, qdot, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        panda_planner.compute(q, qdot)


def test_huge_but_finite_state_is_accepted_and_answered_with_a_finite_command(panda_planner: FabricPlanner) -> None:
    """The finiteness check squares the input (numpy warns that it overflows); the overflow
    must not count as a NaN."""
    qdot = np.array([1e200, 0, 0, 0, 0, 0, 0.0])
    with pytest.warns(RuntimeWarning, match="overflow"):
        out = panda_planner.compute(Q0, qdot)
    assert np.isfinite(out).all()


def test_non_finite_parameter_raises(panda_planner: FabricPlanner) -> None:
    panda_planner.parameters.obstacle_position[1] = [np.nan, 0, 0]
    with pytest.raises(ValueError, match="parameter"):
        panda_planner.compute(Q0, np.zeros(7))
    panda_planner.parameters.obstacle_position[1] = [0, 0, 0]


@pytest.mark.parametrize(("config", "message"), [
    (lambda: PlannerConfig(goals=()), "at least one goal"),
    (lambda: PlannerConfig(goals=HAND_GOAL, obstacle_slots=-1), "obstacle_slots"),
    (lambda: FabricPlanner(PANDA, PlannerConfig(goals=(GoalConfig(link="panda_hand", axes="xq"),))), "axes"),
    (lambda: FabricPlanner(PANDA, PlannerConfig(goals=(GoalConfig(link="no_such_link"),))), "no_such_link"),
    (lambda: FabricPlanner(PANDA, PlannerConfig(goals=(GoalConfig(joints=(9,)),))), "joints"),
    (lambda: FabricPlanner(PANDA, PlannerConfig(goals=HAND_GOAL, obstacle_slots=1, collision_links=("panda_link99",))), "collision_links"),
])
def test_invalid_configuration_raises_clear_error(config, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        config()


def test_self_collision_pair_map_matches_finite_differences() -> None:
    q, qdot = ca.SX.sym("q", 7), ca.SX.sym("qdot", 7)
    spheres = PANDA.collision_spheres
    for a, b in PANDA.self_collision_pairs[:3]:
        maps = [DifferentialMap.from_expression(PANDA.kinematics.position(q, spheres[i].link, offset=spheres[i].center), q, qdot)
                for i in (a, b)]
        offset, offset_velocity = ca.SX.sym("o", 3), ca.SX.sym("od", 3)
        pair = sphere_distance_map(offset, offset_velocity, ca.DM.zeros(3), ca.DM(0.1)).after(difference(*maps))
        check_map_against_finite_differences(pair, trials=4)


def test_joint_goal_and_subset_axes_build() -> None:
    planner = FabricPlanner(PANDA, PlannerConfig(goals=(GoalConfig(joints=(0, 3)), GoalConfig(link="panda_hand", axes="z"))))
    assert [len(g) for g in planner.parameters.goal_position] == [2, 1]
    planner.parameters.goal_position[0][:] = [0.0, -2.0]
    planner.parameters.goal_position[1][:] = [0.5]
    assert np.isfinite(planner.compute(Q0, np.zeros(7))).all()
