"""Runtime parameters of a planner: named, typed views into one packed vector.

The compiled planner takes a single input ``z = [q, q̇, p]``; ``p`` holds the goals,
the sphere obstacle slots and the shape slots (boxes, cylinders, capsules, planes).
:class:`ParameterLayout` says where each named quantity lives, creates the matching CasADi
symbols at build time, and numpy views into the packed buffer at run
time, so that ``params.obstacle_position[2] = [x, y, z]`` writes straight into the
planner's input without any per-call conversion.

A *dynamic* layout also carries the velocity and acceleration of every goal reference
and obstacle (paper section IV: the dynamic pullback needs ``ẋ̃`` and ``ẍ̃``); a static
layout has none, and its planner treats them as structurally zero.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields

import casadi as ca
import numpy as np

from dynfab.fabric.maps import Reference
from dynfab.fabric.parameter_views import (STATIC_REMEDY, AbsentParameter, GoalViews, LeafParameters, LeafViews,
                                           ParameterError)

__all__ = ["SHAPE_DIMENSIONS", "AbsentParameter", "GoalViews", "LeafParameters", "LeafViews", "ParameterError",
           "ParameterLayout", "ParameterSymbols", "RuntimeParameters", "ShapeSlots", "ShapeSymbols", "ShapeViews"]


#: Obstacle shapes that have slots of their own, and how many numbers size each
#: (box ``(lx, ly, lz)``, cylinder and capsule ``(radius, length)``, plane none) [m].
SHAPE_DIMENSIONS: dict[str, int] = {"box": 3, "cylinder": 2, "capsule": 2, "plane": 0}

#: the :class:`RuntimeParameters` field of each shape kind
_PLURAL: dict[str, str] = {"box": "boxes", "cylinder": "cylinders", "capsule": "capsules", "plane": "planes"}


@dataclass(frozen=True)
class ShapeSlots:
    """How many slots of each obstacle shape a planner has (fixed at build time).

    Attributes:
        box, cylinder, capsule, plane: slot counts (>= 0).
    """

    box: int = 0
    cylinder: int = 0
    capsule: int = 0
    plane: int = 0

    def __post_init__(self) -> None:
        for slot in fields(self):
            count = getattr(self, slot.name)
            if isinstance(count, bool) or not isinstance(count, int) or count < 0:
                raise ValueError(f"ShapeSlots.{slot.name} must be an integer >= 0, got {count!r}")

    def count(self, kind: str) -> int:
        """Slots of ``kind`` (a key of :data:`SHAPE_DIMENSIONS`)."""
        return int(getattr(self, kind))

    @property
    def total(self) -> int:
        """Slots of all shapes."""
        return sum(self.count(kind) for kind in SHAPE_DIMENSIONS)


@dataclass(frozen=True)
class ShapeSymbols:
    """CasADi symbols of one shape slot.

    Attributes:
        kind: a key of :data:`SHAPE_DIMENSIONS`.
        reference: the shape frame's origin ``(c, ċ, c̈)`` (3-D) [m, m/s, m/s²]; velocity and
            acceleration are structural zeros in a static layout.
        orientation: the frame's quaternion ``(w, x, y, z)`` (4, 1), taken as constant in time.
        dimensions: the sizes (:data:`SHAPE_DIMENSIONS` of them) [m].
        allowance: how far the robot's spheres may enter the shape [m]: its leaves act on
            the clearance plus this (0: none).
    """

    kind: str
    reference: Reference
    orientation: ca.SX
    dimensions: ca.SX
    allowance: ca.SX


@dataclass(frozen=True)
class ShapeViews:
    """Writable numpy views of the slots of one shape kind (k slots).

    A box, cylinder or capsule slot with a dimension ≤ 0 is inactive; a plane slot is
    inactive while its orientation is the zero quaternion. Every slot starts inactive.

    Attributes:
        position: (k, 3) shape-frame origins [m] (a plane: a point on it).
        orientation: (k, 4) unit quaternions ``(w, x, y, z)`` of the shape frames (a
            plane's frame has its z axis along the normal, pointing out of the solid).
        dimensions: (k, n) sizes [m]: box ``(lx, ly, lz)``, cylinder and capsule
            ``(radius, length)``, plane none.
        allowance: (k,) how far the robot's spheres may enter each shape [m] (0, the
            default: not at all; global guidance sets it near a goal that needs it).
        velocity, acceleration: (k, 3) of the origin [m/s], [m/s²] (dynamic planners only;
            an :class:`AbsentParameter` in a static one).
    """

    position: np.ndarray
    orientation: np.ndarray
    dimensions: np.ndarray
    allowance: np.ndarray
    velocity: np.ndarray | AbsentParameter
    acceleration: np.ndarray | AbsentParameter


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
        shapes: every shape slot, kinds in the order of :data:`SHAPE_DIMENSIONS`.
        leaves: per leaf name, its parameters' symbols by name.
    """

    vector: ca.SX
    goals: tuple[Reference, ...]
    goal_weight: tuple[ca.SX, ...]
    obstacles: tuple[Reference, ...]
    obstacle_radius: tuple[ca.SX, ...]
    shapes: tuple[ShapeSymbols, ...] = ()
    leaves: Mapping[str, Mapping[str, ca.SX]] = field(default_factory=dict)


@dataclass(frozen=True)
class RuntimeParameters:
    """Writable numpy views of the runtime parameters.

    Attributes:
        goal_position: one view per goal, of the goal's dimension [m or rad; unit
            directions for orientation goals]; ``goal_position[i] = value`` writes goal ``i``.
        goal_weight: (n_goals,) weights; 0 deactivates a goal.
        obstacle_position: (slots, 3) sphere centres [m] (z ignored by planar robots).
        obstacle_radius: (slots,) radii [m]; 0 marks an unused slot.
        goal_velocity, goal_acceleration: per goal ``ẋ̃`` [m/s], ``ẍ̃`` [m/s²]
            (dynamic planners only; an :class:`AbsentParameter` in a static one).
        obstacle_velocity, obstacle_acceleration: (slots, 3) [m/s], [m/s²]
            (dynamic planners only; an :class:`AbsentParameter` in a static one).
        boxes, cylinders, capsules, planes: the shape slots of each kind (zero rows if
            the planner has none).
        leaves: the parameters of the planner's leaves (``PlannerConfig.leaves``):
            ``leaves[leaf][key] = value``.
    """

    goal_position: GoalViews
    goal_weight: np.ndarray
    obstacle_position: np.ndarray
    obstacle_radius: np.ndarray
    boxes: ShapeViews
    cylinders: ShapeViews
    capsules: ShapeViews
    planes: ShapeViews
    goal_velocity: GoalViews | AbsentParameter
    goal_acceleration: GoalViews | AbsentParameter
    obstacle_velocity: np.ndarray | AbsentParameter
    obstacle_acceleration: np.ndarray | AbsentParameter
    leaves: LeafParameters = field(default_factory=lambda: LeafParameters({}))

    def shape_views(self, kind: str) -> ShapeViews:
        """The views of the slots of ``kind`` (a key of :data:`SHAPE_DIMENSIONS`)."""
        return getattr(self, _PLURAL[kind])


@dataclass(frozen=True)
class ParameterLayout:
    """Order of the packed parameters: per goal its position (then velocity and
    acceleration if dynamic), the goal weights, the obstacle centres (then velocities and
    accelerations if dynamic), the obstacle radii; then per shape kind (in the order of
    :data:`SHAPE_DIMENSIONS`) its origins (then velocities and accelerations if dynamic),
    orientations, dimensions and allowances; then each leaf's parameters in order.

    Attributes:
        goal_dimensions: the dimension of each goal.
        obstacle_slots: sphere slots.
        dynamic: whether goals and obstacles carry velocities and accelerations.
        shape_slots: shape slots per kind.
        leaf_parameters: per leaf ``(name, ((key, size), ...))``.
    """

    goal_dimensions: tuple[int, ...]
    obstacle_slots: int
    dynamic: bool = False
    shape_slots: ShapeSlots = ShapeSlots()
    leaf_parameters: tuple[tuple[str, tuple[tuple[str, int], ...]], ...] = ()

    @property
    def _derivatives(self) -> int:
        return 3 if self.dynamic else 1

    @property
    def size(self) -> int:
        return self._leaf_start + sum(size for _, keys in self.leaf_parameters for _, size in keys)

    @property
    def _leaf_start(self) -> int:
        """Where the leaves' parameters start: after the goals, spheres and shapes."""
        k = self._derivatives
        return self._goal_and_sphere_size + sum(self.shape_slots.count(kind) * (3 * k + 4 + n + 1)
                                                for kind, n in SHAPE_DIMENSIONS.items())

    def _leaf_blocks(self) -> dict[str, dict[str, slice]]:
        """Per leaf, the slice of each of its parameters."""
        start, blocks = self._leaf_start, {}
        for name, keys in self.leaf_parameters:
            blocks[name] = {}
            for key, size in keys:
                blocks[name][key] = slice(start, start + size)
                start += size
        return blocks

    @property
    def _goal_and_sphere_size(self) -> int:
        """Length of the goal and sphere-slot part, which comes first."""
        k = self._derivatives
        return k * sum(self.goal_dimensions) + len(self.goal_dimensions) + (3 * k + 1) * self.obstacle_slots

    def _shape_blocks(self) -> dict[str, tuple[list[slice], slice, slice, slice]]:
        """Per kind: its origin blocks (one per derivative), orientations, dimensions, allowances."""
        k, start = self._derivatives, self._goal_and_sphere_size
        blocks = {}
        for kind, n in SHAPE_DIMENSIONS.items():
            slots = self.shape_slots.count(kind)
            origins = [slice(start + i * 3 * slots, start + (i + 1) * 3 * slots) for i in range(k)]
            start += 3 * k * slots
            orientations = slice(start, start + 4 * slots)
            dimensions = slice(start + 4 * slots, start + (4 + n) * slots)
            allowances = slice(start + (4 + n) * slots, start + (5 + n) * slots)
            start += (5 + n) * slots
            blocks[kind] = (origins, orientations, dimensions, allowances)
        return blocks

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
            shapes=self._shape_symbols(vector),
            leaves={name: {key: vector[block] for key, block in keys.items()}
                    for name, keys in self._leaf_blocks().items()},
        )

    def _shape_symbols(self, vector: ca.SX) -> tuple[ShapeSymbols, ...]:
        slots = []
        for kind, (origins, orientations, dimensions, allowances) in self._shape_blocks().items():
            n = SHAPE_DIMENSIONS[kind]
            for slot in range(self.shape_slots.count(kind)):
                parts = [vector[block.start + 3 * slot: block.start + 3 * slot + 3] for block in origins]
                parts += [ca.SX(3, 1)] * (3 - len(parts))
                slots.append(ShapeSymbols(
                    kind, Reference(*parts),
                    vector[orientations.start + 4 * slot: orientations.start + 4 * slot + 4],
                    vector[dimensions.start + n * slot: dimensions.start + n * slot + n],
                    vector[allowances.start + slot]))
        return tuple(slots)

    def views(self, buffer: np.ndarray) -> RuntimeParameters:
        """Views into ``buffer`` (length :attr:`size`); writes go straight into it."""
        if buffer.shape != (self.size,):
            raise ValueError(f"parameter buffer must have shape ({self.size},), got {buffer.shape}")
        goals, weights, obstacle_blocks, radii = self._blocks()
        n_goals = len(self.goal_dimensions)
        names = ("goal_position", "goal_velocity", "goal_acceleration")
        goal_views = [GoalViews([buffer[slices[i]] for slices in goals], names[i]) for i in range(self._derivatives)]
        obstacle_views = [buffer[block].reshape(self.obstacle_slots, 3) for block in obstacle_blocks]
        shapes = self._shape_views(buffer)
        return RuntimeParameters(
            goal_position=goal_views[0],
            goal_weight=buffer[weights: weights + n_goals],
            obstacle_position=obstacle_views[0],
            obstacle_radius=buffer[radii: radii + self.obstacle_slots],
            boxes=shapes["box"],
            cylinders=shapes["cylinder"],
            capsules=shapes["capsule"],
            planes=shapes["plane"],
            goal_velocity=goal_views[1] if self.dynamic else AbsentParameter("goal_velocity", STATIC_REMEDY),
            goal_acceleration=goal_views[2] if self.dynamic else AbsentParameter("goal_acceleration", STATIC_REMEDY),
            obstacle_velocity=(obstacle_views[1] if self.dynamic
                               else AbsentParameter("obstacle_velocity", STATIC_REMEDY)),
            obstacle_acceleration=(obstacle_views[2] if self.dynamic
                                   else AbsentParameter("obstacle_acceleration", STATIC_REMEDY)),
            leaves=LeafParameters({name: LeafViews(name, {key: buffer[block] for key, block in keys.items()})
                                   for name, keys in self._leaf_blocks().items()}),
        )

    def _shape_views(self, buffer: np.ndarray) -> dict[str, ShapeViews]:
        views = {}
        for kind, (origins, orientations, dimensions, allowances) in self._shape_blocks().items():
            slots = self.shape_slots.count(kind)
            origin = [buffer[block].reshape(slots, 3) for block in origins]
            views[kind] = ShapeViews(
                position=origin[0],
                orientation=buffer[orientations].reshape(slots, 4),
                dimensions=buffer[dimensions].reshape(slots, SHAPE_DIMENSIONS[kind]),
                allowance=buffer[allowances],
                velocity=origin[1] if self.dynamic else AbsentParameter(f"{_PLURAL[kind]}.velocity", STATIC_REMEDY),
                acceleration=origin[2] if self.dynamic else AbsentParameter(f"{_PLURAL[kind]}.acceleration", STATIC_REMEDY),
            )
        return views
