"""The global planner's view of point clouds near its goal: the kept points around the robot
at the goal read on a finer grid (:mod:`dynfab.geometry.focused_cloud`).

The focus of a cloud is the box, in the cloud's frame, around the robot's collision spheres
at the goal configuration ``q_g`` grown by ``reach``:

    [min_i (c_i − r_i) − reach, max_i (c_i + r_i) + reach]          [m],

``c_i = Rᵀ (p_i(q_g) − p)`` the spheres' centres in the cloud's frame and ``r_i`` their
radii. Its points become a :class:`~dynfab.geometry.focused_cloud.FocusedCloud` gridded at
``pitch``, the rest stays on the cloud's own grid; other obstacles are untouched. The bound
is the same (``d(x, C) − δ``); only the grid's shortfall below it shrinks, from up to
1.7 cm to up to ``pitch·√3`` (7 mm at 4 mm) where the robot is near its goal.

Guidance plans on the focus only where the whole clouds' grids give no plan in their first
``whole_attempts`` attempts (:meth:`~dynfab.motion.guidance.JointGuidance.plan`; then every
attempt is made on the focus): plans on it run closer to the scene
(what the grid no longer takes away), and with it as the first choice held-out
table_pick/0020's first plan passed 2.7 cm (spheres, true shapes) from the table top, which
the fabric then entered 5 cm deep. On the point-cloud MotionBenchMaker problems (training
10-16, first plan only) the focus planned cage 10, 11, 12, 14 and 16, which failed on the
whole cloud's grid (``no_path`` or ``goal_in_collision``), and bookshelf_small 15
(``no_path``); a credit on the margin within the focus (the planner reading the bound 5 or
10 mm higher there) planned nothing more and was not kept.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.focused_cloud import FocusedCloud, split_cloud
from dynfab.geometry.point_cloud import PointCloud
from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.placed_obstacle import any_cloud
from dynfab.robots.robot import Robot

__all__ = ["CloudFocus", "FocusCache", "focused_obstacles"]


@dataclass(frozen=True)
class CloudFocus:
    """How the planner looks at clouds near its goal (module docstring).

    Attributes:
        reach: how far the focus reaches beyond the robot's spheres at the goal [m].
        pitch: node spacing of the focused points' grid [m] (grown by the grid to stay
            within its node budget: 8 M nodes, a 0.8 m cube at 4 mm).
        whole_attempts: plan attempts on the whole clouds' grids before the focus [-]
            (at least 1): a cage grasp blocked on the whole cloud spent all three (1 + 2 +
            4 s of search) there before the focus planned it, about 11 s a plan.
    """

    reach: float = 0.1
    pitch: float = 0.004
    whole_attempts: int = 1

    def __post_init__(self) -> None:
        if not (math.isfinite(self.reach) and self.reach >= 0.0):
            raise ValueError(f"cloud focus reach: must be a finite number >= 0, got {self.reach}")
        if not (math.isfinite(self.pitch) and self.pitch > 0.0):
            raise ValueError(f"cloud focus pitch: must be a positive number, got {self.pitch}")
        if self.whole_attempts < 1:
            raise ValueError(f"cloud focus whole_attempts: must be at least 1, got {self.whole_attempts}")


def focused_obstacles(obstacles: Sequence[PlacedObstacle], centres: NDArray[np.float64], radii: NDArray[np.float64],
                      focus: CloudFocus) -> tuple[PlacedObstacle, ...]:
    """``obstacles`` with every non-empty point cloud split into its focus around the
    spheres ``(centres (m, 3), radii (m,))`` [m] at the goal and the rest (module docstring)."""
    centres = np.asarray(centres, dtype=float).reshape(-1, 3)
    radii = np.asarray(radii, dtype=float).reshape(-1)
    result: list[PlacedObstacle] = []
    for obstacle in obstacles:
        cloud = obstacle.shape
        if not isinstance(cloud, PointCloud) or isinstance(cloud, FocusedCloud) or cloud.empty:
            result.append(obstacle)
            continue
        local = obstacle.placement.to_local(centres)
        low = (local - radii[:, None]).min(axis=0) - focus.reach
        high = (local + radii[:, None]).max(axis=0) + focus.reach
        parts = split_cloud(cloud, low, high, focus.pitch)
        result.extend(PlacedObstacle(part, obstacle.placement) for part in parts if part is not None)
    return tuple(result)


class FocusCache:
    """The focus of the last plan's clouds around ``robot`` at its goal, made again only for
    other obstacles or another goal (a replan builds no new grids)."""

    def __init__(self, robot: Robot, focus: CloudFocus | None) -> None:
        self.robot = robot
        self.focus = focus
        self._last: tuple[tuple[PlacedObstacle, ...], bytes, tuple[PlacedObstacle, ...]] | None = None

    def focused(self, obstacles: Sequence[PlacedObstacle],
                target: NDArray[np.float64]) -> tuple[PlacedObstacle, ...] | None:
        """``obstacles`` with their point clouds focused around the robot at ``target``
        (:func:`focused_obstacles`), None without clouds or focus; the last result reused for
        the same obstacles (shapes and placements) and goal."""
        if self.focus is None or not any_cloud(obstacles):
            return None
        key = np.asarray(target, dtype=float).tobytes()
        last = self._last
        if (last is not None and last[1] == key and len(last[0]) == len(obstacles)
                and all(a.shape is b.shape and np.array_equal(a.placement.position, b.placement.position)
                        and np.array_equal(a.placement.orientation, b.placement.orientation)
                        for a, b in zip(last[0], obstacles))):
            return last[2]
        centres = np.asarray(self.robot.sphere_centers(target), dtype=float)
        focused = focused_obstacles(obstacles, centres, np.asarray(self.robot.sphere_radii, dtype=float), self.focus)
        self._last = (tuple(obstacles), key, focused)
        return focused
