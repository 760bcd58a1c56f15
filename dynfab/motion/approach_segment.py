"""The segment of a grasp's approach in joint space: where the robot is along it, how far
beside it, and the obstacles' allowances ahead of it
(:meth:`~dynfab.motion.guidance.JointGuidance.approach_allowances`,
:class:`~dynfab.motion.guided_fabric.GuidedFabric`).

A grasp's approach is straight: measured on the line from its first configuration to its
last. An escape found on the meshes (:mod:`dynfab.motion.mesh_escape_plan`) is a polyline:
measured on its nearest piece, between consecutive configurations of ``segment`` (the same
numbers for a straight one, which keeps the line's arithmetic). A straight approach's
obstacles keep, ahead of the robot, the largest allowance of the rest of the way (what the
goal needs, the grasped object's neighbours); a polyline's only the largest of its nearest
configurations and the next ``POLYLINE_AHEAD``: it runs long through a pocket of the scene,
where the rest's largest allowance let development kitchen/0008 (seed 4) stray off its path
(clear of the meshes by 0.4 mm and more), ``panda_hand`` into the cupboard (−50 mm, the
hulls' depth, for 0.26 s)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.shapes import Sphere

if TYPE_CHECKING:
    from dynfab.fabric.planner_config import PlannerConfig
    from dynfab.motion.configuration_checker import PlacedObstacle

__all__ = ["POLYLINE_AHEAD", "allowances_ahead", "along_segment", "across_segment", "leaf_buffers", "segment_offset"]

#: configurations of a polyline approach beyond the robot's whose allowances count [-]
POLYLINE_AHEAD = 2


def allowances_ahead(segment: NDArray[np.float64], table: NDArray[np.float64],
                     q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per obstacle, the largest allowance [m] of ``table`` (k, m) at the approach's
    configurations ``segment`` (k, n) [rad] from the robot's (``q``'s projection on the
    segment, less one sample) to the goal (:meth:`~dynfab.motion.guidance.JointGuidance.approach_allowances`)."""
    first = max(0, int(np.floor(along_segment(segment, q) * (len(segment) - 1))) - 1)
    if not _straight(segment):   # a polyline's: only where the robot is (see the module docstring)
        return table[first:first + POLYLINE_AHEAD + 2].max(axis=0)
    return table[first:].max(axis=0)


def along_segment(segment: NDArray[np.float64], q: NDArray[np.float64]) -> float:
    """Where ``q`` projects on the straight segment from the first to the last configuration
    of ``segment`` (k, n) [rad]: 0 at its start, 1 at its end (clipped) [-]; on a polyline,
    its nearest point's piece and place on it, in pieces over their number."""
    if not _straight(segment):
        piece, fraction = _nearest_piece(segment, q)
        return (piece + fraction) / (len(segment) - 1)
    start, direction = segment[0], segment[-1] - segment[0]
    return float(np.clip(np.dot(q - start, direction) / max(float(np.dot(direction, direction)), 1e-12), 0.0, 1.0))


def segment_offset(segment: NDArray[np.float64], q: NDArray[np.float64]) -> float:
    """Distance [rad] of ``q`` from the straight segment from the first to the last
    configuration of ``segment`` (k, n) (or from the polyline): from its nearest point."""
    if not _straight(segment):
        piece, fraction = _nearest_piece(segment, q)
        return float(np.linalg.norm(q - (segment[piece] + fraction * (segment[piece + 1] - segment[piece]))))
    start, direction = segment[0], segment[-1] - segment[0]
    return float(np.linalg.norm(q - (start + along_segment(segment, q) * direction)))


def across_segment(segment: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
    """The step (n,) [rad] from ``q`` to the line through the first and last configurations
    of ``segment`` (k, n), across it (perpendicular to its direction): the step to the
    nearest point where ``q`` projects inside the segment (on a polyline, to the line of
    its nearest piece)."""
    if _straight(segment):
        base, direction = segment[0], segment[-1] - segment[0]
    else:   # the line of the polyline's nearest piece
        piece = _nearest_piece(segment, q)[0]
        base, direction = segment[piece], segment[piece + 1] - segment[piece]
    step = base - q
    squared = float(np.dot(direction, direction))
    if squared < 1e-12:
        return step
    return step - float(np.dot(step, direction)) / squared * direction


def _straight(segment: NDArray[np.float64]) -> bool:
    """Whether every configuration of ``segment`` (k, n) lies on the line through its first
    and last (within 1e-9 rad), or it has fewer than three."""
    if len(segment) < 3:
        return True
    start, direction = segment[0], segment[-1] - segment[0]
    squared = max(float(np.dot(direction, direction)), 1e-12)
    offsets = segment - start
    beside = offsets - np.outer(offsets @ direction / squared, direction)
    return float(np.max(np.linalg.norm(beside, axis=1))) <= 1e-9


def _nearest_piece(segment: NDArray[np.float64], q: NDArray[np.float64]) -> tuple[int, float]:
    """The piece ``i`` (from ``segment[i]`` to ``segment[i + 1]``) of the polyline ``segment``
    (k ≥ 2, n) nearest ``q``, and where on it its nearest point is, 0 to 1 [-]."""
    starts, pieces = segment[:-1], np.diff(segment, axis=0)
    squared = np.maximum(np.einsum("ij,ij->i", pieces, pieces), 1e-12)
    fractions = np.clip(np.einsum("ij,ij->i", q - starts, pieces) / squared, 0.0, 1.0)
    piece = int(np.argmin(np.linalg.norm(starts + fractions[:, None] * pieces - q, axis=1)))
    return piece, float(fractions[piece])


def leaf_buffers(config: PlannerConfig, obstacles: Sequence[PlacedObstacle]) -> tuple[float, ...]:
    """Per obstacle, the clearance [m] a fabric of ``config`` keeps from it (its leaves'
    barrier offset: the sphere leaves' for a sphere, the shape leaves' otherwise, 0 without
    such leaves): what an approach's allowances add to (:meth:`~dynfab.motion.guidance.JointGuidance.approach_allowances`)."""
    spheres, shapes = config.obstacle_avoidance, config.shape_avoidance
    return tuple((spheres.barrier.offset if spheres else 0.0) if isinstance(o.shape, Sphere)
                 else (shapes.barrier.offset if shapes else 0.0) for o in obstacles)
