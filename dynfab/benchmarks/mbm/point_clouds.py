"""The ``points`` variant: an ``object-removed`` case whose scene the planner knows only as a
point cloud (issue 20).

Every box and cylinder of the scene is sampled on its surface every :data:`SPACING` (a grid on
each box face; on a cylinder, rings on its side and concentric rings on its caps), each
sample moved by Gaussian noise of :data:`NOISE` per axis, seeded by the problem; the cloud
is saved as ``.npy`` under ``<cache>/mbm-clouds/`` (``$DYNFAB_CACHE_DIR`` or
``~/.cache/dynfab``) and the scenario has one obstacle, ``{type: points, file: ...,
voxel:`` :data:`VOXEL` ``}``. The
run is checked against the true shapes (:attr:`~dynfab.benchmarks.mbm.variants.Case.check_obstacles`),
not against the cloud.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from dynfab.benchmarks.mbm.problems import PROBLEM_TYPES
from dynfab.robots.collision_model import cache_dir
from dynfab.geometry.shapes import quaternion_matrix, unit_quaternion

if TYPE_CHECKING:
    from dynfab.benchmarks.mbm.variants import Case

__all__ = ["NOISE", "SPACING", "VOXEL", "as_point_cloud", "surface_points"]

#: Distance between surface samples [m].
SPACING = 0.005
#: Standard deviation of the noise on each coordinate [m].
NOISE = 0.002
#: The cloud's voxel [m]. Its half-diagonal (8.7 mm) is clearance the planners give away, and
#: it covers what the samples miss of the true surface (up to half a sampling diagonal plus the
#: noise): at 5 mm a run on bookshelf_small 18 went 1 cm into a true shelf.
VOXEL = 0.01


def as_point_cloud(case: Case, seed: int = 0) -> Case:
    """``case`` (object removed) with its primitives replaced by their noisy surface samples
    (module doc); the primitives become the obstacles the run is checked against."""
    obstacles = case.mapping["obstacles"]
    problem = case.problem
    rng = np.random.default_rng([seed, PROBLEM_TYPES.index(problem.type), problem.number, 20])
    points = np.concatenate([surface_points(o) for o in obstacles])
    points = points + rng.normal(0.0, NOISE, points.shape)
    folder = Path(cache_dir()) / "mbm-clouds"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{problem.type}_{problem.number:04d}_seed{seed}_{SPACING * 1e3:g}mm_{NOISE * 1e3:g}mm.npy"
    partial = path.with_suffix(".partial.npy")
    np.save(partial, points)
    partial.replace(path)
    mapping = {**case.mapping, "obstacles": [{"type": "points", "file": str(path), "voxel": VOXEL}]}
    return dataclasses.replace(case, variant="points", mapping=mapping, check_obstacles=tuple(obstacles))


def surface_points(obstacle: Mapping[str, Any], spacing: float = SPACING) -> NDArray[np.float64]:
    """Points (N, 3) [m] every ``spacing`` on the surface of a scenario ``box`` or
    ``cylinder`` mapping, in the world."""
    if obstacle["type"] == "box":
        local = _box_surface(obstacle["size"], spacing)
    elif obstacle["type"] == "cylinder":
        local = _cylinder_surface(obstacle["radius"], obstacle["length"], spacing)
    else:
        raise ValueError(f"cannot sample a {obstacle['type']!r} obstacle")
    rotation = quaternion_matrix(unit_quaternion(obstacle.get("orientation", (1.0, 0.0, 0.0, 0.0))))
    return local @ rotation.T + np.asarray(obstacle["position"], dtype=float)


def _steps(length: float, spacing: float) -> NDArray[np.float64]:
    """Evenly spaced values from ``-length/2`` to ``length/2``, at most ``spacing`` apart."""
    return np.linspace(-0.5 * length, 0.5 * length, max(2, math.ceil(length / spacing) + 1))


def _box_surface(size: Sequence[float], spacing: float) -> NDArray[np.float64]:
    faces = []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        a, b = np.meshgrid(_steps(size[u], spacing), _steps(size[v], spacing), indexing="ij")
        for side in (-0.5, 0.5):
            face = np.zeros((a.size, 3))
            face[:, axis] = side * size[axis]
            face[:, u], face[:, v] = a.ravel(), b.ravel()
            faces.append(face)
    return np.concatenate(faces)


def _ring(radius: float, spacing: float) -> NDArray[np.float64]:
    count = max(1, math.ceil(2 * math.pi * radius / spacing))
    angles = np.arange(count) * (2 * math.pi / count)
    return radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)


def _cylinder_surface(radius: float, length: float, spacing: float) -> NDArray[np.float64]:
    rim = _ring(radius, spacing)
    side = [np.column_stack([rim, np.full(len(rim), z)]) for z in _steps(length, spacing)]
    disc = np.concatenate([_ring(r, spacing) for r in np.linspace(0.0, radius, max(2, math.ceil(radius / spacing) + 1))])
    caps = [np.column_stack([disc, np.full(len(disc), z)]) for z in (-0.5 * length, 0.5 * length)]
    return np.concatenate(side + caps)
