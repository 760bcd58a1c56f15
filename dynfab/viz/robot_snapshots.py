"""The robot's body at a few instants of a run, for plots: a skeleton (a segment from each
link's origin to each child link's origin) and the collision spheres.

The instants are the start, the end, the closest approach to an obstacle (where a
collision would show) and evenly spaced ones between, so that a plot shows where the body
went, not only the goal link's path.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.robots.robot import Robot

#: Snapshots of a plot besides the closest approach: the start, the end and the rest
#: evenly spaced between them.
DEFAULT_SNAPSHOTS = 4


@dataclass(frozen=True)
class RobotSnapshots:
    """The robot's body at ``K`` instants.

    Attributes:
        times: The instants [s], shape (K,), increasing.
        segments: Skeleton segments, shape (K, L, 2, 3) [m]: from each joint's parent
            link's origin to its child link's origin.
        sphere_centres: Collision-sphere centres, shape (K, S, 3) [m].
        sphere_radii: Their radii, shape (S,) [m].
        closest: Index into ``times`` of the closest approach to an obstacle, or None.
    """

    times: NDArray[np.float64]
    segments: NDArray[np.float64]
    sphere_centres: NDArray[np.float64]
    sphere_radii: NDArray[np.float64]
    closest: int | None = None


def snapshot_indices(samples: int, clearance: ArrayLike | None = None,
                     count: int = DEFAULT_SNAPSHOTS) -> tuple[tuple[int, ...], int | None]:
    """Which of ``samples`` rows to draw: ``count`` evenly spaced ones from the first to
    the last, plus the row of least clearance (if given and finite); the position of
    that row among the returned ones, or None."""
    evenly = {int(round(k)) for k in np.linspace(0, samples - 1, max(count, 2))}
    closest_row = None
    if clearance is not None:
        values = np.asarray(clearance, dtype=float)
        if values.size == samples and np.isfinite(values).any():
            closest_row = int(np.nanargmin(np.where(np.isfinite(values), values, np.nan)))
            evenly.add(closest_row)
    rows = tuple(sorted(evenly))
    return rows, None if closest_row is None else rows.index(closest_row)


def robot_snapshots(robot: Robot, qs: ArrayLike, times: ArrayLike, clearance: ArrayLike | None = None,
                    count: int = DEFAULT_SNAPSHOTS) -> RobotSnapshots:
    """The robot's skeleton and collision spheres at the instants of
    :func:`snapshot_indices` of a run with configurations ``qs`` (T, n) at ``times`` (T,)."""
    qs, times = np.asarray(qs, dtype=float), np.asarray(times, dtype=float)
    rows, closest = snapshot_indices(qs.shape[0], clearance, count)
    kin = robot.kinematics
    q = ca.SX.sym("q", kin.dof)
    joints = [j for j in kin.model.joints if j.parent in kin.link_names and j.child in kin.link_names]
    ends = ca.vertcat(*[ca.vertcat(kin.position(q, j.parent), kin.position(q, j.child)) for j in joints]) \
        if joints else ca.SX(0, 1)
    spheres = robot.collision_spheres
    centres = ca.reshape(robot.sphere_centers(q).T, 3 * len(spheres), 1) if spheres else ca.SX(0, 1)
    function = ca.Function("snapshot", [q], [ends, centres])
    segments, sphere_centres = [], []
    for row in rows:
        e, c = function(qs[row])
        segments.append(np.array(e, dtype=float).reshape(len(joints), 2, 3))
        sphere_centres.append(np.array(c, dtype=float).reshape(len(spheres), 3))
    return RobotSnapshots(times[list(rows)], np.array(segments), np.array(sphere_centres),
                          np.asarray(robot.sphere_radii if spheres else np.zeros(0), dtype=float), closest)
