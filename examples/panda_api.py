"""The library without scenario files: a Panda control loop that moves its goal and an
obstacle at run time, with no rebuild.

    .venv/bin/python examples/panda_api.py
"""

import numpy as np

import dynfab

robot = dynfab.load_robot("panda")
planner = dynfab.FabricPlanner(robot, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="panda_hand"),),
                                                           obstacle_slots=2))
print(f"built in {planner.build_time_s:.2f} s ({planner.backend}), {planner.n_instructions} SX instructions per step")

p = planner.parameters
p.goal_position[0] = [0.5, -0.4, 0.3]
p.obstacle_position[0] = [0.5, -0.05, 0.45]
p.obstacle_radius[0] = 0.12  # slot 1 keeps radius 0: inactive

q, qdot = robot.default_q, np.zeros(robot.dof)
for step in range(2500):  # 25 s at the planner's 10 ms control period
    if step == 800:  # a new goal and a second obstacle, mid-motion
        p.goal_position[0] = [0.3, 0.4, 0.6]
        p.obstacle_position[1] = [0.45, 0.25, 0.75]
        p.obstacle_radius[1] = 0.1
    q, qdot = planner.step(q, qdot)

hand = robot.link_position(q, "panda_hand")
print("hand at", hand.round(3), "error", round(float(np.linalg.norm(hand - [0.3, 0.4, 0.6])), 4), "m")
