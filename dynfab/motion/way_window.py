"""Which of a plan's way allowances hold where the robot is
(:meth:`~dynfab.motion.guidance.JointGuidance.way_allowances`,
:meth:`~dynfab.motion.guided_fabric.GuidedFabric.allowances`).

A way's allowances let the fabric's leaves see, at each configuration of the plan, what
the plan's tighter spheres kept there. They hold near where the robot and its reference
are: per obstacle, the largest allowance of the way's configurations from the one before
the nearer of the two (of the robot's nearest and the reference's nearest) to
:data:`WAY_AHEAD` beyond the farther, so that an allowance is in place before the robot
reaches the configuration that needs it and gone once it is past.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["WAY_AHEAD", "allowances_near"]

#: configurations of the way (``path.resolution`` apart) beyond the robot's and the
#: reference's nearest whose allowances count [-]
WAY_AHEAD = 3


def allowances_near(way: NDArray[np.float64], table: NDArray[np.float64], q: NDArray[np.float64],
                    reference: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per obstacle, the largest allowance [m] of ``table`` (k, m) at the configurations of
    ``way`` (k, n) [rad] near the robot at ``q`` and its reference at ``reference`` (module
    docstring)."""
    robot = int(np.argmin(np.linalg.norm(way - q, axis=1)))
    followed = int(np.argmin(np.linalg.norm(way - reference, axis=1)))
    first = max(0, min(robot, followed) - 1)
    return table[first:max(robot, followed) + WAY_AHEAD + 1].max(axis=0)
