"""Finite joint bounds, for sampling configurations and keeping a search within reach.

A joint's position limits (``Kinematics.lower`` / ``upper``, ``∓inf`` where a URDF joint has
none, as a continuous joint) bound it where they are finite; where they are not, one turn
about zero does:

    l_i' = l_i if l_i is finite else −π,    u_i' = u_i if u_i is finite else π    [rad or m]
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["UNLIMITED_JOINT_BOUND", "finite_joint_bounds"]

#: the bound of a joint without a position limit: one turn about zero, ``±π`` [rad]
UNLIMITED_JOINT_BOUND = np.pi


def finite_joint_bounds(lower: ArrayLike, upper: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(l', u')`` of the module docstring for the position limits ``lower`` and ``upper``
    (n,) [rad or m], as new arrays."""
    return (np.where(np.isfinite(lower), lower, -UNLIMITED_JOINT_BOUND),
            np.where(np.isfinite(upper), upper, UNLIMITED_JOINT_BOUND))
