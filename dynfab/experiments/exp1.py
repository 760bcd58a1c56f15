"""Experiment 1 scenarios: the Panda reaches a random goal among 1-5 static spheres.

Distribution (``shared/EXPERIMENTS.md``, Experiment 1), with the choices the paper leaves
open made explicit:

- goal: an end-effector position in the box ``[-0.4, -0.4, 0.1] .. [0.7, 0.0, 1.1]`` m,
  tolerance 0.05 m. *Choice:* goals are drawn as the hand position of a random
  configuration within the joint limits (rejected until inside the box and at least
  0.1 m from the start), so every goal is reachable;
- 1-5 spheres of radius 0.15 m, centres uniform in ``[-1, -1, 0] .. [1, 0.3, 1]`` m.
  *Choice:* a sphere is rejected if it comes within 0.05 m of any robot collision sphere
  at the start, or within 0.1 m (surface) of the goal;
- start ``q0 = [1, 0, 0, -1.5, 0, 1.8675, 0]`` at rest, dt 0.01 s, 20 s.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from dynfab.robots import load_robot

Q0 = (1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0)
GOAL_LOW, GOAL_HIGH = np.array([-0.4, -0.4, 0.1]), np.array([0.7, 0.0, 1.1])
OBSTACLE_LOW, OBSTACLE_HIGH = np.array([-1.0, -1.0, 0.0]), np.array([1.0, 0.3, 1.0])
OBSTACLE_RADIUS = 0.15
START_MARGIN = 0.05
GOAL_MARGIN = 0.1
DURATION = 20.0


def scenario(seed: int, planner: str = "static-fabric") -> dict[str, Any]:
    """The scenario of run ``seed`` as a scenario-file mapping (DESIGN.md section 5)."""
    rng = np.random.default_rng(seed)
    robot = load_robot("panda")
    kin = robot.kinematics
    q = ca.SX.sym("q", kin.dof)
    hand = ca.Function("hand", [q], [kin.position(q, "panda_hand")])
    spheres = ca.Function("spheres", [q], [ca.horzcat(*[kin.position(q, s.link, offset=s.center)
                                                       for s in robot.collision_spheres])])
    start_hand = np.array(hand(Q0)).ravel()
    while True:
        goal = np.array(hand(rng.uniform(kin.lower, kin.upper))).ravel()
        if np.all(goal >= GOAL_LOW) and np.all(goal <= GOAL_HIGH) and np.linalg.norm(goal - start_hand) > 0.1:
            break
    centres = np.array(spheres(Q0)).T
    radii = np.array([s.radius for s in robot.collision_spheres])
    obstacles = []
    for _ in range(int(rng.integers(1, 6))):
        while True:
            centre = rng.uniform(OBSTACLE_LOW, OBSTACLE_HIGH)
            start_clearance = np.min(np.linalg.norm(centres - centre, axis=1) - radii) - OBSTACLE_RADIUS
            goal_clearance = np.linalg.norm(goal - centre) - OBSTACLE_RADIUS
            if start_clearance > START_MARGIN and goal_clearance > GOAL_MARGIN:
                break
        obstacles.append({"type": "sphere", "position": [round(float(c), 4) for c in centre],
                          "radius": OBSTACLE_RADIUS})
    return {
        "robot": "panda",
        "planner": planner,
        "dt": 0.01,
        "duration": DURATION,
        "initial_state": {"q": list(Q0)},
        "goal": [{"type": "position", "link": "panda_hand",
                  "position": [round(float(g), 4) for g in goal], "tolerance": 0.05}],
        "obstacles": obstacles,
    }
