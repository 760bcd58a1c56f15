"""Each tick, a point cloud's nearest points written into a nearest-point leaf, in two buffer
evaluations around one KD-tree query (three queries and three evaluations with far-side slots).

For the ``K`` spheres of a :class:`~dynfab.fabric.leaves.surface_points.NearestSurfaceAvoidance`
leaf (centres ``x_i(q)``, radii ``r_i``) and a cloud of kept points ``C`` (voxel centres,
lowering ``δ = h√3/2``, :class:`~dynfab.geometry.point_cloud.PointCloud`), a tick is

1. the centres ``x_i(q)`` (K, 3) [m] and each sphere's reach [m]: a CasADi function of
   ``(q, q̇)`` evaluated on fixed buffers (no argument conversion). The reach is the leaf's
   barrier's ``horizon + offset + r_i``, and with a braking barrier (``a_b``) and ``q̇``
   given, grown by the sphere's stopping distance as the scenario's feed grows it
   (:meth:`SurfaceFeed.braking_reach <dynfab.perception.surfaces.SurfaceFeed.braking_reach>`):

       reach_i = horizon + offset + r_i + ‖J_{x_i}(q) q̇‖² / (2 a_b)          [m];

2. one KD-tree query of all ``K`` centres, bounded by ``max_i reach_i + δ``, giving per
   sphere its nearest kept point ``c_i`` and whether one is within the bound (``f_i``);
3. a second CasADi function of ``(x, reach, c, f, δ)`` whose outputs are the leaf's own
   parameter views (no copy, no per-sphere loop): with ``e_i = x_i − c_i``, ``g_i = ‖e_i‖``,

       n_i = e_i / g_i  (n_i = +z if g_i <= 10⁻¹²),
       active_i = f_i · [g_i − δ <= reach_i],
       points_i = active_i (c_i + δ n_i),   normals_i = n_i if active_i else +z,
       velocities_i = 0                                                       [m, -, m/s].

   The written point lies ``δ`` from ``c_i`` toward the sphere, so the leaf's clearance
   ``‖x_i − c_i‖ − δ − r_i`` never exceeds the distance to a measured point;
4. with a ``far_side`` leaf, its second ``K`` slots: two more KD-tree queries beyond each
   centre (three with a braking leaf: also where each sphere would stop, its velocity
   ``J_{x_i}(q) q̇`` a second output of step 1) and a third compiled function
   (:mod:`dynfab.perception.far_side_writer`).

The values are those of :class:`~dynfab.perception.surfaces.SurfaceFeed` (the scenario's
feed) given the same cloud, ``q`` and ``q̇``. An empty cloud skips the queries and writes
every slot inactive. The functions are compiled to C on the ``"c"`` backend
(:mod:`dynfab.fabric.c_backend`: cached as the planners' libraries are, by their code; the
CasADi VM without a compiler). Cost (Panda, 58 spheres): the writer 1.2 µs compiled, about
9 µs in the VM; a query about 10 µs (a 53 k-point table scene); what the reach and the far
side add is measured by ``bench/bench_point_clouds.py``.
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
from dynfab.perception.far_side_writer import beyond, far_side_function, query_count
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
        reach: Per sphere of the leaf, how far from its centre points are looked for at rest
            (``q̇ = 0``) [m].
        index: Per sphere, the row of its nearest kept point in the last cloud written (K,);
            valid where the leaf's first ``active`` slots are 1 (elsewhere it may be the
            cloud's length).
    """

    def __init__(self, robot: Robot, leaf: NearestSurfaceAvoidance, views: LeafViews,
                 backend: str | None = None) -> None:
        spheres = list(leaf.spheres)
        count = len(spheres)
        radii = np.asarray(robot.sphere_radii, dtype=float)[spheres]
        self.reach = leaf.barrier.horizon + leaf.barrier.offset + radii
        self.index: NDArray[np.integer] = np.zeros(count, dtype=np.int64)
        self._count = count
        self._far_side = leaf.far_side
        self._braking = leaf.barrier.braking
        self._grows = self._braking is not None   # the reach depends on q̇
        self._static_reach = float(self.reach.max()) if count else 0.0
        self._q = np.zeros(robot.kinematics.dof)
        self._qdot = np.zeros(robot.kinematics.dof)
        # writer input z = [x (3K, row-major), reach (K), c (3K), f (K), δ]; x and reach evaluated into it
        self._input = np.zeros(8 * count + 1)
        self._centres = self._input[:3 * count].reshape(count, 3)
        self._reach = self._input[3 * count:4 * count]
        self._nearest = self._input[4 * count:7 * count].reshape(count, 3)
        self._found = self._input[7 * count:8 * count]
        self._velocities = np.zeros((count, 3))   # the sphere centres' velocities [m/s] (braking leaves)
        # far-side candidates: per query [c_s (3K), f_s (K)]
        self._far = np.zeros(4 * count * query_count(self._braking))
        if count == 0:
            self._evaluate_centres = self._evaluate_writer = self._evaluate_far = _nothing
            return
        self._views = {key: _writable(views, key, leaf.name) for key in _OUTPUTS}
        backend = default_backend() if backend is None else backend
        centres = _evaluable(_centres_function(robot, spheres, self.reach, leaf.barrier.braking), backend)
        self._centres_buffer, self._evaluate_centres = centres.buffer()
        self._centres_buffer.set_arg(0, memoryview(self._q))
        self._centres_buffer.set_arg(1, memoryview(self._qdot))
        self._centres_buffer.set_res(0, memoryview(self._input[:4 * count]))
        self._centres_buffer.set_res(1, memoryview(self._velocities.reshape(-1)))
        writer = _evaluable(_writer_function(count), backend)
        self._writer_buffer, self._evaluate_writer = writer.buffer()
        self._writer_buffer.set_arg(0, memoryview(self._input))
        for slot, key in enumerate(_OUTPUTS):
            self._writer_buffer.set_res(slot, memoryview(self._first(key)))
        self._evaluate_far = _nothing
        if self._far_side:
            far = _evaluable(far_side_function(radii, _COMPILED_NAME, self._braking), backend)
            self._far_buffer, self._evaluate_far = far.buffer()
            self._far_buffer.set_arg(0, memoryview(self._input))
            self._far_buffer.set_arg(1, memoryview(self._first("normals")))
            self._far_buffer.set_arg(2, memoryview(self._first("active")))
            self._far_buffer.set_arg(3, memoryview(self._far))
            self._far_buffer.set_arg(4, memoryview(self._velocities.reshape(-1)))
            for slot, key in enumerate(_OUTPUTS):
                self._far_buffer.set_res(slot, memoryview(self._second(key)))

    @property
    def centres(self) -> NDArray[np.float64]:
        """The leaf's sphere centres at the last ``q`` written (K, 3) [m] (a view; copy to keep)."""
        return self._centres

    def write(self, q: NDArray[np.float64], cloud: PointCloud, qdot: NDArray[np.float64] | None = None) -> None:
        """Write the leaf's nearest points of ``cloud`` for the configuration ``q`` (and, with
        a braking leaf, its reach grown by the spheres' stopping distances at ``qdot``
        [rad/s]; None: at rest).

        Raises:
            ValueError: ``q`` or ``qdot`` has the wrong length.
        """
        if np.shape(q) != self._q.shape:
            raise ValueError(f"q must have shape {self._q.shape}, got {np.shape(q)}")
        if qdot is not None and np.shape(qdot) != self._qdot.shape:
            raise ValueError(f"qdot must have shape {self._qdot.shape}, got {np.shape(qdot)}")
        if self._count == 0:
            return
        self._q[:] = q
        if self._grows:
            self._qdot[:] = 0.0 if qdot is None else qdot
        self._evaluate_centres()
        if cloud.empty:
            self._found[:] = 0.0
        else:
            bound = (float(self._reach.max()) if self._grows else self._static_reach) + cloud.lowering
            gaps, self.index = cloud.tree.query(self._centres, distance_upper_bound=bound)
            np.take(cloud.points, self.index, axis=0, out=self._nearest, mode="clip")
            np.isfinite(gaps, out=self._found, casting="unsafe")
        self._input[-1] = cloud.lowering
        self._evaluate_writer()
        if self._far_side:
            self._write_far_side(cloud)

    def _write_far_side(self, cloud: PointCloud) -> None:
        """The far-side slots (step 4 of the module docstring): a query per shift (and the
        stopping points), then the compiled choice."""
        count = self._count
        for s, (queries, bound) in enumerate(beyond(self._centres, self._first("points").reshape(count, 3),
                                                    self._first("active"), self._reach, cloud.lowering,
                                                    self._velocities, self._braking)):
            block = self._far[4 * count * s:4 * count * (s + 1)]
            if cloud.empty:
                block[3 * count:] = 0.0
                continue
            gaps, index = cloud.tree.query(queries, distance_upper_bound=bound)
            np.take(cloud.points, index, axis=0, out=block[:3 * count].reshape(count, 3), mode="clip")
            np.isfinite(gaps, out=block[3 * count:], casting="unsafe")
        self._evaluate_far()

    def _first(self, key: str) -> NDArray[np.float64]:
        """The leaf's parameter ``key`` of the first ``K`` slots (a view)."""
        view = self._views[key]
        return view[:len(view) // 2] if self._far_side else view

    def _second(self, key: str) -> NDArray[np.float64]:
        """The leaf's parameter ``key`` of the far-side slots (a view)."""
        view = self._views[key]
        return view[len(view) // 2:]


def _writable(views: LeafViews, key: str, leaf: str) -> NDArray[np.float64]:
    """The leaf's view ``key``, checked writable and contiguous (the writers write into it)."""
    view = views[key]
    if not (view.flags.c_contiguous and view.flags.writeable):
        raise ValueError(f"leaves[{leaf!r}][{key!r}]: expected a writable contiguous view")
    return view


def _centres_function(robot: Robot, spheres: list[int], reach: NDArray[np.float64],
                      braking: float | None) -> ca.Function:
    """Step 1 of the module docstring: ``(q, q̇) ↦ ([x (3K, row-major), reach (K)], ẋ (3K,
    row-major))``."""
    q = ca.SX.sym("q", robot.kinematics.dof)
    qdot = ca.SX.sym("qdot", robot.kinematics.dof)
    centres = robot.sphere_centers(q)[spheres, :]
    velocities = ca.reshape(ca.jtimes(ca.vec(centres), q, qdot), centres.shape)
    grown = ca.DM(reach)
    if braking is not None:
        grown = grown + ca.sum2(velocities**2) / (2.0 * braking)
    return ca.Function(_COMPILED_NAME, [q, qdot], [ca.vertcat(ca.vec(centres.T), grown), ca.vec(velocities.T)])


def _writer_function(count: int) -> ca.Function:
    """Step 3 of the module docstring: ``z = [x, reach, c, f, δ] ↦ (points, normals,
    velocities, active)`` for ``count`` spheres."""
    z = ca.SX.sym("z", 8 * count + 1)
    delta = z[8 * count]
    up = ca.DM([0.0, 0.0, 1.0])
    points, normals, actives = [], [], []
    for i in range(count):
        x, reach = z[3 * i:3 * i + 3], z[3 * count + i]
        c, found = z[4 * count + 3 * i:4 * count + 3 * i + 3], z[7 * count + i]
        offset = x - c
        length = ca.norm_2(offset)
        normal = ca.if_else(length > _TINY, offset / ca.fmax(length, _TINY), up)
        active = found * (length - delta <= reach)
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
