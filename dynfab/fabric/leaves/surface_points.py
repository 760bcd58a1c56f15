"""Avoidance of surfaces known only by their nearest points: meshes (and point clouds).

Each control tick the caller writes, for every robot collision sphere ``i`` (centre
``p_i(q)``, radius ``r_i``), the nearest point ``c_i`` of the surfaces around it, the
outward unit normal ``n_i`` there (from the surface toward the sphere) and the velocity
``v_i`` of that surface point (zero for a static surface), and whether there is one
(``active_i``: 1 or 0). The leaf keeps the sphere in front of the tangent plane at ``c_i``:

    x_i = n_iᵀ (p_i(q) − c_i) − r_i                   [m],
    J_i = n_iᵀ J_{p_i},      J̇_i q̇ = n_iᵀ J̇_{p_i} q̇,

under the :class:`~dynfab.fabric.leaves.barrier.Barrier`, in the relative coordinates of a
surface point that moves with ``v_i`` (the dynamic pullback, ``ẋ_rel = n_iᵀ (ṗ_i − v_i)``,
as for moving shapes). At the configuration where the points were found ``x_i`` is the exact
clearance ``‖p_i − c_i‖ − r_i`` and ``J_i`` the exact gradient of the distance to the
surface, so the leaf is exact to first order wherever the nearest point is unique; between
ticks the tangent plane stands for the surface. Nothing here knows about meshes: a point
cloud's nearest points serve as well.

With ``far_side`` every sphere has a second slot, the same leaf on a second point: one
nearest point stands for one surface, and a link between two (a cage's bar and its side wall)
sees only the nearer until the other is the nearer and too close to brake for. The feed
writes there a point of another side (:mod:`dynfab.geometry.cloud_far_side`).

A leaf of the leaf interface (:mod:`dynfab.fabric.leaf`); its runtime parameters
(``planner.parameters.leaves[name]``), for its ``K`` slots (the spheres it acts on in their
order, then with ``far_side`` the same spheres again): ``points`` (3K), ``normals`` (3K),
``velocities`` (3K) [m, -, m/s] and ``active`` (K).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import casadi as ca

from dynfab.fabric.energy import WeightedGeometry
from dynfab.fabric.leaf import LeafContext
from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.maps import DifferentialMap, Reference
from dynfab.fabric.point_maps import link_point_maps
from dynfab.robots.robot import Robot

__all__ = ["NearestSurfaceAvoidance", "moving_spheres"]


@dataclass(frozen=True)
class NearestSurfaceAvoidance:
    """Keeps robot spheres off surfaces given by their nearest points (module docstring).

    Attributes:
        spheres: Indices of the robot's collision spheres the leaf acts on (``K`` of them);
            :func:`moving_spheres` gives every sphere some joint moves.
        name: The leaf's name (unique among the planner's leaves).
        barrier: Geometry and energy on the clearance; by default the shape obstacles'
            (``k = 5``, ``λ = 0.5``, range 0.2 m).
        far_side: Give every sphere a second slot (module docstring).
    """

    spheres: tuple[int, ...]
    name: str = "surfaces"
    barrier: Barrier = field(default_factory=lambda: Barrier(geometry_gain=5.0, energy_gain=0.5, horizon=0.2))
    far_side: bool = False

    @property
    def slots(self) -> tuple[int, ...]:
        """The sphere of each slot: :attr:`spheres`, then again with :attr:`far_side`."""
        return self.spheres + self.spheres if self.far_side else self.spheres

    def parameter_sizes(self) -> Mapping[str, int]:
        k = len(self.slots)
        return {"points": 3 * k, "normals": 3 * k, "velocities": 3 * k, "active": k} if k else {}

    def geometry(self, context: LeafContext) -> WeightedGeometry:
        robot = context.robot
        if robot.planar:
            raise ValueError(f"leaf {self.name!r}: surfaces are 3-D; a planar robot cannot avoid them")
        spheres = [robot.collision_spheres[i] for i in self.slots]
        maps = link_point_maps(robot.kinematics, context.q, context.qdot,
                               [(sphere.link, sphere.center) for sphere in spheres])
        n = context.q.shape[0]
        total = WeightedGeometry(ca.SX(n, n), ca.SX(n, 1), ca.SX(n, 1), context.q, context.qdot)
        if not spheres:
            return total
        values = context.parameters
        leaf = self.barrier.weighted_geometry()
        for k, (sphere, point_map) in enumerate(zip(spheres, maps)):
            point, normal = values["points"][3 * k:3 * k + 3], values["normals"][3 * k:3 * k + 3]
            velocity = values["velocities"][3 * k:3 * k + 3]
            clearance = DifferentialMap(
                ca.dot(normal, point_map.phi - point) - sphere.radius, ca.mtimes(normal.T, point_map.jacobian),
                ca.dot(normal, point_map.jdot_qdot), context.q, context.qdot)
            moving = Reference(ca.SX(1, 1), ca.dot(normal, velocity), ca.SX(1, 1))
            relative = leaf.scaled(values["active"][k]).dynamic_pull(leaf.x, leaf.xdot, moving)
            total = total + relative.pull(clearance)
        return total


def moving_spheres(robot: Robot) -> tuple[int, ...]:
    """Indices of the robot's collision spheres that some joint moves (the others cannot
    avoid anything)."""
    q = ca.SX.sym("q", robot.kinematics.dof)
    centres = robot.sphere_centers(q)
    return tuple(i for i in range(len(robot.collision_spheres))
                 if ca.jacobian(centres[i, :], q).nnz() > 0)
