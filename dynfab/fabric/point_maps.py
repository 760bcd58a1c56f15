"""Maps of points fixed on links (collision-sphere centres), sharing the work per link.

A point with offset ``c`` [m] in the frame of a link with pose ``(p_l(q), R_l(q))`` is

    x = p_l + R_l c,
    J = J_p + Σ_m c_m J_{R,m},                 J_{R,m} = ∂(R_l e_m)/∂q   (3, n)
    J̇ q̇ = a_p + Σ_m c_m a_{R,m},               a_{R,m} = (d/dt J_{R,m}) q̇

with ``J_p = ∂p_l/∂q``, ``a_p = J̇_p q̇``: everything is linear in ``c``. The derivatives of
the link's pose are taken once per link by automatic differentiation, and each point costs
a few multiply-adds per Jacobian entry instead of its own derivatives of the whole chain
(about half the instructions of :meth:`DifferentialMap.from_expression` per point on a
Panda).
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca

from dynfab.fabric.maps import DifferentialMap
from dynfab.robots.kinematics import Kinematics

__all__ = ["link_point_maps"]


def link_point_maps(kinematics: Kinematics, q: ca.SX, qdot: ca.SX,
                    points: Sequence[tuple[str, Sequence[float]]], dims: int = 3) -> list[DifferentialMap]:
    """The maps ``q ↦ x`` of points ``(link, offset)``, keeping the first ``dims`` coordinates.

    Args:
        kinematics: The robot's kinematics.
        q: Joint position symbols (n, 1).
        qdot: Joint velocity symbols (n, 1).
        points: ``(link, offset in the link frame [m])`` per point.
        dims: 3, or 2 for a planar robot (x, y).
    """
    per_link: dict[str, tuple[ca.SX, ...]] = {}
    maps = []
    for link, offset in points:
        if link not in per_link:
            per_link[link] = _link_derivatives(kinematics.transform(q, link), q, qdot)
        position, rotation, position_jacobian, axis_jacobians, position_curvature, axis_curvatures = per_link[link]
        phi, jacobian, curvature = position, position_jacobian, position_curvature
        for m, c in enumerate(float(value) for value in offset):
            if c != 0.0:
                phi = phi + c * rotation[:, m]
                jacobian = jacobian + c * axis_jacobians[m]
                curvature = curvature + c * axis_curvatures[m]
        maps.append(DifferentialMap(phi[:dims], jacobian[:dims, :], curvature[:dims], q, qdot))
    return maps


def _link_derivatives(transform: ca.SX, q: ca.SX, qdot: ca.SX) -> tuple[ca.SX, ...]:
    """``p_l``, ``R_l``, ``J_p``, ``[J_{R,m}]``, ``a_p``, ``[a_{R,m}]`` of a link pose."""
    position = transform[:3, 3]
    rotation = transform[:3, :3]
    position_jacobian = ca.jacobian(position, q)
    axis_jacobians = [ca.jacobian(rotation[:, m], q) for m in range(3)]

    def curvature(jacobian: ca.SX) -> ca.SX:
        return ca.jtimes(ca.mtimes(jacobian, qdot), q, qdot)

    return (position, rotation, position_jacobian, axis_jacobians, curvature(position_jacobian),
            [curvature(j) for j in axis_jacobians])
