"""Which problems are valid on Franka's Panda: start and goal within the joint limits (a
value within :data:`~dynfab.benchmarks.mbm.franka.LIMIT_SLACK` of a limit is at it) and
free of the scene's static obstacles and of self-collision on the meshes (fingers open).

An invalid problem is reported as such, never run: neither a success nor a failure of
the planner.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from dynfab.benchmarks.mbm.franka import Franka
from dynfab.robots.mesh_sweep import PlacedShape, sweep_meshes
from dynfab.scenario.exact_metrics import obstacle_shapes
from dynfab.scenario.schema import Scenario

__all__ = ["invalid_reason", "static_shapes"]

_WHEN = ("start", "goal")


def static_shapes(scenario: Scenario) -> list[PlacedShape]:
    """The scenario's obstacles that do not move, named ``obstacles[k]`` by their index."""
    static = [k for k, o in enumerate(scenario.obstacles) if o.trajectory is None]
    if static != list(range(len(static))):
        raise ValueError("static obstacles must come before moving ones")
    centres = np.array([[scenario.obstacles[k].position for k in static]], dtype=float).reshape(1, len(static), 3)
    return obstacle_shapes(scenario.obstacles[:len(static)], centres)


def invalid_reason(start: Sequence[float], goal: Sequence[float], shapes: Sequence[PlacedShape],
                   names: Sequence[str], robot: Franka) -> str | None:
    """Why a problem is invalid on Franka's meshes, in one line, or None if it is valid.

    Args:
        start: Start configuration [rad].
        goal: Goal configuration [rad].
        shapes: The static obstacles, ``shapes[k]`` named ``obstacles[k]``.
        names: The scene's name of each obstacle (its collision object id).
        robot: Franka's Panda.
    """
    for when, q in zip(_WHEN, (start, goal)):
        problem = robot.limit_problem(q)
        if problem is not None:
            return f"{when}: {problem}"
    sweep = sweep_meshes(robot.meshes, np.array([start, goal], dtype=float), shapes)
    if sweep.obstacle_contacts:
        contact = sweep.obstacle_contacts[0]
        index = int(contact.second.removeprefix("obstacles[").removesuffix("]"))
        return (f"{_WHEN[contact.samples[0]]}: {contact.first} touches {names[index]} "
                f"(distance {contact.depth:.3g} m)")
    if sweep.self_contacts:
        contact = sweep.self_contacts[0]
        return (f"{_WHEN[contact.samples[0]]}: {contact.first} touches {contact.second} "
                f"(self-collision, distance {contact.depth:.3g} m)")
    return None
