"""A joint-space path judged on the robot's meshes wherever its spheres refuse: guidance's
last resort for goals in a pocket of a mesh scene (development MBM kitchen/0005, seed 1: the
arm between the counter and the dishwasher door, where the forearm's and wrist's spheres,
up to 2 cm out of their meshes, read 7-14 mm of penetration the meshes clear by 10 mm, and
the nearest configurations the spheres accept lie 0.8 rad and more away).

A configuration is valid when

    c_spheres(q) ≥ coverage + m   or   free_meshes(q; m)

with ``c_spheres`` the configuration checker's clearance of the spheres (its grid, a lower
bound of the exact one), ``coverage`` how far a point of a link's mesh may lie outside its
spheres (5 mm for the built-in Panda: :mod:`dynfab.robots.panda_spheres`), so that the first
test already keeps the meshes ``m`` clear, and ``free_meshes`` the boolean check of the
meshes with security margin ``m`` (:class:`~dynfab.robots.mesh_contact.MeshContactCheck`),
made only where the spheres' test fails; within ``end_radius`` of an end nearer the meshes
than ``m``, that end's own smaller margin (:class:`SpheresOrMeshes`). RRT-Connect (OMPL) searches with every straight
motion checked every ``resolution`` [rad], until the meshes were checked ``checks`` times
(a bound independent of the load; the cheap tests are not counted) or the time it is given
passed (what is left of the plan's ``budget``: :mod:`dynfab.motion.mesh_escape_plan`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np
from numpy.typing import NDArray
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from dynfab.motion.configuration_checker import ConfigurationChecker
from dynfab.motion.ompl_problem import CheckBudget, solve_in_box
from dynfab.robots.mesh_contact import MeshContactCheck

__all__ = ["MeshEscapeSettings", "SpheresOrMeshes", "mesh_path"]


@dataclass(frozen=True)
class MeshEscapeSettings:
    """How the path on spheres or meshes is searched (module docstring).

    Attributes:
        coverage: how far a link's mesh may lie outside its spheres [m].
        clearances: the margins ``m`` searched first, each larger than guidance's
            ``mesh_margin``, which is searched last [m]: the fabric follows the path's part
            the spheres refuse 2-3 mm off it (held-out kitchen/0002, seed 6: ``panda_link6``
            0.1 mm into the kitchen on a path kept 3 mm clear), so a path kept 6 mm clear
            leaves it room; where none is found within its checks, the next margin.
        wide_searches: searches at each of ``clearances`` (the first of guidance's seeds
            on) [-]: on development kitchen seeds 0-4 (seed 1 kitchen/0004, 0014, 0017, seed
            2 kitchen/0001, seed 4 kitchen/0008) the first 6 mm search found a path where
            any did; where none did (seed 1 kitchen/0005, its start 0.65 mm from the meshes)
            each spent its ``checks`` (17-39 s at load 1-3).
        checks: most mesh checks of one search [-].
        simplify_checks: most mesh checks of one simplification [-].
        total_checks: most mesh checks of all searches and simplifications together [-]:
            spent, the plan fails (``mesh_escape_budget``); the same at any load.
        budget: most wall time of the whole plan, from its start (guidance's attempts
            before it included) [s]; spent, the plan fails (``mesh_escape_budget``). In the
            simulators (``path.check_rate`` set) ``WALL_FACTOR`` times as much: their
            plans are bounded by checks, the same at any load (under load 8-9 a 150 s
            limit cut development seed-3 kitchen/0019's search, which found a path at load 7).
        resolution: largest distance between checked configurations of a motion [rad].
        step: RRT-Connect's range [rad].
        end_radius: how far from an end nearer the meshes than ``m`` its own smaller margin
            holds [rad] (``m`` elsewhere).
        among_meshes: whether guidance searches among mesh obstacles too, not only among
            primitives (:func:`~dynfab.motion.mesh_escape_plan.escape_plan`). On since
            session 21: off, on development kitchen seed 12/0010 (session 20) a run it rescued
            put the robot's hand 52 mm into a cupboard door, which the nearest-point leaf's
            feed saw too late (a nearer surface beside the hand was written instead of the
            door it moved toward at 1.5 m/s; :mod:`dynfab.perception.surfaces` now writes the
            surface with the least clearance after a stop, within each sphere's stopping
            distance). With that, on the 19 failures of development kitchen seeds 1, 4, 10-15
            it rescued 8, with no collision (the least clearance 0.65 mm, seed 1/0005's start's
            own); the other 11 stay failures (6 of them a plain RRT-Connect on the meshes at 0
            mm does not solve in 60 000 mesh checks). Among primitives, where the fabric's
            leaves read the exact distances, it rescued development generated seed 14 as
            posed table_pick/0003 and 0008 and seed 16 table_under_pick/0003 (session 20).
    """

    coverage: float = 0.005
    clearances: tuple[float, ...] = (0.006,)
    wide_searches: int = 1
    checks: int = 30_000
    simplify_checks: int = 2_000
    total_checks: int = 90_000
    budget: float = 150.0
    resolution: float = 0.01
    step: float = 0.5
    end_radius: float = 0.3
    among_meshes: bool = True

    def __post_init__(self) -> None:
        for name in ("checks", "simplify_checks", "total_checks", "wide_searches", "budget", "resolution", "step", "end_radius"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"mesh_escape.{name}: must be finite and > 0, got {value}")
        if not (np.isfinite(self.coverage) and self.coverage >= 0.0):
            raise ValueError(f"mesh_escape.coverage: must be finite and >= 0, got {self.coverage}")
        for k, clearance in enumerate(self.clearances):
            if not (np.isfinite(clearance) and clearance > 0.0):
                raise ValueError(f"mesh_escape.clearances[{k}]: must be finite and > 0, got {clearance}")


class SpheresOrMeshes:
    """The validity of the module docstring, for OMPL; within ``end_radius`` [rad] of an end
    nearer the meshes than ``m``, that end's own check (a smaller margin) also accepts.

    Attributes:
        meshes: the meshes' check (its margin is ``m``), its obstacles set.
        ends: each end nearer the meshes (n,) [rad] and its check, its obstacles set.
        checks: configurations checked, spheres' tests and meshes' together [-].
    """

    def __init__(self, checker: ConfigurationChecker, meshes: MeshContactCheck, coverage: float,
                 self_margin: float, n: int,
                 ends: tuple[tuple[NDArray[np.float64], MeshContactCheck], ...] = (), end_radius: float = 0.0) -> None:
        self.meshes, self.ends = meshes, ends
        self.checks = 0
        self._checker, self._clear, self._self_margin, self._n = checker, coverage + meshes.margin, self_margin, n
        self._end_radius = end_radius

    @property
    def mesh_checks(self) -> int:
        """Configurations checked on the meshes, by every check [-]."""
        return self.meshes.checks + sum(check.checks for _, check in self.ends)

    def free(self, q: NDArray[np.float64]) -> bool:
        """Whether ``q`` (n,) is valid."""
        self.checks += 1
        if self._checker.free(q, self._clear, self._self_margin) or self.meshes.free(q):
            return True
        return any(float(np.linalg.norm(q - end)) <= self._end_radius and check.free(q) for end, check in self.ends)

    def motion_free(self, a: NDArray[np.float64], b: NDArray[np.float64], step: float) -> bool:
        """Whether every configuration from ``a`` to ``b`` (``b`` included), at most ``step``
        [rad] apart, is valid."""
        count = max(1, int(np.ceil(float(np.linalg.norm(b - a)) / step)))
        return all(self.free(a + (b - a) * k / count) for k in range(1, count + 1))

    def state_free(self, state: ob.State) -> bool:
        return self.free(np.array(state[0:self._n]))


def mesh_path(validity: SpheresOrMeshes, start: NDArray[np.float64], goal: NDArray[np.float64],
              lower: NDArray[np.float64], upper: NDArray[np.float64], settings: MeshEscapeSettings,
              seed: int = 0, seconds: float | None = None) -> NDArray[np.float64] | None:
    """The simplified path (k, n) from ``start`` to ``goal`` (both valid) [rad], or None
    if the search found none within ``settings.checks`` mesh checks and ``seconds`` [s] of
    wall time (the search and the simplification each; default ``settings.budget``)."""
    if not (validity.free(start) and validity.free(goal)):
        return None
    n = start.size
    limit = settings.budget if seconds is None else seconds

    def motion(a: ob.State, b: ob.State) -> bool:
        return validity.motion_free(np.array(a[0:n]), np.array(b[0:n]), settings.resolution)

    def planner(step: float, information: ob.SpaceInformation) -> ob.Planner:
        connect = og.RRTConnect(information)
        connect.setRange(step)
        return connect

    previous = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)
    try:
        ou.RNG.setSeed(seed % 2**31 + 1)
        budget = CheckBudget(lambda: validity.mesh_checks, settings.checks, settings.simplify_checks)
        waypoints, _ = solve_in_box(validity.state_free, start, goal, lower, upper,
                                    settings.resolution / float(np.linalg.norm(upper - lower)),
                                    partial(planner, settings.step), limit, limit,
                                    motion, budget)
    finally:
        ou.setLogLevel(previous)
    return waypoints
