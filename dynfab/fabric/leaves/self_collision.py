"""Self-collision avoidance between two robot spheres.

Task map: ``x = ‖p_a(q) − p_b(q)‖ − r_a − r_b`` [m], composed from the two spheres'
forward-kinematics maps (``J = nᵀ (J_a − J_b)``); the leaf is a
:class:`~dynfab.fabric.leaves.barrier.Barrier` on ``x``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from dynfab.fabric.energy import WeightedGeometry
from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.maps import DifferentialMap, difference, sphere_distance_map


@dataclass(frozen=True)
class SelfCollisionAvoidance:
    """Keeps pairs of robot spheres apart.

    Attributes:
        barrier: geometry and energy on the pair's clearance.
    """

    barrier: Barrier = field(default_factory=lambda: Barrier(geometry_gain=0.5, energy_gain=0.1, horizon=0.2))

    def on_pair(self, sphere_a: DifferentialMap, sphere_b: DifferentialMap,
                radius_a: float, radius_b: float) -> WeightedGeometry:
        """The pair's leaf pulled to joint space."""
        d = sphere_a.phi.shape[0]
        offset = ca.SX.sym("offset", d)
        offset_velocity = ca.SX.sym("offset_velocity", d)
        distance = sphere_distance_map(offset, offset_velocity, ca.SX.zeros(d), radius_a + radius_b)
        pair = distance.after(difference(sphere_a, sphere_b))
        return self.barrier.weighted_geometry().pull(pair)
