"""Connecting dynfab to a position-controlled robot: a Panda in MuJoCo, with Franka's
identified inertias, stands in for the real arm (scene and loop: mujoco_common.py).

The planner runs at 100 Hz and returns joint accelerations; the robot's controller runs at
1 kHz and takes joint positions q_d [rad] (a position interface: UR's servoj, Franka's
joint position control).

    .venv/bin/python examples/mujoco_position_control.py
"""

from mujoco_common import panda_in_mujoco, run

from dynfab.sim.control_interfaces import PositionInterface

robot, planner, scene, data = panda_in_mujoco()
run(robot, planner, scene, data, PositionInterface(), "position")
