"""What a moving obstacle covers soon: the capsule a sphere sweeps over the next seconds.

A replan made with a moving sphere frozen where it is puts the new reference on the
sphere's path again, a little ahead of it (moving-sphere MBM bookshelf_tall/0063: five
``blocked`` replans in 2 s, the robot running ahead of the sphere along its line until
cornered). A sphere of radius ``r`` at ``c`` moving at velocity ``v`` [m/s] covers, over
``[0, T]``, the capsule of radius ``r`` about the segment from ``c`` to ``c + v T``:

    S(c, v, T) = {x : min_{s ∈ [0, T]} ‖x − (c + v s)‖ ≤ r}                    [m]

A plan that avoids it leaves the sphere's line sideways, and a reference that meets it
is one the sphere is about to cross.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.shapes import Capsule, Placement, Sphere, quaternion_from_normal
from dynfab.motion.configuration_checker import PlacedObstacle

__all__ = ["SHORTENINGS", "SHORTEST_SWEEP", "swept_clear_of", "swept_obstacle"]

#: a sweep shorter than this is the sphere itself [m]
SHORTEST_SWEEP = 1e-6
#: halvings of the horizon tried for a capsule clear of the robot (:func:`swept_clear_of`) [-]
SHORTENINGS = 3


def swept_obstacle(obstacle: PlacedObstacle, horizon: float) -> PlacedObstacle:
    """The capsule ``S(c, v, T)`` of the module docstring that ``obstacle`` (a sphere at
    ``c`` moving at ``obstacle.velocity``) sweeps over ``horizon`` = ``T`` [s]; a sphere
    that sweeps less than :data:`SHORTEST_SWEEP`, or another shape, as it is.

    Raises:
        ValueError: ``horizon`` is negative or not finite.
    """
    if not np.isfinite(horizon) or horizon < 0.0:
        raise ValueError(f"sweep horizon must be a finite number >= 0 s, got {horizon}")
    if not isinstance(obstacle.shape, Sphere):
        return obstacle
    sweep = np.asarray(obstacle.velocity, dtype=float) * horizon
    length = float(np.linalg.norm(sweep))
    if length < SHORTEST_SWEEP:
        return obstacle
    middle = np.asarray(obstacle.placement.position, dtype=float) + sweep / 2
    placement = Placement(tuple(middle), quaternion_from_normal(sweep))
    return PlacedObstacle(Capsule(obstacle.shape.radius, length), placement, obstacle.velocity)


def swept_clear_of(obstacle: PlacedObstacle, horizon: float, configurations: Sequence[NDArray[np.float64]],
                   clearance: Callable[[NDArray[np.float64], PlacedObstacle], float],
                   margin: float) -> PlacedObstacle:
    """What ``obstacle`` sweeps over the longest of ``horizon``, ``horizon/2``, …,
    ``horizon/2^SHORTENINGS`` [s] (:func:`swept_obstacle`) from which the robot keeps
    ``margin`` [m] at each of ``configurations`` (``clearance(q, o)``: the robot's at ``q``
    from ``o`` alone [m]), else ``obstacle`` where it is. A robot in the whole capsule has the
    sphere coming at it: every reference near it would meet the capsule, and a plan would
    start with an escape of it, which led the robot along the sphere's line on training
    moving-sphere bookshelf_tall/0022 (problems 17-28), into it."""
    for halvings in range(SHORTENINGS + 1):
        swept = swept_obstacle(obstacle, horizon / 2**halvings)
        if swept is obstacle:
            return obstacle
        if all(clearance(q, swept) >= margin for q in configurations):
            return swept
    return obstacle
