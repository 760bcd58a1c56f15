"""The boolean mesh contact check (``dynfab/robots/mesh_contact.py``) beside the exact mesh
distances it replaces in a planner's validity (``MeshGoalCheck.clearance``), on
MotionBenchMaker's kitchen around the start of development kitchen/0005 (seed 1), where the
Panda's arm is millimetres from the counter and the dishwasher door.

    python bench/bench_mesh_contact.py

Prints the time per configuration of each [ms] over the same 200 configurations (the start
plus normal steps of 0.1 rad per joint), their ratio, and how often they agree (3 mm margin).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from dynfab.benchmarks.mbm.scene_configs import data_root
from dynfab.motion.mesh_goal_check import MeshGoalCheck, robot_mesh_model
from dynfab.robots.mesh_contact import MeshContactCheck
from dynfab.scenario import guided_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import robot_for
from dynfab.scenario.schema import load_scenario, validate_for_robot

START = [0.857053615, 0.673721676, -1.26315155, -1.009226058, 1.109981113, 2.855927208, -2.795497129]
SCENE = """robot: panda
planner: dynamic-fabric
dt: 0.01
duration: 20.0
initial_state:
  q: {start}
goal:
- type: pose
  position: [0.610852, -0.427765, -0.067808]
  orientation: [0.706550609, -0.003801147, 0.707649416, -0.002023009]
obstacles:
- type: urdf
  file: package://motion_bench_maker/configs/scenes/kitchen/kitchen.urdf
  package_dirs: [{data}]
  position: [0.112931, 0.337453, -0.7]
  orientation: [1.0, 0.0, 0.0, 0.0]
  joints: {{dishwasher_door_joint: -0.266745, cupboard_door_l_joint: -1.683137, cupboard_door_r_joint: 2.399996}}
"""
MARGIN = 0.003


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "kitchen_0005.yaml"
        path.write_text(SCENE.format(start=START, data=data_root()))
        scenario = load_scenario(path)
    robot = robot_for(scenario)
    scenario = validate_for_robot(scenario, robot)
    obstacles = guided_controller.placed_obstacles(scenario, scenario_references(scenario, robot), 0.0, static=True)
    model = robot_mesh_model(robot)
    assert model is not None
    exact, contact = MeshGoalCheck(model, MARGIN), MeshContactCheck(model, MARGIN)
    exact.set_obstacles(obstacles)
    contact.set_obstacles(obstacles)
    configurations = np.asarray(START) + np.random.default_rng(0).normal(0.0, 0.1, (200, 7))
    began = time.perf_counter()
    truth = [exact.free(q) for q in configurations]
    exact_ms = 1e3 * (time.perf_counter() - began) / len(configurations)
    began = time.perf_counter()
    answers = [contact.free(q) for q in configurations]
    contact_ms = 1e3 * (time.perf_counter() - began) / len(configurations)
    agree = sum(a == b for a, b in zip(truth, answers))
    print("| check | per configuration [ms] |")
    print("|---|---|")
    print(f"| exact distances (MeshGoalCheck.free) | {exact_ms:.2f} |")
    print(f"| boolean contact (MeshContactCheck.free) | {contact_ms:.2f} |")
    print(f"ratio exact / boolean: {exact_ms / contact_ms:.1f}; agree on {agree}/{len(truth)} "
          f"({sum(truth)} free)")


if __name__ == "__main__":
    main()
