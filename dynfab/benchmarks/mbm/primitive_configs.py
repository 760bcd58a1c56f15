"""MotionBenchMaker's Panda problem configs of the seven primitive types (those of the
archive, :data:`~dynfab.benchmarks.mbm.problems.PROBLEM_TYPES`), read from the bundled copy
of its ``configs/`` folder (``data/motion_bench_maker/``, BSD-3-Clause, ``LICENSE`` beside it).

A config (``configs/problems/<type>_panda.yaml``) names a scene of boxes and cylinders (a
MoveIt planning scene, read by :func:`~dynfab.benchmarks.mbm.moveit.scene_objects`), its
queries, its variation and two poses, ``base_offset`` and ``ee_offset``, as the mesh scenes'
configs do (:mod:`~dynfab.benchmarks.mbm.scene_configs`). Every object a query or a
variation names must be in the scene.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
from numpy.typing import NDArray

from dynfab.benchmarks.mbm.moveit import ProblemError, SceneObject, scene_objects
from dynfab.benchmarks.mbm.problems import PROBLEM_TYPES
from dynfab.benchmarks.mbm.scene_configs import (PACKAGE, Query, Variation, config_pose, query_list, read_config,
                                                 variation_list)

__all__ = ["WORLD", "PrimitiveConfig", "primitive_config"]

#: The variation entry name that moves the whole scene.
WORLD = "World"


@dataclass(frozen=True)
class PrimitiveConfig:
    """A primitive type's Panda problem config (module doc).

    Attributes:
        name: One of :data:`~dynfab.benchmarks.mbm.problems.PROBLEM_TYPES`.
        scene: The nominal scene, one entry per primitive, in the scene file's frame.
        base_offset: ``T_base`` (4x4): the scene file's frame in the robot's base frame.
        ee_offset: ``T_ee`` (4x4): the query frame in ``panda_link8``'s.
        start_queries: Where problems start; empty: at MBM's ready state.
        goal_queries: Where they end (one per object an entry names).
        world: The variation of the whole scene; None if the file has none.
        object_variations: The other variation entries, in file order.
    """

    name: str
    scene: tuple[SceneObject, ...]
    base_offset: NDArray[np.float64]
    ee_offset: NDArray[np.float64]
    start_queries: tuple[Query, ...]
    goal_queries: tuple[Query, ...]
    world: Variation | None
    object_variations: tuple[Variation, ...]


@cache
def primitive_config(name: str) -> PrimitiveConfig:
    """The bundled config of primitive type ``name``.

    Raises:
        ValueError: An unknown type.
        ProblemError: A query or a variation names an object the scene lacks.
    """
    if name not in PROBLEM_TYPES:
        raise ValueError(f"unknown problem type {name!r} (expected one of {', '.join(PROBLEM_TYPES)})")
    config = read_config(f"package://{PACKAGE}/configs/problems/{name}_panda.yaml")
    scene = scene_objects(read_config(config["scene"]), config["scene"])
    queries = read_config(config["queries"])
    starts, goals = query_list(queries.get("start_queries", ())), query_list(queries["goal_queries"])
    variations = variation_list(read_config(config["variation"]))
    ids = {o.id for o in scene}
    for field, objects in (("queries", [q.obj for q in starts + goals]),
                           ("variation", [n for v in variations for n in v.names if n != WORLD])):
        missing = [obj for obj in objects if obj not in ids]
        if missing:
            raise ProblemError(config[field], "objects", f"{missing[0]!r} is not an object of {config['scene']}")
    world = [v for v in variations if WORLD in v.names]
    return PrimitiveConfig(name, scene, config_pose(config["base_offset"]), config_pose(config["ee_offset"]), starts,
                           goals, world[-1] if world else None, tuple(v for v in variations if WORLD not in v.names))
