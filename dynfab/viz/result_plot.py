"""The PNG of a finished run (``dynfab run --plot``, ``dynfab plot run.npz``, the example
of an experiment series), or of runs to compare (``dynfab demo dynamic``: the dynamic
fabric and its static baseline, one above the other): the robot's body at a few instants,
the goal link's path, the goals, the obstacles and the clearance over time: the clearance
the run's metrics report (on the collision meshes for a robot measured by meshes, else on
the collision spheres), named so in the plot."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure, SubFigure
from numpy.typing import NDArray

from dynfab.robots.mesh_sweep import clearance_per_sample
from dynfab.scenario.exact_metrics import mesh_model_for, obstacle_shapes
from dynfab.scenario.runner import RunResult, link_path
from dynfab.viz.plots import draw_run, run_figure_size, run_panels
from dynfab.viz.robot_snapshots import robot_snapshots


def plot_result(result: RunResult, path: str | Path, title: str | None = None) -> Figure:
    """Plot ``result`` to ``path`` and return the figure (see :func:`plot_results`).

    Args:
        result: The run.
        path: Output PNG file.
        title: Figure title; default the robot's name and the outcome.
    """
    return plot_results([result], path, [f"{title or result.robot.name}: {outcome_of(result)}"])


def plot_results(results: Sequence[RunResult], path: str | Path, titles: Sequence[str] | None = None) -> Figure:
    """Plot runs one above the other to ``path`` and return the figure (one run: the
    drawing fills it; several: one subfigure each, in order).

    The goal link's path is drawn in the goal's workspace coordinates; a goal in other
    coordinates (joint goals, a subset of axes) or without a point (axis goals) is not
    drawn, the link's full path is. The clearance panel shows :func:`reported_clearance`.

    Args:
        results: The runs.
        path: Output PNG file.
        titles: One per run; default the robot's name, the planner and the outcome.
    """
    titles = titles or [f"{r.robot.name}, {r.scenario.planner}: {outcome_of(r)}" for r in results]
    sizes = [run_figure_size(r.robot.planar, _panels(r)) for r in results]
    figure = Figure(figsize=(max(w for w, _ in sizes), sum(h for _, h in sizes)), layout="constrained")
    targets: Sequence[Figure | SubFigure] = [figure] if len(results) == 1 else \
        figure.subfigures(len(results), 1, height_ratios=[h for _, h in sizes])
    for target, result, title in zip(targets, results, titles):
        _draw_result(target, result, title)
    figure.savefig(Path(path), dpi=100)
    return figure


def outcome_of(result: RunResult) -> str:
    """``success``, ``collision`` or ``goal not reached``."""
    metrics = result.metrics
    return "success" if metrics.success else "collision" if metrics.collision else "goal not reached"


def reported_clearance(result: RunResult) -> tuple[NDArray[np.float64], str]:
    """The clearance over time (T,) [m] whose minimum the run's ``clearance`` metric is, and
    its name: ``"mesh clearance"`` (collision meshes against the obstacles' exact shapes,
    :func:`~dynfab.robots.mesh_sweep.clearance_per_sample`) where the metrics are measured
    on meshes, else ``"sphere clearance"`` (the planner's collision spheres)."""
    if result.mesh_sweep is None or not result.scenario.obstacles:
        return result.clearance, "sphere clearance"
    model = mesh_model_for(result.robot)
    shapes = obstacle_shapes(result.scenario.obstacles, result.obstacle_centers, lowered=True)
    return clearance_per_sample(model, result.record.q, shapes), "mesh clearance"


def _panels(result: RunResult) -> int:
    tracked = result.scenario.goals[0].type == "path" and result.goal_positions.shape[1] == 2
    return run_panels(result.robot.planar, bool(result.scenario.obstacles), tracked)


def _draw_result(target: Figure | SubFigure, result: RunResult, title: str) -> None:
    goal = result.scenario.goals[0]
    robot = result.robot
    dimension = 2 if robot.planar else 3
    if goal.type not in ("joint", "axis") and result.goal_positions.shape[1] == dimension:
        positions = result.goal_positions
        markers = [(result.goal_reference if goal.type == "path" else goal.position, goal.tolerance)]
    else:
        link = goal.link if goal.type != "joint" else robot.goal_link
        positions = link_path(robot, link, result.record.q)[:, :dimension]
        markers = []
    obstacles = result.scenario.obstacles
    spheres = [k for k, o in enumerate(obstacles) if o.type == "sphere"]
    shapes = [(o.shape, o.orientation, result.obstacle_centers[:, k]) for k, o in enumerate(obstacles)
              if o.type != "sphere"]
    clearance, clearance_label = reported_clearance(result)
    snapshots = robot_snapshots(robot, result.record.q, result.record.t, clearance if obstacles else None)
    draw_run(target, positions, markers, result.obstacle_centers[:, spheres], [obstacles[k].radius for k in spheres],
             robot.planar, clearance_over_time=clearance if obstacles else None, times=result.record.t,
             clearance_label=clearance_label, title=title,
             base_path=None if robot.base is None else result.record.q[:, :2], shapes=shapes, robot=snapshots,
             camera=result.scenario.camera)
