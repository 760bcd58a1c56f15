"""The orientation leaf: its task map against finite differences, its forcing against the
potential it descends, the angle helpers and the turning-direction references."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from dynfab.fabric.leaves.orientation import FRAME_AXES, OrientationGoalConfig, direction_map
from dynfab.fabric.maps import Reference
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.geometry.orientation import direction_angle, rotation_angle, unit_vector
from dynfab.geometry.shapes import quaternion_matrix, unit_quaternion
from dynfab.motion.directions import RotatingDirections
from dynfab.robots import load_robot
from test_maps import check_map_against_finite_differences

RNG = np.random.default_rng(11)
PANDA = load_robot("panda")
HAND_AXES = (((0.0, 0.0, 1.0),), FRAME_AXES, ((0.6, 0.0, 0.8), (0.0, 1.0, 0.0)))


def _panda_direction_map(link_axes):
    q, qdot = ca.SX.sym("q", 7), ca.SX.sym("qdot", 7)
    return direction_map(PANDA.kinematics.rotation(q, "panda_hand"), link_axes, q, qdot)


def _random_rotation() -> np.ndarray:
    return quaternion_matrix(unit_quaternion(RNG.normal(size=4)))


@pytest.mark.parametrize("link_axes", HAND_AXES, ids=["z", "frame", "two"])
def test_direction_map_jacobian_and_curvature_match_finite_differences(link_axes) -> None:
    check_map_against_finite_differences(_panda_direction_map(link_axes), trials=5)


def test_direction_map_is_the_rotated_axes() -> None:
    dmap = _panda_direction_map(FRAME_AXES)
    phi = ca.Function("phi", [dmap.q], [dmap.phi])
    for _ in range(5):
        q = RNG.uniform(PANDA.kinematics.lower, PANDA.kinematics.upper)
        rotation = np.array(PANDA.kinematics.rotation(q, "panda_hand"))
        np.testing.assert_allclose(np.array(phi(q)).ravel(), rotation.T.ravel(), atol=1e-12)


@pytest.mark.parametrize("link_axes", HAND_AXES[:2], ids=["z", "frame"])
def test_forcing_points_downhill_in_the_potential(link_axes) -> None:
    """At rest the pulled forcing is ``f = Jᵀ M_ψ ∇ψ``: ``fᵀ ∇_q ψ(φ(q)) > 0``, and a small
    step along ``−f`` lowers ``ψ``."""
    config = OrientationGoalConfig(link="panda_hand", link_axes=link_axes)
    dmap = _panda_direction_map(config.link_axes)
    target = ca.SX.sym("d", config.dimension)
    zero = ca.SX(config.dimension, 1)
    spec = config.attractor.forcing(dmap, Reference(target, zero, zero), ca.SX(1.0))
    potential = config.attractor.potential_of(dmap.phi - target)
    inputs = [dmap.q, dmap.qdot, target]
    force = ca.Function("f", inputs, [spec.f])
    psi = ca.Function("psi", inputs, [potential])
    gradient = ca.Function("grad", inputs, [ca.gradient(potential, dmap.q)])
    metric = ca.Function("M", inputs, [spec.M])
    for _ in range(10):
        q = RNG.uniform(PANDA.kinematics.lower, PANDA.kinematics.upper)
        d = config.target(_random_rotation())
        f = np.array(force(q, np.zeros(7), d)).ravel()
        g = np.array(gradient(q, np.zeros(7), d)).ravel()
        assert f @ g > 0.0
        step = 1e-4 * f / np.linalg.norm(f)
        assert float(psi(q - step, np.zeros(7), d)) < float(psi(q, np.zeros(7), d))
        assert np.linalg.eigvalsh(np.array(metric(q, np.zeros(7), d))).min() > -1e-9


def test_half_turn_is_an_unstable_equilibrium_of_the_axis_forcing() -> None:
    """With the hand's z opposite to the target the forcing vanishes; slightly off it,
    the forcing pushes further away from the half turn (downhill)."""
    config = OrientationGoalConfig(link="panda_hand", link_axes=((0.0, 0.0, 1.0),))
    dmap = _panda_direction_map(config.link_axes)
    target = ca.SX.sym("d", 3)
    zero = ca.SX(3, 1)
    spec = config.attractor.forcing(dmap, Reference(target, zero, zero), ca.SX(1.0))
    force = ca.Function("f", [dmap.q, dmap.qdot, target], [spec.f])
    q = RNG.uniform(PANDA.kinematics.lower, PANDA.kinematics.upper)
    opposite = -np.array(PANDA.kinematics.rotation(q, "panda_hand"))[:, 2]
    assert np.abs(np.array(force(q, np.zeros(7), opposite))).max() < 1e-9
    tilted = np.array(unit_vector(opposite + [0.05, 0.0, 0.0]))
    f = np.array(force(q, np.zeros(7), tilted)).ravel()
    assert np.linalg.norm(f) > 1e-3


def test_angles_of_known_rotations() -> None:
    axis = np.array(unit_vector([1.0, 2.0, -0.5]))
    for angle in (1e-6, 0.3, 2.0, np.pi - 1e-6):
        relative = quaternion_matrix((np.cos(angle / 2), *(np.sin(angle / 2) * axis)))
        base = _random_rotation()
        assert rotation_angle(base @ relative, base) == pytest.approx(angle, rel=1e-6, abs=1e-9)
        assert direction_angle(relative @ [0, 0, 1.0], [0, 0, 1.0]) <= angle + 1e-9
    assert direction_angle([0, 0, 1.0], [0, 0, -2.0]) == pytest.approx(np.pi)
    with pytest.raises(ValueError, match="non-zero"):
        unit_vector([0, 0, 0])


def test_rotating_directions_match_finite_differences_and_stay_unit() -> None:
    start = (unit_vector([1.0, 0.0, -1.0]), unit_vector([0.0, 1.0, 0.2]))
    trajectory = RotatingDirections(start, (0.2, -0.4, 0.7))
    times = np.linspace(0.0, 5.0, 11)
    h = 1e-5
    position, velocity, acceleration = trajectory.sample(times)
    plus, minus = trajectory.sample(times + h)[0], trajectory.sample(times - h)[0]
    np.testing.assert_allclose(velocity, (plus - minus) / (2 * h), atol=1e-8)
    np.testing.assert_allclose(acceleration, (plus - 2 * position + minus) / h**2, atol=1e-4)
    np.testing.assert_allclose(np.linalg.norm(position.reshape(-1, 2, 3), axis=-1), 1.0, atol=1e-12)
    np.testing.assert_allclose(position[0], np.ravel(start))
    # the angle between the directions is kept (a rigid rotation)
    dots = np.einsum("ti,ti->t", position[:, :3], position[:, 3:])
    np.testing.assert_allclose(dots, np.dot(*start), atol=1e-12)


def test_orientation_goal_config_normalises_and_rejects_zero_axes() -> None:
    assert OrientationGoalConfig("panda_hand", ((0, 0, 2.0),)).link_axes == ((0.0, 0.0, 1.0),)
    with pytest.raises(ValueError, match="link_axes"):
        OrientationGoalConfig("panda_hand", ((0, 0, 0),))
    with pytest.raises(ValueError, match="link_axes"):
        OrientationGoalConfig("panda_hand", ())


def test_planner_reaches_a_pose_and_speed_control_uses_the_position_goal() -> None:
    """A planner with a position goal on a tool point and a full orientation goal: both
    errors vanish; the layout holds 3 + 9 goal numbers."""
    tool = (0.0, 0.0, 0.1)
    goals = (OrientationGoalConfig("panda_hand"), GoalConfig(link="panda_hand", offset=tool))
    planner = FabricPlanner(PANDA, PlannerConfig.for_robot(PANDA, goals))
    assert [view.size for view in planner.parameters.goal_position] == [9, 3]
    target_rotation = np.diag([1.0, -1.0, -1.0])
    target_point = np.array([0.45, 0.25, 0.35])
    planner.parameters.goal_position[0][:] = goals[0].target(target_rotation)
    planner.parameters.goal_position[1][:] = target_point
    q, qdot, dt = np.array([1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]), np.zeros(7), 0.01
    for _ in range(800):
        qddot = planner.compute(q, qdot)
        q, qdot = q + dt * qdot + 0.5 * dt**2 * qddot, qdot + dt * qddot
    rotation = np.array(PANDA.kinematics.rotation(q, "panda_hand"))
    point = np.array(PANDA.kinematics.position(q, "panda_hand", offset=tool)).ravel()
    assert rotation_angle(rotation, target_rotation) < 1e-3
    assert np.linalg.norm(point - target_point) < 1e-3
    assert np.linalg.norm(qdot) < 1e-2


def test_axis_target_is_a_runtime_parameter() -> None:
    """One planner, two target directions written at run time: the hand's z follows each."""
    goal = OrientationGoalConfig("panda_hand", ((0.0, 0.0, 1.0),))
    planner = FabricPlanner(PANDA, PlannerConfig.for_robot(PANDA, (goal,)))
    q, qdot, dt = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785]), np.zeros(7), 0.01
    for direction in (unit_vector([1.0, 0.0, -1.0]), unit_vector([0.0, -1.0, -1.0])):
        planner.parameters.goal_position[0][:] = direction
        for _ in range(500):
            qddot = planner.compute(q, qdot)
            q, qdot = q + dt * qdot + 0.5 * dt**2 * qddot, qdot + dt * qddot
        hand_z = np.array(PANDA.kinematics.rotation(q, "panda_hand"))[:, 2]
        assert direction_angle(hand_z, direction) < 1e-3
