"""Each tick, a point cloud's nearest points written into a nearest-point leaf, in two buffer
evaluations around one KD-tree query.

For the ``K`` spheres of a :class:`~dynfab.fabric.leaves.surface_points.NearestSurfaceAvoidance`
leaf (centres ``x_i(q)``, radii ``r_i``) and a cloud of kept points ``C`` (voxel centres,
lowering ``δ = h√3/2``, :class:`~dynfab.geometry.point_cloud.PointCloud`), a tick is

1. the centres ``x_i(q)`` (K, 3) [m]: a CasADi function of ``q`` evaluated on fixed buffers
   (no argument conversion: 0.2 µs compiled, 1.5 µs in the VM, for the Panda's 58 spheres);
2. one KD-tree query of all ``K`` centres, bounded by ``max_i reach_i + δ``, giving per
   sphere its nearest kept point ``c_i`` and whether one is within the bound (``f_i``);
3. a second CasADi function of ``(x, c, f, δ)`` whose outputs are the leaf's own parameter
   views (no copy, no per-sphere loop): with ``e_i = x_i − c_i``, ``g_i = ‖e_i‖``,

       n_i = e_i / g_i  (n_i = +z if g_i <= 10⁻¹²),
       active_i = f_i · [g_i − δ <= reach_i],
       points_i = active_i (c_i + δ n_i),   normals_i = n_i if active_i else +z,
       velocities_i = 0                                                       [m, -, m/s],

   ``reach_i = horizon + offset + r_i`` of the leaf's barrier. The written point lies ``δ``
   from ``c_i`` toward the sphere, so the leaf's clearance ``‖x_i − c_i‖ − δ − r_i`` never
   exceeds the distance to a measured point (the same values as
   :meth:`PointCloud.nearest <dynfab.geometry.point_cloud.PointCloud.nearest>` with
   :class:`~dynfab.perception.surfaces.SurfaceFeed`).

An empty cloud skips the query and writes every sphere inactive. Both functions are
compiled to C on the ``"c"`` backend (:mod:`dynfab.fabric.c_backend`: cached as the planners'
libraries are, by their code; the CasADi VM without a compiler): the Panda's writer costs
1.2 µs compiled, about 9 µs in the VM; the query about 10 µs (a 53 k-point table scene).
"""

from __future__ import annotations

import sys

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from dynfab.fabric import c_backend
from dynfab.fabric.backends import default_backend
from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance
from dynfab.fabric.parameters import LeafViews
from dynfab.geometry.point_cloud import PointCloud
from dynfab.robots.robot import Robot

__all__ = ["NearestCloudPoints"]

#: Shorter offsets than this [m] get the normal +z (a sphere centre on a kept point).
_TINY = 1e-12
#: The name :func:`dynfab.fabric.c_backend.compile_planner` loads a library's function by.
_COMPILED_NAME = "fabric"
#: The leaf's parameters, in the order of the writer's outputs.
_OUTPUTS = ("points", "normals", "velocities", "active")


class NearestCloudPoints:
    """Writes a nearest-point leaf from a point cloud each tick (module docstring).

    Attributes:
        reach: Per sphere of the leaf, how far from its centre points are looked for [m].
        index: Per sphere, the row of its nearest kept point in the last cloud written (K,);
            valid where the leaf's ``active`` is 1 (elsewhere it may be the cloud's length).
    """

    def __init__(self, robot: Robot, leaf: NearestSurfaceAvoidance, views: LeafViews,
                 backend: str | None = None) -> None:
        if leaf.far_side:
            raise ValueError(f"leaf {leaf.name!r}: far_side slots are written by SurfaceFeed, "
                             "not by the per-tick cloud writer (one point per sphere)")
        spheres = list(leaf.spheres)
        count = len(spheres)
        radii = np.asarray(robot.sphere_radii, dtype=float)[spheres]
        self.reach = leaf.barrier.horizon + leaf.barrier.offset + radii
        self.index: NDArray[np.integer] = np.zeros(count, dtype=np.int64)
        self._reach = float(self.reach.max()) if count else 0.0
        self._count = count
        self._q = np.zeros(robot.kinematics.dof)
        # writer input z = [x (3K, row-major), c (3K), f (K), δ]; the centres are evaluated into it
        self._input = np.zeros(7 * count + 1)
        self._centres = self._input[:3 * count].reshape(count, 3)
        self._nearest = self._input[3 * count:6 * count].reshape(count, 3)
        self._found = self._input[6 * count:7 * count]
        if count == 0:
            self._evaluate_centres = self._evaluate_writer = _nothing
            return
        q = ca.SX.sym("q", robot.kinematics.dof)
        backend = default_backend() if backend is None else backend
        centres = _evaluable(ca.Function(_COMPILED_NAME, [q], [ca.vec(robot.sphere_centers(q)[spheres, :].T)]),
                             backend)
        self._centres_buffer, self._evaluate_centres = centres.buffer()
        self._centres_buffer.set_arg(0, memoryview(self._q))
        self._centres_buffer.set_res(0, memoryview(self._input[:3 * count]))
        writer = _evaluable(_writer_function(self.reach), backend)
        self._writer_buffer, self._evaluate_writer = writer.buffer()
        self._writer_buffer.set_arg(0, memoryview(self._input))
        for slot, key in enumerate(_OUTPUTS):
            view = views[key]
            if not (view.flags.c_contiguous and view.flags.writeable):
                raise ValueError(f"leaves[{leaf.name!r}][{key!r}]: expected a writable contiguous view")
            self._writer_buffer.set_res(slot, memoryview(view))

    @property
    def centres(self) -> NDArray[np.float64]:
        """The leaf's sphere centres at the last ``q`` written (K, 3) [m] (a view; copy to keep)."""
        return self._centres

    def write(self, q: NDArray[np.float64], cloud: PointCloud) -> None:
        """Write the leaf's nearest points of ``cloud`` for the configuration ``q``.

        Raises:
            ValueError: ``q`` has the wrong length.
        """
        if np.shape(q) != self._q.shape:
            raise ValueError(f"q must have shape {self._q.shape}, got {np.shape(q)}")
        if self._count == 0:
            return
        self._q[:] = q
        self._evaluate_centres()
        if cloud.empty:
            self._found[:] = 0.0
        else:
            gaps, self.index = cloud.tree.query(self._centres, distance_upper_bound=self._reach + cloud.lowering)
            np.take(cloud.points, self.index, axis=0, out=self._nearest, mode="clip")
            np.isfinite(gaps, out=self._found, casting="unsafe")
        self._input[-1] = cloud.lowering
        self._evaluate_writer()


def _writer_function(reach: NDArray[np.float64]) -> ca.Function:
    """Step 3 of the module docstring: ``z = [x, c, f, δ] ↦ (points, normals, velocities,
    active)`` for spheres of reach ``reach`` (K,) [m]."""
    count = len(reach)
    z = ca.SX.sym("z", 7 * count + 1)
    delta = z[7 * count]
    up = ca.DM([0.0, 0.0, 1.0])
    points, normals, actives = [], [], []
    for i in range(count):
        x, c, found = z[3 * i:3 * i + 3], z[3 * count + 3 * i:3 * count + 3 * i + 3], z[6 * count + i]
        offset = x - c
        length = ca.norm_2(offset)
        normal = ca.if_else(length > _TINY, offset / ca.fmax(length, _TINY), up)
        active = found * (length - delta <= float(reach[i]))
        points.append(active * (c + delta * normal))
        normals.append(ca.if_else(active > 0.5, normal, up))
        actives.append(active)
    return ca.Function(_COMPILED_NAME, [z],
                       [ca.vertcat(*points), ca.vertcat(*normals), ca.SX.zeros(3 * count), ca.vertcat(*actives)])


def _evaluable(function: ca.Function, backend: str) -> ca.Function:
    """``function`` compiled to C on the ``"c"`` backend (or loaded from the cache), else as
    it is (the VM; also when no compiler works, with one warning line)."""
    compiler = c_backend.find_compiler() if backend == "c" else None
    if compiler is None:
        return function
    try:
        return c_backend.compile_planner(function, compiler).function
    except (RuntimeError, OSError) as error:
        print(f"dynfab: warning: {error}; the point-cloud feed uses the CasADi VM", file=sys.stderr)
        return function


def _nothing() -> None:
    """A leaf without spheres has nothing to evaluate."""
