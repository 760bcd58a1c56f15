"""Benchmark (issue 20): the cost of a 100k-point cloud in view, beside the same scene as primitives.

Scene: a table top (box 1.0 x 1.2 x 0.05 m) and a box on it (0.2 x 0.3 x 0.4 m) in front of
the Panda. As primitives: two box slots of the fabric. As a cloud: their surfaces sampled
(``dynfab.benchmarks.mbm.point_clouds.surface_points``) at the spacing that gives about
``--points`` points, with 2 mm Gaussian noise, fed through ``PointCloudFeed``
(voxel 1 cm) into the nearest-point leaf on every moving sphere.

Measured, as wall-clock medians (and p95) over ``--ticks`` ticks of a closed-loop run
(the planner's own accelerations integrated at dt 0.01 s):

- per cloud: ``update_points`` (NaN drop, voxel downsample, robot filter, KD-tree build),
  wall time and the thread's CPU time (``time.thread_time``: without the waits for a core);
- per tick: ``write(q)`` (sphere centres, one KD-tree query of all spheres, the leaf's
  parameters: :mod:`dynfab.perception.nearest_cloud_points`, compiled on ``--backend c``) and the fabric
  step ``compute(q, qdot)``, beside the primitives' step; the ratio of the cloud's tick
  (write + step) to the primitives' step;
- per tick, a scenario's feed of a ``points`` obstacle (``SurfaceFeed``, the guided fabric's
  braking leaf): as on e94d6d6 (one slot per sphere, reach without the spheres' speeds) and
  now (a far-side slot per sphere, :mod:`dynfab.geometry.cloud_far_side`, and the reach grown
  by each sphere's stopping distance), write and step each;
- per tick, the library's feed (``NearestCloudPoints``, compiled on ``--backend c``) of the same
  two leaves given ``q̇``: the reach grown by the speeds alone, then with the far side, write
  and step each and their sum against the primitives' step.

    .venv/bin/python bench/bench_point_clouds.py [--points 100000] [--ticks 1000] [--backend c|vm]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

TABLE = {"type": "box", "size": [1.0, 1.2, 0.05], "position": [0.6, 0.0, -0.025], "orientation": [1, 0, 0, 0]}
BLOCK = {"type": "box", "size": [0.2, 0.3, 0.4], "position": [0.55, 0.25, 0.2], "orientation": [1, 0, 0, 0]}
Q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
GOAL = [0.5, -0.3, 0.25]


def scene_cloud(count: int, rng: np.random.Generator) -> np.ndarray:
    """About ``count`` noisy points on the table's and the block's surfaces."""
    from dynfab.benchmarks.mbm.point_clouds import surface_points

    area = sum(2 * (a * b + b * c + a * c) for a, b, c in (TABLE["size"], BLOCK["size"]))
    spacing = float(np.sqrt(area / count))
    points = np.concatenate([surface_points(box, spacing) for box in (TABLE, BLOCK)])
    return points + rng.normal(0.0, 0.002, points.shape)


def closed_loop(planner, ticks: int, before_step=None) -> tuple[list[float], list[float]]:
    """Run ``ticks`` ticks; per tick the time of ``before_step(q, qdot)`` and of the step [µs]."""
    q, qdot = Q0.copy(), np.zeros(7)
    feed_times, step_times = [], []
    for _ in range(ticks):
        start = time.perf_counter()
        if before_step is not None:
            before_step(q, qdot)
        middle = time.perf_counter()
        qddot = planner.compute(q, qdot)
        end = time.perf_counter()
        feed_times.append((middle - start) * 1e6)
        step_times.append((end - middle) * 1e6)
        qdot = qdot + 0.01 * np.asarray(qddot)
        q = q + 0.01 * qdot
    return feed_times, step_times


def summary(times: list[float]) -> str:
    return f"median {statistics.median(times):8.1f} µs   p95 {np.percentile(times, 95):8.1f} µs"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=100_000)
    parser.add_argument("--ticks", type=int, default=1000)
    parser.add_argument("--backend", choices=("c", "vm"), default="c")
    args = parser.parse_args()

    from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance, moving_spheres
    from dynfab.fabric.parameters import ShapeSlots
    from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
    from dynfab.perception.point_clouds import PointCloudFeed
    from dynfab.robots.builtin import load_robot

    print(f"load average {os.getloadavg()[0]:.1f}, backend {args.backend}, {args.ticks} ticks")
    robot = load_robot("panda")
    goals = (GoalConfig(link="panda_hand"),)

    start = time.perf_counter()
    shapes = FabricPlanner(robot, PlannerConfig(goals=goals, shape_slots=ShapeSlots(box=2), backend=args.backend))
    print(f"primitives planner built in {time.perf_counter() - start:.1f} s")
    shapes.parameters.goal_position[0][:] = GOAL
    for row, box in enumerate((TABLE, BLOCK)):
        shapes.parameters.boxes.position[row] = box["position"]
        shapes.parameters.boxes.orientation[row] = box["orientation"]
        shapes.parameters.boxes.dimensions[row] = box["size"]

    leaf = NearestSurfaceAvoidance(spheres=moving_spheres(robot))
    start = time.perf_counter()
    cloudy = FabricPlanner(robot, PlannerConfig(goals=goals, leaves=(leaf,), backend=args.backend))
    print(f"cloud planner built in {time.perf_counter() - start:.1f} s ({len(leaf.spheres)} spheres in the leaf)")
    cloudy.parameters.goal_position[0][:] = GOAL
    feed = PointCloudFeed(robot, leaf, cloudy.parameters.leaves[leaf.name], backend=args.backend)

    rng = np.random.default_rng(0)
    raw = scene_cloud(args.points, rng)
    updates, update_cpus = [], []
    for _ in range(20):
        start, cpu = time.perf_counter(), time.thread_time()
        update = feed.update_points(raw, Q0)
        feed.cloud.tree  # the KD-tree is built here, as the first write would
        update_cpus.append((time.thread_time() - cpu) * 1e3)
        updates.append((time.perf_counter() - start) * 1e3)
    print(f"cloud: {len(raw)} raw points -> {update.kept} kept (voxel {update.voxel * 100:.0f} cm, "
          f"{update.on_robot} on the robot)")
    print(f"per cloud, update_points:     median {statistics.median(updates):8.1f} ms   "
          f"p95 {np.percentile(updates, 95):8.1f} ms   (CPU median {statistics.median(update_cpus):.1f} ms)")

    _, primitive_steps = closed_loop(shapes, args.ticks)
    feed_times, cloud_steps = closed_loop(cloudy, args.ticks, lambda q, qdot: feed.write(q))
    ticks = [a + b for a, b in zip(feed_times, cloud_steps)]
    print(f"per tick, primitives step:    {summary(primitive_steps)}")
    print(f"per tick, cloud write(q):     {summary(feed_times)}")
    print(f"per tick, cloud step:         {summary(cloud_steps)}")
    print(f"per tick, cloud write + step: {summary(ticks)}")
    print(f"ratio cloud step / primitives step:         {statistics.median(cloud_steps) / statistics.median(primitive_steps):.2f}")
    print(f"ratio cloud (write + step) / primitives step: {statistics.median(ticks) / statistics.median(primitive_steps):.2f}")
    scenario_feed(robot, goals, feed.cloud, args, statistics.median(primitive_steps))


def scenario_feed(robot, goals, cloud, args: argparse.Namespace, primitive_step: float) -> None:
    """A scenario's feed of ``cloud`` (module docstring), as on e94d6d6 and now, and the
    library's per-tick feed (``NearestCloudPoints``) of the same leaves given ``q̇``: its reach
    alone, then with the far side; each tick against the primitives' median step
    ``primitive_step`` [µs]."""
    from dynfab.fabric.leaves.barrier import Barrier
    from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance, moving_spheres
    from dynfab.fabric.planner import FabricPlanner, PlannerConfig
    from dynfab.perception.nearest_cloud_points import NearestCloudPoints
    from dynfab.perception.surfaces import SurfaceFeed
    from dynfab.scenario import guided_controller as guided

    barrier = Barrier(geometry_gain=5.0, energy_gain=guided.GUIDED_SURFACE_ENERGY, horizon=guided.GUIDED_OBSTACLE_RANGE,
                      offset=guided.GUIDED_OBSTACLE_BUFFER, braking=guided.GUIDED_BRAKING_DECELERATION)
    medians = {}
    for far_side in (False, True):
        leaf = NearestSurfaceAvoidance(spheres=moving_spheres(robot), barrier=barrier, far_side=far_side)
        start = time.perf_counter()
        planner = FabricPlanner(robot, PlannerConfig(goals=goals, leaves=(leaf,), backend=args.backend))
        planner.parameters.goal_position[0][:] = GOAL
        print(f"scenario planner ({len(leaf.slots)} slots) built in {time.perf_counter() - start:.1f} s")
        feed = SurfaceFeed(robot, leaf, planner.parameters.leaves[leaf.name])
        write = ((lambda q, qdot: feed.write(q, [], [cloud], qdot=qdot)) if far_side
                 else (lambda q, qdot: feed.write(q, [], [cloud])))
        writes, steps = closed_loop(planner, args.ticks, write)
        name = "far side + speeds" if far_side else "as on e94d6d6   "
        print(f"per tick, scenario feed, {name}: write {summary(writes)}")
        print(f"per tick, scenario feed, {name}: step  {summary(steps)}")
        medians[far_side] = statistics.median([a + b for a, b in zip(writes, steps)])
        library = NearestCloudPoints(robot, leaf, planner.parameters.leaves[leaf.name], args.backend)
        writes, steps = closed_loop(planner, args.ticks, lambda q, qdot: library.write(q, cloud, qdot))
        name = "far side + speeds" if far_side else "speeds only     "
        print(f"per tick, library feed,  {name}: write {summary(writes)}")
        print(f"per tick, library feed,  {name}: step  {summary(steps)}")
        ticks = [a + b for a, b in zip(writes, steps)]
        print(f"per tick, library feed,  {name}: write + step {summary(ticks)}; "
              f"/ primitives step {statistics.median(ticks) / primitive_step:.2f}")
    print(f"ratio scenario tick (write + step), now / e94d6d6: {medians[True] / medians[False]:.2f}")


if __name__ == "__main__":
    main()
