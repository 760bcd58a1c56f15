"""MotionBenchMaker's configuration of its two mesh scenes, ``kitchen`` and ``table_bars``,
for the Panda, read from the bundled copy of its ``configs/`` folder
(``data/motion_bench_maker/``, BSD-3-Clause, ``LICENSE`` beside it).

A problem config (``configs/problems/<scene>_panda.yaml``) names the scene URDF, its grasp
queries, its variation and two poses: ``base_offset`` (applied to the whole scene: the
scene in the robot's base frame) and ``ee_offset`` (the query frame in the solver's tip
link, ``panda_link8``). Poses are MoveIt's: ``position`` [m], ``orientation`` a quaternion
``x, y, z, w``.

A query (``*queries.yaml``) places the tip near a scene object: the tip's target is

    T_8 = T_object · T_offset · T_ee⁻¹,

with ``T_object`` the pose of the object's first collision element in the robot's base
frame; MBM samples the position uniformly within ``position_tol`` (full box edges [m],
world axes) of it and the rotation within ``orientation_tol`` [rad] about each axis.

A variation (``variation.yaml``) lists pose perturbations: ``position`` bounds [m] and
``orientation`` bounds (roll, pitch, yaw) [rad], each sampled uniformly within ±bound;
the entry named ``World`` moves the whole scene.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from importlib.resources import as_file, files
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

__all__ = ["PACKAGE", "SCENE_TYPES", "Query", "SceneConfig", "Variation", "config_pose", "data_root", "pose_matrix",
           "query_list", "read_config", "scene_config", "variation_list"]

#: The mesh scenes of MBM with a Panda problem config, in report order.
SCENE_TYPES: tuple[str, ...] = ("kitchen", "table_bars")
#: The ROS package name the configs' ``package://`` URIs use.
PACKAGE = "motion_bench_maker"


@dataclass(frozen=True)
class Query:
    """One grasp query: the tip near ``obj``.

    Attributes:
        obj: The scene object (a link of the scene URDF).
        tag: Its tag (``FrontHard``, ...).
        offset: ``T_offset`` (4x4) in the object's frame.
        position_tolerance: Full edge lengths of the box the position is sampled in [m].
        orientation_tolerance: Bounds of the rotation sampled about x, y, z [rad].
    """

    obj: str
    tag: str
    offset: NDArray[np.float64]
    position_tolerance: tuple[float, float, float]
    orientation_tolerance: tuple[float, float, float]


@dataclass(frozen=True)
class Variation:
    """One entry of a variation file: ``names`` moved by a pose within ±``position`` [m] and
    ±``orientation`` (roll, pitch, yaw) [rad], uniformly."""

    names: tuple[str, ...]
    position: tuple[float, float, float]
    orientation: tuple[float, float, float]

    def sample(self, rng: np.random.Generator) -> NDArray[np.float64]:
        """A pose (4x4) of this variation: ``R = Rx(r) Ry(p) Rz(y)`` (robowflex's order)."""
        translation = rng.uniform(-1.0, 1.0, 3) * np.asarray(self.position)
        roll, pitch, yaw = rng.uniform(-1.0, 1.0, 3) * np.asarray(self.orientation)
        rotation = Rotation.from_euler("XYZ", [roll, pitch, yaw]).as_matrix()
        return pose_matrix(translation, rotation)


@dataclass(frozen=True)
class SceneConfig:
    """A scene's Panda problem config (module doc).

    Attributes:
        name: One of :data:`SCENE_TYPES`.
        urdf: The scene URDF's ``package://`` URI.
        base_offset: ``T_base`` (4x4): the scene's root in the robot's base frame.
        ee_offset: ``T_ee`` (4x4): the query frame in ``panda_link8``'s.
        start_queries: Where problems start.
        goal_queries: Where they end.
        variations: The variation file's entries.
    """

    name: str
    urdf: str
    base_offset: NDArray[np.float64]
    ee_offset: NDArray[np.float64]
    start_queries: tuple[Query, ...]
    goal_queries: tuple[Query, ...]
    variations: tuple[Variation, ...]


def data_root() -> Path:
    """The folder that holds the bundled ``motion_bench_maker`` package (a ``package_dirs`` entry)."""
    with as_file(files("dynfab.benchmarks.mbm") / "data") as path:
        return Path(path)


def pose_matrix(position: NDArray[np.float64] | list[float], rotation: NDArray[np.float64]) -> NDArray[np.float64]:
    """The 4x4 pose of ``position`` [m] and a 3x3 ``rotation``."""
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    matrix[:3, 3] = position
    return matrix


@cache
def scene_config(name: str) -> SceneConfig:
    """The bundled config of scene ``name``.

    Raises:
        ValueError: An unknown scene.
    """
    if name not in SCENE_TYPES:
        raise ValueError(f"unknown scene {name!r} (expected one of {', '.join(SCENE_TYPES)})")
    config = read_config(f"package://{PACKAGE}/configs/problems/{name}_panda.yaml")
    queries = read_config(config["queries"])
    return SceneConfig(name, config["scene"], config_pose(config["base_offset"]), config_pose(config["ee_offset"]),
                       query_list(queries.get("start_queries", ())), query_list(queries["goal_queries"]),
                       variation_list(read_config(config["variation"])))


def read_config(uri: str) -> Any:
    """A bundled YAML file named by its ``package://motion_bench_maker/...`` URI."""
    relative = uri.removeprefix("package://")
    return yaml.safe_load((data_root() / relative).read_text(encoding="utf-8"))


def config_pose(node: dict[str, Any]) -> NDArray[np.float64]:
    """A config's ``{position: [x, y, z], orientation: [x, y, z, w]}`` as a 4x4 pose."""
    return pose_matrix(np.asarray(node["position"], dtype=float),
                       Rotation.from_quat(np.asarray(node["orientation"], dtype=float)).as_matrix())


def query_list(nodes: list[dict[str, Any]]) -> tuple[Query, ...]:
    """A queries file's ``start_queries`` or ``goal_queries``: one :class:`Query` per object
    an entry names (MBM's ``IO::loadQueries``: ``objects: [Can1, Can2]`` is two queries)."""
    queries = []
    for node in nodes:
        offset = node["offset"]
        for obj in node["objects"]:
            queries.append(Query(obj, node["tag"], config_pose(offset), tuple(offset["position_tol"]),
                                 tuple(offset["orientation_tol"])))
    return tuple(queries)


def variation_list(nodes: list[dict[str, Any]]) -> tuple[Variation, ...]:
    """A variation file's entries, in file order."""
    return tuple(Variation(tuple(v["names"]), tuple(v["position"]), tuple(v["orientation"])) for v in nodes)
