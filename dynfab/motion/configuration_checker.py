"""Is a robot configuration free? Its collision spheres against obstacle shapes and against
each other: the global planner's validity check.

For a configuration ``q`` the checker gives

    c_obs(q)  = min_{i, k} d_k(R_kᵀ (p_i(q) − c_k)) − r_i               [m]
    c_self(q) = min_{(a, b) ∈ pairs} ‖p_a(q) − p_b(q)‖ − r_a − r_b       [m]

over the robot's collision spheres ``(p_i, r_i)`` that some joint moves (for ``c_obs``: a
sphere on the base has the same clearance at every configuration, so it cannot make one
configuration freer than another, and the fabric's leaves do not act on it either; counted,
a base sphere within ``margin`` of an obstacle blocked every configuration, held-out MBM
kitchen/0012, its base 4.8 mm from a dishwasher door, −11.6 mm on the grid), the obstacles ``k`` (centre ``c_k``,
rotation ``R_k``, the exact signed distance ``d_k`` of a sphere, box, cylinder, capsule or
plane in its own frame, :mod:`dynfab.geometry.distance`; for a mesh, compiled, a lower bound
of it from a grid, :mod:`dynfab.geometry.distance_grid`, at most ``h√3`` = 1.7 cm below it
within 4 cm of the surface; for a point cloud, compiled, the grid of
:mod:`dynfab.geometry.cloud_grid`, interpreted, the KD-tree distance less the voxel
half-diagonal; the part of a cloud near a goal, :mod:`dynfab.geometry.focused_cloud`, on a
finer grid) and the robot's self-collision
pairs: the same spheres, shapes and pairs the fabric's leaves avoid, so a path the
checker accepts is one the fabric can follow. ``inf`` where there is nothing to check.

It runs compiled (``checker_kernel.c``, built per robot and cached: a broad phase by
bounding spheres and an early exit when only validity is asked), or, without a C
compiler, as numpy distances over the CasADi forward kinematics evaluated per
configuration (the same numbers, slower).

**A second look on fine spheres.** A robot with
:attr:`~dynfab.robots.robot.Robot.fine_spheres` (the built-in Panda's: every link within
5 mm of its meshes, 396 spheres against guidance's 101) is checked against the primitive
shapes ``P`` (spheres, boxes, cylinders, capsules, planes) with the larger of the two sets'
clearances, against meshes and point clouds ``S`` with its own spheres alone:

    c_obs(q) = min( max(c_P(q; spheres), c_P(q; fine spheres)),  c_S(q; spheres) )   [m]

(each set leaves at most 5 mm of the meshes outside, so the larger is as safe as either),
``c_self`` on the planning spheres' pairs alone. Not among meshes: there the fabric's leaves
get no allowance along the plan's way (:mod:`dynfab.motion.allowance_tables`), and plans
that the fine spheres let closer to a kitchen's walls left its larger spheres lagging until
they stalled (MBM kitchen seed 11/0016). The fine set is evaluated only where the
other finds a configuration blocked (:meth:`ConfigurationChecker.free`,
:meth:`~ConfigurationChecker.first_blocked`, :meth:`~ConfigurationChecker.motion_free`: a
motion blocked on the planning spheres is checked again at every configuration); the
values (:meth:`~ConfigurationChecker.clearances`, :meth:`~ConfigurationChecker.batch`)
evaluate both. Why: the planning spheres reach up to 1 cm out of the wrist and the hand and
2 cm elsewhere, and refused goals and ways free on the meshes (``goal_in_collision``,
``no_path``; docs/results.md, session 19).

A straight motion ``q(s) = a + s (b − a)``, ``s ∈ [0, 1]``, is free when the
configurations at most ``step`` apart along it are (:meth:`ConfigurationChecker.motion_free`:
``b`` first, then coarse to fine, in one compiled call).
"""

from __future__ import annotations

import ctypes
import math
from collections.abc import Sequence
from dataclasses import replace

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from dynfab.fabric.leaves.surface_points import moving_spheres
from dynfab.geometry.distance import placed_distance
from dynfab.motion.checker_library import as_pointer, load_checker_library
from dynfab.motion.obstacle_buffer import ROW, gridded, obstacle_buffer, obstacle_row, same_grids
from dynfab.motion.placed_obstacle import PlacedObstacle
from dynfab.robots.robot import Robot

__all__ = ["ConfigurationChecker", "PlacedObstacle"]

_ONE = ctypes.c_int(1)


class ConfigurationChecker:
    """``q ↦ (c_obs, c_self)`` of the module docstring, with obstacles set at run time.

    Attributes:
        robot: the robot.
        compiled: whether the compiled kernel is in use.
    """

    def __init__(self, robot: Robot, obstacles: Sequence[PlacedObstacle] = ()) -> None:
        self.robot = robot
        self._library = load_checker_library(robot)
        self.compiled = self._library is not None
        self._n = robot.dof
        self._q = np.zeros(self._n)
        self._q_pointer = as_pointer(self._q)
        self._q_address = ctypes.c_void_p(self._q.ctypes.data)
        self._b = np.zeros(self._n)
        self._b_pointer = as_pointer(self._b)
        self._margins = (math.nan, math.nan)
        self._margin_values = (ctypes.c_double(math.nan), ctypes.c_double(math.nan))
        self._out = np.zeros(2)
        self._out_pointer = as_pointer(self._out)
        self._centres: ca.Function | None = None  # the numpy path's forward kinematics, made on first use
        self._moving = moving_spheres(robot)       # the spheres c_obs is over
        self._obstacles: tuple[PlacedObstacle, ...] = ()
        self._rows = np.zeros(0)
        # the second look (module docstring): a robot's that plans on its own spheres (not the
        # fabric's spheres of a robot with planning spheres: guidance checks those among clouds)
        fine = robot.fine_robot if robot.planning_robot is robot else None
        self._fine = None if fine is None else ConfigurationChecker(fine)   # on the primitives
        self._surfaces: ConfigurationChecker | None = None   # these spheres on the meshes and clouds alone
        self._second_look = False   # fine spheres and primitives among the obstacles
        self._mixed = False         # primitives and surfaces among the obstacles
        self.set_obstacles(obstacles)

    @property
    def obstacles(self) -> tuple[PlacedObstacle, ...]:
        """The obstacles checked against."""
        return self._obstacles

    def set_obstacles(self, obstacles: Sequence[PlacedObstacle]) -> None:
        """Check against ``obstacles`` from now on (a mesh's distance grid is built on its
        first use, and kept on disk: 0.1-9 s per mesh of MBM kitchen and table_bars,
        :mod:`dynfab.geometry.distance_grid`; a point cloud's in 0.05-1 s,
        :mod:`dynfab.geometry.cloud_grid`). Where the same meshes and clouds (the same
        objects) stand at the same places in the list as before, only the rows are written
        into the buffer in place: the grids (13-32 MB a mesh of MBM kitchen) are not copied
        again (a guided run sets its checkers' obstacles at every plan)."""
        obstacles = tuple(obstacles)
        if self._fine is not None:
            self._set_second_look(obstacles)
        if self._rows.size and same_grids(self._obstacles, obstacles):
            head = self._rows[:len(obstacles) * ROW].reshape(-1, ROW)
            rows = np.array([obstacle_row(o) for o in obstacles]).reshape(-1, ROW)
            on_grids = [gridded(o) for o in obstacles]
            rows[on_grids, 13] = head[on_grids, 13]   # the grids' offsets, as they were
            head[:] = rows
            self._obstacles = obstacles
            return
        self._obstacles = obstacles
        self._rows = obstacle_buffer(self._obstacles)
        self._rows_pointer = as_pointer(self._rows)
        self._rows_address = ctypes.c_void_p(self._rows.ctypes.data)
        self._count = ctypes.c_int(len(self._obstacles))

    def clearances(self, q: NDArray[np.float64]) -> tuple[float, float]:
        """``(c_obs, c_self)`` at one configuration [m] (with fine spheres, ``c_obs`` of the
        second look, module docstring)."""
        obstacle, itself = self._own_clearances(q)
        if self._second_look:
            q = np.ascontiguousarray(q, dtype=float).reshape(1, self._n)
            obstacle = float(self._looked_again(np.array([obstacle]), q)[0])
        return obstacle, itself

    def batch(self, qs: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(c_obs, c_self)`` at every row of ``qs`` (N, n), shape (N, 2)."""
        qs = np.ascontiguousarray(qs, dtype=float).reshape(-1, self._n)
        out = self._own_batch(qs)
        if self._second_look:
            out[:, 0] = self._looked_again(out[:, 0], qs)
        return out

    def free(self, q: NDArray[np.float64], margin: float, self_margin: float) -> bool:
        """Whether ``c_obs(q) ≥ margin`` and ``c_self(q) ≥ self_margin`` (stops at the first
        clearance below its margin; the fine spheres only where the others find ``q``
        blocked)."""
        if self._own_free(q, margin, self_margin):
            return True
        if not self._second_look:
            return False
        assert self._fine is not None
        if not self._fine._own_free(q, margin, -math.inf):   # most often blocked there too: asked first
            return False
        if self._mixed and self._surfaces is not None and not self._surfaces._own_free(q, margin, -math.inf):
            return False
        return self._own_clearances(q)[1] >= self_margin

    def first_blocked(self, qs: NDArray[np.float64], margin: float, self_margin: float) -> int:
        """Index of the first row of ``qs`` (N, n) with ``c_obs < margin`` or
        ``c_self < self_margin``, or -1 if every row is free (stops at the first)."""
        qs = np.ascontiguousarray(qs, dtype=float).reshape(-1, self._n)
        first = self._own_first_blocked(qs, margin, self_margin)
        if first < 0 or not self._second_look:
            return first
        return next((k for k in range(first, len(qs)) if not self.free(qs[k], margin, self_margin)), -1)

    def motion_free(self, a: NDArray[np.float64], b: NDArray[np.float64], step: float, margin: float,
                    self_margin: float) -> tuple[bool, int]:
        """Whether the straight motion from ``a`` to ``b`` (n,) is free at configurations at
        most ``step`` [rad] apart, ``b`` included and ``a`` not (module docstring), and how
        many configurations were checked to know it (with fine spheres, where the others
        find the motion blocked, its configurations from there on are checked again in the
        same order, each by :meth:`free`)."""
        free, checked = self._own_motion_free(a, b, step, margin, self_margin)
        if free or not self._second_look:
            return free, checked
        count = max(1, math.ceil(float(np.linalg.norm(b - a)) / step))
        rest = _motion_order(count)[checked - 1:]   # from the one found blocked
        for k, index in enumerate(rest, start=1):
            if not self.free(a + (index / count) * (b - a), margin, self_margin):
                return False, checked + k
        return True, checked + len(rest)

    def _set_second_look(self, obstacles: tuple[PlacedObstacle, ...]) -> None:
        """The fine spheres' obstacles: the primitives; and, beside primitives, these spheres'
        own checker of the meshes and clouds alone (module docstring)."""
        assert self._fine is not None
        primitives = tuple(o for o in obstacles if not gridded(o))
        surfaces = tuple(o for o in obstacles if gridded(o))
        self._fine.set_obstacles(primitives)
        self._second_look = bool(primitives)
        self._mixed = bool(primitives and surfaces)
        if self._mixed:
            if self._surfaces is None:
                self._surfaces = ConfigurationChecker(replace(self.robot, fine_spheres=None))
            self._surfaces.set_obstacles(surfaces)

    def _looked_again(self, own: NDArray[np.float64], qs: NDArray[np.float64]) -> NDArray[np.float64]:
        """``c_obs`` of the second look at ``qs`` (N, n) given this checker's own ``own`` (N,):
        ``min(max(own, fine on the primitives), own on the meshes and clouds)`` [m]."""
        assert self._fine is not None
        looked = np.maximum(own, self._fine._own_batch(qs)[:, 0])
        if self._mixed and self._surfaces is not None:
            np.minimum(looked, self._surfaces._own_batch(qs)[:, 0], out=looked)
        return looked

    def _own_clearances(self, q: NDArray[np.float64]) -> tuple[float, float]:
        """:meth:`clearances` of this checker's spheres alone."""
        if self._library is None:
            obstacle, itself = self._numpy(np.asarray(q, dtype=float)[None])[0]
            return float(obstacle), float(itself)
        self._q[:] = q
        self._library.clearances(self._q_pointer, 1, self._rows_pointer, len(self._obstacles), self._out_pointer)
        return float(self._out[0]), float(self._out[1])

    def exact_free(self, q: NDArray[np.float64], margin: float, self_margin: float) -> bool:
        """:meth:`free` on the exact distances (numpy: a mesh's triangles, not its grid;
        milliseconds a configuration, for a few candidates such as goals)."""
        qs = np.asarray(q, dtype=float).reshape(1, self._n)
        obstacle, itself = self._numpy(qs)[0]
        if self._second_look and obstacle < margin:
            assert self._fine is not None
            obstacle = max(obstacle, self._fine._numpy(qs)[0, 0])
            if self._mixed and self._surfaces is not None:
                obstacle = min(obstacle, self._surfaces._numpy(qs)[0, 0])
        return bool(obstacle >= margin and itself >= self_margin)

    def _own_batch(self, qs: NDArray[np.float64]) -> NDArray[np.float64]:
        """:meth:`batch` of this checker's spheres alone."""
        qs = np.ascontiguousarray(qs, dtype=float).reshape(-1, self._n)
        if self._library is None:
            return self._numpy(qs)
        out = np.empty((qs.shape[0], 2))
        self._library.clearances(as_pointer(qs), qs.shape[0], self._rows_pointer, len(self._obstacles),
                                 as_pointer(out))
        return out

    def _own_free(self, q: NDArray[np.float64], margin: float, self_margin: float) -> bool:
        """:meth:`free` of this checker's spheres alone."""
        if self._library is None:
            obstacle, itself = self._own_clearances(q)
            return obstacle >= margin and itself >= self_margin
        if (margin, self_margin) != self._margins:  # the planner asks with the same margins every time
            self._margins = (margin, self_margin)
            self._margin_values = (ctypes.c_double(margin), ctypes.c_double(self_margin))
        self._q[:] = q
        return self._library.first_blocked_unconverted(self._q_address, _ONE, self._rows_address, self._count,
                                                       *self._margin_values) < 0

    def _own_first_blocked(self, qs: NDArray[np.float64], margin: float, self_margin: float) -> int:
        """:meth:`first_blocked` of this checker's spheres alone (``qs`` contiguous (N, n))."""
        if self._library is None:
            values = self._numpy(qs)
            blocked = np.flatnonzero((values[:, 0] < margin) | (values[:, 1] < self_margin))
            return int(blocked[0]) if blocked.size else -1
        return int(self._library.first_blocked(as_pointer(qs), qs.shape[0], self._rows_pointer,
                                               len(self._obstacles), margin, self_margin))

    def _own_motion_free(self, a: NDArray[np.float64], b: NDArray[np.float64], step: float, margin: float,
                         self_margin: float) -> tuple[bool, int]:
        """:meth:`motion_free` of this checker's spheres alone."""
        if self._library is None:
            qs = _motion_configurations(a, b, step)
            blocked = self._own_first_blocked(qs, margin, self_margin)
            return blocked < 0, len(qs) if blocked < 0 else blocked + 1
        self._q[:] = a
        self._b[:] = b
        checked = self._library.motion_free(self._q_pointer, self._b_pointer, step, self._rows_pointer,
                                            len(self._obstacles), margin, self_margin)
        return checked > 0, abs(checked)

    def _numpy(self, qs: NDArray[np.float64]) -> NDArray[np.float64]:
        """The clearances from the CasADi forward kinematics and numpy distances."""
        if self._centres is None:
            q = ca.SX.sym("q", self._n)
            self._centres = ca.Function("centres", [q], [self.robot.sphere_centers(q)])
        radii = self.robot.sphere_radii
        moving = list(self._moving)
        out = np.full((qs.shape[0], 2), math.inf)
        pairs = np.array(self.robot.self_collision_pairs, dtype=int).reshape(-1, 2)
        for row, q in enumerate(qs):
            centres = np.asarray(self._centres(q))
            for obstacle in self._obstacles:
                distance = placed_distance(obstacle.shape, obstacle.placement, centres[moving]) - radii[moving]
                out[row, 0] = min(out[row, 0], float(distance.min(initial=math.inf)))
            if len(pairs):
                gaps = np.linalg.norm(centres[pairs[:, 0]] - centres[pairs[:, 1]], axis=1)
                out[row, 1] = float((gaps - radii[pairs[:, 0]] - radii[pairs[:, 1]]).min())
        return out


def _motion_configurations(a: NDArray[np.float64], b: NDArray[np.float64], step: float) -> NDArray[np.float64]:
    """The configurations of the straight motion from ``a`` to ``b`` at most ``step`` [rad]
    apart, ``a`` left out, in the order the compiled ``motion_free`` checks them
    (:func:`_motion_order`: ``b`` first, then coarse to fine)."""
    count = max(1, math.ceil(float(np.linalg.norm(b - a)) / step))
    return a + (np.array(_motion_order(count)) / count)[:, None] * (b - a)


def _motion_order(count: int) -> list[int]:
    """The order the compiled ``motion_free`` checks the configurations ``a + (i / count)(b −
    a)`` of a motion in: ``i = count`` (``b``) first, then the odd multiples of each stride,
    strides halving from the largest power of two below ``count`` to 1 (coarse to fine)."""
    order, stride = [count], 1
    while 2 * stride < count:
        stride *= 2
    while stride >= 1:
        order += range(stride, count, 2 * stride)
        stride //= 2
    return order
