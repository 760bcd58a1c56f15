"""MotionBenchMaker's mesh scenes, ``kitchen`` and ``table_bars``, as Panda problems generated
from a seed the way MBM's ``generate`` does (``src/scene_sampler.cpp``,
``src/problem_generator.cpp``), then run like the other types (``--types kitchen,table_bars``).

Problem ``number`` of a scene draws from ``numpy.random.default_rng([seed, scene, number])``:

1. **the scene**: every movable joint of the scene URDF uniform within its limits (MoveIt's
   ``setToRandomPositions``, what MBM does with a URDF scene: the kitchen's doors open at
   random, the table's bars slide), the scene's root at ``T_World · T_base`` with ``T_World``
   a sample of the variation entry ``World`` (:mod:`~dynfab.benchmarks.mbm.scene_configs`).
   MBM's sampler applies only the ``World`` entry to URDF scenes; table_bars' entry for its
   bars (±0.1 m along y) is not applied, its bars moving by their joints (0.35 m) instead;
2. **start and goal**: a start and a goal query (distinct names), each the tip target
   ``T_8 = T_object · T_offset · T_ee⁻¹`` sampled within the query's tolerances, then
   inverse kinematics of Franka's ``panda_link8`` onto it (:mod:`~dynfab.benchmarks.mbm.query_ik`:
   MBM's 200 attempts) whose solution is within the limits and free of the scene and of
   self-collision on Franka's meshes (fingers open);
3. a scene whose start or goal has no such solution is drawn again (:data:`MESH_SCENE_ATTEMPTS`),
   as MBM's loop does. MBM also keeps only problems its planner solves in 60 s; here none is
   dropped for that.

The case runs the built-in ``panda`` from the start configuration to a **pose goal** of its
``panda_hand`` (Franka's ``panda_hand_tcp``) at the goal target (``T_8`` times the fixed
``panda_link8`` → ``panda_hand_tcp`` transform), reached within :data:`TOLERANCE` [m] and
:data:`ANGLE_TOLERANCE` [rad]; the scene is one ``{type: urdf}`` obstacle with its
``joints``, and every run is checked on Franka's meshes as the other types.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from dynfab.benchmarks.mbm.conversion import DT, DURATION, PLANNER
from dynfab.benchmarks.mbm.franka import TCP_LINK, Franka
from dynfab.benchmarks.mbm.moveit import ProblemError
from dynfab.benchmarks.mbm.query_ik import READY, TIP_LINK, free_query_ik
from dynfab.benchmarks.mbm.scene_configs import (SCENE_TYPES, Query, SceneConfig, data_root, pose_matrix,
                                                 scene_config)
from dynfab.benchmarks.mbm.validity import static_shapes
from dynfab.benchmarks.mbm.variants import Case
from dynfab.robots.mesh_paths import resolve_uri
from dynfab.robots.mesh_sweep import PlacedShape
from dynfab.robots.urdf import load_urdf
from dynfab.robots.urdf_model import UrdfModel
from dynfab.scenario.scene_files import link_poses
from dynfab.scenario.schema import scenario_from_dict

__all__ = ["ANGLE_TOLERANCE", "MESH_SCENE_ATTEMPTS", "TOLERANCE", "VARIANT", "SceneProblem", "generate_scene_problem",
           "prepare_scene_case", "scene_problems"]

#: The variant's name: the scenes have no graspable object to remove.
VARIANT = "as-posed"
#: Position tolerance of the pose goal [m].
TOLERANCE = 0.01
#: Orientation tolerance of the pose goal [rad].
ANGLE_TOLERANCE = 0.05
#: Scenes drawn per problem of a mesh scene (kitchen, table_bars) before giving up; the
#: primitive types' generated problems draw up to
#: :data:`~dynfab.benchmarks.mbm.generated_problems.PRIMITIVE_SCENE_ATTEMPTS`.
MESH_SCENE_ATTEMPTS = 50


@dataclass(frozen=True)
class SceneProblem:
    """One generated problem of a mesh scene.

    Attributes:
        type: The scene, one of :data:`~dynfab.benchmarks.mbm.scene_configs.SCENE_TYPES`.
        number: Its number (1, 2, ...).
        seed: The generation seed.
        start: Start configuration of the 7 arm joints [rad].
        goal: The IK solution found for the goal (proof it is reachable and free) [rad].
        goal_pose: The pose goal of ``panda_hand_tcp`` (4x4) in the robot's base frame.
        scene: The scene's ``{type: urdf}`` obstacle mapping (its root pose and joints).
        queries: ``start -> goal`` query names (``object_tag``).
    """

    type: str
    number: int
    seed: int
    start: tuple[float, ...]
    goal: tuple[float, ...]
    goal_pose: NDArray[np.float64]
    scene: dict[str, Any]
    queries: str

    @property
    def name(self) -> str:
        """``<scene>/<NNNN>``, e.g. ``kitchen/0003``."""
        return f"{self.type}/{self.number:04d}"


def scene_problems(types: tuple[str, ...], per_type: int, skip: int, seed: int, robot: Franka) -> tuple[SceneProblem, ...]:
    """Problems ``skip + 1 .. skip + per_type`` of each scene of ``types`` (in that order)."""
    return tuple(generate_scene_problem(name, number, seed, robot)
                 for name in types for number in range(skip + 1, skip + per_type + 1))


def generate_scene_problem(name: str, number: int, seed: int, robot: Franka) -> SceneProblem:
    """Problem ``number`` of scene ``name`` drawn from ``seed`` (module doc).

    Raises:
        ValueError: An unknown scene.
        ProblemError: No scene of :data:`MESH_SCENE_ATTEMPTS` had a free start and goal.
    """
    config = scene_config(name)
    rng = np.random.default_rng([seed, SCENE_TYPES.index(name), number])
    for _ in range(MESH_SCENE_ATTEMPTS):
        scene = _sample_scene(config, rng)
        shapes = static_shapes(scenario_from_dict(_mapping(READY, _pose_goal(np.eye(4)), scene, PLANNER)))
        objects = _object_poses(config, scene)
        start_query = config.start_queries[rng.integers(len(config.start_queries))]
        goals = [q for q in config.goal_queries if _query_name(q) != _query_name(start_query)]
        goal_query = goals[rng.integers(len(goals))]
        start = _free_ik(robot, config, start_query, objects, shapes, rng)
        if start is None:
            continue
        goal = _free_ik(robot, config, goal_query, objects, shapes, rng)
        if goal is None:
            continue
        goal_q, tip = goal
        return SceneProblem(name, number, seed, tuple(float(v) for v in start[0]), tuple(float(v) for v in goal_q),
                            tip @ _tip_to_tcp(robot), scene, f"{_query_name(start_query)} -> {_query_name(goal_query)}")
    raise ProblemError(f"configs/problems/{name}_panda.yaml", "queries",
                       f"no free start and goal in {MESH_SCENE_ATTEMPTS} scenes (problem {number}, seed {seed})")


def prepare_scene_case(problem: SceneProblem, planner: str = PLANNER) -> Case:
    """``problem`` as a case of the benchmark (module doc); it is valid by construction."""
    mapping = _mapping(problem.start, _pose_goal(problem.goal_pose), problem.scene, planner)
    names = tuple(_links_with_collisions(problem.scene["file"]))
    return Case(problem, VARIANT, mapping, names, None, None)  # type: ignore[arg-type]


def _sample_scene(config: SceneConfig, rng: np.random.Generator) -> dict[str, Any]:
    """The scene's obstacle mapping: its joints uniform within their limits, its root at
    ``T_World · T_base``."""
    model = _scene_model(config.urdf)
    joints = {j.name: round(float(rng.uniform(j.limit.lower, j.limit.upper)), 6)
              for j in model.joints if j.is_actuated and j.limit is not None}
    root = config.base_offset
    for variation in config.variations:
        if "World" in variation.names:
            root = variation.sample(rng) @ root
    x, y, z, w = Rotation.from_matrix(root[:3, :3]).as_quat()
    return {"type": "urdf", "file": config.urdf, "package_dirs": [str(data_root())],
            "position": [round(float(v), 6) for v in root[:3, 3]],
            "orientation": [round(float(v), 9) for v in (w, x, y, z)], "joints": joints}


def _object_poses(config: SceneConfig, scene: dict[str, Any]) -> dict[str, NDArray[np.float64]]:
    """Each link's first collision element's pose in the robot's base frame (MBM's object pose)."""
    model = _scene_model(config.urdf)
    w, x, y, z = scene["orientation"]
    root = pose_matrix(np.asarray(scene["position"]), Rotation.from_quat([x, y, z, w]).as_matrix())
    poses = {}
    for link, pose in link_poses(model, scene["joints"]).items():
        collisions = next(entry for entry in model.links if entry.name == link).collisions
        if collisions:
            origin = collisions[0].origin
            poses[link] = root @ pose @ pose_matrix(np.asarray(origin.xyz), np.asarray(origin.rotation))
    return poses


def _free_ik(robot: Franka, config: SceneConfig, query: Query, objects: dict[str, NDArray[np.float64]],
             shapes: list[PlacedShape], rng: np.random.Generator) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """:func:`~dynfab.benchmarks.mbm.query_ik.free_query_ik` onto ``query``'s object."""
    return free_query_ik(robot, objects[query.obj] @ query.offset @ np.linalg.inv(config.ee_offset), query, shapes, rng)


def _tip_to_tcp(robot: Franka) -> NDArray[np.float64]:
    """``panda_link8`` → ``panda_hand_tcp`` (4x4), fixed."""
    q = np.zeros(robot.robot.kinematics.dof)
    tip = np.array(robot.robot.kinematics.transform(q, TIP_LINK), dtype=float)
    tcp = np.array(robot.robot.kinematics.transform(q, TCP_LINK), dtype=float)
    return np.linalg.inv(tip) @ tcp


def _pose_goal(pose: NDArray[np.float64]) -> dict[str, Any]:
    x, y, z, w = Rotation.from_matrix(pose[:3, :3]).as_quat()
    return {"type": "pose", "position": [round(float(v), 6) for v in pose[:3, 3]],
            "orientation": [round(float(v), 9) for v in (w, x, y, z)], "tolerance": TOLERANCE,
            "angle_tolerance": ANGLE_TOLERANCE}


def _mapping(start: tuple[float, ...] | NDArray[np.float64] | list[float], goal: dict[str, Any],
             scene: dict[str, Any], planner: str) -> dict[str, Any]:
    return {"robot": "panda", "planner": planner, "dt": DT, "duration": DURATION,
            "initial_state": {"q": [round(float(v), 9) for v in start]}, "goal": [goal], "obstacles": [scene]}


def _query_name(query: Query) -> str:
    return f"{query.obj}_{query.tag}"


@cache
def _scene_model(uri: str) -> UrdfModel:
    path = resolve_uri(uri, None, [data_root()])
    assert path is not None  # bundled
    return load_urdf(path, [data_root()])


def _links_with_collisions(uri: str) -> list[str]:
    """The scene's obstacles' names: its links, one per collision element, in the order
    :mod:`dynfab.scenario.scene_files` expands them."""
    model = _scene_model(uri)
    return [link for link in link_poses(model, {})
            for _ in next(entry for entry in model.links if entry.name == link).collisions]
