"""A point cloud given to the planner at run time: a simulated depth sensor sees a wall and
the robot's own hand at 20 Hz; each cloud goes through PointCloudFeed.update_points (voxel
downsampling, the robot filtered out) and every 10 ms tick writes the nearest points.

    .venv/bin/python examples/panda_point_cloud.py
"""

import numpy as np

import dynfab
from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance, moving_spheres
from dynfab.perception.point_clouds import PointCloudFeed

robot = dynfab.load_robot("panda")
leaf = NearestSurfaceAvoidance(spheres=moving_spheres(robot))
planner = dynfab.FabricPlanner(robot, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="panda_hand"),),
                                                           leaves=(leaf,)))
planner.parameters.goal_position[0] = [0.45, -0.35, 0.35]  # past the wall's edge
feed = PointCloudFeed(robot, leaf, planner.parameters.leaves[leaf.name], voxel=0.01)

rng = np.random.default_rng(0)
y, z = np.meshgrid(np.arange(-0.2, 0.2, 0.005), np.arange(0.2, 0.8, 0.005))
wall = np.column_stack([np.full(y.size, 0.5), y.ravel() - 0.1, z.ravel()])  # x = 0.5, 40 x 60 cm


def sensor(q: np.ndarray) -> np.ndarray:
    """A noisy cloud of the wall and of the hand (which the feed must filter out), with
    some missing returns (NaN)."""
    centres = np.asarray(robot.sphere_centers(q), dtype=float).reshape(-1, 3)
    near = np.linalg.norm(centres - robot.link_position(q, "panda_hand"), axis=1) < 0.15  # the hand's spheres
    rays = rng.normal(size=(near.sum(), 20, 3))
    rays /= np.linalg.norm(rays, axis=2, keepdims=True)
    hand = (centres[near, None] + np.asarray(robot.sphere_radii)[near, None, None] * rays).reshape(-1, 3)
    points = np.concatenate([wall, hand]) + rng.normal(0.0, 0.002, (len(wall) + len(hand), 3))
    points[rng.random(len(points)) < 0.01] = np.nan
    return points


q, qdot = robot.default_q, np.zeros(robot.dof)
closest = np.inf
for step in range(1000):  # 10 s at 10 ms
    if step % 5 == 0:  # a new cloud every 50 ms
        update = feed.update_points(sensor(q), q)
    feed.write(q)
    q, qdot = planner.step(q, qdot)
    centres = np.asarray(robot.sphere_centers(q), dtype=float).reshape(-1, 3)
    gaps = np.abs(centres[:, 0] - 0.5) - np.asarray(robot.sphere_radii)
    beside = (np.abs(centres[:, 1] + 0.1) < 0.2) & (centres[:, 2] > 0.2) & (centres[:, 2] < 0.8)
    closest = min(closest, float(gaps[beside].min())) if beside.any() else closest

print(f"last cloud: {update.received} points, {update.dropped} NaN dropped, {update.on_robot} on the robot, "
      f"{update.kept} kept (voxel {update.voxel * 100:.0f} cm)")
hand = robot.link_position(q, "panda_hand")
print("hand at", hand.round(3), "error", round(float(np.linalg.norm(hand - [0.45, -0.35, 0.35])), 3), "m;",
      f"closest sphere to the wall {closest * 100:.1f} cm")
