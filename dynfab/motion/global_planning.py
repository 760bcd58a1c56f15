"""Global path planning for the goal link among static spheres (OMPL RRT).

Scenario trajectories of type ``rrt`` (docs/design.md section 5, Experiment 2(b)) need a
collision-free polyline for the goal link from its start to a goal position, which a
spline then turns into a timed reference. :func:`plan_path` plans that polyline for a
POINT in R^d (d = 3 for arms, 2 for planar robots) with OMPL's RRT-Connect or RRT,
and shortens it with OMPL's path simplifier; :func:`path_duration` gives a duration
for traversing it at a mean speed.

OMPL 2.0 Python API (nanobind) used here: ``base.RealVectorStateSpace``,
``base.RealVectorBounds``, ``geometric.SimpleSetup`` with a plain Python callable as
state validity checker, states from ``space.allocState()`` written and read by index
(``copyFromReals`` / ``copyToReals`` are broken in the 2.0 bindings),
``geometric.RRTConnect`` / ``geometric.RRT``, ``SimpleSetup.simplifySolution``,
``util.RNG.setSeed`` and ``util.setLogLevel``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from dynfab.motion.ompl_problem import solve_in_box

DEFAULT_MARGIN = 0.1
"""Default clearance [m] between the point and each sphere's surface.

The planned point is the goal link's origin, but the link itself (the Panda hand is
about 0.2 m wide) has extent: 0.1 m keeps the hand's body, not just its origin, off
the spheres and leaves the reactive planner room to follow the path.
"""

VALIDITY_RESOLUTION = 0.005
"""Motion-check step as a fraction of the bounds' diagonal (OMPL's resolution)."""

PlannerName = Literal["RRTConnect", "RRT"]

_PLANNERS: dict[str, type] = {"RRTConnect": og.RRTConnect, "RRT": og.RRT}
_MAX_SEED = 2**32 - 2


class GlobalPlanningError(ValueError):
    """The global planner got an infeasible problem or found no path in time."""


@dataclass(frozen=True)
class _ClearanceChecker:
    """State validity for OMPL: the point keeps its clearance from every sphere.

    Attributes:
        centers: Sphere centres, shape (m, d).
        required: Required distance from each centre, shape (m,): radius + margin,
            inflated so that straight motions checked at a finite step keep it too.
    """

    centers: NDArray[np.float64]
    required: NDArray[np.float64]

    def distances(self, point: NDArray[np.float64]) -> NDArray[np.float64]:
        """Distances from ``point`` to every sphere centre, shape (m,)."""
        return np.linalg.norm(self.centers - point, axis=1)

    def __call__(self, state: ob.State) -> bool:
        """Whether an OMPL state keeps the required distance from all centres."""
        point = np.asarray(state[0 : self.centers.shape[1]])
        offsets = self.centers - point
        return bool(np.all(np.einsum("ij,ij->i", offsets, offsets) >= self.required**2))


def plan_path(
    start: ArrayLike,
    goal: ArrayLike,
    spheres: Sequence[tuple[ArrayLike, float]],
    *,
    bounds_low: ArrayLike,
    bounds_high: ArrayLike,
    margin: float = DEFAULT_MARGIN,
    seed: int = 0,
    time_limit: float = 1.0,
    planner: PlannerName = "RRTConnect",
) -> NDArray[np.float64]:
    """Plans a short collision-free polyline for a point among static spheres.

    The point stays inside the axis-aligned box [bounds_low, bounds_high] and at
    least ``radius + margin`` from each sphere centre, along every segment of the
    returned polyline, not only at its vertices: states are checked every
    ``VALIDITY_RESOLUTION`` times the box diagonal along each motion, and the
    required distance is inflated to sqrt((radius + margin)^2 + (step / 2)^2) so that
    the chords between checked states cannot cut into the clearance (the inflation
    is about step^2 / (8 (radius + margin)): 0.2 mm for a 2 m cube and 0.2 m).

    After planning, OMPL's path simplifier (vertex reduction, shortcutting,
    smoothing) shortens the path and leaves few waypoints. ``time_limit`` bounds the
    planning only; simplification adds a few milliseconds.

    Deterministic: the same arguments and ``seed`` give the same path, also
    repeatedly within one process, because the planner stops at its first exact
    solution and the simplifier runs a fixed number of steps. This re-seeds OMPL's
    process-wide seed generator (``ompl.util.RNG.setSeed(seed + 1)``, as OMPL
    rejects 0), so it also fixes the seeds of OMPL objects created afterwards.
    OMPL's console output is silenced during the call.

    Args:
        start: Start position of the point, shape (d,).
        goal: Goal position of the point, shape (d,).
        spheres: Static obstacles as (centre of shape (d,), radius) pairs.
        bounds_low: Lower corner of the planning box, shape (d,).
        bounds_high: Upper corner of the planning box, shape (d,), above
            ``bounds_low`` in every coordinate.
        margin: Clearance [m] added to every radius; the default accounts for the
            goal link's own size (see ``DEFAULT_MARGIN``).
        seed: Non-negative random seed.
        time_limit: Planning time limit [s].
        planner: ``"RRTConnect"`` (bidirectional, fast) or ``"RRT"``.

    Returns:
        Waypoints of shape (k, d), k >= 2; the first is ``start`` and the last is
        ``goal``, exactly.

    Raises:
        GlobalPlanningError: The start or the goal is outside the bounds or too close
            to a sphere (the message names which, and the sphere), or no path was
            found within ``time_limit``.
        ValueError: Inconsistent shapes or invalid parameters.
    """
    start_point = np.asarray(start, dtype=float)
    goal_point = np.asarray(goal, dtype=float)
    low = np.asarray(bounds_low, dtype=float)
    high = np.asarray(bounds_high, dtype=float)
    dim = start_point.size
    if start_point.shape != (dim,) or dim == 0:
        raise ValueError(f"start must be a non-empty vector, got shape {start_point.shape}")
    for name, array in (("goal", goal_point), ("bounds_low", low), ("bounds_high", high)):
        if array.shape != (dim,):
            raise ValueError(f"{name} must have shape ({dim},) like start, got {array.shape}")
    if not np.all(low < high):
        raise ValueError(f"bounds_low {low.tolist()} must be below bounds_high {high.tolist()}")
    if margin < 0.0:
        raise ValueError(f"margin must be non-negative, got {margin}")
    if time_limit <= 0.0:
        raise ValueError(f"time_limit must be positive, got {time_limit}")
    if not 0 <= seed <= _MAX_SEED:
        raise ValueError(f"seed must be in [0, {_MAX_SEED}], got {seed}")
    if planner not in _PLANNERS:
        raise ValueError(f"planner must be one of {sorted(_PLANNERS)}, got {planner!r}")

    step = VALIDITY_RESOLUTION * float(np.linalg.norm(high - low))
    checker = _make_checker(spheres, dim, margin, step)
    for name, point in (("start", start_point), ("goal", goal_point)):
        _check_endpoint(name, point, low, high, checker)

    previous_log_level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)
    try:
        ou.RNG.setSeed(seed + 1)
        return _solve(start_point, goal_point, low, high, checker, time_limit, planner)
    finally:
        ou.setLogLevel(previous_log_level)


def path_duration(waypoints: ArrayLike, speed: float) -> float:
    """Time [s] to traverse a polyline at a mean speed.

    Args:
        waypoints: Polyline vertices, shape (k, d), k >= 1.
        speed: Mean speed [m/s], positive.

    Returns:
        The polyline's length divided by ``speed``.

    Raises:
        ValueError: ``waypoints`` is not a non-empty (k, d) array or ``speed`` is not
            positive.
    """
    points = np.asarray(waypoints, dtype=float)
    if points.ndim != 2 or points.shape[0] == 0:
        raise ValueError(f"waypoints must have shape (k, d) with k >= 1, got {points.shape}")
    if speed <= 0.0:
        raise ValueError(f"speed must be positive, got {speed}")
    length = float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1)))
    return length / speed


def _make_checker(
    spheres: Sequence[tuple[ArrayLike, float]], dim: int, margin: float, step: float
) -> _ClearanceChecker:
    """Builds the clearance checker, validating the spheres.

    Args:
        spheres: (centre, radius) pairs.
        dim: Dimension d of the planning space.
        margin: Clearance added to every radius [m].
        step: Longest distance between checked states along a motion [m].

    Returns:
        The checker with the inflated required distances.

    Raises:
        ValueError: A centre does not have d coordinates or a radius is negative.
    """
    centers = np.zeros((len(spheres), dim))
    radii = np.zeros(len(spheres))
    for index, (center, radius) in enumerate(spheres):
        center_array = np.asarray(center, dtype=float)
        if center_array.shape != (dim,):
            raise ValueError(
                f"sphere {index}: centre must have shape ({dim},) like start, "
                f"got {center_array.shape}"
            )
        if radius < 0.0:
            raise ValueError(f"sphere {index}: radius must be non-negative, got {radius}")
        centers[index] = center_array
        radii[index] = radius
    required = np.sqrt((radii + margin) ** 2 + (0.5 * step) ** 2)
    return _ClearanceChecker(centers=centers, required=required)


def _check_endpoint(
    name: str,
    point: NDArray[np.float64],
    low: NDArray[np.float64],
    high: NDArray[np.float64],
    checker: _ClearanceChecker,
) -> None:
    """Raises GlobalPlanningError if a start or goal point is not a valid state.

    Args:
        name: ``"start"`` or ``"goal"``, for the message.
        point: The point, shape (d,).
        low: Lower corner of the bounds, shape (d,).
        high: Upper corner of the bounds, shape (d,).
        checker: The clearance checker.

    Raises:
        GlobalPlanningError: The point is outside the bounds or too close to a sphere.
    """
    if np.any(point < low) or np.any(point > high):
        raise GlobalPlanningError(
            f"{name} {point.tolist()} is outside the planning bounds "
            f"[{low.tolist()}, {high.tolist()}]"
        )
    distances = checker.distances(point)
    blocked = np.flatnonzero(distances < checker.required)
    if blocked.size:
        index = int(blocked[np.argmin(distances[blocked] - checker.required[blocked])])
        raise GlobalPlanningError(
            f"{name} {point.tolist()} is in collision with sphere {index} "
            f"(centre {checker.centers[index].tolist()}): distance "
            f"{distances[index]:.4f} m < required {checker.required[index]:.4f} m "
            f"(radius + margin)"
        )


def _solve(
    start: NDArray[np.float64],
    goal: NDArray[np.float64],
    low: NDArray[np.float64],
    high: NDArray[np.float64],
    checker: _ClearanceChecker,
    time_limit: float,
    planner: PlannerName,
) -> NDArray[np.float64]:
    """Sets up OMPL, plans, simplifies and returns the waypoints.

    Args:
        start: Valid start point, shape (d,).
        goal: Valid goal point, shape (d,).
        low: Lower corner of the bounds, shape (d,).
        high: Upper corner of the bounds, shape (d,).
        checker: The state validity checker.
        time_limit: Planning time limit [s].
        planner: Name of the OMPL planner.

    Returns:
        Waypoints of shape (k, d).

    Raises:
        GlobalPlanningError: No exact solution within the time limit.
    """
    waypoints, status = solve_in_box(checker, start, goal, low, high, VALIDITY_RESOLUTION, _PLANNERS[planner],
                                     time_limit)
    if waypoints is None:
        raise GlobalPlanningError(
            f"no collision-free path from {start.tolist()} to {goal.tolist()} found "
            f"within {time_limit} s ({planner}: {status})"
        )
    return waypoints
