"""Which pixels of a depth camera's frame show something that arrived since the last frame.

A pixel *arrived* when something is now nearer than what it showed in the previous frame:

    d_t < d_{t−1} − τ,      τ = max(τ_min, 6 √2 σ)                          [m],

with ``d_{t−1} = +inf`` where the previous frame had no return (or one outside the
workspace crop), so anything appearing there arrived. ``σ`` is the camera's depth noise: the
difference of two noisy depths of a static pixel has standard deviation ``√2 σ``, and
``6 √2 σ`` is exceeded by about one pixel in 10⁹. The robot's pixels of this frame never
arrive; those of the previous frame compare with the robot's depth there: a ball passing in
front of the arm arrives, the background the arm uncovers (farther) does not.

Only arrivals count, not departures: where a thing leaves, the pixel shows the static
background behind it. A thing that moves has arrivals at its leading edge (and on its whole
silhouette if it comes nearer); a static scene has none, so a velocity tracker that starts
from the arrived points (:class:`~dynfab.perception.motion_tracks.ClusterTracker`) costs
nothing where nothing moves. The first frame has no predecessor: nothing arrived.

Cost: a few passes over the image (keep the depths for the next frame, compare).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["MIN_CHANGE", "DepthChanges"]

#: Least depth decrease τ_min a pixel must show to have arrived [m].
MIN_CHANGE = 0.02


class DepthChanges:
    """The arrived pixels of successive frames of one camera (module docstring).

    Attributes:
        threshold: ``τ`` [m].
    """

    def __init__(self, noise: float, min_change: float = MIN_CHANGE) -> None:
        if not (math.isfinite(noise) and noise >= 0.0):
            raise ValueError(f"noise must be a finite number >= 0, got {noise}")
        if not (math.isfinite(min_change) and min_change > 0.0):
            raise ValueError(f"min_change must be a finite number > 0, got {min_change}")
        self.threshold = max(min_change, 6.0 * math.sqrt(2.0) * noise)
        self._last: NDArray[np.float32] | None = None

    def arrived(self, depth: NDArray[np.floating], returns: NDArray[np.bool_],
                kept: NDArray[np.bool_]) -> NDArray[np.bool_]:
        """The pixels of ``kept`` (H, W) (those with a return, not the robot's) whose depth
        ``depth`` (H, W) [m] arrived since the previous call; ``returns`` (H, W): every pixel
        with a return, the robot's included. Remembers this frame."""
        last = np.where(returns, depth, np.float32(np.inf)).astype(np.float32, copy=False)
        previous, self._last = self._last, last
        if previous is None or previous.shape != depth.shape:
            return np.zeros(depth.shape, dtype=bool)
        return kept & (last < previous - np.float32(self.threshold))
