"""Workspace bounds: a point on a link kept inside an axis-aligned box of the world frame
(a work cell's safe zone), written at run time. A leaf of the leaf interface
(:mod:`dynfab.fabric.leaf`): the planner builds it without knowing its kind.

Task maps: the distances of the point ``p(q)`` to the box's six faces,

    x_i⁻ = p_i − l_i,    x_i⁺ = u_i − p_i    [m],   J = ±e_iᵀ J_p,   J̇ q̇ = ±e_iᵀ J̇_p q̇,

each under the :class:`~dynfab.fabric.leaves.barrier.Barrier`; ``l`` and ``u`` are the runtime
parameters ``lower`` and ``upper``. An axis with ``u_i ≤ l_i`` is unbounded (its two leaves
are off): every axis is, until the bounds are written.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import casadi as ca

from dynfab.fabric.energy import WeightedGeometry
from dynfab.fabric.leaf import LeafContext
from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.maps import DifferentialMap


@dataclass(frozen=True)
class WorkspaceBounds:
    """Keeps a point of ``link`` inside ``[lower, upper]`` (world frame).

    Runtime parameters (``planner.parameters.leaves[name]``): ``lower`` and ``upper``, the
    box's corners (3,) [m]; an axis with ``upper ≤ lower`` is unbounded.

    Attributes:
        link: the link carrying the point.
        offset: the point in the link frame [m].
        name: the leaf's name (unique among the planner's leaves).
        barrier: geometry and energy on the distance to a face [m]; by default the sphere
            obstacle leaf's gains (``k = 5``, ``λ = 0.5``) with a 0.1 m range, so that it
            acts only near a face.
    """

    link: str
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    name: str = "workspace"
    barrier: Barrier = field(default_factory=lambda: Barrier(geometry_gain=5.0, energy_gain=0.5, horizon=0.1))

    def parameter_sizes(self) -> Mapping[str, int]:
        return {"lower": 3, "upper": 3}

    def geometry(self, context: LeafContext) -> WeightedGeometry:
        point = context.link_point(self.link, self.offset)
        lower, upper = context.parameters["lower"], context.parameters["upper"]
        n = context.q.shape[0]
        total = WeightedGeometry(ca.SX(n, n), ca.SX(n, 1), ca.SX(n, 1), context.q, context.qdot)
        leaf = self.barrier.weighted_geometry()
        for i in range(point.phi.shape[0]):
            bounded = upper[i] > lower[i]
            for sign, face in ((1.0, lower[i]), (-1.0, upper[i])):
                distance = DifferentialMap(sign * (point.phi[i] - face), sign * point.jacobian[i, :],
                                           sign * point.jdot_qdot[i], context.q, context.qdot)
                total = total + leaf.scaled(bounded).pull(distance)
        return total
