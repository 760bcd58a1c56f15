"""The benchmark's variants of a problem, each a scenario mapping ready to run:

- ``as-posed``: the scene as the benchmark poses it (the open hand 2-10 mm from the object
  it is about to grasp);
- ``object-removed``: the graspable object (ids ``Can*``, ``Cube*``, ``Object*``) nearest
  the hand (hand and finger meshes, fingers open) at the goal removed: the motion to a
  grasp pose without the grasp;
- ``moving-sphere``: ``object-removed`` plus a sphere crossing the hand's straight path
  around mid-motion (:mod:`dynfab.benchmarks.mbm.moving_sphere`): with the object in
  place the built-in Panda's spheres cannot reach most grasp goals at all, which would
  hide what the sphere adds.

A case is invalid (never run) when its start or goal is outside Franka's limits or
touches its own static scene (:mod:`dynfab.benchmarks.mbm.validity`): for
``object-removed`` and ``moving-sphere`` a goal that touches only the removed object is
valid.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from dynfab.benchmarks.mbm.conversion import DURATION, PLANNER, scenario_mapping
from dynfab.benchmarks.mbm.franka import HAND_LINKS, Franka
from dynfab.benchmarks.mbm.moveit import ProblemError
from dynfab.benchmarks.mbm.moving_sphere import crossing_sphere
from dynfab.benchmarks.mbm.point_clouds import as_point_cloud
from dynfab.benchmarks.mbm.problems import PROBLEM_TYPES, Problem
from dynfab.benchmarks.mbm.validity import invalid_reason, static_shapes
from dynfab.geometry.exact_collision import exact_distance, placement_matrix, shape_geometry
from dynfab.geometry.shapes import Placement
from dynfab.scenario.schema import scenario_from_dict

__all__ = ["GRASPABLE_PREFIXES", "VARIANTS", "Case", "grasped_object", "prepare_case"]

VARIANTS: tuple[str, ...] = ("as-posed", "object-removed", "moving-sphere", "points")
#: Collision object ids of the objects a goal grasps start with one of these.
GRASPABLE_PREFIXES: tuple[str, ...] = ("Can", "Cube", "Object")


@dataclass(frozen=True, eq=False)
class Case:
    """One problem in one variant.

    Attributes:
        problem: The problem.
        variant: One of :data:`VARIANTS`.
        mapping: Its scenario mapping (what a scenario file would hold).
        obstacle_names: The scene's id of each obstacle of ``mapping`` (``moving-sphere``
            for the sphere).
        removed: The id of the removed object; None for ``as-posed``.
        invalid: Why the case is invalid, in one line; None if it is valid.
        check_obstacles: The obstacles the run is checked against instead of the mapping's
            (``points``: the true shapes); None: the mapping's.
    """

    problem: Problem
    variant: str
    mapping: dict[str, Any]
    obstacle_names: tuple[str, ...]
    removed: str | None
    invalid: str | None
    check_obstacles: tuple[dict[str, Any], ...] | None = None


def prepare_case(problem: Problem, variant: str, robot: Franka, planner: str = PLANNER, seed: int = 0) -> Case:
    """``problem`` in ``variant`` (module doc); the moving sphere is drawn from ``seed``
    and the problem's type and number.

    Raises:
        ValueError: An unknown variant.
        ProblemError: The problem has no graspable object (variants that remove it).
        ScenarioError: The converted scenario breaks the schema.
    """
    if variant not in VARIANTS:
        raise ValueError(f"unknown variant {variant!r} (expected one of {', '.join(VARIANTS)})")
    if variant == "points":  # the scene as a noisy point cloud (dynfab/benchmarks/mbm/point_clouds.py)
        return as_point_cloud(prepare_case(problem, "object-removed", robot, planner, seed), seed)
    objects = problem.objects
    removed = None
    if variant != "as-posed":
        index = grasped_object(problem, robot)
        removed = objects[index].id
        objects = objects[:index] + objects[index + 1:]
    names = tuple(o.id for o in objects)
    mapping = scenario_mapping(problem, objects, robot, planner)
    invalid = invalid_reason(problem.start, problem.goal, static_shapes(scenario_from_dict(mapping)), names, robot)
    if variant == "moving-sphere" and invalid is None:
        rng = np.random.default_rng([seed, PROBLEM_TYPES.index(problem.type), problem.number])
        sphere = crossing_sphere(problem.start, problem.goal, robot, rng, DURATION)
        if sphere is None:
            invalid = "no sphere path keeps the start and goal configurations free"
        else:
            mapping = scenario_mapping(problem, objects, robot, planner, [sphere.mapping()])
            names += ("moving-sphere",)
    return Case(problem, variant, mapping, names, removed, invalid)


def grasped_object(problem: Problem, robot: Franka) -> int:
    """Index into ``problem.objects`` of the graspable object nearest the hand at the goal,
    measured on the hand's and fingers' meshes.

    Raises:
        ProblemError: The scene has no graspable object.
    """
    candidates = [k for k, o in enumerate(problem.objects) if o.id.startswith(GRASPABLE_PREFIXES)]
    if not candidates:
        raise ProblemError(f"problems/{problem.type}_panda/scene{problem.number:04d}.yaml", "world.collision_objects",
                           f"no graspable object (ids {', '.join(p + '*' for p in GRASPABLE_PREFIXES)})")
    scenario = scenario_from_dict(scenario_mapping(problem, problem.objects, robot))
    poses = robot.meshes.link_poses(robot.clipped(problem.goal))[0]
    hand = [robot.meshes.links.index(link) for link in HAND_LINKS]

    def distance(k: int) -> float:
        obstacle = scenario.obstacles[k]
        pose = placement_matrix(Placement(obstacle.position, obstacle.orientation))
        geometry = shape_geometry(obstacle.shape)
        return min(exact_distance(robot.meshes.meshes[i], poses[i], geometry, pose) for i in hand)

    return min(candidates, key=distance)
