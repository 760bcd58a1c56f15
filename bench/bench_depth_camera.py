"""Benchmark of the depth camera (issue 20, item 4): a depth frame to world points with the
robot filtered out, to the planner's cloud and its velocities, beside the same scene given
to the planner as primitives.

    .venv/bin/python bench/bench_depth_camera.py [--frames 40] [--json]

The scene is examples/panda_spheres.yaml (the Panda at its start among four spheres) plus a
ball (radius 8 cm) moving at 0.5 m/s above them (so the velocity tracker has something to
follow), seen by one camera (60° vertical field of view, σ = 2 mm depth noise) in front of
the robot, bare (only the spheres, the ball and the robot return depth) and on a floor
(every pixel returns depth: the most points). ``--frames`` successive frames of the moving
ball are rendered first (30 Hz); per resolution, medians over them of

- render: MuJoCo's offscreen depth render (``update_scene`` + ``render``, far plane → inf);
- noise: the simulated sensor's Gaussian noise (:meth:`DepthCamera.sensed`), what a real
  sensor's image comes with: not part of the spans below, which start from the noisy image;
- frame: robot filter, back-projection and the arrivals (pixels that came nearer since the
  previous frame) (:meth:`DepthCamera.frame`), render and noise excluded;
- to the planner: the frame's points into the point-cloud feed the planner reads
  (``PointCloudFeed.update_points``: 1 cm voxels, and its KD-tree, built at the first query),
  after the frame;
- velocities: the cluster tracker's update from the frame's arrivals (what the camera feed
  runs), and, for comparison, the same tracker clustering every point (no arrivals given,
  as before the arrivals: the 22-66 ms with a floor);
- frame -> representation: frame and to the planner in one timed span (issue 20's "a depth
  frame becomes the planner's representation");
- camera tick: frame, to the planner and velocities in one timed span (what the camera feed
  does per frame: frame -> cloud -> KD-tree -> velocities);

the last two as wall time and as the thread's CPU time (``time.thread_time``: what the work
costs, without the waits for a core that a loaded machine adds), without and with the camera
cropped to the Panda's workspace ball (``robot_workspace(robot, 0.3)``: its reach bound
plus 0.3 m; ``camera.workspace_margin: 0.3`` in a scenario), beside the primitives' update:
writing the same spheres into the planner's parameters (``FabricController.retarget``, what
the planner needs per tick when the scene is given as primitives), as a ratio. Targets: a
640 x 480 frame in <= 15 ms, 320 x 240 in <= 5 ms. The machine's load average is printed
with the numbers.
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
from dynfab.perception.depth_camera import CameraFrame, DepthCamera  # noqa: E402
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


#: The moving ball: its radius [m], start [m], velocity [m/s]; the frames' rate [Hz].
BALL_RADIUS, BALL_START, BALL_VELOCITY, RATE = 0.08, np.array([0.6, -0.8, 0.9]), np.array([0.0, 0.5, 0.0]), 30.0


def timed_ms(call: Callable[[], object], repeats: int) -> tuple[float, float]:
    """Median and minimum wall time of ``call`` [ms] (the minimum: when the shared cores were ours)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return 1e3 * statistics.median(times), 1e3 * min(times)


def timed_frames(step: Callable[[int], object], count: int) -> tuple[float, float, float]:
    """Median and minimum wall time and median CPU time of this thread of ``step(k)`` for the
    frames ``k = 0 .. count − 1`` in order [ms]."""
    walls, cpus = [], []
    for k in range(count):
        wall, cpu = time.perf_counter(), time.thread_time()
        step(k)
        cpus.append(time.thread_time() - cpu)
        walls.append(time.perf_counter() - wall)
    return 1e3 * statistics.median(walls), 1e3 * min(walls), 1e3 * statistics.median(cpus)


def representation(camera: DepthCamera, feed: PointCloudFeed, depth: np.ndarray, q: np.ndarray,
                   t: float) -> CameraFrame:
    """A depth frame into the planner's representation: the frame, its points into the feed's
    cloud, the cloud's KD-tree."""
    frame = camera.frame(t, depth, q)
    feed.update_points(frame.points, None)
    feed.cloud.tree
    return frame


def camera_tick(camera: DepthCamera, feed: PointCloudFeed, tracker: ClusterTracker, depth: np.ndarray,
                q: np.ndarray, t: float) -> None:
    """What the camera feed does per frame: the representation, then the velocities."""
    frame = representation(camera, feed, depth, q, t)
    tracker.update(t, frame.points, frame.arrived)


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


def ball_depths(renderer: MujocoDepthRenderer, scene: object, data: object, count: int) -> list[np.ndarray]:
    """``count`` depth images of the ball moving at ``RATE``."""
    depths = []
    for k in range(count):
        data.mocap_pos[scene.mocap[0]] = BALL_START + BALL_VELOCITY * k / RATE
        mujoco.mj_forward(scene.model, data)
        depths.append(renderer.render(data))
    return depths


def camera_rows(floor: bool, frames: int) -> list[dict]:
    scenario = load_scenario(SCENE)
    robot = load_robot("panda")
    feed = cloud_feed(robot)
    q = np.array(scenario.initial_state.q)
    obstacles = [SceneObstacle(Sphere(o.radius), tuple(o.position), IDENTITY, False) for o in scenario.obstacles]
    obstacles.append(SceneObstacle(Sphere(BALL_RADIUS), tuple(BALL_START), IDENTITY, True))
    if floor:
        obstacles.append(SceneObstacle(Box((6.0, 6.0, 0.1)), (0.0, 0.0, -0.05), IDENTITY, False))
    workspace = robot_workspace(robot, 0.3)
    times = np.arange(frames) / RATE
    rows = []
    for width, height, target in RESOLUTIONS:
        spec = CameraSpec(position=(1.6, -1.4, 1.3), look_at=(0.2, -0.2, 0.35), width=width, height=height,
                          fov=60.0, noise=0.002, rate=RATE)
        scene = build_scene(robot, obstacles, cameras=[spec])
        data = mujoco.MjData(scene.model)
        data.qpos[scene.joint_qpos] = q
        mujoco.mj_forward(scene.model, data)
        renderer = MujocoDepthRenderer(scene.model, spec)
        clean = ball_depths(renderer, scene, data, frames)
        render = timed_ms(lambda: renderer.render(data), frames)
        renderer.close()
        sensor, depths = DepthCamera(spec, robot), []
        noise_ms = timed_frames(lambda k: depths.append(sensor.sensed(clean[k])), frames)
        camera = DepthCamera(spec, robot)
        frame_ms = timed_frames(lambda k: camera.frame(times[k], depths[k], q), frames)
        probe = DepthCamera(spec, robot)
        seen = [probe.frame(times[k], depths[k], q) for k in range(frames)]
        clouds = []
        for frame in seen:
            feed.update_points(frame.points, None)
            clouds.append(np.array(feed.cloud.points))
        tracker, every = ClusterTracker(), ClusterTracker()
        row = {
            "resolution": f"{width}x{height}", "floor": floor, "target_ms": target,
            "returns": int(np.isfinite(depths[-1]).sum()), "points": len(seen[-1].points),
            "robot_pixels": seen[-1].robot_points, "arrived": int(statistics.median(f.arrived.sum() for f in seen)),
            "render_ms": render, "noise_ms": noise_ms, "frame_ms": frame_ms,
            "to_planner_ms": timed_frames(lambda k: (feed.update_points(seen[k].points, None), feed.cloud.tree),
                                          frames),
            "kept": len(feed.cloud.points),
            "velocities_ms": timed_frames(lambda k: tracker.update(times[k], seen[k].points, seen[k].arrived), frames),
            "ball_velocity": [[round(float(v), 3) for v in ball.velocity] for ball in tracker.moving(0.1)],
            "velocities_all_points_ms": timed_frames(lambda k: every.update(times[k], clouds[k]), frames),
        }
        for crop in (None, workspace):
            suffix = "" if crop is None else "_cropped"
            camera = DepthCamera(spec, robot, workspace=crop)
            row["representation_ms" + suffix] = timed_frames(
                lambda k: representation(camera, feed, depths[k], q, times[k]), frames)
            camera, tracker = DepthCamera(spec, robot, workspace=crop), ClusterTracker()
            row["tick_ms" + suffix] = timed_frames(
                lambda k: camera_tick(camera, feed, tracker, depths[k], q, times[k]), frames)
            row["kept" + suffix] = len(feed.cloud.points)
            row["points" + suffix] = len(camera.frame(times[-1] + 1.0, depths[-1], q).points)
        rows.append(row)
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
    print(f"depth camera -> world points, robot filtered, velocities (Panda, examples/panda_spheres.yaml and a ball "
          f"at 0.5 m/s); {result['cores']} cores, load average {load_before[0]:.2f} before, {load_after[0]:.2f} after; "
          f"MUJOCO_GL={result['mujoco_gl']}; medians of {args.frames} frames")
    print(f"primitives' update (4 spheres + goal written, FabricController.retarget): {1e3 * primitives:.1f} µs")
    print(f"{'image':>8} {'floor':>5} {'points':>7} {'arrived':>7} {'render ms':>13} {'noise ms':>13} "
          f"{'frame ms':>13} {'to planner ms':>13} {'velocities ms':>13} {'every point ms':>14}  (CPU ms: noise, "
          f"frame, to planner, velocities, every point) ball velocity")
    for row in rows:
        keys = ("noise_ms", "frame_ms", "to_planner_ms", "velocities_ms", "velocities_all_points_ms")
        cells = " ".join(f"{row[key][0]:6.2f} ({row[key][1]:5.2f})" for key in ("render_ms",) + keys)
        cells += "  (" + ", ".join(f"{row[key][2]:.2f}" for key in keys) + ")"
        print(f"{row['resolution']:>8} {'yes' if row['floor'] else 'no':>5} {row['points']:>7} {row['arrived']:>7} "
              f"{cells} {row['ball_velocity']}")
    print()
    print("frame -> representation (frame + update_points + KD-tree) and camera tick (the same + velocities), "
          "render and the simulated noise excluded: wall median (min), CPU median; ratio: wall median over the primitives' update")
    print(f"{'image':>8} {'floor':>5} {'crop':>5} {'points':>7} {'kept':>7} {'span':>14} {'wall ms':>14} "
          f"{'cpu ms':>7} {'target':>7} {'wall':>5} {'cpu':>5} {'ratio':>7}")
    for row in rows:
        for crop, suffix in ((False, ""), (True, "_cropped")):
            for span, key in (("representation", "representation_ms"), ("camera tick", "tick_ms")):
                wall, low, cpu = row[key + suffix]
                verdicts = ["ok" if value <= row["target_ms"] else "MISS" for value in (wall, cpu)]
                print(f"{row['resolution']:>8} {'yes' if row['floor'] else 'no':>5} {'yes' if crop else 'no':>5} "
                      f"{row['points' + suffix]:>7} {row['kept' + suffix]:>7} {span:>14} {wall:6.2f} ({low:5.2f}) "
                      f"{cpu:7.2f} {row['target_ms']:>7.0f} {verdicts[0]:>5} {verdicts[1]:>5} "
                      f"{wall / primitives:>6.0f}x")
    print("wall median (minimum) per frame, CPU median in brackets. render: MuJoCo offscreen depth; noise: the "
          "simulated sensor's (excluded from every span: a real sensor's image has it); frame: robot filter + "
          "back-projection + arrivals (render and noise excluded); to planner: PointCloudFeed.update_points "
          "of the frame's points and its KD-tree; velocities: ClusterTracker.update from the frame's arrivals (the camera feed's); every point: "
          "the same tracker clustering every point of the cloud (no arrivals); ball velocity: the tracker's moving "
          "clusters at the last frame (truth [0, 0.5, 0])")

if __name__ == "__main__":
    main()
