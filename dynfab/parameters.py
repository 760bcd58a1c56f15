"""Runtime parameters of a planner: named, typed views into one packed vector.

The compiled planner takes a single input ``z = [q, q̇, p]``; ``p`` holds the goals and
obstacle slots. :class:`ParameterLayout` says where each named quantity lives, creates the
matching CasADi symbols at build time, and numpy views into the packed buffer at run
time, so that ``params.obstacle_position[2] = [x, y, z]`` writes straight into the
planner's input without any per-call conversion.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np


@dataclass(frozen=True)
class ParameterSymbols:
    """CasADi symbols of the runtime parameters (slices of one vector ``p``)."""

    vector: ca.SX
    goal_position: tuple[ca.SX, ...]
    goal_weight: tuple[ca.SX, ...]
    obstacle_position: tuple[ca.SX, ...]
    obstacle_radius: tuple[ca.SX, ...]


@dataclass(frozen=True)
class RuntimeParameters:
    """Writable numpy views of the runtime parameters.

    Attributes:
        goal_position: one view per goal, of the goal's dimension [m or rad].
        goal_weight: (n_goals,) weights; 0 deactivates a goal.
        obstacle_position: (slots, 3) sphere centres [m] (z ignored by planar robots).
        obstacle_radius: (slots,) radii [m]; 0 marks an unused slot.
    """

    goal_position: tuple[np.ndarray, ...]
    goal_weight: np.ndarray
    obstacle_position: np.ndarray
    obstacle_radius: np.ndarray


@dataclass(frozen=True)
class ParameterLayout:
    """Order of the packed parameters: goal positions, goal weights, obstacle centres,
    obstacle radii."""

    goal_dimensions: tuple[int, ...]
    obstacle_slots: int

    @property
    def size(self) -> int:
        return sum(self.goal_dimensions) + len(self.goal_dimensions) + 4 * self.obstacle_slots

    def _offsets(self) -> tuple[list[slice], int, int, int]:
        goal_slices, start = [], 0
        for dim in self.goal_dimensions:
            goal_slices.append(slice(start, start + dim))
            start += dim
        weights = start
        centres = weights + len(self.goal_dimensions)
        radii = centres + 3 * self.obstacle_slots
        return goal_slices, weights, centres, radii

    def symbols(self) -> ParameterSymbols:
        vector = ca.SX.sym("p", self.size)
        goal_slices, weights, centres, radii = self._offsets()
        n_goals = len(self.goal_dimensions)
        return ParameterSymbols(
            vector=vector,
            goal_position=tuple(vector[s] for s in goal_slices),
            goal_weight=tuple(vector[weights + i] for i in range(n_goals)),
            obstacle_position=tuple(vector[centres + 3 * k: centres + 3 * k + 3] for k in range(self.obstacle_slots)),
            obstacle_radius=tuple(vector[radii + k] for k in range(self.obstacle_slots)),
        )

    def views(self, buffer: np.ndarray) -> RuntimeParameters:
        """Views into ``buffer`` (length :attr:`size`); writes go straight into it."""
        if buffer.shape != (self.size,):
            raise ValueError(f"parameter buffer must have shape ({self.size},), got {buffer.shape}")
        goal_slices, weights, centres, radii = self._offsets()
        n_goals = len(self.goal_dimensions)
        return RuntimeParameters(
            goal_position=tuple(buffer[s] for s in goal_slices),
            goal_weight=buffer[weights: weights + n_goals],
            obstacle_position=buffer[centres: radii].reshape(self.obstacle_slots, 3),
            obstacle_radius=buffer[radii: radii + self.obstacle_slots],
        )
