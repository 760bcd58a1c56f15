"""The PNG of a finished run (``dynfab run --plot``, ``dynfab plot run.npz``, the example
of an experiment series): the robot's body at a few instants, the goal link's path, the
goals, the obstacles and the clearance over time."""

from __future__ import annotations

from pathlib import Path

from dynfab.scenario.runner import RunResult, link_path
from dynfab.viz.plots import plot_run
from dynfab.viz.robot_snapshots import robot_snapshots


def plot_result(result: RunResult, path: str | Path, title: str | None = None) -> None:
    """Plot ``result`` to ``path``. The goal link's path is drawn in the goal's workspace
    coordinates; a goal in other coordinates (joint goals, a subset of axes) or without
    a point (axis goals) is not drawn, the link's full path is.

    Args:
        result: The run.
        path: Output PNG file.
        title: Figure title; default the robot's name and the outcome.
    """
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
    metrics = result.metrics
    outcome = "success" if metrics.success else "collision" if metrics.collision else "goal not reached"
    snapshots = robot_snapshots(robot, result.record.q, result.record.t, result.clearance if obstacles else None)
    plot_run(path, positions, markers, result.obstacle_centers[:, spheres], [obstacles[k].radius for k in spheres],
             robot.planar, clearance_over_time=result.clearance if obstacles else None, times=result.record.t,
             title=f"{title or robot.name}: {outcome}",
             base_path=None if robot.base is None else result.record.q[:, :2], shapes=shapes, robot=snapshots)
