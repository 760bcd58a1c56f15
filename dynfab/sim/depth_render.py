"""Depth images of a scene's camera, rendered offscreen by MuJoCo (``mujoco.Renderer`` with
depth rendering).

MuJoCo's depth image holds, per pixel, the distance along the camera's optical axis [m]
(linearised from the z-buffer between the near and far clipping planes,
``znear · extent`` and ``zfar · extent``); a pixel where nothing was hit reads the far
plane's distance. Those become ``inf`` (no return), as
:class:`~dynfab.perception.depth_camera.DepthCamera` expects. Rendering needs an OpenGL
platform: ``MUJOCO_GL=egl`` (or ``osmesa``) headless, set before ``mujoco`` is first imported.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from dynfab.perception.camera_spec import CameraSpec
from dynfab.sim.mjcf_cameras import camera_name

__all__ = ["MujocoDepthRenderer"]

#: A depth at or beyond this fraction of the far plane's distance counts as no hit.
_FAR_FRACTION = 0.999


class MujocoDepthRenderer:
    """Renders the depth image of camera ``k`` of a model built with ``cameras``
    (:func:`dynfab.sim.mujoco_model.build_scene`).

    Attributes:
        far: The far clipping plane's distance [m]; depths from ``_FAR_FRACTION`` of it on are ``inf``.
    """

    def __init__(self, model: mujoco.MjModel, spec: CameraSpec, k: int = 0) -> None:
        self._camera = model.camera(camera_name(k)).id
        self._renderer = mujoco.Renderer(model, spec.height, spec.width)
        self._renderer.enable_depth_rendering()
        self.far = float(model.vis.map.zfar * model.stat.extent)

    def render(self, data: mujoco.MjData) -> NDArray[np.float32]:
        """The depth image (height, width) [m] of the scene in ``data``, ``inf`` without a hit."""
        self._renderer.update_scene(data, camera=self._camera)
        depth = self._renderer.render()
        depth[depth >= _FAR_FRACTION * self.far] = np.inf
        return depth

    def close(self) -> None:
        """Free the OpenGL context."""
        self._renderer.close()
