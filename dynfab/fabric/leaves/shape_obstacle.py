"""Obstacle avoidance against a box, cylinder, capsule or half-space plane, static or moving.

Task map, for one robot sphere (centre ``p``, radius ``r_s``) and one shape slot (frame
origin ``c(t)``, rotation ``R`` from the slot's quaternion, sizes ``s``):

    x = d_ε(Rᵀ (p − c), s) − r_s + a    [m],

the smoothed signed distance of :mod:`dynfab.geometry.smooth_distance` (conservative: it
under-estimates the exact distance by at most ``δ`` of the shape, a few millimetres for the
default smoothing ``ε = 0.01 m``) and ``a`` the slot's allowance, how far the spheres may
enter the shape (a runtime parameter, 0 by default). ``J`` and ``J̇ ṗ`` are in closed form for a box
(:func:`~dynfab.geometry.smooth_distance.smooth_box_distance_derivatives`) and follow by
automatic differentiation for the other shapes.
The leaf is the :class:`~dynfab.fabric.leaves.barrier.Barrier` on ``x``, written in the
coordinates ``p_rel = p − c`` and brought to the fixed frame by the dynamic pullback with
the origin's ``ċ`` and ``c̈``, exactly as
:class:`~dynfab.fabric.leaves.obstacle.SphereObstacleAvoidance`: a moving shape
*translates*; its rotation is taken as constant (its rate does not enter the pullback).

Planar robots (``p`` in the xy-plane) see the shape at the height of its origin:
``p_rel = (p_x − c_x, p_y − c_y, 0)``, so an upright box, cylinder or capsule acts as its
cross-section there and a vertical plane as a wall line.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from dynfab.fabric.energy import WeightedGeometry
from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.maps import DifferentialMap, Reference
from dynfab.fabric.parameters import ShapeSymbols
from dynfab.geometry.smooth_distance import (
    quaternion_rotation,
    smooth_box_distance,
    smooth_box_distance_derivatives,
    smooth_capsule_distance,
    smooth_cylinder_distance,
    smooth_plane_distance,
)


@dataclass(frozen=True)
class ShapeObstacleAvoidance:
    """Keeps robot spheres outside boxes, cylinders, capsules and half-spaces.

    Attributes:
        barrier: geometry and energy on the clearance; the sphere leaf's defaults
            (``k = 5``, ``λ = 0.5``, range 0.2 m).
        smoothing: ``ε`` of the box and cylinder distances [m]; the clearance is
            under-estimated by at most ``(√3/2) ε`` (box) or ``(√2/2) ε`` (cylinder).
    """

    barrier: Barrier = field(default_factory=lambda: Barrier(geometry_gain=5.0, energy_gain=0.5, horizon=0.2))
    smoothing: float = 0.01

    def __post_init__(self) -> None:
        if not self.smoothing > 0:
            raise ValueError(f"ShapeObstacleAvoidance.smoothing must be > 0, got {self.smoothing}")

    def distance(self, kind: str, local: ca.SX, dimensions: ca.SX) -> ca.SX:
        """Smoothed signed distance [m] of a point ``local`` (3, 1) in the shape's frame."""
        if kind == "box":
            return smooth_box_distance(local, dimensions, self.smoothing)
        if kind == "cylinder":
            return smooth_cylinder_distance(local, dimensions[0], dimensions[1], self.smoothing)
        if kind == "capsule":
            return smooth_capsule_distance(local, dimensions[0], dimensions[1])
        if kind == "plane":
            return smooth_plane_distance(local)
        raise ValueError(f"ShapeSymbols.kind: unknown shape {kind!r}")

    def clearance_map(self, relative: ca.SX, relative_velocity: ca.SX, slot: ShapeSymbols,
                      sphere_radius: float) -> DifferentialMap:
        """``x = d_ε(Rᵀ p̄_rel, s) − r_s + a`` [m] with ``J``, ``J̇ ṗ_rel`` by automatic
        differentiation; ``p̄_rel`` is ``p_rel`` (d, 1) padded with zeros to 3-D."""
        d = relative.shape[0]
        rotation = quaternion_rotation(slot.orientation)
        local = ca.mtimes(rotation.T, _lifted(relative))
        if slot.kind == "box":  # closed-form derivatives: cheaper than automatic differentiation
            local_velocity = ca.mtimes(rotation.T, _lifted(relative_velocity))
            distance, gradient, curvature = smooth_box_distance_derivatives(
                local, local_velocity, slot.dimensions, self.smoothing)
            jacobian = ca.mtimes(rotation, gradient)[:d].T
            return DifferentialMap(distance - sphere_radius + slot.allowance, jacobian, curvature, relative,
                                   relative_velocity)
        clearance = self.distance(slot.kind, local, slot.dimensions) - sphere_radius + slot.allowance
        return DifferentialMap.from_expression(clearance, relative, relative_velocity)

    def on_point(self, point: ca.SX, point_velocity: ca.SX, slot: ShapeSymbols,
                 sphere_radius: float) -> WeightedGeometry:
        """The leaf pulled to the point space of one robot sphere.

        Args:
            point: sphere centre symbols ``p`` (d, 1), d = 2 or 3 [m].
            point_velocity: ``ṗ`` symbols (d, 1) [m/s].
            slot: the shape slot's parameters (origin reference, orientation, sizes).
            sphere_radius: radius of the robot sphere [m].
        """
        d = point.shape[0]
        distance = self.clearance_map(ca.SX.sym("p_rel", d), ca.SX.sym("p_rel_dot", d), slot, sphere_radius)
        in_shape_frame = self.barrier.weighted_geometry().scaled(_active(slot)).pull(distance)
        reference = slot.reference
        origin = Reference(reference.position[:d], reference.velocity[:d], reference.acceleration[:d])
        return in_shape_frame.dynamic_pull(point, point_velocity, origin)


def _lifted(vector: ca.SX) -> ca.SX:
    """A planar (2, 1) vector padded with a zero z; a 3-D one unchanged."""
    return ca.vertcat(vector, ca.SX(3 - vector.shape[0], 1))


def _active(slot: ShapeSymbols) -> ca.SX:
    """1 for a slot in use: all sizes > 0 (a plane: a non-zero quaternion), else 0."""
    if slot.kind == "plane":
        return ca.dot(slot.orientation, slot.orientation) > 1e-12
    smallest = slot.dimensions[0]
    for i in range(1, slot.dimensions.shape[0]):
        smallest = ca.fmin(smallest, slot.dimensions[i])
    return smallest > 0
