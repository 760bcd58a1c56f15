import numpy as np
import dynfab

robot = dynfab.load_robot("panda")
planner = dynfab.FabricPlanner(robot, dynfab.PlannerConfig(
    goals=(dynfab.GoalConfig(link="panda_hand"),), obstacle_slots=1, dynamic=True))
p = planner.parameters
p.goal_position[0] = [0.5, -0.3, 0.4]
p.obstacle_radius[0] = 0.08
q, qdot = robot.default_q, np.zeros(robot.dof)
for k in range(1000):                          # 10 s at the 10 ms control period
    p.obstacle_position[0] = [0.45, 0.4 - 0.0016 * k, 0.45]   # a sphere crossing at 16 cm/s
    p.obstacle_velocity[0] = [0.0, -0.16, 0.0]
    q, qdot = planner.step(q, qdot)            # q̈ from the fabric, one control period
print("hand at", robot.link_position(q, "panda_hand").round(3))
