"""Draw :class:`~dynfab.viz.robot_snapshots.RobotSnapshots` into a run plot: the skeleton
and collision spheres at each snapshot (fainter the earlier), the closest approach to an
obstacle in its own colour, with the sphere obstacles where they were at that instant (so
a collision with a moving obstacle is visible)."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Circle
from mpl_toolkits.mplot3d import Axes3D
from numpy.typing import NDArray

from dynfab.viz.robot_snapshots import RobotSnapshots

_BODY_COLOR = "0.25"
_CLOSEST_COLOR = "C1"
_OBSTACLE_COLOR = "C3"


def _style(snapshots: RobotSnapshots, k: int) -> tuple[str, float]:
    """Colour and opacity of snapshot ``k``: later ones darker, the closest approach orange."""
    if k == snapshots.closest:
        return _CLOSEST_COLOR, 0.9
    count = len(snapshots.times)
    return _BODY_COLOR, 0.25 + 0.6 * k / max(count - 1, 1)


def _label(snapshots: RobotSnapshots, k: int) -> str | None:
    if k == snapshots.closest:
        return f"closest approach (t = {snapshots.times[k]:.2f} s)"
    return "robot (faint: earlier)" if k == len(snapshots.times) - 1 else None


def draw_body_projection(ax: Axes, axes: tuple[int, int], snapshots: RobotSnapshots,
                         obstacles: NDArray[np.float64], radii: NDArray[np.float64],
                         times: NDArray[np.float64] | None) -> None:
    """Snapshots projected on the plane of two axes; spheres project to their exact disc.

    Args:
        ax: The axes.
        axes: The two coordinates drawn, e.g. ``(0, 1)`` for the top view.
        snapshots: The robot's body at a few instants.
        obstacles: Sphere obstacle centres over the run, shape (T, m, 3) [m].
        radii: Their radii (m,) [m].
        times: The run's sample times (T,) [s], to place the obstacles at the closest approach.
    """
    i, j = axes
    for k in range(len(snapshots.times)):
        color, alpha = _style(snapshots, k)
        for n, (start, end) in enumerate(snapshots.segments[k]):
            ax.plot([start[i], end[i]], [start[j], end[j]], "-", color=color, alpha=alpha, linewidth=2,
                    solid_capstyle="round", label=_label(snapshots, k) if n == 0 else None)
        for centre, radius in zip(snapshots.sphere_centres[k], snapshots.sphere_radii):
            ax.add_patch(Circle((centre[i], centre[j]), radius, fill=False, color=color, alpha=0.5 * alpha,
                                linewidth=0.8))
    row = _closest_row(snapshots, times, obstacles.shape[0])
    if row is not None:
        for centre, radius in zip(obstacles[row], radii):
            ax.add_patch(Circle((centre[i], centre[j]), radius, fill=False, linestyle="--", color=_OBSTACLE_COLOR,
                                linewidth=1.2))


def draw_body_3d(ax: Axes3D, snapshots: RobotSnapshots) -> list[NDArray[np.float64]]:
    """Snapshots' skeletons and sphere centres in 3-D; the points drawn (for the axes' extent)."""
    drawn = []
    for k in range(len(snapshots.times)):
        color, alpha = _style(snapshots, k)
        for start, end in snapshots.segments[k]:
            ax.plot([start[0], end[0]], [start[1], end[1]], [start[2], end[2]], "-", color=color, alpha=alpha,
                    linewidth=2)
        centres = snapshots.sphere_centres[k]
        if len(centres):
            ax.scatter(centres[:, 0], centres[:, 1], centres[:, 2], color=color, alpha=0.4 * alpha, s=8)
        drawn.append(snapshots.segments[k].reshape(-1, 3))
    return drawn


#: Margin around the robot's snapshots and the goals in a focused view [m].
FOCUS_MARGIN = 0.3


def focus_box(snapshots: RobotSnapshots, points: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Corners (3,) of the box around the robot's snapshots and ``points`` (k, 3) (goals),
    widened by :data:`FOCUS_MARGIN`: the views show where the robot worked, not the far
    ends of obstacle tracks."""
    body = np.vstack([snapshots.segments.reshape(-1, 3), snapshots.sphere_centres.reshape(-1, 3),
                      np.asarray(points, dtype=float).reshape(-1, 3)])
    radius = float(snapshots.sphere_radii.max(initial=0.0))
    return body.min(axis=0) - radius - FOCUS_MARGIN, body.max(axis=0) + radius + FOCUS_MARGIN


def _closest_row(snapshots: RobotSnapshots, times: NDArray[np.float64] | None, samples: int) -> int | None:
    """The run's sample row of the closest approach, or None."""
    if snapshots.closest is None or times is None or samples == 0:
        return None
    return int(np.argmin(np.abs(np.asarray(times, dtype=float) - snapshots.times[snapshots.closest])))
