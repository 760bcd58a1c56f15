"""Mesh obstacles: the checker's distance grid built vs loaded from its disk cache, and the
fabric's per-tick nearest points (coal), on MotionBenchMaker's kitchen and table_bars meshes.

    python bench/bench_meshes.py

Prints per mesh: triangles, grid build [s], grid load from the cache [s] and their ratio;
the grid's exact band (:mod:`dynfab.geometry.triangle_band`) compiled and in numpy [s] and
their ratio; nearest points of 30 points 0-20 cm from the surface (what robot spheres in
reach ask each tick) [ms], median of 21.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

from dynfab.benchmarks.mbm.scene_configs import data_root
from dynfab.geometry.distance_grid import BAND, distance_grid
from dynfab.geometry.mesh_distance import nearest_on_mesh
from dynfab.geometry.mesh_files import read_mesh
from dynfab.geometry.triangle_band import numpy_triangle_band, triangle_band


def _median_ms(call, repeats: int = 21) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return 1e3 * float(np.median(times))


def main() -> None:
    rng = np.random.default_rng(0)
    folder = data_root() / "motion_bench_maker/configs/scenes"
    print("| mesh | triangles | grid build [s] | grid from cache [s] | ratio | exact band compiled / numpy [s] | ratio "
          "| nearest points, 30 points [ms] |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as cache:
        for path in sorted(folder.glob("*/meshes/*.stl")):
            mesh = read_mesh(path, (1.0, 1.0, 1.0))
            start = time.perf_counter()
            distance_grid(mesh, cache=Path(cache))
            built = time.perf_counter() - start
            start = time.perf_counter()
            distance_grid(read_mesh(path, (1.0, 1.0, 1.0)), cache=Path(cache))
            loaded = time.perf_counter() - start
            grid = distance_grid(mesh, cache=Path(cache))
            triangles, shape = mesh.vertices[mesh.faces], grid.values.shape
            start = time.perf_counter()
            triangle_band(triangles, grid.origin, grid.pitch, shape, BAND)
            compiled = time.perf_counter() - start
            start = time.perf_counter()
            numpy_triangle_band(triangles, grid.origin, grid.pitch, shape, BAND)
            in_numpy = time.perf_counter() - start
            surface, _ = trimesh.sample.sample_surface(mesh.triangles, 30, seed=1)
            direction = rng.normal(size=(30, 3))
            points = surface + direction / np.linalg.norm(direction, axis=1)[:, None] * rng.uniform(0, 0.2, (30, 1))
            nearest = _median_ms(lambda: nearest_on_mesh(mesh, points, max_distance=0.25))
            print(f"| {path.parent.parent.name}/{path.name} | {len(mesh.faces)} | {built:.2f} | {loaded:.3f} | "
                  f"{built / loaded:.0f} | {compiled:.2f} / {in_numpy:.2f} | {in_numpy / compiled:.0f} | {nearest:.2f} |")


if __name__ == "__main__":
    main()
