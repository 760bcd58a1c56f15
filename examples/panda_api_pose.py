"""The library without scenario files: a Panda brings a tool point (0.1 m in front of its
hand) to a target while a full orientation goal turns the hand to point down; halfway
the target rotation turns by 90° about the world z, written at run time, no rebuild.

    .venv/bin/python examples/panda_api_pose.py
"""

import numpy as np

import dynfab
from dynfab.geometry.orientation import rotation_angle

TOOL = (0.0, 0.0, 0.1)  # the tool centre point in the hand frame [m]
robot = dynfab.load_robot("panda")
position = dynfab.GoalConfig(link="panda_hand", offset=TOOL)  # the primary goal: drives speed control
orientation = dynfab.OrientationGoalConfig(link="panda_hand")  # all three hand axes
planner = dynfab.FabricPlanner(robot, dynfab.PlannerConfig(goals=(position, orientation)))

hand_down = np.diag([1.0, -1.0, -1.0])
turned = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])  # 90° about z, still down
planner.parameters.goal_position[0] = [0.5, -0.2, 0.3]
planner.parameters.goal_position[1] = orientation.target(hand_down)

q, qdot = robot.default_q, np.zeros(robot.dof)
for step in range(1600):  # 16 s at the planner's 10 ms control period
    if step == 800:
        planner.parameters.goal_position[1] = orientation.target(turned)
    q, qdot = planner.step(q, qdot)

tool = robot.link_position(q, "panda_hand", offset=TOOL)
angle = rotation_angle(np.asarray(robot.kinematics.rotation(q, "panda_hand")), turned)
print("tool at", tool.round(3), "orientation error", f"{float(angle):.2e} rad")
