"""The moving-sphere variant's obstacle: a sphere that crosses the straight line between
the hand's start and goal positions around mid-motion, in no plan.

Drawn per problem from a seeded generator: radius in :data:`RADII`, speed in
:data:`SPEEDS`, a direction perpendicular to the hand's line, and the time
``crossing_time`` in :data:`CROSSING_TIMES` at which its centre passes through the point
at fraction ``s`` in :data:`FRACTIONS` of the line; it moves on a straight line at
constant velocity (a ``linear`` trajectory), before and after. A draw is kept only if the
sphere keeps :data:`START_MARGIN` from the arm at its start configuration over the first
:data:`REACTION_TIME` of the run,
keeps :data:`START_MARGIN` from the links no avoidance can move out of its way
(:data:`FIXED_LINKS`) for the whole run, and never touches the arm at its goal
configuration from ``crossing_time +`` :data:`SETTLE_TIME` on (the goal stays reachable
once the sphere has passed).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from dynfab.benchmarks.mbm.franka import Franka
from dynfab.geometry.shapes import Placement, Sphere
from dynfab.robots.mesh_sweep import PlacedShape, sweep_meshes

__all__ = ["CROSSING_TIMES", "FRACTIONS", "RADII", "REACTION_TIME", "SPEEDS", "CrossingSphere", "crossing_sphere"]

#: Sphere radius range [m].
RADII = (0.05, 0.08)
#: Speed range [m/s].
SPEEDS = (0.2, 0.5)
#: When the centre crosses the hand's line [s]: while the hand is under way (reached goals
#: took 5-12 s, median 9 s, on a 14-problem object-removed subset with guidance).
CROSSING_TIMES = (1.5, 3.0)
#: Where on the hand's line it crosses, as a fraction from start to goal.
FRACTIONS = (0.35, 0.65)
#: Smallest distance from the arm at the start, at t = 0 [m].
START_MARGIN = 0.05
#: How long the arm, still at its start configuration, must keep :data:`START_MARGIN` from
#: the sphere [s]: a sphere already on its way into the arm leaves no time to react (fresh
#: ``--seed 14`` table_under_pick/0100: 5 cm from the arm's shoulder at 0.46 m/s, it met
#: ``panda_link2`` at 0.25 s, beside the joint-2 axis, where no joint moves the link
#: out of its way in time). 0.5 s, ten times guidance's simulated plan latency, set from
#: that draw before measuring.
REACTION_TIME = 0.5
#: After the crossing, from when on the goal configuration must stay free [s].
SETTLE_TIME = 1.5
#: Links a sphere must keep :data:`START_MARGIN` from at all times: no joint moves
#: ``panda_link0`` (the base) and joint 1 only turns ``panda_link1`` about its own vertical
#: axis, so a sphere that meets them cannot be avoided by any controller (a training draw,
#: bookshelf_thin/0016, swept through the base).
FIXED_LINKS = ("panda_link0", "panda_link1")
#: Draws tried before giving up.
ATTEMPTS = 50


@dataclass(frozen=True)
class CrossingSphere:
    """A sphere moving at constant velocity.

    Attributes:
        radius: [m].
        start: Centre at t = 0 [m].
        velocity: [m/s].
        crossing_time: When the centre is on the hand's line [s].
        crossing_point: Where [m].
    """

    radius: float
    start: tuple[float, float, float]
    velocity: tuple[float, float, float]
    crossing_time: float
    crossing_point: tuple[float, float, float]

    def centre(self, t: float) -> np.ndarray:
        """Centre at time ``t`` [m]."""
        return np.array(self.start) + t * np.array(self.velocity)

    def mapping(self) -> dict[str, Any]:
        """The scenario obstacle mapping (a sphere on a ``linear`` trajectory)."""
        return {"type": "sphere", "radius": self.radius,
                "trajectory": {"type": "linear", "start": list(self.start), "velocity": list(self.velocity)}}


def crossing_sphere(start: Sequence[float], goal: Sequence[float], robot: Franka, rng: np.random.Generator,
                    duration: float) -> CrossingSphere | None:
    """A sphere crossing the hand's line (module doc); None if no draw keeps the start and
    goal configurations free.

    Args:
        start: Start configuration [rad].
        goal: Goal configuration [rad].
        robot: Franka's Panda (hand positions and meshes).
        rng: The problem's generator.
        duration: The run's duration [s].
    """
    hand_start, hand_goal = robot.tcp(start), robot.tcp(goal)
    for _ in range(ATTEMPTS):
        sphere = _draw(hand_start, hand_goal, rng)
        if _clear(sphere, start, goal, robot, duration):
            return sphere
    return None


def _draw(hand_start: np.ndarray, hand_goal: np.ndarray, rng: np.random.Generator) -> CrossingSphere:
    line = hand_goal - hand_start
    length = float(np.linalg.norm(line))
    along = line / length if length > 1e-6 else np.array([1.0, 0.0, 0.0])
    direction = rng.normal(size=3)
    direction -= direction.dot(along) * along
    direction /= np.linalg.norm(direction)
    radius, speed = rng.uniform(*RADII), rng.uniform(*SPEEDS)
    crossing_time, fraction = rng.uniform(*CROSSING_TIMES), rng.uniform(*FRACTIONS)
    point = hand_start + fraction * line
    velocity = speed * direction
    return CrossingSphere(float(radius), _triple(point - crossing_time * velocity), _triple(velocity),
                          float(crossing_time), _triple(point))


def _clear(sphere: CrossingSphere, start: Sequence[float], goal: Sequence[float], robot: Franka,
           duration: float) -> bool:
    """The sphere (grown by :data:`START_MARGIN`) is off the arm at the start over the first
    :data:`REACTION_TIME` and off :data:`FIXED_LINKS` throughout, and off the arm at the goal
    from the crossing on (sampled every 0.1 s; one sweep of the start configuration serves
    both of its tests)."""
    run = np.arange(0.0, duration + 0.1, 0.1)
    grown = PlacedShape("sphere", Sphere(sphere.radius + START_MARGIN),
                        tuple(Placement(_triple(sphere.centre(t))) for t in run))
    swept = sweep_meshes(robot.meshes, np.repeat(np.array([start], dtype=float), len(run), axis=0), [grown])
    if any(contact.first in FIXED_LINKS or run[contact.samples[0]] < REACTION_TIME + 0.05
           for contact in swept.obstacle_contacts):
        return False
    times = np.arange(sphere.crossing_time + SETTLE_TIME, duration + 0.1, 0.1)
    later = PlacedShape("sphere", Sphere(sphere.radius), tuple(Placement(_triple(sphere.centre(t))) for t in times))
    return not sweep_meshes(robot.meshes, np.repeat(np.array([goal], dtype=float), len(times), axis=0),
                            [later]).obstacle_contacts


def _triple(values: np.ndarray) -> tuple[float, float, float]:
    x, y, z = (float(v) for v in values)
    return (x, y, z)
