"""Shared sampling helpers for the Panda experiments: reachable goals, spheres clear of the
start pose, and the hand's start position."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from dynfab.robots.builtin import panda_robot

Q0 = (1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0)


@dataclass(frozen=True)
class PandaSampler:
    """Numeric forward kinematics of the Panda for drawing scenarios."""

    hand: ca.Function
    spheres: ca.Function
    sphere_radii: np.ndarray
    lower: np.ndarray
    upper: np.ndarray

    @classmethod
    def create(cls, sphere_model: str = "fitted") -> PandaSampler:
        """The built-in Panda's sampler, with its ``"fitted"`` spheres (those it runs with) or
        the 13 ``"hand-written"`` ones (whose indices name parts: base, forearm, fingertips)."""
        robot = panda_robot(sphere_model)
        kin = robot.kinematics
        q = ca.SX.sym("q", kin.dof)
        hand = ca.Function("hand", [q], [kin.position(q, "panda_hand")])
        spheres = ca.Function("spheres", [q], [robot.sphere_centers(q).T])
        return cls(hand, spheres, robot.sphere_radii, kin.lower, kin.upper)

    def hand_position(self, q: tuple[float, ...] = Q0) -> np.ndarray:
        return np.array(self.hand(q)).ravel()

    def reachable_goal(self, rng: np.random.Generator, low: np.ndarray, high: np.ndarray,
                       min_distance_from_start: float = 0.1) -> np.ndarray:
        """A hand position of a random configuration within the joint limits, inside the
        box ``[low, high]`` and away from the start hand position."""
        start = self.hand_position()
        while True:
            goal = np.array(self.hand(rng.uniform(self.lower, self.upper))).ravel()
            if np.all(goal >= low) and np.all(goal <= high) and np.linalg.norm(goal - start) > min_distance_from_start:
                return goal

    def start_clearance(self, centre: np.ndarray, radius: float) -> float:
        """Clearance [m] of a sphere to the robot's spheres in the start pose."""
        centres = np.array(self.spheres(Q0)).T
        return float(np.min(np.linalg.norm(centres - centre, axis=1) - self.sphere_radii) - radius)


def panda_scenario(planner: str, duration: float, goal: dict[str, Any],
                   obstacles: list[dict[str, Any]]) -> dict[str, Any]:
    """A Panda scenario mapping: at rest in ``Q0``, dt 0.01 s, one goal for ``panda_hand``
    (``goal`` gives its type, position or trajectory, and tolerance)."""
    return {
        "robot": "panda",
        "planner": planner,
        "dt": 0.01,
        "duration": duration,
        "initial_state": {"q": list(Q0)},
        "goal": [{"link": "panda_hand", **goal}],
        "obstacles": obstacles,
    }
