"""The scenario as the viewer shows it: the robot, and where goals and obstacles are at
time t, including where the user dragged them.

A dragged goal or obstacle keeps its motion and is moved by an offset ``Δ``
(:class:`~dynfab.motion.shifted_trajectory.ShiftedTrajectory`): dragging to ``P`` at time
``t`` sets the new offset ``Δ1 = P − x̃(t)`` on the axes the reference has, and the offset
glides there from its value at ``t`` over the simulated time since the previous drag
event (at most :data:`MAX_GLIDE`), so that a dragged item moves with the hand's velocity,
which the dynamic fabric sees; the static fabric, by design, sees positions only.
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
#: Longest glide of a dragged item to the handle's point [s] (and the glide after a pause
#: in dragging).
MAX_GLIDE = 0.2


@dataclass(frozen=True)
class Shift:
    """The offset of one reference: gliding from ``start_offset`` to ``offset`` over
    ``[start, start + glide]`` [m, s] (see :class:`ShiftedTrajectory`)."""

    start_offset: np.ndarray
    offset: np.ndarray
    start: float = 0.0
    glide: float = 0.0

    def at(self, t: float) -> np.ndarray:
        """The offset at ``t`` [m]."""
        progress = 1.0 if self.glide == 0.0 else float(np.clip((t - self.start) / self.glide, 0.0, 1.0))
        return self.start_offset + progress * (self.offset - self.start_offset)

    def moved(self, offset: np.ndarray, t: float, dt: float) -> Shift:
        """Gliding from the offset at ``t`` to ``offset``, over the time since the last move
        (between ``dt`` and :data:`MAX_GLIDE`)."""
        since = t - self.start
        glide = MAX_GLIDE if since > MAX_GLIDE else max(since, dt)
        return Shift(self.at(t), np.asarray(offset, dtype=float), t, glide)

    def shifted(self, reference: Trajectory) -> Trajectory:
        """``reference`` with this offset (itself while the offset is zero)."""
        if not (self.offset.any() or self.start_offset.any()):
            return reference
        return ShiftedTrajectory(reference, tuple(self.offset), tuple(self.start_offset), self.start, self.glide)


def _zero_shift(dimension: int) -> Shift:
    return Shift(np.zeros(dimension), np.zeros(dimension))


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
        goal_shifts: per scenario goal, its offset (on the goal's axes).
        obstacle_shifts: per obstacle, its offset (on its trajectory's axes).
    """

    def __init__(self, scenario: Scenario, robot: Robot | None = None) -> None:
        """Build the robot (unless given) and the references.

        Raises:
            ScenarioError: the scenario does not fit its robot (as ``dynfab run``).
        """
        self.robot = robot_for(scenario) if robot is None else robot
        self.scenario = validate_for_robot(scenario, self.robot)
        self._references = scenario_references(self.scenario, self.robot)
        self.goal_shifts = [_zero_shift(g.dimension) for g in self._references.goals]
        self.obstacle_shifts = [_zero_shift(o.dimension) for o in self._references.obstacles]

    def draggable_goal(self, k: int) -> bool:
        """True if goal ``k`` is a workspace point in the world frame (it gets a handle)."""
        goal = self.scenario.goals[k]
        return goal.type in POINT_GOALS and goal.parent_link is None

    def goal_moves(self, k: int) -> bool:
        """True if goal ``k``'s scenario reference moves (a path goal)."""
        return not isinstance(self._references.goals[k], StaticPoint)

    def obstacle_moves(self, k: int) -> bool:
        """True if obstacle ``k`` rides on a trajectory in the scenario."""
        return not isinstance(self._references.obstacles[k], StaticPoint)

    def references(self) -> References:
        """The scenario's references moved by the offsets."""
        base = self._references
        goals = tuple(shift.shifted(g) for g, shift in zip(base.goals, self.goal_shifts))
        obstacles = tuple(shift.shifted(o) for o, shift in zip(base.obstacles, self.obstacle_shifts))
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
        self.goal_shifts[k] = self.goal_shifts[k].moved(np.asarray(point, dtype=float)[axes] - now, t,
                                                        self.scenario.dt)

    def move_obstacle(self, k: int, point: np.ndarray, t: float) -> None:
        """Put obstacle ``k``'s centre at the world point ``point`` (3,) at time ``t`` [s]."""
        now = self._references.obstacles[k].evaluate(t).position
        self.obstacle_shifts[k] = self.obstacle_shifts[k].moved(np.asarray(point, dtype=float)[: now.size] - now, t,
                                                                self.scenario.dt)

    def clear_offsets(self) -> None:
        """Every goal and obstacle back on its scenario reference."""
        self.goal_shifts = [_zero_shift(g.dimension) for g in self._references.goals]
        self.obstacle_shifts = [_zero_shift(o.dimension) for o in self._references.obstacles]

    def goal_point(self, k: int, t: float) -> np.ndarray | None:
        """Goal ``k``'s point in the world at ``t`` (axes it leaves free at 0) [m], or None."""
        if not self.draggable_goal(k):
            return None
        point = np.zeros(3)
        point[goal_axes(self.scenario.goals[k], self.robot)] = (
            self._references.goals[k].evaluate(t).position + self.goal_shifts[k].at(t))
        return point

    def obstacle_centres(self, t: float) -> np.ndarray:
        """(m, 3) obstacle centres at ``t`` (planar ones at z = 0) [m]."""
        centres = np.zeros((len(self._references.obstacles), 3))
        for k, (reference, shift) in enumerate(zip(self._references.obstacles, self.obstacle_shifts)):
            position = reference.evaluate(t).position + shift.at(t)
            centres[k, : position.size] = position
        return centres

    def goal_path(self, k: int, times: np.ndarray) -> np.ndarray | None:
        """The world points (T, 3) of a moving point goal ``k`` at ``times``, or None."""
        reference = self._references.goals[k]
        if not self.draggable_goal(k) or isinstance(reference, StaticPoint):
            return None
        points = np.zeros((len(times), 3))
        points[:, goal_axes(self.scenario.goals[k], self.robot)] = reference.sample(times)[0] + self.goal_shifts[k].offset
        return points

    def obstacle_path(self, k: int, times: np.ndarray) -> np.ndarray | None:
        """The centres (T, 3) of a moving obstacle ``k`` at ``times``, or None."""
        reference = self._references.obstacles[k]
        if isinstance(reference, StaticPoint):
            return None
        positions = reference.sample(times)[0] + self.obstacle_shifts[k].offset
        points = np.zeros((len(times), 3))
        points[:, : positions.shape[1]] = positions
        return points

    def state(self, t: float, q: np.ndarray) -> SceneState:
        """The scene at ``t`` with the robot at ``q``."""
        goals = tuple(self.goal_point(k, t) for k in range(len(self.scenario.goals)))
        return SceneState(t, np.array(q, dtype=float), goals, self.obstacle_centres(t))

