"""Helpers shared by the scenario samplers: scattering obstacle spheres, rounding numbers."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def scatter_spheres(rng: np.random.Generator, count: int, radius_range: tuple[float, float],
                    draw_centre: Callable[[], np.ndarray], robot_centres: np.ndarray,
                    robot_radii: np.ndarray, goal: np.ndarray, start_margin: float, goal_margin: float,
                    passage: float) -> list[tuple[np.ndarray, float]]:
    """``count`` spheres ``(centre, radius)``, each redrawn (radius, then centre) until its
    surface is more than ``start_margin`` [m] from every robot sphere at the start, more
    than ``goal_margin`` from the goal point, and more than ``passage`` from every sphere
    drawn before it (so the gaps between spheres are passable)."""
    spheres: list[tuple[np.ndarray, float]] = []
    while len(spheres) < count:
        radius = float(rng.uniform(*radius_range))
        centre = draw_centre()
        start_gap = np.min(np.linalg.norm(robot_centres - centre, axis=1) - robot_radii) - radius
        goal_gap = np.linalg.norm(goal - centre) - radius
        apart = all(np.linalg.norm(centre - c) - radius - r > passage for c, r in spheres)
        if start_gap > start_margin and goal_gap > goal_margin and apart:
            spheres.append((centre, radius))
    return spheres


def rounded(values: np.ndarray, digits: int = 4) -> list[float]:
    """Plain floats for a scenario file."""
    return [round(float(v), digits) for v in values]
