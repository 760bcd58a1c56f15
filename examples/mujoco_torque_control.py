"""Connecting dynfab to a torque-controlled robot: a Panda in MuJoCo, with Franka's
identified inertias, stands in for the real arm (scene and loop: mujoco_common.py).

The planner runs at 100 Hz and returns joint accelerations; the robot's controller runs at
1 kHz and takes joint torques τ [N m] (Franka's torque control): computed torque through
an inverse-dynamics model, here MuJoCo's (on a real robot e.g. pinocchio's rnea or
libfranka's model), with a PD term on the setpoint's tracking error.

    .venv/bin/python examples/mujoco_torque_control.py
"""

from mujoco_common import panda_in_mujoco, run

from dynfab.sim.control_interfaces import TorqueInterface
from dynfab.sim.mujoco_drives import MujocoInverseDynamics

robot, planner, scene, data = panda_in_mujoco()
interface = TorqueInterface(MujocoInverseDynamics(scene, data), stiffness=400.0, damping=40.0,
                            effort=robot.limits.effort)
run(robot, planner, scene, data, interface, "torque")
