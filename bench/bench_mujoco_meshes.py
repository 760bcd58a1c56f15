"""Benchmark of mesh obstacles in MuJoCo (issue 20): what the convex parts cost a physics
step, beside the same Panda without obstacles and with each mesh as one convex hull.

    .venv/bin/python bench/bench_mujoco_meshes.py [--problems 5] [--repeats 200] [--json]

Scenes: MotionBenchMaker's ``kitchen`` problems 1..``--problems`` (seed 7, the Panda at each
problem's start and goal configuration, both free of the meshes by construction). Variants:

- none: the Panda alone;
- parts: the scene as dynfab builds it (:mod:`dynfab.sim.mesh_parts`: closed convex
  components as hulls, every other triangle a 1 mm prism);
- hulls: every mesh replaced by its convex hull (what one MuJoCo mesh geom per mesh collides),
  which fills the cupboard's and the counter's openings.

Per variant: the model's obstacle geoms, the time to build and compile the model, the median
CPU time (``time.thread_time``) of ``mj_forward`` (collision detection included) over the
start and goal configurations, ``--repeats`` each, as a ratio to none's; and in how many of
those free configurations MuJoCo finds a robot-obstacle contact (parts: should be 0; hulls:
the openings filled). The machine's load average is printed with the numbers.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from dynfab.benchmarks.mbm.franka import franka  # noqa: E402
from dynfab.benchmarks.mbm.scenes import generate_scene_problem, prepare_scene_case  # noqa: E402
from dynfab.geometry.shapes import Mesh  # noqa: E402
from dynfab.robots import load_robot  # noqa: E402
from dynfab.robots.builtin_meshes import builtin_collision_meshes  # noqa: E402
from dynfab.scenario.schema import scenario_from_dict  # noqa: E402
from dynfab.sim.mujoco_model import MujocoScene, SceneObstacle, build_scene  # noqa: E402


def _obstacles(mapping: dict, hulls: bool) -> list[SceneObstacle]:
    """The scene's obstacles as MuJoCo takes them; with ``hulls`` each mesh is its hull."""
    obstacles = []
    for spec in scenario_from_dict(mapping).obstacles:
        shape = spec.shape
        if hulls and isinstance(shape, Mesh):
            hull = shape.triangles.convex_hull
            shape = Mesh(hull.vertices, hull.faces, source=shape.source)
        assert spec.position is not None
        obstacles.append(SceneObstacle(shape, tuple(float(v) for v in spec.position), spec.orientation, False))
    return obstacles


def _forward_time(scene: MujocoScene, qs: list[np.ndarray], repeats: int) -> tuple[float, int]:
    """Median CPU time of one ``mj_forward`` [µs] and the configurations touching an obstacle."""
    data = mujoco.MjData(scene.model)
    samples, touching = [], 0
    for q in qs:
        data.qpos[scene.joint_qpos] = q
        mujoco.mj_forward(scene.model, data)
        geoms = {int(g) for pair in data.contact.geom[:data.ncon] for g in pair}
        touching += bool(geoms & set(scene.obstacle_of_geom))
        for _ in range(repeats):
            start = time.thread_time()
            mujoco.mj_forward(scene.model, data)
            samples.append(time.thread_time() - start)
    return statistics.median(samples) * 1e6, touching


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problems", type=int, default=5)
    parser.add_argument("--repeats", type=int, default=200)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    robot, mbm = load_robot("panda"), franka()
    meshes = builtin_collision_meshes(robot)
    rows: dict[str, dict[str, float]] = {name: {"geoms": 0, "build_ms": 0.0, "touching": 0, "configurations": 0}
                                         for name in ("none", "parts", "hulls")}
    forward: dict[str, list[float]] = {name: [] for name in rows}
    for number in range(1, args.problems + 1):
        problem = generate_scene_problem("kitchen", number, 7, mbm)
        mapping = prepare_scene_case(problem).mapping
        qs = [np.array(problem.start), np.array(problem.goal)]
        for name in rows:
            obstacles = [] if name == "none" else _obstacles(mapping, hulls=name == "hulls")
            start = time.perf_counter()
            scene = build_scene(robot, obstacles, (), meshes)
            rows[name]["build_ms"] += (time.perf_counter() - start) * 1e3 / args.problems
            rows[name]["geoms"] = sum(1 for g in scene.obstacle_of_geom if scene.model.geom_conaffinity[g])
            micros, touching = _forward_time(scene, qs, args.repeats)
            forward[name].append(micros)
            rows[name]["touching"] += touching
            rows[name]["configurations"] += len(qs)
    for name, row in rows.items():
        row["forward_us"] = statistics.median(forward[name])
        row["ratio_to_none"] = row["forward_us"] / statistics.median(forward["none"])
    load = os.getloadavg()[0]
    if args.json:
        print(json.dumps({"load": load, "rows": rows}))
        return
    print(f"MBM kitchen, {args.problems} problems (start and goal), load average {load:.1f}")
    print(f"{'variant':8} {'geoms':>6} {'build ms':>9} {'forward µs':>11} {'× none':>7} {'touching':>9}")
    for name, row in rows.items():
        print(f"{name:8} {row['geoms']:6d} {row['build_ms']:9.1f} {row['forward_us']:11.1f} "
              f"{row['ratio_to_none']:7.2f} {row['touching']:4d}/{row['configurations']}")


if __name__ == "__main__":
    main()
