"""The scenario as the viewer shows it: the robot, and where goals and obstacles are at
time t, including where the user dragged them.

A dragged goal or obstacle keeps its motion and is moved by a constant offset ``Δ``
(:class:`~dynfab.motion.shifted_trajectory.ShiftedTrajectory`; a static one simply sits
at the new point): dragging to ``P`` at time ``t`` sets ``Δ = P − x̃(t)`` on the axes the
reference has.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from dynfab.motion.references import References
from dynfab.motion.shifted_trajectory import ShiftedTrajectory
from dynfab.motion.trajectories import StaticPoint, Trajectory
from dynfab.robots.robot import Robot
from dynfab.scenario.references import goal_axes, scenario_references
from dynfab.scenario.runner import robot_for
from dynfab.scenario.schema import Scenario, validate_for_robot

#: Goal types whose reference is a point of the workspace (a drag handle moves it).
POINT_GOALS = ("position", "pose", "path")


@dataclass(frozen=True)
class SceneState:
    """What the viewer draws at one instant.

    Attributes:
        t: time since the start [s].
        q: the robot's configuration.
        goal_points: per scenario goal, its point in the world (3,) [m], or None for goals
            that are not a point (joint, axis) or are given in a link's frame.
        obstacle_centres: (m, 3) obstacle centres (a plane: its point) [m].
    """

    t: float
    q: np.ndarray
    goal_points: tuple[np.ndarray | None, ...]
    obstacle_centres: np.ndarray


class ViewWorld:
    """The robot and the references of a scenario, with the user's offsets.

    Attributes:
        scenario: the scenario, validated for the robot.
        robot: the robot it names.
        goal_offsets: per scenario goal, its offset (on the goal's axes) [m].
        obstacle_offsets: per obstacle, its offset (on its trajectory's axes) [m].
    """

    def __init__(self, scenario: Scenario, robot: Robot | None = None) -> None:
        """Build the robot (unless given) and the references.

        Raises:
            ScenarioError: the scenario does not fit its robot (as ``dynfab run``).
        """
        self.robot = robot_for(scenario) if robot is None else robot
        self.scenario = validate_for_robot(scenario, self.robot)
        self._references = scenario_references(self.scenario, self.robot)
        self.goal_offsets = [np.zeros(g.dimension) for g in self._references.goals]
        self.obstacle_offsets = [np.zeros(o.dimension) for o in self._references.obstacles]

    def draggable_goal(self, k: int) -> bool:
        """True if goal ``k`` is a workspace point in the world frame (it gets a handle)."""
        goal = self.scenario.goals[k]
        return goal.type in POINT_GOALS and goal.parent_link is None

    def references(self) -> References:
        """The scenario's references moved by the offsets."""
        base = self._references
        goals = tuple(_shifted(g, o) for g, o in zip(base.goals, self.goal_offsets))
        obstacles = tuple(_shifted(r, o) for r, o in zip(base.obstacles, self.obstacle_offsets))
        return dataclasses.replace(base, goals=goals, obstacles=obstacles)

    def move_goal(self, k: int, point: np.ndarray, t: float) -> None:
        """Put goal ``k`` at the world point ``point`` (3,) at time ``t`` [s].

        Raises:
            ValueError: goal ``k`` is not draggable (:meth:`draggable_goal`).
        """
        if not self.draggable_goal(k):
            raise ValueError(f"goal[{k}]: a {self.scenario.goals[k].type} goal has no point to move")
        axes = goal_axes(self.scenario.goals[k], self.robot)
        now = self._references.goals[k].evaluate(t).position
        self.goal_offsets[k] = np.asarray(point, dtype=float)[axes] - now

    def move_obstacle(self, k: int, point: np.ndarray, t: float) -> None:
        """Put obstacle ``k``'s centre at the world point ``point`` (3,) at time ``t`` [s]."""
        now = self._references.obstacles[k].evaluate(t).position
        self.obstacle_offsets[k] = np.asarray(point, dtype=float)[: now.size] - now

    def clear_offsets(self) -> None:
        """Every goal and obstacle back on its scenario reference."""
        for offset in self.goal_offsets + self.obstacle_offsets:
            offset[:] = 0.0

    def goal_point(self, k: int, t: float) -> np.ndarray | None:
        """Goal ``k``'s point in the world at ``t`` (axes it leaves free at 0) [m], or None."""
        if not self.draggable_goal(k):
            return None
        point = np.zeros(3)
        point[goal_axes(self.scenario.goals[k], self.robot)] = (
            self._references.goals[k].evaluate(t).position + self.goal_offsets[k])
        return point

    def obstacle_centres(self, t: float) -> np.ndarray:
        """(m, 3) obstacle centres at ``t`` (planar ones at z = 0) [m]."""
        centres = np.zeros((len(self._references.obstacles), 3))
        for k, (reference, offset) in enumerate(zip(self._references.obstacles, self.obstacle_offsets)):
            position = reference.evaluate(t).position + offset
            centres[k, : position.size] = position
        return centres

    def goal_path(self, k: int, times: np.ndarray) -> np.ndarray | None:
        """The world points (T, 3) of a moving point goal ``k`` at ``times``, or None."""
        reference = self._references.goals[k]
        if not self.draggable_goal(k) or isinstance(reference, StaticPoint):
            return None
        points = np.zeros((len(times), 3))
        points[:, goal_axes(self.scenario.goals[k], self.robot)] = reference.sample(times)[0] + self.goal_offsets[k]
        return points

    def obstacle_path(self, k: int, times: np.ndarray) -> np.ndarray | None:
        """The centres (T, 3) of a moving obstacle ``k`` at ``times``, or None."""
        reference = self._references.obstacles[k]
        if isinstance(reference, StaticPoint):
            return None
        positions = reference.sample(times)[0] + self.obstacle_offsets[k]
        points = np.zeros((len(times), 3))
        points[:, : positions.shape[1]] = positions
        return points

    def state(self, t: float, q: np.ndarray) -> SceneState:
        """The scene at ``t`` with the robot at ``q``."""
        goals = tuple(self.goal_point(k, t) for k in range(len(self.scenario.goals)))
        return SceneState(t, np.array(q, dtype=float), goals, self.obstacle_centres(t))


def _shifted(reference: Trajectory, offset: np.ndarray) -> Trajectory:
    """``reference`` moved by ``offset`` (itself if the offset is zero)."""
    if not offset.any():
        return reference
    if isinstance(reference, StaticPoint):
        return StaticPoint(tuple(reference.evaluate(0.0).position + offset))
    return ShiftedTrajectory(reference, tuple(offset))
