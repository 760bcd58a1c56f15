"""The library without scenario files: a Panda control loop that moves its goal and an
obstacle at run time, with no rebuild.

    .venv/bin/python examples/panda_api.py
"""

import numpy as np

from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.robots import load_robot

robot = load_robot("panda")
planner = FabricPlanner(robot, PlannerConfig(goals=(GoalConfig(link="panda_hand"),), obstacle_slots=2))
print(f"built in {planner.build_time_s:.2f} s, {planner.n_instructions} SX instructions per step")

planner.parameters.goal_position[0][:] = [0.5, -0.4, 0.3]
planner.parameters.obstacle_position[0] = [0.5, -0.05, 0.45]
planner.parameters.obstacle_radius[0] = 0.12  # slot 1 keeps radius 0: inactive

q, qdot, dt = robot.default_q.copy(), np.zeros(robot.dof), 0.01
for step in range(2500):
    if step == 800:  # a new goal and a second obstacle, mid-motion
        planner.parameters.goal_position[0][:] = [0.3, 0.4, 0.6]
        planner.parameters.obstacle_position[1] = [0.45, 0.25, 0.75]
        planner.parameters.obstacle_radius[1] = 0.1
    qddot = planner.compute(q, qdot)
    q, qdot = q + qdot * dt + 0.5 * qddot * dt**2, qdot + qddot * dt

hand = np.asarray(robot.kinematics.position(q, "panda_hand")).ravel()
print("hand at", hand.round(3), "error", round(float(np.linalg.norm(hand - [0.3, 0.4, 0.6])), 4), "m")
