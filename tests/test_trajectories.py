"""Reference trajectories: closed forms, finite-difference derivatives, the safe expression
parser and the field paths of scenario-mapping errors."""

from __future__ import annotations

import copy
import dataclasses
import math
import pickle
from collections.abc import Callable
from types import MappingProxyType

import casadi as ca
import numpy as np
import pytest

from dynfab.motion.expression import MAX_LENGTH, ExpressionError, parse_expression
from dynfab.motion.spline_trajectory import SplineTrajectory
from dynfab.motion.trajectories import (
    CircleTrajectory,
    ExpressionTrajectory,
    LinearTrajectory,
    PolynomialTrajectory,
    StaticPoint,
    Trajectory,
    TrajectoryError,
)
from dynfab.motion.trajectory_mapping import trajectory_from_mapping

RNG = np.random.default_rng(7)
STEP = 1e-5  # [s] central-difference step

WAYPOINTS = ((0.0, 0.0, 0.2), (0.5, 0.1, 0.4), (0.6, 0.6, 0.4), (0.1, 0.8, 0.9))
SPLINE_DURATION = 6.0

TRAJECTORIES: dict[str, Trajectory] = {
    "static": StaticPoint((0.3, -0.2, 0.5)),
    "linear-2d": LinearTrajectory((1.0, -2.0), (0.3, 0.1)),
    "linear-3d": LinearTrajectory([-1.0, -0.4, 0.7], [0.1, 0.0, -0.05]),
    "circle-2d": CircleTrajectory((0.5, -0.5), 0.3, 1.3, phase=0.4),
    "circle-3d": CircleTrajectory((0.2, 0.1, 0.6), 0.25, -0.8, normal=(1.0, -2.0, 0.5), phase=2.0),
    "polynomial": PolynomialTrajectory(((0.1, 0.2, -0.3, 0.04), (1.0,), (0.0, 0.0, 0.5))),
    "expression": ExpressionTrajectory(
        ("0.5 + 0.1*sin(0.5*t)", "0.2*t**2 - exp(-t)", "atan2(sin(t), 2 + cos(t))")
    ),
    "expression-sparse": ExpressionTrajectory(("1 + 2*t", "0.5", "t**2")),  # structural zeros
    "spline": SplineTrajectory(WAYPOINTS, SPLINE_DURATION),
}


def chord_times(waypoints: tuple[tuple[float, ...], ...], duration: float) -> np.ndarray:
    """Times at which a chord-length-parameterised path reaches each waypoint [s]."""
    lengths = np.linalg.norm(np.diff(np.array(waypoints), axis=0), axis=1)
    return duration * np.concatenate([[0.0], np.cumsum(lengths)]) / lengths.sum()


def interior_times(trajectory: Trajectory, count: int = 20) -> np.ndarray:
    """Random times [s]; for the spline inside (0, T) and away from its knots."""
    if isinstance(trajectory, SplineTrajectory):
        knots = chord_times(WAYPOINTS, SPLINE_DURATION)
        times = RNG.uniform(0.05, SPLINE_DURATION - 0.05, size=10 * count)
        far = np.min(np.abs(times[:, None] - knots[None, :]), axis=1) > 1e-3
        return times[far][:count]
    return RNG.uniform(-3.0, 10.0, size=count)


@pytest.mark.parametrize("name", TRAJECTORIES)
def test_velocity_and_acceleration_match_central_differences(name: str) -> None:
    trajectory = TRAJECTORIES[name]
    for t in interior_times(trajectory):
        point = trajectory.evaluate(t)
        after, before = trajectory.evaluate(t + STEP), trajectory.evaluate(t - STEP)
        velocity = (after.position - before.position) / (2 * STEP)
        acceleration = (after.velocity - before.velocity) / (2 * STEP)
        np.testing.assert_allclose(point.velocity, velocity, rtol=1e-6, atol=1e-7)
        np.testing.assert_allclose(point.acceleration, acceleration, rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("name", TRAJECTORIES)
def test_sample_equals_repeated_evaluate(name: str) -> None:
    trajectory = TRAJECTORIES[name]
    times = np.concatenate([interior_times(trajectory, 7), [-1.0, 0.0, SPLINE_DURATION, 20.0]])
    positions, velocities, accelerations = trajectory.sample(times)
    assert positions.shape == velocities.shape == accelerations.shape == (times.size, trajectory.dimension)
    for i, t in enumerate(times):
        point = trajectory.evaluate(t)
        np.testing.assert_allclose(positions[i], point.position, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(velocities[i], point.velocity, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(accelerations[i], point.acceleration, rtol=1e-12, atol=1e-12)
    empty = trajectory.sample(np.zeros(0))
    assert all(array.shape == (0, trajectory.dimension) for array in empty)


def test_sample_rejects_non_vector_times() -> None:
    with pytest.raises(ValueError, match="1-D"):
        TRAJECTORIES["linear-3d"].sample(np.zeros((2, 2)))


def test_static_point_rests_in_any_dimension() -> None:
    for position in ([0.3, -0.2, 0.5], [0.7], [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]):
        positions, velocities, accelerations = StaticPoint(position).sample(RNG.uniform(-5, 5, 9))
        np.testing.assert_array_equal(positions, np.tile(position, (9, 1)))
        assert not velocities.any() and not accelerations.any()
    with pytest.raises(TrajectoryError, match="position: expected numbers, got an empty list"):
        StaticPoint(())


def test_linear_closed_form() -> None:
    times = RNG.uniform(-3, 10, 25)
    positions, velocities, accelerations = TRAJECTORIES["linear-3d"].sample(times)
    start, velocity = np.array([-1.0, -0.4, 0.7]), np.array([0.1, 0.0, -0.05])
    np.testing.assert_allclose(positions, start + times[:, None] * velocity, rtol=1e-14, atol=1e-14)
    np.testing.assert_array_equal(velocities, np.tile(velocity, (25, 1)))
    assert not accelerations.any()


def test_circle_closed_form_about_z() -> None:
    center, radius, omega, phase = np.array([0.4, -0.1, 0.7]), 0.2, 0.9, 0.3
    circle = CircleTrajectory(tuple(center), radius, omega, phase=phase)
    times = RNG.uniform(-3, 10, 25)
    angle = omega * times + phase
    expected = center + radius * np.stack([np.cos(angle), np.sin(angle), np.zeros_like(angle)], axis=1)
    np.testing.assert_allclose(circle.sample(times)[0], expected, rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("name", ["circle-2d", "circle-3d"])
def test_circle_stays_on_radius_in_plane_and_turns_about_normal(name: str) -> None:
    circle = TRAJECTORIES[name]
    assert isinstance(circle, CircleTrajectory)
    times = RNG.uniform(-3, 10, 50)
    positions, velocities, accelerations = circle.sample(times)
    offsets = positions - np.array(circle.center)
    np.testing.assert_allclose(np.linalg.norm(offsets, axis=1), circle.radius, rtol=1e-13)
    speed = circle.radius * abs(circle.angular_velocity)
    np.testing.assert_allclose(np.linalg.norm(velocities, axis=1), speed, rtol=1e-13)
    np.testing.assert_allclose(accelerations, -(circle.angular_velocity**2) * offsets, rtol=1e-12, atol=1e-14)
    if circle.dimension == 3:
        normal = np.array(circle.normal) / np.linalg.norm(circle.normal)
        np.testing.assert_allclose(offsets @ normal, 0.0, atol=1e-14)
        spin = np.cross(offsets, velocities) @ normal
    else:
        spin = offsets[:, 0] * velocities[:, 1] - offsets[:, 1] * velocities[:, 0]
    np.testing.assert_allclose(spin, circle.radius**2 * circle.angular_velocity, rtol=1e-12)


def test_planar_circle_ignores_normal() -> None:
    times = RNG.uniform(0, 5, 10)
    tilted = CircleTrajectory((0.5, -0.5), 0.3, 1.3, normal=(1.0, 1.0, 0.0), phase=0.4)
    np.testing.assert_array_equal(tilted.sample(times)[0], TRAJECTORIES["circle-2d"].sample(times)[0])


def test_polynomial_closed_form() -> None:
    coefficients = ((0.1, 0.2, -0.3, 0.04), (1.0,), (0.0, 0.0, 0.5))
    times = RNG.uniform(-3, 10, 25)
    positions = TRAJECTORIES["polynomial"].sample(times)[0]
    for axis, row in enumerate(coefficients):
        expected = np.polynomial.polynomial.polyval(times, row)
        np.testing.assert_allclose(positions[:, axis], expected, rtol=1e-13)


def test_expression_closed_form() -> None:
    times = RNG.uniform(-3, 10, 25)
    positions = TRAJECTORIES["expression"].sample(times)[0]
    expected = np.stack(
        [0.5 + 0.1 * np.sin(0.5 * times), 0.2 * times**2 - np.exp(-times),
         np.arctan2(np.sin(times), 2 + np.cos(times))],
        axis=1,
    )
    np.testing.assert_allclose(positions, expected, rtol=1e-13, atol=1e-15)


def test_expression_trajectory_survives_copy_and_pickle() -> None:
    original = TRAJECTORIES["expression"]
    for clone in (copy.deepcopy(original), pickle.loads(pickle.dumps(original))):
        assert clone == original
        np.testing.assert_array_equal(clone.evaluate(1.3).acceleration, original.evaluate(1.3).acceleration)


def test_spline_passes_through_waypoints_at_increasing_times() -> None:
    spline = TRAJECTORIES["spline"]
    times = chord_times(WAYPOINTS, SPLINE_DURATION)
    assert np.all(np.diff(times) > 0) and times[-1] == pytest.approx(SPLINE_DURATION)
    np.testing.assert_allclose(spline.sample(times)[0], np.array(WAYPOINTS), atol=1e-12)


def test_spline_starts_and_ends_at_rest_and_rests_afterwards() -> None:
    spline = TRAJECTORIES["spline"]
    for t in (0.0, 1e-9, SPLINE_DURATION - 1e-9, SPLINE_DURATION):
        np.testing.assert_allclose(spline.evaluate(t).velocity, 0.0, atol=1e-7)
    later = np.linspace(SPLINE_DURATION, SPLINE_DURATION + 50.0, 11)
    positions, velocities, accelerations = spline.sample(later)
    np.testing.assert_allclose(positions, np.tile(WAYPOINTS[-1], (11, 1)), atol=1e-12)
    assert not velocities.any() and not accelerations.any()
    earlier = spline.sample(np.array([-5.0, -1e-3]))
    np.testing.assert_allclose(earlier[0], np.tile(WAYPOINTS[0], (2, 1)), atol=1e-12)
    assert not earlier[1].any() and not earlier[2].any()


def test_spline_is_c2_at_its_knots() -> None:
    spline = TRAJECTORIES["spline"]
    delta = 1e-7
    for knot in chord_times(WAYPOINTS, SPLINE_DURATION)[1:-1]:
        left, right = spline.evaluate(knot - delta), spline.evaluate(knot + delta)
        np.testing.assert_allclose(left.velocity, right.velocity, atol=1e-6)
        np.testing.assert_allclose(left.acceleration, right.acceleration, atol=1e-5)
        assert np.linalg.norm(left.acceleration) > 1e-3  # a real, non-trivial comparison


def test_spline_speed_is_roughly_uniform() -> None:
    """Mean speed along the curve on each segment is close to total chord length / T."""
    waypoints = ((0.0, 0.0), (1.0, 0.0), (1.1, 0.0), (1.1, 3.0))  # segments 1, 0.1, 3 [m]
    spline = SplineTrajectory(waypoints, 4.0)
    knots = chord_times(waypoints, 4.0)
    for start, end in zip(knots[:-1], knots[1:]):
        times = np.linspace(start, end, 2001)
        speeds = np.linalg.norm(spline.sample(times)[1], axis=1)
        mean_speed = np.trapezoid(speeds, times) / (end - start)
        assert mean_speed == pytest.approx(4.1 / 4.0, rel=0.15)


def test_trajectories_are_frozen_values() -> None:
    assert LinearTrajectory([0, 1], [2, 3]) == LinearTrajectory((0.0, 1.0), (2.0, 3.0))
    assert hash(SplineTrajectory(WAYPOINTS, 2)) == hash(SplineTrajectory([list(p) for p in WAYPOINTS], 2.0))
    with pytest.raises(dataclasses.FrozenInstanceError):
        TRAJECTORIES["linear-2d"].start = (0.0, 0.0)  # type: ignore[misc]


# --- safe expressions ---------------------------------------------------------------

GOOD_EXPRESSIONS: list[tuple[str, Callable[[float], float]]] = [
    ("0.5 + 0.1*sin(0.5*t)", lambda t: 0.5 + 0.1 * math.sin(0.5 * t)),
    ("-t**2", lambda t: -(t**2)),
    ("2**-t", lambda t: 2**-t),
    ("+t / 4 - 1e-3", lambda t: t / 4 - 1e-3),
    ("pi * e * t", lambda t: math.pi * math.e * t),
    ("cos(t) + tan(t) + exp(t) + log(t) + sqrt(t)",
     lambda t: math.cos(t) + math.tan(t) + math.exp(t) + math.log(t) + math.sqrt(t)),
    ("asin(t/3) + acos(t/3) + atan(t) + atan2(1, t)",
     lambda t: math.asin(t / 3) + math.acos(t / 3) + math.atan(t) + math.atan2(1, t)),
    ("sinh(t) * cosh(t) - tanh(t)", lambda t: math.sinh(t) * math.cosh(t) - math.tanh(t)),
    ("abs(1 - t) + min(t, 1) + max(t, 2)", lambda t: abs(1 - t) + min(t, 1) + max(t, 2)),
    ("(t\n + 1) * 2", lambda t: (t + 1) * 2),
    ("3", lambda t: 3.0),
]


@pytest.mark.parametrize(("text", "reference"), GOOD_EXPRESSIONS)
def test_parser_accepts_whitelisted_arithmetic(text: str, reference: Callable[[float], float]) -> None:
    t = ca.SX.sym("t")
    function = ca.Function("f", [t], [parse_expression(text, t)])
    for value in (0.3, 1.7):
        assert float(function(value)) == pytest.approx(reference(value), rel=1e-14, abs=1e-14)


def test_parser_result_differentiates_by_casadi() -> None:
    t = ca.SX.sym("t")
    derivative = ca.Function("d", [t], [ca.jacobian(parse_expression("t**3 + sin(2*t)", t), t)])
    assert float(derivative(0.7)) == pytest.approx(3 * 0.7**2 + 2 * math.cos(1.4), rel=1e-14)


BAD_EXPRESSIONS: list[tuple[str, str]] = [
    ("__import__('os')", "unknown function: '__import__'"),
    ("__import__('os').system('true')", "only named functions can be called"),
    ("().__class__", "attribute access not allowed: '().__class__'"),
    ("t.real", "attribute access not allowed: 't.real'"),
    ("open('x')", "unknown function: 'open'"),
    ("lambda: 1", "lambdas not allowed: 'lambda: 1'"),
    ("[t for t in x]", "comprehensions not allowed"),
    ("'abc'", "strings not allowed: \"'abc'\""),
    ("t if t else 1", "conditional expressions not allowed"),
    ("sin(t, 2)", "sin takes 1 argument, got 2"),
    ("atan2(t)", "atan2 takes 2 arguments, got 1"),
    ("foo(t)", "unknown function: 'foo'"),
    ("t" + " + t" * (MAX_LENGTH // 4), "expression too long"),
    ("t == 1", "comparisons not allowed: 't == 1'"),
    ("x + 1", "unknown name: 'x'"),
    ("sin", "unknown name: 'sin' (functions must be called)"),
    ("sin(x=t)", "keyword arguments not allowed"),
    ("t[0]", "subscripts not allowed"),
    ("t // 2", "operator not allowed: 't // 2'"),
    ("not t", "operator not allowed: 'not t'"),
    ("t and 1", "boolean operators not allowed"),
    ("True", "bool literals not allowed"),
    ("2j", "complex literals not allowed"),
    ("1e999", "number too large: '1e999'"),
    ("(t, t)", "tuples not allowed"),
    ("t +", "invalid syntax"),
    ("", "empty expression"),
    ("-" * 150 + "t", "nested deeper than"),
    ("t\x00", "invalid syntax"),
]


@pytest.mark.parametrize(("text", "fragment"), BAD_EXPRESSIONS)
def test_parser_rejects_everything_outside_the_whitelist(text: str, fragment: str) -> None:
    with pytest.raises(ExpressionError) as raised:
        parse_expression(text, ca.SX.sym("t"))
    message = str(raised.value)
    assert fragment in message
    assert "\n" not in message


def test_parser_rejects_non_text() -> None:
    with pytest.raises(ExpressionError, match="expected text, got int"):
        parse_expression(3, ca.SX.sym("t"))  # type: ignore[arg-type]


# --- scenario mappings ----------------------------------------------------------------

PREFIX = "obstacles[1].trajectory"


def test_mapping_builds_every_type() -> None:
    mappings = {
        "linear": {"type": "linear", "start": [0, 0, 1], "velocity": [1, 0, 0]},
        "circle": {"type": "circle", "center": [0, 0, 1], "radius": 0.5, "angular_velocity": 1,
                   "normal": [0, 1, 0], "phase": 0.2},
        "polynomial": {"type": "polynomial", "coefficients": [[1, 2], [3]]},
        "expression": {"type": "expression", "x": ["t", "2*t", "1"]},
        "spline": {"type": "spline", "waypoints": [[0, 0], [1, 1]], "duration": 2},
    }
    built = {name: trajectory_from_mapping(data, PREFIX) for name, data in mappings.items()}
    assert built["linear"] == LinearTrajectory((0, 0, 1), (1, 0, 0))
    assert built["circle"] == CircleTrajectory((0, 0, 1), 0.5, 1.0, (0, 1, 0), 0.2)
    assert built["polynomial"] == PolynomialTrajectory(((1, 2), (3,)))
    assert built["expression"] == ExpressionTrajectory(("t", "2*t", "1"))
    assert built["spline"] == SplineTrajectory(((0, 0), (1, 1)), 2.0)
    np.testing.assert_allclose(built["expression"].evaluate(1.5).position, [1.5, 3.0, 1.0])


def test_mapping_accepts_read_only_yaml_values() -> None:
    waypoints = ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0))
    frozen = MappingProxyType({"type": "spline", "waypoints": waypoints, "duration": 1})
    trajectory = trajectory_from_mapping(frozen, PREFIX)
    np.testing.assert_allclose(trajectory.evaluate(1.0).position, [1.0, 0.0, 0.0])


MAPPING_ERRORS: list[tuple[object, str]] = [
    ({"type": "linear", "start": [0, 0, 0], "velocity": [1, 0]}, "velocity: expected 3 numbers, got 2"),
    ({"type": "linear", "start": [0, 0], "velocity": [0, 0], "speed": 1}, "speed: unknown key"),
    ({"type": "linear", "start": [0, 0]}, "velocity: missing required key"),
    ({"start": [0, 0], "velocity": [0, 0]}, "type: missing required key"),
    ({"type": "warp"}, "type: expected one of linear, circle, polynomial, expression, spline, rrt"),
    ({"type": ["linear"]}, "type: expected one of"),
    ({"type": "rrt", "goal": [1, 1], "duration": 5}, "type: rrt must be resolved by the caller"),
    ({"type": "linear", "start": [0, float("inf")], "velocity": [0, 0]},
     "start[1]: expected a finite number"),
    ({"type": "linear", "start": ["1e-3", 0], "velocity": [0, 0]}, "start[0]: expected a number, got str"),
    ({"type": "linear", "start": [True, 0], "velocity": [0, 0]}, "start[0]: expected a number, got boolean"),
    ({"type": "linear", "start": [0, 0, 0, 0], "velocity": [0] * 4}, "start: expected 2 or 3 numbers, got 4"),
    ({"type": "linear", "start": "origin", "velocity": [0, 0]}, "start: expected a list, got str"),
    ({"type": "circle", "center": [0, 0], "radius": -1, "angular_velocity": 1}, "radius: must be positive"),
    ({"type": "circle", "center": [0, 0, 0], "radius": 1, "angular_velocity": 1, "normal": [0, 0, 0]},
     "normal: must not be the zero vector"),
    ({"type": "circle", "center": [0, 0], "radius": 1, "angular_velocity": 1, "normal": [0, 1]},
     "normal: expected 3 numbers, got 2"),
    ({"type": "circle", "center": [0, 0], "radius": 1, "angular_velocity": None},
     "angular_velocity: expected a number, got null"),
    ({"type": "polynomial", "coefficients": [[1], [2], [3], [4]]}, "coefficients: expected 2 or 3 lists"),
    ({"type": "polynomial", "coefficients": [[1], []]},
     "coefficients[1]: expected numbers, got an empty list"),
    ({"type": "polynomial", "coefficients": [[1], [0, "t"]]}, "coefficients[1][1]: expected a number"),
    ({"type": "expression", "x": ["t", "foo(t)"]}, "x[1]: unknown function: 'foo'"),
    ({"type": "expression", "x": ["t", "t.real"]}, "x[1]: attribute access not allowed"),
    ({"type": "expression", "x": "t"}, "x: expected a list, got str"),
    ({"type": "expression", "x": ["t"]}, "x: expected 2 or 3 expressions (one per axis), got 1"),
    ({"type": "expression", "x": ["t", 2]}, "x[1]: expected text, got int"),
    ({"type": "expression", "x": ["log(t)", "t"]}, "x[0]: value or derivatives not finite at t = 0"),
    ({"type": "expression", "x": ["t", "sqrt(t)"]}, "x[1]: value or derivatives not finite at t = 0"),
    ({"type": "spline", "waypoints": [[0, 0]], "duration": 1},
     "waypoints: expected at least 2 waypoints, got 1"),
    ({"type": "spline", "waypoints": [[0, 0], [0, 0, 1]], "duration": 1},
     "waypoints[1]: expected 2 numbers, got 3"),
    ({"type": "spline", "waypoints": [[0, 0], [1, 1], [1, 1]], "duration": 1},
     "waypoints[2]: equals waypoints[1]"),
    ({"type": "spline", "waypoints": [[0, 0], [1, 1]], "duration": 0}, "duration: must be positive, got 0"),
    ([1, 2], "expected a mapping, got a list of 2"),
]


@pytest.mark.parametrize(("data", "expected"), MAPPING_ERRORS)
def test_mapping_errors_name_the_field(data: object, expected: str) -> None:
    with pytest.raises(TrajectoryError) as raised:
        trajectory_from_mapping(data, PREFIX)  # type: ignore[arg-type]
    message = str(raised.value)
    assert message.startswith(PREFIX + (": " if isinstance(data, list) else "."))
    assert expected in message
    assert "\n" not in message
    assert isinstance(raised.value, ValueError)


def test_mapping_error_path_without_prefix() -> None:
    with pytest.raises(TrajectoryError) as raised:
        trajectory_from_mapping({"type": "linear", "start": [0, 0, 0], "velocity": [1, 0]}, "")
    assert str(raised.value) == "velocity: expected 3 numbers, got 2"
    assert raised.value.field == "velocity"
