"""The part of a point cloud near a goal, for the global planner: the same bound on a finer grid.

The checker's grid of a whole cloud (:mod:`dynfab.geometry.cloud_grid`, pitch ``h`` = 1 cm)
reads up to ``h√3`` = 1.7 cm below ``d(x, C) − δ`` between its nodes (``C`` the kept
points, ``δ`` the voxel half-diagonal). Near a grasp goal, millimetres from the scene, that
is the difference between a goal that can be escaped and one that cannot
(MotionBenchMaker's cage as a cloud, issue 20). A cloud's kept points split into those inside
a box (the *focus*) and the rest:

    d(x, C) = min(d(x, C_in), d(x, C_out))                 [m],

so the minimum of a lower bound of each is one of the whole (the checker takes the minimum
over obstacles). :class:`FocusedCloud` holds ``C_in``: the same points and the same ``δ``,
its grid built at the finer ``pitch`` (short of ``d(x, C_in) − δ`` by at most
``pitch·√3``); the bound itself, and so what the robot's meshes and the fabric read, is
unchanged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from dynfab.geometry.point_cloud import PointCloud

__all__ = ["FocusedCloud", "split_cloud"]


@dataclass(frozen=True, eq=False)
class FocusedCloud(PointCloud):
    """The kept points of a cloud inside its focus (module docstring).

    Attributes:
        pitch: node spacing of the planner's grid of these points [m].
    """

    pitch: float = 0.004

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (math.isfinite(self.pitch) and self.pitch > 0.0):
            raise ValueError(f"focused cloud {self.source}: pitch must be a positive number, got {self.pitch}")


def split_cloud(cloud: PointCloud, low: ArrayLike, high: ArrayLike,
                pitch: float) -> tuple[FocusedCloud | None, PointCloud | None]:
    """``cloud``'s kept points inside the box ``[low, high]`` (cloud frame) [m] as a
    :class:`FocusedCloud` gridded at ``pitch`` [m], and the rest as a plain cloud of the
    same voxel; None for a part with no points.

    Raises:
        ValueError: ``low`` or ``high`` is not 3 finite numbers with ``low ≤ high``.
    """
    lower, upper = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    if lower.shape != (3,) or upper.shape != (3,) or not (np.isfinite(lower).all() and np.isfinite(upper).all()):
        raise ValueError(f"focus box of {cloud.source}: low and high must be 3 finite numbers, got {low} and {high}")
    if (lower > upper).any():
        raise ValueError(f"focus box of {cloud.source}: low {lower} exceeds high {upper}")
    inside = np.all((cloud.points >= lower) & (cloud.points <= upper), axis=1)
    focused = (FocusedCloud(cloud.points[inside], cloud.voxel, 0, f"{cloud.source} (focus)", pitch)
               if inside.any() else None)
    rest = PointCloud(cloud.points[~inside], cloud.voxel, cloud.dropped, cloud.source) if not inside.all() else None
    return focused, rest
