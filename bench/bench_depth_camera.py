"""Benchmark of the depth camera (issue 20, item 4): a depth frame to world points with the
robot filtered out, beside the same scene given to the planner as primitives.

    .venv/bin/python bench/bench_depth_camera.py [--frames 40] [--json]

The scene is examples/panda_spheres.yaml (the Panda at its start among four spheres), seen
by one camera (60° vertical field of view, σ = 2 mm depth noise) in front of the robot, bare
(only the spheres and the robot return depth) and on a floor (every pixel returns depth: the
most points). Per resolution, medians over ``--frames`` frames of

- render: MuJoCo's offscreen depth render (``update_scene`` + ``render``, far plane → inf);
- frame: noise, robot filter, back-projection (:meth:`DepthCamera.frame`), render excluded;
- render + frame: the two together;
- velocities: the cluster tracker's update on the frame's points (3 cm voxels);
- to the planner: the frame's points into the point-cloud feed the planner reads
  (``PointCloudFeed.update_points``: 1 cm voxels, and its KD-tree, built at the first query),
  after the frame;
- frame -> representation: frame and to the planner in one timed span, a new frame each time
  (issue 20's "a depth frame becomes the planner's representation"), as wall time and as
  the thread's CPU time (``time.thread_time``: what the work costs, without the waits for a
  core that a loaded machine adds); and the same with the camera cropped to the Panda's
  workspace ball (``robot_workspace(robot, 0.3)``: its reach bound plus 0.3 m, the
  nearest-point leaf's 0.2 m range and 0.1 m more);

beside the primitives' update: writing the same four spheres into the planner's parameters
(``FabricController.retarget``, what the planner needs per tick when the scene is given as
primitives), as a ratio. Targets: a 640 x 480 frame in <= 15 ms, 320 x 240 in <= 5 ms.
The machine's load average is printed with the numbers.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("DYNFAB_BACKEND", "vm")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from dynfab.geometry.shapes import Box, Sphere  # noqa: E402
from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance, moving_spheres  # noqa: E402
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig  # noqa: E402
from dynfab.perception.camera_spec import CameraSpec  # noqa: E402
from dynfab.perception.depth_camera import DepthCamera  # noqa: E402
from dynfab.perception.motion_tracks import ClusterTracker  # noqa: E402
from dynfab.perception.point_clouds import PointCloudFeed  # noqa: E402
from dynfab.perception.workspace import robot_workspace  # noqa: E402
from dynfab.robots import load_robot  # noqa: E402
from dynfab.scenario.controllers import make_controller  # noqa: E402
from dynfab.scenario.references import scenario_references  # noqa: E402
from dynfab.scenario.schema import load_scenario  # noqa: E402
from dynfab.sim.depth_render import MujocoDepthRenderer  # noqa: E402
from dynfab.sim.mujoco_model import SceneObstacle, build_scene  # noqa: E402

SCENE = Path(__file__).resolve().parent.parent / "examples" / "panda_spheres.yaml"
RESOLUTIONS = ((640, 480, 15.0), (320, 240, 5.0))
IDENTITY = (1.0, 0.0, 0.0, 0.0)


def timed_ms(call: Callable[[], object], repeats: int) -> tuple[float, float]:
    """Median and minimum wall time of ``call`` [ms] (the minimum: when the shared cores were ours)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return 1e3 * statistics.median(times), 1e3 * min(times)


def timed_cpu_ms(call: Callable[[], object], repeats: int) -> tuple[float, float, float]:
    """Median and minimum wall time and median CPU time of this thread of ``call`` [ms]."""
    walls, cpus = [], []
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.thread_time()
        call()
        cpus.append(time.thread_time() - cpu)
        walls.append(time.perf_counter() - wall)
    return 1e3 * statistics.median(walls), 1e3 * min(walls), 1e3 * statistics.median(cpus)


def representation(camera: DepthCamera, feed: PointCloudFeed, depth: np.ndarray, q: np.ndarray) -> None:
    """A depth frame into the planner's representation: the frame, its points into the feed's
    cloud, the cloud's KD-tree."""
    feed.update_points(camera.frame(0.0, depth, q).points, None)
    feed.cloud.tree


def primitives_ms(repeats: int) -> float:
    """The primitives' update: every goal and sphere of the scene written at once."""
    scenario = load_scenario(SCENE)
    robot = load_robot("panda")
    controller = make_controller(scenario, robot, scenario_references(scenario, robot))
    return timed_ms(lambda: controller.retarget(controller.references, 0.5), repeats)[0]


def cloud_feed(robot: object) -> PointCloudFeed:
    """The feed of a planner's nearest-point leaf (the planner itself is not called)."""
    leaf = NearestSurfaceAvoidance(spheres=moving_spheres(robot))
    planner = FabricPlanner(robot, PlannerConfig(goals=(GoalConfig(link="panda_hand"),), leaves=(leaf,)))
    return PointCloudFeed(robot, leaf, planner.parameters.leaves[leaf.name])


def camera_rows(floor: bool, frames: int) -> list[dict]:
    scenario = load_scenario(SCENE)
    robot = load_robot("panda")
    feed = cloud_feed(robot)
    q = np.array(scenario.initial_state.q)
    obstacles = [SceneObstacle(Sphere(o.radius), tuple(o.position), IDENTITY, False) for o in scenario.obstacles]
    if floor:
        obstacles.append(SceneObstacle(Box((6.0, 6.0, 0.1)), (0.0, 0.0, -0.05), IDENTITY, False))
    rows = []
    for width, height, target in RESOLUTIONS:
        spec = CameraSpec(position=(1.6, -1.4, 1.3), look_at=(0.2, -0.2, 0.35), width=width, height=height,
                          fov=60.0, noise=0.002)
        scene = build_scene(robot, obstacles, cameras=[spec])
        data = mujoco.MjData(scene.model)
        data.qpos[scene.joint_qpos] = q
        mujoco.mj_forward(scene.model, data)
        renderer = MujocoDepthRenderer(scene.model, spec)
        camera = DepthCamera(spec, robot)
        depth = renderer.render(data)
        renderer.render(data)  # warm
        frame = camera.frame(0.0, depth, q)
        cropped = DepthCamera(spec, robot, workspace=robot_workspace(robot, 0.3))
        cropped_points = len(cropped.frame(0.0, depth, q).points)
        tracker = ClusterTracker()
        clock = iter(np.arange(10 * frames) / 30.0)
        rows.append({
            "resolution": f"{width}x{height}", "floor": floor, "target_ms": target,
            "returns": int(np.isfinite(depth).sum()), "points": len(frame.points), "robot_pixels": frame.robot_points,
            "render_ms": timed_ms(lambda: renderer.render(data), frames),
            "frame_ms": timed_ms(lambda: camera.frame(0.0, depth, q), frames),
            "render_and_frame_ms": timed_ms(lambda: camera.frame(0.0, renderer.render(data), q), frames),
            "velocities_ms": timed_ms(lambda: tracker.update(float(next(clock)), frame.points), frames),
            "to_planner_ms": timed_ms(lambda: (feed.update_points(frame.points, None), feed.cloud.tree), frames),
            "representation_ms": timed_cpu_ms(lambda: representation(camera, feed, depth, q), frames),
            "kept": len(feed.cloud.points),
            "cropped_points": cropped_points,
            "cropped_representation_ms": timed_cpu_ms(lambda: representation(cropped, feed, depth, q), frames),
            "cropped_kept": len(feed.cloud.points),
        })
        renderer.close()
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    load_before = os.getloadavg()
    rows = camera_rows(False, args.frames) + camera_rows(True, args.frames)
    primitives = primitives_ms(2000)
    load_after = os.getloadavg()
    result = {"cores": os.cpu_count(), "load_before": load_before, "load_after": load_after,
              "mujoco_gl": os.environ["MUJOCO_GL"], "primitives_update_ms": primitives, "rows": rows}
    if args.json:
        print(json.dumps(result, indent=1))
        return
    print(f"depth camera -> world points, robot filtered (Panda, examples/panda_spheres.yaml); "
          f"{result['cores']} cores, load average {load_before[0]:.2f} before, {load_after[0]:.2f} after; "
          f"MUJOCO_GL={result['mujoco_gl']}; medians of {args.frames} frames")
    print(f"primitives' update (4 spheres + goal written, FabricController.retarget): {1e3 * primitives:.1f} µs")
    print(f"{'image':>8} {'floor':>5} {'returns':>7} {'points':>7} {'robot':>6} {'render ms':>12} {'frame ms':>12} "
          f"{'both ms':>12} {'target':>9} {'frame/prim':>10} {'velocities ms':>14} {'to planner ms':>14}")
    for row in rows:
        ratio = row["frame_ms"][0] / primitives
        ok = "ok" if row["frame_ms"][0] <= row["target_ms"] else "MISS"
        cells = " ".join(f"{row[key][0]:6.2f} ({row[key][1]:5.2f})" for key in
                         ("render_ms", "frame_ms", "render_and_frame_ms"))
        print(f"{row['resolution']:>8} {'yes' if row['floor'] else 'no':>5} {row['returns']:>7} {row['points']:>7} "
              f"{row['robot_pixels']:>6} {cells} {row['target_ms']:>4.0f} {ok:>4} {ratio:>9.0f}x "
              f"{row['velocities_ms'][0]:6.2f} ({row['velocities_ms'][1]:5.2f}) "
              f"{row['to_planner_ms'][0]:6.2f} ({row['to_planner_ms'][1]:5.2f})")
    print()
    print("frame -> representation (frame + update_points + KD-tree, render excluded): wall median (min), "
          "CPU median; ratio: wall median over the primitives' update")
    print(f"{'image':>8} {'floor':>5} {'crop':>5} {'points':>7} {'kept':>7} {'wall ms':>14} {'cpu ms':>7} "
          f"{'target':>7} {'wall':>5} {'cpu':>5} {'ratio':>7}")
    for row in rows:
        for crop, key, points, kept in ((False, "representation_ms", "points", "kept"),
                                        (True, "cropped_representation_ms", "cropped_points", "cropped_kept")):
            wall, low, cpu = row[key]
            verdicts = ["ok" if value <= row["target_ms"] else "MISS" for value in (wall, cpu)]
            print(f"{row['resolution']:>8} {'yes' if row['floor'] else 'no':>5} {'yes' if crop else 'no':>5} "
                  f"{row[points]:>7} {row[kept]:>7} {wall:6.2f} ({low:5.2f}) {cpu:7.2f} {row['target_ms']:>7.0f} "
                  f"{verdicts[0]:>5} {verdicts[1]:>5} {wall / primitives:>6.0f}x")
    print("median (minimum) per frame. render: MuJoCo offscreen depth; frame: noise + robot filter + "
          "back-projection (render excluded; the target applies to it); both: render included; "
          "velocities: ClusterTracker.update on the frame's points; to planner: PointCloudFeed.update_points of "
          "the frame's points and its KD-tree (after the frame); frame/prim: frame over the primitives' update")


if __name__ == "__main__":
    main()
