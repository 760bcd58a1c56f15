"""What the three ``mujoco_*_control.py`` examples share: the Panda reaching a point, a
MuJoCo scene standing in for the real arm, and the control loop that connects them.

The loop is the part a real robot keeps: the planner runs every 10 ms (100 Hz) and returns
joint accelerations q̈; :class:`~dynfab.sim.control_interfaces.SetpointIntegrator`
integrates them into setpoints every 1 ms; the control interface turns a setpoint into
the command of the arm's controller (a joint position, velocity or torque), which is sent
to it once per servo period.
"""

import mujoco
import numpy as np

import dynfab
from dynfab.sim.control_interfaces import ControlInterface, SetpointIntegrator
from dynfab.sim.mujoco_drives import JointDrive
from dynfab.sim.mujoco_model import MujocoScene, build_scene

#: the hand's goal [m]
GOAL = [0.5, -0.4, 0.3]
#: the arm's controller period and the planner's [s]
SERVO_PERIOD, PLANNER_PERIOD = 0.001, 0.01


def panda_in_mujoco() -> tuple[dynfab.Robot, dynfab.FabricPlanner, MujocoScene, mujoco.MjData]:
    """The Panda, its planner toward :data:`GOAL`, and the MuJoCo scene and state that
    stand in for the real arm (Franka's identified inertias, 1 kHz physics), at rest in
    the default configuration."""
    robot = dynfab.load_robot("panda")
    planner = dynfab.FabricPlanner(robot, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="panda_hand"),)))
    planner.parameters.goal_position[0] = GOAL
    scene = build_scene(robot)
    data = mujoco.MjData(scene.model)
    data.qpos[:] = robot.default_q
    return robot, planner, scene, data


def run(robot: dynfab.Robot, planner: dynfab.FabricPlanner, scene: MujocoScene, data: mujoco.MjData,
        interface: ControlInterface, control: str, seconds: float = 5.0) -> None:
    """Drive the arm through ``interface`` for ``seconds``, its own controller in ``control``
    mode (``"position"``, ``"velocity"`` or ``"torque"``), and print the hand's final error
    [mm]."""
    robot_controller = JointDrive(scene, data, control, servo_period=SERVO_PERIOD)  # the arm's own controller
    setpoints = SetpointIntegrator(servo_period=SERVO_PERIOD)
    setpoints.reset(data.qpos, data.qvel)
    every = round(PLANNER_PERIOD / SERVO_PERIOD)
    for tick in range(round(seconds / SERVO_PERIOD)):
        q, qdot = data.qpos.copy(), data.qvel.copy()  # the measured joint state
        if tick % every == 0:  # the planner, every 10 ms
            setpoints.hold(planner.compute(q, qdot))
        command = interface.command(setpoints.advance(), q, qdot)  # every 1 ms
        mujoco.mj_step1(scene.model, data)
        robot_controller.apply(command, q, qdot)  # on a real robot: send `command` to it
        mujoco.mj_step2(scene.model, data)
    hand = robot.link_position(data.qpos, "panda_hand")
    print(f"{control} control: hand at {hand.round(3)}, error {1e3 * np.linalg.norm(hand - GOAL):.3f} mm")
