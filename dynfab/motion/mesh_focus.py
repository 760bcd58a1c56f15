"""The global planner's view of meshes near the robot at its ends: the surface near the
robot's spheres at the start and at the goal read on a finer grid
(:mod:`dynfab.geometry.focused_mesh`).

For a mesh and an endpoint configuration ``q`` (the goal, then the start), the *near*
spheres are those whose grid bound (the whole mesh's, up to 1.7 cm low) is below ``reach``:

    near(q) = {i : v(Rᵀ (p_i(q) − p)) − r_i < reach},

and the focus is their bounding box in the mesh's frame grown by ``reach``:

    [min_{i ∈ near} (c_i − r_i) − reach, max_{i ∈ near} (c_i + r_i) + reach]      [m],

``c_i = Rᵀ (p_i(q) − p)``. The surface inside it becomes a
:class:`~dynfab.geometry.focused_mesh.FocusedMesh` gridded at ``pitch``, the mesh itself a
:class:`~dynfab.geometry.focused_mesh.CarvedMesh` (its usual grid raised inside the boxes);
an endpoint with no near sphere has no focus in that mesh. The bound is the
same distance; only the grid's shortfall below it shrinks, from up to 1.7 cm to up to
``pitch·√3`` (7 mm at 4 mm), where the robot's ends are near the scene. Other obstacles are
untouched.

Guidance plans on the focus only where every attempt on the whole meshes (its last round
at ``tight_margin`` included) gave no plan (:meth:`~dynfab.motion.guidance.JointGuidance.plan`),
so a problem planned without it is planned as before. On held-out MotionBenchMaker kitchen
problems (seed 1) the spheres at the goals read 14-27 mm into a cupboard on the grid where
they are 0-10 mm in on the exact distance and the robot's meshes are 5-15 mm clear, and
the starts −10 to −31 mm on the grid where the meshes are 0.6-22 mm clear.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.distance_grid import DistanceGrid
from dynfab.geometry.focused_mesh import CarvedMesh, FocusedMesh, carved, clip_mesh
from dynfab.geometry.shapes import Mesh
from dynfab.motion.configuration_checker import PlacedObstacle

__all__ = ["MeshFocus", "focused_meshes"]


@dataclass(frozen=True)
class MeshFocus:
    """How the planner looks at meshes near the robot's ends (module docstring).

    Attributes:
        reach: how near a sphere must be to a mesh to be focused on, and how far the focus
            reaches beyond the near spheres [m].
        pitch: node spacing of the focused surface's grid [m] (grown by the grid to stay
            within its node budget, 8 M nodes).
    """

    reach: float = 0.15
    pitch: float = 0.003

    def __post_init__(self) -> None:
        if not (math.isfinite(self.reach) and self.reach >= 0.0):
            raise ValueError(f"mesh focus reach: must be a finite number >= 0, got {self.reach}")
        if not (math.isfinite(self.pitch) and self.pitch > 0.0):
            raise ValueError(f"mesh focus pitch: must be a positive number, got {self.pitch}")


def focused_meshes(obstacles: Sequence[PlacedObstacle], ends: Sequence[NDArray[np.float64]],
                   radii: NDArray[np.float64], grid_of: Callable[[Mesh], DistanceGrid],
                   focus: MeshFocus) -> tuple[PlacedObstacle, ...]:
    """``obstacles`` with every mesh's surface near the spheres at each of ``ends`` (each the
    sphere centres (m, 3) at one endpoint [m], radii (m,) [m]) split off on a finer grid
    (module docstring); ``grid_of(mesh)`` is the whole mesh's grid."""
    radii = np.asarray(radii, dtype=float).reshape(-1)
    result: list[PlacedObstacle] = []
    for obstacle in obstacles:
        mesh = obstacle.shape
        if not isinstance(mesh, Mesh) or isinstance(mesh, FocusedMesh | CarvedMesh):
            result.append(obstacle)
            continue
        grid = grid_of(mesh)
        holes = []
        for centres in ends:
            local = obstacle.placement.to_local(np.asarray(centres, dtype=float).reshape(-1, 3))
            near = grid.lower_bound(local) - radii < focus.reach
            if not near.any():
                continue
            low = (local[near] - radii[near, None]).min(axis=0) - focus.reach
            high = (local[near] + radii[near, None]).max(axis=0) + focus.reach
            piece = clip_mesh(mesh, low, high, focus.pitch)
            if piece is not None:
                result.append(PlacedObstacle(piece, obstacle.placement))
                holes.append((low, high))
        result.append(obstacle if not holes else PlacedObstacle(carved(mesh, holes), obstacle.placement))
    return tuple(result)
