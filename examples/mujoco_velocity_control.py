"""Connecting dynfab to a velocity-controlled robot: a Panda in MuJoCo, with Franka's
identified inertias, stands in for the real arm (scene and loop: mujoco_common.py).

The planner runs at 100 Hz and returns joint accelerations; the robot's controller runs at
1 kHz and takes joint velocities q̇_d [rad/s] (a velocity interface: UR's speedj,
Franka's joint velocity control).

    .venv/bin/python examples/mujoco_velocity_control.py
"""

from mujoco_common import panda_in_mujoco, run

from dynfab.sim.control_interfaces import VelocityInterface

robot, planner, scene, data = panda_in_mujoco()
run(robot, planner, scene, data, VelocityInterface(), "velocity")
