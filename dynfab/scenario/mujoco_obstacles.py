"""What MuJoCo cannot take among a scenario's obstacles, refused as the file is loaded.

Under ``simulator: mujoco`` every obstacle entry is in the physics (:mod:`dynfab.sim.mjcf_obstacles`)
except a point cloud (``type: points``), which is no solid: it stays an obstacle of the planner
(read from its file) and of the metrics, but nothing in MuJoCo touches it and no camera sees
it. Refused, each naming its entry ``obstacles[k]``:

* a point cloud under ``perception: camera``: the planner would know the scene only through
  the camera, which cannot see the cloud, while the metrics still count it;
* a mesh (a ``type: mesh`` entry, or a mesh of a ``type: urdf`` scene) of more than
  :data:`dynfab.sim.mesh_parts.MAX_PARTS` convex parts (its non-convex components count one
  part per triangle, :func:`dynfab.sim.mesh_parts.convex_parts`).
"""

from __future__ import annotations

from collections.abc import Sequence

from dynfab.scenario.fields import ScenarioError
from dynfab.scenario.obstacle_schema import ObstacleSpec
from dynfab.sim.mesh_parts import TooManyPartsError, convex_parts

__all__ = ["check_mujoco_obstacles"]


def check_mujoco_obstacles(entries: Sequence[Sequence[ObstacleSpec]], perception: str) -> None:
    """Refuse what MuJoCo cannot simulate (module doc); ``entries[k]`` holds the obstacles
    of the file's entry ``obstacles[k]`` (a URDF scene: several).

    Raises:
        ScenarioError: Naming ``obstacles[k]`` (a point cloud) or ``obstacles[k].file`` (a mesh).
    """
    for k, specs in enumerate(entries):
        for spec in specs:
            if spec.type == "points" and perception == "camera":
                raise ScenarioError(f"obstacles[{k}]", "a point cloud is not in MuJoCo's physics nor in the camera's "
                                    "images, so under perception: camera nothing would show it to the planner; "
                                    "remove it, give the surfaces as meshes, or use perception: truth")
            if spec.type == "mesh":
                assert spec.mesh is not None
                try:
                    convex_parts(spec.mesh)
                except TooManyPartsError as error:
                    raise ScenarioError(f"obstacles[{k}].file", str(error)) from None
