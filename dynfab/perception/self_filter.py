"""The robot's own body in a depth image: pixels whose points lie within its collision
spheres plus a margin.

A pixel of depth ``d`` and ray ``r`` (:mod:`dynfab.perception.depth_image`) is the point
``p = o + d r``; it is the robot's when, for some collision sphere ``(c_i, R_i)`` (``R_i`` the
radius plus the margin) at the configuration of the frame's time,

    ‖p − c_i‖² = d² ‖r‖² − 2 d rᵀ(c_i − o) + ‖c_i − o‖² <= R_i²          [m²].

Per sphere only the pixels in the image of its bounding box are tested
(:meth:`~dynfab.perception.depth_image.DepthProjector.windows`), in float32, without forming
the points: the cost follows the robot's area in the image, not the image's size.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from dynfab.perception.depth_image import DepthProjector

__all__ = ["robot_pixels"]


def robot_pixels(depth: NDArray[np.floating], returns: NDArray[np.bool_], projector: DepthProjector,
                 centres: NDArray[np.float64], radii: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Pixels of ``depth`` (H, W) [m] with a return (``returns``) whose point lies in a ball
    ``(centres (k, 3), radii (k,))`` [m] (radii including the margin); shape (H, W)."""
    robot = np.zeros(depth.shape, dtype=bool)
    offsets = (centres - projector.origin).astype(np.float32)
    squares = np.einsum("ij,ij->i", offsets, offsets) - np.asarray(radii, dtype=np.float32) ** 2
    for (v0, v1, u0, u1), offset, square in zip(projector.windows(centres, radii), offsets, squares):
        if v0 >= v1 or u0 >= u1:
            continue
        d = depth[v0:v1, u0:u1]
        inside = d * (d * projector.ray_norms[v0:v1, u0:u1] - 2.0 * (projector.rays[v0:v1, u0:u1] @ offset)) \
            <= -square
        robot[v0:v1, u0:u1] |= inside & returns[v0:v1, u0:u1]
    return robot
