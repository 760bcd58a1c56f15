"""Which of a plan's way allowances hold where the robot is
(:meth:`~dynfab.motion.guidance.JointGuidance.way_allowances`,
:meth:`~dynfab.motion.guided_fabric.GuidedFabric.allowances`).

A way's allowances let the fabric's leaves see, at each configuration of the plan, what
the plan's tighter spheres kept there. They hold near where the robot and its reference
are: per obstacle, the largest allowance of the way's configurations from the one before
the nearer of the two (of the robot's nearest and the reference's nearest) to
:data:`WAY_AHEAD` beyond the farther, so that an allowance is in place before the robot
reaches the configuration that needs it and gone once it is past. An allowance was read at
the way's configurations, so it holds only near the way: in full while the robot is within
``reach`` [rad] of the way's configuration nearest it, fading linearly to none at twice
that (a robot pushed off its way kept an allowance meant for another sphere: fresh
generated seed 21, as posed table_under_pick/0005, lay 0.25 rad off its way with the 14 mm
allowance of a box that its hand's spheres needed on the way, and ``panda_link7``, whose
spheres fit its meshes tightly, touched that box). Within ``reach`` the guided fabric caps
them by what the robot's own configuration gives
(:meth:`~dynfab.motion.allowance_tables.AllowanceTables.way_at`): 0.09 rad beside its way
a robot kept the way's 7-10 mm and put a finger on MBM table_bars' bars (fresh seed 34).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["WAY_AHEAD", "WayWindow", "way_window"]

#: configurations of the way (``path.resolution`` apart) beyond the robot's and the
#: reference's nearest whose allowances count [-]
WAY_AHEAD = 3


@dataclass(frozen=True)
class WayWindow:
    """Where on its way the robot is.

    Attributes:
        rows: The way's configurations whose allowances count (module docstring).
        held: The share of them that holds, ``clip(2 − d / reach, 0, 1)`` [-].
    """

    rows: slice
    held: float

    def allowances(self, table: NDArray[np.float64]) -> NDArray[np.float64]:
        """Per obstacle, the largest allowance [m] of ``table`` (k, m) in :attr:`rows`, times :attr:`held`."""
        return self.held * table[self.rows].max(axis=0)


def way_window(way: NDArray[np.float64], q: NDArray[np.float64], reference: NDArray[np.float64],
               reach: float = np.inf) -> WayWindow:
    """The window of ``way`` (k, n) [rad] near the robot at ``q`` and its reference at
    ``reference``, ``d`` the robot's distance from the nearest of its configurations [rad]
    (module docstring)."""
    distances = np.linalg.norm(way - q, axis=1)
    robot = int(np.argmin(distances))
    followed = int(np.argmin(np.linalg.norm(way - reference, axis=1)))
    first = max(0, min(robot, followed) - 1)
    held = float(np.clip(2.0 - distances[robot] / reach, 0.0, 1.0))
    return WayWindow(slice(first, max(robot, followed) + WAY_AHEAD + 1), held)

