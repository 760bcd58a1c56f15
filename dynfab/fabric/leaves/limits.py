"""Joint-limit avoidance: a barrier on ``q_i − q_low,i`` and on ``q_high,i − q_i``.

The task maps are rows of the identity (``J = ±e_iᵀ``, ``J̇ q̇ = 0``), so each side adds one
diagonal entry to the root metric.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from dynfab.fabric.energy import WeightedGeometry
from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.maps import linear_map


@dataclass(frozen=True)
class JointLimitAvoidance:
    """Keeps each limited joint inside ``[low, high]``.

    Attributes:
        barrier: geometry and energy on the distance to a limit [rad or m].
    """

    barrier: Barrier = field(default_factory=lambda: Barrier(geometry_gain=0.1, energy_gain=0.05))

    def on_joints(self, q: ca.SX, qdot: ca.SX, lower: np.ndarray, upper: np.ndarray) -> WeightedGeometry:
        """Sum of both sides' leaves for every joint with finite limits, in joint space."""
        n = q.shape[0]
        leaf = self.barrier.weighted_geometry()
        total = WeightedGeometry(ca.SX(n, n), ca.SX(n, 1), ca.SX(n, 1), q, qdot)
        for i in range(n):
            row = np.zeros((1, n))
            row[0, i] = 1.0
            if np.isfinite(lower[i]):
                total = total + leaf.pull(linear_map(row, ca.SX(lower[i]), q, qdot))
            if np.isfinite(upper[i]):
                total = total + leaf.pull(linear_map(-row, ca.SX(-upper[i]), q, qdot))
        return total
