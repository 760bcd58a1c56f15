"""Property tests (hypothesis): scenario documents, valid or mutated, never give a
traceback; planner inputs never give a non-finite or unbounded command; the paper's
identities hold on random inputs."""

from __future__ import annotations

import copy
from typing import Any

import casadi as ca
import numpy as np
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st
from malformed_scenarios import VALID

from dynfab.fabric.energy import Lagrangian, energize
from dynfab.fabric.maps import DifferentialMap
from dynfab.fabric.spec import Spec
from dynfab.scenario.schema import ScenarioError, scenario_from_dict

#: Any YAML-like value: what a mutated document may hold in place of a field.
YAML_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-10**20, 10**20) | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=12),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
    max_leaves=12)


def _paths(document: Any, prefix: tuple = ()) -> list[tuple]:
    """Every path (keys and indices) to a value of the document."""
    paths = [prefix]
    if isinstance(document, dict):
        for key, value in document.items():
            paths += _paths(value, prefix + (key,))
    elif isinstance(document, list):
        for index, value in enumerate(document):
            paths += _paths(value, prefix + (index,))
    return paths


PATHS = _paths(VALID)[1:]


@settings(max_examples=300, deadline=2000, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(PATHS), value=YAML_VALUES)
@example(path=("robot",), value={"\n": None})  # a key with a newline: the message escapes it
def test_a_mutated_scenario_is_accepted_or_refused_with_a_scenario_error(path: tuple, value: Any) -> None:
    document = copy.deepcopy(VALID)
    target = document
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    try:
        scenario_from_dict(document)
    except ScenarioError as error:
        assert "\n" not in str(error) and str(error).split(":")[0]   # one line, naming a field


@settings(max_examples=100, deadline=None)
@given(st.data())
def test_the_planner_never_returns_a_non_finite_or_unbounded_command(data: st.DataObject) -> None:
    planner = _panda_planner()
    limits = planner.config.limits
    kin = planner.robot.kinematics
    finite = dict(allow_nan=False, allow_infinity=False)
    q = np.array([data.draw(st.floats(lo - 1.0, hi + 1.0, **finite)) for lo, hi in zip(kin.lower, kin.upper)])
    qdot = np.array(data.draw(st.lists(st.floats(-50.0, 50.0, **finite), min_size=7, max_size=7)))
    centre = data.draw(st.sampled_from(list(planner.robot.sphere_centers(q))))
    offset = np.array(data.draw(st.lists(st.floats(-1e-3, 1e-3, **finite), min_size=3, max_size=3)))
    planner.parameters.obstacle_position[0] = centre + offset
    planner.parameters.obstacle_radius[0] = data.draw(st.floats(0.01, 0.5))
    planner.parameters.goal_position[0][:] = data.draw(st.lists(st.floats(-1e3, 1e3, **finite), min_size=3,
                                                                max_size=3))
    command = planner.compute(q, qdot)
    assert np.isfinite(command).all()
    assert (np.abs(command) <= limits.acceleration * (1 + 1e-9)).all()


_PLANNER = []


def _panda_planner():
    if not _PLANNER:
        from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
        from dynfab.robots import load_robot
        _PLANNER.append(FabricPlanner(load_robot("panda"), PlannerConfig(goals=(GoalConfig(link="panda_hand"),),
                                                                         obstacle_slots=1)))
    return _PLANNER[0]


_X, _XDOT = ca.SX.sym("x", 2), ca.SX.sym("xdot", 2)
_Q, _QDOT = ca.SX.sym("q", 2), ca.SX.sym("qdot", 2)
_MAP = DifferentialMap.from_expression(ca.vertcat(ca.sin(_Q[0]) + _Q[1] ** 2, _Q[0] * ca.cos(_Q[1])), _Q, _QDOT)
_ENERGY = Lagrangian(0.5 * (1 + _X[0] ** 2) * ca.dot(_XDOT, _XDOT) + 0.2 * _XDOT[0] * _XDOT[1] * _X[1] ** 2
                     + 0.5 * ca.dot(_XDOT, _XDOT), _X, _XDOT)
_GEOMETRY = Spec(ca.SX.eye(2), ca.dot(_XDOT, _XDOT) * ca.vertcat(0.3 * _X[1], -0.2 * _X[0]), _X, _XDOT)
_ENERGY_SPEC = _ENERGY.spec()
_ENERGIZED = energize(_GEOMETRY, _ENERGY)
_POWER = ca.Function("power", [_X, _XDOT], [
    ca.dot(_XDOT, ca.mtimes(_ENERGY_SPEC.M, _ENERGIZED.acceleration()) + _ENERGY_SPEC.f), ca.dot(_XDOT, _XDOT)])
_PULLED = ca.Function("pulled", [_Q, _QDOT], [
    _ENERGY.pull(_MAP).spec().f, _ENERGY_SPEC.pull(_MAP).f, _ENERGY.pull(_MAP).spec().M, _ENERGY_SPEC.pull(_MAP).M])


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-2.0, 2.0, allow_nan=False), min_size=4, max_size=4))
def test_an_energized_geometry_conserves_its_energy(values: list[float]) -> None:
    """``Ḣ = ẋᵀ (M ẍ + f_L) = 0`` along the energized geometry, on random moving states
    (energization is undefined at rest)."""
    x, xdot = np.array(values[:2]), np.array(values[2:])
    assume(np.linalg.norm(xdot) > 1e-3)
    power, speed_squared = (float(v) for v in _POWER(x, xdot))
    assert abs(power) <= 1e-9 * (1 + speed_squared) ** 2


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-2.0, 2.0, allow_nan=False), min_size=4, max_size=4))
def test_euler_lagrange_commutes_with_the_pullback(values: list[float]) -> None:
    """The spec of the pulled Lagrangian equals the pulled spec of the Lagrangian."""
    q, qdot = np.array(values[:2]), np.array(values[2:])
    f_of_pulled, pulled_f, m_of_pulled, pulled_m = (np.array(v) for v in _PULLED(q, qdot))
    np.testing.assert_allclose(f_of_pulled, pulled_f, atol=1e-9 * (1 + np.abs(pulled_f).max()))
    np.testing.assert_allclose(m_of_pulled, pulled_m, atol=1e-9 * (1 + np.abs(pulled_m).max()))
