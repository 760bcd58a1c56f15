"""Connecting dynfab to a velocity-controlled robot: a Panda in MuJoCo, with Franka's
identified inertias, stands in for the real arm.

The planner runs at 100 Hz and returns joint accelerations; the robot's controller runs at
1 kHz and takes joint velocities q̇_d [rad/s] (a velocity interface: UR's speedj,
Franka's joint velocity control).
dynfab.sim.control_interfaces turns one into the other.

    .venv/bin/python examples/mujoco_velocity_control.py
"""

import mujoco
import numpy as np

from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.robots import load_robot
from dynfab.sim.control_interfaces import SetpointIntegrator, VelocityInterface
from dynfab.sim.mujoco_drives import JointDrive
from dynfab.sim.mujoco_model import build_scene

GOAL = [0.5, -0.4, 0.3]
robot = load_robot("panda")
planner = FabricPlanner(robot, PlannerConfig(goals=(GoalConfig(link="panda_hand"),)))
planner.parameters.goal_position[0][:] = GOAL

scene = build_scene(robot)  # the "robot": MuJoCo physics at 1 kHz
data = mujoco.MjData(scene.model)
data.qpos[:] = robot.default_q
robot_controller = JointDrive(scene, data, "velocity", servo_period=0.001)  # the arm's own velocity controller

setpoints = SetpointIntegrator(servo_period=0.001)
interface = VelocityInterface()
setpoints.reset(data.qpos, data.qvel)
for tick in range(5000):  # 5 s
    q, qdot = data.qpos.copy(), data.qvel.copy()  # the measured joint state
    if tick % 10 == 0:  # the planner, every 10 ms
        setpoints.hold(planner.compute(q, qdot))
    command = interface.command(setpoints.advance(), q, qdot)  # every 1 ms
    mujoco.mj_step1(scene.model, data)
    robot_controller.apply(command, q, qdot)  # on a real robot: send `command` to it
    mujoco.mj_step2(scene.model, data)

hand = np.asarray(robot.kinematics.position(data.qpos, "panda_hand")).ravel()
print(f"velocity control: hand at {hand.round(3)}, error {np.linalg.norm(hand - GOAL):.4f} m")
