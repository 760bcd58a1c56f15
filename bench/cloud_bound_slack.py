"""How far a cloud's kept points read from the true surfaces (issue 20): voxel centres beside
voxel centroids, on MotionBenchMaker's ``points`` clouds.

For each problem's cloud (raw points: the surfaces sampled every 5 mm, noise σ = 2 mm,
``dynfab.benchmarks.mbm.point_clouds``) the raw points are reduced on a 1 cm voxel grid two
ways: the cell's centre (what :class:`~dynfab.geometry.point_cloud.PointCloud` keeps) and the
centroid of the cell's raw points. Query points ``x = s + d n`` are drawn on the true boxes
and cylinders (``s`` uniform on their surfaces, ``n`` the outward normal, ``d`` = 5, 10, 20
mm), and per set of kept points ``C``

    e(x) = d(x, C) − d                                        [m]

is the excess of the kept points' distance over the true one (``d`` is the true distance
unless another shape is nearer: then ``e`` understates). The planners' bound ``d(x, C) − δ``
never reads above the true distance where ``δ ≥ max e``; its shortfall below it is
``δ − e``. Printed per problem and over all: the largest ``e``, its 99.9th percentile and its
median [mm].

    .venv/bin/python bench/cloud_bound_slack.py --first 10 --problems 7   # training problems 10-16
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pykdtree.kdtree import KDTree

from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.problems import load_problems
from dynfab.benchmarks.mbm.variants import prepare_case
from dynfab.geometry.shapes import quaternion_matrix, unit_quaternion

#: The voxel edge [m] (the benchmark's).
VOXEL = 0.01
#: Offsets of the query points along the outward normals [m].
OFFSETS = (0.005, 0.01, 0.02)
#: Query points drawn per shape.
SAMPLES = 4000


def surface_with_normals(obstacle: Mapping[str, Any], rng: np.random.Generator
                         ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:data:`SAMPLES` points (world) uniform on a scenario box or cylinder and their outward
    unit normals, each (SAMPLES, 3)."""
    count = SAMPLES
    if obstacle["type"] == "box":
        size = np.asarray(obstacle["size"], dtype=float)
        areas = np.repeat([size[1] * size[2], size[2] * size[0], size[0] * size[1]], 2)
        face = rng.choice(6, count, p=areas / areas.sum())
        axis, sign = face // 2, np.where(face % 2, 1.0, -1.0)
        local = rng.uniform(-0.5, 0.5, (count, 3)) * size
        local[np.arange(count), axis] = sign * size[axis] / 2
        normal = np.zeros((count, 3))
        normal[np.arange(count), axis] = sign
    elif obstacle["type"] == "cylinder":
        radius, length = obstacle["radius"], obstacle["length"]
        side, cap = 2 * math.pi * radius * length, math.pi * radius**2
        kind = rng.choice(3, count, p=np.array([side, cap, cap]) / (side + 2 * cap))
        angle = rng.uniform(0.0, 2 * math.pi, count)
        across = radius * np.sqrt(rng.uniform(0.0, 1.0, count))
        height = np.where(kind == 0, rng.uniform(-length / 2, length / 2, count), np.where(kind == 1, length / 2,
                                                                                           -length / 2))
        reach = np.where(kind == 0, radius, across)
        local = np.column_stack([reach * np.cos(angle), reach * np.sin(angle), height])
        normal = np.where((kind == 0)[:, None], np.column_stack([np.cos(angle), np.sin(angle), np.zeros(count)]),
                          np.column_stack([np.zeros(count), np.zeros(count), np.where(kind == 1, 1.0, -1.0)]))
    else:
        raise ValueError(f"cannot sample a {obstacle['type']!r} obstacle")
    rotation = quaternion_matrix(unit_quaternion(obstacle.get("orientation", (1.0, 0.0, 0.0, 0.0))))
    return local @ rotation.T + np.asarray(obstacle["position"], dtype=float), normal @ rotation.T


def kept_points(raw: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The occupied cells' centres and the centroids of their raw points, each (M, 3) [m]."""
    cells, inverse, counts = np.unique(np.floor(raw / VOXEL).astype(np.int64), axis=0, return_inverse=True,
                                       return_counts=True)
    sums = np.zeros((len(cells), 3))
    np.add.at(sums, inverse.reshape(-1), raw)
    return (cells + 0.5) * VOXEL, sums / counts[:, None]


def excesses(kept: NDArray[np.float64], surface: NDArray[np.float64], normals: NDArray[np.float64]
             ) -> NDArray[np.float64]:
    """``e(x)`` (module docstring) at every offset of :data:`OFFSETS` [m]."""
    tree = KDTree(kept)
    return np.concatenate([tree.query(surface + offset * normals)[0] - offset for offset in OFFSETS])


def _summary(values: NDArray[np.float64]) -> str:
    return (f"max {1e3 * values.max():4.1f} p99.9 {1e3 * np.percentile(values, 99.9):4.1f} "
            f"median {1e3 * np.median(values):5.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--first", type=int, default=10, help="first problem number (default 10)")
    parser.add_argument("--problems", type=int, default=7, help="problems per type (default 7)")
    args = parser.parse_args()
    robot, rng = franka(), np.random.default_rng(0)
    centres_all, centroids_all = [], []
    for problem in load_problems(skip=args.first - 9, per_type=args.problems):
        case = prepare_case(problem, "points", robot)
        raw = np.load(case.mapping["obstacles"][0]["file"])
        drawn = [surface_with_normals(obstacle, rng) for obstacle in case.check_obstacles]
        surface, normals = np.concatenate([s for s, _ in drawn]), np.concatenate([n for _, n in drawn])
        centres, centroids = kept_points(raw)
        centres_all.append(excesses(centres, surface, normals))
        centroids_all.append(excesses(centroids, surface, normals))
        print(f"{problem.name:22s} centres {_summary(centres_all[-1])} | centroids {_summary(centroids_all[-1])}",
              flush=True)
    print(f"{'all':22s} centres {_summary(np.concatenate(centres_all))} | "
          f"centroids {_summary(np.concatenate(centroids_all))}")


if __name__ == "__main__":
    main()
