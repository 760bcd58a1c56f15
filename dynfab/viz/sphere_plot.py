"""Plot of a robot's collision spheres against its collision meshes, in the zero pose.

Drawn on matplotlib's Agg canvas (no pyplot, no display, no global state): the meshes'
surface samples as dots and every sphere as its outline circle, in three projections.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Circle
from numpy.typing import ArrayLike

_VIEWS = (("x", "y", 0, 1), ("x", "z", 0, 2), ("y", "z", 1, 2))


def plot_spheres(path: str | Path, surface_points: ArrayLike, centers: ArrayLike, radii: ArrayLike,
                 title: str) -> None:
    """Write a PNG: root-frame surface samples (N, 3) and spheres (k, 3), (k,) [m]."""
    points = np.asarray(surface_points, dtype=float).reshape(-1, 3)
    centers = np.asarray(centers, dtype=float).reshape(-1, 3)
    radii = np.asarray(radii, dtype=float).reshape(-1)
    figure = Figure(figsize=(15, 5.5))
    for column, (first, second, i, j) in enumerate(_VIEWS):
        axes = figure.add_subplot(1, 3, column + 1)
        axes.scatter(points[:, i], points[:, j], s=0.2, color="0.3")
        for center, radius in zip(centers, radii):
            axes.add_patch(Circle((center[i], center[j]), radius, fill=False, color="C3", linewidth=0.8))
        axes.set_xlabel(f"{first} [m]")
        axes.set_ylabel(f"{second} [m]")
        axes.set_aspect("equal", adjustable="datalim")
        axes.autoscale_view()
    figure.suptitle(title)
    figure.tight_layout()
    figure.savefig(str(path), dpi=120)
