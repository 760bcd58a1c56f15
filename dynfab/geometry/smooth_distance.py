"""Signed distance from a point to obstacle shapes in CasADi SX, smooth enough for fabrics.

A fabric leaf needs ``J = ∂d/∂x`` and ``J̇ ẋ = ẋᵀ ∇²d ẋ`` everywhere its point can go. The
exact distance (:mod:`dynfab.geometry.distance`) is C¹ outside a convex shape but its
Hessian jumps where the nearest feature changes (a box's face planes extended past its
edges, a cylinder's rim), and it has kinks inside. Where that happens the functions here
replace ``max(q, 0)`` by the smooth ramp

    m_ε(q) = (q + √(q² + ε²)) / 2,   max(q, 0) ≤ m_ε(q) ≤ max(q, 0) + ε/2,

with the smoothing length ``ε`` [m], and subtract the largest excess, so the result is
*conservative and bounded*: for every point outside or on the shape

    d − δ ≤ d_ε ≤ d,

where ``δ`` is given per shape (:func:`box_smoothing_bound`, ...). Inside the shape
``d − δ ≤ d_ε < ε₀``: the sign is right but the depth saturates near ``−δ`` (a robot
sphere whose centre is inside an obstacle is in collision either way, and the barrier is
clamped there; the gradient still points out through the nearest face).
``ε₀ = 1e-6`` m keeps Euclidean norms differentiable at zero (``√(‖x‖² + ε₀²)``); where
it is used it is counted in ``δ``.

Points ``x`` are (3, 1) expressions in the shape's frame [m]; sizes are expressions too
(runtime parameters of the planner).
"""

from __future__ import annotations

import math

import casadi as ca

__all__ = ["NORM_SMOOTHING", "box_smoothing_bound", "cylinder_smoothing_bound", "quaternion_rotation",
           "smooth_box_distance",
           "smooth_box_distance_derivatives",
           "smooth_capsule_distance", "smooth_cylinder_distance", "smooth_plane_distance", "smooth_ramp",
           "smooth_sphere_distance"]

#: ``ε₀`` [m]: regularises ``‖x‖`` at ``x = 0`` so its derivative stays finite.
NORM_SMOOTHING = 1e-6


def smooth_ramp(q: ca.SX, smoothing: float) -> ca.SX:
    """``m_ε(q) = (q + √(q² + ε²)) / 2`` elementwise: a C^∞ ``max(q, 0)`` that exceeds it by
    at most ``ε/2`` (at ``q = 0``) [m]."""
    return 0.5 * (q + ca.sqrt(q * q + smoothing**2))


def box_smoothing_bound(smoothing: float) -> float:
    """``δ = (√3/2) ε``: the most :func:`smooth_box_distance` under-estimates [m]."""
    return 0.5 * math.sqrt(3.0) * smoothing


def cylinder_smoothing_bound(smoothing: float) -> float:
    """``δ = (√2/2) ε + ε₀``: the most :func:`smooth_cylinder_distance` under-estimates [m]."""
    return 0.5 * math.sqrt(2.0) * smoothing + NORM_SMOOTHING


def smooth_sphere_distance(x: ca.SX, radius: ca.SX) -> ca.SX:
    """``d_ε = √(‖x‖² + ε₀²) − r − ε₀``; ``d − ε₀ ≤ d_ε ≤ d`` [m]."""
    return ca.sqrt(ca.dot(x, x) + NORM_SMOOTHING**2) - radius - NORM_SMOOTHING


def smooth_box_distance(x: ca.SX, size: ca.SX, smoothing: float) -> ca.SX:
    """Box of full edge lengths ``size`` (3, 1), centred, axis-aligned [m].

    ``q = |x| − size/2``, ``d_ε = ‖m_ε(q)‖ − δ`` with ``δ`` of :func:`box_smoothing_bound`.
    ``‖m_ε(q)‖ > 0`` everywhere, so ``d_ε`` is C^∞ in ``q``; ``|x|`` has a kink only on the
    box's mid-planes, where ``m_ε`` of that axis is below ``ε²/(2 size)`` and its slope
    below ``ε²/size²`` (negligible).
    """
    q = ca.fabs(x) - 0.5 * size
    ramp = smooth_ramp(q, smoothing)
    return ca.sqrt(ca.dot(ramp, ramp)) - box_smoothing_bound(smoothing)


def smooth_box_distance_derivatives(x: ca.SX, v: ca.SX, size: ca.SX, smoothing: float
                                    ) -> tuple[ca.SX, ca.SX, ca.SX]:
    """:func:`smooth_box_distance` with its gradient and curvature in closed form.

    With ``q = |x| − size/2``, ``w = √(q² + ε²)``, ``r = m_ε(q) = (q + w)/2``, ``a = r/w``
    (``= dr/dq``), ``b = ε²/(2 w³)`` (``= da/dq``), ``n = ‖r‖`` (all per axis but ``n``):

        d = n − δ,   ∇d_i = sign(x_i) r_i a_i / n,
        vᵀ ∇²d v = (Σ_i v_i² (a_i² + r_i b_i) − (∇d · v)²) / n.

    (``sign(x_i)`` has zero derivative away from the mid-planes, where it flips; there
    ``r_i a_i`` is below ``ε²/size`` and the kink is negligible, as in
    :func:`smooth_box_distance`.) Cheaper than automatic differentiation of that function.

    Args:
        x: point in the box frame (3, 1) [m].
        v: its velocity in the box frame (3, 1) [m/s].
        size: full edge lengths (3, 1) [m].
        smoothing: ``ε`` [m].

    Returns:
        ``d`` [m], ``∇d`` (3, 1) [-] and ``vᵀ ∇²d v`` [1/s² · m].
    """
    q = ca.fabs(x) - 0.5 * size
    w = ca.sqrt(q * q + smoothing**2)
    r = 0.5 * (q + w)
    a = r / w
    b = 0.5 * smoothing**2 / (w * w * w)
    n = ca.sqrt(ca.dot(r, r))
    gradient = ca.sign(x) * r * a / n
    slope = ca.dot(gradient, v)
    curvature = (ca.dot(v * v, a * a + r * b) - slope * slope) / n
    return n - box_smoothing_bound(smoothing), gradient, curvature


def smooth_cylinder_distance(x: ca.SX, radius: ca.SX, length: ca.SX, smoothing: float) -> ca.SX:
    """Solid cylinder along z, centred, of ``radius`` and full ``length`` [m].

    ``ρ = √(x² + y² + ε₀²)``, ``q = (ρ − r, |z| − l/2)``, ``d_ε = ‖m_ε(q)‖ − δ`` with
    ``δ`` of :func:`cylinder_smoothing_bound` (the rim is rounded by about ``ε``).
    """
    rho = ca.sqrt(x[0] ** 2 + x[1] ** 2 + NORM_SMOOTHING**2)
    q = ca.vertcat(rho - radius, ca.fabs(x[2]) - 0.5 * length)
    ramp = smooth_ramp(q, smoothing)
    return ca.sqrt(ca.dot(ramp, ramp)) - cylinder_smoothing_bound(smoothing)


def smooth_capsule_distance(x: ca.SX, radius: ca.SX, length: ca.SX) -> ca.SX:
    """Capsule about the z segment ``[−l/2, l/2]`` [m]: exact up to ``ε₀`` (C¹: its Hessian
    jumps only where a cap meets the side, by at most ``1/‖x − segment‖``).

    ``e = z − clamp(z, −l/2, l/2)``, ``d_ε = √(x² + y² + e² + ε₀²) − r − ε₀``.
    """
    half = 0.5 * length
    beyond = x[2] - ca.fmin(ca.fmax(x[2], -half), half)
    return ca.sqrt(x[0] ** 2 + x[1] ** 2 + beyond**2 + NORM_SMOOTHING**2) - radius - NORM_SMOOTHING


def smooth_plane_distance(x: ca.SX) -> ca.SX:
    """The half-space ``z ≤ 0``: ``d = z`` (exact) [m]."""
    return x[2]


def quaternion_rotation(quaternion: ca.SX) -> ca.SX:
    """Rotation matrix (3, 3) of the quaternion ``(w, x, y, z)`` after normalising it,
    ``q / √(‖q‖² + 10⁻¹²)``; the zero quaternion gives the identity (an inactive slot)."""
    w, x, y, z = ca.vertsplit(quaternion / ca.sqrt(ca.dot(quaternion, quaternion) + 1e-12), 1)
    return ca.vertcat(
        ca.horzcat(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        ca.horzcat(2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        ca.horzcat(2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    )
