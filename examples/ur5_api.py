"""The library with a robot as it ships: a UR5 from example-robot-data, its collision spheres
fitted to its meshes (cached), reaching a pose with the tool pointing down past a box that
is moved at run time, no rebuild.

    .venv/bin/python examples/ur5_api.py
"""

import numpy as np

from dynfab.fabric.leaves.orientation import OrientationGoalConfig
from dynfab.fabric.parameters import ShapeSlots
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.robots import robot_from_urdf
from dynfab.robots.collision_model import auto_collision_model
from dynfab.robots.mesh_paths import resolve_uri

urdf = resolve_uri("package://example-robot-data/robots/ur_description/urdf/ur5_robot.urdf", None)
collision = auto_collision_model(urdf)  # fitted on the first call (~20 s), then from ~/.cache/dynfab
home = [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]
robot = robot_from_urdf(urdf, "tool0", collision.spheres, collision.self_collision_pairs, default_q=home)
print(f"{robot.dof} joints {robot.kinematics.joint_names}, {len(robot.collision_spheres)} spheres, "
      f"{len(robot.self_collision_pairs)} self-collision pairs")

tool = GoalConfig(link="tool0", offset=(0.0, 0.0, 0.05))  # a point 5 cm ahead of the flange
down = OrientationGoalConfig(link="tool0", link_axes=((0.0, 0.0, 1.0),))  # only its z axis
planner = FabricPlanner(robot, PlannerConfig(goals=(tool, down), shape_slots=ShapeSlots(box=1)))
planner.parameters.goal_position[0][:] = [0.3, 0.4, 0.3]
planner.parameters.goal_position[1][:] = [0.0, 0.0, -1.0]  # tool z along the world's -z
box = planner.parameters.boxes
box.position[0], box.orientation[0], box.dimensions[0] = [0.45, 0.3, 0.1], [1, 0, 0, 0], [0.1, 0.1, 0.2]

q, qdot, dt = np.array(home), np.zeros(robot.dof), 0.01
for step in range(1500):
    if step == 500:  # the box is pushed 10 cm, mid-motion
        box.position[0] = [0.4, 0.35, 0.1]
    qddot = planner.compute(q, qdot)
    q, qdot = q + qdot * dt + 0.5 * qddot * dt**2, qdot + qddot * dt

point = np.asarray(robot.kinematics.position(q, "tool0", offset=(0.0, 0.0, 0.05))).ravel()
z_axis = np.asarray(robot.kinematics.rotation(q, "tool0"))[:, 2]
print("tool point at", point.round(3), "error", round(float(np.linalg.norm(point - [0.3, 0.4, 0.3])), 4), "m;",
      f"tool z tilted {np.degrees(np.arccos(-z_axis[2])):.2f} deg from straight down")
