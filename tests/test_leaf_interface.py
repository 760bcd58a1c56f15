"""The leaf interface: a leaf kind defined outside the planner (here, in this file, and
``WorkspaceBounds`` in its own module) is built into the fabric, energized with the others,
and fed its own runtime parameters."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pytest

import dynfab
from dynfab.fabric.c_export import input_fields
from dynfab.fabric.energy import WeightedGeometry
from dynfab.fabric.leaf import LeafContext
from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.leaves.workspace import WorkspaceBounds
from dynfab.fabric.maps import linear_map


@dataclass(frozen=True)
class JointCeiling:
    """A leaf written here, as a user would: joint 0 kept below a runtime value."""

    name: str = "ceiling"
    barrier: Barrier = field(default_factory=lambda: Barrier(geometry_gain=5.0, energy_gain=0.5, horizon=0.2))

    def parameter_sizes(self) -> Mapping[str, int]:
        return {"value": 1}

    def geometry(self, context: LeafContext) -> WeightedGeometry:
        n = context.q.shape[0]
        row = np.zeros((1, n))
        row[0, 0] = -1.0
        distance = linear_map(row, -context.parameters["value"], context.q, context.qdot)  # value − q₀
        return self.barrier.weighted_geometry().pull(distance)


@pytest.fixture(scope="module")
def point() -> dynfab.Robot:
    return dynfab.load_robot("point")


def _run(planner: dynfab.FabricPlanner, steps: int = 1500) -> np.ndarray:
    q, qdot = np.zeros(2), np.zeros(2)
    path = []
    for _ in range(steps):
        q, qdot = planner.step(q, qdot)
        path.append(q)
    return np.array(path)


def test_workspace_bounds_hold_the_point_inside_once_written(point: dynfab.Robot) -> None:
    planner = dynfab.FabricPlanner(point, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="point"),),
                                                               leaves=(WorkspaceBounds(link="point"),)))
    planner.parameters.goal_position[0] = [1.5, 0.5]
    free = _run(planner)
    np.testing.assert_allclose(free[-1], [1.5, 0.5], atol=1e-3)  # unwritten bounds: no bound at all
    bounds = planner.parameters.leaves["workspace"]
    bounds["lower"] = [-1.0, -1.0, 0.0]
    bounds["upper"] = [1.0, 1.0, 0.0]  # z unbounded (upper <= lower)
    held = _run(planner)
    assert held[:, 0].max() < 1.0 and 0.9 < held[-1, 0]  # at the face, not through it
    assert abs(held[-1, 1] - 0.5) < 1e-2  # the free axis still reaches


def test_a_leaf_defined_outside_the_package_is_built_and_fed(point: dynfab.Robot) -> None:
    planner = dynfab.FabricPlanner(point, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="point"),),
                                                               leaves=(JointCeiling(),)))
    planner.parameters.goal_position[0] = [1.5, 0.0]
    planner.parameters.leaves["ceiling"]["value"] = 0.6
    path = _run(planner)
    assert path[:, 0].max() < 0.6 and path[-1, 0] > 0.5


def test_leaf_parameters_are_checked_and_named(point: dynfab.Robot) -> None:
    planner = dynfab.FabricPlanner(point, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="point"),),
                                                               leaves=(WorkspaceBounds(link="point", name="cell"),)))
    cell = planner.parameters.leaves["cell"]
    cell["upper"] = [1.0, 2.0, 3.0]
    np.testing.assert_array_equal(cell["upper"], [1.0, 2.0, 3.0])
    with pytest.raises(dynfab.ParameterError, match=r"leaves\['cell'\]\['upper'\] must have 3 values, got 2"):
        cell["upper"] = [1.0, 2.0]
    with pytest.raises(dynfab.ParameterError, match=r"leaves\['cell'\]\['uper'\]: no such parameter"):
        cell["uper"] = [1.0, 2.0, 3.0]
    with pytest.raises(dynfab.ParameterError, match=r"leaves\['workspace'\]: the planner has no leaf"):
        planner.parameters.leaves["workspace"]
    names = [f.name for f in input_fields(planner)]
    assert "leaf_cell_lower" in names and "leaf_cell_upper" in names  # a C export names them too


def test_leaves_are_validated_when_configured() -> None:
    goal = (dynfab.GoalConfig(link="point"),)
    with pytest.raises(ValueError, match="two leaves are named 'workspace'"):
        dynfab.PlannerConfig(goals=goal, leaves=(WorkspaceBounds("a"), WorkspaceBounds("b")))
    with pytest.raises(TypeError, match=r"leaves\[0\]: Barrier is not a leaf"):
        dynfab.PlannerConfig(goals=goal, leaves=(Barrier(),))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"leaves\[0\]\.name must be an identifier"):
        dynfab.PlannerConfig(goals=goal, leaves=(WorkspaceBounds("a", name="my cell"),))


def test_a_leaf_outside_joint_space_is_refused(point: dynfab.Robot) -> None:
    @dataclass(frozen=True)
    class Unpulled(JointCeiling):
        def geometry(self, context: LeafContext) -> WeightedGeometry:
            return self.barrier.weighted_geometry()  # still on its 1-D task variable

    with pytest.raises(ValueError, match=r"leaf 'ceiling': geometry\(context\) must be in joint space \(M 2x2"):
        dynfab.FabricPlanner(point, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="point"),),
                                                         leaves=(Unpulled(),)))
