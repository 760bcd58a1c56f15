"""The ``points`` variant of the MotionBenchMaker benchmark: the object-removed scene as a
noisy point cloud on the true surfaces, the run checked against the true shapes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.point_clouds import NOISE, SPACING, surface_points
from dynfab.benchmarks.mbm.problems import load_problems
from dynfab.benchmarks.mbm.variants import prepare_case
from dynfab.geometry.distance import placed_distance
from dynfab.geometry.shapes import Placement
from dynfab.scenario.schema import scenario_from_dict


@pytest.mark.parametrize("kind", ["box", "cylinder"])
def test_surface_samples_lie_on_the_surface_no_farther_apart_than_the_spacing(kind: str) -> None:
    mapping = ({"type": "box", "size": [0.3, 0.2, 0.1]} if kind == "box" else
               {"type": "cylinder", "radius": 0.05, "length": 0.2})
    mapping |= {"position": [0.4, -0.1, 0.3], "orientation": [0.924, 0.0, 0.383, 0.0]}
    spec = scenario_from_dict({"robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 1.0,
                               "initial_state": {"q": [0, -0.3, 0, -2.2, 0, 2.0, 0.8]},
                               "goal": [{"type": "joint", "position": [0, -0.3, 0, -2.2, 0, 2.0, 0.8]}],
                               "obstacles": [mapping]}).obstacles[0]
    points = surface_points(mapping)
    placement = Placement(spec.position, spec.orientation)
    assert np.abs(placed_distance(spec.shape, placement, points)).max() < 1e-9
    # every surface point is within the spacing of a sample: test on a denser sampling
    dense = surface_points(mapping, SPACING / 4)
    assert cKDTree(points).query(dense)[0].max() <= SPACING


def test_a_points_case_is_the_object_removed_scene_as_one_noisy_cloud() -> None:
    problem = load_problems(("box",), 1, skip=8)[0]
    removed = prepare_case(problem, "object-removed", franka())
    case = prepare_case(problem, "points", franka())
    assert case.variant == "points" and case.invalid == removed.invalid
    assert case.check_obstacles == tuple(removed.mapping["obstacles"])
    (entry,) = case.mapping["obstacles"]
    assert entry["type"] == "points"
    cloud = np.load(entry["file"])
    scenario = scenario_from_dict(removed.mapping)
    gaps = np.min([np.abs(placed_distance(o.shape, Placement(o.position, o.orientation), cloud))
                   for o in scenario.obstacles], axis=0)
    assert np.std(gaps) < 2 * NOISE and gaps.max() < 6 * NOISE  # |N(0, σ²I)| along the normal
