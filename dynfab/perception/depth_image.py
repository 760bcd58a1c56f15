"""Depth image to world points: pinhole back-projection from a fixed camera.

Pixel ``(row v, column u)`` has its centre at image coordinates ``(u + ½, v + ½)``; with the
intrinsics of :class:`~dynfab.perception.camera_spec.CameraSpec` (focal length ``f``
[pixels], principal point ``(W/2, H/2)``) its ray in the camera frame (x right, y up,
looking along −z) is

    a = (u + ½ − W/2) / f,   b = −(v + ½ − H/2) / f,   r_cam = (a, b, −1),

and a pixel of depth ``d`` [m] (the distance along the optical axis, as MuJoCo's and most
depth sensors' images hold it) is the world point

    p = o + d R r_cam = o + d r,

``o`` the camera's position and ``R`` its rotation. The rays ``r`` of a fixed camera are
computed once, so a frame costs one multiply-add per kept pixel. A pixel without a return
(depth ``inf``, NaN or ``<= 0``) gives no point.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from dynfab.perception.camera_spec import CameraSpec

__all__ = ["DepthProjector"]


class DepthProjector:
    """Back-projects depth images of one fixed camera (module docstring).

    Attributes:
        spec: The camera.
        origin: Its position ``o`` (3,) [m].
        rotation: Its axes in the world frame (3, 3) (columns x, y, z).
        rays: ``r`` per pixel, (height, width, 3), world frame, float32, read-only.
        ray_norms: ``‖r‖²`` per pixel, (height, width), float32, read-only.
    """

    def __init__(self, spec: CameraSpec) -> None:
        self.spec = spec
        self.origin = np.array(spec.position)
        self.rotation = spec.rotation
        f = spec.focal
        a = (np.arange(spec.width) + 0.5 - 0.5 * spec.width) / f
        b = -(np.arange(spec.height) + 0.5 - 0.5 * spec.height) / f
        camera_rays = np.stack(np.broadcast_arrays(a[None, :], b[:, None], -1.0), axis=-1)
        self.rays = (camera_rays @ self.rotation.T).astype(np.float32)
        self.ray_norms = np.einsum("ijk,ijk->ij", self.rays, self.rays)
        for array in (self.rays, self.ray_norms):
            array.setflags(write=False)

    def check(self, depth: NDArray[np.floating]) -> None:
        """Raise ValueError unless ``depth`` is a (height, width) image of this camera."""
        if depth.shape != (self.spec.height, self.spec.width):
            raise ValueError(f"depth image: expected shape ({self.spec.height}, {self.spec.width}), "
                             f"got {depth.shape}")

    @staticmethod
    def returns(depth: NDArray[np.floating]) -> NDArray[np.bool_]:
        """Pixels with a return: finite depth > 0, shape of ``depth``."""
        return np.isfinite(depth) & (depth > 0.0)

    def points(self, depth: NDArray[np.floating], keep: NDArray[np.bool_]) -> NDArray[np.float64]:
        """World points ``o + d r`` of the pixels where ``keep`` holds, (N, 3) [m], in row-major
        pixel order."""
        with np.errstate(invalid="ignore"):  # inf · 0 where a pixel without return has a ray component 0
            scaled = np.multiply(depth[..., None], self.rays, dtype=np.float32)  # every pixel: cheaper than gathering
        points = np.compress(keep.reshape(-1), scaled.reshape(-1, 3), axis=0).astype(np.float64)
        points += self.origin
        return points

    def ball_depths(self, centre: NDArray[np.float64],
                    radius: float) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """Per pixel, the depths between which its point lies in the ball ``(centre (3,), radius)``
        [m]: ``‖o + d r − c‖ <= R`` is the quadratic ``‖r‖² d² − 2 d rᵀa + ‖a‖² − R² <= 0``
        (``a = c − o``), so ``d ∈ [(rᵀa − √D)/‖r‖², (rᵀa + √D)/‖r‖²]``, ``D = (rᵀa)² −
        ‖r‖²(‖a‖² − R²)``; a ray that misses the ball (``D < 0``) gets the empty range
        ``[inf, −inf]``. Two (height, width) float32 images, read-only."""
        offset = np.asarray(centre, dtype=float) - self.origin
        along = self.rays.astype(float) @ offset
        norms = self.ray_norms.astype(float)
        discriminant = along ** 2 - norms * (offset @ offset - radius ** 2)
        root = np.sqrt(np.maximum(discriminant, 0.0))
        hit = discriminant >= 0.0
        near = np.where(hit, (along - root) / norms, np.inf).astype(np.float32)
        far = np.where(hit, (along + root) / norms, -np.inf).astype(np.float32)
        for array in (near, far):
            array.setflags(write=False)
        return near, far

    def windows(self, centres: NDArray[np.float64], radii: NDArray[np.float64]) -> NDArray[np.int64]:
        """Per ball (``centres`` (k, 3), ``radii`` (k,) [m]), the pixels whose rays may meet it:
        rows ``[v0, v1)`` and columns ``[u0, u1)`` as (k, 4) ``(v0, v1, u0, u1)``. It is the
        image of the ball's bounding box in the camera frame, of depths ``z ± r``:

            u = W/2 + f (x ± r) / (z ± r),   v = H/2 − f (y ± r) / (z ± r),

        extreme at the box's corners; the whole image for a box that reaches behind the
        camera (``z − r <= 0``)."""
        local = (centres - self.origin) @ self.rotation  # (x, y, −depth) in the camera frame
        radii = np.asarray(radii, dtype=float)[:, None]
        depths = np.concatenate([-local[:, 2:3] - radii, -local[:, 2:3] + radii], axis=1)  # (k, 2)
        f, width, height = self.spec.focal, self.spec.width, self.spec.height
        xs = np.concatenate([local[:, 0:1] - radii, local[:, 0:1] + radii], axis=1)
        ys = np.concatenate([local[:, 1:2] - radii, local[:, 1:2] + radii], axis=1)
        ahead = depths[:, 0] > 1e-6
        safe = np.where(ahead[:, None], depths, 1.0)
        us = 0.5 * width + f * (xs[:, :, None] / safe[:, None, :]).reshape(-1, 4)
        vs = 0.5 * height - f * (ys[:, :, None] / safe[:, None, :]).reshape(-1, 4)
        bounds = np.column_stack([np.floor(vs.min(axis=1)), np.ceil(vs.max(axis=1)),
                                  np.floor(us.min(axis=1)), np.ceil(us.max(axis=1))])
        bounds[~ahead] = (0, height, 0, width)
        limits = np.array([height, height, width, width])
        return np.clip(bounds, 0, limits).astype(np.int64)
