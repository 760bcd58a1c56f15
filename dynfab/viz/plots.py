"""Plots of a run: the robot's body at a few instants, goal-link path, goals and
obstacles, and clearance over time.

Figures are drawn on matplotlib's Agg canvas (no pyplot, no display, no global state).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure, SubFigure
from matplotlib.patches import Circle
from mpl_toolkits.mplot3d import Axes3D
from numpy.typing import ArrayLike, NDArray

from dynfab.geometry.shapes import Shape
from dynfab.perception.camera_spec import CameraSpec
from dynfab.viz.body_drawing import draw_body_3d, draw_body_projection, focus_box
from dynfab.viz.robot_snapshots import RobotSnapshots
from dynfab.viz.scene_drawing import (
    draw_camera_3d,
    draw_camera_projection,
    draw_shape_3d,
    draw_shape_projection,
    shape_label,
)

_PATH_COLOR = "C0"
_GOAL_COLOR = "C2"
_OBSTACLE_COLOR = "C3"
_AXIS_NAMES = "xyz"

GoalMarker = tuple[ArrayLike, float]
"""``(position, tolerance)``: a goal point (d,) or a reference path (T, d), and [m]."""

ShapeTrack = tuple[Shape, Sequence[float], ArrayLike]
"""``(shape, orientation, centres)``: an obstacle shape (a primitive, a mesh or a point
cloud), its quaternion (w, x, y, z) and its frame's origin over time (T, 3) [m]."""


def run_panels(planar: bool, has_clearance: bool, has_reference: bool) -> int:
    """Panels in a row of a planar run's drawing: the top view, the clearance, the
    tracking error (3-D runs always take a 2 x 3 grid)."""
    return 1 + has_clearance + has_reference if planar else 3


def run_figure_size(planar: bool, panels: int) -> tuple[float, float]:
    """Width and height [in] of one run's drawing (:func:`draw_run`)."""
    return (5.5 * panels, 5.0) if planar else (16.0, 10.0)


def draw_run(
    figure: Figure | SubFigure,
    goal_link_positions: ArrayLike,
    goals: Sequence[GoalMarker],
    obstacles_over_time: ArrayLike,
    obstacle_radii: ArrayLike,
    planar: bool,
    clearance_over_time: ArrayLike | None = None,
    times: ArrayLike | None = None,
    title: str = "dynfab run",
    base_path: ArrayLike | None = None,
    shapes: Sequence[ShapeTrack] = (),
    robot: RobotSnapshots | None = None,
    clearance_label: str = "clearance",
    camera: CameraSpec | None = None,
) -> None:
    """Draw a run on ``figure`` (a whole figure, or one of its subfigures to compare runs).

    3-D robots get a 3-D view plus top (x-y) and side (x-z) projections; planar robots a
    top view. Obstacles are drawn at their start (faint) and end positions with the path
    of their centre; goals as stars with their tolerance circle (reference paths as
    dashed lines). A last panel shows the clearance over time if given.

    Args:
        figure: Where to draw; sized by :func:`run_figure_size` for a figure of its own.
        goal_link_positions: Goal-link positions over time, shape (T, 3) or (T, 2) [m].
        goals: ``(position, tolerance)`` per goal; position (d,) or a reference (T, d).
        obstacles_over_time: Obstacle centres, shape (T, m, 3) or (T, m, 2) [m].
        obstacle_radii: Obstacle radii, shape (m,) [m].
        planar: Draw the top view only.
        clearance_over_time: Clearance at each sample, shape (T,) [m].
        times: Sample times, shape (T,) [s], for the clearance axis (else step indices).
        title: The drawing's title.
        base_path: Positions (T, 2) of a mobile base [m], drawn in the top view.
        shapes: Box, cylinder, capsule and plane obstacles, drawn as wireframes at their
            end position (with the path of their origin if they move); meshes as their
            triangles, point clouds as their points (bounded samples,
            :mod:`dynfab.viz.scene_drawing`).
        robot: The robot's skeleton and collision spheres at a few instants, drawn in
            every view (the closest approach with the sphere obstacles where they were then).
        clearance_label: What ``clearance_over_time`` measures (e.g. ``"mesh clearance"``),
            the clearance panel's title and axis label.
        camera: A depth camera, drawn as its frustum (kept in the focused views).
    """
    positions = np.asarray(goal_link_positions, dtype=float)
    obstacles = np.asarray(obstacles_over_time, dtype=float)
    radii = np.asarray(obstacle_radii, dtype=float)
    markers = [(np.asarray(goal, dtype=float), float(tol)) for goal, tol in goals]
    tracks = [(shape, orientation, np.asarray(centres, dtype=float)) for shape, orientation, centres in shapes]
    reference = markers[0][0] if markers and markers[0][0].ndim == 2 else None
    if planar:
        panels = run_panels(True, clearance_over_time is not None, reference is not None)
        grid = figure.add_gridspec(1, panels)
        top = figure.add_subplot(grid[0, 0])
        _draw_projection(top, (0, 1), positions, markers, obstacles, radii)
        _draw_shapes(top, (0, 1), tracks, camera)
        if robot is not None:
            draw_body_projection(top, (0, 1), robot, obstacles, radii, _times(times))
            _focus(top, (0, 1), focus_box(robot, _kept_points(markers, camera)))
        _draw_base(top, base_path)
        top.legend(loc="best", fontsize="small")
        extra = [grid[0, k] for k in range(1, panels)]
    else:
        grid = figure.add_gridspec(2, 3)
        view = figure.add_subplot(grid[0, 0], projection="3d")
        _draw_3d(view, positions, markers, obstacles, radii, tracks, robot, camera)
        for slot, axes in ((grid[0, 1], (0, 1)), (grid[0, 2], (1, 2)), (grid[1, 0], (0, 2))):
            ax = figure.add_subplot(slot)
            _draw_projection(ax, axes, positions, markers, obstacles, radii)
            _draw_shapes(ax, axes, tracks, camera)
            if robot is not None:
                draw_body_projection(ax, axes, robot, obstacles, radii, _times(times))
                _focus(ax, axes, focus_box(robot, _kept_points(markers, camera)))
            if axes == (0, 1):
                _draw_base(ax, base_path)
                ax.legend(loc="best", fontsize="small")
        extra = [grid[1, 1], grid[1, 2]]
    if clearance_over_time is not None:
        _draw_clearance(figure.add_subplot(extra.pop(0)), clearance_over_time, times, clearance_label)
    if reference is not None:
        _draw_tracking_error(figure.add_subplot(extra.pop(0)), positions, reference, markers[0][1], times)
    figure.suptitle(title)


def _kept_points(markers: list[tuple[NDArray[np.float64], float]], camera: CameraSpec | None
                 ) -> NDArray[np.float64]:
    """The points (k, 3) to keep in a focused view: the goals (zero-padded planar ones) and
    the camera's optical centre."""
    points = [goal if goal.ndim == 1 else goal[-1] for goal, _ in markers]
    if camera is not None:
        points.append(np.asarray(camera.position))
    return np.array([np.pad(p[:3], (0, 3 - min(p.size, 3))) for p in points]).reshape(-1, 3)


def _focus(ax: Axes, axes: tuple[int, int], box: tuple[NDArray[np.float64], NDArray[np.float64]]) -> None:
    """Limit a projection to ``box`` (equal scales; what lies outside is cut)."""
    (i, j), (low, high) = axes, box
    centre, half = (low + high) / 2, max(high[i] - low[i], high[j] - low[j]) / 2
    ax.set_xlim(centre[i] - half, centre[i] + half)
    ax.set_ylim(centre[j] - half, centre[j] + half)
    ax.set_aspect("equal", adjustable="box")


def _times(times: ArrayLike | None) -> NDArray[np.float64] | None:
    return None if times is None else np.asarray(times, dtype=float)


def _draw_base(ax: Axes, base_path: ArrayLike | None) -> None:
    """The path of a mobile base's axle in the top view."""
    if base_path is None:
        return
    points = np.asarray(base_path, dtype=float)
    ax.plot(points[:, 0], points[:, 1], color="0.45", linewidth=1.5, label="base")
    ax.plot(points[-1, 0], points[-1, 1], "s", color="0.45", markersize=5)


def _draw_tracking_error(ax: Axes, positions: NDArray[np.float64], reference: NDArray[np.float64],
                         tolerance: float, times: ArrayLike | None) -> None:
    """Distance between the goal link and its moving reference over time."""
    error = np.linalg.norm(positions - reference[:, : positions.shape[1]], axis=1)
    x = np.arange(error.size) if times is None else np.asarray(times, dtype=float)
    ax.plot(x, error, color=_PATH_COLOR)
    ax.axhline(tolerance, color=_GOAL_COLOR, linestyle="--", linewidth=1, label="tolerance")
    ax.set_xlabel("time [s]" if times is not None else "step")
    ax.set_ylabel("tracking error [m]")
    ax.set_title(f"tracking error (mean {error.mean():.3f} m)")
    ax.set_yscale("log")
    ax.legend(loc="best", fontsize="small")
    ax.grid(True, alpha=0.3)


_VIEW_NAMES = {(0, 1): "top (x-y)", (1, 2): "front (y-z)", (0, 2): "side (x-z)"}


def _draw_projection(
    ax: Axes,
    axes: tuple[int, int],
    positions: NDArray[np.float64],
    goals: list[tuple[NDArray[np.float64], float]],
    obstacles: NDArray[np.float64],
    radii: NDArray[np.float64],
) -> None:
    """Draw the path, goals and obstacles projected on the plane of two axes."""
    i, j = axes
    for k, radius in enumerate(radii):
        centers = obstacles[:, k, :]
        label = "obstacle" if k == 0 else None
        if np.ptp(centers[:, [i, j]], axis=0).max() > 0.0:
            ax.plot(centers[:, i], centers[:, j], ":", color=_OBSTACLE_COLOR, linewidth=1)
            start = (centers[0, i], centers[0, j])
            ax.add_patch(Circle(start, radius, color=_OBSTACLE_COLOR, alpha=0.12))
        end = (centers[-1, i], centers[-1, j])
        ax.add_patch(Circle(end, radius, color=_OBSTACLE_COLOR, alpha=0.35, label=label))
    for k, (goal, tolerance) in enumerate(goals):
        target = goal if goal.ndim == 1 else goal[-1]
        label = "goal" if k == 0 else None
        if goal.ndim == 2:
            ax.plot(goal[:, i], goal[:, j], "--", color=_GOAL_COLOR, linewidth=1, label="reference")
        ax.plot(target[i], target[j], "*", color=_GOAL_COLOR, markersize=12, label=label)
        tolerance_circle = Circle(
            (target[i], target[j]), tolerance, fill=False, linestyle="--", color=_GOAL_COLOR
        )
        ax.add_patch(tolerance_circle)
    ax.plot(positions[:, i], positions[:, j], color=_PATH_COLOR, label="goal link")
    ax.plot(positions[0, i], positions[0, j], "o", color=_PATH_COLOR, label="start")
    ax.set_xlabel(f"{_AXIS_NAMES[i]} [m]")
    ax.set_ylabel(f"{_AXIS_NAMES[j]} [m]")
    ax.set_title(_VIEW_NAMES[axes])
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)


def _draw_shapes(ax: Axes, axes: tuple[int, int], tracks: list[tuple[Shape, Sequence[float], NDArray[np.float64]]],
                 camera: CameraSpec | None) -> None:
    """The shapes at their end positions and the camera's frustum, projected on two axes
    (one legend entry per kind of shape)."""
    labelled: set[str] = set()
    for shape, orientation, centres in tracks:
        draw_shape_projection(ax, axes, shape, orientation, centres, shape_label(shape) not in labelled)
        labelled.add(shape_label(shape))
    if camera is not None:
        draw_camera_projection(ax, axes, camera, True)


def _draw_3d(
    ax: Axes3D,
    positions: NDArray[np.float64],
    goals: list[tuple[NDArray[np.float64], float]],
    obstacles: NDArray[np.float64],
    radii: NDArray[np.float64],
    tracks: list[tuple[Shape, Sequence[float], NDArray[np.float64]]],
    robot: RobotSnapshots | None = None,
    camera: CameraSpec | None = None,
) -> None:
    """Draw the path, goals (with tolerance spheres), obstacles, shapes, the camera's frustum
    and the robot in 3-D."""
    extent = [positions]
    if robot is not None:
        extent += draw_body_3d(ax, robot)
    for shape, orientation, centres in tracks:
        extent.append(draw_shape_3d(ax, shape, orientation, centres))
    if camera is not None:
        extent.append(draw_camera_3d(ax, camera))
    for k, radius in enumerate(radii):
        centers = obstacles[:, k, :]
        ax.plot(*centers.T, ":", color=_OBSTACLE_COLOR, linewidth=1)
        x, y, z = _sphere_surface(centers[-1], radius)
        ax.plot_surface(x, y, z, color=_OBSTACLE_COLOR, alpha=0.3, linewidth=0)
        extent += [centers - radius, centers + radius]
    for goal, tolerance in goals:
        end = goal if goal.ndim == 1 else goal[-1]
        if goal.ndim == 2:
            ax.plot(goal[:, 0], goal[:, 1], goal[:, 2], "--", color=_GOAL_COLOR, linewidth=1)
        ax.plot([end[0]], [end[1]], [end[2]], "*", color=_GOAL_COLOR, markersize=12)
        x, y, z = _sphere_surface(end, tolerance)
        ax.plot_wireframe(x, y, z, color=_GOAL_COLOR, alpha=0.4, linewidth=0.5)
        extent += [np.atleast_2d(end) - tolerance, np.atleast_2d(end) + tolerance]
    ax.plot(positions[:, 0], positions[:, 1], positions[:, 2], color=_PATH_COLOR)
    ax.plot([positions[0, 0]], [positions[0, 1]], [positions[0, 2]], "o", color=_PATH_COLOR)
    points = np.vstack(extent)
    low, high = points.min(axis=0), points.max(axis=0)
    if robot is not None:  # where the robot worked, not the far ends of obstacle tracks
        low, high = focus_box(robot, _kept_points(goals, camera))
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.set_zlim(low[2], high[2])
    ax.set_box_aspect(np.maximum(high - low, 1e-3))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title("3-D view")


def _draw_clearance(ax: Axes, clearance: ArrayLike, times: ArrayLike | None, label: str) -> None:
    """Plot clearance over time with the collision threshold at zero; ``label`` names it."""
    values = np.asarray(clearance, dtype=float)
    x = np.arange(values.shape[0]) if times is None else np.asarray(times, dtype=float)
    ax.plot(x, values, color=_PATH_COLOR, label=label)
    ax.axhline(0.0, color=_OBSTACLE_COLOR, linestyle="--", linewidth=1, label="collision")
    finite = values[np.isfinite(values)]
    ax.set_title(f"{label} (min {finite.min():+.3f} m)" if finite.size else label)
    ax.set_xlabel("step" if times is None else "time [s]")
    ax.set_ylabel(f"{label} [m]")
    ax.legend(loc="best", fontsize="small")
    ax.grid(True, alpha=0.3)


def _sphere_surface(
    center: NDArray[np.float64], radius: float, resolution: int = 16
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Grid points (x, y, z) of a sphere surface, for plot_surface / plot_wireframe."""
    u, v = np.meshgrid(
        np.linspace(0.0, 2.0 * np.pi, resolution), np.linspace(0.0, np.pi, resolution)
    )
    return (
        center[0] + radius * np.cos(u) * np.sin(v),
        center[1] + radius * np.sin(u) * np.sin(v),
        center[2] + radius * np.cos(v),
    )
