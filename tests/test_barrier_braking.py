"""A braking barrier stops a fast approach in time under the Panda's acceleration limits.

The hand of the Panda moves down at 1 m/s toward a box 0.2 m below it, pulled on by a goal
under the box; the planner bounds every command into Franka's joint acceleration limits.
The guided fabric's box leaf (k = 5, λ = 0.02 m², range 0.1 m, buffer 5 mm) without braking
asks near contact for more deceleration than the limits give, the command is scaled down
and the hand goes into the box; with braking at 4 m/s² it stops outside.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.leaves.shape_obstacle import ShapeObstacleAvoidance
from dynfab.fabric.parameters import ShapeSlots
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.geometry.distance import placed_distance
from dynfab.geometry.shapes import Box, Placement
from dynfab.robots.builtin import panda_robot

Q0 = np.array([0.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.785])
BOX = Box((0.4, 0.4, 0.1))
GAP = 0.2          # [m] from the lowest sphere to the box's top
SPEED = 1.0        # [m/s] of the hand, down
TIME_STEP = 0.01   # [s]
STEPS = 200


def _lowest_clearance(braking: float | None) -> tuple[float, float]:
    """(clearance at the start, least clearance over the run) [m] of the robot's spheres to the box."""
    panda = panda_robot("hand-written")
    q = ca.SX.sym("q", 7)
    centres = ca.Function("centres", [q], [panda.sphere_centers(q)])
    hand_jacobian = ca.Function("jacobian", [q], [ca.jacobian(panda.kinematics.position(q, "panda_hand"), q)])
    radii = np.array([sphere.radius for sphere in panda.collision_spheres])
    hand_spheres = [i for i, sphere in enumerate(panda.collision_spheres) if sphere.link == "panda_hand"]
    start = np.array(centres(Q0))
    top = float(np.min(start[hand_spheres, 2] - radii[hand_spheres])) - GAP
    hand = np.array(panda.kinematics.position(Q0, "panda_hand")).ravel()
    placement = Placement((float(hand[0]), float(hand[1]), top - BOX.size[2] / 2), (1.0, 0.0, 0.0, 0.0))

    def clearance(configuration: np.ndarray) -> float:
        return float(np.min(placed_distance(BOX, placement, np.array(centres(configuration))) - radii))

    barrier = Barrier(geometry_gain=5.0, energy_gain=0.02, horizon=0.1, offset=0.005, braking=braking)
    planner = FabricPlanner(panda, PlannerConfig(goals=(GoalConfig(link="panda_hand"),), shape_slots=ShapeSlots(box=1),
                                                 shape_avoidance=ShapeObstacleAvoidance(barrier),
                                                 control_period=TIME_STEP))
    planner.parameters.goal_position[0][:] = hand + [0.0, 0.0, -0.4]
    boxes = planner.parameters.boxes
    boxes.position[0], boxes.orientation[0], boxes.dimensions[0] = placement.position, placement.orientation, BOX.size
    configuration = Q0.copy()
    velocity = np.linalg.pinv(np.array(hand_jacobian(Q0))) @ [0.0, 0.0, -SPEED]
    least = clearance(configuration)
    for _ in range(STEPS):
        acceleration = planner.compute(configuration, velocity)
        assert np.all(np.abs(acceleration) <= planner.config.limits.acceleration + 1e-9)
        velocity = velocity + acceleration * TIME_STEP
        configuration = configuration + velocity * TIME_STEP
        least = min(least, clearance(configuration))
    return clearance(Q0), least


def test_without_braking_the_limits_let_the_hand_into_the_box() -> None:
    start, least = _lowest_clearance(None)
    assert start == pytest.approx(GAP)
    assert least < -0.01


def test_with_braking_the_hand_stops_outside_the_box() -> None:
    start, least = _lowest_clearance(4.0)
    assert start == pytest.approx(GAP)
    assert least > 0.005
