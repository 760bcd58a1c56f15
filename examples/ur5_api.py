"""The library with a robot as it ships: a UR5 from example-robot-data, its collision spheres
fitted to its meshes (cached), reaching a pose with the tool pointing down past a box that
is moved at run time, no rebuild.

    .venv/bin/python examples/ur5_api.py

The first run fits the spheres and compiles the planner to C (a minute; both cached).
"""

import numpy as np

import dynfab

urdf = "package://example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"
home = [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]
robot = dynfab.robot_from_urdf(urdf, "tool0", default_q=home)  # spheres fitted to its meshes once, then cached
print(f"{robot.dof} joints {robot.kinematics.joint_names}, {len(robot.collision_spheres)} spheres, "
      f"{len(robot.self_collision_pairs)} self-collision pairs")

tool = dynfab.GoalConfig(link="tool0", offset=(0.0, 0.0, 0.05))  # a point 5 cm ahead of the flange
down = dynfab.OrientationGoalConfig(link="tool0", link_axes=((0.0, 0.0, 1.0),))  # only its z axis
planner = dynfab.FabricPlanner(robot, dynfab.PlannerConfig(goals=(tool, down), shape_slots=dynfab.ShapeSlots(box=1)))
p = planner.parameters
p.goal_position[0] = [0.3, 0.4, 0.3]
p.goal_position[1] = [0.0, 0.0, -1.0]  # tool z along the world's -z
p.boxes.position[0], p.boxes.orientation[0], p.boxes.dimensions[0] = [0.45, 0.3, 0.1], [1, 0, 0, 0], [0.1, 0.1, 0.2]

q, qdot = np.array(home), np.zeros(robot.dof)
for step in range(1500):  # 15 s at the planner's 10 ms control period
    if step == 500:  # the box is pushed 10 cm, mid-motion
        p.boxes.position[0] = [0.4, 0.35, 0.1]
    q, qdot = planner.step(q, qdot)

point = robot.link_position(q, "tool0", offset=(0.0, 0.0, 0.05))
z_axis = np.asarray(robot.kinematics.rotation(q, "tool0"))[:, 2]
print("tool point at", point.round(3), "error", round(float(np.linalg.norm(point - [0.3, 0.4, 0.3])), 4), "m;",
      f"tool z tilted {np.degrees(np.arccos(-z_axis[2])):.2f} deg from straight down")
