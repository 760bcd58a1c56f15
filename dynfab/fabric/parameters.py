"""Runtime parameters of a planner: named, typed views into one packed vector.

The compiled planner takes a single input ``z = [q, q̇, p]``; ``p`` holds the goals and
obstacle slots. :class:`ParameterLayout` says where each named quantity lives, creates the
matching CasADi symbols at build time, and numpy views into the packed buffer at run
time, so that ``params.obstacle_position[2] = [x, y, z]`` writes straight into the
planner's input without any per-call conversion.

A *dynamic* layout also carries the velocity and acceleration of every goal reference
and obstacle (paper section IV: the dynamic pullback needs ``ẋ̃`` and ``ẍ̃``); a static
layout has none, and its planner treats them as structurally zero.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from dynfab.fabric.maps import Reference


@dataclass(frozen=True)
class ParameterSymbols:
    """CasADi symbols of the runtime parameters (slices of one vector ``p``).

    Attributes:
        vector: the whole ``p``.
        goals: per goal, its reference ``(x̃, ẋ̃, ẍ̃)``; velocity and acceleration are
            structural zeros in a static layout.
        goal_weight: per goal, its weight.
        obstacles: per slot, the centre's reference ``(c, ċ, c̈)`` (3-D).
        obstacle_radius: per slot, the radius.
    """

    vector: ca.SX
    goals: tuple[Reference, ...]
    goal_weight: tuple[ca.SX, ...]
    obstacles: tuple[Reference, ...]
    obstacle_radius: tuple[ca.SX, ...]


@dataclass(frozen=True)
class RuntimeParameters:
    """Writable numpy views of the runtime parameters.

    Attributes:
        goal_position: one view per goal, of the goal's dimension [m or rad; unit
            directions for orientation goals].
        goal_weight: (n_goals,) weights; 0 deactivates a goal.
        obstacle_position: (slots, 3) sphere centres [m] (z ignored by planar robots).
        obstacle_radius: (slots,) radii [m]; 0 marks an unused slot.
        goal_velocity, goal_acceleration: per goal ``ẋ̃`` [m/s], ``ẍ̃`` [m/s²]
            (dynamic planners only, else ``None``).
        obstacle_velocity, obstacle_acceleration: (slots, 3) [m/s], [m/s²]
            (dynamic planners only, else ``None``).
    """

    goal_position: tuple[np.ndarray, ...]
    goal_weight: np.ndarray
    obstacle_position: np.ndarray
    obstacle_radius: np.ndarray
    goal_velocity: tuple[np.ndarray, ...] | None = None
    goal_acceleration: tuple[np.ndarray, ...] | None = None
    obstacle_velocity: np.ndarray | None = None
    obstacle_acceleration: np.ndarray | None = None


@dataclass(frozen=True)
class ParameterLayout:
    """Order of the packed parameters: per goal its position (then velocity and
    acceleration if dynamic), the goal weights, the obstacle centres (then velocities and
    accelerations if dynamic), the obstacle radii."""

    goal_dimensions: tuple[int, ...]
    obstacle_slots: int
    dynamic: bool = False

    @property
    def _derivatives(self) -> int:
        return 3 if self.dynamic else 1

    @property
    def size(self) -> int:
        k = self._derivatives
        return k * sum(self.goal_dimensions) + len(self.goal_dimensions) + (3 * k + 1) * self.obstacle_slots

    def _blocks(self) -> tuple[list[list[slice]], int, list[slice], int]:
        """Goal slices per goal and derivative, weight offset, obstacle blocks, radius offset."""
        k, start = self._derivatives, 0
        goals = []
        for dim in self.goal_dimensions:
            goals.append([slice(start + i * dim, start + (i + 1) * dim) for i in range(k)])
            start += k * dim
        weights = start
        start += len(self.goal_dimensions)
        obstacle_blocks = [slice(start + i * 3 * self.obstacle_slots, start + (i + 1) * 3 * self.obstacle_slots)
                           for i in range(k)]
        radii = start + 3 * k * self.obstacle_slots
        return goals, weights, obstacle_blocks, radii

    def symbols(self) -> ParameterSymbols:
        vector = ca.SX.sym("p", self.size)
        goals, weights, obstacle_blocks, radii = self._blocks()
        goal_references = []
        for dim, slices in zip(self.goal_dimensions, goals):
            parts = [vector[s] for s in slices] + [ca.SX(dim, 1)] * (3 - len(slices))
            goal_references.append(Reference(*parts))
        obstacle_references = []
        for slot in range(self.obstacle_slots):
            parts = [vector[block.start + 3 * slot: block.start + 3 * slot + 3] for block in obstacle_blocks]
            parts += [ca.SX(3, 1)] * (3 - len(parts))
            obstacle_references.append(Reference(*parts))
        return ParameterSymbols(
            vector=vector,
            goals=tuple(goal_references),
            goal_weight=tuple(vector[weights + i] for i in range(len(self.goal_dimensions))),
            obstacles=tuple(obstacle_references),
            obstacle_radius=tuple(vector[radii + k] for k in range(self.obstacle_slots)),
        )

    def views(self, buffer: np.ndarray) -> RuntimeParameters:
        """Views into ``buffer`` (length :attr:`size`); writes go straight into it."""
        if buffer.shape != (self.size,):
            raise ValueError(f"parameter buffer must have shape ({self.size},), got {buffer.shape}")
        goals, weights, obstacle_blocks, radii = self._blocks()
        n_goals = len(self.goal_dimensions)
        goal_views = [tuple(buffer[slices[i]] for slices in goals) for i in range(self._derivatives)]
        obstacle_views = [buffer[block].reshape(self.obstacle_slots, 3) for block in obstacle_blocks]
        return RuntimeParameters(
            goal_position=goal_views[0],
            goal_weight=buffer[weights: weights + n_goals],
            obstacle_position=obstacle_views[0],
            obstacle_radius=buffer[radii: radii + self.obstacle_slots],
            goal_velocity=goal_views[1] if self.dynamic else None,
            goal_acceleration=goal_views[2] if self.dynamic else None,
            obstacle_velocity=obstacle_views[1] if self.dynamic else None,
            obstacle_acceleration=obstacle_views[2] if self.dynamic else None,
        )
