"""What a camera cannot see behind the surfaces it sees, taken as solid.

A depth camera sees the front of things; behind each point ``p`` it saw, along its ray from
the camera's centre ``o``, lies either the rest of the object or free space, and the camera
cannot tell which. A planner that took it as free would route the robot through the unseen
back of an obstacle. Here each point is extended along its ray by ``thickness`` [m], in
steps of ``step``:

    p_k = p + k · step · (p − o) / ‖p − o‖,      k = 0 .. ⌊thickness / step⌋,

so an object no deeper than ``thickness`` (seen from the camera) is wholly covered, at the
price of thin ones (a pole, a panel) standing ``thickness`` deep to the planner.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["behind_surfaces"]


def behind_surfaces(points: NDArray[np.float64], origin: ArrayLike, thickness: float,
                    step: float) -> NDArray[np.float64]:
    """``points`` (N, 3) [m] and their extensions away from ``origin`` (module docstring),
    ((K + 1) N, 3) with ``K = ⌊thickness / step⌋``.

    Raises:
        ValueError: ``thickness`` < 0 or ``step`` <= 0.
    """
    if not (thickness >= 0.0 and step > 0.0):
        raise ValueError(f"thickness must be >= 0 and step > 0, got {thickness} and {step}")
    rays = points - np.asarray(origin, dtype=float)
    rays /= np.maximum(np.linalg.norm(rays, axis=1, keepdims=True), 1e-12)
    offsets = step * np.arange(int(np.floor(thickness / step + 1e-9)) + 1)
    return (points[None, :, :] + offsets[:, None, None] * rays[None, :, :]).reshape(-1, 3)
