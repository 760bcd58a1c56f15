"""Videos of MuJoCo runs: offscreen frames (``mujoco.Renderer``) written by imageio-ffmpeg.

Rendering needs an OpenGL context without a display: set ``MUJOCO_GL=egl`` (Mesa's
libEGL, as on a headless Linux machine) or ``osmesa`` before MuJoCo is imported;
:func:`prepare_headless_rendering` picks ``egl`` when nothing is set. The camera looks at
the robot's centre of mass from the front left, following a mobile base.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

__all__ = ["VideoRecorder", "prepare_headless_rendering"]


def prepare_headless_rendering() -> None:
    """Use EGL for offscreen rendering unless ``MUJOCO_GL`` says otherwise; call before
    MuJoCo creates its first context."""
    os.environ.setdefault("MUJOCO_GL", "egl")


class VideoRecorder:
    """A ``(t, data)`` observer of :func:`dynfab.sim.mujoco_sim.simulate_mujoco` that
    renders a frame every ``1 / fps`` seconds of simulated time and writes an MP4 (H.264)
    on :meth:`close`.

    Attributes:
        path: The video file.
        frames: The rendered frames, each (height, width, 3) uint8 RGB.
    """

    def __init__(self, path: Path, fps: int = 30, width: int = 640, height: int = 480,
                 distance: float = 2.6) -> None:
        """Args:
            path: Output file (``.mp4``).
            fps: Frames per second of simulated time and of the video.
            width: Frame width [px].
            height: Frame height [px].
            distance: Camera distance from the robot's centre of mass [m].
        """
        self.path = Path(path)
        self.fps = fps
        self.width, self.height = width, height
        self.distance = distance
        self.frames: list[np.ndarray] = []
        self._renderer = None
        self._camera = None
        self._next = 0.0

    def __call__(self, t: float, data: object) -> None:
        if t + 1e-9 < self._next:
            return
        self._next += 1.0 / self.fps
        import mujoco

        if self._renderer is None:
            self._renderer = mujoco.Renderer(data.model, self.height, self.width)
            self._camera = mujoco.MjvCamera()
            self._camera.azimuth, self._camera.elevation, self._camera.distance = 150.0, -25.0, self.distance
        self._camera.lookat[:] = data.subtree_com[0] if data.model.nbody > 1 else np.zeros(3)
        self._renderer.update_scene(data, self._camera)
        self.frames.append(self._renderer.render().copy())

    def close(self) -> None:
        """Write the frames to :attr:`path` and free the renderer."""
        import imageio_ffmpeg

        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        writer = imageio_ffmpeg.write_frames(str(self.path), (self.width, self.height), fps=self.fps,
                                             macro_block_size=16, quality=7)
        writer.send(None)
        for frame in self.frames:
            writer.send(np.ascontiguousarray(frame))
        writer.close()
