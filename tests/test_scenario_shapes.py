"""Box, cylinder, capsule and plane obstacles in scenario files: parsing, one-line errors,
metrics and end-to-end runs (static and moving, arm and planar robot)."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from dynfab.geometry.distance import shape_distance
from dynfab.geometry.shapes import Box, Capsule, Cylinder, Plane, quaternion_matrix
from dynfab.robots import load_robot
from dynfab.scenario.controllers import make_controller
from dynfab.scenario.metrics import shape_clearance_over_time
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import ScenarioError, scenario_from_dict, validate_for_robot

Q0 = [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]


def _panda(obstacles: list[dict[str, Any]], goal: list[float] | None = None, planner: str = "static-fabric",
           duration: float = 8.0) -> dict[str, Any]:
    return {"robot": "panda", "planner": planner, "dt": 0.01, "duration": duration, "initial_state": {"q": Q0},
            "goal": [{"type": "position", "link": "panda_hand", "position": goal or [0.5, -0.35, 0.25]}],
            "obstacles": obstacles}


def test_every_shape_parses_into_its_geometry() -> None:
    scenario = scenario_from_dict(_panda([
        {"type": "box", "position": [0.5, 0.0, 0.2], "size": [0.1, 0.2, 0.3], "orientation": [2.0, 0.0, 0.0, 0.0]},
        {"type": "cylinder", "position": [0.5, 0.0, 0.2], "radius": 0.05, "length": 0.4},
        {"type": "capsule", "radius": 0.05, "length": 0.2, "orientation": [0.0, 0.0, 0.0, 3.0],
         "trajectory": {"type": "linear", "start": [0.0, 1.0, 0.5], "velocity": [0.1, 0.0, 0.0]}},
        {"type": "plane", "point": [0.0, 0.0, -0.05], "normal": [0.0, 2.0, 0.0]},
    ]))
    box, cylinder, capsule, plane = scenario.obstacles
    assert box.shape == Box((0.1, 0.2, 0.3)) and box.orientation == (1.0, 0.0, 0.0, 0.0)
    assert box.position == (0.5, 0.0, 0.2) and box.radius == 0.0
    assert cylinder.shape == Cylinder(0.05, 0.4) and cylinder.orientation == (1.0, 0.0, 0.0, 0.0)
    assert capsule.shape == Capsule(0.05, 0.2) and capsule.orientation == (0.0, 0.0, 0.0, 1.0)
    assert capsule.position is None and capsule.trajectory["type"] == "linear"
    assert plane.shape == Plane() and plane.position == (0.0, 0.0, -0.05) and plane.normal == (0.0, 1.0, 0.0)
    np.testing.assert_allclose(quaternion_matrix(plane.orientation)[:, 2], [0.0, 1.0, 0.0], atol=1e-12)


_BOX = {"type": "box", "position": [0.5, 0.0, 0.2], "size": [0.1, 0.2, 0.3]}
_PLANE = {"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}


@pytest.mark.parametrize(("obstacle", "message"), [
    ({**_BOX, "size": [0.1, 0.0, 0.3]}, "obstacles[0].size[1]: must be positive, got 0"),
    ({**_BOX, "size": [0.1, math.nan, 0.3]}, "obstacles[0].size[1]: expected a finite number"),
    ({**_BOX, "size": [0.1, 0.2]}, "obstacles[0].size: expected 3 numbers, got 2"),
    ({**_BOX, "orientation": [0.0, 0.0, 0.0, 0.0]}, "obstacles[0].orientation: expected a non-zero quaternion"),
    ({**_BOX, "orientation": [1.0, 0.0, 0.0]}, "obstacles[0].orientation: expected 4 numbers, got 3"),
    ({**_BOX, "radius": 0.1}, "obstacles[0].radius: unknown key (allowed: type, size, orientation, position, "
                              "trajectory)"),
    ({"type": "box", "position": [0.5, 0.0, 0.2]}, "obstacles[0].size: missing required key"),
    ({"type": "cylinder", "position": [0.5, 0.0, 0.2], "radius": 0.1}, "obstacles[0].length: missing required key"),
    ({"type": "capsule", "position": [0.5, 0.0, 0.2], "radius": -0.1, "length": 0.2},
     "obstacles[0].radius: must be positive"),
    ({"type": "sphere", "position": [0.5, 0.0, 0.2], "radius": 0.1, "orientation": [1, 0, 0, 0]},
     "obstacles[0].orientation: unknown key"),
    ({**_PLANE, "normal": [0.0, 0.0, 0.0]}, "obstacles[0].normal: expected a non-zero vector"),
    ({"type": "plane", "normal": [0.0, 0.0, 1.0]}, "obstacles[0]: expected exactly one of 'point' (static) or "
                                                   "'trajectory' (moving)"),
    ({**_PLANE, "position": [0.0, 0.0, 0.0]}, "obstacles[0].position: unknown key"),
    ({"size": [0.1, 0.1, 0.1]}, "obstacles[0].type: missing required key"),
])
def test_bad_shapes_name_the_field(obstacle: dict[str, Any], message: str) -> None:
    with pytest.raises(ScenarioError) as error:
        scenario_from_dict(_panda([obstacle]))
    assert str(error.value).startswith(message), str(error.value)
    assert "\n" not in str(error.value)


def test_planar_robot_rejects_a_floor_and_the_mpc_rejects_shapes() -> None:
    data = _panda([_PLANE])
    data.update(robot="point", initial_state={"q": [0.0, 0.0]})
    data["goal"][0].update(link="point", position=[1.0, 0.0])
    with pytest.raises(ScenarioError, match=r"^obstacles\[0\]\.normal: a planar robot moves in the xy-plane"):
        validate_for_robot(scenario_from_dict(data), load_robot("point"))
    scenario = validate_for_robot(scenario_from_dict(_panda([_BOX], planner="mpc")), load_robot("panda"))
    robot = load_robot("panda")
    with pytest.raises(ScenarioError, match=r"^obstacles\[0\]\.type: the mpc planner avoids spheres only"):
        make_controller(scenario, robot, scenario_references(scenario, robot))


def test_shape_clearance_over_time_is_the_exact_signed_distance() -> None:
    spheres = np.array([[[0.5, 0.0, 0.0], [0.0, 0.0, 1.0]], [[0.25, 0.0, 0.0], [0.0, 0.0, 1.0]]])  # (T=2, k=2, 3)
    radii = np.array([0.05, 0.1])
    box = Box((0.2, 0.2, 0.2))
    quarter_turn_about_z = (math.cos(math.pi / 8), 0.0, 0.0, math.sin(math.pi / 8))  # 45 degrees
    centers = np.zeros((2, 1, 3))
    clearance = shape_clearance_over_time(spheres, radii, [box], [quarter_turn_about_z], centers)
    half_diagonal = 0.1 * math.sqrt(2)
    np.testing.assert_allclose(clearance, [0.5 - half_diagonal - 0.05, 0.25 - half_diagonal - 0.05])
    floor = shape_clearance_over_time(spheres, radii, [Plane()], [(1.0, 0.0, 0.0, 0.0)], centers)
    np.testing.assert_allclose(floor, [-0.05, -0.05])
    planar = shape_clearance_over_time(spheres, radii, [box], [quarter_turn_about_z], centers, planar=True)
    np.testing.assert_allclose(planar, [-0.1 - 0.1, -0.1 - 0.1])  # the second sphere is at the box centre
    assert np.isinf(shape_clearance_over_time(spheres[:, :0], radii[:0], [box], [(1, 0, 0, 0)], centers)).all()


def test_panda_stays_above_a_table_it_is_told_to_reach_through() -> None:
    table = {"type": "plane", "point": [0.0, 0.0, -0.04], "normal": [0.0, 0.0, 1.0]}
    result = run_scenario(scenario_from_dict(_panda([table], goal=[0.5, -0.2, -0.2])))
    assert not result.metrics.goal_reached
    assert not result.metrics.collision and result.metrics.clearance > 0.0
    lowest_hand = result.goal_positions[:, 2].min()
    assert -0.04 < lowest_hand < 0.1, "the hand comes down to the table and stops above it"


def test_point_robot_goes_around_an_upright_box_and_a_cylinder_in_the_plane() -> None:
    data = {"robot": "point", "planner": "static-fabric", "dt": 0.01, "duration": 15.0,
            "initial_state": {"q": [-1.5, 0.05]},
            "goal": [{"type": "position", "link": "point", "position": [1.5, 0.0]}],
            "obstacles": [{"type": "box", "position": [-0.3, 0.0, 2.0], "size": [0.4, 0.6, 1.0],
                           "orientation": [math.cos(0.3), 0.0, 0.0, math.sin(0.3)]},
                          {"type": "cylinder", "position": [0.7, 0.1], "radius": 0.25, "length": 1.0}]}
    result = run_scenario(scenario_from_dict(data))
    assert result.metrics.success and result.metrics.clearance > 0.0
    straight = copy.deepcopy(data)
    del straight["obstacles"]
    through = run_scenario(scenario_from_dict(straight))
    assert result.metrics.path_length > through.metrics.path_length + 0.05


@pytest.mark.parametrize("planner", ["static-fabric", "dynamic-fabric"])
def test_a_box_moving_across_the_arm(planner: str) -> None:
    box = {"type": "box", "size": [0.2, 0.2, 0.2],
           "trajectory": {"type": "linear", "start": [0.55, -1.5, 0.45], "velocity": [0.0, 0.15, 0.0]}}
    data = {**_panda([box], goal=[0.5, 0.0, 0.45], planner=planner, duration=16.0), "guidance": False}  # the fabric alone
    result = run_scenario(scenario_from_dict(data))
    if planner == "dynamic-fabric":
        assert result.metrics.success and result.metrics.clearance > 0.0
    else:  # a static fabric sees the box only where it is: it hits the arm at rest (the paper's point)
        assert result.metrics.collision


def test_shape_outlines_trace_the_shapes(tmp_path) -> None:  # noqa: ANN001
    from dynfab.cli import main
    from dynfab.viz.shape_outlines import shape_outline

    edges = shape_outline(Box((0.1, 0.2, 0.3)), (math.cos(0.2), 0.0, math.sin(0.2), 0.0), [1.0, 2.0, 3.0])
    assert len(edges) == 12
    lengths = sorted(round(float(np.linalg.norm(edge[1] - edge[0])), 9) for edge in edges)
    assert lengths == [0.1] * 4 + [0.2] * 4 + [0.3] * 4
    np.testing.assert_allclose(np.mean([edge.mean(axis=0) for edge in edges], axis=0), [1.0, 2.0, 3.0])
    wall = shape_outline(Plane(), (math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0), [0.5, 0.0, 0.0])
    np.testing.assert_allclose(wall[0][:, 0], 0.5, atol=1e-12)  # normal along +x: the square lies in x = 0.5
    for shape in (Capsule(0.1, 0.4), Cylinder(0.1, 0.4), Box((0.1, 0.2, 0.3))):
        for line in shape_outline(shape, (1.0, 0.0, 0.0, 0.0), [0.0, 0.0, 0.0]):
            np.testing.assert_allclose(shape_distance(shape, line), 0.0, atol=1e-12)  # on the surface
    plot = tmp_path / "table.png"
    example = Path(__file__).resolve().parent.parent / "examples" / "panda_table_box.yaml"
    assert main(["run", str(example), "--plot", str(plot)]) == 0
    assert plot.stat().st_size > 10_000
